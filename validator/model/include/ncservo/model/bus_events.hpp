// What the bus and slave models saw happen in one frame, for the bus and slave rules to judge
// (docs/rules.md). The models decide what happened (a datagram returned with another WKC than its
// slaves add, an outage, an AL control write) and measure (a cycle interval, a return latency);
// the rules compare with their limits, decide whether that is a finding and say so.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <variant>

#include "ncservo/base/stamp.hpp"

namespace ncservo {

// A returned cyclic process-data datagram whose WKC differs from the expected one
// (docs/protocol.md §8), at the start of such an episode for that datagram.
struct WorkingCounterEvent {
  std::uint8_t command = 0;
  std::uint32_t address = 0;
  std::uint16_t length = 0;
  std::uint16_t wkc = 0;
  std::uint16_t expected = 0;
};

// An interval between two ticks of a cyclic frame's clock longer than 1.5 × the nominal cycle
// (docs/rules.md#com-002), judged at the tick after it: a late cycle when that next interval makes
// the two about two cycles, else lost cycles. A segment start or the capture's end before the
// next tick leaves it untold, counted as lost.
struct CycleGapEvent {
  enum class Verdict : std::uint8_t { Late, Lost, SegmentEnds, CaptureEnds };
  Verdict verdict = Verdict::Lost;
  std::int64_t interval_ns = 0;
  std::int64_t nominal_ns = 0;
  std::optional<std::int64_t> next_interval_ns;  // Late and Lost only
  std::uint32_t missing = 0;         // 0 when late; else round(interval ÷ nominal) − 1
  std::uint64_t previous_frame = 0;  // the tick before the gap
  std::uint64_t next_frame = 0;      // the tick that ended it
};

// The bus model follows at most this many cyclic frames at once.
inline constexpr std::size_t kMaxCyclicFrames = 16;

// Which cyclic frame a measurement is of: its slot among the frames followed, which a frame keeps
// while followed and a later one may reuse, and the serial number no other frame gets.
struct CyclicFrameId {
  std::uint8_t slot = 0;  // below kMaxCyclicFrames
  std::uint32_t serial = 0;
};

// The interval between two ticks of a cyclic frame's clock, once the segment has a nominal
// cycle; COM-006 judges its deviation against cycle_jitter_percent (docs/rules.md#com-006).
struct CycleIntervalEvent {
  std::int64_t interval_ns = 0;
  std::int64_t nominal_ns = 0;
  std::uint64_t previous_frame = 0;  // the tick before it
  CyclicFrameId cyclic_frame;        // whose clock: a run of cycles is one frame's
  bool gap = false;                  // longer than 1.5 cycles: a CycleGapEvent tells it
};

// The time from a master copy to its returned copy; COM-007 judges it against
// return_latency_us (docs/rules.md#com-007).
struct ReturnLatencyEvent {
  std::int64_t latency_ns = 0;
  std::uint64_t master_frame = 0;
  CyclicFrameId cyclic_frame;  // whose copies: a run of cycles is one frame's
};

// A cyclic master frame that was not returned before the next cycle's master frame, at the
// start of such an episode (docs/rules.md#com-004).
struct NotReturnedEvent {
  struct Axes {
    std::uint16_t first = 0;
    std::uint16_t last = 0;
  };
  std::uint64_t master_frame = 0;
  std::optional<Axes> axes;  // the servo axes it carries, if any
  // Its first process-data datagram, and how many it holds: what names a frame without axes.
  std::uint8_t command = 0;
  std::uint32_t address = 0;
  std::uint16_t length = 0;
  std::uint16_t datagrams = 0;
};

// One slave, as the capture names it: by station address, ring position, both or neither (a
// broadcast).
struct SlaveRef {
  std::optional<std::uint16_t> station;
  std::optional<std::uint16_t> position;
};

// An AL control write (0x0120) to a slave whose AL state is known (docs/protocol.md §8).
struct AlControlEvent {
  SlaveRef slave;
  std::uint16_t raw = 0;
  std::uint8_t requested = 0;  // bits 3..0
  std::uint8_t known_state = 0;
};

// An AL status read (0x0130) showing the error indicator, at the start of such an episode.
struct AlErrorEvent {
  SlaveRef slave;
  std::uint16_t raw = 0;
  std::optional<std::uint8_t> requested;  // last AL control request to it or to all
  std::optional<std::uint8_t> previous;   // its known state before this read
  std::optional<std::uint16_t> status_code;
  std::uint64_t status_code_frame = 0;  // where the status code was read
};

// A drive's CoE emergency (PROTOCOL.md §11), on the frame that read it from its mailbox.
struct EmergencyEvent {
  SlaveRef slave;
  std::uint16_t code = 0;
  std::uint8_t error_register = 0;
};

// An SDO request the slave aborted, on the frame of the abort (MBX-003).
struct SdoAbortEvent {
  SlaveRef slave;
  std::uint16_t index = 0;
  std::uint8_t subindex = 0;
  std::uint32_t code = 0;
  std::optional<std::uint64_t> request_frame;
  bool expected = false;  // 0x08000024 on an entry of an empty 1003h (seed 002)
};

// 1003h subindex 0 read lower than the read before, with no write of 0 between (ERH-001).
struct ErrorHistoryShrunkEvent {
  SlaveRef slave;
  std::uint32_t before = 0;
  std::uint32_t now = 0;
  std::uint64_t before_frame = 0;
};

// A link the ESC counters name (JSON `link_faults`, LNK-001/LNK-002): the cable between two
// ports, upstream first in processing order.
struct LinkFault {
  std::optional<SlaveRef> upstream;  // none where the ring order does not say
  std::uint8_t upstream_port = 0;
  SlaveRef downstream;
  std::uint8_t downstream_port = 0;
  // For a fault at port 1 the slave read is the upstream side: `reported` names the slave and
  // port whose counters rose.
  SlaveRef reported;
  std::uint8_t reported_port = 0;
  std::uint32_t errors = 0;
  std::uint64_t frame = 0;
};

// A slave's ESC error counters rose at a port, at a counter read: RX and invalid frames no
// upstream slave forwarded, a fault of the link at that port (LNK-001), or its lost-link counter
// (LNK-002).
struct LinkErrorEvent {
  LinkFault link;                         // errors: the rise; reported: the slave read
  bool lost = false;                      // the lost-link counter
  std::uint64_t previous_read_frame = 0;  // the read the counter rose since (0: a clear)
};

// A slave's system time difference (0x092C) read, in ns, with its read before (DC-001: a run of
// reads beyond the limit is one finding) and the smallest magnitude of its earlier reads (DC-001
// judges a slave once it has been within the limit: the reads before are its start-up's
// convergence).
struct DcDifferenceEvent {
  SlaveRef slave;
  std::int64_t difference_ns = 0;
  std::optional<std::int64_t> previous_ns;
  std::uint64_t previous_frame = 0;
  std::optional<std::int64_t> smallest_before_ns;
};

using BusEventData =
    std::variant<WorkingCounterEvent, CycleGapEvent, CycleIntervalEvent, ReturnLatencyEvent,
                 NotReturnedEvent, AlControlEvent, AlErrorEvent, EmergencyEvent, SdoAbortEvent,
                 ErrorHistoryShrunkEvent, LinkErrorEvent, DcDifferenceEvent>;

struct BusEvent {
  Stamp since;  // where the condition began
  BusEventData data;
};

}  // namespace ncservo
