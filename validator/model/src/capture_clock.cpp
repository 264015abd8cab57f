#include "ncservo/model/capture_clock.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "ncservo/model/dc_clock.hpp"
#include "ncservo/wire/slave_directory.hpp"

namespace ncservo {

namespace {
// A read of the reference clock: the commands masters read it with (docs/protocol.md §12).
constexpr bool readsSystemTime(std::uint8_t command) {
  return command == ecat::kFrmw || command == ecat::kArmw || command == ecat::kFprd ||
         command == ecat::kAprd || command == ecat::kBrd;
}

std::int64_t medianOf(std::vector<std::int64_t> values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>((values.size() - 1) / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

std::string microseconds(std::int64_t ns) {
  return fmt::format("{:g} us", static_cast<double>(ns) / 1000.0);
}

// "4 ms" for whole milliseconds, else microseconds.
std::string duration(std::int64_t ns) {
  if (ns >= 1'000'000 && ns % 100'000 == 0) {
    return fmt::format("{:g} ms", static_cast<double>(ns) / 1e6);
  }
  return microseconds(ns);
}

// Whole milliseconds when the value is within 2 % of one (a burst length read off noisy stamps).
std::int64_t roundedBurst(std::int64_t ns) {
  const std::int64_t ms = (ns + 500'000) / 1'000'000;
  return ms > 0 && std::abs(ns - ms * 1'000'000) * 50 <= ms * 1'000'000 ? ms * 1'000'000 : ns;
}

std::string stampsProblem(const CaptureStamps& s) {
  if (s.late) {
    return fmt::format(
        "capture stamps late by up to {} (p99) against the bus clock, over a quarter "
        "of the {} cycle",
        microseconds(s.late_p99_ns.value_or(0)), microseconds(s.cycle_ns));
  }
  if (s.quantised) {
    return fmt::format("capture stamps quantised to {}: {} of {} intervals are zero",
                       duration(s.quantum_ns.value_or(0)), s.zero_intervals, s.intervals);
  }
  return fmt::format("capture stamps bunched{}: {} of {} intervals under {}",
                     s.burst_ns ? " into " + duration(roundedBurst(*s.burst_ns)) + " bursts" : "",
                     s.short_intervals, s.intervals, microseconds(s.cycle_ns / 4));
}
}  // namespace

const char* clockSourceName(ClockSource source) {
  for (const ClockSourceRow& row : kClockSources) {
    if (row.source == source) return row.name;
  }
  return "capture";
}

const char* clockSourceMeaning(ClockSource source) {
  for (const ClockSourceRow& row : kClockSources) {
    if (row.source == source) return row.meaning;
  }
  return kClockSources.front().meaning;
}

std::optional<SystemTimeRead> systemTimeRead(const EcatFrame& frame, const ByteReader& bytes) {
  for (std::size_t i = 0; i < frame.count; ++i) {
    const Datagram& dg = frame.datagrams[i];
    if (!readsSystemTime(dg.command) || !dg.has_wkc || dg.wkc == 0) continue;
    if (const std::optional<std::size_t> at = registerAt(dg, ecat::kRegDcSystemTime, 8)) {
      if (const std::optional<std::uint64_t> raw = bytes.le64(*at)) {
        return SystemTimeRead{*raw, true, dg.command, dg.adp()};
      }
    }
    if (const std::optional<std::size_t> at = registerAt(dg, ecat::kRegDcSystemTime, 4)) {
      if (const std::optional<std::uint32_t> raw = bytes.le32(*at)) {
        return SystemTimeRead{*raw, false, dg.command, dg.adp()};
      }
    }
  }
  return std::nullopt;
}

bool sameClock(const SystemTimeRead& a, const SystemTimeRead& b) {
  return a.command == b.command && (!ecat::addressSurvivesRing(a.command) || a.adp == b.adp);
}

bool asksSystemTime(const EcatFrame& frame) {
  for (std::size_t i = 0; i < frame.count; ++i) {
    const Datagram& dg = frame.datagrams[i];
    if (readsSystemTime(dg.command) && dg.ado() <= ecat::kRegDcSystemTime &&
        std::size_t{dg.ado()} + dg.length >= std::size_t{ecat::kRegDcSystemTime} + 4) {
      return true;
    }
  }
  return false;
}

std::uint64_t SystemTimeUnwrapper::extend(const SystemTimeRead& read) {
  if (read.wide || !last_) {
    last_ = read.raw;
    return read.raw;
  }
  // The low 32 bits advanced by their unsigned difference (less than a wrap between two reads).
  const auto step = static_cast<std::uint32_t>(read.raw - static_cast<std::uint32_t>(*last_));
  last_ = *last_ + step;
  return *last_;
}

void StampAssessor::add(std::int64_t capture_ns, std::optional<std::uint64_t> bus_ns) {
  if (enough()) return;
  samples_.push_back({capture_ns, bus_ns});
}

std::optional<std::int64_t> StampAssessor::busCycleNs() const {
  std::vector<std::int64_t> steps;
  for (std::size_t i = 1; i < samples_.size(); ++i) {
    if (samples_[i].bus_ns && samples_[i - 1].bus_ns) {
      steps.push_back(static_cast<std::int64_t>(*samples_[i].bus_ns - *samples_[i - 1].bus_ns));
    }
  }
  if (steps.size() < kFewest) return std::nullopt;
  if (std::any_of(steps.begin(), steps.end(), [](std::int64_t s) { return s <= 0; })) {
    return std::nullopt;
  }
  return medianOf(std::move(steps));
}

bool StampAssessor::busClockUsable() const {
  const std::optional<std::int64_t> bus_cycle = busCycleNs();
  if (!bus_cycle || samples_.size() < 2) return false;
  // The stamps' mean interval is right however they lie: only their spread is wrong.
  const double mean =
      static_cast<double>(samples_.back().capture_ns - samples_.front().capture_ns) /
      static_cast<double>(samples_.size() - 1);
  return static_cast<double>(*bus_cycle) > mean / 2 && static_cast<double>(*bus_cycle) < mean * 2;
}

void StampAssessor::addRead(std::int64_t capture_ns, std::uint64_t bus_ns) {
  if (reads_.size() < 4 * kCycles) reads_.push_back({capture_ns, bus_ns});
}

// Each read's stamp against the bus's time it carried, less the line through them (the clocks'
// offset and drift), over the earliest.
std::optional<std::int64_t> StampAssessor::lateP99Ns() const {
  if (reads_.size() < kFewest) return std::nullopt;
  LineFit fit;
  const std::uint64_t bus0 = *reads_.front().bus_ns;
  const std::int64_t capture0 = reads_.front().capture_ns;
  const auto point = [&](const Sample& read) {
    const auto x = static_cast<double>(*read.bus_ns - bus0);
    return std::pair{x, static_cast<double>(read.capture_ns - capture0) - x};
  };
  for (const Sample& read : reads_) {
    const auto [x, y] = point(read);
    fit.add(x, y);
  }
  const double slope = fit.slope().value_or(0);
  const double offset = (fit.sy - slope * fit.sx) / fit.n;
  std::vector<std::int64_t> residuals;
  for (const Sample& read : reads_) {
    const auto [x, y] = point(read);
    residuals.push_back(std::llround(y - (offset + slope * x)));
  }
  const std::int64_t earliest = *std::min_element(residuals.begin(), residuals.end());
  for (std::int64_t& r : residuals) r -= earliest;
  std::sort(residuals.begin(), residuals.end());
  return residuals[(residuals.size() * 99 + 99) / 100 - 1];
}

CaptureStamps StampAssessor::stamps() const {
  CaptureStamps s;
  if (samples_.size() < 2) return s;
  s.intervals = samples_.size() - 1;
  if (s.intervals < kFewest) return s;
  const std::int64_t span = samples_.back().capture_ns - samples_.front().capture_ns;
  const bool bus = busClockUsable();
  s.cycle_ns = bus ? *busCycleNs() : span / static_cast<std::int64_t>(s.intervals);
  std::vector<std::int64_t> long_intervals;
  for (std::size_t i = 1; i < samples_.size(); ++i) {
    const std::int64_t interval = samples_[i].capture_ns - samples_[i - 1].capture_ns;
    if (interval == 0) ++s.zero_intervals;
    if (interval * 4 < s.cycle_ns) {
      ++s.short_intervals;
    } else {
      long_intervals.push_back(interval);
    }
    if (interval > 0 && (!s.quantum_ns || interval < *s.quantum_ns)) s.quantum_ns = interval;
  }
  s.quantised = s.zero_intervals * 10 >= s.intervals;
  const bool short_ones = !s.quantised && s.short_intervals * 20 >= s.intervals;
  if (!s.quantised) s.quantum_ns.reset();
  if (short_ones && !long_intervals.empty()) {
    s.burst_ns = medianOf(std::move(long_intervals));
    s.bunched = *s.burst_ns >= 2 * s.cycle_ns;
    if (!s.bunched) s.burst_ns.reset();
  }
  if (bus) {
    s.late_p99_ns = lateP99Ns();
    s.late = s.late_p99_ns && !s.quantised && !s.bunched && *s.late_p99_ns * 4 > s.cycle_ns;
  }
  // Short intervals neither in bursts nor explained by lateness against a bus clock: the stamps
  // cannot be told apart from a bus that sent in bursts, so they are not trusted either.
  s.bunched = s.bunched || (short_ones && !s.late && !bus);
  return s;
}

ClockChoice chooseClock(bool probe_timed, const StampAssessor& assessed,
                        const std::optional<SystemTimeRead>& reference) {
  ClockChoice choice;
  choice.stamps = assessed.stamps();
  const CaptureStamps& s = choice.stamps;
  if (probe_timed) {
    choice.source = ClockSource::Probe;
    choice.why = "the probe timed the frames";
    return choice;
  }
  if (s.intervals < StampAssessor::kFewest) {
    choice.why =
        fmt::format("too few cycles to judge the capture's stamps ({} intervals)", s.intervals);
    return choice;
  }
  if (s.fit()) {
    choice.why =
        fmt::format("capture stamps steady: {} intervals, none bunched or quantised", s.intervals);
    if (s.late_p99_ns && *s.late_p99_ns > 0) {
      choice.why += fmt::format("; late by up to {} (p99) against the bus clock",
                                microseconds(*s.late_p99_ns));
    }
    return choice;
  }
  if (reference && assessed.busClockUsable()) {
    choice.source = ClockSource::Bus;
    choice.reference = reference;
    choice.why = stampsProblem(s);
    return choice;
  }
  choice.source = ClockSource::Cycles;
  choice.cycle_ns = s.cycle_ns;
  choice.why = fmt::format("{}; {}: cycles counted at {}", stampsProblem(s),
                           reference ? "the reference clock's reads do not advance with the cycles"
                                     : "no read of the reference clock's system time",
                           microseconds(s.cycle_ns));
  return choice;
}

std::string describeClock(const ClockChoice& choice) {
  std::string head = clockSourceName(choice.source);
  if (choice.source == ClockSource::Bus && choice.reference) {
    head += fmt::format(" (reference clock {:#06x}, {} of 0x0910)", choice.reference->adp,
                        ecat::commandName(choice.reference->command));
  }
  return choice.why.empty() ? head : head + "; " + choice.why;
}

}  // namespace ncservo
