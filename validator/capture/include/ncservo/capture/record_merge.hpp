// A capture's records with those of its interfaces merged by time (docs/cli.md#interfaces): the
// two ports of a TAP, one direction each, are written by dumpcap in the order its threads hand
// them over, not always in the order they were seen, and a cycle's master copy must come before
// its returned copy for the two to pair (docs/protocol.md §8). Each interface's records keep
// their file order among themselves; across interfaces the earliest comes first, within a bounded
// look-ahead. A record further back than the look-ahead's window is a jump of the capture
// (docs/cli.md "Appended or paused captures"), never merged across. A section of one interface (the
// common case) goes straight through, its records read in place.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/wire/capture_record.hpp"

namespace ncservo {

// How far ahead the merge looks: a record is held until a record this much later was read, or
// until this many are held; a record may overtake only those less than the window after it.
// Memory stays bounded by the count (each held record is a copy).
struct MergeLimits {
  std::size_t records = 64;
  std::int64_t window_ns = 5'000'000;
};

class RecordMerge {
 public:
  explicit RecordMerge(CaptureReader& reader, MergeLimits limits = {});

  // As CaptureReader::next: the next record by time, its bytes valid until the next call; false
  // at the end; a read error once every record before it was given. Frame numbers stay the
  // file's (as Wireshark numbers frames), so they may go back where interfaces were merged.
  // Inline, one result returned from every path: a section of one interface costs a record a
  // few instructions over the reader's own (docs/benchmarks.md "Reading captures").
  Result<bool> next(CaptureRecord& record) {
    const bool merging = merging_;
    Result<bool> read = merging ? nextMerged(record) : reader_.next(record);
    if (!merging && read && *read && (!origin_ns_ || reader_.sectionInterfaces() > 1)) {
      start(read, record);
    }
    return read;
  }
  // The time of the capture's first record (frame 1), once read: what its seconds count from.
  const std::optional<std::int64_t>& origin() const { return origin_ns_; }

 private:
  struct Held {
    CaptureRecord record;
    std::vector<std::uint8_t> bytes;  // the record's, copied out of the reader's window
    std::uint64_t era = 0;            // jumps back read before it
    std::uint64_t read = 0;           // its place in the file's order
  };
  // One interface's held records, in file order: slots[front..] (the front ones given).
  struct Lane {
    std::uint32_t interface = 0;
    std::vector<std::size_t> slots;
    std::size_t front = 0;
    bool empty() const { return front == slots.size(); }
  };
  // The capture's first record, or the first of a section of several interfaces (then held, and
  // `read` and `record` become the merge's first).
  void start(Result<bool>& read, CaptureRecord& record);
  Result<bool> nextMerged(CaptureRecord& record);
  void hold(const CaptureRecord& record);
  Lane& laneOf(std::uint32_t interface);
  // The lane whose next record is to be given now; kNone when none is due yet.
  std::size_t due() const;
  void give(Lane& lane, CaptureRecord& record);

  CaptureReader& reader_;
  MergeLimits limits_;
  bool merging_ = false;
  static constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::vector<Held> slots_;        // reused; at most limits_.records held and one given
  std::vector<std::size_t> free_;  // the slots not held
  std::vector<Lane> lanes_;        // by interface, kept while empty (few)
  std::size_t held_ = 0;
  std::size_t given_ = kNone;   // the slot whose bytes the caller holds until the next call
  std::int64_t latest_ns_ = 0;  // the latest time read while merging (since a jump back)
  std::uint64_t era_ = 0;       // jumps back so far
  std::uint64_t reads_ = 0;
  CaptureRecord read_;  // the record just read
  std::optional<std::int64_t> origin_ns_;
  bool ended_ = false;
  Result<bool> end_ = false;  // how the reader ended: false, or its error
};

}  // namespace ncservo
