#include "ncservo/wire/frame_clock.hpp"

#include <fmt/format.h>

namespace ncservo {

namespace {
struct ModeName {
  TimestampMode mode;
  const char* name;
};
constexpr ModeName kModeNames[] = {
    {TimestampMode::Capture, "capture"},
    {TimestampMode::Probe, "probe"},
    {TimestampMode::Auto, "auto"},
};
}  // namespace

std::optional<TimestampMode> timestampModeFromName(std::string_view name) {
  for (const ModeName& m : kModeNames) {
    if (name == m.name) return m.mode;
  }
  return std::nullopt;
}

const char* timestampSourceName(TimestampSource source) {
  return source == TimestampSource::Probe ? "probe" : "capture";
}

std::int64_t timestampResolutionNs(TimestampSource source, int digits) {
  if (source == TimestampSource::Probe) return 1;
  std::int64_t ns = 1;
  for (int d = digits; d < 9; ++d) ns *= 10;
  return ns;
}

std::int64_t FrameClock::time(std::uint64_t frame_number, std::int64_t capture_ns,
                              const ProbeHeader& probe) {
  const bool stamped = probe.present && probe.timestampValid();
  counts_.probed += probe.present ? 1 : 0;
  counts_.stamped += stamped ? 1 : 0;
  counts_.alignment_errors += probe.present && probe.alignmentError() ? 1 : 0;
  if (probe.present && probe.crcError() && counts_.crc_errors++ == 0) {
    counts_.first_crc_error = frame_number;
  }
  const bool first = !probe_timed_.has_value();
  if (first) {
    probe_timed_ = mode_ == TimestampMode::Probe || (mode_ == TimestampMode::Auto && stamped);
  }
  if (!*probe_timed_) return capture_ns;
  std::int64_t time_ns;
  if (first) {
    time_ns = capture_ns;
  } else if (stamped && anchor_) {
    // Unsigned difference, then signed: a probe clock that steps back gives a negative interval.
    time_ns = anchor_->time_ns + static_cast<std::int64_t>(probe.timestamp_ns - anchor_->probe_ns);
  } else {
    time_ns = last_time_ns_ + (capture_ns - last_capture_ns_);
  }
  if (stamped) {
    anchor_ = Anchor{time_ns, probe.timestamp_ns};
  } else if (anchor_ && counts_.unstamped++ == 0) {
    counts_.first_unstamped = frame_number;
  }
  last_time_ns_ = time_ns;
  last_capture_ns_ = capture_ns;
  return time_ns;
}

std::string FrameClock::note() const {
  std::string out;
  auto add = [&out](const std::string& text) { out += (out.empty() ? "" : "; ") + text; };
  if (counts_.unstamped > 0) {
    add(
        fmt::format("{} EtherCAT frame{} without a probe timestamp (first: frame {}) timed by the "
                    "capture clock from the frame before",
                    counts_.unstamped, counts_.unstamped == 1 ? "" : "s", counts_.first_unstamped));
  }
  if (source() == TimestampSource::Capture && counts_.stamped > 0) {
    add(fmt::format("{} frame{} carried a probe timestamp, unused ({})", counts_.stamped,
                    counts_.stamped == 1 ? "" : "s",
                    mode_ == TimestampMode::Capture ? "--timestamps capture"
                                                    : "the first EtherCAT frame had none"));
  }
  if (counts_.crc_errors > 0) {
    add(fmt::format("{} frame{} with a CRC error on the bus (first: frame {}), not decoded",
                    counts_.crc_errors, counts_.crc_errors == 1 ? "" : "s",
                    counts_.first_crc_error));
  }
  if (counts_.alignment_errors > 0) {
    add(fmt::format("{} frame{} with an alignment error", counts_.alignment_errors,
                    counts_.alignment_errors == 1 ? "" : "s"));
  }
  return out;
}

}  // namespace ncservo
