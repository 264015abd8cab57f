#include "ncservo/capture/capture_stream.hpp"

namespace ncservo {

Status streamCapture(CaptureReader& reader, CapturePipeline& pipeline, StreamStop* stop,
                     CaptureThreads threads) {
  if (threads == CaptureThreads::Two) {
    return streamOnTwoThreads([&reader](CaptureRecord& record) { return reader.next(record); },
                              pipeline, stop);
  }
  CaptureRecord record;
  Result<bool> status;
  while ((status = reader.next(record)) && *status) {
    if (stopRequested(stop)) return endStream(status, true, pipeline, stop);
    pipeline.onRecord(record);
  }
  // A read that Ctrl-C cut short (standard input waiting for more) is no damage of the capture.
  return endStream(status, !status && stopRequested(stop), pipeline, stop);
}

}  // namespace ncservo
