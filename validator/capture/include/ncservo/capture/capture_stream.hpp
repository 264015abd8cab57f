// A capture file through the capture pipeline.
#pragma once

#include <atomic>

#include "ncservo/base/error.hpp"
#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"

namespace ncservo {

// What ends a stream early (Ctrl-C: docs/cli.md#interrupted), asked before each record.
struct StreamStop {
  const std::atomic<bool>* requested = nullptr;
  bool stopped = false;  // set when the stream ended for it, the pipeline unfinished
};

// Reads to the end, or to the reader's error (everything before it is delivered), then finishes
// the pipeline: `start` is called even for a capture with no frame. With `stop` it may end before.
Status streamCapture(CaptureReader& reader, CapturePipeline& pipeline, StreamStop* stop = nullptr);

}  // namespace ncservo
