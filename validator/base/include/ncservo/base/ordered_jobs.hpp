// Tasks run on several threads, their results handed on in the tasks' order: `validate --jobs`
// writes the captures' reports in argument order, byte for byte as one thread would.
#pragma once

#include <algorithm>
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

namespace ncservo {

// Runs task(i) for every i below `count` on up to `jobs` threads and hands each result to
// deliver(i, result) on the calling thread, in order of i, as soon as it and all before it are
// done. A thread starts a task only while fewer than 2 * jobs results wait to be handed on, so
// memory stays bounded whatever the count.
template <typename T>
void runInOrder(std::size_t count, unsigned jobs, const std::function<T(std::size_t)>& task,
                const std::function<void(std::size_t, T&)>& deliver) {
  jobs = std::max(1u, std::min<unsigned>(jobs, static_cast<unsigned>(count)));
  if (jobs == 1) {
    for (std::size_t i = 0; i < count; ++i) {
      T result = task(i);
      deliver(i, result);
    }
    return;
  }
  const std::size_t window = 2 * static_cast<std::size_t>(jobs);
  std::mutex mutex;
  std::condition_variable changed;
  std::vector<std::optional<T>> results(count);
  std::size_t next = 0;       // the next task to start
  std::size_t delivered = 0;  // results handed on
  auto work = [&] {
    std::unique_lock<std::mutex> lock(mutex);
    for (;;) {
      changed.wait(lock, [&] { return next >= count || next < delivered + window; });
      if (next >= count) return;
      const std::size_t i = next++;
      lock.unlock();
      T result = task(i);
      lock.lock();
      results[i] = std::move(result);
      changed.notify_all();
    }
  };
  std::vector<std::thread> threads;
  for (unsigned j = 0; j < jobs; ++j) threads.emplace_back(work);
  for (std::size_t i = 0; i < count; ++i) {
    std::unique_lock<std::mutex> lock(mutex);
    changed.wait(lock, [&] { return results[i].has_value(); });
    T result = std::move(*results[i]);
    results[i].reset();
    lock.unlock();
    deliver(i, result);
    lock.lock();
    delivered = i + 1;
    changed.notify_all();
  }
  for (std::thread& thread : threads) thread.join();
}

}  // namespace ncservo
