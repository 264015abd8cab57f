// Timing statistics of a capture (docs/timing.md): the cycle time between consecutive master
// copies of each cyclic frame and the return latency from a master copy to its returned copy, as
// seen at the capture point. Numbers only; the reports present them. Streaming, in bounded memory:
// quantiles are exact while a series holds at most kExactSamples samples, and come from the
// histogram beyond (error at most half a bin: 0.5 µs within ±50 µs of the median).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace ncservo {

// One bin of the deviation histogram: [from_ns, to_ns) relative to SeriesSummary::reference_ns.
struct HistogramBin {
  std::int64_t from_ns = 0;
  std::int64_t to_ns = 0;
  std::uint64_t count = 0;
};

struct SeriesSummary {
  std::uint64_t count = 0;
  std::int64_t min_ns = 0, max_ns = 0;
  std::int64_t median_ns = 0, p1_ns = 0, p99_ns = 0, p999_ns = 0;
  double mean_ns = 0, stddev_ns = 0;  // the population standard deviation
  bool exact = true;                  // quantiles from every sample, not from the histogram
  // The histogram's zero: the median, or where the series outgrew kExactSamples (or a sample lay
  // more than 2.1 s from the first) the median of the samples kept until then.
  std::int64_t reference_ns = 0;
  std::vector<HistogramBin> histogram;  // the bins that hold samples, in ascending order
  std::uint64_t under = 0, over = 0;    // samples beyond the histogram's range
};

// A stream of durations (ns): exact moments, quantiles and a fixed histogram of the signed
// deviation from the median (the nominal cycle, for cycle times).
class TimingSeries {
 public:
  // Samples kept for exact quantiles, as 32-bit offsets from the first (256 KiB at most).
  static constexpr std::size_t kExactSamples = std::size_t{1} << 16;
  // Histogram ranges, ascending: [from_us, to_us) in bins of width_us. 1 µs bins near nominal,
  // coarser further out; beyond ±5 ms a sample is under or over.
  struct BinRange {
    std::int64_t from_us, to_us, width_us;
  };
  static constexpr std::array<BinRange, 5> kBinRanges{
      {{-5000, -500, 100}, {-500, -50, 10}, {-50, 50, 1}, {50, 500, 10}, {500, 5000, 100}}};
  static constexpr std::size_t kBinCount = 45 + 45 + 100 + 45 + 45;

  void add(std::int64_t ns);
  std::uint64_t count() const { return count_; }
  // Nothing when the series is empty.
  std::optional<SeriesSummary> summary() const;

 private:
  // The histogram bin of a deviation, or -1 (under) / kBinCount (over).
  static std::ptrdiff_t binOf(std::int64_t deviation_ns);
  void fixReference();
  // Into its histogram bin, or under / over.
  void countDeviation(std::int64_t deviation_ns);

  std::uint64_t count_ = 0;
  std::int64_t min_ = 0, max_ = 0;
  double mean_ = 0, m2_ = 0;  // Welford's running mean and sum of squared deviations
  std::int64_t first_ = 0;
  std::vector<std::int32_t> samples_;         // minus first_, while count_ <= kExactSamples
  std::optional<std::int64_t> reference_ns_;  // the histogram's zero once samples_ overflowed
  std::array<std::uint64_t, kBinCount> bins_{};
  std::uint64_t under_ = 0, over_ = 0;
};

// A cycle interval or a return latency with the frames that bound it.
struct TimedFrames {
  std::uint64_t frame = 0;
  std::uint64_t since_frame = 0;  // the previous master copy, or the master copy returned
  std::int64_t ns = 0;
};

// The largest values seen, worst first (equal values: the earlier first).
class WorstList {
 public:
  static constexpr std::size_t kSize = 10;
  void add(const TimedFrames& entry);
  const std::vector<TimedFrames>& entries() const { return entries_; }

 private:
  std::vector<TimedFrames> entries_;
};

// What one frame gave the timing statistics, for presenting them frame by frame (the plugin's
// ncservo.cycle.* and ncservo.latency).
struct FrameTiming {
  std::uint64_t frame = 0;                   // the frame these belong to
  std::optional<std::int64_t> interval_ns;   // the cycle interval this frame closed
  std::optional<std::int64_t> deviation_ns;  // that interval minus the segment's nominal cycle
  std::optional<std::int64_t> latency_ns;    // a returned copy's, since its master copy
};

struct TimingSummary {
  std::optional<SeriesSummary> cycle, latency;
  std::vector<TimedFrames> worst_cycles, worst_latencies;
};

class TimingStats {
 public:
  // An interval between consecutive master copies of one cyclic frame (never across a segment
  // start), reported on the later one.
  void onCycle(std::uint64_t frame, std::uint64_t previous_frame, std::int64_t interval_ns);
  // A returned copy `latency_ns` after its master copy.
  void onLatency(std::uint64_t frame, std::uint64_t master_frame, std::int64_t latency_ns);
  TimingSummary summary() const;

 private:
  TimingSeries cycles_, latencies_;
  WorstList worst_cycles_, worst_latencies_;
};

}  // namespace ncservo
