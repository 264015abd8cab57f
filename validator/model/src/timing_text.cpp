#include "ncservo/model/timing_text.hpp"

#include <fmt/format.h>

#include "ncservo/model/al_tracker.hpp"

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

std::string dcText(const std::vector<DcStation>& stations, std::int64_t settled_ns,
                   std::string_view against) {
  if (stations.empty()) return {};
  std::string out = fmt::format("distributed clocks (drift against {}, ± at 95 %):\n", against);
  for (const DcStation& s : stations) {
    out += fmt::format("  {}{}:", slaveName(s.slave), s.reference ? ", the reference clock" : "");
    if (s.time_reads > 0) {
      out += s.drift_ppm ? fmt::format(" drift {:+.3f}{} ppm", *s.drift_ppm,
                                       s.drift_uncertainty_ppm
                                           ? fmt::format(" ± {:.3f}", *s.drift_uncertainty_ppm)
                                           : std::string())
                         : " drift unknown";
      if (s.first_half_ppm && s.second_half_ppm) {
        out += fmt::format(" (first half {:+.3f}, second half {:+.3f})", *s.first_half_ppm,
                           *s.second_half_ppm);
      }
      out += fmt::format(" over {} system time read{}", s.time_reads, s.time_reads == 1 ? "" : "s");
      if (s.last_difference_ns) out += ";";
    }
    if (s.last_difference_ns) {
      out += fmt::format(" system time difference last {} ns, max |diff| {} ns over {} read{}, ",
                         *s.last_difference_ns, s.max_abs_difference_ns, s.difference_reads,
                         s.difference_reads == 1 ? "" : "s");
      out += s.settled_frame
                 ? fmt::format("within {} ns from frame {}", settled_ns, *s.settled_frame)
                 : fmt::format("not settled within {} ns", settled_ns);
    }
    out += "\n";
  }
  return out;
}

std::string copiesMissingText(std::uint64_t master, std::uint64_t returned) {
  if (master == 0 && returned == 0) return "";
  return fmt::format(
      "{} master cop{} missing from the capture ({} returned cop{} the cycle{} ran), {} "
      "returned cop{} never came",
      master, master == 1 ? "y" : "ies", master == 1 ? "its" : "their",
      master == 1 ? "y proves" : "ies prove", master == 1 ? "" : "s", returned,
      returned == 1 ? "y" : "ies");
}

}  // namespace ncservo
