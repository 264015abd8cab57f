#include "ncservo/model/interval_stats.hpp"

#include <algorithm>
#include <cmath>

namespace ncservo {

std::int64_t IntervalStats::bucketOf(std::int64_t ns) const {
  // Round to the nearest bucket; intervals never go below zero (timers use the latest time).
  return (std::max<std::int64_t>(ns, 0) + resolution_ns_ / 2) / resolution_ns_;
}

void IntervalStats::add(std::int64_t interval_ns) {
  max_ns_ = count_ == 0 ? interval_ns : std::max(max_ns_, interval_ns);
  const std::int64_t bucket = bucketOf(interval_ns);
  // A steady cycle's intervals mostly fall in the median's bucket: no look-up for them.
  if (count_ != 0 && bucket == median_->first) {
    ++median_->second;
  } else {
    auto [it, inserted] = buckets_.try_emplace(bucket, 0);
    ++it->second;
    if (count_ == 0) {
      median_ = it;
      below_median_ = 0;
    } else if (bucket < median_->first) {
      ++below_median_;
    }
  }
  ++count_;
  rebalance();
  if (buckets_.size() > kMaxBuckets) coarsen();
}

void IntervalStats::merge(const IntervalStats& other) {
  if (other.count_ == 0) return;
  if (count_ == 0) resolution_ns_ = std::max(resolution_ns_, other.resolution_ns_);
  while (resolution_ns_ < other.resolution_ns_) coarsen();
  for (const auto& [bucket, n] : other.buckets_) {
    buckets_[bucketOf(bucket * other.resolution_ns_)] += n;
  }
  max_ns_ = count_ == 0 ? other.max_ns_ : std::max(max_ns_, other.max_ns_);
  count_ += other.count_;
  median_ = buckets_.begin();
  below_median_ = 0;
  rebalance();
  while (buckets_.size() > kMaxBuckets) coarsen();
}

void IntervalStats::clear() {
  buckets_.clear();
  below_median_ = 0;
  count_ = 0;
  resolution_ns_ = 1000;
  max_ns_ = 0;
}

// Moves the median iterator so that it holds the element of rank (count - 1) / 2.
void IntervalStats::rebalance() {
  const std::uint64_t rank = (count_ - 1) / 2;
  while (below_median_ > rank) {
    --median_;
    below_median_ -= median_->second;
  }
  while (below_median_ + median_->second <= rank) {
    below_median_ += median_->second;
    ++median_;
  }
}

void IntervalStats::coarsen() {
  std::map<std::int64_t, std::uint64_t> merged;
  resolution_ns_ *= 2;
  for (const auto& [bucket, n] : buckets_) merged[(bucket + 1) / 2] += n;
  buckets_.swap(merged);
  median_ = buckets_.begin();
  below_median_ = 0;
  rebalance();
}

std::optional<std::int64_t> IntervalStats::medianNs() const {
  if (count_ == 0) return std::nullopt;
  return median_->first * resolution_ns_;
}

std::optional<std::int64_t> IntervalStats::quantileNs(double q) const {
  if (count_ == 0) return std::nullopt;
  const auto rank =
      static_cast<std::uint64_t>(std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(count_)));
  std::uint64_t seen = 0;
  for (const auto& [bucket, n] : buckets_) {
    seen += n;
    if (seen >= std::max<std::uint64_t>(rank, 1)) return bucket * resolution_ns_;
  }
  return buckets_.rbegin()->first * resolution_ns_;
}

std::optional<std::int64_t> IntervalStats::maxNs() const {
  if (count_ == 0) return std::nullopt;
  return max_ns_;
}

}  // namespace ncservo
