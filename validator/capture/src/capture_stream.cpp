#include "ncservo/capture/capture_stream.hpp"

namespace ncservo {

Status streamCapture(CaptureReader& reader, CapturePipeline& pipeline, StreamStop* stop) {
  CaptureRecord record;
  Result<bool> status;
  while ((status = reader.next(record)) && *status) {
    if (stop != nullptr && stop->requested != nullptr && stop->requested->load()) {
      stop->stopped = true;
      return {};
    }
    pipeline.onRecord(reader.link(), record);
  }
  pipeline.finish();
  if (!status) return fail(status.error());
  return {};
}

}  // namespace ncservo
