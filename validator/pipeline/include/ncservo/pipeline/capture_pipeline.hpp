// A capture read frame by frame, the one way every command and the plugin's first pass read it:
// each record walked (docs/protocol.md §8) and timed by the frame clock (the probe's or the
// PC's); held in the learning window until the layout is known (docs/layout.md), then delivered
// in capture order, the window's frames first; judged by the validator, frame by frame; and at
// the end, what only the frames that did not come could tell (docs/rules.md#com-002). Frames
// that are not EtherCAT, carry no datagrams or are a probe's bus faults are timed but not
// delivered.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/base/error.hpp"
#include "ncservo/base/wall_time.hpp"
#include "ncservo/incidents/incident_detector.hpp"
#include "ncservo/layout/decoder.hpp"
#include "ncservo/layout/eni.hpp"
#include "ncservo/layout/layout_fit.hpp"
#include "ncservo/layout/layout_window.hpp"
#include "ncservo/model/bus_model.hpp"
#include "ncservo/pipeline/capture_result.hpp"
#include "ncservo/pipeline/clock_stage.hpp"
#include "ncservo/rules/finding.hpp"
#include "ncservo/rules/rules.hpp"
#include "ncservo/rules/validator.hpp"
#include "ncservo/wire/capture_record.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "ncservo/wire/frame_clock.hpp"

namespace ncservo {

// `--from TIME --to TIME` (docs/cli.md#time-window): the frames whose time lies in [from, to].
// A bound is seconds since the capture's first record (as Wireshark's frame.time_relative), or
// an ISO 8601 time of day (then `absolute`: nanoseconds since the epoch). The frames outside are
// neither decoded for their values nor judged: the capture seen starts mid-operation at `from`.
// They still show the layout (a start-up before the window, the learning window's cyclic
// traffic): the pipeline gives them to `Sinks::layout_only`.
struct TimeWindow {
  std::optional<std::int64_t> from_ns, to_ns;
  bool from_absolute = false, to_absolute = false;
  // `relative_ns` since the first record, whose own time is `first_ns`.
  bool contains(std::int64_t relative_ns, std::int64_t first_ns) const {
    const std::int64_t absolute_ns = relative_ns + first_ns;
    return (!from_ns || (from_absolute ? absolute_ns : relative_ns) >= *from_ns) &&
           (!to_ns || (to_absolute ? absolute_ns : relative_ns) <= *to_ns);
  }
  bool limited() const { return from_ns || to_ns; }
};
// The window of `--from`/`--to`, each seconds or an ISO 8601 time (without an offset, in `zone`);
// fails when either is neither, or when `to` is before `from` (both of one kind).
Result<TimeWindow> timeWindowOf(const std::optional<std::string>& from,
                                const std::optional<std::string>& to, TimeZone zone);
// "--from 1.5 --to 2", "--from 1.5", for messages.
std::string describeTimeWindow(const TimeWindow& window);

// An ENI whose tasks' cycle times the capture does not bear out (docs/layout.md#eni-cycle-times):
// one line per cyclic frame of the ENI whose frame in the capture (one sharing a command, address
// and length) repeats at a cycle more than a tenth off its task's <CycleTime>.
std::vector<std::string> eniCycleWarnings(const std::vector<EniCyclicFrame>& eni,
                                          const std::vector<CyclicFrameSummary>& seen);

struct CaptureRun {
  std::uint64_t records = 0;                  // read, of any kind
  std::optional<std::int64_t> first_time_ns;  // of the first record
  std::uint64_t in_window = 0;                // EtherCAT frames inside the time window
  std::uint64_t ethercat = 0;                 // EtherCAT frames, in the window or not
  std::uint64_t snapped = 0;                  // records cut by the capture's snap length
  std::uint64_t first_snapped = 0;            // the first of them (0: none)
};

// Why nothing was judged although the capture had frames: none in the time window; empty when
// there were.
std::string emptyWindowReason(const TimeWindow& window, const CaptureRun& run);
// Why nothing was judged when the capture holds no EtherCAT frame at all (an empty file, a
// loopback capture): no layout would help; empty when it holds one.
std::string noEtherCatReason(const CaptureRun& run);

struct PipelineOptions {
  DecoderOptions layout;
  // The validator's settings: each delivered frame is judged. None: the frames are only
  // delivered (decode's rows decode them themselves).
  std::optional<RuleSettings> rules;
  TimeWindow window;
  TimestampMode timestamps = TimestampMode::Auto;
};

// One delivered frame: walked over `bytes`, with its 1-based number and capture time.
struct PipelineFrame {
  std::uint64_t number;
  std::int64_t time_ns;
  const EcatFrame& frame;
  const ByteReader& bytes;
  const Observation* judged;  // the validator's placements and states; null without rules
};

// A record walk() found an EtherCAT frame of process data in: its time by the frame clock, and
// whether it lies inside the time window.
struct WalkedRecord {
  std::int64_t time_ns;
  bool judged;
  bool probe_timed;  // by the probe's clock
};

class CapturePipeline {
 public:
  struct Sinks {
    // Once, with the layout decided, before the first frame is delivered; validator() is there.
    std::function<void(const DecoderOptions& layout)> start;
    // A frame inside the time window, after the validator judged it.
    std::function<void(const PipelineFrame& frame)> frame;
    // A frame outside it, after the validator took what it shows of the layout (may be null).
    std::function<void(const PipelineFrame& frame)> layout_only;
    // The findings the validator reported on a frame, after `frame`, and at the end of the
    // capture (may be null).
    std::function<void(const std::vector<Finding>& findings)> findings;
    // A record dropped as a duplicate of one within its cycle (docs/cli.md#duplicates; may be
    // null).
    std::function<void(std::uint64_t number)> duplicate;
  };

  explicit CapturePipeline(PipelineOptions options, WindowLimits limits = {});
  CapturePipeline(const CapturePipeline&) = delete;
  CapturePipeline& operator=(const CapturePipeline&) = delete;

  // Given before the first record or frame.
  void setSinks(Sinks sinks) { sinks_ = std::move(sinks); }

  // One record as read: walked from its own link type, timed, held in the learning window or
  // delivered. The same as walk(), then onWalkedFrame over the record's bytes when it returned a
  // frame.
  void onRecord(const CaptureRecord& record);
  // onRecord's first half, which a reading thread runs ahead of the rest (docs/cli.md#two-threads):
  // the record counted in run() and under its interface, walked into `frame` and timed by clock().
  // None when the frame goes no further (not EtherCAT, not process data, a probe's bus fault, a
  // link type the walker does not know). The two halves share no state but run().first_time_ns,
  // set by the first record (or setTimeOrigin), before any frame is delivered.
  std::optional<WalkedRecord> walk(const CaptureRecord& record, EcatFrame& frame);
  // The time of the capture's frame 1, when the records come merged by time (record_merge.hpp)
  // and another came first: the capture's own seconds count from frame 1, as Wireshark's
  // frame.time_relative. Given before that first record.
  void setTimeOrigin(std::int64_t time_ns) { run_.first_time_ns = time_ns; }
  // One frame already walked over `bytes` (any status but NotEtherCat, NotDatagrams and
  // BusFault) and timed, as the plugin's first pass sees it: timed on the capture's clock
  // (docs/timing.md#the-clock), then held or delivered. `judged`: inside the time window;
  // `probe_timed`: `time_ns` is the probe's.
  void onWalkedFrame(std::uint64_t number, std::int64_t time_ns, LinkType link,
                     const ByteReader& bytes, const EcatFrame& frame, bool judged = true,
                     bool probe_timed = false);
  // A face that shows each frame as it comes (the plugin's single pass) has the frames held back
  // judged at once, for the findings whose rules read no process data (standsWithoutLayout):
  // by a validator of the layout known so far, dropped once frames are delivered
  // (docs/layout.md). Given before the first frame.
  void judgeHeldFrames() { judge_held_ = true; }
  // That validator while the last frame given was held (its findings are that frame's), else null.
  const Validator* heldJudge() const { return held_judge_ ? &*held_judge_ : nullptr; }
  // The frames ended while learning: the window decides with what it held and delivers it.
  void endLearning();
  // The capture ended: endLearning, then the validator's end-of-capture judgement, whose
  // findings go to `Sinks::findings`. `start` has been called even for a capture with no frame.
  void finish();

  // Frames are still held back: while the capture's stamps are judged, or in the learning
  // window.
  bool learning() const { return clock_stage_.assessing() || window_.learning(); }
  // The layout decided and what the inference found, once no longer learning.
  const DecoderOptions& layout() const { return window_.options(); }
  const std::optional<InferenceResult>& inference() const { return window_.inference(); }
  // Whether `axis` of the layout was inferred from the PDO structure alone, no handshake
  // confirming it (docs/layout.md): what every view of its findings says.
  bool structureOnly(std::uint16_t axis) const;
  // An ENI's cyclic frames, whose tasks' cycle times the capture is held against at the end
  // (docs/layout.md#eni-cycle-times); their warnings join layoutWarnings().
  void holdEniCycles(std::vector<EniCyclicFrame> frames) { eni_frames_ = std::move(frames); }
  // A configured or ENI layout whose data does not look like the protocol's PDOs: one line per
  // axis (docs/layout.md#a-layout-that-does-not-fit); then one per ENI frame whose cycle the
  // capture does not bear out; after finish().
  const std::vector<std::string>& layoutWarnings() const { return layout_warnings_; }
  // The configured or ENI layout's misfits of the frames so far, as layoutWarnings() has them:
  // for a view with no end of capture (the plugin's later passes).
  std::vector<std::string> layoutMisfitsSoFar() const;
  // Whether the layout was inferred after the first window, and the frames not judged then.
  const LateLayout& lateLayout() const { return window_.late(); }
  // Null until the layout is decided, and without rules.
  const Validator* validator() const { return validator_ ? &*validator_ : nullptr; }
  // The incidents found so far (docs/incidents.md); null as validator().
  const IncidentDetector* incidents() const { return incidents_ ? &*incidents_ : nullptr; }
  const FrameClock& clock() const { return clock_; }
  // The clock that judges the capture, and the duplicates dropped (docs/timing.md#the-clock).
  const ClockStage& clockStage() const { return clock_stage_; }
  const CaptureRun& run() const { return run_; }
  // The most interfaces counted one by one in result() (a pcapng may describe any number).
  static constexpr std::size_t kMaxInterfaces = 64;
  const TimeWindow& timeWindow() const { return time_window_; }
  // What the run found, for every report of it; after finish(), or at any point after the
  // layout was decided for what was found so far.
  CaptureResult result() const;

 private:
  void decided();
  // A frame timed on the capture's clock: held in the learning window or delivered.
  void route(std::uint64_t number, std::int64_t time_ns, LinkType link, const ByteReader& bytes,
             const EcatFrame& frame, bool judged);
  void started();
  void deliver(std::uint64_t number, std::int64_t time_ns, const EcatFrame& frame,
               const ByteReader& bytes);
  void deliverLayoutOnly(std::uint64_t number, std::int64_t time_ns, const EcatFrame& frame,
                         const ByteReader& bytes);
  // The count of the record's interface, found or added (then the last one); null past
  // kMaxInterfaces (its records are counted as omitted).
  CaptureInterface* interfaceOf(const CaptureRecord& record);

  std::optional<RuleSettings> rules_;
  TimeWindow time_window_;
  FrameClock clock_;
  ClockStage clock_stage_;
  bool clock_told_ = false;  // the validator knows which clock times it
  LayoutWindow window_;
  std::optional<Validator> validator_;
  bool judge_held_ = false;
  std::optional<Validator> held_judge_;        // while frames are held, with judge_held_
  std::optional<IncidentDetector> incidents_;  // beside the validator
  std::optional<LayoutFit> fit_;               // a configured or ENI layout, judged
  std::vector<EniCyclicFrame> eni_frames_;
  std::vector<std::string> layout_warnings_;
  Sinks sinks_;
  bool started_ = false;
  CaptureRun run_;
  EcatFrame frame_;                             // the record being walked
  std::vector<CaptureInterface> interfaces_;    // in the order first seen
  CaptureInterface* last_interface_ = nullptr;  // the last record's, in interfaces_
  std::uint64_t interface_records_omitted_ = 0;
};

}  // namespace ncservo
