// The capturing PC between the simulated bus and the capture writer (capture_shaper.hpp,
// docs/simulate.md#the-capturing-pc).
#include "capture_shaper.hpp"

#include <algorithm>

namespace ncservo::sim {

CaptureShaper::CaptureShaper(const SimOptions& o)
    : active_(o.capture_stamps.shape != StampShape::Exact || o.duplicate_records ||
              o.second_interface),
      duplicates_(o.duplicate_records),
      clock_(o.capture_stamps, o.seed) {
  if (o.second_interface) office_.emplace(o.seed);
}

bool CaptureShaper::written(const SimFrame& frame, const FrameSink& sink) {
  if (!sink(frame)) return false;
  ++records_;
  return true;
}

bool CaptureShaper::capture(const SimFrame& frame, const FrameSink& sink) {
  const std::int64_t stamp = clock_.stamp(frame.time_ns);
  if (office_) {  // the office port's records up to this one, interleaved by time
    if (!office_->started()) office_->start(stamp);
    while (office_->nextAt() <= stamp) {
      const std::vector<std::uint8_t>& bytes = office_->nextBytes();
      if (!written(SimFrame{.time_ns = office_->nextAt(),
                            .data = bytes.data(),
                            .size = bytes.size(),
                            .returned = false,
                            .interface_id = kOfficeInterface},
                   sink)) {
        return false;
      }
      office_->advance();
    }
  }
  SimFrame shaped = frame;
  shaped.time_ns = stamp;
  if (!written(shaped, sink)) return false;
  ++bus_frames_;
  recent_.emplace_back(bus_frames_, records_);
  if (recent_.size() > kRecent) recent_.pop_front();
  if (pending_.erase(bus_frames_) != 0) tracked_[bus_frames_] = records_;
  if (duplicates_) {  // the mirrored copy, byte for byte, right after it
    shaped.time_ns = clock_.duplicate(stamp);
    if (!written(shaped, sink)) return false;
  }
  return true;
}

FrameSink CaptureShaper::sink(FrameSink written) {
  return [this, written = std::move(written)](const SimFrame& frame) {
    return capture(frame, written);
  };
}

void CaptureShaper::track(std::uint64_t bus_frame) {
  if (!active_) return;
  if (bus_frame > bus_frames_) {
    pending_.insert(bus_frame);
    return;
  }
  const auto seen = std::find_if(recent_.begin(), recent_.end(),
                                 [&](const auto& entry) { return entry.first == bus_frame; });
  if (seen != recent_.end()) tracked_[bus_frame] = seen->second;
}

std::optional<std::uint64_t> CaptureShaper::recordOf(std::uint64_t bus_frame) const {
  if (!active_) return bus_frame;
  const auto found = tracked_.find(bus_frame);
  if (found == tracked_.end()) return std::nullopt;
  return found->second;
}

}  // namespace ncservo::sim
