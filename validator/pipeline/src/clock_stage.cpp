#include "ncservo/pipeline/clock_stage.hpp"

#include <algorithm>
#include <cstring>
#include <utility>

namespace ncservo {

namespace {
// Records kept since the cycle began, to find their copies: more are not compared.
constexpr std::size_t kSinceCycle = 64;
// A read whose step differs from the stamps' by more than this restarts the bus clock there: the
// capture was paused, appended to another, or the reference clock was set anew.
constexpr std::int64_t kReanchorNs = 1'000'000'000;

// Which copy a frame of the cyclic frame is, by its working counters: none captured (a snap
// length cut them) says nothing.
ClockStage::Copy copyOf(const EcatFrame& frame) {
  if (frame.anyWkcAboveZero()) return ClockStage::Copy::Returned;
  for (std::size_t i = 0; i < frame.count; ++i) {
    if (frame.datagrams[i].has_wkc) return ClockStage::Copy::Master;
  }
  return ClockStage::Copy::None;
}

bool sameBytes(const std::vector<std::uint8_t>& kept, const ByteReader& bytes) {
  return kept.size() == bytes.size() &&
         (bytes.size() == 0 || std::memcmp(kept.data(), bytes.data(), bytes.size()) == 0);
}

void copyInto(std::vector<std::uint8_t>& into, const ByteReader& bytes) {
  into.assign(bytes.data(), bytes.data() + bytes.size());
}
}  // namespace

bool ClockStage::FrameKey::matches(const EcatFrame& frame) const {
  if (frame.count != datagrams.size()) return false;
  for (std::size_t i = 0; i < frame.count; ++i) {
    const Datagram& a = datagrams[i];
    const Datagram& b = frame.datagrams[i];
    if (a.command != b.command || a.length != b.length) return false;
    if (ecat::addressSurvivesRing(a.command) && a.address != b.address) return false;
  }
  return true;
}

const ClockChoice& ClockStage::choice() const {
  if (choice_) return *choice_;
  if (!capture_choice_) capture_choice_.emplace();
  return *capture_choice_;
}

bool ClockStage::isDuplicate(const EcatFrame& frame, const ByteReader& bytes) {
  if (cyclic_key_ && cyclic_key_->matches(frame)) {
    const Copy copy = copyOf(frame);
    if (copy == last_copy_ && sameBytes(last_copy_bytes_, bytes)) return true;
    last_copy_ = copy;
    copyInto(last_copy_bytes_, bytes);
    if (copy == Copy::Master) since_cycle_used_ = 0;
    return false;
  }
  for (std::size_t i = 0; i < since_cycle_used_; ++i) {
    if (sameBytes(since_cycle_[i], bytes)) return true;
  }
  if (since_cycle_used_ < kSinceCycle) {
    if (since_cycle_.size() <= since_cycle_used_) since_cycle_.emplace_back();
    copyInto(since_cycle_[since_cycle_used_++], bytes);
  }
  return false;
}

std::vector<std::uint8_t> ClockStage::spareBuffer() {
  if (spare_.empty()) return {};
  std::vector<std::uint8_t> buffer = std::move(spare_.back());
  spare_.pop_back();
  return buffer;
}

void ClockStage::hold(std::uint64_t number, std::int64_t time_ns, LinkType link,
                      const ByteReader& bytes, const EcatFrame& frame, bool judged,
                      bool duplicate) {
  Held held{number, time_ns, link, judged, duplicate, false, std::nullopt, spareBuffer()};
  copyInto(held.bytes, bytes);
  held_bytes_ += bytes.size();
  // The bus's clock: the reads of the reference clock in returned copies, and the master copies
  // that ask for them.
  const Copy copy = copyOf(frame);
  if (copy == Copy::Returned && reference_) {
    const std::optional<SystemTimeRead> read = systemTimeRead(frame, bytes);
    if (read && sameClock(*read, *reference_)) held.bus_ns = unwrap_.extend(*read);
  } else if (copy == Copy::Master) {
    held.clock_master = asksSystemTime(frame);
  }
  held_.push_back(std::move(held));
}

void ClockStage::onFrame(std::uint64_t number, std::int64_t time_ns, LinkType link,
                         const ByteReader& bytes, const EcatFrame& frame, bool judged,
                         bool probe_timed) {
  if (!choice_) {
    probe_timed_ = probe_timed_ || probe_timed;
    if (!cyclic_key_ && frame.mayCarryProcessData()) {
      cyclic_key_ = FrameKey{{frame.datagrams.begin(), frame.datagrams.begin() + frame.count}};
    }
    const bool duplicate = isDuplicate(frame, bytes);
    if (!duplicate && !reference_ && copyOf(frame) == Copy::Returned) {
      reference_ = systemTimeRead(frame, bytes);
    }
    hold(number, time_ns, link, bytes, frame, judged, duplicate);
    // Each copy of the cyclic frame with the last read of the reference clock since the one
    // before: a read every cycle, in that frame or another, pairs the bus's intervals with the
    // stamps' (a start-up's bursts of reads, before the first cyclic frame, do not).
    if (const std::optional<std::uint64_t> read = held_.back().bus_ns) {
      read_for_master_ = read_for_returned_ = read;
      cyclic_stamps_.addRead(time_ns, *read);
      returned_stamps_.addRead(time_ns, *read);
    }
    if (cyclic_key_ && cyclic_key_->matches(frame)) {
      ++copies_;
      duplicate_copies_ += duplicate ? 1 : 0;
      const Copy copy = copyOf(frame);
      if (!duplicate && copy == Copy::Master) {
        cyclic_stamps_.add(time_ns, std::exchange(read_for_master_, std::nullopt));
      } else if (!duplicate && copy == Copy::Returned) {
        returned_stamps_.add(time_ns, std::exchange(read_for_returned_, std::nullopt));
      }
    }
    const bool clean_early = cyclic_stamps_.samples() == StampAssessor::kEarlyCycles + 1 &&
                             cyclic_stamps_.stamps().clean();
    if (clean_early || cyclic_stamps_.enough() || returned_stamps_.enough() ||
        held_.size() >= kMaxHeldFrames || held_bytes_ >= kMaxHeldBytes) {
      decide();
    }
    return;
  }
  if (drop_duplicates_ && isDuplicate(frame, bytes)) {
    drop(number);
    return;
  }
  switch (choice_->source) {
    case ClockSource::Capture:
    case ClockSource::Probe:
      last_passed_ns_ = time_ns;
      sink_(number, time_ns, link, bytes, frame, judged);
      return;
    case ClockSource::Cycles:
      sink_(number, cycleTime(time_ns, frame), link, bytes, frame, judged);
      return;
    case ClockSource::Bus:
      hold(number, time_ns, link, bytes, frame, judged, false);
      onBusHeld();
      return;
  }
}

void ClockStage::drop(std::uint64_t number) {
  if (duplicates_.count++ == 0) duplicates_.first_frame = number;
  if (dropped_) dropped_(number);
}

void ClockStage::pass(const Held& held, std::int64_t time_ns) {
  const ByteReader bytes(held.bytes.data(), held.bytes.size());
  EcatFrame frame;
  walkPacket(held.link, bytes, frame);
  // On the bus's clock each frame is later than the one before, if only by a nanosecond: a
  // returned copy comes after its master copy, as a timer expiring at the read sees it.
  const bool bus = choice_ && choice_->source == ClockSource::Bus;
  last_passed_ns_ = std::max(last_passed_ns_ + (bus ? 1 : 0), time_ns);
  sink_(held.number, last_passed_ns_, held.link, bytes, frame, held.judged);
}

// Cycles: a master copy of the cyclic frame, or a returned copy whose master copy the capture
// missed, begins a cycle; before the first, frames keep their stamps.
std::int64_t ClockStage::cycleTime(std::int64_t capture_ns, const EcatFrame& frame) {
  const Copy copy = cyclic_key_ && cyclic_key_->matches(frame) ? copyOf(frame) : Copy::None;
  // A copy not told apart (its working counters not captured) begins no cycle.
  if (copy == Copy::Master || (copy == Copy::Returned && last_cycle_copy_ != Copy::Master)) {
    if (last_cycle_copy_ == Copy::None) cycles_anchor_ns_ = capture_ns;
    cycles_ += last_cycle_copy_ == Copy::None ? 0 : 1;
  }
  if (copy != Copy::None) last_cycle_copy_ = copy;
  if (last_cycle_copy_ == Copy::None) return capture_ns;
  return cycles_anchor_ns_ + static_cast<std::int64_t>(cycles_) * choice_->cycle_ns;
}

void ClockStage::decide() {
  // The cyclic frame's master copies, or its returned copies in a capture without master copies.
  const StampAssessor& cyclic =
      cyclic_stamps_.samples() >= StampAssessor::kFewest ? cyclic_stamps_ : returned_stamps_;
  choice_ = chooseClock(probe_timed_, cyclic, reference_);
  drop_duplicates_ = copies_ > 0 && duplicate_copies_ * 10 >= copies_;
  std::deque<Held> window = std::move(held_);
  held_.clear();
  held_bytes_ = 0;
  for (Held& held : window) {
    if (held.duplicate && drop_duplicates_) {
      drop(held.number);
      spare_.push_back(std::move(held.bytes));
      continue;
    }
    switch (choice_->source) {
      case ClockSource::Bus:
        held_.push_back(std::move(held));
        onBusHeld();
        continue;
      case ClockSource::Cycles: {
        const ByteReader bytes(held.bytes.data(), held.bytes.size());
        EcatFrame frame;
        walkPacket(held.link, bytes, frame);
        pass(held, cycleTime(held.capture_ns, frame));
        break;
      }
      case ClockSource::Capture:
      case ClockSource::Probe:
        pass(held, held.capture_ns);
        break;
    }
    spare_.push_back(std::move(held.bytes));
  }
  if (spare_.size() > kSinceCycle) spare_.resize(kSinceCycle);
}

void ClockStage::onBusHeld() {
  const Held& last = held_.back();
  const std::int64_t capture_ns = last.capture_ns;
  if (last.bus_ns) {
    std::int64_t read_time_ns;
    if (!bus_anchor_) {
      bus_anchor_ = *last.bus_ns;
      time_anchor_ns_ = capture_ns;
      read_time_ns = capture_ns;
    } else {
      const auto bus_step = static_cast<std::int64_t>(*last.bus_ns - *bus_anchor_);
      read_time_ns = time_anchor_ns_ + bus_step;
      const std::int64_t capture_step = capture_ns - last_read_capture_ns_;
      if (read_time_ns < last_read_time_ns_ ||
          std::abs((read_time_ns - last_read_time_ns_) - capture_step) > kReanchorNs) {
        read_time_ns = last_read_time_ns_ + capture_step;
        bus_anchor_ = *last.bus_ns;
        time_anchor_ns_ = read_time_ns;
      }
    }
    releasePending(read_time_ns, held_.size());
    return;
  }
  if (held_.size() > kMaxPending) {
    const std::size_t count = held_.size() / 2;
    untimed_ += count;
    releasePending(std::nullopt, count);
  }
}

void ClockStage::releasePending(std::optional<std::int64_t> read_time_ns, std::size_t count) {
  const bool first_read = read_time_ns && !read_seen_;
  // The reading frame's master copies take the read's time, evenly spread back to the last read
  // when the returned copies of some never came.
  std::vector<std::int64_t> master_times;
  if (read_time_ns) {
    std::size_t masters = 0;
    for (std::size_t i = 0; i < count; ++i) masters += held_[i].clock_master ? 1 : 0;
    for (std::size_t m = 1; m <= masters; ++m) {
      master_times.push_back(first_read || m == masters
                                 ? *read_time_ns
                                 : last_read_time_ns_ + (*read_time_ns - last_read_time_ns_) *
                                                            static_cast<std::int64_t>(m) /
                                                            static_cast<std::int64_t>(masters));
    }
  }
  std::int64_t base_ns = last_read_time_ns_;
  std::int64_t base_capture_ns = last_read_capture_ns_;
  std::size_t next_master = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const Held& held = held_[i];
    std::int64_t time_ns;
    if (!read_time_ns) {
      // No read to time it by: its stamp's offset from the last frame timed.
      time_ns = read_seen_ ? base_ns + std::max<std::int64_t>(held.capture_ns - base_capture_ns, 0)
                           : held.capture_ns;
      base_ns = std::max(base_ns, time_ns);
      base_capture_ns = std::max(base_capture_ns, held.capture_ns);
    } else if (held.clock_master) {
      time_ns = master_times[next_master++];
      base_ns = time_ns;
      base_capture_ns = held.capture_ns;
    } else if (first_read) {
      time_ns = std::min(held.capture_ns, *read_time_ns);
    } else {
      const std::int64_t limit =
          next_master < master_times.size() ? master_times[next_master] : *read_time_ns;
      time_ns = base_ns + std::clamp<std::int64_t>(held.capture_ns - base_capture_ns, 0,
                                                   std::max<std::int64_t>(limit - base_ns, 0));
    }
    pass(held, time_ns);
  }
  if (read_time_ns) {
    last_read_time_ns_ = *read_time_ns;
    last_read_capture_ns_ = held_[count - 1].capture_ns;
    read_seen_ = true;
  } else if (read_seen_) {
    last_read_time_ns_ = base_ns;
    last_read_capture_ns_ = base_capture_ns;
  }
  for (std::size_t i = 0; i < count; ++i) {
    if (spare_.size() < kSinceCycle) spare_.push_back(std::move(held_.front().bytes));
    held_.pop_front();
  }
}

void ClockStage::finish() {
  if (!choice_) decide();
  if (choice_->source == ClockSource::Bus && !held_.empty()) {
    releasePending(std::nullopt, held_.size());
  }
}

}  // namespace ncservo
