// Items handed from one producing thread to one consuming thread, in the order pushed: a capture
// read and walked on one core, judged on the other (docs/cli.md#two-threads). At most `capacity`
// items wait; the producer waits while they do, and takes back the items the consumer is done
// with, their buffers with them, so memory stays bounded whatever the length of the stream.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <optional>
#include <utility>
#include <vector>

namespace ncservo {

template <typename T>
class BoundedQueue {
 public:
  explicit BoundedQueue(std::size_t capacity) : capacity_(capacity == 0 ? 1 : capacity) {}

  // Producer: an item to fill, one the consumer gave back when there is (as it left it), else a
  // new one.
  T spare() {
    const std::lock_guard lock(mutex_);
    if (spares_.empty()) return T{};
    T item = std::move(spares_.back());
    spares_.pop_back();
    return item;
  }
  // Producer: hands `item` over, waiting while `capacity` items wait. False once stopped: the
  // item is dropped.
  bool push(T item) {
    std::unique_lock lock(mutex_);
    not_full_.wait(lock, [&] { return stopped_ || waiting_.size() < capacity_; });
    if (stopped_) return false;
    waiting_.push_back(std::move(item));
    not_empty_.notify_one();
    return true;
  }
  // Producer: no more items. The consumer still gets those waiting.
  void close() {
    const std::lock_guard lock(mutex_);
    closed_ = true;
    not_empty_.notify_one();
  }

  // Consumer: the next item in the order pushed, waiting for one; none once closed and drained,
  // or stopped.
  std::optional<T> pop() {
    std::unique_lock lock(mutex_);
    not_empty_.wait(lock, [&] { return stopped_ || closed_ || !waiting_.empty(); });
    if (stopped_ || waiting_.empty()) return std::nullopt;
    T item = std::move(waiting_.front());
    waiting_.pop_front();
    not_full_.notify_one();
    return item;
  }
  // Consumer: an item done with, for spare() to hand back.
  void recycle(T item) {
    const std::lock_guard lock(mutex_);
    // The producer holds one, the consumer one, `capacity_` wait: no more spares are ever taken.
    if (spares_.size() < capacity_ + 1) spares_.push_back(std::move(item));
  }

  // Either side: the stream ends here (an interrupt, a failure). The waiting items are dropped,
  // push fails and pop returns none from now on.
  void stop() {
    const std::lock_guard lock(mutex_);
    stopped_ = true;
    waiting_.clear();
    not_full_.notify_one();
    not_empty_.notify_one();
  }
  bool stopped() const {
    const std::lock_guard lock(mutex_);
    return stopped_;
  }

 private:
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable not_full_, not_empty_;
  std::deque<T> waiting_;
  std::vector<T> spares_;
  bool closed_ = false;
  bool stopped_ = false;
};

}  // namespace ncservo
