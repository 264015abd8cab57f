// The capture writer's input as the capturing PC makes it (docs/simulate.md#the-capturing-pc):
// each frame of the bus stamped by the PC's clock, written twice when a switch port mirrors it,
// and the office port's records between them by time. The bus's frames, their bytes and order
// are not changed; only what the PC adds to them is.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <utility>

#include "ncservo/sim/capture_shapes.hpp"
#include "ncservo/sim/options.hpp"

namespace ncservo::sim {

// The capture's interfaces: the bus's (Ethernet) and the office port's (Linux cooked).
inline constexpr std::uint32_t kBusInterface = 0;
inline constexpr std::uint32_t kOfficeInterface = 1;

class CaptureShaper {
 public:
  explicit CaptureShaper(const SimOptions& options);
  CaptureShaper(const CaptureShaper&) = delete;
  CaptureShaper& operator=(const CaptureShaper&) = delete;

  // Whether the options ask for any shape; without one the bus's frames are written as they are.
  bool active() const { return active_; }
  // A sink that writes into `written` what the PC records of each bus frame it is given; it
  // refers to this shaper, which must outlive it.
  FrameSink sink(FrameSink written);
  // The records written so far: the bus's frames, their copies and the office port's.
  std::uint64_t records() const { return records_; }

  // The truth names frames by their number on the bus (from 1); the capture's record numbers
  // (as validate and Wireshark count) differ once copies and office records are written. `track`
  // a bus frame number before it is written or within the last kRecent frames; `recordOf` gives
  // its own record's number (not its copy's), or nothing for a frame not tracked in time.
  void track(std::uint64_t bus_frame);
  std::optional<std::uint64_t> recordOf(std::uint64_t bus_frame) const;

 private:
  static constexpr std::size_t kRecent = 64;
  bool capture(const SimFrame& frame, const FrameSink& written);
  bool written(const SimFrame& frame, const FrameSink& sink);

  bool active_;
  bool duplicates_;
  CaptureClock clock_;
  std::optional<OfficePort> office_;
  std::uint64_t bus_frames_ = 0;
  std::uint64_t records_ = 0;
  std::deque<std::pair<std::uint64_t, std::uint64_t>> recent_;  // bus frame, record
  std::set<std::uint64_t> pending_;                             // tracked, not written yet
  std::map<std::uint64_t, std::uint64_t> tracked_;              // bus frame -> record
};

}  // namespace ncservo::sim
