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

const FrameView& Validator::onFrame(std::uint64_t frame_number, std::int64_t time_ns,
                                    const EcatFrame& frame, const ByteReader& bytes) {
  findings_.clear();
  // RULES.md: timestamps that go backwards do not move timers back.
  const std::int64_t monotonic = any_frame_ ? std::max(now_.time_ns, time_ns) : time_ns;
  any_frame_ = true;
  now_ = Stamp{frame_number, monotonic};
  frame_time_ns_ = time_ns;

  // The placements, then each axis's values read and judged in one pass (what a Session would
  // give, without building its view and then walking it again).
  decoder_.decode(frame, bytes, decode_);
  view_.copy = decode_.copy;
  view_.paired = decode_.paired;
  view_.axis_count = decode_.axis_count;
  observeAl(frame, bytes);
  const std::size_t axis_count = decode_.axis_count;
  // The slots grow once (which moves them), then this frame's are looked up once.
  std::uint16_t first_axis = std::numeric_limits<std::uint16_t>::max(), last_axis = 0;
  for (std::size_t i = 0; i < axis_count; ++i) {
    first_axis = std::min(first_axis, decode_.axes[i].axis);
    last_axis = std::max(last_axis, decode_.axes[i].axis);
  }
  if (axis_count > 0 && last_axis >= axes_.size()) axes_.resize(last_axis + 1u);
  for (std::size_t i = 0; i < axis_count; ++i) {
    const std::uint16_t axis = decode_.axes[i].axis;
    AxisSlot& s = axes_[axis];
    if (!s.model) s.model.emplace(axis, settings_.readyModeFor(axis));
    frame_slots_[i] = &s;
  }
  if (axis_count > 0) accountCycle(frame, first_axis);
  const std::vector<AxisInfo>& infos = decoder_.axes();
  for (std::size_t i = 0; i < axis_count; ++i) {
    AxisFrameView& a = view_.axes[i];
    a.placement = decode_.axes[i];
    readFrameValues(a.placement, bytes, a.values);
    AxisSlot& s = *frame_slots_[i];
    AxisModel& model = *s.model;
    const AxisInfo* info = a.placement.axis < infos.size() ? &infos[a.placement.axis] : nullptr;
    if (info != nullptr && info->has_station) {
      model.setAlState(al_.stateOfStation(info->station));
      if (al_.enteredOp(info->station)) model.enteredOp();
    }
    // Fast path: the words the rules read are unchanged and no timer runs, so no condition can
    // have changed (RULES.md reports at beginnings and at timeouts only).
    if (s.pending != 0 || s.evaluated_revision != model.revision() ||
        !model.wouldNotChange(a.values)) {
      model.observe(a.values, now_);
      evaluateAxis(s);
      s.evaluated_revision = model.revision();
    }
    a.state = model.state();
  }
  return view_;
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
  al_.onFrame(frame, bytes, decode_.copy == CopyKind::Returned, decode_.paired, now_, al_findings_);
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
  const bool master = decode_.copy == CopyKind::Master;
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
    cyclic.axes.clear();
    for (std::size_t i = 0; i < decode_.axis_count; ++i) {
      cyclic.axes.push_back(decode_.axes[i].axis);
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
    for (std::size_t i = 0; i < decode_.axis_count; ++i) {
      if (missing > 0) frame_slots_[i]->model->cycleFailed(true, missing, now_);
    }
  }
  intervals_.add(interval);
  cyclic.last_tick = now_;
}

Validator::WkcRecord* Validator::wkcRecord(const Datagram& dg) {
  for (WkcRecord& r : wkc_) {
    if (r.command == dg.command && r.address == dg.address && r.length == dg.length) return &r;
  }
  if (wkc_.size() >= kMaxWkcRecords) return nullptr;
  wkc_.push_back(WkcRecord{dg.command, dg.address, dg.length});
  return &wkc_.back();
}

// RULES.md COM-001 on each returned datagram that carries servo PDOs, and each axis's cycle:
// lost (WKC 0), failed (another wrong WKC) or good.
void Validator::checkWorkingCounters(const EcatFrame& frame) {
  enum Outcome : std::uint8_t { kGood, kFailed, kLost };
  // Per datagram: what the axes it carries add to its WKC, the bytes of theirs it holds, and the
  // outcome. One pass over the axes; only the frame's first `count` entries are used.
  struct Carried {
    bool carries;
    std::uint16_t expected;
    std::size_t covered;
    std::uint8_t outcome;
  };
  std::array<Carried, ecat::kMaxDatagrams> carried;
  const std::size_t count = std::min(frame.count, carried.size());
  for (std::size_t d = 0; d < count; ++d) carried[d] = Carried{false, 0, 0, kGood};
  auto add = [&](std::size_t d, bool out, bool in) {
    if (d >= count) return;
    Carried& c = carried[d];
    c.carries = true;
    c.expected =
        static_cast<std::uint16_t>(c.expected + wkcShare(frame.datagrams[d].command, out, in));
    c.covered += (out ? kRxPdoSize : 0) + (in ? kTxPdoSize : 0);
  };
  for (std::size_t i = 0; i < decode_.axis_count; ++i) {
    const AxisPlacement& p = decode_.axes[i];
    if (p.rx_placed && p.tx_placed && p.rx_datagram == p.tx_datagram) {
      add(p.rx_datagram, true, true);
      continue;
    }
    if (p.rx_placed) add(p.rx_datagram, true, false);
    if (p.tx_placed) add(p.tx_datagram, false, true);
  }
  for (std::size_t d = 0; d < count; ++d) {
    const Datagram& dg = frame.datagrams[d];
    Carried& c = carried[d];
    if (!c.carries || !dg.has_wkc) continue;
    std::uint16_t expected = c.expected;
    WkcRecord* record = wkcRecord(dg);
    // Other slaves share the datagram: the expected value is the one seen most often so far.
    if (c.covered != dg.length && record != nullptr) {
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
      c.outcome = dg.wkc == 0 ? kLost : kFailed;
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
  for (std::size_t i = 0; i < decode_.axis_count; ++i) {
    const AxisPlacement& p = decode_.axes[i];
    std::uint8_t outcome = kGood;
    if (p.rx_placed && p.rx_datagram < count) outcome = carried[p.rx_datagram].outcome;
    if (p.tx_placed && p.tx_datagram < count) {
      outcome = std::max(outcome, carried[p.tx_datagram].outcome);
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
