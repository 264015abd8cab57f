#include "ncservo/report/chunk_queue.hpp"

#include <utility>

namespace ncservo::cli {

ChunkQueue::ChunkQueue(std::size_t capacity, std::size_t chunk_bytes)
    : capacity_(capacity == 0 ? 1 : capacity), chunk_bytes_(chunk_bytes) {}

Status ChunkQueue::push(Chunk chunk) {
  std::unique_lock lock(mutex_);
  not_full_.wait(lock, [&] { return stopped_ || waiting_.size() < capacity_; });
  if (stopped_) return fail(*stopped_);
  waiting_.push_back(std::move(chunk));
  not_empty_.notify_one();
  return {};
}

ChunkQueue::Chunk ChunkQueue::spare() {
  {
    std::lock_guard lock(mutex_);
    if (!spares_.empty()) {
      Chunk chunk = std::move(spares_.back());
      spares_.pop_back();
      chunk.used = 0;
      return chunk;
    }
  }
  return Chunk{std::vector<char>(chunk_bytes_), 0};
}

void ChunkQueue::close() {
  std::lock_guard lock(mutex_);
  closed_ = true;
  not_empty_.notify_one();
}

std::optional<ChunkQueue::Chunk> ChunkQueue::pop() {
  std::unique_lock lock(mutex_);
  not_empty_.wait(lock, [&] { return stopped_ || closed_ || !waiting_.empty(); });
  if (stopped_ || waiting_.empty()) return std::nullopt;
  Chunk chunk = std::move(waiting_.front());
  waiting_.pop_front();
  not_full_.notify_one();
  return chunk;
}

void ChunkQueue::recycle(Chunk chunk) {
  std::lock_guard lock(mutex_);
  // The producer holds one, the consumer one, `capacity_` wait: more spares are never taken.
  if (spares_.size() < capacity_ + 1) spares_.push_back(std::move(chunk));
}

void ChunkQueue::stop(Error error) {
  std::lock_guard lock(mutex_);
  stopped_ = std::move(error);
  waiting_.clear();
  not_full_.notify_one();
}

}  // namespace ncservo::cli
