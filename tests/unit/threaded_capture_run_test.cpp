// Two threads for one capture (threaded_capture_run.hpp, docs/cli.md#two-threads): the bounded
// queue hands items over in order, holds back a producer that runs ahead and ends on either
// side's stop; and a capture read on one thread and judged on another gives the pipeline's sinks
// what one thread gives them, frame by frame, whatever the batches, with a read error and the
// end of the capture in the same place; Ctrl-C and a failing sink end both threads.
#include "ncservo/capture/threaded_capture_run.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "ncservo/base/bounded_queue.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"
#include "ncservo/sim/simulator.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

// ---- The queue ----

struct QueueCase {
  const char* name;
  std::size_t capacity;
  std::size_t items;                                // the producer pushes 0, 1, ... items - 1
  std::optional<std::size_t> consumer_stops_after;  // items taken, then stop()
  std::optional<std::size_t> producer_stops_after;  // items pushed, then stop() (no close)
};

class BoundedQueueTest : public ::testing::TestWithParam<QueueCase> {};

TEST_P(BoundedQueueTest, OrderBoundEndAndStop) {
  const QueueCase& c = GetParam();
  BoundedQueue<std::vector<std::size_t>> queue(c.capacity);
  std::atomic<std::size_t> pushed{0};
  std::set<const std::size_t*> buffers;  // every item's storage the producer ever filled
  bool refused = false;
  std::thread producer([&] {
    for (std::size_t n = 0; n < c.items; ++n) {
      if (c.producer_stops_after && n == *c.producer_stops_after) {
        queue.stop();
        return;
      }
      std::vector<std::size_t> item = queue.spare();
      item.assign(4, n);  // a recycled item keeps its capacity: no new storage
      buffers.insert(item.data());
      if (!queue.push(std::move(item))) {
        refused = true;
        return;
      }
      ++pushed;
    }
    queue.close();
  });
  std::vector<std::size_t> received;
  std::size_t most_ahead = 0;  // pushed and not yet taken
  while (std::optional<std::vector<std::size_t>> item = queue.pop()) {
    std::this_thread::sleep_for(std::chrono::microseconds(100));  // a slow consumer
    most_ahead = std::max(most_ahead, pushed.load() - received.size());
    ASSERT_EQ(item->size(), 4u);
    received.push_back(item->front());
    queue.recycle(std::move(*item));
    if (c.consumer_stops_after && received.size() == *c.consumer_stops_after) {
      queue.stop();
      break;
    }
  }
  producer.join();

  for (std::size_t i = 0; i < received.size(); ++i) EXPECT_EQ(received[i], i);  // in order
  const std::size_t capacity = std::max<std::size_t>(c.capacity, 1);
  EXPECT_LE(most_ahead, capacity + 1);      // at most `capacity` wait, one in the consumer's hands
  EXPECT_LE(buffers.size(), capacity + 2);  // the items come back to be filled again
  if (c.consumer_stops_after) {
    EXPECT_EQ(received.size(), *c.consumer_stops_after);
    EXPECT_TRUE(refused);  // the producer learns of it at its next push
    EXPECT_LE(pushed.load(), received.size() + capacity + 1);
  } else if (c.producer_stops_after) {
    EXPECT_LE(received.size(), *c.producer_stops_after);  // the waiting ones are dropped
    EXPECT_FALSE(refused);
  } else {
    EXPECT_EQ(received.size(), c.items);  // every item, then the end
    EXPECT_FALSE(refused);
  }
}

const QueueCase kQueueCases[] = {
    {"empty", 2, 0, std::nullopt, std::nullopt},
    {"one item", 2, 1, std::nullopt, std::nullopt},
    {"capacity one", 1, 50, std::nullopt, std::nullopt},
    {"many through four", 4, 200, std::nullopt, std::nullopt},
    {"capacity zero is one", 0, 20, std::nullopt, std::nullopt},
    {"consumer stops early", 2, 100, 5, std::nullopt},
    {"consumer stops at once", 3, 100, 1, std::nullopt},
    {"producer stops early", 2, 100, std::nullopt, 10},
    {"producer stops before any", 2, 100, std::nullopt, 0},
};
INSTANTIATE_TEST_SUITE_P(Cases, BoundedQueueTest, ::testing::ValuesIn(kQueueCases),
                         test::rowName<QueueCase>);

// ---- A capture on two threads against one ----

struct Recorded {
  std::vector<std::uint8_t> bytes;
  std::int64_t time_ns;
  std::size_t original;
};

// The faults scenario (four axes, 4.3 s); every 97th frame cut to its first 40 bytes (a snap
// length), and between the frames other traffic and bytes that are no frame at all.
const std::vector<Recorded>& records() {
  static const std::vector<Recorded> recorded = [] {
    sim::SimOptions options;
    options.scenario = sim::Scenario::Faults;
    const Status resolved = sim::resolveOptions(options);
    EXPECT_TRUE(resolved) << resolved.error().text();
    std::vector<Recorded> frames;
    sim::Simulator simulator(options);
    EXPECT_TRUE(simulator.run([&](const sim::SimFrame& f) {
      std::vector<std::uint8_t> bytes(f.data, f.data + f.size);
      if (frames.size() % 97 == 50) bytes.resize(40);
      frames.push_back({std::move(bytes), f.time_ns, f.size});
      if (frames.size() % 61 == 0) {  // IPv4, then garbage, then nothing at all
        std::vector<std::uint8_t> other(60, 0xA5);
        other[12] = 0x08;
        other[13] = 0x00;
        frames.push_back({other, f.time_ns + 1000, other.size()});
        frames.push_back({std::vector<std::uint8_t>(7, 0x88), f.time_ns + 2000, 7});
        frames.push_back({{}, f.time_ns + 3000, 0});
      }
      return true;
    }));
    return frames;
  }();
  return recorded;
}

// What the sinks saw, in order, as text.
struct Seen {
  std::vector<std::string> events;
  CapturePipeline::Sinks sinks(const CapturePipeline& pipeline) {
    const auto frame = [this, &pipeline](const char* kind, const PipelineFrame& f) {
      unsigned sum = 0;
      for (std::size_t i = 0; i < f.bytes.size(); ++i) sum = sum * 31 + f.bytes.data()[i];
      events.push_back(std::string(kind) + " " + std::to_string(f.number) + " " +
                       std::to_string(f.time_ns - *pipeline.run().first_time_ns) + " " +
                       std::to_string(f.frame.count) + " " + std::to_string(sum) + " " +
                       std::to_string(f.judged ? f.judged->decode.axis_count : 99));
    };
    return {[this](const DecoderOptions& layout) {
              events.push_back("start " + std::to_string(layout.axes.size()));
            },
            [frame](const PipelineFrame& f) { frame("frame", f); },
            [frame](const PipelineFrame& f) { frame("layout", f); },
            [this](const std::vector<Finding>& found) {
              for (const Finding& f : found) {
                events.push_back("finding " + std::to_string(f.at.frame) + " " + f.message);
              }
            },
            nullptr};
  }
};

// The records as a reader gives them: the bytes valid until the next call (they are overwritten
// then), an error after `error_after` records, and Ctrl-C asked for after `stop_after`.
struct Source {
  Source(std::optional<std::size_t> error, std::optional<std::size_t> stop = std::nullopt,
         std::atomic<bool>* ctrl_c = nullptr)
      : error_after(error), stop_after(stop), requested(ctrl_c) {}
  std::optional<std::size_t> error_after, stop_after;
  std::atomic<bool>* requested;
  std::size_t read = 0;
  std::vector<std::uint8_t> scratch;  // one buffer, overwritten by every record
  Result<bool> next(CaptureRecord& record) {
    const std::vector<Recorded>& all = records();
    if (stop_after && read == *stop_after) requested->store(true);
    if (error_after && read == *error_after) {
      return fail("capture.pcap: frame " + std::to_string(read + 1) + ": cut short");
    }
    if (read == all.size()) return false;
    const Recorded& r = all[read++];
    scratch = r.bytes;
    record = CaptureRecord{};
    record.frame = read;
    record.time_ns = r.time_ns;
    record.data = scratch.data();
    record.captured = r.bytes.size();
    record.original = r.original;
    record.link = LinkType::Ethernet;
    return true;
  }
};

struct RunCase {
  const char* name;
  BatchLimits limits;
  std::optional<std::size_t> error_after;
  TimeWindow window;
};

struct Outcome {
  std::vector<std::string> events;
  std::optional<std::string> error;
  CaptureRun run;
};

PipelineOptions optionsOf(const RunCase& c) {
  return {DecoderOptions{}, RuleSettings{}, c.window, TimestampMode::Auto};
}

// The reference: streamCapture's loop on one thread.
Outcome oneThread(const RunCase& c) {
  CapturePipeline pipeline(optionsOf(c));
  Seen seen;
  pipeline.setSinks(seen.sinks(pipeline));
  Source source(c.error_after);
  CaptureRecord record;
  Result<bool> status;
  while ((status = source.next(record)) && *status) pipeline.onRecord(record);
  pipeline.finish();
  Outcome out{seen.events, std::nullopt, pipeline.run()};
  if (!status) out.error = status.error().text();
  return out;
}

Outcome twoThreads(const RunCase& c) {
  CapturePipeline pipeline(optionsOf(c));
  Seen seen;
  pipeline.setSinks(seen.sinks(pipeline));
  Source source(c.error_after);
  const Status status = streamOnTwoThreads(
      [&](CaptureRecord& record) { return source.next(record); }, pipeline, nullptr, c.limits);
  Outcome out{seen.events, std::nullopt, pipeline.run()};
  if (!status) out.error = status.error().text();
  return out;
}

class TwoThreadsTest : public ::testing::TestWithParam<RunCase> {};

TEST_P(TwoThreadsTest, TheSinksSeeWhatOneThreadShowsThem) {
  const RunCase& c = GetParam();
  const Outcome one = oneThread(c);
  const Outcome two = twoThreads(c);
  const bool long_enough = !c.error_after || *c.error_after > 100;
  if (long_enough) {
    ASSERT_GT(one.events.size(), 100u);
  }
  EXPECT_EQ(two.events, one.events);
  EXPECT_EQ(two.error, one.error);
  EXPECT_EQ(two.run.records, one.run.records);
  EXPECT_EQ(two.run.in_window, one.run.in_window);
  EXPECT_EQ(two.run.snapped, one.run.snapped);
  EXPECT_EQ(two.run.first_snapped, one.run.first_snapped);
  if (long_enough) {
    EXPECT_GT(one.run.snapped, 0u);
  }
  EXPECT_EQ(one.error.has_value(), c.error_after.has_value());
}

const RunCase kRunCases[] = {
    {"default batches", BatchLimits{}, std::nullopt, TimeWindow{}},
    {"one record a batch", {1, 1 << 16, 1}, std::nullopt, TimeWindow{}},
    {"small batches", {7, 1 << 16, 2}, std::nullopt, TimeWindow{}},
    {"batches cut by bytes", {512, 300, 3}, std::nullopt, TimeWindow{}},
    {"a byte limit below one record", {512, 1, 2}, std::nullopt, TimeWindow{}},
    {"read error mid-capture", {64, 1 << 16, 2}, 1500, TimeWindow{}},
    {"read error mid-batch", {1000, 1 << 20, 2}, 1234, TimeWindow{}},
    {"read error at the first record", BatchLimits{}, 0, TimeWindow{}},
    {"time window", {33, 1 << 16, 2}, std::nullopt, {400'000'000, 900'000'000}},
};
INSTANTIATE_TEST_SUITE_P(Cases, TwoThreadsTest, ::testing::ValuesIn(kRunCases),
                         test::rowName<RunCase>);

// Ctrl-C: the stream ends unfinished before the record it was asked before; no end of capture is
// judged, and the reading thread learns of it at once.
TEST(TwoThreads, CtrlCStopsBothThreadsUnfinished) {
  for (const std::size_t stop_after : {0u, 1u, 700u, 2000u}) {
    SCOPED_TRACE(stop_after);
    const Outcome one = oneThread({"", {}, std::nullopt, {}});
    CapturePipeline pipeline(optionsOf({"", {}, std::nullopt, {}}));
    Seen seen;
    pipeline.setSinks(seen.sinks(pipeline));
    std::atomic<bool> requested{false};
    Source source(std::nullopt, stop_after, &requested);
    StreamStop stop{&requested};
    const Status status =
        streamOnTwoThreads([&](CaptureRecord& record) { return source.next(record); }, pipeline,
                           &stop, {16, 1 << 16, 2});
    EXPECT_TRUE(status);
    EXPECT_TRUE(stop.stopped);
    EXPECT_EQ(pipeline.run().records, stop_after);  // as one thread says where it stopped
    ASSERT_LE(seen.events.size(), one.events.size());
    EXPECT_TRUE(std::equal(seen.events.begin(), seen.events.end(), one.events.begin()));
  }
}

// A sink that throws ends the reading too, a few batches on, and the caller gets the exception.
TEST(TwoThreads, AFailingSinkEndsTheReading) {
  CapturePipeline pipeline(optionsOf({"", {}, std::nullopt, {}}));
  std::size_t frames = 0;
  pipeline.setSinks({nullptr,
                     [&](const PipelineFrame&) {
                       if (++frames == 1000) throw std::runtime_error("cannot write");
                     },
                     nullptr, nullptr, nullptr});
  Source source(std::nullopt);
  const BatchLimits limits{8, 1 << 16, 2};
  EXPECT_THROW(streamOnTwoThreads([&](CaptureRecord& record) { return source.next(record); },
                                  pipeline, nullptr, limits),
               std::runtime_error);
  EXPECT_GE(frames, 1000u);
  EXPECT_LT(source.read, records().size());
}

}  // namespace
}  // namespace ncservo
