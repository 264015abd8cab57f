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

struct CycleTimeSummary {
  std::optional<double> median_us, p99_us, max_us;
};

class Validator {
 public:
  Validator(DecoderOptions options, RuleSettings settings);

  // One walked EtherCAT frame (any status) with its 1-based frame number and capture time.
  // Returns the frame's decoded view; findings() then holds what was reported on this frame.
  const FrameView& onFrame(std::uint64_t frame_number, std::int64_t time_ns, const EcatFrame& frame,
                           const ByteReader& bytes);
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
  };
  // The cyclic frame that carries a group of axes, named by its lowest axis index.
  struct CyclicFrame {
    std::uint16_t first_axis = 0;
    std::optional<Stamp> last_tick;
    bool awaiting_return = false;
    bool not_returned_episode = false;
    Stamp last_master;
    std::vector<std::uint16_t> axes;  // axes of the last master copy
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
  WkcRecord* wkcRecord(const Datagram& dg);
  // On this frame's placements (decode_). `first_axis`: the lowest axis index of the frame,
  // which names its cyclic frame.
  void accountCycle(const EcatFrame& frame, std::uint16_t first_axis);
  void tick(CyclicFrame& cyclic);
  void checkWorkingCounters(const EcatFrame& frame);
  void evaluateAxis(AxisSlot& axis);
  void observeAl(const EcatFrame& frame, const ByteReader& bytes);

  Decoder decoder_;
  FrameDecode decode_;  // this frame's placements
  FrameView view_;      // this frame's placements, values and states, as a Session gives them
  RuleSettings settings_;
  AlTracker al_;
  std::vector<AlFinding> al_findings_;
  std::vector<AxisSlot> axes_;
  std::array<AxisSlot*, kMaxAxesPerFrame> frame_slots_{};  // this frame's axes, in view order
  std::vector<CyclicFrame> cyclic_;
  std::vector<WkcRecord> wkc_;
  IntervalStats intervals_;
  std::uint64_t cycles_ = 0;
  bool master_copies_seen_ = false;
  bool returned_copies_seen_ = false;
  Stamp now_;                       // this frame, on the monotonic clock of the timers
  std::int64_t frame_time_ns_ = 0;  // this frame's own timestamp
  bool any_frame_ = false;
  std::vector<Finding> findings_;
};

}  // namespace ncservo
