// Discontinuities of a capture (docs/protocol.md §8, docs/cli.md): two recordings appended (the
// timestamps jump back) or a paused one (they jump forward by seconds or hours). Each part is a
// segment; nothing measured across a boundary means anything, so the timers restart there.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace ncservo {

// Frames and times are the frames' own (capture clock, absolute nanoseconds).
struct CaptureSegment {
  std::uint64_t first_frame = 0;
  std::uint64_t last_frame = 0;
  std::int64_t start_ns = 0;  // the first frame's time
  std::int64_t end_ns = 0;    // the latest time seen in the segment
};

enum class Discontinuity : std::uint8_t { None, Back, Forward };

// A jump back is more than a cycle; before the segment knows its nominal cycle, more than this
// floor (a millisecond: above any capture's reordering, below the restart of a recording).
inline constexpr std::int64_t kBackJumpFloorNs = 1'000'000;

// Whether a frame at `time_ns` breaks a segment whose latest time is `latest_ns`.
Discontinuity discontinuity(std::int64_t latest_ns, std::int64_t time_ns,
                            std::optional<std::int64_t> nominal_cycle_ns, std::int64_t pause_ns);

class SegmentTracker {
 public:
  // Segments listed; later ones are counted (their timers restart all the same).
  static constexpr std::size_t kMaxListed = 1000;

  explicit SegmentTracker(std::int64_t pause_ns) : pause_ns_(pause_ns) {}

  // One frame in capture order. True when it starts a new segment (never the first frame).
  bool onFrame(std::uint64_t frame, std::int64_t time_ns,
               std::optional<std::int64_t> nominal_cycle_ns);
  // The segment's clock: its latest time, so small back-steps do not move timers back.
  std::int64_t now() const { return latest_ns_; }

  const std::vector<CaptureSegment>& segments() const { return segments_; }
  // All segments, listed or not.
  std::uint64_t count() const { return count_; }

 private:
  std::int64_t pause_ns_;
  std::int64_t latest_ns_ = 0;
  std::uint64_t count_ = 0;
  std::vector<CaptureSegment> segments_;
};

}  // namespace ncservo
