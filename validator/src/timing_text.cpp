#include "ncservo/timing_text.hpp"

#include <fmt/format.h>

namespace ncservo {

namespace {
// Microseconds with as many decimals as the timestamps resolve (µs: one; finer: ns).
std::string us(std::int64_t ns, int decimals) {
  return fmt::format("{:.{}f}", static_cast<double>(ns) / 1000.0, decimals);
}

std::string seriesLine(const SeriesSummary& s, int decimals) {
  const std::string mean = fmt::format("{:.{}f}", s.mean_ns / 1000.0, decimals);
  const std::string sd = fmt::format("{:.{}f}", s.stddev_ns / 1000.0, decimals);
  return fmt::format("min {} p1 {} median {} mean {} sd {} p99 {} p99.9 {} max {} us ({}{})",
                     us(s.min_ns, decimals), us(s.p1_ns, decimals), us(s.median_ns, decimals), mean,
                     sd, us(s.p99_ns, decimals), us(s.p999_ns, decimals), us(s.max_ns, decimals),
                     s.count, s.exact ? "" : ", quantiles from the histogram");
}
}  // namespace

std::string timingText(const TimingSummary& timing, const char* timestamps,
                       std::int64_t resolution_ns) {
  const int decimals = resolution_ns >= 1000 ? 1 : 3;
  std::string out = fmt::format("timing ({} timestamps, {} ns): ", timestamps, resolution_ns);
  if (!timing.cycle) return out + "no cycle intervals\n";
  out += "cycle " + seriesLine(*timing.cycle, decimals) + "\n";
  if (timing.latency) {
    out += "  return latency at the capture point " + seriesLine(*timing.latency, decimals) + "\n";
  }
  const TimedFrames& cycle = timing.worst_cycles.front();
  out += fmt::format("  worst cycle {} us at frame {} (since frame {})", us(cycle.ns, decimals),
                     cycle.frame, cycle.since_frame);
  if (!timing.worst_latencies.empty()) {
    const TimedFrames& latency = timing.worst_latencies.front();
    out += fmt::format("; worst latency {} us at frame {} (master frame {})",
                       us(latency.ns, decimals), latency.frame, latency.since_frame);
  }
  return out + "\n";
}

}  // namespace ncservo
