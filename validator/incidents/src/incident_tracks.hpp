// What the incident detector keeps of each axis and of the bus between frames, and what a cause
// row is given (causes.hpp). Every part is bounded (docs/incidents.md "Memory").
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/base/stamp.hpp"
#include "ncservo/incidents/incident.hpp"
#include "ncservo/model/axis_measurements.hpp"
#include "ncservo/model/bus_events.hpp"
#include "ncservo/rules/rules.hpp"

namespace ncservo {

// docs/incidents.md#overtemperature: the motor temperature rose by at least this much from the
// lowest reading of the minute before to the last one.
inline constexpr double kTemperatureRiseC = 10.0;

// How far the rows that look at what came just before a fault look back (docs/incidents.md).
inline constexpr std::int64_t kShortWindowNs = 100 * kMsNs;

// Failed cycles of an axis close together (docs/rules.md#com-003): a new failure within
// kFailureMergeNs of the last joins its run.
inline constexpr std::int64_t kFailureMergeNs = 10 * kMsNs;
struct FailureRun {
  Mark first, last;  // where the detector learnt of its first and last failures
  // The frames they are about (AxisAccount): the master copies that got no returned copy, the
  // returned copies with a wrong WKC; when `between`, only cycles of which nothing was captured,
  // lying between these two frames.
  Stamp first_frame, last_frame;
  bool between = false;
  std::uint64_t lost = 0;    // cycles lost or not returned
  std::uint64_t failed = 0;  // cycles returned with a wrong WKC
};

struct FindingMark {
  Mark at;
  RuleId rule{};
  std::string what;  // "COM-002 12 cycles lost ..."
};

// What the drive itself said (docs/incidents.md#the-drives-own-words): an emergency, or an entry
// of its error history (1003h), its last error code (603Fh) or error register (1001h) read.
struct DriveWordMark {
  Mark at;
  std::string what;  // "drive: emergency 0x8611 following error too large (...)"
};

// What the detector keeps of an axis beside its model's measurements (axis_measurements.hpp).
struct AxisTrack {
  Ring<FailureRun, 8> failures;
  Ring<FindingMark, 16> findings;
  Ring<DriveWordMark, 4> words;
  // The drive fault not yet recovered: its index in the detector's incidents.
  std::optional<std::size_t> open;

  void resetWindows() {
    failures.clear();
    findings.clear();
    words.clear();
  }
};

// "12 cycles lost (frames 3027-3038)": the axis's failure runs whose last failure lies within
// `window_ns` before `at`, each added to `evidence` where given (docs/incidents.md).
std::string lostCyclesText(const AxisTrack& axis, const Mark& at, std::int64_t window_ns,
                           std::vector<IncidentEvidence>* evidence);

// The first frame of the axis's failure runs whose last failure lies within `window_ns` before
// `at` (0: none).
std::uint64_t firstFailedFrame(const AxisTrack& axis, const Mark& at, std::int64_t window_ns);

// A link's counters rising at a read (EscErrorTracker; LNK-001, LNK-002), and where.
struct LinkMark {
  Mark at;
  LinkErrorEvent event;
  // Whether the rise covers failures from frame `first_failed` on: the read before it came
  // before them, this one after their start (docs/incidents.md#link-fault).
  bool covers(std::uint64_t first_failed) const {
    return event.previous_read_frame < first_failed && at.frame >= first_failed;
  }
};
// link-fault's text of a rise: "the link between ... port 1 and ... port 0: 5 RX errors at the
// read of frame 912 (since frame 400)", and its evidence.
std::string linkRiseText(const LinkMark& link);
IncidentEvidence linkRiseEvidence(const LinkMark& link);

// The reads that can still name a link: how long after a failure the counters may be read.
inline constexpr std::int64_t kLinkReadWaitNs = 10'000 * kMsNs;

struct BusTrack {
  Ring<FindingMark, 16> findings;  // about the bus, or a slave that is no axis
  Ring<LinkMark, 8> links;         // the last rises of the links' counters
};

// What a cause row is given: the incident's axis (none for the bus, or a slave that is no axis)
// with its model's measurements and the messages the drive gave before the incident, the bus,
// the SEW at the incident and where it is, the last AL status code read of its slave.
struct CauseContext {
  IncidentKind kind = IncidentKind::DriveFault;
  const AxisTrack* axis = nullptr;
  const AxisMeasurements* signals = nullptr;  // null where the axis has no model
  const MessageHistory* messages = nullptr;
  const BusTrack* bus = nullptr;
  std::uint32_t sew = 0;
  Mark at;
  std::string what;  // ESM: the state change, for an unknown cause's text
  std::optional<AlCodeMark> al_code;
};

}  // namespace ncservo
