#include "ncservo/capture/capture_stream.hpp"

namespace ncservo {

Status streamCapture(CaptureReader& reader, CapturePipeline& pipeline) {
  CaptureRecord record;
  Result<bool> status;
  while ((status = reader.next(record)) && *status) pipeline.onRecord(reader.link(), record);
  pipeline.finish();
  if (!status) return fail(status.error());
  return {};
}

}  // namespace ncservo
