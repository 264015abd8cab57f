#include "ncservo/capture/capture_stream.hpp"

#include "ncservo/capture/record_merge.hpp"

namespace ncservo {

Status streamCapture(CaptureReader& reader, CapturePipeline& pipeline, StreamStop* stop,
                     CaptureThreads threads) {
  RecordMerge merged(reader);
  bool first = true;
  const auto next = [&](CaptureRecord& record) {
    Result<bool> read = merged.next(record);
    // The capture's seconds count from its frame 1, which the merge may give later.
    if (first && read && *read) {
      first = false;
      if (record.frame != 1 && merged.origin()) pipeline.setTimeOrigin(*merged.origin());
    }
    return read;
  };
  if (threads == CaptureThreads::Two) return streamOnTwoThreads(next, pipeline, stop);
  CaptureRecord record;
  Result<bool> status;
  while ((status = next(record)) && *status) {
    if (stopRequested(stop)) return endStream(status, true, pipeline, stop);
    pipeline.onRecord(record);
  }
  // A read that Ctrl-C cut short (standard input waiting for more) is no damage of the capture.
  return endStream(status, !status && stopRequested(stop), pipeline, stop);
}

}  // namespace ncservo
