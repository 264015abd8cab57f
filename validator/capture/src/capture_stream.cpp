#include "ncservo/capture/capture_stream.hpp"

namespace ncservo {

Status streamCapture(CaptureReader& reader, CapturePipeline& pipeline, StreamStop* stop,
                     CaptureThreads threads) {
  if (threads == CaptureThreads::Two) {
    return streamOnTwoThreads(
        [&reader](CaptureRecord& record, LinkType& link) {
          Result<bool> read = reader.next(record);
          link = reader.link();  // as the loop below asks it, after the record
          return read;
        },
        pipeline, stop);
  }
  CaptureRecord record;
  Result<bool> status;
  while ((status = reader.next(record)) && *status) {
    if (stopRequested(stop)) return endStream(status, true, pipeline, stop);
    pipeline.onRecord(reader.link(), record);
  }
  // A read that Ctrl-C cut short (standard input waiting for more) is no damage of the capture.
  return endStream(status, !status && stopRequested(stop), pipeline, stop);
}

}  // namespace ncservo
