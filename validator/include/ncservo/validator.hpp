// One capture through the model and the rules: frames in, findings out, one pass in capture
// order (RULES.md "Time"). Shared by the CLI (`validate`) and the plugin (expert info).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/al_tracker.hpp"
#include "ncservo/axis_model.hpp"
#include "ncservo/finding.hpp"
#include "ncservo/interval_stats.hpp"
#include "ncservo/rules.hpp"
#include "ncservo/session.hpp"

namespace ncservo {

// What the validator gives back for one frame: where each axis's PDOs sit, and each placed
// axis's drive state after the frame. The values are read from the bytes at the placements
// (readFrameValues) by whoever shows them.
struct ValidatedFrame {
  FrameDecode decode;  // copy, pairing and placements, in axis order
  std::array<std::optional<DriveState>, kMaxAxesPerFrame> states{};  // by placement
};

struct CycleTimeSummary {
  std::optional<double> median_us, p99_us, max_us;
};

class Validator {
 public:
  Validator(DecoderOptions options, RuleSettings settings);

  // One walked EtherCAT frame (any status) with its 1-based frame number and capture time.
  // Returns the frame's placements and states; findings() then holds what was reported on it.
  const ValidatedFrame& onFrame(std::uint64_t frame_number, std::int64_t time_ns,
                                const EcatFrame& frame, const ByteReader& bytes);
  const std::vector<Finding>& findings() const { return findings_; }

  const Decoder& decoder() const { return decoder_; }
  const RuleSettings& settings() const { return settings_; }
  // Models of the axes seen so far, by axis index (null where an axis was never seen).
  std::size_t axisCount() const { return axes_.size(); }
  const AxisModel* axis(std::size_t index) const;
  std::uint64_t cycles() const { return cycles_; }
  CycleTimeSummary cycleTime() const;

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
    std::optional<std::uint64_t> evaluated_revision;
    std::uint64_t al_epoch = 0;  // al_epoch_ when the AL state was last taken (0: never)
    std::optional<std::uint16_t> al_station;  // the station it was taken from
    std::uint32_t op_entries = 0;             // the station's OP entries then
  };
  // What a frame shape's datagrams that carry servo PDOs should return (COM-001), worked out
  // once per shape (FrameDecode::shape_id) instead of every cycle.
  struct WkcCheck {
    std::uint16_t datagram;
    std::uint16_t expected;    // what the axes it carries add to its WKC (PROTOCOL.md §8)
    bool shared;               // other slaves' bytes share it: judged against its usual WKC
    std::int16_t record;       // index in wkc_; kNoWkcRecord, kUnresolvedWkcRecord
    std::uint8_t outcome = 0;  // this frame's
  };
  static constexpr std::int16_t kNoWkcRecord = -1;  // too many datagrams are followed
  static constexpr std::int16_t kUnresolvedWkcRecord = -2;
  struct WkcPlan {
    std::uint64_t shape_id = 0;
    std::vector<WkcCheck> checks;
  };
  // The cyclic frame that carries a group of axes, named by its lowest axis index.
  struct CyclicFrame {
    std::uint16_t first_axis = 0;
    std::optional<Stamp> last_tick;
    bool awaiting_return = false;
    bool not_returned_episode = false;
    Stamp last_master;
    std::vector<std::uint16_t> axes;  // axes of the last master copy
    std::uint64_t axes_shape_id = 0;  // the shape they were taken from (0: none cached)
  };
  // A cyclic datagram carrying servo PDOs: its WKC history (COM-001).
  struct WkcRecord {
    std::uint8_t command;
    std::uint32_t address;
    std::uint16_t length;
    bool wrong_episode = false;
    std::array<std::uint16_t, 8> values{};
    std::array<std::uint32_t, 8> counts{};
  };

  void report(RuleId rule, std::optional<std::uint16_t> axis, const Stamp& since,
              std::string message);
  AxisSlot& slot(std::uint16_t axis);
  CyclicFrame* cyclicFrame(std::uint16_t first_axis);
  std::int16_t wkcRecord(const Datagram& dg);
  WkcPlan& wkcPlan(const EcatFrame& frame);
  // On this frame's placements (view_.decode). `first_axis`: the lowest axis index of the frame,
  // which names its cyclic frame.
  void accountCycle(const EcatFrame& frame, std::uint16_t first_axis);
  void tick(CyclicFrame& cyclic);
  void checkWorkingCounters(const EcatFrame& frame);
  void evaluateAxis(AxisSlot& axis);
  void observeAl(const EcatFrame& frame, const ByteReader& bytes);
  void syncAlState(const AxisPlacement& placement, AxisSlot& slot);

  Decoder decoder_;
  ValidatedFrame view_;  // this frame's placements and states
  RuleSettings settings_;
  AlTracker al_;
  std::vector<AlFinding> al_findings_;
  std::vector<AxisSlot> axes_;
  std::array<AxisSlot*, kMaxAxesPerFrame> frame_slots_{};  // this frame's axes, in view order
  std::vector<CyclicFrame> cyclic_;
  std::vector<WkcRecord> wkc_;
  std::array<WkcPlan, 4> wkc_plans_{};  // of recent frame shapes, replaced in turn
  std::size_t wkc_plan_next_ = 0;
  WkcPlan uncached_plan_;  // for a frame whose shape is not cached
  IntervalStats intervals_;
  std::uint64_t al_epoch_ = 1;  // frames so far that could move an AL state or a station
  std::uint64_t cycles_ = 0;
  bool master_copies_seen_ = false;
  bool returned_copies_seen_ = false;
  Stamp now_;                       // this frame, on the monotonic clock of the timers
  std::int64_t frame_time_ns_ = 0;  // this frame's own timestamp
  bool any_frame_ = false;
  std::vector<Finding> findings_;
};

}  // namespace ncservo
