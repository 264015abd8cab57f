// Everything one capture's run found, as every command and the plugin's summary report it: the
// layout and what was inferred of it, each axis's end state, the incidents, the bus's timing and
// DC, the segments, what was cut or not checked, and the capture's own clock. Made once a run
// ends (CapturePipeline::result()); the findings come frame by frame through the pipeline's
// sinks, since a stream of them must not be kept.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/incidents/incident.hpp"
#include "ncservo/layout/decoder.hpp"
#include "ncservo/layout/layout_inference.hpp"
#include "ncservo/layout/layout_window.hpp"
#include "ncservo/model/axis_model.hpp"
#include "ncservo/model/bus_model.hpp"
#include "ncservo/model/capture_clock.hpp"
#include "ncservo/model/capture_segments.hpp"
#include "ncservo/model/dc_clock.hpp"
#include "ncservo/model/timing.hpp"
#include "ncservo/pipeline/clock_stage.hpp"
#include "ncservo/rules/coverage.hpp"
#include "ncservo/rules/validator.hpp"
#include "ncservo/wire/frame_clock.hpp"

namespace ncservo {

// One axis at the end of a capture.
struct AxisSummary {
  std::uint16_t index = 0;
  std::string name;
  std::optional<DriveState> state;
  std::vector<StateChange> timeline;
  std::uint64_t timeline_omitted = 0;
  std::vector<ErrorHistoryEntry> error_history;
  std::uint32_t telegram_failures = 0;
  std::optional<int> ready_mode;
};

// What a capture's snap length (or damage) cut off: the records cut short, and the frames where
// placed PDO regions were cut short or lay outside their datagram, with those axes' names.
struct Truncation {
  std::uint64_t snapped = 0;
  std::uint64_t first_snapped = 0;
  std::uint64_t cut_frames = 0;
  std::uint64_t first_cut = 0;
  std::vector<std::string> axes;
  bool any() const { return snapped > 0 || cut_frames > 0; }
};
Truncation truncationOf(std::uint64_t snapped, std::uint64_t first_snapped, const CutRegions& cut,
                        const std::vector<AxisInfo>& axes);

// An axis's name in `layout` ("axis3" where it has none there).
std::string axisNameIn(const std::vector<AxisInfo>& layout, std::uint16_t axis);

// What one interface of the capture held (docs/cli.md#interfaces): its records, and whether any
// was an EtherCAT frame. `link_type` is its link type's number (1 Ethernet, 113 Linux cooked).
struct CaptureInterface {
  std::uint32_t id = 0;
  int link_type = 0;
  std::uint64_t frames = 0;
  bool ethercat = false;
};

struct CaptureResult {
  std::uint64_t frames = 0;  // records read, of any kind
  std::uint64_t cycles = 0;
  std::int64_t first_time_ns = 0;
  CycleTimeSummary cycle_time;
  LayoutSource layout_source = LayoutSource::None;
  std::vector<AxisInfo> layout;
  // When the layout was inferred: the evidence of each axis of `layout`, in the same order.
  std::vector<AxisEvidence> inferred;
  std::vector<AxisSummary> axes;
  Coverage coverage;  // whether every axis was checked
  TimestampSource timestamps = TimestampSource::Capture;
  ProbeCounts probe;
  std::string probe_note;  // FrameClock::note()
  // The clock that judged the capture and why (docs/timing.md#the-clock); the records dropped as
  // duplicates; frames the bus's clock could not time (its reads stopped).
  ClockChoice clock;
  CaptureDuplicates duplicates;
  std::uint64_t untimed_frames = 0;
  Truncation truncation;
  std::uint64_t startup_frames_cut = 0;  // layout from a start-up cut by the snap length
  LateLayout late_layout;                // inference went on looking after its first window
  // A configured or ENI layout whose data does not look like the protocol's PDOs, per axis.
  std::vector<std::string> layout_warnings;
  std::vector<CaptureSegment> segments;  // listed ones (SegmentTracker::kMaxListed)
  std::uint64_t segment_count = 0;
  TimingSummary timing;
  std::vector<CyclicDatagram> cyclic_datagrams;   // what the bus rules judged
  std::uint64_t unfollowed_frames = 0;            // beyond BusModel::kMaxCyclicFrames
  std::vector<CyclicFrameSummary> cyclic_frames;  // each with its own cycle
  std::uint64_t master_copies_missing = 0;        // from the capture; their cycles ran
  std::uint64_t returned_copies_missing = 0;      // never came back (COM-004)
  std::uint64_t lost_cycles = 0;                  // in gaps (COM-002), not returned (COM-004)
  std::uint64_t wkc_errors = 0;                   // returned datagrams with a wrong WKC
  std::vector<DcStation> dc;                      // distributed clocks (docs/timing.md)
  std::int64_t dc_settled_ns = 0;
  // What the drives said over their mailboxes and what the ESCs counted (docs/drive-messages.md):
  // each listed up to its tracker's bound, the rest counted.
  std::vector<DriveMessage> drive_messages;
  std::uint64_t drive_messages_omitted = 0;
  std::vector<MailboxNote> mailbox_notes;
  MailboxCounts mailbox_counts;
  std::vector<EscErrorDelta> esc_errors;
  std::vector<LinkFault> link_faults;
  std::uint64_t esc_errors_omitted = 0;
  std::vector<Incident> incidents;  // docs/incidents.md, in frame order
  std::uint64_t incidents_omitted = 0;
  // Each interface the records came from, by id (up to CapturePipeline::kMaxInterfaces), and the
  // records of further interfaces, not listed.
  std::vector<CaptureInterface> interfaces;
  std::uint64_t interface_records_omitted = 0;
};

// What the validator's models hold at the end of a run: the bus, the layout and each axis (the
// part of CapturePipeline::result() a bare validator gives).
void takeValidator(const Validator& validator, CaptureResult& result);

}  // namespace ncservo
