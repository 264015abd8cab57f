#include "ncservo/rules/validator.hpp"

#include <algorithm>
#include <limits>

#include "ncservo/wire/diagnosis_texts.hpp"

namespace ncservo {

Validator::Validator(DecoderOptions options, RuleSettings settings, FastPath fast_path)
    : decoder_(std::move(options)),
      settings_(std::move(settings)),
      judged_(judgedBits(settings_, fast_path)),
      fast_path_(fast_path == FastPath::On),
      dc_(settings_.dc_settled_ns),
      segments_(settings_.timeoutNs(Timeout::CapturePause)) {
  for (const RuleDef& rule : kRules) {
    if (rule.event != kNoEvent && settings_.isEnabled(rule.id)) judged_events_[rule.event] = true;
  }
  mailbox_.configure(decoder_.mailboxAreas());
}

// What the fast path compares, derived from what the axis model and the enabled axis rules
// declare they read (the "reads" of docs/rules.md).
Validator::Judged Validator::judgedBits(const RuleSettings& settings, FastPath fast_path) {
  Reads reads = AxisModel::kReads;
  for (const RuleDef& rule : kRules) {
    if (rule.kind == RuleKind::Axis && settings.isEnabled(rule.id)) reads = reads | rule.reads;
  }
  Judged judged;
  judged.mailbox = reads.mailbox;  // not a fast path: whether the models take the messages
  if (fast_path == FastPath::Off) return judged;
  for (const WordDef& def : kWords) {
    const std::uint64_t bits = reads.bits[static_cast<std::size_t>(def.word)];
    const WordClass word_class = reads.classes[static_cast<std::size_t>(def.word)];
    if (bits == 0 && word_class == nullptr) continue;
    JudgedPdo& pdo = def.pdo == Pdo::Rx ? judged.rx : judged.tx;
    pdo.words[pdo.count++] = JudgedWord{static_cast<std::uint8_t>(def.word), bits, word_class};
  }
  judged.al_state = reads.al_state;
  return judged;
}

// Whether this frame's values hold the judged bits the model last took. A PDO the frame does not
// carry (or that is cut short) changes nothing.
bool Validator::unchanged(const PdoValues& values, const AxisModel& model) const {
  // Outside OP and SAFE-OP, which PDOs a frame carries counts (Reads::al_state); a change of the
  // AL state itself changes the model's revision.
  if (judged_.al_state && model.alState() && !ecat::exchangesInputs(*model.alState())) return false;
  const PdoValues& latest = model.latest();
  auto same = [&](const JudgedPdo& judged, bool has, bool had) {
    if (!has) return true;
    if (!had) return false;
    for (std::size_t i = 0; i < judged.count; ++i) {
      const JudgedWord& w = judged.words[i];
      const std::uint64_t now = values.raw[w.index];
      const std::uint64_t then = latest.raw[w.index];
      if (((now ^ then) & w.bits) != 0) return false;
      // equal words are of one class: the call is needed only when an unread bit moved
      if (w.word_class != nullptr && now != then && w.word_class(now) != w.word_class(then))
        return false;
    }
    return true;
  };
  return same(judged_.rx, values.has_rx, latest.has_rx) &&
         same(judged_.tx, values.has_tx, latest.has_tx);
}

const AxisModel* Validator::axis(std::size_t index) const {
  if (index >= axes_.size() || !axes_[index].model) return nullptr;
  return &*axes_[index].model;
}

CycleTimeSummary Validator::cycleTime() const {
  CycleTimeSummary summary;
  auto us = [](std::optional<std::int64_t> ns) -> std::optional<double> {
    if (!ns) return std::nullopt;
    return static_cast<double>(*ns) / 1000.0;
  };
  const IntervalStats intervals = bus_.captureIntervals();
  summary.median_us = us(intervals.medianNs());
  summary.p99_us = us(intervals.quantileNs(0.99));
  summary.max_us = us(intervals.maxNs());
  return summary;
}

void Validator::report(RuleId rule, std::optional<std::uint16_t> axis, const Stamp& since,
                       std::string message) {
  if (!settings_.isEnabled(rule)) return;
  const std::uint32_t ordinal = ++ordinals_[{rule, axis ? *axis : kNoAxisKey}];
  findings_.push_back(Finding{rule, settings_.severityOf(rule), axis,
                              Stamp{now_.frame, frame_time_ns_}, since, std::move(message),
                              ordinal});
}

Validator::AxisSlot& Validator::slot(std::uint16_t axis) {
  if (axis < axes_.size() && axes_[axis].model) return axes_[axis];
  if (axis >= axes_.size()) axes_.resize(axis + 1u);
  AxisSlot& s = axes_[axis];
  s.model.emplace(axis, settings_.readyModeFor(axis));
  return s;
}

const Observation& Validator::onFrame(std::uint64_t frame_number, std::int64_t time_ns,
                                      const EcatFrame& frame, const ByteReader& bytes) {
  findings_.clear();
  accounts_.clear();
  view_.servo_error_rises = 0;
  // docs/timing.md#rule-time: timestamps that go back a little do not move timers back; a
  // discontinuity starts a segment with timers of its own.
  const bool new_segment = segments_.onFrame(frame_number, time_ns, bus_.nominalCycleNs());
  now_ = Stamp{frame_number, segments_.now()};
  frame_time_ns_ = time_ns;
  if (new_segment) startSegment();

  FrameDecode& decode = view_.decode;
  decoder_.placeAxes(frame, bytes, decode);
  if (decode.any_malformed) cut_.add(frame_number, decode);
  // The slave trackers address the frame's datagrams alike: worked out once for both.
  if (frame.status == WalkStatus::Ok || frame.status == WalkStatus::Truncated) {
    addressing_.beginFrame(frame, decode.copy == CopyKind::Returned, decode.paired);
    observeAl(frame, bytes);
    events_.clear();
    dc_.onFrame(frame, bytes, addressing_, now_, time_ns, events_);
    // Mailboxes and ESC counters are read by register commands only: a frame of nothing but
    // process data and the DC clock's FRMW skips both (docs/benchmarks.md).
    if (decode.registers) {
      mailbox_.onFrame(frame, bytes, addressing_, now_, time_ns, events_);
      if (judged_.mailbox) takeDriveMessages();
      esc_.onFrame(frame, bytes, addressing_, now_, events_);
    } else {
      mailbox_.quietFrame();
      esc_.quietFrame();
    }
    if (!events_.empty()) reportEvents();
  }
  // Only a frame that reaches slave registers moves an AL state or gives an axis its station.
  if (decode.registers || al_.lastFrameReachedRegisters()) ++al_epoch_;
  const std::size_t axis_count = decode.axis_count;
  if (axis_count == 0) {
    // The bus rules judge cyclic traffic without servos too (docs/timing.md "Which frames").
    if (BusModel::exchangesProcessData(frame, decode)) {
      events_.clear();
      accounts_.clear();
      bus_.onCyclicFrame(frame, decode, now_, frame_time_ns_, events_, accounts_);
      reportEvents();
    }
    return view_;
  }
  // The placements are in axis order: the slots grow once (which moves them), then this frame's
  // are looked up once.
  const std::uint16_t last_axis = decode.axes[axis_count - 1].axis;
  if (last_axis >= axes_.size()) axes_.resize(last_axis + 1u);
  for (std::size_t i = 0; i < axis_count; ++i) {
    const AxisPlacement& placement = decode.axes[i];
    AxisSlot& s = axes_[placement.axis];
    if (!s.model) s.model.emplace(placement.axis, settings_.readyModeFor(placement.axis));
    if (s.al_epoch != al_epoch_) {
      syncAlState(placement, s);
      s.al_epoch = al_epoch_;
    }
    frame_slots_[i] = &s;
  }
  events_.clear();
  accounts_.clear();
  const bool all_good = bus_.onCyclicFrame(frame, decode, now_, frame_time_ns_, events_, accounts_);
  reportEvents();
  applyAccounts();
  // slot() may have grown the slots for an axis of an earlier master copy.
  if (!accounts_.empty()) {
    for (std::size_t i = 0; i < axis_count; ++i) frame_slots_[i] = &axes_[decode.axes[i].axis];
  }
  if (all_good) {
    for (std::size_t i = 0; i < axis_count; ++i) frame_slots_[i]->model->cycleOk(now_);
  }
  // A returned copy right after its master copy carries the same outputs: one set point a cycle.
  const bool outputs_cycle = !(decode.copy == CopyKind::Returned && decode.paired);
  const Mark mark{frame_number, now_.time_ns, frame_time_ns_};
  for (std::size_t i = 0; i < axis_count; ++i) {
    AxisSlot& s = *frame_slots_[i];
    AxisModel& model = *s.model;
    PdoValues& values = view_.values[i];
    readFrameValues(decode.axes[i], bytes, values);
    view_.servo_error_rises += model.measure(values, outputs_cycle, mark) ? 1 : 0;
    // Fast path: the bits the model and the rules read are unchanged and no timer runs out, so
    // no condition can have changed (rules report at beginnings and at timeouts only).
    if (!fast_path_ || (s.pending != 0 && now_.time_ns > s.pending_until_ns) ||
        s.evaluated_revision != model.revision() || !unchanged(values, model)) {
      model.observe(values, now_);
      evaluateAxis(s);
      s.evaluated_revision = model.revision();
    }
    view_.states[i] = model.state();
  }
  return view_;
}

void Validator::applyAccounts() {
  for (const AxisAccount& account : accounts_) {
    AxisModel& model = *slot(account.axis).model;
    if (account.outcome == AxisAccount::Outcome::Good) {
      model.cycleOk(now_);
    } else {
      model.cycleFailed(account.outcome == AxisAccount::Outcome::Lost, account.cycles, now_);
    }
  }
}

void Validator::finish() {
  findings_.clear();
  events_.clear();
  accounts_.clear();
  bus_.finish(events_, accounts_);
  reportEvents();
  applyAccounts();
  for (const AxisAccount& account : accounts_) evaluateAxis(slot(account.axis));
}

void Validator::startSegment() {
  events_.clear();
  bus_.startSegment(events_);
  reportEvents();
  runs_.clear();
  al_.startSegment();
  dc_.startSegment();
  ++al_epoch_;  // the AL states are taken again
  for (AxisSlot& s : axes_) {
    if (!s.model) continue;
    s.model->startSegment();
    s.episodes = {};
    s.pending = 0;
    s.evaluated_revision.reset();
  }
  // After the events that closed the segment before: they count in it.
  ordinals_.clear();
}

// The AL state of the axis's slave, where its station is known (ESM-002), and its entries into
// OP since the last look (the total failure counter resets), whichever frames showed
// them: an AL status poll need not share a frame with the axis's PDOs.
void Validator::syncAlState(const AxisPlacement& placement, AxisSlot& slot) {
  const std::vector<AxisInfo>& infos = decoder_.axes();
  if (placement.axis >= infos.size() || !infos[placement.axis].has_station) return;
  const std::uint16_t station = infos[placement.axis].station;
  AxisModel& model = *slot.model;
  model.setAlState(al_.stateOfStation(station));
  const std::uint32_t entries = al_.opEntries(station);
  if (slot.al_station == station && entries != slot.op_entries) model.enteredOp();
  slot.al_station = station;
  slot.op_entries = entries;
}

// docs/timing.md#rule-time: a condition is reported once per episode — when it begins, or for a
// delayed rule on the first frame past its timeout after it began — and again only after it ended.
// A rule about a stamped event (RuleDef::began) times it from the event, and a new event after a
// reported one is a new episode.
void Validator::evaluateAxis(AxisSlot& s, bool mailbox_only) {
  const AxisModel& model = *s.model;
  const RuleSubject subject{&model, nullptr};
  if (!mailbox_only) s.pending_until_ns = std::numeric_limits<std::int64_t>::max();
  for (const RuleDef& rule : kRules) {
    if (rule.kind != RuleKind::Axis || !settings_.isEnabled(rule.id)) continue;
    if (mailbox_only && !rule.reads.mailbox) continue;
    Episode& episode = s.episodes[static_cast<std::size_t>(rule.id)];
    const bool was_pending = episode.active && !episode.reported;
    const RuleContext context{rule, settings_};
    if (!rule.check(subject, context)) {
      if (was_pending) --s.pending;
      episode.active = false;
      continue;
    }
    const std::optional<Stamp> began = rule.began ? rule.began(subject) : std::nullopt;
    if (!episode.active || (episode.reported && began && began->frame != episode.began.frame)) {
      episode = Episode{true, false, began.value_or(now_)};
    }
    if (episode.reported) continue;
    const std::int64_t held = now_.time_ns - episode.began.time_ns;
    const std::int64_t timeout = rule.delayed() ? context.timeoutNs() : 0;
    if (rule.delayed() && held <= timeout) {
      if (!was_pending) ++s.pending;
      // held <= timeout: began + timeout does not overflow where now_ does not
      s.pending_until_ns = std::min(s.pending_until_ns, now_.time_ns + (timeout - held));
      continue;
    }
    if (was_pending) --s.pending;
    episode.reported = true;
    report(rule.id, model.index(), episode.began, rule.describe(subject, context, held));
  }
}

// docs/drive-messages.md#the-rules: what an axis's drive said in this frame, to its model (an
// axis seen in the PDOs, whose station is known), and the rules that read it judged at once.
void Validator::takeDriveMessages() {
  for (const DriveMessage& m : mailbox_.frameMessages()) {
    if (m.frame != now_.frame || !m.slave.station) continue;
    const std::optional<std::uint16_t> axis = decoder_.axisOfStation(*m.slave.station);
    if (!axis || *axis >= axes_.size() || !axes_[*axis].model) continue;
    AxisSlot& s = axes_[*axis];
    bool took = false;
    if (m.kind == DriveMessage::Kind::Emergency) {
      s.model->takeEmergency(m.emergency.code, now_);
      took = true;
    } else if (m.kind == DriveMessage::Kind::SdoUpload && m.index == diag::kPredefinedErrorField &&
               m.subindex == 1 && m.value) {
      took = s.model->takeHistoryRead(static_cast<std::uint32_t>(*m.value), now_);
    }
    if (took) evaluateAxis(s, true);
  }
}

void Validator::observeAl(const EcatFrame& frame, const ByteReader& bytes) {
  events_.clear();
  al_.onFrame(frame, bytes, addressing_, now_, events_);
  reportEvents();
}

const FrameTiming& Validator::frameTiming() const {
  static const FrameTiming kNone;
  return bus_.frameTiming().frame == now_.frame ? bus_.frameTiming() : kNone;
}

// The bus and slave rules on this frame's events; a slave's finding names the axis whose
// station it is.
void Validator::reportEvents() {
  for (const BusEvent& event : events_) {
    if (!judged_events_[event.data.index()]) continue;
    event_findings_.clear();
    judgeEvent(event, settings_, runs_, event_findings_);
    for (EventFinding& f : event_findings_) {
      const std::optional<std::uint16_t> axis =
          f.slave.station ? decoder_.axisOfStation(*f.slave.station) : std::nullopt;
      report(f.rule, axis, event.since, std::move(f.message));
    }
  }
}

}  // namespace ncservo
