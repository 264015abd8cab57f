#include "ncservo/capture/capture_stream.hpp"

#include "ncservo/capture/record_merge.hpp"

namespace ncservo {

namespace {

// The capture's seconds count from its frame 1, which the merge may give after another.
void keepOrigin(const RecordMerge& merged, const Result<bool>& read, const CaptureRecord& record,
                CapturePipeline& pipeline) {
  if (read && *read && record.frame != 1 && merged.origin()) {
    pipeline.setTimeOrigin(*merged.origin());
  }
}

}  // namespace

Status streamCapture(CaptureReader& reader, CapturePipeline& pipeline, StreamStop* stop,
                     CaptureThreads threads) {
  RecordMerge merged(reader);
  if (threads == CaptureThreads::Two) {
    bool first = true;
    return streamOnTwoThreads(
        [&](CaptureRecord& record) {
          Result<bool> read = merged.next(record);
          if (first) keepOrigin(merged, read, record, pipeline);
          first = false;
          return read;
        },
        pipeline, stop);
  }
  CaptureRecord record;
  Result<bool> status = merged.next(record);
  keepOrigin(merged, status, record, pipeline);
  for (; status && *status; status = merged.next(record)) {
    if (stopBeforeRecord(stop)) return endStream(status, true, pipeline, stop);
    pipeline.onRecord(record);
  }
  // A read that Ctrl-C cut short (standard input waiting for more) is no damage of the capture.
  return endStream(status, !status && stopRequested(stop), pipeline, stop);
}

}  // namespace ncservo
