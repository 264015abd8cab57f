// Blocks of bytes handed from one producing thread to one consuming thread: `decode --format vcd`
// judges frames on one core and writes their text on the other (docs/benchmarks.md). At most
// `capacity` chunks wait; the producer waits while they do, so memory stays bounded.
#pragma once

#include <cstddef>
#include <mutex>
#include <optional>
#include <utility>
#include <vector>

#include "ncservo/base/bounded_queue.hpp"
#include "ncservo/base/error.hpp"

namespace ncservo::report {

class ChunkQueue {
 public:
  // `bytes` is allocated once and reused; `used` of them are filled.
  struct Chunk {
    std::vector<char> bytes;
    std::size_t used = 0;
  };

  ChunkQueue(std::size_t capacity, std::size_t chunk_bytes)
      : queue_(capacity), chunk_bytes_(chunk_bytes) {}

  // Producer: hands a chunk over, waiting while `capacity` chunks wait. Fails with the consumer's
  // error once it has stopped (the chunk is dropped).
  Status push(Chunk chunk);
  // Producer: an empty chunk of `chunk_bytes` to fill, one the consumer is done with when there is.
  Chunk spare();
  // Producer: no more chunks. The consumer still gets those waiting.
  void close() { queue_.close(); }

  // Consumer: the next chunk, in the order pushed, waiting for one; none once closed and drained,
  // or stopped.
  std::optional<Chunk> pop() { return queue_.pop(); }
  // Consumer: a chunk written out, for spare() to hand back.
  void recycle(Chunk chunk) { queue_.recycle(std::move(chunk)); }
  // Consumer: it cannot go on (a failed write). Waiting chunks are dropped and push fails with
  // `error` from now on.
  void stop(Error error);

 private:
  BoundedQueue<Chunk> queue_;
  const std::size_t chunk_bytes_;
  std::mutex error_mutex_;
  std::optional<Error> error_;  // why the consumer stopped
};

}  // namespace ncservo::report
