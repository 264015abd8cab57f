#include "ncservo/model/capture_segments.hpp"

#include <algorithm>

namespace ncservo {

Discontinuity discontinuity(std::int64_t latest_ns, std::int64_t time_ns,
                            std::optional<std::int64_t> nominal_cycle_ns, std::int64_t pause_ns) {
  const std::int64_t back_limit = nominal_cycle_ns ? *nominal_cycle_ns : kBackJumpFloorNs;
  if (latest_ns - time_ns > back_limit) return Discontinuity::Back;
  if (time_ns - latest_ns > pause_ns) return Discontinuity::Forward;
  return Discontinuity::None;
}

bool SegmentTracker::onFrame(std::uint64_t frame, std::int64_t time_ns,
                             std::optional<std::int64_t> nominal_cycle_ns) {
  const bool starts = count_ == 0 || discontinuity(latest_ns_, time_ns, nominal_cycle_ns,
                                                   pause_ns_) != Discontinuity::None;
  if (starts) {
    latest_ns_ = time_ns;
    if (segments_.size() < kMaxListed) segments_.push_back({frame, frame, time_ns, time_ns});
    ++count_;
    return count_ > 1;
  }
  latest_ns_ = std::max(latest_ns_, time_ns);
  if (count_ <= kMaxListed) {
    segments_.back().last_frame = frame;
    segments_.back().end_ns = latest_ns_;
  }
  return false;
}

}  // namespace ncservo
