// What the incident detector keeps of each axis and of the bus between frames, and what a cause
// row is given (causes.hpp). Every part is bounded (docs/incidents.md "Memory").
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>

#include "ncservo/base/stamp.hpp"
#include "ncservo/incidents/incident.hpp"
#include "ncservo/rules/rules.hpp"

namespace ncservo {

inline constexpr std::int64_t kMsNs = 1'000'000;

// docs/incidents.md#following-error-after-step: a set-point step is an SSP change of at least
// kStepMinimum in one cycle that is at least kStepFactor times every change of the kStepHistory
// cycles before it and of the cycle after it (at least kStepHistoryMinimum of them seen).
inline constexpr std::uint32_t kStepFactor = 8;
inline constexpr std::size_t kStepHistory = 16;
inline constexpr std::size_t kStepHistoryMinimum = 4;
inline constexpr std::int64_t kStepMinimum = 100;
// docs/incidents.md#overtemperature: the motor temperature rose by at least this much from the
// lowest reading of the minute before to the last one.
inline constexpr double kTemperatureRiseC = 10.0;

// Where something was seen: its frame, the segment's clock (which the windows are measured on,
// docs/timing.md#rule-time) and the frame's own capture time (which reports show).
struct Mark {
  std::uint64_t frame = 0;
  std::int64_t clock_ns = 0;
  std::int64_t time_ns = 0;
  Stamp stamp() const { return Stamp{frame, time_ns}; }
};
// `m` lies at or before `at`, at most `window_ns` before it.
inline bool within(const Mark& m, const Mark& at, std::int64_t window_ns) {
  return m.clock_ns <= at.clock_ns && at.clock_ns - m.clock_ns <= window_ns;
}

// The last N items pushed, newest first.
template <class T, std::size_t N>
class Ring {
 public:
  void push(T item) {
    head_ = (head_ + 1) % N;
    items_[head_] = std::move(item);
    if (count_ < N) ++count_;
  }
  std::size_t size() const { return count_; }
  // 0 is the newest.
  const T& operator[](std::size_t i) const { return items_[(head_ + N - i) % N]; }
  T& newest() { return items_[head_]; }
  void clear() { count_ = 0; }

 private:
  std::array<T, N> items_{};
  std::size_t head_ = 0;
  std::size_t count_ = 0;
};

// Failed cycles of an axis close together (docs/rules.md#com-003): a new failure within
// kFailureMergeNs of the last joins its run.
inline constexpr std::int64_t kFailureMergeNs = 10 * kMsNs;
struct FailureRun {
  Mark first, last;
  std::uint64_t lost = 0;    // cycles lost or not returned
  std::uint64_t failed = 0;  // cycles returned with a wrong WKC
};

struct FindingMark {
  Mark at;
  RuleId rule{};
  std::string what;  // "COM-002 12 cycles lost ..."
};

// The lowest motor temperature of one second of the segment's clock.
struct TemperatureBucket {
  std::int64_t second = std::numeric_limits<std::int64_t>::min();
  double lowest = 0;
  Mark at;
};
inline constexpr std::int64_t kTemperatureWindowS = 60;

// An SSP step (kStepFactor above).
struct Step {
  Mark at;
  std::int64_t from = 0;
  std::int64_t to = 0;
  std::uint64_t before_max = 0;  // the largest change of the cycles before it
};

struct AxisTrack {
  // The last inputs (returned copies with a WKC above zero).
  bool tx_known = false;
  std::uint32_t ssw = 0;
  std::uint32_t sew = 0;
  std::array<std::optional<double>, kBefore.size()> before{};
  std::array<TemperatureBucket, kTemperatureWindowS + 1> temperature{};
  std::optional<Mark> temperature_last_at;
  double temperature_last = 0;
  std::optional<Mark> temp_warning_rose;
  std::optional<Mark> no_encoder_rose;
  std::optional<Mark> following_rose;
  // The set points of the master copies.
  bool ssp_known = false;
  std::int64_t ssp = 0;
  std::array<std::uint64_t, kStepHistory> changes{};
  std::size_t change_count = 0;
  std::size_t change_next = 0;
  std::optional<Step> candidate;  // a step whose next cycle is not seen yet
  Ring<Step, 4> steps;
  Ring<FailureRun, 8> failures;
  Ring<FindingMark, 16> findings;
  // The drive fault not yet recovered: its index in the detector's incidents.
  std::optional<std::size_t> open;

  void resetWindows() {
    temperature = {};
    temperature_last_at.reset();
    temp_warning_rose.reset();
    no_encoder_rose.reset();
    following_rose.reset();
    tx_known = false;
    ssp_known = false;
    change_count = 0;
    change_next = 0;
    candidate.reset();
    steps.clear();
    failures.clear();
    findings.clear();
  }
};

struct BusTrack {
  Ring<FindingMark, 16> findings;  // about the bus, or a slave that is no axis
};

// What a cause row is given: the incident's axis (none for the bus, or a slave that is no axis),
// the bus, the SEW at the incident and where it is.
struct CauseContext {
  IncidentKind kind = IncidentKind::DriveFault;
  const AxisTrack* axis = nullptr;
  const BusTrack* bus = nullptr;
  std::uint32_t sew = 0;
  Mark at;
  std::string what;  // ESM: the state change, for an unknown cause's text
};

}  // namespace ncservo
