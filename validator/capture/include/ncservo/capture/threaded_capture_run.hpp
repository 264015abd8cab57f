// A capture through the capture pipeline on two threads (docs/cli.md#two-threads): the calling
// thread reads the records and walks them (CapturePipeline::walk), a second one delivers the walked
// frames (onWalkedFrame) to the learning window, the validator, the incident detector and the
// sinks. The frames travel in batches through a bounded queue; the pipeline sees what it sees on
// one thread (streamCapture), frame by frame in the same order, and the same end.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>

#include "ncservo/base/error.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"
#include "ncservo/wire/capture_record.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo {

// What ends a stream early (Ctrl-C: docs/cli.md#interrupted), asked before each record.
struct StreamStop {
  const std::atomic<bool>* requested = nullptr;
  bool stopped = false;  // set when the stream ended for it, the pipeline unfinished
  // Counts the records read, for a progress line (cli/progress.hpp); none when null.
  std::atomic<std::uint64_t>* records = nullptr;
};
inline bool stopRequested(const StreamStop* stop) {
  return stop != nullptr && stop->requested != nullptr && stop->requested->load();
}
// Asked before each record: stopRequested, counting the record.
inline bool stopBeforeRecord(const StreamStop* stop) {
  if (stop != nullptr && stop->records != nullptr) {
    stop->records->fetch_add(1, std::memory_order_relaxed);
  }
  return stopRequested(stop);
}

// A stream's end, on one thread or two, once its records are read (`status`: the last read) or the
// reading `stopped` for `stop`: stopped, the pipeline is left unfinished; otherwise it finishes,
// and a read error is the stream's.
Status endStream(const Result<bool>& status, bool stopped, CapturePipeline& pipeline,
                 StreamStop* stop);

// The records of a capture in order: fills `record` (its bytes valid until the next call; its
// link type its own) and returns true; false at the end; an error when a record cannot be read
// (the records before it were good).
using NextRecord = std::function<Result<bool>(CaptureRecord& record)>;

// A batch holds up to `records` records or about `bytes` of their bytes (a longer record still
// fits); at most `in_flight` batches wait for the judging thread, so memory stays bounded.
struct BatchLimits {
  std::size_t records = 512;
  std::size_t bytes = std::size_t{1} << 19;
  std::size_t in_flight = 4;
};

// streamCapture's work on two threads, over `next`: to the end, or to the read error (every frame
// before it judged, then the end of the capture, then the error), or to `stop`. The sinks run on
// the second thread, finish() and its findings on this one. The second thread blocks the
// signals sent to the process, so that Ctrl-C reaches this one and cuts short a read waiting for
// input, as on one thread. An exception on either thread ends both and is thrown here.
Status streamOnTwoThreads(const NextRecord& next, CapturePipeline& pipeline,
                          StreamStop* stop = nullptr, BatchLimits limits = {});

}  // namespace ncservo
