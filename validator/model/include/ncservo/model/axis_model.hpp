// The model of one axis: the stream of its observations turned into state — signal levels and
// edges, the valid-enable of docs/protocol.md §2, the handshakes, the drive state and its named
// transitions (§6), the error history (§7) and the telegram-failure counters (docs/rules.md COM-*).
// Rules read this state; they never see bytes.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/base/stamp.hpp"
#include "ncservo/model/axis_measurements.hpp"
#include "ncservo/protocol/drive_state.hpp"
#include "ncservo/protocol/pdo.hpp"
#include "ncservo/protocol/reads.hpp"

namespace ncservo {

// One bit (or small value) of a PDO as seen over time.
struct Signal {
  std::uint32_t value = 0;
  bool known = false;
  bool rose = false;  // became non-zero in this frame's observation (never on the first)
  bool fell = false;
  Stamp since;  // where it took its current value (the first observation, if it never changed)

  void observe(std::uint32_t v, const Stamp& now);
  void clearEdges() { rose = fell = false; }
  bool on() const { return known && value != 0; }
  bool off() const { return known && value == 0; }
};

// docs/protocol.md §7: SEW cause bit -> display code and CANopen-style code.
struct SewCause {
  std::uint32_t mask;
  const char* display;  // E-number, or the bit's name where the definition gives none
  std::uint16_t canopen;
};
extern const std::array<SewCause, popcount64(kSewCauseMask)> kSewCauses;
// The bit's name from the field table ("OverSpeed"), and how the reports name a cause: "E11
// OverSpeed", or the name alone where the definition gives no E-number ("HallSErr").
std::string_view sewCauseName(const SewCause& cause);
std::string sewCauseText(const SewCause& cause);

struct ErrorHistoryEntry {
  const SewCause* cause = nullptr;
  Stamp at;
};

// The last event of one kind with the nearest of another kind at or before it and the first after
// it: a drive's emergency and a rise of a SEW cause bit answer each other (docs/rules.md#mbx-001,
// #mbx-002). Stamps on the segment's clock.
struct Answered {
  std::optional<Stamp> at;      // the last event
  std::optional<Stamp> before;  // the last answer at or before it
  std::optional<Stamp> after;   // the first answer after it
  // Whether an answer came within `window_ns` before or after the event.
  bool within(std::int64_t window_ns) const;
};

// A read of 1003h:01, the newest entry of the drive's own error history (docs/rules.md#erh-002).
struct HistoryRead {
  Stamp at;
  std::uint32_t value = 0;  // number << 24 | class << 16 | code (docs/drive-messages.md)
};

struct StateChange {
  DriveState state{};
  const char* transition = nullptr;  // docs/protocol.md §6's name, where it has one
  Stamp at;
  std::optional<DriveState> from;  // none when the state first became known
};

// A bit field the model reads (AxisModel::kReads) that changed value in one observation.
struct FieldEdge {
  std::uint16_t field;  // row in kFields
  std::uint32_t from, to;
};
// "SE 0x1→0x2" for a multi-bit field, "ServoEn ↑" / "ServoEn ↓" for a flag.
std::string edgeText(const FieldEdge& edge);
// The change's transition name (docs/protocol.md §6), else "switched on → control active", else
// "→ ready to switch on" when the state first became known.
std::string transitionText(const StateChange& change);

class AxisModel {
 public:
  // What observe() reads of the PDOs: the signals below, the drive state's inputs
  // (drive_state.hpp) and the error history's SEW causes. The validator's fast path compares
  // these bits with the rules' (rules.hpp Reads).
  static constexpr Reads kReads =
      readsOf({"ncservo.scw.se", "ncservo.scw.emgon", "ncservo.scw.brake",
               "ncservo.scw.zpulse_request", "ncservo.scw.error_clear", "ncservo.ssw.servo_en",
               "ncservo.ssw.servo_rdy", "ncservo.ssw.zpulse_ack", "ncservo.ssw.err_clear_ack",
               "ncservo.ssw.pulse_enabled", "ncservo.sew"});
  static constexpr std::size_t kErrorHistoryDepth = 8;  // as object 1003h
  static constexpr std::size_t kMaxTimeline = 4096;     // bounded memory per axis
  static constexpr std::uint32_t kFailureCounterMax = 65535;

  explicit AxisModel(std::uint16_t index, std::optional<int> ready_mode)
      : index_(index), ready_mode_(ready_mode), ready_mode_configured_(ready_mode.has_value()) {}

  // Telegram accounting, done by the bus model before the frame's values are observed.
  // `lost`: missing, not returned, or returned with WKC 0 (COM-003); otherwise a wrong WKC.
  void cycleFailed(bool lost, std::uint32_t cycles, const Stamp& now);
  void cycleOk(const Stamp& now) {
    now_ = now;
    if (consecutive_lost_ == 0 && consecutive_failed_ == 0)
      return;  // every cycle while all is well
    ++revision_;
    endOutage();
    consecutive_failed_ = 0;
  }
  // The slave entered OP: the total counter resets (docs/cli.md, `telegram_failures`).
  void enteredOp() {
    total_failures_ = 0;
    ++revision_;
  }
  // The AL state of the axis's slave, where the capture shows it (docs/protocol.md §8; ESM-002).
  void setAlState(std::optional<std::uint8_t> state) {
    if (state != al_state_) {
      ++revision_;
      inputs_in_al_state_ = false;
    }
    al_state_ = state;
  }
  // What the axis's drive said over its mailbox, given by the validator where the axis's station
  // is known (docs/drive-messages.md#the-rules). An error reset (code 0x0000) reports no fault.
  void takeEmergency(std::uint16_t code, const Stamp& at);
  // A read of 1003h:01: taken when it is the first since the last fault (ERH-002); returns
  // whether it was.
  bool takeHistoryRead(std::uint32_t value, const Stamp& at);
  // Inputs were exchanged since the AL state last changed (ESM-002).
  bool inputsInAlState() const { return inputs_in_al_state_; }
  // Counts changes made other than by observe(): an unchanged revision and unchanged read bits
  // (kReads and the rules' Reads) mean the rules' conditions are unchanged too.
  std::uint64_t revision() const { return revision_; }
  std::optional<std::uint8_t> alState() const { return al_state_; }

  // This frame's values of the axis (outputs and/or inputs), at `now`.
  void observe(const PdoValues& values, const Stamp& now);
  // What the incidents' causes measure of this frame's values (axis_measurements.hpp): every
  // frame, also one observe() is not given. `outputs_cycle`: the outputs are a cycle's set
  // point (not a returned copy's repeat of its master's copy just before). Returns whether
  // SEW.ServoErrors rose in them.
  bool measure(const PdoValues& values, bool outputs_cycle, const Mark& at) {
    if (outputs_cycle && values.has_rx) measurements_.takeSetPoint(values.ssp(), at);
    return values.has_tx && measurements_.takeInputs(values, at);
  }
  const AxisMeasurements& measurements() const { return measurements_; }
  // A capture segment starts (capture_segments.hpp): the next observation is a first one, as in
  // a capture begun mid-operation (docs/timing.md#rule-time), and the telegram-failure run
  // restarts; the drive state, its timeline, the error history and Servo_Ready_Mode carry on.
  void startSegment();

  // --- state, for rules and reports ---
  std::uint16_t index() const { return index_; }
  const Stamp& now() const { return now_; }
  // The values last judged (an observation that would change nothing is not taken).
  const PdoValues& latest() const { return latest_; }
  bool knowsOutputs() const { return latest_.has_rx; }
  bool knowsInputs() const { return latest_.has_tx; }
  // Whether any frame of the capture, in any segment, gave the axis's outputs or inputs.
  bool sawOutputs() const { return saw_outputs_; }
  bool sawInputs() const { return saw_inputs_; }

  // SCW.SE this frame moved to 0x2 from something other than 0x1 (SE-001).
  bool illegalEnableEdge() const { return illegal_enable_edge_; }
  std::uint32_t previousSe() const { return previous_se_; }
  // A valid enable: SE reached 0x2 from 0x1 (or was 0x2 when first seen) and held since.
  bool validEnable() const { return valid_enable_; }
  // When the last valid enable ended (SE left 0x2).
  const std::optional<Stamp>& validEnableEnded() const { return valid_enable_ended_; }

  const Signal& se() const { return se_; }
  const Signal& emgon() const { return emgon_; }
  const Signal& brake() const { return brake_; }
  const Signal& zpulseRequest() const { return zpulse_request_; }
  const Signal& errorClear() const { return error_clear_; }
  const Signal& servoEn() const { return servo_en_; }
  const Signal& servoRdy() const { return servo_rdy_; }
  const Signal& zpulseAck() const { return zpulse_ack_; }
  const Signal& errClearAck() const { return err_clear_ack_; }
  const Signal& servoErrors() const { return servo_errors_; }
  const Signal& ecatTimeout() const { return ecat_timeout_; }
  // ErrClearAck rose while ErrorClear was 1, since ErrorClear last rose (EC-002, EC-004).
  bool clearAcknowledged() const { return clear_acknowledged_; }

  // Servo_Ready_Mode (docs/protocol.md §5): configured, or inferred (docs/rules.md#rdy-001).
  std::optional<int> readyMode() const { return ready_mode_; }
  bool readyModeConfigured() const { return ready_mode_configured_; }
  // ServoRDY as the §5 table requires it for the latest inputs.
  std::optional<bool> expectedReady() const;

  std::uint32_t consecutiveLost() const { return consecutive_lost_; }
  std::uint32_t consecutiveFailed() const { return consecutive_failed_; }
  std::uint32_t totalFailures() const { return total_failures_; }
  // The lost cycles of the last outage after which traffic resumed, while ECatTErr has not been
  // seen since; 0 when none. COM-003 judges how many.
  std::uint32_t unansweredOutageCycles() const { return unanswered_outage_cycles_; }

  // The last emergency reporting a fault and the SEW cause rises nearest it (MBX-001), with its
  // code; the last rise of a SEW cause bit and the fault emergencies nearest it (MBX-002), with
  // the bits that rose; the drive's first emergency, of any code, in the capture.
  const Answered& emergencies() const { return emergencies_; }
  std::uint16_t emergencyCode() const { return emergency_code_; }
  const Answered& faults() const { return faults_; }
  std::uint32_t faultCauses() const { return fault_causes_; }
  const std::optional<Stamp>& firstEmergency() const { return first_emergency_; }
  // The first read of 1003h:01 since the last fault (ERH-002).
  const std::optional<HistoryRead>& historyRead() const { return history_read_; }

  std::optional<DriveState> state() const { return state_; }
  // The edges of the observation taken in `frame`; empty when none was taken there.
  const std::vector<FieldEdge>& edgesIn(std::uint64_t frame) const {
    static const std::vector<FieldEdge> kNone;
    return observed_frame_ == frame ? edges_ : kNone;
  }
  // The state change taken in `frame`, kept even when the timeline is full.
  const StateChange* stateChangeIn(std::uint64_t frame) const {
    return last_change_ && last_change_->at.frame == frame ? &*last_change_ : nullptr;
  }
  const std::vector<StateChange>& timeline() const { return timeline_; }
  std::uint64_t timelineOmitted() const { return timeline_omitted_; }
  // Newest first, at most kErrorHistoryDepth.
  const std::vector<ErrorHistoryEntry>& errorHistory() const { return error_history_; }

 private:
  void observeOutputs(const PdoValues& values, const Stamp& now);
  void observeInputs(const PdoValues& values, const Stamp& now);
  void updateState(const Stamp& now);
  void takeEdges(const PdoValues& before);
  void copyWords(Pdo pdo, const PdoValues& values);
  void endOutage();

  std::uint16_t index_;
  std::uint64_t revision_ = 0;
  Stamp now_;
  std::optional<std::uint8_t> al_state_;
  bool inputs_in_al_state_ = false;
  PdoValues latest_;
  bool saw_outputs_ = false;
  bool saw_inputs_ = false;

  bool illegal_enable_edge_ = false;
  std::uint32_t previous_se_ = 0;
  bool valid_enable_ = false;
  std::optional<Stamp> valid_enable_ended_;
  bool clear_acknowledged_ = false;

  Signal se_, emgon_, brake_, zpulse_request_, error_clear_;
  Signal servo_en_, servo_rdy_, zpulse_ack_, err_clear_ack_, servo_errors_, ecat_timeout_;
  std::uint32_t previous_sew_ = 0;

  std::optional<int> ready_mode_;
  bool ready_mode_configured_;

  std::uint32_t consecutive_lost_ = 0;
  std::uint32_t consecutive_failed_ = 0;
  std::uint32_t total_failures_ = 0;
  std::uint32_t unanswered_outage_cycles_ = 0;

  std::optional<DriveState> state_;
  std::uint64_t observed_frame_ = 0;
  std::vector<FieldEdge> edges_;  // of the observation in observed_frame_
  std::optional<StateChange> last_change_;
  std::vector<StateChange> timeline_;
  std::uint64_t timeline_omitted_ = 0;
  std::vector<ErrorHistoryEntry> error_history_;
  AxisMeasurements measurements_;

  Answered emergencies_, faults_;
  std::uint16_t emergency_code_ = 0;
  std::uint32_t fault_causes_ = 0;
  std::optional<Stamp> first_emergency_;
  std::optional<HistoryRead> history_read_;
};

}  // namespace ncservo
