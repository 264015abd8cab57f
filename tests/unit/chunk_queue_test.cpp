// The bounded queue between decode's walking thread and its VCD text writer (chunk_queue.hpp):
// chunks arrive in the order pushed, the producer waits while the queue is full and reuses the
// chunks written out (bounded memory), and a consumer's failure reaches the producer as its error.
#include "ncservo/report/chunk_queue.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <numeric>
#include <optional>
#include <set>
#include <thread>
#include <vector>

#include "row_name.hpp"

namespace ncservo::report {
namespace {

struct QueueCase {
  const char* name;
  std::size_t capacity;
  std::size_t chunks;                     // the producer pushes 0, 1, ... chunks - 1
  std::optional<std::size_t> stop_after;  // the consumer fails after this many
};

class ChunkQueueTest : public ::testing::TestWithParam<QueueCase> {};

TEST_P(ChunkQueueTest, OrderBackPressureAndFailure) {
  const QueueCase& c = GetParam();
  ChunkQueue queue(c.capacity, sizeof(std::size_t));
  std::atomic<std::size_t> pushed{0};
  std::set<const char*> buffers;
  Status produced;
  std::thread producer([&] {
    for (std::size_t n = 0; n < c.chunks; ++n) {
      ChunkQueue::Chunk chunk = queue.spare();
      buffers.insert(chunk.bytes.data());
      std::memcpy(chunk.bytes.data(), &n, sizeof n);
      chunk.used = sizeof n;
      produced = queue.push(std::move(chunk));
      if (!produced) break;
      ++pushed;
    }
    queue.close();
  });

  std::vector<std::size_t> received;
  std::size_t most_ahead = 0;  // pushed and not yet written out
  while (std::optional<ChunkQueue::Chunk> chunk = queue.pop()) {
    // A slow consumer: the producer runs as far ahead as the queue lets it.
    std::this_thread::sleep_for(std::chrono::microseconds(200));
    most_ahead = std::max(most_ahead, pushed.load() - received.size());
    ASSERT_EQ(chunk->used, sizeof(std::size_t));
    std::size_t n = 0;
    std::memcpy(&n, chunk->bytes.data(), sizeof n);
    received.push_back(n);
    queue.recycle(std::move(*chunk));
    if (c.stop_after && received.size() == *c.stop_after) {
      queue.stop(Error{"out.vcd", 0, 0, {}, "cannot write: No space left on device"});
      break;
    }
  }
  producer.join();

  std::vector<std::size_t> expected(c.stop_after ? *c.stop_after : c.chunks);
  std::iota(expected.begin(), expected.end(), std::size_t{0});
  EXPECT_EQ(received, expected);
  // At most `capacity` wait, besides the one being written out.
  EXPECT_LE(most_ahead, c.capacity + 1);
  // The producer's chunk, those waiting and the consumer's: no more are ever made.
  EXPECT_LE(buffers.size(), c.capacity + 2);
  if (c.stop_after) {
    ASSERT_FALSE(produced);
    EXPECT_EQ(produced.error().text(), "out.vcd: cannot write: No space left on device");
  } else {
    EXPECT_TRUE(produced);
    EXPECT_EQ(pushed.load(), c.chunks);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Cases, ChunkQueueTest,
    ::testing::Values(QueueCase{"none", 2, 0, std::nullopt},
                      QueueCase{"in_order_with_room", 8, 100, std::nullopt},
                      QueueCase{"back_pressure_one_waiting", 1, 50, std::nullopt},
                      QueueCase{"back_pressure_two_waiting", 2, 50, std::nullopt},
                      QueueCase{"failure_reaches_the_producer", 2, 100, 3},
                      QueueCase{"failure_at_the_first_chunk", 1, 10, 1}),
    test::rowName<QueueCase>);

TEST(ChunkQueue, PopAfterCloseGivesWhatWaitedThenNothing) {
  ChunkQueue queue(4, 1);
  for (char c : {'a', 'b'}) {
    ChunkQueue::Chunk chunk = queue.spare();
    chunk.bytes[0] = c;
    chunk.used = 1;
    ASSERT_TRUE(queue.push(std::move(chunk)));
  }
  queue.close();
  std::string seen;
  while (std::optional<ChunkQueue::Chunk> chunk = queue.pop()) seen += chunk->bytes[0];
  EXPECT_EQ(seen, "ab");
  EXPECT_FALSE(queue.pop());
}

}  // namespace
}  // namespace ncservo::report
