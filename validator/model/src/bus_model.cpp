#include "ncservo/model/bus_model.hpp"

#include <algorithm>
#include <cmath>

#include "ncservo/protocol/pdo_layout.hpp"

namespace ncservo {

namespace {
// docs/rules.md#com-002: no gap is judged before 8 intervals; a gap is more than 1.5 × the median.
constexpr std::uint64_t kIntervalsBeforeGaps = 8;
constexpr std::int64_t kGapNumerator = 3, kGapDenominator = 2;
constexpr std::size_t kMaxWkcRecords = 64;
using Outcome = AxisAccount::Outcome;

// round(interval ÷ nominal) − 1: the cycles an interval leaves out (docs/rules.md#com-002).
std::uint32_t missingCycles(std::int64_t interval_ns, std::int64_t nominal_ns) {
  const long long cycles =
      std::llround(static_cast<double>(interval_ns) / static_cast<double>(nominal_ns));
  return cycles > 1 ? static_cast<std::uint32_t>(cycles - 1) : 0;
}

// docs/protocol.md §8: an LRW/FPRW adds 2 for a slave whose outputs it writes and 1 for one whose
// inputs it reads; LRD/LWR/FPRD/FPWR add 1 per slave.
std::uint16_t wkcShare(std::uint8_t cmd, bool outputs, bool inputs) {
  if (cmd == ecat::kLrw || cmd == ecat::kFprw) return (outputs ? 2 : 0) + (inputs ? 1 : 0);
  return (outputs && ecat::writesSlaves(cmd)) || (inputs && ecat::readsSlaves(cmd)) ? 1 : 0;
}
}  // namespace

bool BusModel::exchangesProcessData(const EcatFrame& frame, const FrameDecode& decode) {
  if (decode.axis_count > 0) return true;
  if (frame.status != WalkStatus::Ok && frame.status != WalkStatus::Truncated) return false;
  const std::size_t count = std::min(frame.count, frame.datagrams.size());
  for (std::size_t d = 0; d < count; ++d) {
    if (ecat::isLogical(frame.datagrams[d].command)) return true;
  }
  return false;
}

std::size_t BusModel::processDatagrams(const EcatFrame& frame, const FrameDecode& decode,
                                       std::array<DatagramKey, ecat::kMaxDatagrams>& keys) {
  const std::size_t count = std::min(frame.count, keys.size());
  // Servo PDOs may also travel in FPRD/FPWR datagrams (docs/protocol.md §9).
  std::array<bool, ecat::kMaxDatagrams> carries_axes{};
  for (std::size_t i = 0; i < decode.axis_count; ++i) {
    const AxisPlacement& p = decode.axes[i];
    if (p.rx_placed && p.rx_datagram < count) carries_axes[p.rx_datagram] = true;
    if (p.tx_placed && p.tx_datagram < count) carries_axes[p.tx_datagram] = true;
  }
  std::size_t n = 0;
  for (std::size_t d = 0; d < count; ++d) {
    const Datagram& dg = frame.datagrams[d];
    if (ecat::isLogical(dg.command) || carries_axes[d]) {
      keys[n++] = DatagramKey{dg.command, dg.address, dg.length};
    }
  }
  return n;
}

BusModel::CyclicFrame* BusModel::cyclicFrame(const EcatFrame& frame, const FrameDecode& decode) {
  if (decode.shape_id != 0) {
    for (const ShapeCyclic& cached : shape_cyclic_) {
      if (cached.shape_id == decode.shape_id) return &cyclic_[cached.index];
    }
  }
  const std::size_t n = processDatagrams(frame, decode, frame_keys_);
  const auto first = frame_keys_.begin();
  const auto last = first + static_cast<std::ptrdiff_t>(n);
  const auto remember = [&](std::size_t index) {
    if (decode.shape_id == 0) return &cyclic_[index];
    shape_cyclic_[shape_cyclic_next_] = ShapeCyclic{decode.shape_id, index};
    shape_cyclic_next_ = (shape_cyclic_next_ + 1) % shape_cyclic_.size();
    return &cyclic_[index];
  };
  for (std::size_t i = 0; i < cyclic_.size(); ++i) {
    const CyclicFrame& c = cyclic_[i];
    if (std::equal(c.datagrams.begin(), c.datagrams.end(), first, last)) return remember(i);
  }
  shape_cyclic_ = {};
  // Bounded memory: a frame seen in one cycle only (a start-up's) gives way to a new one.
  if (cyclic_.size() >= kMaxCyclicFrames) {
    const auto once = std::find_if(cyclic_.begin(), cyclic_.end(),
                                   [](const CyclicFrame& c) { return c.ticks <= 1; });
    if (once == cyclic_.end()) {
      ++unfollowed_frames_;
      return nullptr;
    }
    cyclic_.erase(once);
  }
  std::array<bool, kMaxCyclicFrames> slot_taken{};
  for (const CyclicFrame& c : cyclic_) slot_taken[c.id.slot] = true;
  const auto free_slot = std::find(slot_taken.begin(), slot_taken.end(), false);
  const auto slot = static_cast<std::uint8_t>(free_slot - slot_taken.begin());
  frame_intervals_[slot].clear();
  frame_capture_intervals_[slot].clear();
  cyclic_.push_back(CyclicFrame{});
  cyclic_.back().id = {slot, ++cyclic_serials_};
  cyclic_.back().datagrams.assign(first, last);
  return remember(cyclic_.size() - 1);
}

std::uint64_t BusModel::cycles() const {
  std::uint64_t busiest = 0;
  for (const CyclicFrame& c : cyclic_) busiest = std::max(busiest, c.ticks);
  return busiest;
}

std::vector<CyclicDatagram> BusModel::cyclicDatagrams() const {
  std::vector<CyclicDatagram> out;
  for (const CyclicFrame& c : cyclic_) {
    if (c.ticks < 2) continue;
    for (const DatagramKey& key : c.datagrams) {
      auto same = std::find_if(out.begin(), out.end(), [&](const CyclicDatagram& d) {
        return d.command == key.command && d.address == key.address && d.length == key.length;
      });
      if (same == out.end())
        same = out.insert(out.end(), {key.command, key.address, key.length, 0});
      same->frames += c.copies;
    }
  }
  return out;
}

std::vector<CyclicFrameSummary> BusModel::cyclicFrames() const {
  std::vector<CyclicFrameSummary> out;
  for (const CyclicFrame& c : cyclic_) {
    if (c.ticks < 2) continue;
    CyclicFrameSummary summary;
    for (const DatagramKey& key : c.datagrams)
      summary.datagrams.push_back({key.command, key.address, key.length, c.copies});
    summary.cycles = c.ticks;
    summary.cycle_ns = frame_capture_intervals_[c.id.slot].medianNs();
    out.push_back(std::move(summary));
  }
  return out;
}

void BusModel::startSegment(std::vector<BusEvent>& events) {
  earlier_intervals_.merge(intervals_);
  intervals_.clear();
  for (IntervalStats& stats : frame_intervals_) stats.clear();
  for (CyclicFrame& c : cyclic_) {
    // The axes' failure counts restart with the segment: the untold gap counts no lost cycle.
    if (c.pending_gap)
      judgeGap(c, std::nullopt, CycleGapEvent::Verdict::SegmentEnds, events, nullptr);
    c.last_tick.reset();
    c.awaiting_return = false;
    c.not_returned_episode = false;
  }
  for (WkcRecord& r : wkc_) r.wrong_episode = false;
}

void BusModel::finish(std::vector<BusEvent>& events, std::vector<AxisAccount>& accounts) {
  for (CyclicFrame& c : cyclic_) {
    if (c.pending_gap) {
      judgeGap(c, std::nullopt, CycleGapEvent::Verdict::CaptureEnds, events, &accounts);
    }
  }
}

std::optional<std::int64_t> BusModel::nominalCycleNs() const {
  if (intervals_.count() < kIntervalsBeforeGaps) return std::nullopt;
  return intervals_.medianNs();
}

IntervalStats BusModel::captureIntervals() const {
  IntervalStats all(earlier_intervals_);
  all.merge(intervals_);
  return all;
}

// Telegram accounting (docs/rules.md#com-002, COM-004; failures for COM-003, COM-005). The clock is
// the master's copy of each cyclic frame, or the returned copy in a capture without master copies.
bool BusModel::onCyclicFrame(const EcatFrame& frame, const FrameDecode& decode, const Stamp& now,
                             std::int64_t frame_time_ns, std::vector<BusEvent>& events,
                             std::vector<AxisAccount>& accounts) {
  now_ = now;
  frame_time_ns_ = frame_time_ns;
  frame_timing_ = FrameTiming{};
  frame_timing_.frame = now.frame;
  events_ = &events;
  accounts_ = &accounts;
  CyclicFrame* followed = cyclicFrame(frame, decode);
  if (followed == nullptr) return false;
  CyclicFrame& cyclic = *followed;
  ++cyclic.copies;
  servo_frames_seen_ = servo_frames_seen_ || decode.axis_count > 0;
  capture_clock_ = decode.axis_count > 0 || !servo_frames_seen_;
  const bool master = decode.copy == CopyKind::Master;
  if (master && !master_copies_seen_) {
    master_copies_seen_ = true;
    for (CyclicFrame& c : cyclic_) c.last_tick.reset();  // returned copies were the clock so far
  }
  returned_copies_seen_ = returned_copies_seen_ || !master;

  if (master) {
    // docs/rules.md#com-004: judged on the next master frame, once returned copies exist at all.
    if (cyclic.awaiting_return && returned_copies_seen_) {
      ++returned_copies_missing_;
      ++lost_cycles_;  // the frame went out and never came back: its cycle was lost
      if (!cyclic.not_returned_episode) {
        cyclic.not_returned_episode = true;
        NotReturnedEvent event;
        event.master_frame = cyclic.last_master.frame;
        if (!cyclic.axes.empty()) {
          event.axes = NotReturnedEvent::Axes{cyclic.axes.front(), cyclic.axes.back()};
        }
        if (!cyclic.datagrams.empty()) {
          const DatagramKey& named = cyclic.datagrams.front();
          event.command = named.command;
          event.address = named.address;
          event.length = named.length;
          event.datagrams = static_cast<std::uint16_t>(cyclic.datagrams.size());
        }
        events.push_back({cyclic.last_master, event});
      }
      for (std::uint16_t a : cyclic.axes) {
        accounts.push_back({a, Outcome::Lost, 1, cyclic.last_master, cyclic.last_master});
      }
    }
    cyclic.awaiting_return = true;
    cyclic.last_master = now_;
    // A cached shape carries the same axes as last time.
    if (decode.shape_id == 0 || decode.shape_id != cyclic.axes_shape_id) {
      cyclic.axes.clear();
      for (std::size_t i = 0; i < decode.axis_count; ++i)
        cyclic.axes.push_back(decode.axes[i].axis);
      cyclic.axes_shape_id = decode.shape_id;
    }
    tick(cyclic, decode, now_, false);
    return false;
  }
  if (!master_copies_seen_) {
    tick(cyclic, decode, now_, false);
  } else if (!cyclic.awaiting_return && cyclic.last_tick) {
    // Capture loss, not bus loss (docs/timing.md "Capture loss"): the returned copy proves its
    // cycle ran; its master copy left about one return latency before it.
    ++master_copies_missing_;
    Stamp sent = now_;
    sent.time_ns -= cyclic.last_latency_ns;
    tick(cyclic, decode, sent, true);
  }
  // A timestamp that went backwards gives no latency (docs/timing.md#rule-time).
  if (cyclic.awaiting_return && frame_time_ns_ >= now_.time_ns) {
    const std::int64_t latency = now_.time_ns - cyclic.last_master.time_ns;
    if (capture_clock_ && latencies_measured_) {
      timing_.onLatency(now_.frame, cyclic.last_master.frame, latency);
    }
    if (latencies_measured_) frame_timing_.latency_ns = latency;
    cyclic.last_latency_ns = latency;
    events.push_back(
        {cyclic.last_master, ReturnLatencyEvent{latency, cyclic.last_master.frame, cyclic.id}});
  }
  cyclic.awaiting_return = false;
  cyclic.not_returned_episode = false;
  return checkWorkingCounters(frame, decode);
}

// One tick of a cyclic frame's clock: the interval statistics, COM-002's gaps against the frame's
// own nominal cycle and the interval COM-006 judges.
void BusModel::tick(CyclicFrame& cyclic, const FrameDecode& decode, const Stamp& at,
                    bool estimated) {
  ++cyclic.ticks;
  // docs/timing.md#rule-time: a timestamp that went back is not an error; the interval it would
  // give is unknown, so the clock of this cyclic frame starts again at the next tick.
  const bool went_back = cyclic.last_tick && at.time_ns < cyclic.last_tick->time_ns;
  if (frame_time_ns_ < now_.time_ns || went_back) {
    cyclic.last_tick.reset();
    cyclic.last_tick_estimated = false;
    return;
  }
  const bool measured = !estimated && !cyclic.last_tick_estimated;
  cyclic.last_tick_estimated = estimated;
  if (!cyclic.last_tick) {
    cyclic.last_tick = at;
    return;
  }
  const std::int64_t interval = at.time_ns - cyclic.last_tick->time_ns;
  // docs/rules.md#com-002: a gap is told late or lost by the interval after it.
  if (cyclic.pending_gap) {
    judgeGap(cyclic, interval, CycleGapEvent::Verdict::Lost, *events_, accounts_);
  }
  IntervalStats& own = frame_intervals_[cyclic.id.slot];
  const std::optional<std::int64_t> median = own.medianNs();
  const bool nominal_known = own.count() >= kIntervalsBeforeGaps && median && *median > 0;
  if (nominal_known) {
    const bool gap = interval * kGapDenominator > *median * kGapNumerator;
    if (gap) {
      PendingGap pending{*cyclic.last_tick, interval, *median, at, {}};
      for (std::size_t i = 0; i < decode.axis_count; ++i)
        pending.axes.push_back(decode.axes[i].axis);
      // From 2.5 cycles on no next interval makes it late: its cycles are lost now, so that
      // COM-003 and COM-005 see them before the traffic that follows.
      const std::uint32_t missing = missingCycles(interval, *median);
      if (missing >= 2) {
        for (std::uint16_t axis : pending.axes)
          accounts_->push_back({axis, Outcome::Lost, missing, pending.since, at, true});
        pending.accounted = true;
      }
      cyclic.pending_gap = std::move(pending);
    }
    if (measured) {
      events_->push_back(
          {*cyclic.last_tick,
           CycleIntervalEvent{interval, *median, cyclic.last_tick->frame, cyclic.id, gap}});
    }
  }
  if (measured) {
    frame_timing_.interval_ns = interval;
    if (nominal_known) frame_timing_.deviation_ns = interval - *median;
    own.add(interval);
    frame_capture_intervals_[cyclic.id.slot].add(interval);
    if (capture_clock_) {
      intervals_.add(interval);
      timing_.onCycle(at.frame, cyclic.last_tick->frame, interval);
    }
  }
  cyclic.last_tick = at;
}

// docs/rules.md#com-002: late when the gap and the interval after it make about two cycles (nothing
// missing); otherwise round(gap ÷ nominal) − 1 cycles lost, as also when the next interval is
// not known. The finding lands on the tick that tells, one cycle after the gap.
void BusModel::judgeGap(CyclicFrame& cyclic, std::optional<std::int64_t> next,
                        CycleGapEvent::Verdict verdict, std::vector<BusEvent>& events,
                        std::vector<AxisAccount>* accounts) {
  const PendingGap& gap = *cyclic.pending_gap;
  CycleGapEvent e;
  e.verdict = verdict;
  e.interval_ns = gap.interval_ns;
  e.nominal_ns = gap.nominal_ns;
  e.next_interval_ns = next;
  e.previous_frame = gap.since.frame;
  e.next_frame = gap.end.frame;
  if (next && missingCycles(gap.interval_ns + *next, gap.nominal_ns) == 1) {
    e.verdict = CycleGapEvent::Verdict::Late;
  } else {
    e.missing = missingCycles(gap.interval_ns, gap.nominal_ns);
    lost_cycles_ += e.missing;
  }
  if (accounts != nullptr && !gap.accounted && e.missing > 0) {
    for (std::uint16_t axis : gap.axes) {
      accounts->push_back({axis, Outcome::Lost, e.missing, gap.since, gap.end, true});
    }
  }
  events.push_back({gap.since, e});
  cyclic.pending_gap.reset();
}

std::int16_t BusModel::wkcRecord(const Datagram& dg) {
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

// Which datagrams of this frame carry servo PDOs, and what the axes in each add to its WKC; the
// logical datagrams of other slaves only, judged against their usual WKC.
BusModel::WkcPlan& BusModel::wkcPlan(const EcatFrame& frame, const FrameDecode& decode) {
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
    if (carried[d].carries) {
      plan.checks.push_back(WkcCheck{static_cast<std::uint16_t>(d), carried[d].expected,
                                     carried[d].covered != frame.datagrams[d].length,
                                     kUnresolvedWkcRecord});
    } else if (ecat::isLogical(frame.datagrams[d].command)) {
      plan.checks.push_back(
          WkcCheck{static_cast<std::uint16_t>(d), 0, true, kUnresolvedWkcRecord, false});
    }
  }
  return plan;
}

// docs/rules.md#com-001 on each returned process-data datagram; each axis's cycle: lost (WKC 0),
// failed (another wrong WKC) or good.
bool BusModel::checkWorkingCounters(const EcatFrame& frame, const FrameDecode& decode) {
  WkcPlan& plan = wkcPlan(frame, decode);
  bool all_good = true;
  for (WkcCheck& check : plan.checks) {
    const Datagram& dg = frame.datagrams[check.datagram];
    check.outcome = Outcome::Good;
    if (!dg.has_wkc) {
      if (check.carries_axes && uncaptured_wkcs_++ == 0) first_uncaptured_wkc_frame_ = now_.frame;
      continue;
    }
    if (check.record == kUnresolvedWkcRecord) check.record = wkcRecord(dg);
    WkcRecord* record = check.record >= 0 ? &wkc_[static_cast<std::size_t>(check.record)] : nullptr;
    if (!check.carries_axes && record == nullptr) continue;  // no usual WKC to judge it by
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
      ++wkc_errors_;
      check.outcome = dg.wkc == 0 ? Outcome::Lost : Outcome::Failed;
      all_good = all_good && !check.carries_axes;
      if (record == nullptr || !record->wrong_episode) {
        if (record != nullptr) record->wrong_episode = true;
        events_->push_back(
            {now_, WorkingCounterEvent{dg.command, dg.address, dg.length, dg.wkc, expected}});
      }
    } else if (record != nullptr) {
      record->wrong_episode = false;
    }
  }
  if (all_good) return true;
  std::array<Outcome, ecat::kMaxDatagrams> outcomes{};
  for (const WkcCheck& check : plan.checks) outcomes[check.datagram] = check.outcome;
  const std::size_t count = std::min(frame.count, outcomes.size());
  for (std::size_t i = 0; i < decode.axis_count; ++i) {
    const AxisPlacement& p = decode.axes[i];
    Outcome outcome = Outcome::Good;
    if (p.rx_placed && p.rx_datagram < count) outcome = outcomes[p.rx_datagram];
    if (p.tx_placed && p.tx_datagram < count) outcome = std::max(outcome, outcomes[p.tx_datagram]);
    accounts_->push_back({p.axis, outcome, 1, now_, now_});
  }
  return false;
}

}  // namespace ncservo
