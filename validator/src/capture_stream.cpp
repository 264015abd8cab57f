#include "ncservo/capture_stream.hpp"

#include <fmt/format.h>

#include <cmath>
#include <tuple>

namespace ncservo {

Result<TimeWindow> timeWindowOf(std::optional<double> from_s, std::optional<double> to_s) {
  constexpr double kLimitS = 1e9;  // about 30 years either way: the nanoseconds fit
  TimeWindow window;
  for (auto [option, seconds, ns] :
       {std::tuple{"--from", from_s, &window.from_ns}, std::tuple{"--to", to_s, &window.to_ns}}) {
    if (!seconds) continue;
    if (!std::isfinite(*seconds) || std::fabs(*seconds) > kLimitS) {
      return fail(
          fmt::format("{} {}: expected seconds since the capture's first frame", option, *seconds));
    }
    *ns = std::llround(*seconds * 1e9);
  }
  if (window.from_ns && window.to_ns && *window.to_ns < *window.from_ns) {
    return fail(fmt::format("--to {} is before --from {}", *to_s, *from_s));
  }
  return window;
}

std::string describeTimeWindow(const TimeWindow& window) {
  std::string out;
  auto add = [&out](const char* option, const std::optional<std::int64_t>& ns) {
    if (ns) out += fmt::format("{}{} {:g}", out.empty() ? "" : " ", option, *ns / 1e9);
  };
  add("--from", window.from_ns);
  add("--to", window.to_ns);
  return out;
}

Status streamCapture(CaptureReader& reader, FrameClock& clock, LayoutWindow& window,
                     const CaptureStream& stream, CaptureRun& run) {
  auto decided = [&] {
    stream.start(window.options());
    window.replay(stream.frame, stream.layout_only);
  };
  if (!window.learning()) stream.start(window.options());
  EcatFrame frame;
  CaptureRecord record;
  Result<bool> status;
  while ((status = reader.next(record)) && *status) {
    if (!run.first_time_ns) run.first_time_ns = record.time_ns;
    run.records = record.frame;
    if (record.captured < record.original && run.snapped++ == 0) run.first_snapped = record.frame;
    const ByteReader bytes(record.data, record.captured);
    walkPacket(reader.link(), bytes, frame);
    if (frame.status == WalkStatus::NotEtherCat) continue;
    const std::int64_t time_ns = clock.time(record.frame, record.time_ns, frame.probe);
    const bool judged = stream.window.contains(time_ns - *run.first_time_ns);
    run.in_window += judged ? 1 : 0;
    if (frame.status == WalkStatus::NotDatagrams || frame.status == WalkStatus::BusFault) continue;
    if (window.learning()) {
      window.hold(record.frame, time_ns, reader.link(), bytes, frame, judged);
      if (!window.learning()) decided();
      continue;
    }
    if (judged) {
      stream.frame(record.frame, time_ns, frame, bytes);
    } else if (stream.layout_only) {
      stream.layout_only(record.frame, time_ns, frame, bytes);
    }
  }
  if (window.learning()) {
    window.finish();
    decided();
  }
  if (!status) return fail(status.error());
  return {};
}

}  // namespace ncservo
