// Running statistics of the cycle intervals (docs/timing.md#rule-time, COM-002): the median of all
// intervals so far after every one, plus p99 and max for the report — in bounded memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>

namespace ncservo {

class IntervalStats {
 public:
  // Distinct bucket values kept; beyond it the resolution halves (rare: jitter spans few µs).
  static constexpr std::size_t kMaxBuckets = 16384;

  IntervalStats() = default;
  IntervalStats(const IntervalStats& other) { merge(other); }
  IntervalStats& operator=(const IntervalStats&) = delete;

  void add(std::int64_t interval_ns);
  // Adds another's intervals (a capture segment's to those of the segments before it).
  void merge(const IntervalStats& other);
  void clear();
  std::uint64_t count() const { return count_; }
  // The running median (lower median), in ns at the current resolution (1 µs to start with).
  std::optional<std::int64_t> medianNs() const;
  std::optional<std::int64_t> quantileNs(double q) const;  // walks the buckets: for reports
  std::optional<std::int64_t> maxNs() const;
  std::int64_t resolutionNs() const { return resolution_ns_; }

 private:
  std::int64_t bucketOf(std::int64_t ns) const;
  void coarsen();
  void rebalance();

  std::map<std::int64_t, std::uint64_t> buckets_;  // bucket -> intervals in it
  std::map<std::int64_t, std::uint64_t>::iterator median_;
  std::uint64_t below_median_ = 0;  // intervals in buckets before median_
  std::uint64_t count_ = 0;
  std::int64_t resolution_ns_ = 1000;
  std::int64_t max_ns_ = 0;
};

}  // namespace ncservo
