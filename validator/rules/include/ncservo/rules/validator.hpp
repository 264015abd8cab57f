// One capture through the model and the rules: frames in, findings out, one pass in capture
// order (docs/timing.md#rule-time). Shared by the CLI (`validate`) and the plugin (expert info).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/layout/session.hpp"
#include "ncservo/model/al_tracker.hpp"
#include "ncservo/model/axis_model.hpp"
#include "ncservo/model/bus_model.hpp"
#include "ncservo/model/capture_segments.hpp"
#include "ncservo/model/dc_clock.hpp"
#include "ncservo/model/esc_errors.hpp"
#include "ncservo/model/mailbox_tracker.hpp"
#include "ncservo/rules/finding.hpp"
#include "ncservo/rules/rules.hpp"

namespace ncservo {

// What the validator saw in one frame: where each axis's PDOs sit, the values the frame carries
// for each, read once through the PDO codec (readFrameValues), and each placed axis's drive state
// after the frame. Each axis's edges and state change are its model's (AxisModel::edgesIn,
// stateChangeIn). Whoever shows or measures a frame reads this, never the bytes again.
struct Observation {
  FrameDecode decode;                                // copy, pairing and placements, in axis order
  std::array<PdoValues, kMaxAxesPerFrame> values{};  // by placement
  std::array<std::optional<DriveState>, kMaxAxesPerFrame> states{};  // by placement
  std::size_t servo_error_rises = 0;  // placed axes whose SEW.ServoErrors rose in this frame
};

struct CycleTimeSummary {
  std::optional<double> median_us, p99_us, max_us;
};

// The validator's fast path: an axis whose read bits did not change (rules.hpp Reads) is not
// observed again. Off only to prove it changes nothing (tests/unit/fast_path_test.cpp).
enum class FastPath : std::uint8_t { On, Off };

class Validator {
 public:
  Validator(DecoderOptions options, RuleSettings settings, FastPath fast_path = FastPath::On);

  // One walked EtherCAT frame (any status) with its 1-based frame number and capture time.
  // Returns what it saw of the frame; findings() then holds what was reported on it.
  const Observation& onFrame(std::uint64_t frame_number, std::int64_t time_ns,
                             const EcatFrame& frame, const ByteReader& bytes);
  const std::vector<Finding>& findings() const { return findings_; }
  // The capture ended: what could be judged only with the frames that did not come (a gap's
  // next interval, docs/rules.md#com-002), reported on the last frame; findings() then holds it.
  void finish();
  // A frame outside the time window (capture_stream.hpp): only what it shows of the layout.
  void onLayoutOnlyFrame(const EcatFrame& frame, const ByteReader& bytes) {
    decoder_.placeAxes(frame, bytes, view_.decode);
  }

  const Decoder& decoder() const { return decoder_; }
  const RuleSettings& settings() const { return settings_; }
  // Models of the axes seen so far, by axis index (null where an axis was never seen).
  std::size_t axisCount() const { return axes_.size(); }
  const AxisModel* axis(std::size_t index) const;
  std::uint64_t cycles() const { return bus_.cycles(); }
  CycleTimeSummary cycleTime() const;
  // The capture's segments (docs/timing.md#rule-time): the rules judge each on its own clock.
  const SegmentTracker& segments() const { return segments_; }
  const BusModel& bus() const { return bus_; }
  // Whether the frames' times measure the return latency: not on the bus's clock or in cycles,
  // where a returned copy has no time of its own (docs/timing.md#the-clock).
  void measureLatencies(bool measured) { bus_.measureLatencies(measured); }
  // The cycle interval and return latency the last frame given to onFrame added to the timing
  // statistics; all empty when it added none.
  const FrameTiming& frameTiming() const;
  const DcClock& dc() const { return dc_; }
  // The slaves' state machines; opChanges() holds the last frame's.
  const AlTracker& al() const { return al_; }
  // What the drives said over their mailboxes, and the ESCs' error counters
  // (docs/drive-messages.md); frameMessages() and frameDeltas() hold the last frame's.
  const MailboxTracker& mailbox() const { return mailbox_; }
  const EscErrorTracker& escErrors() const { return esc_; }
  // The telegram accounting of the last frame given to onFrame (or of finish()): the axes whose
  // cycles failed or were lost, and those whose cycles ran again (docs/rules.md#com-003).
  const std::vector<AxisAccount>& frameAccounts() const { return accounts_; }
  // The placed PDO regions the capture cut short (a snap length).
  const CutRegions& cutRegions() const { return cut_; }

 private:
  struct Episode {
    bool active = false;
    bool reported = false;
    Stamp began;
  };
  struct AxisSlot {
    std::optional<AxisModel> model;
    std::array<Episode, kRuleCount> episodes{};
    std::uint32_t pending = 0;  // delayed episodes running towards their timeout
    // The earliest time one of them can report (its start plus its timeout): until then a
    // frame that changes nothing the rules read changes no condition either.
    std::int64_t pending_until_ns = 0;
    std::optional<std::uint64_t> evaluated_revision;
    std::uint64_t al_epoch = 0;  // al_epoch_ when the AL state was last taken (0: never)
    std::optional<std::uint16_t> al_station;  // the station it was taken from
    std::uint32_t op_entries = 0;             // the station's OP entries then
  };
  // The bits of each PDO word that the axis model or an enabled rule reads, as the fast path
  // compares them.
  struct JudgedWord {
    std::uint8_t index;  // in kWords and PdoValues::raw
    std::uint64_t bits;
    WordClass word_class;  // or null
  };
  struct JudgedPdo {
    std::array<JudgedWord, kWordCount> words{};
    std::size_t count = 0;
  };
  struct Judged {
    JudgedPdo rx, tx;
    bool al_state = false;  // an enabled rule reads the AL state (Reads::al_state)
    bool mailbox = false;   // an enabled rule reads what the drives said (Reads::mailbox)
  };
  static Judged judgedBits(const RuleSettings& settings, FastPath fast_path);
  void applyAccounts();
  bool unchanged(const PdoValues& values, const AxisModel& model) const;

  void report(RuleId rule, std::optional<std::uint16_t> axis, const Stamp& since,
              std::string message);
  AxisSlot& slot(std::uint16_t axis);
  // `mailbox_only`: only the rules that read the mailbox, on a frame that gave the axis a
  // message (its PDOs need not be in it).
  void evaluateAxis(AxisSlot& axis, bool mailbox_only = false);
  void takeDriveMessages();
  void observeAl(const EcatFrame& frame, const ByteReader& bytes);  // addressing_ begun
  void reportEvents();
  void syncAlState(const AxisPlacement& placement, AxisSlot& slot);
  void startSegment();

  Decoder decoder_;
  Observation view_;  // this frame's
  RuleSettings settings_;
  Judged judged_;
  bool fast_path_;
  FrameAddressing addressing_;  // this frame's, read by al_ and dc_ (a walked frame's)
  AlTracker al_;
  DcClock dc_;
  MailboxTracker mailbox_;
  EscErrorTracker esc_;
  BusModel bus_;
  SegmentTracker segments_;
  CutRegions cut_;
  std::vector<BusEvent> events_;  // this frame's, from the slave and bus models
  std::vector<EventFinding> event_findings_;
  MeasurementRuns runs_;
  std::array<bool, kNoEvent> judged_events_{};  // by BusEventData index: an enabled rule judges it
  std::vector<AxisAccount> accounts_;           // this frame's telegram accounting
  std::vector<AxisSlot> axes_;
  std::array<AxisSlot*, kMaxAxesPerFrame> frame_slots_{};  // this frame's axes, in view order
  std::uint64_t al_epoch_ = 1;      // frames so far that could move an AL state or a station
  Stamp now_;                       // this frame, on its segment's clock (the timers')
  std::int64_t frame_time_ns_ = 0;  // this frame's own timestamp
  std::vector<Finding> findings_;
  // Findings so far in this segment, by rule and axis (kNoAxisKey: the bus): each finding's
  // ordinal (docs/baselines.md#fingerprints).
  static constexpr std::uint32_t kNoAxisKey = 0x10000;
  std::map<std::pair<RuleId, std::uint32_t>, std::uint32_t> ordinals_;
};

}  // namespace ncservo
