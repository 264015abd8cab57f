#include "ncservo/model/timing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ncservo {

namespace {
constexpr std::int64_t kUs = 1000;

// Nearest rank: the smallest sample with at least q of the samples at or below it (the lower
// median for q = 0.5).
std::uint64_t rankOf(double q, std::uint64_t count) {
  const auto rank = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count)));
  return std::clamp<std::uint64_t>(rank, 1, count);
}

std::int64_t exactQuantile(const std::vector<std::int64_t>& sorted, double q) {
  return sorted[rankOf(q, sorted.size()) - 1];
}

// The first bin of each range.
constexpr std::array<std::size_t, TimingSeries::kBinRanges.size()> firstBins() {
  std::array<std::size_t, TimingSeries::kBinRanges.size()> first{};
  std::size_t next = 0;
  for (std::size_t i = 0; i < TimingSeries::kBinRanges.size(); ++i) {
    first[i] = next;
    const TimingSeries::BinRange& r = TimingSeries::kBinRanges[i];
    next += static_cast<std::size_t>((r.to_us - r.from_us) / r.width_us);
  }
  return first;
}
constexpr auto kFirstBins = firstBins();
static_assert(kFirstBins.back() + 45 == TimingSeries::kBinCount);

HistogramBin binBounds(std::size_t bin) {
  std::size_t range = 0;
  while (range + 1 < kFirstBins.size() && kFirstBins[range + 1] <= bin) ++range;
  const TimingSeries::BinRange& r = TimingSeries::kBinRanges[range];
  const std::int64_t from =
      (r.from_us + static_cast<std::int64_t>(bin - kFirstBins[range]) * r.width_us) * kUs;
  return HistogramBin{from, from + r.width_us * kUs, 0};
}
}  // namespace

std::ptrdiff_t TimingSeries::binOf(std::int64_t deviation_ns) {
  if (deviation_ns < kBinRanges.front().from_us * kUs) return -1;
  for (std::size_t i = 0; i < kBinRanges.size(); ++i) {
    const BinRange& r = kBinRanges[i];
    if (deviation_ns < r.to_us * kUs) {
      return static_cast<std::ptrdiff_t>(
          kFirstBins[i] +
          static_cast<std::size_t>((deviation_ns - r.from_us * kUs) / (r.width_us * kUs)));
    }
  }
  return static_cast<std::ptrdiff_t>(kBinCount);
}

void TimingSeries::add(std::int64_t ns) {
  if (count_ == 0) {
    min_ = max_ = first_ = ns;
  } else {
    min_ = std::min(min_, ns);
    max_ = std::max(max_, ns);
  }
  ++count_;
  const double delta = static_cast<double>(ns) - mean_;
  mean_ += delta / static_cast<double>(count_);
  m2_ += delta * (static_cast<double>(ns) - mean_);
  if (!reference_ns_) {
    const std::int64_t offset = ns - first_;
    if (samples_.size() < kExactSamples && offset >= std::numeric_limits<std::int32_t>::min() &&
        offset <= std::numeric_limits<std::int32_t>::max()) {
      samples_.push_back(static_cast<std::int32_t>(offset));
      return;
    }
    fixReference();
  }
  countDeviation(ns - *reference_ns_);
}

void TimingSeries::countDeviation(std::int64_t deviation_ns) {
  const std::ptrdiff_t bin = binOf(deviation_ns);
  if (bin < 0) {
    ++under_;
  } else if (bin >= static_cast<std::ptrdiff_t>(kBinCount)) {
    ++over_;
  } else {
    ++bins_[static_cast<std::size_t>(bin)];
  }
}

// Too many samples to keep: the histogram's zero becomes the median of those kept, which go
// into the histogram.
void TimingSeries::fixReference() {
  const auto middle =
      samples_.begin() + static_cast<std::ptrdiff_t>(rankOf(0.5, samples_.size()) - 1);
  std::nth_element(samples_.begin(), middle, samples_.end());
  reference_ns_ = first_ + *middle;
  for (std::int32_t s : samples_) countDeviation(first_ + s - *reference_ns_);
  samples_.clear();
  samples_.shrink_to_fit();
}

std::optional<SeriesSummary> TimingSeries::summary() const {
  if (count_ == 0) return std::nullopt;
  SeriesSummary s;
  s.count = count_;
  s.min_ns = min_;
  s.max_ns = max_;
  s.mean_ns = mean_;
  s.stddev_ns = std::sqrt(m2_ / static_cast<double>(count_));
  std::array<std::uint64_t, kBinCount> bins = bins_;
  std::uint64_t under = under_, over = over_;
  std::int64_t reference = 0;
  if (!reference_ns_) {
    std::vector<std::int64_t> sorted(samples_.begin(), samples_.end());
    for (std::int64_t& v : sorted) v += first_;
    std::sort(sorted.begin(), sorted.end());
    s.median_ns = exactQuantile(sorted, 0.5);
    s.p1_ns = exactQuantile(sorted, 0.01);
    s.p99_ns = exactQuantile(sorted, 0.99);
    s.p999_ns = exactQuantile(sorted, 0.999);
    reference = s.median_ns;
    for (std::int64_t v : sorted) {
      const std::ptrdiff_t bin = binOf(v - reference);
      if (bin < 0) {
        ++under;
      } else if (bin >= static_cast<std::ptrdiff_t>(kBinCount)) {
        ++over;
      } else {
        ++bins[static_cast<std::size_t>(bin)];
      }
    }
  } else {
    // From the histogram: the middle of the bin that holds the rank, within [min, max].
    s.exact = false;
    reference = *reference_ns_;
    auto quantile = [&](double q) {
      const std::uint64_t rank = rankOf(q, count_);
      std::uint64_t seen = under;
      if (rank <= seen) return min_;
      for (std::size_t b = 0; b < kBinCount; ++b) {
        seen += bins[b];
        if (rank <= seen) {
          const HistogramBin bounds = binBounds(b);
          const std::int64_t middle = reference + (bounds.from_ns + bounds.to_ns) / 2;
          return std::clamp(middle, min_, max_);
        }
      }
      return max_;
    };
    s.median_ns = quantile(0.5);
    s.p1_ns = quantile(0.01);
    s.p99_ns = quantile(0.99);
    s.p999_ns = quantile(0.999);
  }
  s.reference_ns = reference;
  for (std::size_t b = 0; b < kBinCount; ++b) {
    if (bins[b] == 0) continue;
    HistogramBin bin = binBounds(b);
    bin.count = bins[b];
    s.histogram.push_back(bin);
  }
  s.under = under;
  s.over = over;
  return s;
}

void WorstList::add(const TimedFrames& entry) {
  if (entries_.size() == kSize && entry.ns <= entries_.back().ns) return;
  const auto at =
      std::upper_bound(entries_.begin(), entries_.end(), entry,
                       [](const TimedFrames& a, const TimedFrames& b) { return a.ns > b.ns; });
  entries_.insert(at, entry);
  if (entries_.size() > kSize) entries_.pop_back();
}

void TimingStats::onCycle(std::uint64_t frame, std::uint64_t previous_frame,
                          std::int64_t interval_ns) {
  cycles_.add(interval_ns);
  worst_cycles_.add({frame, previous_frame, interval_ns});
}

void TimingStats::onLatency(std::uint64_t frame, std::uint64_t master_frame,
                            std::int64_t latency_ns) {
  latencies_.add(latency_ns);
  worst_latencies_.add({frame, master_frame, latency_ns});
}

TimingSummary TimingStats::summary() const {
  return TimingSummary{cycles_.summary(), latencies_.summary(), worst_cycles_.entries(),
                       worst_latencies_.entries()};
}

}  // namespace ncservo
