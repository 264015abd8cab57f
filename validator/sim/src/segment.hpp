// The simulated slaves (docs/protocol.md §8): each an EtherCAT slave controller (ESC) with register
// memory, FMMUs and the AL state machine, driven only by what the master writes, so that the
// capture is consistent by construction; in ring order, with where their process data lies.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/config/config.hpp"
#include "ncservo/model/al_tracker.hpp"
#include "ncservo/sim/diagnosis_truth.hpp"
#include "ncservo/sim/models.hpp"
#include "ncservo/sim/options.hpp"
#include "ncservo/wire/diagnosis_texts.hpp"
#include "ncservo/wire/ecat_wire.hpp"

namespace ncservo::sim {

inline constexpr std::size_t kEscMemory = 0x2000;                  // registers and process RAM
inline constexpr std::int64_t kEpochNs = 1'767'225'600 * kSecond;  // 2026-01-01 00:00:00 UTC

// What a slave's process data is, for what the master writes and the slave answers.
enum class SlaveRole : std::uint8_t {
  Servo,    // this protocol (docs/protocol.md §1-5)
  Digital,  // a walking output bit; inputs count up
  Analog,   // 16-bit channels: ramps out, triangles in
  Drive,    // another protocol's drive (CiA 402-like control and status words)
  Bridge,   // a gateway's bytes: counters both ways
};

// A kind of slave: its process data's sizes, and where its sync managers put it in its RAM.
// Terminals without a mailbox carry theirs in SM0 (as EL2008/EL1008); the others by convention
// outputs in SM2 and inputs in SM3 (docs/protocol.md §8).
struct SlaveModel {
  const char* name;
  SlaveRole role;
  std::uint16_t output_bytes;
  std::uint16_t input_bytes;
  std::uint8_t output_sm;
  std::uint8_t input_sm;
  std::uint16_t output_phys;
  std::uint16_t input_phys;
};
const SlaveModel& servoModel();

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

// A servo's mailbox areas (docs/simulate.md#diagnosis): SM0 for the master's requests, SM1 for
// the drive's answers, right below its process data.
inline constexpr std::uint16_t kMailboxOutPhys = 0x1000;
inline constexpr std::uint16_t kMailboxInPhys = 0x1080;
inline constexpr std::uint16_t kMailboxBytes = 128;
// SM0 and SM1 as the master configures them for the mailbox: 16 bytes from 0x0800.
inline constexpr std::size_t kMailboxSyncManagers = 2 * ecat::kSyncManagerStride;
void writeMailboxSyncManagers(std::uint8_t* registers);

class Esc {
 public:
  const SlaveModel* model = &servoModel();
  int axis = -1;  // for a servo
  std::vector<std::uint8_t> mem = std::vector<std::uint8_t>(kEscMemory, 0);
  std::uint8_t state = ecat::kAlInit;
  int transition_frames = 1;    // frames a state change takes
  bool refuse_next_op = false;  // ESM-003
  bool outputs_taken = false;   // this cycle's LRW wrote its outputs
  bool skip_next_lrw = false;   // COM-001
  std::uint32_t outputs_logical = 0;
  std::uint32_t inputs_logical = 0;
  // A terminal's inputs change this often; 0: every cycle, to values drawn from the slave and time.
  std::int64_t input_step_ns = 50 * kMs;
  std::uint64_t cycle_ns = kMs;

  bool servo() const { return model->role == SlaveRole::Servo; }
  // Process data: bytes, and where they lie in the process RAM.
  std::size_t outputBytes() const { return model->output_bytes; }
  std::size_t inputBytes() const { return model->input_bytes; }
  std::uint16_t outputsPhysical() const { return model->output_phys; }
  std::uint16_t inputsPhysical() const { return model->input_phys; }
  // A slave other than a servo writes its inputs into its RAM (a servo's drive does that).
  void updateTerminalInputs(std::int64_t now_ns);

  std::uint16_t station() const;
  bool processData() const;  // SAFE-OP or OP
  void publishAlStatus();
  // ESM-004: the slave comes up with an AL error left from its power-up.
  void powerUpError();
  // The slave leaves OP on its own for SAFE-OP with an AL error (the incidents scenario).
  void fallFromOp(std::uint16_t code);
  // In OP with the station address and FMMUs the master's start-up would have written (a
  // capture that begins with the segment running).
  void startInOp(std::uint16_t station);
  // Its mailbox configured as the start-up would have done (a capture without it).
  void startWithMailbox() { writeMailboxSyncManagers(&mem[ecat::kRegSyncManager0]); }
  // One datagram passing through, then (once per frame) the end of the frame.
  void process(RingDatagram& dg);
  void endOfFrame();

  // The mailbox, once the master configured SM0 and SM1 in mailbox mode: what it wrote into SM0
  // waits here for the drive; what the drive answers waits for the master's read of SM1, one
  // message per read (a read of an empty SM1 is not counted in the WKC).
  struct MailboxAnswer {
    std::vector<std::uint8_t> bytes;
    DriveSaid said;  // the truth of it
  };
  std::vector<std::vector<std::uint8_t>> mailbox_written;
  std::deque<MailboxAnswer> mailbox_answers;
  std::vector<MailboxAnswer> mailbox_taken;  // read by the master in the last frames
  // The error counters (0x0300-0x0313) and watchdog counters (0x0442-0x0443): each rises by one
  // and stays at 0xFF. `counted` keeps what rose since the last read of them, per counter and
  // port, the truth a read must show.
  void countError(diag::EscCounter counter, std::uint8_t port);
  std::array<std::array<std::uint32_t, ecat::kEscPorts>, diag::kEscCounters.size()> counted{};
  // Frames that came corrupted over the cable into port 0 since that read (a bad link's truth).
  std::uint32_t corrupted_frames = 0;
  // The sync manager watchdog (0x0420, 100 ms): in OP, outputs not written for longer expire it
  // once, until they come again. Before a frame passes (`processed` false) and after.
  void watchOutputs(std::int64_t now_ns, bool processed);
  // The system time difference (0x092C) the slave's DC unit shows, in ns.
  void setTimeDifference(std::int32_t ns);

 private:
  void onAlControl(std::uint16_t value);
  void readRegisters(RingDatagram& dg) const;
  void writeRegisters(const RingDatagram& dg);
  std::uint16_t logicalAccess(RingDatagram& dg);  // the WKC increment
  // The start of an SM configured in mailbox mode, if it is.
  std::optional<std::uint16_t> mailboxArea(std::size_t sm) const;
  bool mailboxAccess(RingDatagram& dg);  // a read or write of SM0/SM1; false: not the mailbox

  bool error_ = false;
  std::uint16_t code_ = 0;
  std::int64_t outputs_ns_ = -1;  // when outputs were last written
  bool watchdog_expired_ = false;
  std::uint8_t pending_ = 0;  // a state change under way
  int pending_frames_ = 0;
};

// The master's outputs for a slave other than a servo, this cycle.
void writeTerminalOutputs(const SlaveModel& model, std::uint64_t cycle, std::uint8_t* out);

// One logical datagram of the process image (docs/protocol.md §8): LRW, LWR or LRD.
struct ImageDatagram {
  std::uint8_t command = 0;
  std::uint32_t logical = 0;
  std::size_t size = 0;
};
// Where a logical address lies in a frame group: which datagram, how far into its data.
struct ImagePlace {
  std::size_t datagram = 0;
  std::size_t offset = 0;
};

struct FrameGroup {  // the slaves whose process data one cyclic frame carries
  std::vector<int> slaves;
  std::vector<ImageDatagram> datagrams;  // in frame order
  std::size_t bytes = 0;                 // the slaves' process data
  std::uint64_t every_cycles = 1;        // sent every this many cycles (a slower task's frame)
  std::optional<ImagePlace> place(std::uint32_t logical) const;
};

// The slaves in ring order, where their process data lies (docs/protocol.md §9.4's styles) and the
// cyclic datagrams that carry it. SOEM and EtherLab: servo 0, terminal 0, servo 1, terminal 1,
// ..., then the rest, the terminals 8-bit digital outputs and inputs in turn; mixed and TwinCAT:
// terminals of every model in kTerminalModels, drawn with the positions from the seed.
struct Segment {
  std::vector<Esc> escs;
  std::vector<int> servo_slave;  // axis -> ring position
  std::vector<FrameGroup> groups;
  ImageStyle style = ImageStyle::Soem;
  bool outputs_first = true;  // all outputs, then all inputs (else per slave)
  bool status_poll = false;   // the cycle's first frame also reads the AL status (BRD 0x0130)
  double dc_drift_ppm = 0;    // the reference clock's rate against the master's clock
  bool watchdogs = false;  // the ESCs count their SM watchdogs' expiries (--diagnosis reads them)

  Segment(const SimOptions& options, Rng& rng);
  // docs/protocol.md §8: what the slaves' FMMUs add to the WKC of a logical datagram.
  std::uint16_t expectedWkc(const ImageDatagram& dg) const;
  // How the slaves are laid out, for the layout file's header.
  std::string describe() const;
  Esc& servo(int axis) {
    return escs[static_cast<std::size_t>(servo_slave[static_cast<std::size_t>(axis)])];
  }
  std::vector<AxisConfig> axisLayout() const;
  // A frame round the ring at this time (since the Unix epoch). `corrupted_into`: the ring
  // position whose port 0 receives it corrupted (a bad link): the slaves from there on count it
  // and do not process it, and it does not come back. False when it does not come back.
  bool pass(std::vector<RingDatagram>& frame, std::int64_t now_ns,
            std::optional<std::size_t> corrupted_into = std::nullopt);
};

}  // namespace ncservo::sim
