// The bus as the cyclic frames show it (docs/protocol.md §8, docs/rules.md COM-*): each frame's
// clock and interval statistics, whether master frames come back, and the working counter of
// every returned process-data datagram, servo or not (docs/timing.md "Which frames"). Gives the
// events the bus rules judge and each axis's telegram accounting; never reports a finding itself.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "ncservo/base/stamp.hpp"
#include "ncservo/layout/decoder.hpp"
#include "ncservo/model/bus_events.hpp"
#include "ncservo/model/interval_stats.hpp"
#include "ncservo/model/timing.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo {

// What one frame means for one axis's telegram-failure counters (docs/rules.md#com-003, COM-005).
struct AxisAccount {
  enum class Outcome : std::uint8_t { Good, Failed, Lost };
  std::uint16_t axis = 0;
  Outcome outcome = Outcome::Good;
  std::uint32_t cycles = 1;
  // The frames the account is about (docs/incidents.md#communication-loss): the master copy that
  // got no returned copy, the returned copy with a wrong WKC; for cycles of which no copy was
  // captured (`between`), the frames before and after them.
  Stamp first, last;
  bool between = false;
};

// A process-data datagram of a cyclic frame, as the report names what was judged.
struct CyclicDatagram {
  std::uint8_t command = 0;
  std::uint32_t address = 0;
  std::uint16_t length = 0;
  std::uint64_t frames = 0;  // copies (master and returned) of the cyclic frames holding it
};

// A cyclic frame that repeated, with its own clock (docs/timing.md "Which frames").
struct CyclicFrameSummary {
  std::vector<CyclicDatagram> datagrams;  // its process-data datagrams; `frames` its copies
  std::uint64_t cycles = 0;               // ticks of its clock
  std::optional<std::int64_t> cycle_ns;   // the median of its own intervals
};

class BusModel {
 public:
  // Whether a frame exchanges process data: a logical datagram (LRW, LRD, LWR) or servo PDOs.
  // Only such a frame is a copy of a cyclic frame.
  static bool exchangesProcessData(const EcatFrame& frame, const FrameDecode& decode);

  // One frame that exchanges process data, at `now` on the timers' monotonic clock;
  // `frame_time_ns` is its own timestamp. Its process-data datagrams name its cyclic frame.
  // Appends the events the bus rules judge and the axes' accounting, in the order they happened.
  // True when the frame is a returned copy whose every axis had a good cycle (the usual case,
  // left out of `accounts`).
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

  // Master copies of the busiest cyclic frame.
  std::uint64_t cycles() const;
  // The segment's nominal cycle, once enough intervals give it (docs/timing.md#rule-time, COM-002).
  std::optional<std::int64_t> nominalCycleNs() const;
  // The intervals of every segment, for reports.
  IntervalStats captureIntervals() const;
  // Cycle intervals and return latencies of every segment (docs/timing.md).
  const TimingStats& timing() const { return timing_; }
  // Off: returned copies add no latency (the frames are timed on a clock that gives them none).
  void measureLatencies(bool measured) { latencies_measured_ = measured; }
  // What the last frame given to onCyclicFrame added to timing().
  const FrameTiming& frameTiming() const { return frame_timing_; }
  // Returned datagrams carrying servo PDOs whose WKC was not captured (COM-001 not judged).
  std::uint64_t uncapturedWkcs() const { return uncaptured_wkcs_; }
  std::uint64_t firstUncapturedWkcFrame() const { return first_uncaptured_wkc_frame_; }
  // The process-data datagrams of the cyclic frames that repeated, in the order they were first
  // seen; one entry per command, address and length.
  std::vector<CyclicDatagram> cyclicDatagrams() const;
  // The cyclic frames that repeated, in the order they were first seen, each with its cycle.
  std::vector<CyclicFrameSummary> cyclicFrames() const;
  // Copies of frames not followed: kMaxCyclicFrames cyclic frames that repeated were already.
  std::uint64_t unfollowedFrames() const { return unfollowed_frames_; }
  // Returned copies whose master copy the capture does not hold: their cycles ran
  // (docs/timing.md "Capture loss").
  std::uint64_t masterCopiesMissing() const { return master_copies_missing_; }
  // Master copies not returned before the next master copy of their cyclic frame (COM-004).
  std::uint64_t returnedCopiesMissing() const { return returned_copies_missing_; }
  // Cycles lost so far, of every cyclic frame: those missing in the gaps COM-002 judges (whether
  // or not the rule is enabled) and the master copies never returned (COM-004); and returned
  // process-data datagrams whose WKC was not the expected one (each copy, where COM-001 reports
  // an episode once). Running totals for the live monitor's metrics and the reports.
  std::uint64_t lostCycles() const { return lost_cycles_; }
  std::uint64_t wkcErrors() const { return wkc_errors_; }

  static constexpr std::size_t kMaxCyclicFrames = ncservo::kMaxCyclicFrames;

 private:
  // What a frame shape's process-data datagrams should return (COM-001), worked out once per
  // shape (FrameDecode::shape_id) instead of every cycle.
  struct WkcCheck {
    std::uint16_t datagram;
    std::uint16_t expected;    // what the axes it carries add to its WKC (docs/protocol.md §8)
    bool shared;               // other slaves' bytes share it: judged against its usual WKC
    std::int16_t record;       // index in wkc_; kNoWkcRecord, kUnresolvedWkcRecord
    bool carries_axes = true;  // else a logical datagram of other slaves only (always shared)
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
    Stamp end;                        // the tick after it
    std::vector<std::uint16_t> axes;  // the axes its missing cycles would have carried
    bool accounted = false;           // its lost cycles already counted (certainly lost)
  };
  // What names a cyclic frame: one of its process-data datagrams, the same in the master's copy
  // and the returned copy (docs/protocol.md §8).
  struct DatagramKey {
    std::uint8_t command = 0;
    std::uint32_t address = 0;
    std::uint16_t length = 0;
    bool operator==(const DatagramKey& other) const {
      return command == other.command && address == other.address && length == other.length;
    }
  };
  // A frame that repeats with the same process-data datagrams.
  struct CyclicFrame {
    CyclicFrameId id;  // names it in the measurements
    std::vector<DatagramKey> datagrams;
    std::uint64_t copies = 0;  // master and returned
    std::uint64_t ticks = 0;   // of its clock
    std::optional<Stamp> last_tick;
    bool last_tick_estimated = false;  // from a returned copy whose master copy is missing
    std::int64_t last_latency_ns = 0;
    bool awaiting_return = false;
    bool not_returned_episode = false;
    Stamp last_master;
    std::vector<std::uint16_t> axes;  // axes of the last master copy (none: no servo PDOs)
    std::uint64_t axes_shape_id = 0;  // the shape they were taken from (0: none cached)
    std::optional<PendingGap> pending_gap;
  };
  // A cyclic process-data datagram: its WKC history (COM-001).
  struct WkcRecord {
    std::uint8_t command;
    std::uint32_t address;
    std::uint16_t length;
    bool wrong_episode = false;
    std::array<std::uint16_t, 8> values{};
    std::array<std::uint32_t, 8> counts{};
  };

  // The frame's process-data datagrams into `keys`; how many.
  static std::size_t processDatagrams(const EcatFrame& frame, const FrameDecode& decode,
                                      std::array<DatagramKey, ecat::kMaxDatagrams>& keys);
  // The cyclic frame with these datagrams; null when it cannot be followed.
  CyclicFrame* cyclicFrame(const EcatFrame& frame, const FrameDecode& decode);
  std::int16_t wkcRecord(const Datagram& dg);
  WkcPlan& wkcPlan(const EcatFrame& frame, const FrameDecode& decode);
  // `at` is the master copy's time; `estimated` when only its returned copy was captured: an
  // interval from or to such a tick is judged for gaps only (no statistics, no COM-006).
  void tick(CyclicFrame& cyclic, const FrameDecode& decode, const Stamp& at, bool estimated);
  // Judges the pending gap with the interval after it, or untold (`next` empty) as `verdict`.
  void judgeGap(CyclicFrame& cyclic, std::optional<std::int64_t> next,
                CycleGapEvent::Verdict verdict, std::vector<BusEvent>& events,
                std::vector<AxisAccount>* accounts);
  bool checkWorkingCounters(const EcatFrame& frame, const FrameDecode& decode);

  // This frame's.
  Stamp now_;
  std::int64_t frame_time_ns_ = 0;
  std::vector<BusEvent>* events_ = nullptr;
  std::vector<AxisAccount>* accounts_ = nullptr;

  std::vector<CyclicFrame> cyclic_;                            // in the order first seen
  std::uint32_t cyclic_serials_ = 0;                           // given so far
  std::array<DatagramKey, ecat::kMaxDatagrams> frame_keys_{};  // this frame's
  // The cyclic frame of recent frame shapes (FrameDecode::shape_id), by index in cyclic_: a
  // shape has the same process-data datagrams every cycle. Forgotten when cyclic_ changes.
  struct ShapeCyclic {
    std::uint64_t shape_id = 0;
    std::size_t index = 0;
  };
  std::array<ShapeCyclic, 4> shape_cyclic_{};
  std::size_t shape_cyclic_next_ = 0;
  std::vector<WkcRecord> wkc_;
  std::array<WkcPlan, 4> wkc_plans_{};  // of recent frame shapes, replaced in turn
  std::size_t wkc_plan_next_ = 0;
  WkcPlan uncached_plan_;    // for a frame whose shape is not cached
  IntervalStats intervals_;  // this segment's
  // Per slot of cyclic_: each frame's own intervals, this segment's (its nominal cycle) and
  // the capture's (its reported cycle).
  std::array<IntervalStats, kMaxCyclicFrames> frame_intervals_;
  std::array<IntervalStats, kMaxCyclicFrames> frame_capture_intervals_;
  IntervalStats earlier_intervals_;  // the segments' before it
  TimingStats timing_;
  FrameTiming frame_timing_;
  std::uint64_t unfollowed_frames_ = 0;
  std::uint64_t master_copies_missing_ = 0;
  std::uint64_t returned_copies_missing_ = 0;
  std::uint64_t lost_cycles_ = 0;
  std::uint64_t wkc_errors_ = 0;
  std::uint64_t uncaptured_wkcs_ = 0;
  std::uint64_t first_uncaptured_wkc_frame_ = 0;
  bool master_copies_seen_ = false;
  // docs/timing.md#which-frames: once a frame with servo PDOs was seen, the capture's cycle and
  // latency statistics are the servos' task's; another task's frames keep only their own clock.
  bool servo_frames_seen_ = false;
  bool capture_clock_ = true;  // the frame in hand feeds the capture's statistics
  bool latencies_measured_ = true;
  bool returned_copies_seen_ = false;
};

}  // namespace ncservo
