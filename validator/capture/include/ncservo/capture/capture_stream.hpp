// A capture file through the capture pipeline.
#pragma once

#include "ncservo/base/error.hpp"
#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"

namespace ncservo {

// Reads to the end, or to the reader's error (everything before it is delivered), then finishes
// the pipeline: `start` is called even for a capture with no frame.
Status streamCapture(CaptureReader& reader, CapturePipeline& pipeline);

}  // namespace ncservo
