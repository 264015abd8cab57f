#include "ncservo/model/axis_measurements.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "ncservo/protocol/word_bits.hpp"

namespace ncservo {

namespace {
constexpr std::uint32_t kTempWarning = mask32("ncservo.ssw.temp_warning");
}  // namespace

void MessageHistory::take(std::int32_t code, double value, const Mark& at) {
  for (std::size_t k = 0; k < kBefore.size(); ++k) {
    if (kBefore[k].message_code == code) {
      before[k] = value;
      before_at[k] = at;
    }
  }
  if (code != kMotorTemperatureCode) return;
  temperature_last = value;
  temperature_last_at = at;
  const std::int64_t second = at.clock_ns / 1'000'000'000;
  constexpr auto kBuckets = static_cast<std::int64_t>(kTemperatureWindowS + 1);
  TemperatureBucket& b =
      temperature[static_cast<std::size_t>(((second % kBuckets) + kBuckets) % kBuckets)];
  if (b.second != second) {
    b = TemperatureBucket{second, value, at, value};
  } else {
    b.lowest = std::min(b.lowest, value);
  }
  if (value <= b.lowest + kSteadyBandC) {
    b.steady_at = at;
    b.steady = value;
  }
}

void AxisMeasurements::takeSetPoint(std::int32_t ssp, const Mark& at) {
  if (ssp_known_) {
    const auto change = static_cast<std::uint64_t>(std::llabs(std::int64_t{ssp} - ssp_));
    if (candidate_) {
      // Confirmed when the cycle after it changes far less (a ramp's start is no step).
      if (change * kStepFactor <=
          static_cast<std::uint64_t>(std::llabs(candidate_->to - candidate_->from))) {
        steps_.push(*candidate_);
      }
      candidate_.reset();
    }
    const std::size_t seen = std::min(change_count_, kStepHistory);
    if (seen >= kStepHistoryMinimum && change >= static_cast<std::uint64_t>(kStepMinimum)) {
      // A step is kStepFactor times every change before it: the first that is not ends the
      // look (a moving set point's does at once).
      std::uint64_t before_max = 0;
      bool step = true;
      for (std::size_t k = 0; k < seen && step; ++k) {
        step = kStepFactor * changes_[k] <= change;
        before_max = std::max(before_max, changes_[k]);
      }
      if (step) candidate_ = Step{at, ssp_, ssp, before_max};
    }
    changes_[change_next_] = change;
    change_next_ = (change_next_ + 1) % kStepHistory;
    ++change_count_;
  }
  ssp_ = ssp;
  ssp_known_ = true;
}

bool AxisMeasurements::takeInputs(const PdoValues& values, const Mark& at) {
  using namespace bits;
  const std::uint32_t ssw = values.ssw();
  const std::uint32_t sew = values.sew();
  sew_rose_ = 0;
  if (inputs_known_) {
    const std::uint32_t ssw_rose = ssw & ~ssw_;
    sew_rose_ = sew & ~sew_;
    if (ssw_rose & kTempWarning) temp_warning_rose_ = at;
    if (ssw_rose & kNoEncoder) no_encoder_rose_ = at;
    if (sew_rose_ & kFollowing) following_rose_ = at;
    if (sew_rose_ & kServoErrors) {
      before_fault_ = messages_;
      fault_frame_ = at.frame;
    }
  }
  inputs_frame_ = at.frame;
  ssw_ = ssw;
  sew_ = sew;
  inputs_known_ = true;
  const double data = values.msgData();
  if (std::isfinite(data)) messages_.take(values.msgCode(), data, at);
  return fault_frame_ == at.frame && (sew_rose_ & bits::kServoErrors) != 0;
}

void AxisMeasurements::reset() {
  messages_.temperature = {};
  messages_.temperature_last_at.reset();
  temp_warning_rose_.reset();
  no_encoder_rose_.reset();
  following_rose_.reset();
  inputs_known_ = false;
  ssp_known_ = false;
  change_count_ = 0;
  change_next_ = 0;
  candidate_.reset();
  steps_.clear();
}

}  // namespace ncservo
