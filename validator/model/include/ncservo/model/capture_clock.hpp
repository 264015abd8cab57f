// Which clock judges a capture (docs/timing.md#the-clock, docs/protocol.md §12). The capturing PC's
// stamps can be quantised (several cycles on one stamp), bunched (a NIC's interrupt coalescing:
// bursts a few µs apart) or late; the bus keeps its own time, read by the master every cycle from
// the reference clock (0x0910) and carried back in the returned copy. A capture is judged on the
// probe's clock when it has one, else on its own stamps when they are fit, else on the bus's; when
// none can be trusted, time is counted in cycles at the nominal cycle. Numbers only: the pipeline
// times the frames with the choice (pipeline/clock_stage.hpp), the reports present it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo {

enum class ClockSource : std::uint8_t { Capture, Probe, Bus, Cycles };

// One row per clock: its name in every report (JSON `clock.source`, the text's `clock:` line, the
// plugin's ncservo.clock) and what it is.
struct ClockSourceRow {
  ClockSource source;
  const char* name;
  const char* meaning;
};
inline constexpr std::array<ClockSourceRow, 4> kClockSources{{
    {ClockSource::Capture, "capture", "the capture's own timestamps"},
    {ClockSource::Probe, "probe", "the ESL probe's timestamps"},
    {ClockSource::Bus, "bus", "the reference clock's system time read every cycle (0x0910)"},
    {ClockSource::Cycles, "cycles", "cycles counted at the nominal cycle time"},
}};
const char* clockSourceName(ClockSource source);
const char* clockSourceMeaning(ClockSource source);

// A read of a slave's system time (0x0910, 64 bits or 32) in a copy some slave answered: the
// value the frame picked up as it passed that clock.
struct SystemTimeRead {
  std::uint64_t raw = 0;
  bool wide = false;  // 64 bits
  std::uint8_t command = 0;
  std::uint16_t adp = 0;  // the station address (FPRD, FRMW) or ring position it names
};
// The frame's first read of the system time that a slave answered (WKC > 0): FRMW, ARMW, FPRD,
// APRD or BRD, of 4 or 8 bytes at 0x0910 or a block that holds them.
std::optional<SystemTimeRead> systemTimeRead(const EcatFrame& frame, const ByteReader& bytes);

// Whether two reads are of the same clock: the same command, and the same slave where the
// address survives the ring (a broadcast's or an auto-increment read's comes back changed).
bool sameClock(const SystemTimeRead& a, const SystemTimeRead& b);
// Whether the frame asks for a system time: its datagram headers alone, so a master copy does too,
// before any slave answered.
bool asksSystemTime(const EcatFrame& frame);

// 32-bit reads of the system time made 64-bit across their wrap-around (every 4.3 s).
class SystemTimeUnwrapper {
 public:
  std::uint64_t extend(const SystemTimeRead& read);

 private:
  std::optional<std::uint64_t> last_;
};

// What the capture's own stamps are fit for, from the intervals between consecutive copies of one
// cyclic frame in the first cycles of the capture.
struct CaptureStamps {
  std::uint64_t intervals = 0;
  std::uint64_t zero_intervals = 0;   // two cycles on one stamp
  std::uint64_t short_intervals = 0;  // under a quarter of the cycle
  std::int64_t cycle_ns = 0;          // the bus's cycle (its clock's median), else the stamps' mean
  bool quantised = false;             // a tenth of the intervals or more are zero
  bool bunched = false;               // a twentieth or more are short, not zero
  bool late = false;  // later than a quarter of the cycle (p99) against the bus clock
  std::optional<std::int64_t> quantum_ns;  // quantised: the smallest step of the stamps
  std::optional<std::int64_t> burst_ns;    // bunched: the median interval between bursts
  // Against the bus clock: how late the stamps were, the 99th percentile over the earliest. Late
  // stamps are short intervals too: they are late, not bunched, when the bursts are no longer
  // than two cycles.
  std::optional<std::int64_t> late_p99_ns;
  bool fit() const { return intervals > 0 && !quantised && !bunched && !late; }
  // Fit with nothing to watch: no short interval at all, and late by no more than an eighth of
  // the cycle.
  bool clean() const {
    return fit() && short_intervals == 0 && (!late_p99_ns || *late_p99_ns * 8 <= cycle_ns);
  }
};

// The first cycles of a capture, taken apart: the capture stamps of one cyclic frame's copies,
// with the bus's time where they carried a read of it.
class StampAssessor {
 public:
  // Cycles enough to judge the stamps by; fewer judge them when the capture ends first.
  static constexpr std::size_t kCycles = 128;
  // Fewer intervals than this say nothing about the stamps.
  static constexpr std::size_t kFewest = 8;
  // Stamps clean over this many cycles are judged fit there: a single pass in Wireshark holds
  // its first frames no longer than it must.
  static constexpr std::size_t kEarlyCycles = 32;

  // One copy of the cyclic frame: its capture stamp and the bus's time of the last read of the
  // reference clock before it (once a cycle, in that frame or another), if any.
  void add(std::int64_t capture_ns, std::optional<std::uint64_t> bus_ns);
  // A read of the reference clock and the stamp of the frame that carried it: how late the
  // stamps are against the bus's clock.
  void addRead(std::int64_t capture_ns, std::uint64_t bus_ns);
  std::size_t samples() const { return samples_.size(); }
  bool enough() const { return samples_.size() > kCycles; }
  // Whether the bus's times advance, every one, by about what the stamps say on average: a clock
  // to time cycles by.
  bool busClockUsable() const;
  CaptureStamps stamps() const;

 private:
  struct Sample {
    std::int64_t capture_ns;
    std::optional<std::uint64_t> bus_ns;
  };
  std::optional<std::int64_t> busCycleNs() const;
  std::optional<std::int64_t> lateP99Ns() const;
  std::vector<Sample> samples_;
  std::vector<Sample> reads_;
};

// The clock a capture is judged on, and why: what every report says (`clock`).
struct ClockChoice {
  ClockSource source = ClockSource::Capture;
  std::string why;
  CaptureStamps stamps;
  std::optional<SystemTimeRead> reference;  // the read the bus clock takes (Bus)
  std::int64_t cycle_ns = 0;                // Cycles: the nominal cycle time counted in
};

// The choice from what the first cycles showed: the probe's when it timed the capture; the
// capture's own when its stamps are fit (or too few to judge); else the bus's when the frames
// read it and it advances; else cycles.
ClockChoice chooseClock(bool probe_timed, const StampAssessor& assessed,
                        const std::optional<SystemTimeRead>& reference);

// "bus (reference clock 0x1001); capture stamps bunched into 4 ms bursts: 480 of 512 intervals
// under 62 us": the text report's `clock:` line after the colon.
std::string describeClock(const ClockChoice& choice);

}  // namespace ncservo
