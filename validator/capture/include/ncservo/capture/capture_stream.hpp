// A capture file through the capture pipeline.
#pragma once

#include <cstdint>

#include "ncservo/base/error.hpp"
#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/capture/threaded_capture_run.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"

namespace ncservo {

// One thread reads, walks and judges; or two, the second judging (threaded_capture_run.hpp,
// docs/cli.md#two-threads). The pipeline sees the same either way.
enum class CaptureThreads : std::uint8_t { One, Two };

// Reads to the end, or to the reader's error (everything before it is delivered), then finishes
// the pipeline: `start` is called even for a capture with no frame. With `stop` it may end before.
// The records of several interfaces are merged by time (record_merge.hpp).
Status streamCapture(CaptureReader& reader, CapturePipeline& pipeline, StreamStop* stop = nullptr,
                     CaptureThreads threads = CaptureThreads::One);

}  // namespace ncservo
