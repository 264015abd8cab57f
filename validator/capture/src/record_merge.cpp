#include "ncservo/capture/record_merge.hpp"

#include <algorithm>

namespace ncservo {

RecordMerge::RecordMerge(CaptureReader& reader, MergeLimits limits)
    : reader_(reader), limits_(limits) {
  limits_.records = std::max<std::size_t>(limits_.records, 1);
}

Result<bool> RecordMerge::next(CaptureRecord& record) {
  if (given_ != kNone) {
    free_.push_back(given_);
    given_ = kNone;
  }
  if (!merging_) {
    Result<bool> read = reader_.next(record);
    if (read && *read && !origin_ns_) origin_ns_ = record.time_ns;
    if (!read || !*read || reader_.sectionInterfaces() < 2) return read;
    // The section's interfaces are described before its records: from its first record on,
    // every record is held until it is due.
    merging_ = true;
    latest_ns_ = record.time_ns;
    hold(record);
  }
  for (;;) {
    if (const std::size_t at = due(); at < order_.size()) {
      give(at, record);
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
    if (order_.empty() && reader_.sectionInterfaces() < 2) {
      merging_ = false;
      record = read_;
      return true;
    }
    // Further back than the look-ahead's window: not a record handed over late but a jump of the
    // capture (another recording appended, docs/cli.md "Appended or paused captures"). What is
    // held goes first, as the file has it, and the merge starts again from there.
    if (read_.time_ns < latest_ns_ - limits_.window_ns) {
      barrier_ = order_.size();
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
  order_.push_back(slot);
}

// Each interface's first held record is its next; the earliest of those is due once the look-ahead
// is full, a record as much later as the window was read, or the reading ended. A tie goes to the
// one first in the file.
std::size_t RecordMerge::due() const {
  if (order_.empty()) return kNone;
  heads_.clear();
  std::size_t best = kNone;
  // Before a jump back, only what was held before it, and at once.
  const std::size_t among = barrier_ > 0 ? barrier_ : order_.size();
  for (std::size_t i = 0; i < among; ++i) {
    const CaptureRecord& r = slots_[order_[i]].record;
    if (std::find(heads_.begin(), heads_.end(), r.interface) != heads_.end()) continue;
    heads_.push_back(r.interface);
    if (best == kNone || r.time_ns < slots_[order_[best]].record.time_ns) best = i;
  }
  const std::int64_t time_ns = slots_[order_[best]].record.time_ns;
  const bool full = order_.size() >= limits_.records;
  return barrier_ > 0 || ended_ || full || latest_ns_ - time_ns >= limits_.window_ns ? best : kNone;
}

void RecordMerge::give(std::size_t at, CaptureRecord& record) {
  const std::size_t slot = order_[at];
  order_.erase(order_.begin() + static_cast<std::ptrdiff_t>(at));
  if (barrier_ > 0) --barrier_;
  record = slots_[slot].record;
  given_ = slot;
}

}  // namespace ncservo
