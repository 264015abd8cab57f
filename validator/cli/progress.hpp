// A long run's progress on a terminal (docs/cli.md#progress): frames, rate and time so far on
// standard error, never in a pipe, a file or under CI.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

namespace ncservo::cli {

// Standard error is a terminal and CI (any value but empty) is not set.
bool progressWanted();

// While it lives, a line "ncservo: WHAT: N frames, R frames/s, S s" redrawn every second from
// the second second on (a short run shows none), counted from `records`; cleared at the end so
// that what follows starts on a clean line. Does nothing unless `shown`.
class Progress {
 public:
  Progress(std::string what, const std::atomic<std::uint64_t>& records, bool shown);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

 private:
  void run();

  std::string what_;
  const std::atomic<std::uint64_t>& records_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool done_ = false;
  bool drawn_ = false;
  std::thread thread_;
};

}  // namespace ncservo::cli
