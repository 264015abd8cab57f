// runInOrder (ordered_jobs.hpp): every task runs once, results come in task order, and no more
// than 2 * jobs results wait, whatever the threads' timing.
#include "ncservo/base/ordered_jobs.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace ncservo {
namespace {

struct Case {
  std::size_t count;
  unsigned jobs;
};
const Case kCases[] = {{0, 2}, {1, 4}, {5, 1}, {20, 2}, {20, 3}, {7, 16}, {100, 4}};

TEST(OrderedJobs, ResultsInTaskOrder) {
  for (const Case& c : kCases) {
    SCOPED_TRACE(testing::Message() << c.count << " tasks on " << c.jobs << " threads");
    std::atomic<std::size_t> started{0}, running_ahead{0};
    std::size_t most_ahead = 0;
    std::mutex ahead_mutex;
    const std::function<std::size_t(std::size_t)> task = [&](std::size_t i) {
      ++started;
      // Later tasks finish first, so results must wait for those before them.
      std::this_thread::sleep_for(std::chrono::microseconds((c.count - i) % 5 * 200));
      const std::size_t ahead = ++running_ahead;
      const std::lock_guard<std::mutex> lock(ahead_mutex);
      most_ahead = std::max(most_ahead, ahead);
      return i * i;
    };
    std::vector<std::size_t> order;
    const std::function<void(std::size_t, std::size_t&)> deliver = [&](std::size_t i,
                                                                       std::size_t& result) {
      EXPECT_EQ(result, i * i);
      order.push_back(i);
      --running_ahead;
    };
    runInOrder(c.count, c.jobs, task, deliver);
    EXPECT_EQ(started, c.count);
    ASSERT_EQ(order.size(), c.count);
    for (std::size_t i = 0; i < c.count; ++i) EXPECT_EQ(order[i], i);
    EXPECT_LE(most_ahead, 2 * static_cast<std::size_t>(std::max(1u, c.jobs)));
  }
}

}  // namespace
}  // namespace ncservo
