#include "ncservo/capture/record_merge.hpp"

#include <algorithm>
#include <tuple>

namespace ncservo {

RecordMerge::RecordMerge(CaptureReader& reader, MergeLimits limits)
    : reader_(reader), limits_(limits) {
  limits_.records = std::max<std::size_t>(limits_.records, 1);
}

void RecordMerge::start(Result<bool>& read, CaptureRecord& record) {
  if (!origin_ns_) origin_ns_ = record.time_ns;
  if (reader_.sectionInterfaces() < 2) return;
  // The section's interfaces are described before its records: from its first record on, every
  // record is held until it is due.
  merging_ = true;
  latest_ns_ = record.time_ns;
  hold(record);
  read = nextMerged(record);
}

Result<bool> RecordMerge::nextMerged(CaptureRecord& record) {
  if (given_ != kNone) {
    free_.push_back(given_);
    given_ = kNone;
  }
  for (;;) {
    if (const std::size_t lane = due(); lane != kNone) {
      give(lanes_[lane], record);
      return true;
    }
    if (ended_) return end_;
    Result<bool> read = reader_.next(read_);
    if (!read || !*read) {
      ended_ = true;
      end_ = std::move(read);
      continue;
    }
    // A later section of one interface: nothing left to merge with.
    if (held_ == 0 && reader_.sectionInterfaces() < 2) {
      merging_ = false;
      record = read_;
      return true;
    }
    // Further back than the look-ahead's window: not a record handed over late but a jump of the
    // capture (another recording appended, docs/cli.md "Appended or paused captures"). What is
    // held goes first, merged as before, and the merge starts again from there.
    if (read_.time_ns < latest_ns_ - limits_.window_ns) {
      ++era_;
      latest_ns_ = read_.time_ns;
    }
    latest_ns_ = std::max(latest_ns_, read_.time_ns);
    hold(read_);
  }
}

void RecordMerge::hold(const CaptureRecord& record) {
  if (free_.empty()) {
    free_.push_back(slots_.size());
    slots_.emplace_back();
  }
  const std::size_t slot = free_.back();
  free_.pop_back();
  Held& held = slots_[slot];
  held.record = record;
  held.bytes.assign(record.data, record.data + record.captured);
  held.record.data = held.bytes.data();
  held.era = era_;
  held.read = reads_++;
  laneOf(record.interface).slots.push_back(slot);
  ++held_;
}

RecordMerge::Lane& RecordMerge::laneOf(std::uint32_t interface) {
  Lane* idle = nullptr;
  for (Lane& lane : lanes_) {
    if (lane.interface == interface) return lane;
    if (idle == nullptr && lane.empty()) idle = &lane;
  }
  // An empty lane is taken over once there are as many as records may be held: a capture of
  // many interfaces does not grow them without bound.
  if (idle != nullptr && lanes_.size() >= limits_.records) {
    idle->interface = interface;
    return *idle;
  }
  lanes_.push_back({.interface = interface, .slots = {}, .front = 0});
  return lanes_.back();
}

// Each interface's first held record is its next; the earliest of those goes first (those read
// before a jump back before all others, a tie to the one first in the file), once the look-ahead
// is full, a record as much later as the window was read, or the reading ended.
std::size_t RecordMerge::due() const {
  std::size_t best = kNone;
  const Held* first = nullptr;
  for (std::size_t i = 0; i < lanes_.size(); ++i) {
    const Lane& lane = lanes_[i];
    if (lane.empty()) continue;
    const Held& next = slots_[lane.slots[lane.front]];
    if (first == nullptr || std::tie(next.era, next.record.time_ns, next.read) <
                                std::tie(first->era, first->record.time_ns, first->read)) {
      best = i;
      first = &next;
    }
  }
  if (first == nullptr) return kNone;
  const bool full = held_ >= limits_.records;
  const bool before_jump = first->era < era_;
  return before_jump || ended_ || full || latest_ns_ - first->record.time_ns >= limits_.window_ns
             ? best
             : kNone;
}

void RecordMerge::give(Lane& lane, CaptureRecord& record) {
  const std::size_t slot = lane.slots[lane.front++];
  // Given ones are dropped from the lane's front now and then, so it stays small.
  if (lane.empty()) {
    lane.slots.clear();
    lane.front = 0;
  } else if (lane.front >= limits_.records) {
    lane.slots.erase(lane.slots.begin(),
                     lane.slots.begin() + static_cast<std::ptrdiff_t>(lane.front));
    lane.front = 0;
  }
  --held_;
  record = slots_[slot].record;
  given_ = slot;
}

}  // namespace ncservo
