#include "ncservo/report/chunk_queue.hpp"

#include <utility>

namespace ncservo::report {

Status ChunkQueue::push(Chunk chunk) {
  if (queue_.push(std::move(chunk))) return {};
  const std::lock_guard lock(error_mutex_);
  return fail(*error_);
}

ChunkQueue::Chunk ChunkQueue::spare() {
  Chunk chunk = queue_.spare();
  if (chunk.bytes.size() != chunk_bytes_) chunk.bytes.resize(chunk_bytes_);
  chunk.used = 0;
  return chunk;
}

void ChunkQueue::stop(Error error) {
  {
    const std::lock_guard lock(error_mutex_);
    error_ = std::move(error);
  }
  queue_.stop();
}

}  // namespace ncservo::report
