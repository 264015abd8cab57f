// What the incidents' causes measure of one axis beyond the signals the rules read
// (docs/incidents.md#causes): set-point steps, the rises of SSW.TempWarning, SSW.NoEncoder and
// SEW.FollowerErr, the last value of each message code and a minute of motor temperature. Taken
// from every frame, also those the validator's fast path does not judge again; bounded.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>

#include "ncservo/base/stamp.hpp"
#include "ncservo/protocol/pdo.hpp"

namespace ncservo {

inline constexpr std::int64_t kMsNs = 1'000'000;

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

// docs/incidents.md#following-error-after-step: a set-point step is an SSP change of at least
// kStepMinimum in one cycle that is at least kStepFactor times every change of the kStepHistory
// cycles before it and of the cycle after it (at least kStepHistoryMinimum of them seen).
inline constexpr std::uint32_t kStepFactor = 8;
inline constexpr std::size_t kStepHistory = 16;
inline constexpr std::size_t kStepHistoryMinimum = 4;
inline constexpr std::int64_t kStepMinimum = 100;

// An SSP step (kStepFactor above).
struct Step {
  Mark at;
  std::int64_t from = 0;
  std::int64_t to = 0;
  std::uint64_t before_max = 0;  // the largest change of the cycles before it
};

// The message code whose data is the motor temperature in °C (docs/protocol.md §5).
inline constexpr std::int32_t kMotorTemperatureCode = 4;

// What the drive reported just before (docs/protocol.md §5): one key per message code, from the
// last cycle that carried it.
struct BeforeDef {
  std::int32_t message_code;
  const char* key;  // the JSON key, public
};
inline constexpr std::array<BeforeDef, 4> kBefore{{
    {1, "motor_current_a"},
    {kMotorTemperatureCode, "motor_temperature_c"},
    {3, "bus_voltage_v"},
    {0, "speed_rpm"},
}};

// A motor temperature within this much of a second's lowest is at that second's steady level
// (docs/incidents.md#overtemperature).
inline constexpr double kSteadyBandC = 1.0;
// The lowest motor temperature of one second of the segment's clock, and the last reading of that
// second at its steady level: where a rise left it.
struct TemperatureBucket {
  std::int64_t second = std::numeric_limits<std::int64_t>::min();
  double lowest = 0;
  Mark steady_at;
  double steady = 0;
};
inline constexpr std::int64_t kTemperatureWindowS = 60;

// The drive's messages up to some frame: the last value of each kBefore code and the lowest
// motor temperature of each second of the minute before.
struct MessageHistory {
  std::array<std::optional<double>, kBefore.size()> before{};  // by kBefore row
  std::array<Mark, kBefore.size()> before_at{};                // ... and where each came
  std::array<TemperatureBucket, kTemperatureWindowS + 1> temperature{};
  std::optional<Mark> temperature_last_at;
  double temperature_last = 0;

  void take(std::int32_t code, double value, const Mark& at);
};

class AxisMeasurements {
 public:
  // A set point the NC sent, once per cycle (a master's copy, or a returned copy whose master's
  // copy was not captured).
  void takeSetPoint(std::int32_t ssp, const Mark& at);
  // The inputs of a returned copy; returns whether SEW.ServoErrors rose in them.
  bool takeInputs(const PdoValues& values, const Mark& at);
  // A capture segment starts (docs/timing.md#rule-time): every window starts afresh.
  void reset();

  // The last inputs taken.
  bool inputsKnown() const { return inputs_known_; }
  std::uint32_t ssw() const { return ssw_; }
  std::uint32_t sew() const { return sew_; }
  // The SEW bits that rose in the inputs taken in `frame` (none on the first inputs).
  std::uint32_t sewRoseIn(std::uint64_t frame) const {
    return inputs_frame_ == frame ? sew_rose_ : 0;
  }
  const std::optional<Mark>& tempWarningRose() const { return temp_warning_rose_; }
  const std::optional<Mark>& noEncoderRose() const { return no_encoder_rose_; }
  const std::optional<Mark>& followingRose() const { return following_rose_; }
  // A step whose next cycle is not seen yet, and the confirmed ones.
  const std::optional<Step>& stepCandidate() const { return candidate_; }
  const Ring<Step, 4>& steps() const { return steps_; }
  const MessageHistory& messages() const { return messages_; }
  // The messages as they stood before the inputs of `frame` when SEW.ServoErrors rose there
  // (what the drive said before its fault), else as they stand.
  const MessageHistory& messagesBefore(std::uint64_t frame) const {
    return fault_frame_ == frame ? before_fault_ : messages_;
  }

 private:
  bool inputs_known_ = false;
  std::uint32_t ssw_ = 0;
  std::uint32_t sew_ = 0;
  std::uint64_t inputs_frame_ = 0;
  std::uint32_t sew_rose_ = 0;
  std::optional<Mark> temp_warning_rose_;
  std::optional<Mark> no_encoder_rose_;
  std::optional<Mark> following_rose_;

  bool ssp_known_ = false;
  std::int64_t ssp_ = 0;
  std::array<std::uint64_t, kStepHistory> changes_{};
  std::size_t change_count_ = 0;
  std::size_t change_next_ = 0;
  std::optional<Step> candidate_;
  Ring<Step, 4> steps_;

  MessageHistory messages_;
  MessageHistory before_fault_;
  std::uint64_t fault_frame_ = 0;
};

}  // namespace ncservo
