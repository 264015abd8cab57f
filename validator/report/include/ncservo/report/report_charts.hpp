// What the HTML report draws beside the findings, kept bounded: a timeline of the bits each
// finding's rule reads (a few cycles either side of it, from a ring of each axis's recent cycles),
// and binned statistics. Presentation only: fed frame by frame by `validate`, never by the library.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/protocol/fields.hpp"
#include "ncservo/rules/finding.hpp"
#include "ncservo/rules/rules.hpp"
#include "ncservo/rules/validator.hpp"

namespace ncservo::report {

// One field-table row a finding's rule reads, over the finding's window: its value at the
// window's start, then each change (time in ns relative to the finding's frame).
struct BitTrace {
  const FieldDef* field = nullptr;
  bool through_class = false;  // the word is read only through its class: 0 or 1
  std::vector<std::pair<std::int64_t, std::uint64_t>> changes;
};

// The bits one finding's rule reads, a few cycles either side of the finding; times in ns
// relative to the finding's frame.
struct FindingTimeline {
  std::size_t finding = 0;  // index in the capture's findings
  std::int64_t start_ns = 0;
  std::int64_t end_ns = 0;
  std::optional<std::int64_t> since_ns;  // where the condition began, when recorded
  // The window the rule's timeout allowed (from, to), placed by its row (allowedWindow).
  std::optional<std::pair<std::int64_t, std::int64_t>> allowed_ns;
  bool clipped = false;  // the condition began before the oldest recorded cycle
  std::vector<BitTrace> traces;
};

struct FindingTimelines {
  std::vector<FindingTimeline> drawn;
  std::uint64_t omitted = 0;  // axis findings past the caps below
};

// Keeps each axis's recent frames in a ring and cuts a window out of it for the first findings
// of each rule and axis.
class TimelineRecorder {
 public:
  static constexpr std::size_t kFramesAround = 16;  // either side: 8 cycles of master and return
  static constexpr std::size_t kRingFrames = 1024;  // covers the longest default timeout at 1 ms
  static constexpr std::size_t kPerRuleAndAxis = 3;
  static constexpr std::size_t kMaxTimelines = 300;

  explicit TimelineRecorder(const RuleSettings& settings) : settings_(settings) {}

  // One validated frame; `time_ns` since the capture's first frame.
  void frame(std::uint64_t number, std::int64_t time_ns, const Observation& frame);
  // A finding reported on the last frame (every finding, in order: its index counts them).
  void finding(const Finding& finding);
  // The windows, the pending ones cut at the last frame seen.
  FindingTimelines finish();

 private:
  struct Sample {
    std::uint64_t frame = 0;
    std::int64_t time_ns = 0;
    std::array<std::uint64_t, kWordCount> raw{};
  };
  struct Pending {
    std::size_t finding;
    RuleId rule;
    Stamp at;
    Stamp since;
    std::size_t after = 0;  // frames recorded since the finding's
  };
  struct AxisRing {
    std::vector<Sample> samples;  // kRingFrames, circular
    std::size_t next = 0;
    std::size_t size = 0;
    std::array<std::uint64_t, kWordCount> current{};
    std::vector<Pending> pending;
    std::array<std::size_t, kRuleCount> drawn{};
  };
  AxisRing& ring(std::uint16_t axis);
  void cut(AxisRing& ring, const Pending& pending);
  std::size_t pendingCount() const;

  RuleSettings settings_;
  std::vector<AxisRing> axes_;
  std::size_t findings_ = 0;
  FindingTimelines out_;
};

}  // namespace ncservo::report
