#include "ncservo/capture_stream.hpp"

namespace ncservo {

Status streamCapture(CaptureReader& reader, FrameClock& clock, LayoutWindow& window,
                     const CaptureStream& stream, CaptureRun& run) {
  auto decided = [&] {
    stream.start(window.options());
    window.replay(stream.frame);
  };
  if (!window.learning()) stream.start(window.options());
  EcatFrame frame;
  CaptureRecord record;
  Result<bool> status;
  while ((status = reader.next(record)) && *status) {
    if (!run.first_time_ns) run.first_time_ns = record.time_ns;
    run.records = record.frame;
    const ByteReader bytes(record.data, record.captured);
    walkPacket(reader.link(), bytes, frame);
    if (frame.status == WalkStatus::NotEtherCat) continue;
    const std::int64_t time_ns = clock.time(record.frame, record.time_ns, frame.probe);
    if (frame.status == WalkStatus::NotDatagrams || frame.status == WalkStatus::BusFault) continue;
    if (window.learning()) {
      window.hold(record.frame, time_ns, reader.link(), bytes, frame);
      if (!window.learning()) decided();
      continue;
    }
    stream.frame(record.frame, time_ns, frame, bytes);
  }
  if (window.learning()) {
    window.finish();
    decided();
  }
  if (!status) return fail(status.error());
  return {};
}

}  // namespace ncservo
