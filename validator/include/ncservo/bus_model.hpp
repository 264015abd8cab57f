// The bus as the cyclic frames show it (PROTOCOL.md §8, RULES.md COM-*): each cyclic frame's
// clock and interval statistics, whether master frames come back, and the working counter of
// every returned datagram that carries servo PDOs. Gives the events the bus rules judge and each
// axis's telegram accounting; never reports a finding itself.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "ncservo/bus_events.hpp"
#include "ncservo/decoder.hpp"
#include "ncservo/ethercat.hpp"
#include "ncservo/interval_stats.hpp"
#include "ncservo/timing.hpp"

namespace ncservo {

// What one frame means for one axis's telegram-failure counters (RULES.md COM-003, COM-005).
struct AxisAccount {
  enum class Outcome : std::uint8_t { Good, Failed, Lost };
  std::uint16_t axis = 0;
  Outcome outcome = Outcome::Good;
  std::uint32_t cycles = 1;
};

// The limits of the timing rules that are off by default, each set only while its rule is
// enabled (RULES.md COM-006, COM-007).
struct TimingLimits {
  std::optional<std::uint32_t> cycle_jitter_percent;
  std::optional<std::int64_t> return_latency_ns;
};

class BusModel {
 public:
  explicit BusModel(TimingLimits limits = {}) : limits_(limits) {}

  // One frame that carries servo PDOs, at `now` on the timers' monotonic clock; `frame_time_ns`
  // is its own timestamp. Appends the events the bus rules judge and the axes' accounting, in the
  // order they happened. True when the frame is a returned copy whose every axis had a good cycle
  // (the usual case, left out of `accounts`).
  bool onCyclicFrame(const EcatFrame& frame, const FrameDecode& decode, const Stamp& now,
                     std::int64_t frame_time_ns, std::vector<BusEvent>& events,
                     std::vector<AxisAccount>& accounts);

  // A capture segment starts (capture_segments.hpp): the interval statistics, the cycle-gap
  // clocks, the frames awaiting their return and the working-counter episodes start again; what
  // the capture showed of the bus (copies, usual working counters) carries on. A gap still
  // waiting for its next interval is judged without it (COM-002).
  void startSegment(std::vector<BusEvent>& events);
  // The capture ended: a gap still waiting for its next interval is judged without it, its
  // missing cycles counted as lost (COM-002).
  void finish(std::vector<BusEvent>& events, std::vector<AxisAccount>& accounts);

  std::uint64_t cycles() const { return cycles_; }
  // The segment's nominal cycle, once enough intervals give it (RULES.md "Time", COM-002).
  std::optional<std::int64_t> nominalCycleNs() const;
  // The intervals of every segment, for reports.
  IntervalStats captureIntervals() const;
  // Cycle intervals and return latencies of every segment (docs/timing.md).
  const TimingStats& timing() const { return timing_; }
  // What the last frame given to onCyclicFrame added to timing().
  const FrameTiming& frameTiming() const { return frame_timing_; }
  // Returned datagrams carrying servo PDOs whose WKC was not captured (COM-001 not judged).
  std::uint64_t uncapturedWkcs() const { return uncaptured_wkcs_; }
  std::uint64_t firstUncapturedWkcFrame() const { return first_uncaptured_wkc_frame_; }

 private:
  // What a frame shape's datagrams that carry servo PDOs should return (COM-001), worked out
  // once per shape (FrameDecode::shape_id) instead of every cycle.
  struct WkcCheck {
    std::uint16_t datagram;
    std::uint16_t expected;  // what the axes it carries add to its WKC (PROTOCOL.md §8)
    bool shared;             // other slaves' bytes share it: judged against its usual WKC
    std::int16_t record;     // index in wkc_; kNoWkcRecord, kUnresolvedWkcRecord
    AxisAccount::Outcome outcome = AxisAccount::Outcome::Good;  // this frame's
  };
  static constexpr std::int16_t kNoWkcRecord = -1;  // too many datagrams are followed
  static constexpr std::int16_t kUnresolvedWkcRecord = -2;
  struct WkcPlan {
    std::uint64_t shape_id = 0;
    std::vector<WkcCheck> checks;
  };
  // An interval longer than 1.5 cycles, judged late or lost at the next tick (COM-002).
  struct PendingGap {
    Stamp since;  // the tick before it
    std::int64_t interval_ns = 0;
    std::int64_t nominal_ns = 0;
    std::uint64_t end_frame = 0;
    std::vector<std::uint16_t> axes;  // the axes its missing cycles would have carried
    bool accounted = false;           // its lost cycles already counted (certainly lost)
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
    std::optional<PendingGap> pending_gap;
    bool jitter_episode = false;       // COM-006
    bool late_return_episode = false;  // COM-007
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

  CyclicFrame& cyclicFrame(std::uint16_t first_axis);
  std::int16_t wkcRecord(const Datagram& dg);
  WkcPlan& wkcPlan(const EcatFrame& frame, const FrameDecode& decode);
  void tick(CyclicFrame& cyclic, const FrameDecode& decode);
  // Judges the pending gap with the interval after it, or untold (`next` empty) as `verdict`.
  void judgeGap(CyclicFrame& cyclic, std::optional<std::int64_t> next,
                CycleGapEvent::Verdict verdict, std::vector<BusEvent>& events,
                std::vector<AxisAccount>* accounts);
  void judgeJitter(CyclicFrame& cyclic, std::int64_t interval, std::int64_t nominal, bool gap);
  void judgeLatency(CyclicFrame& cyclic, std::int64_t latency, std::vector<BusEvent>& events);
  bool checkWorkingCounters(const EcatFrame& frame, const FrameDecode& decode);

  // This frame's.
  Stamp now_;
  std::int64_t frame_time_ns_ = 0;
  std::vector<BusEvent>* events_ = nullptr;
  std::vector<AxisAccount>* accounts_ = nullptr;

  TimingLimits limits_;
  std::vector<CyclicFrame> cyclic_;
  std::vector<WkcRecord> wkc_;
  std::array<WkcPlan, 4> wkc_plans_{};  // of recent frame shapes, replaced in turn
  std::size_t wkc_plan_next_ = 0;
  WkcPlan uncached_plan_;            // for a frame whose shape is not cached
  IntervalStats intervals_;          // this segment's
  IntervalStats earlier_intervals_;  // the segments' before it
  TimingStats timing_;
  FrameTiming frame_timing_;
  std::uint64_t cycles_ = 0;
  std::uint64_t uncaptured_wkcs_ = 0;
  std::uint64_t first_uncaptured_wkc_frame_ = 0;
  bool master_copies_seen_ = false;
  bool returned_copies_seen_ = false;
};

}  // namespace ncservo
