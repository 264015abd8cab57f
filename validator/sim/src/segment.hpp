// The simulated slaves (PROTOCOL.md §8): each an EtherCAT slave controller (ESC) with register
// memory, FMMUs and the AL state machine, driven only by what the master writes, so that the
// capture is consistent by construction; in ring order, with where their process data lies.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "ncservo/al_tracker.hpp"
#include "ncservo/sim/models.hpp"
#include "ncservo/sim/simulator.hpp"

namespace ncservo::sim {

inline constexpr std::size_t kEscMemory = 0x2000;  // registers and process RAM
inline constexpr std::uint16_t kFirstStation = 0x03E9;
inline constexpr std::int64_t kEpochNs = 1'767'225'600 * kSecond;  // 2026-01-01 00:00:00 UTC

enum class SlaveKind : std::uint8_t { Servo, OutputTerminal, InputTerminal };

// A datagram on its way round the ring: the slaves read and write its data and count its WKC.
struct RingDatagram {
  std::uint8_t command = 0;
  std::uint8_t index = 0;
  std::uint16_t adp = 0;
  std::uint16_t ado = 0;  // with adp, the logical address of LRD/LWR/LRW
  std::vector<std::uint8_t> data;
  std::uint16_t wkc = 0;
  std::uint32_t logical() const {
    return static_cast<std::uint32_t>(adp) | (static_cast<std::uint32_t>(ado) << 16);
  }
};

class Esc {
 public:
  SlaveKind kind = SlaveKind::Servo;
  int axis = -1;  // for a servo
  std::vector<std::uint8_t> mem = std::vector<std::uint8_t>(kEscMemory, 0);
  std::uint8_t state = ecat::kAlInit;
  int transition_frames = 1;    // frames a state change takes
  bool refuse_next_op = false;  // ESM-003
  bool outputs_taken = false;   // this cycle's LRW wrote its outputs
  bool skip_next_lrw = false;   // COM-001
  std::uint32_t outputs_logical = 0;
  std::uint32_t inputs_logical = 0;

  // Process data: bytes, and where they lie in the process RAM (SM2/SM3 of a servo, SM0 of a
  // digital terminal).
  std::size_t outputBytes() const;
  std::size_t inputBytes() const;
  std::uint16_t outputsPhysical() const;
  std::uint16_t inputsPhysical() const;

  std::uint16_t station() const;
  bool processData() const;  // SAFE-OP or OP
  void publishAlStatus();
  // ESM-004: the slave comes up with an AL error left from its power-up.
  void powerUpError();
  // In OP with the station address and FMMUs the master's start-up would have written (a
  // capture that begins with the segment running).
  void startInOp(std::uint16_t station);
  // One datagram passing through, then (once per frame) the end of the frame.
  void process(RingDatagram& dg);
  void endOfFrame();

 private:
  void onAlControl(std::uint16_t value);
  void readRegisters(RingDatagram& dg) const;
  void writeRegisters(const RingDatagram& dg);
  std::uint16_t logicalAccess(RingDatagram& dg);  // the WKC increment

  bool error_ = false;
  std::uint16_t code_ = 0;
  std::uint8_t pending_ = 0;  // a state change under way
  int pending_frames_ = 0;
};

struct FrameGroup {  // the slaves whose process data one cyclic frame carries
  std::vector<int> slaves;
  std::uint32_t base = 0;
  std::size_t size = 0;
};

// The slaves in ring order: servo 0, terminal 0, servo 1, terminal 1, ..., then the rest.
struct Segment {
  std::vector<Esc> escs;
  std::vector<int> servo_slave;  // axis -> ring position
  std::vector<FrameGroup> groups;

  Segment(const SimOptions& options, Rng& rng);
  Esc& servo(int axis) {
    return escs[static_cast<std::size_t>(servo_slave[static_cast<std::size_t>(axis)])];
  }
  std::vector<SimAxisLayout> axisLayout() const;
  // A frame round the ring at this time (since the Unix epoch).
  void pass(std::vector<RingDatagram>& frame, std::int64_t now_ns);
};

}  // namespace ncservo::sim
