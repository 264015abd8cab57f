#include "ncservo/capture/threaded_capture_run.hpp"

#include <signal.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <optional>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include "ncservo/base/bounded_queue.hpp"
#include "ncservo/base/byte_reader.hpp"

namespace ncservo {
namespace {

// An EcatFrame is a few fields and room for the most datagrams a chain can hold (8 KiB); a batch
// keeps the fields and only the datagrams the frame has, byte for byte.
static_assert(std::is_trivially_copyable_v<EcatFrame> && std::is_standard_layout_v<EcatFrame>);
constexpr std::size_t kDatagramsAt = offsetof(EcatFrame, datagrams);
constexpr std::size_t kAfterDatagrams = kDatagramsAt + sizeof(EcatFrame::datagrams);
constexpr std::size_t kTail = sizeof(EcatFrame) - kAfterDatagrams;

void pack(const EcatFrame& frame, std::vector<std::uint8_t>& out) {
  const auto* from = reinterpret_cast<const std::uint8_t*>(&frame);
  const std::size_t datagrams = frame.count * sizeof(Datagram);
  const std::size_t at = out.size();
  out.resize(at + kDatagramsAt + datagrams + kTail);
  std::uint8_t* to = out.data() + at;
  std::memcpy(to, from, kDatagramsAt);
  std::memcpy(to + kDatagramsAt, from + kDatagramsAt, datagrams);
  std::memcpy(to + kDatagramsAt + datagrams, from + kAfterDatagrams, kTail);
}

// The slots past `count` keep what they held: no one reads them (as with a frame walked in place).
void unpack(const std::uint8_t* from, EcatFrame& frame) {
  auto* to = reinterpret_cast<std::uint8_t*>(&frame);
  std::memcpy(to, from, kDatagramsAt);
  const std::size_t datagrams = frame.count * sizeof(Datagram);
  std::memcpy(to + kDatagramsAt, from + kDatagramsAt, datagrams);
  std::memcpy(to + kAfterDatagrams, from + kDatagramsAt + datagrams, kTail);
}

// Walked frames of process data in capture order, the records' bytes one after another.
struct WalkedBatch {
  struct Entry {
    std::uint64_t number;
    std::int64_t time_ns;
    std::size_t bytes_at, captured, frame_at;
    LinkType link;
    bool judged;
    bool probe_timed;
  };
  std::vector<Entry> entries;
  std::vector<std::uint8_t> bytes;   // the records'
  std::vector<std::uint8_t> frames;  // the walked frames, packed

  void clear() {
    entries.clear();
    bytes.clear();
    frames.clear();
  }
  void add(const CaptureRecord& record, const WalkedRecord& walked, const EcatFrame& frame) {
    entries.push_back({record.frame, walked.time_ns, bytes.size(), record.captured, frames.size(),
                       record.link, walked.judged, walked.probe_timed});
    bytes.insert(bytes.end(), record.data, record.data + record.captured);
    pack(frame, frames);
  }
  bool full(const BatchLimits& limits) const {
    return entries.size() >= limits.records || bytes.size() >= limits.bytes;
  }
};

// The judging thread: signals to the process go to the reading one (the header says why).
void blockProcessSignals() {
  sigset_t signals;
  sigemptyset(&signals);
  for (const int signal : {SIGINT, SIGTERM, SIGHUP, SIGQUIT}) sigaddset(&signals, signal);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
}

}  // namespace

Status streamOnTwoThreads(const NextRecord& next, CapturePipeline& pipeline, StreamStop* stop,
                          BatchLimits limits) {
  BoundedQueue<WalkedBatch> queue(limits.in_flight);
  std::exception_ptr judging_failed;
  std::thread judge([&] {
    blockProcessSignals();
    try {
      EcatFrame frame;
      while (std::optional<WalkedBatch> batch = queue.pop()) {
        for (const WalkedBatch::Entry& e : batch->entries) {
          unpack(batch->frames.data() + e.frame_at, frame);
          const ByteReader bytes(batch->bytes.data() + e.bytes_at, e.captured);
          pipeline.onWalkedFrame(e.number, e.time_ns, e.link, bytes, frame, e.judged,
                                 e.probe_timed);
        }
        queue.recycle(std::move(*batch));
      }
    } catch (...) {
      judging_failed = std::current_exception();
      queue.stop();
    }
  });
  // Drained: the judging thread delivers every batch waiting; else it drops them.
  const auto join = [&](bool drained) {
    if (drained) {
      queue.close();
    } else {
      queue.stop();
    }
    judge.join();
  };

  Result<bool> status;
  bool stopped = false;
  try {
    WalkedBatch batch = queue.spare();
    batch.clear();
    CaptureRecord record;
    EcatFrame frame;
    while ((status = next(record)) && *status) {
      if (stopBeforeRecord(stop)) {
        stopped = true;
        break;
      }
      const std::optional<WalkedRecord> walked = pipeline.walk(record, frame);
      if (!walked) continue;
      batch.add(record, *walked, frame);
      if (!batch.full(limits)) continue;
      if (!queue.push(std::move(batch))) break;  // the judging thread failed
      batch = queue.spare();
      batch.clear();
    }
    // A read that Ctrl-C cut short (standard input waiting for more) is no damage of the capture.
    if (!status && stopRequested(stop)) stopped = true;
    if (!stopped && !batch.entries.empty()) queue.push(std::move(batch));
  } catch (...) {
    join(false);
    throw;
  }
  join(!stopped);
  if (judging_failed) std::rethrow_exception(judging_failed);
  return endStream(status, stopped, pipeline, stop);
}

Status endStream(const Result<bool>& status, bool stopped, CapturePipeline& pipeline,
                 StreamStop* stop) {
  if (stopped) {
    stop->stopped = true;
    return {};
  }
  pipeline.finish();
  if (!status) return fail(status.error());
  return {};
}

}  // namespace ncservo
