#include "ncservo/model/axis_model.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "ncservo/protocol/fields.hpp"
#include "ncservo/protocol/word_bits.hpp"
#include "ncservo/wire/diagnosis_texts.hpp"

namespace ncservo {

namespace {
using namespace bits;

constexpr bool declared(Word w, std::uint64_t bits) {
  return (AxisModel::kReads.bits[static_cast<std::size_t>(w)] & bits) == bits;
}
static_assert(declared(Word::Scw, kSe | kEmgon | kBrake | kZPulseRequest | kErrorClear) &&
                  declared(Word::Ssw, kServoEn | kServoRdy | kZPulseAck | kErrClearAck) &&
                  declared(Word::Sew, kServoErrors | kEcatTimeout | kSewCauseMask),
              "AxisModel::kReads declares every bit observe() reads");

// The rows of the bit fields the model reads, whose changes are its edges.
constexpr std::size_t kEdgeFieldCount = [] {
  std::size_t n = 0;
  for (const FieldDef& f : kFields)
    n += (f.mask & AxisModel::kReads.bits[static_cast<std::size_t>(f.word)]) != 0;
  return n;
}();
constexpr std::array<std::uint16_t, kEdgeFieldCount> kEdgeFields = [] {
  std::array<std::uint16_t, kEdgeFieldCount> rows{};
  std::size_t n = 0;
  for (std::size_t row = 0; row < kFieldCount; ++row) {
    const FieldDef& f = kFields[row];
    if ((f.mask & AxisModel::kReads.bits[static_cast<std::size_t>(f.word)]) != 0)
      rows[n++] = static_cast<std::uint16_t>(row);
  }
  return rows;
}();
// Per word, the bits of those fields: a frame that moved none of them has no edge.
constexpr std::array<std::uint64_t, kWordCount> kEdgeBits = [] {
  std::array<std::uint64_t, kWordCount> bits{};
  for (const std::uint16_t row : kEdgeFields) {
    const auto word = static_cast<std::size_t>(kFields[row].word);
    bits[word] |= kFields[row].mask & AxisModel::kReads.bits[word];
  }
  return bits;
}();

const char* transitionName(std::optional<DriveState> from, DriveState to, const AxisModel& axis) {
  if (!from) return nullptr;
  const bool was_error = *from == DriveState::Error || *from == DriveState::FaultReactionActive;
  if (to == DriveState::FaultReactionActive) return "FAULT REACTION ACTIVE";
  if (to == DriveState::Error) return "FAULT";
  if (was_error) return "FAULT RESET";
  if (axis.servoEn().rose) return axis.validEnable() ? "ENABLE OPERATION" : nullptr;
  if (axis.servoEn().fell) return "DISABLE OPERATION";
  return nullptr;
}
}  // namespace

// clang-format off
const std::array<SewCause, popcount64(kSewCauseMask)> kSewCauses{{
    {mask32("ncservo.sew.encoder"), "E01", 0x7305},
    {mask32("ncservo.sew.i2t_endat"), "E19", 0x4200},
    {mask32("ncservo.sew.ecat_config"), "E14", 0x8100},
    {mask32("ncservo.sew.bus_voltage"), "E05", 0x3100},
    {mask32("ncservo.sew.current"), "E06", 0x2300},
    {mask32("ncservo.sew.current_offset"), "E07", 0x2300},
    {mask32("ncservo.sew.hall"), "E08", 0x7306},
    {mask32("ncservo.sew.hall_sequence"), "HallSErr", 0x7306},
    {mask32("ncservo.sew.servo_runtime"), "SRTErr", 0x6010},
    {mask32("ncservo.sew.can1_timeout"), "CAN1TErr", 0x8130},
    {mask32("ncservo.sew.can2_timeout"), "CAN2TErr", 0x8130},
    {mask32("ncservo.sew.can1_hw"), "CAN1HErr", 0x8100},
    {mask32("ncservo.sew.can2_hw"), "CAN2HErr", 0x8100},
    {mask32("ncservo.sew.ecat_timeout"), "E15", 0x8130},
    {mask32("ncservo.sew.pdpint"), "E16", 0x2300},
    {mask32("ncservo.sew.param_checksum"), "E30", 0x6320},
    {mask32("ncservo.sew.program_checksum"), "PRGCHKSErr", 0x6100},
    {mask32("ncservo.sew.following"), "E09", 0x8611},
    {mask32("ncservo.sew.overload"), "E20", 0x2300},
    {mask32("ncservo.sew.flash"), "E32", 0x7600},
    {mask32("ncservo.sew.ecat_watchdog"), "E31", 0x8100},
    {mask32("ncservo.sew.overspeed"), "E11", 0x8400},
    {mask32("ncservo.sew.current_symmetry"), "E12", 0x2300},
}};
// clang-format on

std::string_view sewCauseName(const SewCause& cause) {
  const FieldDef* row = sewCauseField(cause.mask);
  return row != nullptr ? causeName(*row) : std::string_view(cause.display);
}

std::string sewCauseText(const SewCause& cause) {
  const std::string_view name = sewCauseName(cause);
  return name == cause.display ? std::string(name) : fmt::format("{} {}", cause.display, name);
}

void Signal::observe(std::uint32_t v, const Stamp& now) {
  rose = known && value == 0 && v != 0;
  fell = known && value != 0 && v == 0;
  if (!known || v != value) since = now;
  value = v;
  known = true;
}

void AxisModel::copyWords(Pdo pdo, const PdoValues& values) {
  const auto first = static_cast<std::ptrdiff_t>(firstWordOf(pdo));
  const auto count = static_cast<std::ptrdiff_t>(wordCountOf(pdo));
  std::copy(values.raw.begin() + first, values.raw.begin() + first + count,
            latest_.raw.begin() + first);
}

void AxisModel::cycleFailed(bool lost, std::uint32_t cycles, const Stamp& now) {
  ++revision_;
  now_ = now;
  if (lost) {
    consecutive_lost_ += cycles;
    unanswered_outage_cycles_ = 0;  // a new outage: COM-003 is judged after it
  } else {
    // A wrong but non-zero WKC: the slaves processed the frame, so traffic went through and a
    // run of lost cycles (COM-003) ends here.
    endOutage();
  }
  consecutive_failed_ += cycles;
  total_failures_ = std::min(kFailureCounterMax, total_failures_ + cycles);
}

// Traffic resumed: the outage's lost cycles await ECatTErr (docs/rules.md#com-003).
void AxisModel::endOutage() {
  if (consecutive_lost_ > 0) unanswered_outage_cycles_ = consecutive_lost_;
  consecutive_lost_ = 0;
}

void AxisModel::observe(const PdoValues& values, const Stamp& now) {
  const PdoValues before = latest_;
  now_ = now;
  illegal_enable_edge_ = false;
  inputs_in_al_state_ = inputs_in_al_state_ || values.has_tx;
  for (Signal* s : {&se_, &emgon_, &brake_, &zpulse_request_, &error_clear_, &servo_en_,
                    &servo_rdy_, &zpulse_ack_, &err_clear_ack_, &servo_errors_, &ecat_timeout_}) {
    s->clearEdges();
  }
  if (values.has_rx) observeOutputs(values, now);
  if (values.has_tx) observeInputs(values, now);
  observed_frame_ = now.frame;
  takeEdges(before);
  updateState(now);
}

// The read bit fields whose value differs from the previous observation of their PDO (never on
// the first, as Signal's edges).
void AxisModel::takeEdges(const PdoValues& before) {
  edges_.clear();
  std::uint64_t moved = 0;
  for (std::size_t word = 0; word < kWordCount; ++word)
    moved |= (before.raw[word] ^ latest_.raw[word]) & kEdgeBits[word];
  if (moved == 0) return;
  for (const std::uint16_t row : kEdgeFields) {
    const FieldDef& f = kFields[row];
    const std::size_t word = static_cast<std::size_t>(f.word);
    const std::uint64_t mask = f.mask & kReads.bits[word];
    if (mask == 0 || !before.has(f.word) || !latest_.has(f.word)) continue;
    const std::uint64_t then = before.raw[word] & mask;
    const std::uint64_t now = latest_.raw[word] & mask;
    if (then == now) continue;
    const unsigned shift = lowestBit(f.mask);
    edges_.push_back(FieldEdge{row, static_cast<std::uint32_t>(then >> shift),
                               static_cast<std::uint32_t>(now >> shift)});
  }
}

std::string edgeText(const FieldEdge& edge) {
  const FieldDef& f = kFields[edge.field];
  if (f.kind == FieldKind::Flag) return std::string(f.label) + (edge.to != 0 ? " ↑" : " ↓");
  return fmt::format("{} {:#x}→{:#x}", f.label, edge.from, edge.to);
}

std::string transitionText(const StateChange& change) {
  if (change.transition != nullptr) return change.transition;
  if (!change.from) return fmt::format("→ {}", driveStateName(change.state));
  return fmt::format("{} → {}", driveStateName(*change.from), driveStateName(change.state));
}

bool Answered::within(std::int64_t window_ns) const {
  if (!at) return false;
  return (before && at->time_ns - before->time_ns <= window_ns) ||
         (after && after->time_ns - at->time_ns <= window_ns);
}

void AxisModel::takeEmergency(std::uint16_t code, const Stamp& at) {
  ++revision_;
  if (!first_emergency_) first_emergency_ = at;
  if (code == diag::kErrorReset) return;
  emergencies_ = Answered{at, faults_.at, std::nullopt};
  emergency_code_ = code;
  if (faults_.at && !faults_.after) faults_.after = at;
}

bool AxisModel::takeHistoryRead(std::uint32_t value, const Stamp& at) {
  if (!faults_.at || history_read_) return false;
  ++revision_;
  history_read_ = HistoryRead{at, value};
  return true;
}

void AxisModel::startSegment() {
  ++revision_;
  // A window does not span a discontinuity (docs/timing.md#rule-time).
  emergencies_ = {};
  faults_ = {};
  fault_causes_ = 0;
  history_read_.reset();
  measurements_.reset();
  for (Signal* s : {&se_, &emgon_, &brake_, &zpulse_request_, &error_clear_, &servo_en_,
                    &servo_rdy_, &zpulse_ack_, &err_clear_ack_, &servo_errors_, &ecat_timeout_}) {
    *s = Signal{};
  }
  latest_.has_rx = false;
  latest_.has_tx = false;
  illegal_enable_edge_ = false;
  previous_se_ = 0;
  valid_enable_ = false;
  valid_enable_ended_.reset();
  clear_acknowledged_ = false;
  consecutive_lost_ = 0;
  consecutive_failed_ = 0;
  unanswered_outage_cycles_ = 0;
}

void AxisModel::observeOutputs(const PdoValues& values, const Stamp& now) {
  const std::uint32_t scw = values.scw();
  const std::uint32_t se = scw & kSe;
  const bool first = !se_.known;
  previous_se_ = se_.value;
  // docs/timing.md#rule-time: an axis first seen with SE 0x2 is taken as validly enabled.
  if (se == kSeEnable) {
    if (first || previous_se_ == kSePrepare) {
      valid_enable_ = true;
    } else if (previous_se_ != kSeEnable) {
      illegal_enable_edge_ = true;
      valid_enable_ = false;
    }
  } else if (valid_enable_) {
    valid_enable_ = false;
    valid_enable_ended_ = now;
  }
  se_.observe(se, now);
  emgon_.observe(scw & kEmgon, now);
  brake_.observe(scw & kBrake, now);
  zpulse_request_.observe(scw & kZPulseRequest, now);
  error_clear_.observe(scw & kErrorClear, now);
  if (error_clear_.rose) clear_acknowledged_ = false;
  for (const WordDef& word : kWords) {
    if (word.pdo == Pdo::Rx)
      latest_.raw[static_cast<std::size_t>(word.word)] = values.word(word.word);
  }
  latest_.has_rx = true;
  saw_outputs_ = true;
}

void AxisModel::observeInputs(const PdoValues& values, const Stamp& now) {
  const std::uint32_t ssw = values.ssw();
  const std::uint32_t sew = values.sew();
  servo_en_.observe(ssw & kServoEn, now);
  servo_rdy_.observe(ssw & kServoRdy, now);
  zpulse_ack_.observe(ssw & kZPulseAck, now);
  err_clear_ack_.observe(ssw & kErrClearAck, now);
  servo_errors_.observe(sew & kServoErrors, now);
  ecat_timeout_.observe(sew & kEcatTimeout, now);
  if (err_clear_ack_.rose && error_clear_.on()) clear_acknowledged_ = true;
  if (ecat_timeout_.on()) unanswered_outage_cycles_ = 0;

  // docs/protocol.md §7: an entry per rising cause bit, newest first; errors present when the axis
  // is first seen are entered too.
  const std::uint32_t rising = sew & ~previous_sew_ & kSewCauseMask;
  previous_sew_ = sew;
  if (rising != 0) {
    // docs/rules.md#mbx-001, #mbx-002: a fault and the emergencies around it.
    faults_ = Answered{now, emergencies_.at, std::nullopt};
    if (emergencies_.at && !emergencies_.after) emergencies_.after = now;
    fault_causes_ = rising;
    history_read_.reset();
  }
  for (const SewCause& cause : kSewCauses) {
    if (!(rising & cause.mask)) continue;
    error_history_.insert(error_history_.begin(), ErrorHistoryEntry{&cause, now});
    if (error_history_.size() > kErrorHistoryDepth) error_history_.pop_back();
  }

  for (const WordDef& word : kWords) {
    if (word.pdo == Pdo::Tx)
      latest_.raw[static_cast<std::size_t>(word.word)] = values.word(word.word);
  }
  latest_.has_tx = true;
  saw_inputs_ = true;

  // docs/rules.md#rdy-001: the mode is inferred from the first sight of ServoEn 0 and no error.
  if (!ready_mode_ && servo_en_.off() && servo_errors_.off()) {
    ready_mode_ = servo_rdy_.on() ? 0 : 1;
  }
}

std::optional<bool> AxisModel::expectedReady() const {
  if (!ready_mode_ || !latest_.has_tx) return std::nullopt;
  // docs/protocol.md §5, the Servo_Ready_Mode table.
  if (servo_errors_.on()) return false;
  if (*ready_mode_ == 0) return true;
  return servo_en_.on();
}

void AxisModel::updateState(const Stamp& now) {
  const std::optional<DriveState> state = driveState(latest_);
  if (!state || state == state_) return;
  const char* transition = transitionName(state_, *state, *this);
  last_change_ = StateChange{*state, transition, now, state_};
  state_ = state;
  if (timeline_.size() >= kMaxTimeline) {
    ++timeline_omitted_;
    return;
  }
  timeline_.push_back(*last_change_);
}

}  // namespace ncservo
