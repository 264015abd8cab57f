// The simulated drive and NC axis (models.hpp). The drive follows docs/protocol.md §2–7 unless a
// misbehaviour armed in it says otherwise; the NC commands what its plan asks and reacts to the
// drive's status the way the rules (docs/rules.md) expect of a well-behaved NC.
#include "ncservo/sim/models.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace ncservo::sim {
namespace {

constexpr unsigned shiftOf(std::uint32_t mask) {
  unsigned shift = 0;
  while (((mask >> shift) & 1U) == 0) ++shift;
  return shift;
}
double clampTo(double value, double limit) {
  return std::max(-limit, std::min(limit, value));
}
// Moves `value` towards `target` by at most `step`.
double approach(double value, double target, double step) {
  return value + clampTo(target - value, step);
}

// Drive constants: plausible for a 3 kW servo motor; none of them is part of the protocol.
constexpr double kMaxRpm = 6000;
constexpr double kAccelRpmPerS = 20000;      // speed regulator's acceleration limit
constexpr double kEmergencyRpmPerS = 30000;  // braking ramp with EMGON 0 (Emergency Feed 0)
constexpr double kCoastRpmPerS = 3000;       // power stage off
constexpr double kStandstillRpm = 5;         // N=0 threshold
constexpr double kTolerance = 0.02;          // N=Ns: within 2 % (or the standstill threshold)
constexpr double kRatedCurrentA = 8;
constexpr double kTorquePerAmp = 0.9;  // Nm/A
constexpr double kBusVoltage = 560;
constexpr double kAmbientC = 35;
constexpr double kPi = 3.14159265358979323846;

// How long the misbehaviours last: each clearly past its rule's default timeout (docs/rules.md),
// each momentary one well inside drive_response so no other rule follows.
constexpr std::int64_t kPulseNs = 4 * kMs;
constexpr std::int64_t kLateDisableNs = 60 * kMs;          // SE-003 (drive_response 20)
constexpr std::int64_t kIgnoreEnableNs = 160 * kMs;        // SE-004 (enable_response 100)
constexpr std::int64_t kHoldAckNs = 60 * kMs;              // ZP-001, EC-003 (drive_response 20)
constexpr std::int64_t kIgnoreClearNs = 160 * kMs;         // EC-004 (clear_response 100)
constexpr std::int64_t kSummaryOnlyNs = 50 * kMs;          // SEW-002 (drive_response 20)
constexpr std::int64_t kReadyInvertedNs = 50 * kMs;        // RDY-001 (drive_response 20)
constexpr std::int64_t kSlowReactionNs = 200 * kMs;        // FLT-001 (fault_reaction 100)
constexpr std::int64_t kIgnoreTableNs = 120 * kMs;         // PT-001 (param_table 50)
constexpr std::int64_t kQuietBeforeSpuriousNs = 30 * kMs;  // request 0 longer than 20 ms
constexpr std::uint32_t kReservedErrorBit = 1U << 25;
constexpr std::uint32_t kReservedStatusBit = 1U << 13;
constexpr std::uint32_t kReservedControlBit = 1U << 20;
constexpr std::int32_t kUndefinedMessageCode = 7;
// SEW.ECatTErr after this many cycles with no data (docs/protocol.md §4)
constexpr int kLostCyclesForTimeout = static_cast<int>(kEcatTimeoutCycles);
constexpr double kTempWarningC = 80;  // SSW.TempWarning (docs/protocol.md §3)
// How fast a drift settles once it tripped its fault: the motor cools in seconds, the bus
// voltage and the current fall within a few milliseconds.
constexpr double kCoolingS = 1.0;
constexpr double kSettleElectricalS = 0.005;

}  // namespace

PdoValues pdoValues(const RxPdo& pdo) {
  PdoValues values;
  values.set(Word::Ssp, static_cast<std::uint32_t>(pdo.ssp));
  values.set(Word::Scw, pdo.scw);
  values.set(Word::ExtCode, static_cast<std::uint16_t>(pdo.ext_code));
  values.has_rx = true;
  return values;
}
PdoValues pdoValues(const TxPdo& pdo) {
  PdoValues values;
  values.set(Word::ActPos, static_cast<std::uint64_t>(pdo.actpos));
  values.set(Word::Ssw, pdo.ssw);
  values.set(Word::Sew, pdo.sew);
  values.set(Word::MsgCode, static_cast<std::uint32_t>(pdo.msg_code));
  values.setFloat(Word::MsgData, pdo.msg_data);
  constexpr std::array<Word, 4> kExtData = {Word::ExtData1, Word::ExtData2, Word::ExtData3,
                                            Word::ExtData4};
  for (std::size_t i = 0; i < kExtData.size(); ++i) values.setFloat(kExtData[i], pdo.ext_data[i]);
  values.has_tx = true;
  return values;
}
RxPdo rxPdoOf(const PdoValues& values) {
  RxPdo pdo;
  pdo.ssp = static_cast<std::int32_t>(values.word(Word::Ssp));
  pdo.scw = values.scw();
  pdo.ext_code = static_cast<std::int16_t>(values.word(Word::ExtCode));
  return pdo;
}
TxPdo txPdoOf(const PdoValues& values) {
  TxPdo pdo;
  pdo.actpos = static_cast<std::int64_t>(values.word(Word::ActPos));
  pdo.ssw = values.ssw();
  pdo.sew = values.sew();
  pdo.msg_code = values.msgCode();
  pdo.msg_data = values.msgData();
  pdo.ext_data = {values.floatOf(Word::ExtData1), values.floatOf(Word::ExtData2),
                  values.floatOf(Word::ExtData3), values.floatOf(Word::ExtData4)};
  return pdo;
}
void encodeRx(const RxPdo& pdo, std::uint8_t* out) {
  writePdoOf<Pdo::Rx>(pdoValues(pdo), out);
}
void encodeTx(const TxPdo& pdo, std::uint8_t* out) {
  writePdoOf<Pdo::Tx>(pdoValues(pdo), out);
}
RxPdo decodeRx(const std::uint8_t* in) {
  PdoValues values;
  readPdoOf<Pdo::Rx>(ByteReader(in, kRxPdoSize), 0, values);
  return rxPdoOf(values);
}

namespace bits {
std::uint32_t scwTable(int table) {
  const auto index = static_cast<std::uint32_t>(std::clamp(table, 1, 8) - 1);
  return ((index & 3U) << shiftOf(kScwPrmtbl)) | ((index >> 2) << shiftOf(kScwExtPrmtbl));
}
std::uint32_t sswTable(int table) {
  const auto index = static_cast<std::uint32_t>(std::clamp(table, 1, 8) - 1);
  return ((index & 3U) << shiftOf(kSswPrmtbl)) | ((index >> 2) << shiftOf(kSswExtPrmtbl));
}
int tableOfScw(std::uint32_t scw) {
  const std::uint32_t low = (scw & kScwPrmtbl) >> shiftOf(kScwPrmtbl);
  const std::uint32_t high = (scw & kScwExtPrmtbl) >> shiftOf(kScwExtPrmtbl);
  return static_cast<int>(high * 4 + low + 1);
}
}  // namespace bits

// --- drive ---

DriveModel::DriveModel(const DriveSetup& setup)
    : setup_(setup), rng_(setup.seed * 0x100000001B3ULL + static_cast<std::uint64_t>(setup.axis)) {
  enable_delay_ns_ = rng_.between(2, 6) * kMs;
  disable_delay_ns_ = rng_.between(1, 3) * kMs;
  fault_reaction_ns_ = rng_.between(10, 40) * kMs;
  table_delay_ns_ = rng_.between(3, 8) * kMs;
  position_ = static_cast<double>(rng_.between(0, 1 << 24));
}

void DriveModel::arm(DriveQuirk quirk, std::int64_t from_ns) {
  quirks_.push_back({quirk, from_ns});
}

DriveModel::Armed* DriveModel::active(DriveQuirk quirk, std::int64_t now_ns) {
  for (Armed& a : quirks_) {
    if (a.quirk == quirk && !a.done && a.until_ns < 0 && now_ns >= a.from_ns) return &a;
  }
  return nullptr;
}
bool DriveModel::fire(DriveQuirk quirk, std::int64_t now_ns, std::int64_t for_ns) {
  Armed* a = active(quirk, now_ns);
  if (a == nullptr) return false;
  a->until_ns = now_ns + for_ns;
  return true;
}
bool DriveModel::within(DriveQuirk quirk, std::int64_t now_ns) {
  for (Armed& a : quirks_) {
    if (a.quirk != quirk || a.done || a.until_ns < 0) continue;
    if (now_ns < a.until_ns) return true;
    a.done = true;
  }
  return false;
}

void DriveModel::step(const RxPdo* outputs, std::int64_t now_ns) {
  const double dt = last_ns_ < 0 ? 0.0 : static_cast<double>(now_ns - last_ns_) * 1e-9;
  last_ns_ = now_ns;
  ++cycle_;
  static const RxPdo kNeutral{0, bits::kEmgon | bits::kBrake, 0};
  if (outputs == nullptr) {
    // EtherCAT timeout (docs/protocol.md §4, E15)
    if (operational_ && ++missed_cycles_ == kLostCyclesForTimeout &&
        !fire(DriveQuirk::SilentTimeout, now_ns, 0)) {
      pending_faults_ |= bits::kEcatTimeout;
    }
  } else {
    missed_cycles_ = 0;
    last_rx_ = operational_ ? *outputs : kNeutral;
  }
  within(DriveQuirk::SilentTimeout, now_ns);  // ends it once traffic is back
  if (pending_faults_ != 0) {
    if (causes_ == 0) fault_since_ns_ = now_ns;
    causes_ |= pending_faults_;
    pending_faults_ = 0;
  }
  updateEnable(last_rx_, now_ns);
  updateHandshakes(last_rx_, now_ns);
  updateMotion(last_rx_, dt);
  updateDrift(now_ns, dt);
  buildInputs(last_rx_, now_ns);
}

void DriveModel::updateDrift(std::int64_t now_ns, double dt) {
  if (!drift_ || now_ns < drift_->from_ns) return;
  const Drift& d = *drift_;
  using Quantity = Drift::Quantity;
  const bool heat = d.quantity == Quantity::MotorTemperature;
  double& value = heat                                 ? temperature_c_
                  : d.quantity == Quantity::BusVoltage ? extra_bus_v_
                                                       : extra_current_a_;
  const double base = heat ? 0.0 : d.quantity == Quantity::BusVoltage ? kBusVoltage : current_a_;
  if (!drift_tripped_) {
    value += d.per_second * dt;
    if (base + value >= d.trip) {
      drift_tripped_ = true;
      pending_faults_ |= d.cause;
    }
    return;
  }
  bool settled = false;
  if (heat) {
    value += (kAmbientC - value) * std::min(1.0, dt / kCoolingS);
    settled = value < kAmbientC + 1;
  } else {
    value -= value * std::min(1.0, dt / kSettleElectricalS);
    settled = std::abs(value) < 0.5;
    if (settled) value = 0;
  }
  if (settled) {
    drift_.reset();
    drift_tripped_ = false;
  }
}

void DriveModel::updateEnable(const RxPdo& rx, std::int64_t now_ns) {
  const std::uint32_t se = rx.scw & bits::kSe;
  // docs/protocol.md §2: only 0x2 reached directly from 0x1 enables, and only while it is held.
  valid_enable_ = se == bits::kSeEnable && (valid_enable_ || last_se_ == bits::kSePrepare);
  last_se_ = se;
  if (valid_enable_) last_enable_end_ns_ = now_ns;
  const bool errors = causes_ != 0;
  const bool normal = (rx.scw & bits::kEmgon) != 0 && (rx.scw & bits::kBrake) != 0;

  if (spurious_until_ns_ >= 0) {  // SE-002: the momentary enable ends
    if (now_ns >= spurious_until_ns_) {
      enabled_ = false;
      spurious_until_ns_ = -1;
    }
    return;
  }
  if (enabled_) {
    want_since_ns_ = -1;
    if (errors) {  // fault reaction: braking ramp, then off (FLT-001 allows fault_reaction)
      if (reaction_ns_ < 0) {
        reaction_ns_ = fire(DriveQuirk::SlowFaultReaction, now_ns, kSlowReactionNs)
                           ? kSlowReactionNs
                           : fault_reaction_ns_;
      }
      if (now_ns - fault_since_ns_ >= reaction_ns_) enabled_ = false;
    } else if (!valid_enable_) {
      if (unwant_since_ns_ < 0) {
        unwant_since_ns_ = now_ns;
        disable_after_ns_ = fire(DriveQuirk::LateDisable, now_ns, kLateDisableNs)
                                ? kLateDisableNs
                                : disable_delay_ns_;
      }
      if (now_ns - unwant_since_ns_ >= disable_after_ns_) enabled_ = false;
    } else {
      unwant_since_ns_ = -1;
    }
    if (!enabled_) {
      unwant_since_ns_ = -1;
      reaction_ns_ = -1;
    }
    return;
  }
  reaction_ns_ = -1;
  unwant_since_ns_ = -1;
  if (valid_enable_ && !errors && normal) {
    if (want_since_ns_ < 0) {
      want_since_ns_ = now_ns;
      enable_after_ns_ = fire(DriveQuirk::IgnoreEnable, now_ns, kIgnoreEnableNs) ? kIgnoreEnableNs
                                                                                 : enable_delay_ns_;
    }
    if (now_ns - want_since_ns_ >= enable_after_ns_) enabled_ = true;
  } else {
    want_since_ns_ = -1;
    // SE-002: enabled for a moment with no valid enable, long after the last one
    if (!valid_enable_ && !errors && now_ns - last_enable_end_ns_ > kQuietBeforeSpuriousNs &&
        fire(DriveQuirk::SpuriousEnable, now_ns, kPulseNs)) {
      enabled_ = true;
      spurious_until_ns_ = now_ns + kPulseNs;
    }
  }
}

void DriveModel::updateHandshakes(const RxPdo& rx, std::int64_t now_ns) {
  // Zero-pulse search (incremental encoder only): ack once the pulse is found, drop it once
  // the request falls.
  const bool zp_request = (rx.scw & bits::kZPulseRequest) != 0 && setup_.incremental;
  if (zp_request) {
    zp_release_ns_ = -1;
    zp_searching_ = !zp_ack_;
    zp_request_since_ns_ = now_ns;
  } else {
    zp_searching_ = false;
    if (zp_ack_ && zp_release_ns_ < 0) {
      zp_release_ns_ =
          now_ns + (fire(DriveQuirk::HoldZPulseAck, now_ns, kHoldAckNs) ? kHoldAckNs : 0);
    }
    if (zp_ack_ && now_ns >= zp_release_ns_ && zp_release_ns_ >= 0) {
      zp_ack_ = false;
      zp_release_ns_ = -1;
    }
    if (!zp_ack_ && zp_spurious_until_ns_ < 0 &&
        now_ns - zp_request_since_ns_ > kQuietBeforeSpuriousNs &&
        fire(DriveQuirk::SpuriousZPulseAck, now_ns, kPulseNs)) {
      zp_spurious_until_ns_ = now_ns + kPulseNs;
    }
  }
  if (zp_spurious_until_ns_ >= 0 && now_ns >= zp_spurious_until_ns_) zp_spurious_until_ns_ = -1;

  // Error clear (FAULT RESET): ErrClearAck answers ErrorClear and falls after it.
  const bool clear = (rx.scw & bits::kErrorClear) != 0;
  if (clear) {
    clear_release_ns_ = -1;
    clear_request_since_ns_ = now_ns;
    if (clear_since_ns_ < 0) {
      clear_since_ns_ = now_ns;
      clear_after_ns_ = causes_ != 0 && fire(DriveQuirk::IgnoreClear, now_ns, kIgnoreClearNs)
                            ? kIgnoreClearNs
                            : 2 * kMs;
    }
    if (!clear_ack_ && now_ns - clear_since_ns_ >= clear_after_ns_ && !enabled_) {
      causes_ = 0;  // every latched cause; a lasting one would rise again
      fault_since_ns_ = -1;
      clear_ack_ = true;
    }
  } else {
    clear_since_ns_ = -1;
    if (clear_ack_ && clear_release_ns_ < 0) {
      clear_release_ns_ =
          now_ns + (fire(DriveQuirk::HoldClearAck, now_ns, kHoldAckNs) ? kHoldAckNs : 0);
    }
    if (clear_ack_ && clear_release_ns_ >= 0 && now_ns >= clear_release_ns_) {
      clear_ack_ = false;
      clear_release_ns_ = -1;
    }
    if (!clear_ack_ && clear_spurious_until_ns_ < 0 &&
        now_ns - clear_request_since_ns_ > kQuietBeforeSpuriousNs &&
        fire(DriveQuirk::SpuriousClearAck, now_ns, kPulseNs)) {
      clear_spurious_until_ns_ = now_ns + kPulseNs;
    }
  }
  if (clear_spurious_until_ns_ >= 0 && now_ns >= clear_spurious_until_ns_) {
    clear_spurious_until_ns_ = -1;
  }

  // Parameter table: the drive switches to the commanded one after a short delay.
  const int commanded = bits::tableOfScw(rx.scw);
  if (commanded != table_target_) {
    table_target_ = commanded;
    table_since_ns_ = now_ns;
    table_after_ns_ =
        fire(DriveQuirk::IgnoreTable, now_ns, kIgnoreTableNs) ? kIgnoreTableNs : table_delay_ns_;
  }
  if (table_ != table_target_ && now_ns - table_since_ns_ >= table_after_ns_) {
    table_ = table_target_;
  }
}

void DriveModel::updateMotion(const RxPdo& rx, double dt) {
  const bool normal = (rx.scw & bits::kEmgon) != 0 && (rx.scw & bits::kBrake) != 0;
  double target = 0;
  double rate = kCoastRpmPerS;
  if (enabled_ && causes_ == 0 && normal) {
    target = clampTo(static_cast<double>(rx.ssp) / kSspPerRpm, kMaxRpm);
    rate = kAccelRpmPerS;
  } else if (enabled_) {
    rate = kEmergencyRpmPerS;  // drive stop or fault reaction: braking ramp
  }
  const double before = speed_rpm_;
  speed_rpm_ = approach(speed_rpm_, target, rate * dt);
  accel_ = dt > 0 ? (speed_rpm_ - before) / dt : 0;
  const double cpr =
      static_cast<double>(setup_.incremental ? kIncrementalCountsPerRev : kAbsoluteCountsPerRev);
  const double old_position = position_;
  position_ += (before + speed_rpm_) / 2 / 60 * cpr * dt;
  if (setup_.incremental) {
    // The encoder's zero pulse: once per revolution.
    const double old_rev = std::floor(old_position / cpr);
    const double new_rev = std::floor(position_ / cpr);
    if (old_rev != new_rev) {
      const double pulse_at = std::max(old_rev, new_rev) * cpr;
      if (zp_searching_) {
        zp_ack_ = true;
        zp_searching_ = false;
        zero_pulse_ = static_cast<std::int32_t>(static_cast<std::int64_t>(pulse_at));
      } else if (zero_pulse_) {
        zero_pulse_ = static_cast<std::int32_t>(static_cast<std::int64_t>(pulse_at));
      }
    }
  }
  const double current = enabled_ ? std::abs(0.4 * (speed_rpm_ > 0   ? 1
                                                    : speed_rpm_ < 0 ? -1
                                                                     : 0) +
                                             accel_ * 2e-4 + speed_rpm_ * 2e-6)
                                  : 0.0;
  current_a_ = current;
  temperature_c_ += (kAmbientC + 0.8 * current * current - temperature_c_) * dt / 100;
}

void DriveModel::buildInputs(const RxPdo& rx, std::int64_t now_ns) {
  TxPdo& in = inputs_;
  const auto position = static_cast<std::int64_t>(std::llround(position_));
  if (setup_.incremental) {
    const auto low = static_cast<std::uint32_t>(static_cast<std::uint64_t>(position));
    const auto high = static_cast<std::uint32_t>(zero_pulse_.value_or(0));
    in.actpos = static_cast<std::int64_t>((static_cast<std::uint64_t>(high) << 32) | low);
  } else {
    in.actpos = position;
  }
  std::uint32_t sew = causes_ != 0 ? causes_ | bits::kServoErrors : 0;
  if (fire(DriveQuirk::SummaryWithoutCause, now_ns, kSummaryOnlyNs) ||
      within(DriveQuirk::SummaryWithoutCause, now_ns)) {
    if (causes_ == 0) sew |= bits::kServoErrors;
  }
  if (fire(DriveQuirk::CauseWithoutSummary, now_ns, 0)) sew = bits::kOverload;
  if (fire(DriveQuirk::ReservedErrorBit, now_ns, 0)) sew |= kReservedErrorBit;
  const bool errors = (sew & bits::kServoErrors) != 0;
  bool ready = !errors && (enabled_ || setup_.ready_mode == 0);  // docs/protocol.md §5
  if (fire(DriveQuirk::ReadyInverted, now_ns, kReadyInvertedNs) ||
      within(DriveQuirk::ReadyInverted, now_ns)) {
    ready = !ready;
  }
  const double set_rpm = static_cast<double>(rx.ssp) / kSspPerRpm;
  std::uint32_t ssw =
      (enabled_ ? bits::kServoEn | bits::kPulseEnabled : 0) | (ready ? bits::kServoRdy : 0) |
      (setup_.incremental ? bits::kIncremental : 0) |
      (zp_ack_ || zp_spurious_until_ns_ >= 0 ? bits::kZPulseAck : 0) |
      (clear_ack_ || clear_spurious_until_ns_ >= 0 ? bits::kErrClearAck : 0) |
      (std::abs(speed_rpm_) < kStandstillRpm ? bits::kNZero : 0) |
      (temperature_c_ > kTempWarningC ? bits::kTempWarning : 0) |
      (std::abs(set_rpm - speed_rpm_) <= std::max(kStandstillRpm, std::abs(set_rpm) * kTolerance)
           ? bits::kNSetpoint
           : 0) |
      bits::sswTable(table_);
  if (fire(DriveQuirk::ReservedStatusBit, now_ns, 0)) ssw |= kReservedStatusBit;
  in.ssw = ssw;
  in.sew = sew;

  // Message codes 0..5 in turn (docs/protocol.md §5), with plausible values.
  const double noise = rng_.uniform() - 0.5;
  const double rpm = speed_rpm_ + (speed_rpm_ != 0 ? noise * 0.2 : 0.0);
  const double current = current_a_ + extra_current_a_ + (enabled_ ? noise * 0.05 : 0.0);
  const double torque = current * kTorquePerAmp;
  in.msg_code = static_cast<std::int32_t>((cycle_ + static_cast<std::uint64_t>(setup_.axis)) % 6);
  double data = 0;
  switch (in.msg_code) {
    case 0:
      data = rpm;
      break;
    case 1:
      data = std::abs(current);
      break;
    case 2:
      data = std::abs(current) / kRatedCurrentA * 100;
      break;
    case 3:
      data = kBusVoltage + extra_bus_v_ + noise * 4 - 0.3 * std::abs(current);
      break;
    case 4:
      data = temperature_c_;
      break;
    default:
      data = rpm * torque * (2 * kPi / 60) / 1000;
      break;
  }
  if (fire(DriveQuirk::UndefinedMessage, now_ns, 0)) {
    in.msg_code = kUndefinedMessageCode;
    data = 0;
  }
  in.msg_data = static_cast<float>(data);
  in.ext_data = {static_cast<float>(set_rpm - speed_rpm_), static_cast<float>(torque),
                 static_cast<float>(current), static_cast<float>(temperature_c_ + 6.5)};
}

// --- NC ---

namespace {
constexpr int kPrepareCycles = 3;                   // SE 0x1 held before 0x2
constexpr std::int64_t kPrepareNs = 2 * kMs;        // ... and at least this long
constexpr std::int64_t kEnableRetryNs = 300 * kMs;  // no ServoEn: back to 0x1, then 0x2 again
constexpr std::int64_t kZeroPulseGiveUpNs = 2000 * kMs;
constexpr double kSearchRpm = 300;  // slow move that crosses a zero pulse within 0.2 s
constexpr double kNcRampRpmPerS = 10000;
constexpr double kNcStopRpmPerS = 30000;
}  // namespace

NcAxis::NcAxis(bool incremental) : incremental_(incremental) {}

void NcAxis::schedule(const NcEvent& event) {
  // Sorted newest first by time, then by the order given, so the next one is at the back.
  auto at = std::find_if(events_.begin(), events_.end(),
                         [&](const NcEvent& e) { return e.at_ns <= event.at_ns; });
  events_.insert(at, event);
}

void NcAxis::enter(Phase phase, std::int64_t now_ns) {
  phase_ = phase;
  phase_since_ns_ = now_ns;
  phase_cycles_ = 0;
}

void NcAxis::runEvents(std::int64_t now_ns) {
  while (!events_.empty() && events_.back().at_ns <= now_ns) {
    const NcEvent e = events_.back();
    events_.pop_back();
    switch (e.action) {
      case NcAction::Enable:
        want_on_ = true;
        if (phase_ == Phase::Off || phase_ == Phase::Disabling) enter(Phase::Prepare, now_ns);
        break;
      case NcAction::IllegalEnable:
        want_on_ = true;
        if (phase_ == Phase::Off) {
          se_ = bits::kSeEnable;  // SE-001: 0x0 -> 0x2
          enter(Phase::Enabling, now_ns);
        }
        break;
      case NcAction::Disable:
        want_on_ = false;
        if (phase_ == Phase::Prepare || phase_ == Phase::Enabling || phase_ == Phase::On) {
          enter(Phase::Disabling, now_ns);
        }
        break;
      case NcAction::Speed:
        target_rpm_ = e.value;
        break;
      case NcAction::SpeedStep:
        target_rpm_ = e.value;
        ssp_rpm_ = e.value;
        break;
      case NcAction::ZeroPulse:
        if (incremental_) {
          zp_request_ = true;
          zp_since_ns_ = now_ns;
        }
        break;
      case NcAction::ZeroPulseAbsolute:
        zp_abs_until_ns_ = now_ns + static_cast<std::int64_t>(e.value * kMs);
        break;
      case NcAction::Table:
        table_ = static_cast<int>(e.value);
        break;
      case NcAction::Emergency:
        emgon_ = false;
        emergency_until_ns_ = now_ns + static_cast<std::int64_t>(e.value * kMs);
        break;
      case NcAction::HoldErrorClear:
        hold_clear_ns_ = static_cast<std::int64_t>(e.value * kMs);
        break;
      case NcAction::ReservedBit:
        reserved_cycles_ = static_cast<int>(e.value);
        break;
    }
  }
}

void NcAxis::fellFromOp() {
  operational_ = false;
  ssp_rpm_ = 0;
  se_ = 0;
  if (phase_ == Phase::Prepare || phase_ == Phase::Enabling || phase_ == Phase::On) {
    enter(Phase::Prepare, last_ns_);
  }
}

RxPdo NcAxis::step(const TxPdo* inputs, std::int64_t now_ns) {
  const double dt = last_ns_ < 0 ? 0.0 : static_cast<double>(now_ns - last_ns_) * 1e-9;
  last_ns_ = now_ns;
  if (!operational_) {
    // Outside OP the NC keeps its axes disabled (ESM-002), unless it misbehaves.
    RxPdo out;
    out.scw = (enable_before_op_ ? bits::kSePrepare : 0U) | bits::kEmgon | bits::kBrake |
              bits::scwTable(table_);
    return out;
  }
  runEvents(now_ns);
  if (!emgon_ && now_ns >= emergency_until_ns_) emgon_ = true;
  ++phase_cycles_;

  if (inputs != nullptr) followDrive(*inputs, now_ns);
  return outputs(now_ns, dt);
}

// The enable handshake and the error clearing, one step on the drive's returned words.
void NcAxis::followDrive(const TxPdo& inputs, std::int64_t now_ns) {
  const bool drive_on = (inputs.ssw & bits::kServoEn) != 0;
  const bool errors = (inputs.sew & bits::kServoErrors) != 0;
  const bool clear_ack = (inputs.ssw & bits::kErrClearAck) != 0;
  if (errors && (phase_ == Phase::Prepare || phase_ == Phase::Enabling || phase_ == Phase::On ||
                 phase_ == Phase::Disabling || phase_ == Phase::Off)) {
    enter(Phase::FaultWait, now_ns);
  }
  switch (phase_) {
    case Phase::Off:
      se_ = 0;
      break;
    case Phase::Prepare:
      se_ = bits::kSePrepare;
      if (phase_cycles_ > kPrepareCycles && now_ns - phase_since_ns_ >= kPrepareNs) {
        se_ = bits::kSeEnable;
        enter(Phase::Enabling, now_ns);
      }
      break;
    case Phase::Enabling:
      if (drive_on) {
        enter(Phase::On, now_ns);
      } else if (now_ns - phase_since_ns_ > kEnableRetryNs) {
        enter(Phase::Prepare, now_ns);  // the drive did not follow: a legal edge again
        se_ = bits::kSePrepare;
      }
      break;
    case Phase::On:
      se_ = bits::kSeEnable;
      break;
    case Phase::FaultWait:
      // The drive reacts to its own fault: the NC keeps SE until the drive is off, so a slow
      // but legal fault reaction is not an enable the drive failed to drop (SE-003).
      if (!errors) {
        enter(drive_on ? Phase::On : (want_on_ ? Phase::Prepare : Phase::Off), now_ns);
      } else if (!drive_on) {
        se_ = bits::kSePrepare;
        error_clear_ = true;
        enter(Phase::Clearing, now_ns);
      }
      break;
    case Phase::Clearing:
      se_ = bits::kSePrepare;
      error_clear_ = true;
      if (clear_ack) {
        if (ack_seen_ns_ < 0) ack_seen_ns_ = now_ns;
        if (now_ns - ack_seen_ns_ >= hold_clear_ns_) {
          error_clear_ = false;
          hold_clear_ns_ = 0;
          ack_seen_ns_ = -1;
          enter(Phase::Releasing, now_ns);
        }
      }
      break;
    case Phase::Releasing:
      error_clear_ = false;
      if (!clear_ack) {
        if (errors) {
          enter(Phase::Clearing, now_ns);
        } else {
          enter(want_on_ ? Phase::Prepare : Phase::Disabling, now_ns);
        }
      }
      break;
    case Phase::Disabling:
      se_ = bits::kSePrepare;
      if (phase_cycles_ > kPrepareCycles) {
        se_ = 0;
        enter(want_on_ ? Phase::Prepare : Phase::Off, now_ns);
      }
      break;
  }
  if (zp_request_ &&
      ((inputs.ssw & bits::kZPulseAck) != 0 || now_ns - zp_since_ns_ > kZeroPulseGiveUpNs)) {
    zp_request_ = false;
  }
}

RxPdo NcAxis::outputs(std::int64_t now_ns, double dt) {
  // Speed set point: the plan's target, a slow move while searching the zero pulse, zero
  // while not enabled or in an emergency; ramped as an interpolator would.
  double target = 0;
  if (phase_ == Phase::On && emgon_) {
    target = target_rpm_;
    if (zp_request_ && std::abs(target) < kSearchRpm / 3) target = kSearchRpm;
  }
  const double rate = emgon_ && phase_ == Phase::On ? kNcRampRpmPerS : kNcStopRpmPerS;
  ssp_rpm_ = approach(ssp_rpm_, target, rate * dt);

  RxPdo out;
  out.ssp = static_cast<std::int32_t>(std::lround(ssp_rpm_ * kSspPerRpm));
  out.scw = se_ | (emgon_ ? bits::kEmgon : 0U) | bits::kBrake | bits::scwTable(table_) |
            (zp_request_ || now_ns < zp_abs_until_ns_ ? bits::kZPulseRequest : 0U) |
            (error_clear_ ? bits::kErrorClear : 0U);
  if (reserved_cycles_ > 0) {
    out.scw |= kReservedControlBit;
    --reserved_cycles_;
  }
  out.ext_code = 0;
  return out;
}

}  // namespace ncservo::sim
