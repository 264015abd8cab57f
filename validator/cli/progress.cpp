#include "progress.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>

namespace ncservo::cli {

bool progressWanted() {
  const char* ci = std::getenv("CI");
  return isatty(STDERR_FILENO) == 1 && (ci == nullptr || ci[0] == '\0');
}

Progress::Progress(std::string what, const std::atomic<std::uint64_t>& records, bool shown)
    : what_(std::move(what)), records_(records) {
  if (shown) thread_ = std::thread([this] { run(); });
}

Progress::~Progress() {
  if (!thread_.joinable()) return;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
  }
  wake_.notify_all();
  thread_.join();
  if (drawn_) std::fputs("\r\033[K", stderr);  // the line erased: the report follows clean
}

void Progress::run() {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  std::unique_lock<std::mutex> lock(mutex_);
  for (int second = 1;; ++second) {
    if (wake_.wait_until(lock, start + std::chrono::seconds(second), [this] { return done_; })) {
      return;
    }
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    const std::uint64_t frames = records_.load(std::memory_order_relaxed);
    fmt::print(stderr, "\r\033[Kncservo: {}: {} frames, {:.0f} frames/s, {} s", what_, frames,
               static_cast<double>(frames) / elapsed, second);
    std::fflush(stderr);
    drawn_ = true;
  }
}

}  // namespace ncservo::cli
