#include "ncservo/validator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ncservo {

namespace {
// RULES.md COM-002: no gap is judged before 8 intervals; a gap is more than 1.5 × the median.
constexpr std::uint64_t kIntervalsBeforeGaps = 8;
constexpr std::int64_t kGapNumerator = 3, kGapDenominator = 2;
constexpr std::size_t kMaxWkcRecords = 64;

// PROTOCOL.md §8: an LRW/FPRW adds 2 for a slave whose outputs it writes and 1 for one whose
// inputs it reads; LRD/LWR/FPRD/FPWR add 1 per slave.
std::uint16_t wkcShare(std::uint8_t cmd, bool outputs, bool inputs) {
  if (cmd == ecat::kLrw || cmd == ecat::kFprw) return (outputs ? 2 : 0) + (inputs ? 1 : 0);
  return (outputs && ecat::writesSlaves(cmd)) || (inputs && ecat::readsSlaves(cmd)) ? 1 : 0;
}
}  // namespace

Validator::Validator(DecoderOptions options, RuleSettings settings)
    : decoder_(std::move(options)), settings_(std::move(settings)) {}

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
  summary.median_us = us(intervals_.medianNs());
  summary.p99_us = us(intervals_.quantileNs(0.99));
  summary.max_us = us(intervals_.maxNs());
  return summary;
}

void Validator::report(RuleId rule, std::optional<std::uint16_t> axis, const Stamp& since,
                       std::string message) {
  if (!settings_.isEnabled(rule)) return;
  findings_.push_back(Finding{rule, settings_.severityOf(rule), axis,
                              Stamp{now_.frame, frame_time_ns_}, since, std::move(message)});
}

Validator::AxisSlot& Validator::slot(std::uint16_t axis) {
  if (axis < axes_.size() && axes_[axis].model) return axes_[axis];
  if (axis >= axes_.size()) axes_.resize(axis + 1u);
  AxisSlot& s = axes_[axis];
  s.model.emplace(axis, settings_.readyModeFor(axis));
  return s;
}

const ValidatedFrame& Validator::onFrame(std::uint64_t frame_number, std::int64_t time_ns,
                                         const EcatFrame& frame, const ByteReader& bytes) {
  findings_.clear();
  // RULES.md: timestamps that go backwards do not move timers back.
  const std::int64_t monotonic = any_frame_ ? std::max(now_.time_ns, time_ns) : time_ns;
  any_frame_ = true;
  now_ = Stamp{frame_number, monotonic};
  frame_time_ns_ = time_ns;

  FrameDecode& decode = view_.decode;
  decoder_.decode(frame, bytes, decode);
  observeAl(frame, bytes);
  // Only a frame that reaches slave registers moves an AL state or gives an axis its station.
  if (decode.registers || al_.lastFrameReachedRegisters()) ++al_epoch_;
  const std::size_t axis_count = decode.axis_count;
  if (axis_count == 0) return view_;
  // The placements are in axis order: the slots grow once (which moves them), then this frame's
  // are looked up once.
  const std::uint16_t first_axis = decode.axes[0].axis;
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
  accountCycle(frame, first_axis);
  for (std::size_t i = 0; i < axis_count; ++i) {
    const AxisPlacement& placement = decode.axes[i];
    AxisSlot& s = *frame_slots_[i];
    AxisModel& model = *s.model;
    // Fast path: the words the rules read are unchanged and no timer runs, so no condition can
    // have changed (RULES.md reports at beginnings and at timeouts only). Only those words are
    // read; the whole PDOs are read when the model takes them.
    if (s.pending != 0 || s.evaluated_revision != model.revision() ||
        !model.wouldNotChange(readJudgedWords(placement, bytes))) {
      PdoValues values;
      readFrameValues(placement, bytes, values);
      model.observe(values, now_);
      evaluateAxis(s);
      s.evaluated_revision = model.revision();
    }
    view_.states[i] = model.state();
  }
  return view_;
}

// The AL state of the axis's slave, where its station is known (ESM-002), and its entries into
// OP since the last look (seed 001: the total failure counter resets), whichever frames showed
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

// RULES.md "Time": a condition is reported once per episode — when it begins, or for a delayed
// rule on the first frame more than its timeout after it began — and again only after it ended.
void Validator::evaluateAxis(AxisSlot& s) {
  const AxisModel& model = *s.model;
  for (const RuleDef& rule : kRules) {
    if (rule.check == nullptr || !settings_.isEnabled(rule.id)) continue;
    Episode& episode = s.episodes[static_cast<std::size_t>(rule.id)];
    const bool was_pending = episode.active && !episode.reported;
    if (!rule.check(model, settings_)) {
      if (was_pending) --s.pending;
      episode.active = false;
      continue;
    }
    if (!episode.active) episode = Episode{true, false, now_};
    if (episode.reported) continue;
    const std::int64_t held = now_.time_ns - episode.began.time_ns;
    if (rule.delayed && held <= settings_.timeoutNs(*rule.timeout)) {
      if (!was_pending) ++s.pending;
      continue;
    }
    if (was_pending) --s.pending;
    episode.reported = true;
    report(rule.id, model.index(), episode.began, rule.describe(model, settings_, held));
  }
}

void Validator::observeAl(const EcatFrame& frame, const ByteReader& bytes) {
  if (frame.status != WalkStatus::Ok && frame.status != WalkStatus::Truncated) return;
  al_findings_.clear();
  al_.onFrame(frame, bytes, view_.decode.copy == CopyKind::Returned, view_.decode.paired, now_,
              al_findings_);
  for (AlFinding& f : al_findings_) {
    std::optional<std::uint16_t> axis;
    for (const AxisInfo& info : decoder().axes()) {
      if (info.has_station && f.station && info.station == *f.station) axis = info.index;
    }
    report(f.rule, axis, now_, std::move(f.message));
  }
}

Validator::CyclicFrame* Validator::cyclicFrame(std::uint16_t first_axis) {
  for (CyclicFrame& c : cyclic_) {
    if (c.first_axis == first_axis) return &c;
  }
  cyclic_.push_back(CyclicFrame{});
  cyclic_.back().first_axis = first_axis;
  return &cyclic_.back();
}

// Telegram accounting (RULES.md COM-002, COM-004; failures for COM-003 and COM-005). The clock is
// the master's copy of each cyclic frame, or the returned copy in a capture without master copies.
void Validator::accountCycle(const EcatFrame& frame, std::uint16_t first_axis) {
  CyclicFrame& cyclic = *cyclicFrame(first_axis);
  const bool master = view_.decode.copy == CopyKind::Master;
  if (master && !master_copies_seen_) {
    master_copies_seen_ = true;
    for (CyclicFrame& c : cyclic_) c.last_tick.reset();  // returned copies were the clock so far
  }
  returned_copies_seen_ = returned_copies_seen_ || !master;

  if (master) {
    // RULES.md COM-004: judged on the next master frame, once returned copies exist at all.
    if (cyclic.awaiting_return && returned_copies_seen_) {
      if (!cyclic.not_returned_episode) {
        cyclic.not_returned_episode = true;
        report(RuleId::Com004, std::nullopt, cyclic.last_master,
               fmt::format("the master frame {} (axes {}-{}) was not returned before the next "
                           "cycle's master frame",
                           cyclic.last_master.frame, cyclic.axes.front(), cyclic.axes.back()));
      }
      for (std::uint16_t a : cyclic.axes) slot(a).model->cycleFailed(true, 1, now_);
    }
    cyclic.awaiting_return = true;
    cyclic.last_master = now_;
    // A cached shape carries the same axes as last time.
    if (view_.decode.shape_id == 0 || view_.decode.shape_id != cyclic.axes_shape_id) {
      cyclic.axes.clear();
      for (std::size_t i = 0; i < view_.decode.axis_count; ++i) {
        cyclic.axes.push_back(view_.decode.axes[i].axis);
      }
      cyclic.axes_shape_id = view_.decode.shape_id;
    }
    tick(cyclic);
  } else {
    if (!master_copies_seen_) tick(cyclic);
    cyclic.awaiting_return = false;
    cyclic.not_returned_episode = false;
    checkWorkingCounters(frame);
  }
}

// One tick of a cyclic frame's clock: the interval statistics and COM-002.
void Validator::tick(CyclicFrame& cyclic) {
  if (cyclic.first_axis == cyclic_.front().first_axis) ++cycles_;
  // RULES.md "Time": a timestamp that went backwards is not an error; the interval it would
  // give is unknown, so the clock of this cyclic frame starts again at the next tick.
  if (frame_time_ns_ < now_.time_ns) {
    cyclic.last_tick.reset();
    return;
  }
  if (!cyclic.last_tick) {
    cyclic.last_tick = now_;
    return;
  }
  const std::int64_t interval = now_.time_ns - cyclic.last_tick->time_ns;
  const std::optional<std::int64_t> median = intervals_.medianNs();
  if (intervals_.count() >= kIntervalsBeforeGaps && median && *median > 0 &&
      interval * kGapDenominator > *median * kGapNumerator) {
    const auto missing = static_cast<std::uint32_t>(
        std::llround(static_cast<double>(interval) / static_cast<double>(*median)) - 1);
    report(RuleId::Com002, std::nullopt, *cyclic.last_tick,
           fmt::format("{:.3f} ms since the previous cycle (frame {}), {:.3f} ms nominal: {} "
                       "cycle{} missing",
                       static_cast<double>(interval) / 1e6, cyclic.last_tick->frame,
                       static_cast<double>(*median) / 1e6, missing, missing == 1 ? "" : "s"));
    for (std::size_t i = 0; i < view_.decode.axis_count; ++i) {
      if (missing > 0) frame_slots_[i]->model->cycleFailed(true, missing, now_);
    }
  }
  intervals_.add(interval);
  cyclic.last_tick = now_;
}

std::int16_t Validator::wkcRecord(const Datagram& dg) {
  for (std::size_t i = 0; i < wkc_.size(); ++i) {
    const WkcRecord& r = wkc_[i];
    if (r.command == dg.command && r.address == dg.address && r.length == dg.length) {
      return static_cast<std::int16_t>(i);
    }
  }
  if (wkc_.size() >= kMaxWkcRecords) return kNoWkcRecord;
  wkc_.push_back(WkcRecord{dg.command, dg.address, dg.length});
  return static_cast<std::int16_t>(wkc_.size() - 1);
}

// Which datagrams of this frame carry servo PDOs, and what the axes in each add to its WKC.
Validator::WkcPlan& Validator::wkcPlan(const EcatFrame& frame) {
  const FrameDecode& decode = view_.decode;
  if (decode.shape_id != 0) {
    for (WkcPlan& plan : wkc_plans_) {
      if (plan.shape_id == decode.shape_id) return plan;
    }
  }
  WkcPlan& plan = decode.shape_id != 0 ? wkc_plans_[wkc_plan_next_] : uncached_plan_;
  if (decode.shape_id != 0) wkc_plan_next_ = (wkc_plan_next_ + 1) % wkc_plans_.size();
  plan.shape_id = decode.shape_id;
  plan.checks.clear();
  // Per datagram: what the axes it carries add to its WKC and the bytes of theirs it holds.
  struct Carried {
    bool carries = false;
    std::uint16_t expected = 0;
    std::size_t covered = 0;
  };
  std::array<Carried, ecat::kMaxDatagrams> carried{};
  const std::size_t count = std::min(frame.count, carried.size());
  auto add = [&](std::size_t d, bool out, bool in) {
    if (d >= count) return;
    Carried& c = carried[d];
    c.carries = true;
    c.expected =
        static_cast<std::uint16_t>(c.expected + wkcShare(frame.datagrams[d].command, out, in));
    c.covered += (out ? kRxPdoSize : 0) + (in ? kTxPdoSize : 0);
  };
  for (std::size_t i = 0; i < decode.axis_count; ++i) {
    const AxisPlacement& p = decode.axes[i];
    if (p.rx_placed && p.tx_placed && p.rx_datagram == p.tx_datagram) {
      add(p.rx_datagram, true, true);
      continue;
    }
    if (p.rx_placed) add(p.rx_datagram, true, false);
    if (p.tx_placed) add(p.tx_datagram, false, true);
  }
  for (std::size_t d = 0; d < count; ++d) {
    if (!carried[d].carries) continue;
    plan.checks.push_back(WkcCheck{static_cast<std::uint16_t>(d), carried[d].expected,
                                   carried[d].covered != frame.datagrams[d].length,
                                   kUnresolvedWkcRecord});
  }
  return plan;
}

// RULES.md COM-001 on each returned datagram that carries servo PDOs, and each axis's cycle:
// lost (WKC 0), failed (another wrong WKC) or good.
void Validator::checkWorkingCounters(const EcatFrame& frame) {
  enum Outcome : std::uint8_t { kGood, kFailed, kLost };
  WkcPlan& plan = wkcPlan(frame);
  const FrameDecode& decode = view_.decode;
  bool all_good = true;
  for (WkcCheck& check : plan.checks) {
    const Datagram& dg = frame.datagrams[check.datagram];
    check.outcome = kGood;
    if (!dg.has_wkc) continue;
    if (check.record == kUnresolvedWkcRecord) check.record = wkcRecord(dg);
    WkcRecord* record = check.record >= 0 ? &wkc_[static_cast<std::size_t>(check.record)] : nullptr;
    std::uint16_t expected = check.expected;
    // Other slaves share the datagram: the expected value is the one seen most often so far.
    if (check.shared && record != nullptr) {
      std::size_t slot_index = record->values.size();
      for (std::size_t k = 0; k < record->values.size(); ++k) {
        if (record->counts[k] > 0 && record->values[k] == dg.wkc) slot_index = k;
      }
      if (slot_index == record->values.size()) {
        slot_index = static_cast<std::size_t>(
            std::min_element(record->counts.begin(), record->counts.end()) -
            record->counts.begin());
        if (record->counts[slot_index] == 0)
          record->values[slot_index] = dg.wkc;
        else
          slot_index = record->values.size();  // too many distinct values: not counted
      }
      if (slot_index < record->values.size()) ++record->counts[slot_index];
      const std::size_t mode = static_cast<std::size_t>(
          std::max_element(record->counts.begin(), record->counts.end()) - record->counts.begin());
      expected = record->values[mode];
    }
    if (dg.wkc != expected) {
      check.outcome = dg.wkc == 0 ? kLost : kFailed;
      all_good = false;
      if (record == nullptr || !record->wrong_episode) {
        if (record != nullptr) record->wrong_episode = true;
        report(RuleId::Com001, std::nullopt, now_,
               fmt::format("{} at 0x{:08X} ({} bytes) returned with WKC {}, expected {}{}",
                           ecat::commandName(dg.command), dg.address, dg.length, dg.wkc, expected,
                           dg.wkc == 0 ? " (no slave processed it)" : "; inputs may be stale"));
      }
    } else if (record != nullptr) {
      record->wrong_episode = false;
    }
  }
  if (all_good) {
    for (std::size_t i = 0; i < decode.axis_count; ++i) frame_slots_[i]->model->cycleOk(now_);
    return;
  }
  std::array<std::uint8_t, ecat::kMaxDatagrams> outcomes{};
  for (const WkcCheck& check : plan.checks) outcomes[check.datagram] = check.outcome;
  const std::size_t count = std::min(frame.count, outcomes.size());
  for (std::size_t i = 0; i < decode.axis_count; ++i) {
    const AxisPlacement& p = decode.axes[i];
    std::uint8_t outcome = kGood;
    if (p.rx_placed && p.rx_datagram < count) outcome = outcomes[p.rx_datagram];
    if (p.tx_placed && p.tx_datagram < count) {
      outcome = std::max(outcome, outcomes[p.tx_datagram]);
    }
    AxisModel& model = *frame_slots_[i]->model;
    if (outcome == kGood) {
      model.cycleOk(now_);
    } else {
      model.cycleFailed(outcome == kLost, 1, now_);
    }
  }
}

}  // namespace ncservo
