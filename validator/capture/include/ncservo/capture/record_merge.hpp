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
  Result<bool> next(CaptureRecord& record);
  // The time of the capture's first record (frame 1), once read: what its seconds count from.
  const std::optional<std::int64_t>& origin() const { return origin_ns_; }

 private:
  struct Held {
    CaptureRecord record;
    std::vector<std::uint8_t> bytes;  // the record's, copied out of the reader's window
  };
  void hold(const CaptureRecord& record);
  // The position in order_ of the record to give now; order_.size() when none is due yet.
  std::size_t due() const;
  void give(std::size_t at, CaptureRecord& record);

  CaptureReader& reader_;
  MergeLimits limits_;
  bool merging_ = false;
  static constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::vector<Held> slots_;         // limits_.records + 1, reused
  std::vector<std::size_t> order_;  // the held slots, in file order
  std::vector<std::size_t> free_;   // the slots not held
  std::size_t given_ = kNone;       // the slot whose bytes the caller holds until the next call
  std::int64_t latest_ns_ = 0;      // the latest time read while merging (since a jump back)
  std::size_t barrier_ = 0;         // the first held records, read before a jump back, go first
  CaptureRecord read_;              // the record just read
  mutable std::vector<std::uint32_t> heads_;  // due()'s: the interfaces whose next it has seen
  std::optional<std::int64_t> origin_ns_;
  bool ended_ = false;
  Result<bool> end_ = false;  // how the reader ended: false, or its error
};

}  // namespace ncservo
