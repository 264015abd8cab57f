#include "ncservo/capture/capture_stream.hpp"

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

RecordStream::RecordStream(FrameClock& clock, LayoutWindow& window, const CaptureStream& stream,
                           CaptureRun& run)
    : clock_(clock), window_(window), stream_(stream), run_(run) {
  if (!window_.learning()) stream_.start(window_.options());
}

void RecordStream::decided() {
  stream_.start(window_.options());
  window_.replay(stream_.frame, stream_.layout_only);
}

void RecordStream::onRecord(LinkType link, const CaptureRecord& record) {
  if (!run_.first_time_ns) run_.first_time_ns = record.time_ns;
  run_.records = record.frame;
  if (record.captured < record.original && run_.snapped++ == 0) run_.first_snapped = record.frame;
  const ByteReader bytes(record.data, record.captured);
  walkPacket(link, bytes, frame_);
  if (frame_.status == WalkStatus::NotEtherCat) return;
  const std::int64_t time_ns = clock_.time(record.frame, record.time_ns, frame_.probe);
  const bool judged = stream_.window.contains(time_ns - *run_.first_time_ns);
  run_.in_window += judged ? 1 : 0;
  if (frame_.status == WalkStatus::NotDatagrams || frame_.status == WalkStatus::BusFault) return;
  if (window_.learning()) {
    window_.hold(record.frame, time_ns, link, bytes, frame_, judged);
    if (!window_.learning()) decided();
    return;
  }
  if (judged) {
    stream_.frame(record.frame, time_ns, frame_, bytes);
  } else if (stream_.layout_only) {
    stream_.layout_only(record.frame, time_ns, frame_, bytes);
  }
}

void RecordStream::finish() {
  if (window_.learning()) {
    window_.finish();
    decided();
  }
}

Status streamCapture(CaptureReader& reader, FrameClock& clock, LayoutWindow& window,
                     const CaptureStream& stream, CaptureRun& run) {
  RecordStream records(clock, window, stream, run);
  CaptureRecord record;
  Result<bool> status;
  while ((status = reader.next(record)) && *status) records.onRecord(reader.link(), record);
  records.finish();
  if (!status) return fail(status.error());
  return {};
}

}  // namespace ncservo
