// Which clock times the frames (docs/cli.md, `--timestamps`): the capturing PC's, or an ESL
// probe's (docs/protocol.md §8), decided in one pass.
//
// A single pass cannot know in advance whether every EtherCAT frame carries a probe timestamp.
// `auto` decides on the first EtherCAT frame: with a probe timestamp, the probe times the capture;
// without one, the PC does, to the end. `probe` uses the probe's timestamps wherever there are
// any. While the probe times the capture, a frame without a probe timestamp is timed from the
// frame before it by the PC's clock (the timeline stays continuous, that one interval has the
// PC's noise); such frames are counted and the first is named (note()).
// Probe timestamps only mean something as differences: the first frame the probe times keeps its
// capture time, and the probe's intervals are counted from there.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "ncservo/wire/ethercat.hpp"

namespace ncservo {

enum class TimestampMode : std::uint8_t { Capture, Probe, Auto };
enum class TimestampSource : std::uint8_t { Capture, Probe };

std::optional<TimestampMode> timestampModeFromName(std::string_view name);
const char* timestampSourceName(TimestampSource source);  // "capture", "probe"
// The resolution of the timestamps that timed a capture: the probe's 1 ns, or the capture's own
// (`digits` of a second).
std::int64_t timestampResolutionNs(TimestampSource source, int digits);

// What the probe headers of a capture said.
struct ProbeCounts {
  std::uint64_t probed = 0;           // EtherCAT frames with an ESL header
  std::uint64_t stamped = 0;          // ... whose timestamp is valid
  std::uint64_t unstamped = 0;        // frames timed by the PC while the probe timed the capture
  std::uint64_t first_unstamped = 0;  // its first frame number (0: none)
  std::uint64_t crc_errors = 0;       // bus faults (docs/protocol.md §8)
  std::uint64_t first_crc_error = 0;
  std::uint64_t alignment_errors = 0;
};

class FrameClock {
 public:
  explicit FrameClock(TimestampMode mode) : mode_(mode) {}

  // The time of an EtherCAT frame (walked: any status but NotEtherCat), in nanoseconds on the
  // capture clock's epoch.
  std::int64_t time(std::uint64_t frame_number, std::int64_t capture_ns, const ProbeHeader& probe);

  // What timed the frames: the probe once it timed any.
  TimestampSource source() const {
    return anchor_ ? TimestampSource::Probe : TimestampSource::Capture;
  }
  const ProbeCounts& counts() const { return counts_; }
  // What a report should say beyond the source: frames the probe did not time, probe timestamps
  // left unused, bus faults; empty when there is nothing to say.
  std::string note() const;

 private:
  struct Anchor {
    std::int64_t time_ns;
    std::uint64_t probe_ns;
  };
  TimestampMode mode_;
  std::optional<bool> probe_timed_;  // decided on the first EtherCAT frame
  std::optional<Anchor> anchor_;     // the last frame the probe timed
  std::int64_t last_time_ns_ = 0;
  std::int64_t last_capture_ns_ = 0;
  ProbeCounts counts_;
};

}  // namespace ncservo
