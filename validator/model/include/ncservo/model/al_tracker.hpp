// Each slave's EtherCAT state machine as a capture shows it (docs/protocol.md §8): station
// addresses assigned by the start-up, AL control writes (0x0120), AL status reads (0x0130) and AL
// status codes (0x0134). Gives the events rules ESM-001, ESM-003 and ESM-004 judge. Bounded memory.
//
// A slave is known by its station address (FP commands), its ring position (AP commands, from the
// master's copy's ADP) or both, once an APWR/APRW of 0x0010 has assigned the one to the other.
// Station aliases (0x0012) are not used as addresses: an alias addresses a slave only when its DL
// control enables it, which the capture rarely shows. A broadcast AL control write that a slave's
// known state does not allow is reported once per such slave, each finding naming its slave. An
// AL status BRD with the error indicator is not reported: the OR of all slaves names none of them.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/model/bus_events.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "ncservo/wire/slave_directory.hpp"

namespace ncservo {

// AL states (ecat::AlState, docs/protocol.md §8) by name, and the transitions a slave accepts.
const char* alStateName(std::uint8_t state);  // "INIT", ..., or "0x5" for a non-state
bool alTransitionAllowed(std::uint8_t from, std::uint8_t to);
bool alStateAboveInit(std::uint8_t state);  // a state, and not INIT
// "station 0x1001 (ring position 0)", "ring position 2", "all slaves (broadcast)".
std::string slaveName(const SlaveRef& slave);

// A slave's AL state moving into or out of OP, seen in an AL status read of that slave
// (docs/incidents.md: an ESM incident begins where it leaves OP and ends where it is back).
struct AlOpChange {
  SlaveRef slave;
  std::uint8_t from = 0;
  std::uint8_t to = 0;
  std::uint16_t raw = 0;  // the AL status read
  std::optional<std::uint16_t> status_code;
  std::optional<std::uint8_t> requested;  // the last AL control request to it or to all
};

// An AL status code (0x0134) read of one slave (docs/incidents.md#sync-error).
struct AlCodeRead {
  SlaveRef slave;
  std::uint16_t code = 0;
};

class AlTracker {
 public:
  static constexpr std::size_t kMaxSlaves = SlaveDirectory<int>::kMaxSlaves;

  // Every EtherCAT frame, in capture order. `paired`: a returned copy whose master's copy was
  // the frame just before (its auto-increment addresses can then be taken from the master's copy).
  // Writes (AL control, station address) are taken from master copies, and from returned copies
  // whose master copy was not captured; reads from returned copies whose WKC is above zero.
  void onFrame(const EcatFrame& frame, const ByteReader& bytes, bool returned, bool paired,
               const Stamp& now, std::vector<BusEvent>& out);
  // The same, with the frame's addressing worked out once for every tracker (Ok or Truncated
  // frames only, `addressing.beginFrame` called for each of them).
  void onFrame(const EcatFrame& frame, const ByteReader& bytes, const FrameAddressing& addressing,
               const Stamp& now, std::vector<BusEvent>& out);

  // A capture segment starts (capture_segments.hpp): what was requested of the slaves and the
  // states they showed are not known any more, as in a capture that began mid-operation; their
  // addresses carry on.
  void startSegment();

  // The slave's known AL state (its last AL status read), if any. A station the tracker has not
  // seen addressed has the state of the last BRD of AL status that returned a state, if any.
  std::optional<std::uint8_t> stateOfStation(std::uint16_t station) const;
  // How often the slave with this station address entered OP so far — its known state went from
  // another known state to OP. A change since an earlier call means it entered OP in between,
  // whichever frame showed it.
  std::uint32_t opEntries(std::uint16_t station) const;
  // Whether the last frame given reached AL registers: only such a frame changes a state.
  bool lastFrameReachedRegisters() const { return last_frame_registers_; }
  // The slaves whose read state left or entered OP in the last frame given (reads of one slave
  // only: a broadcast's OR names none).
  const std::vector<AlOpChange>& opChanges() const { return op_changes_; }
  // The AL status codes read of single slaves in the last frame given.
  const std::vector<AlCodeRead>& codeReads() const { return code_reads_; }

 private:
  // What the capture showed of one slave's state machine.
  struct AlData {
    std::optional<std::uint8_t> state;      // last AL status read (bits 3..0)
    std::optional<std::uint8_t> requested;  // last AL control write to it or to all (bits 3..0)
    std::optional<std::uint16_t> status_code;
    std::uint64_t status_code_frame = 0;  // where the status code was read
    bool error_reported = false;          // once per episode of the error indicator
    std::uint32_t op_entries = 0;
    void absorb(const AlData& other);  // one slave seen by station before its assignment
  };
  using Slave = SlaveDirectory<AlData>::Slave;

  std::size_t slaveFor(const SlaveAddress& address);  // finds or adds; kNone for none
  void fresh(AlData& data) const;                     // what the last broadcasts told every slave
  void onControlWrite(const SlaveAddress& address, std::uint8_t requested, std::uint16_t raw,
                      const Stamp& now, std::vector<BusEvent>& out);
  void onStatusRead(const SlaveAddress& address, std::uint16_t raw, const Stamp& now,
                    std::vector<BusEvent>& out);
  void setState(AlData& slave, std::uint8_t state);

  SlaveDirectory<AlData> directory_;
  FrameAddressing addressing_;                 // for frames given with `returned` and `paired`
  std::optional<std::uint8_t> requested_all_;  // last broadcast AL control request
  std::optional<std::uint8_t> state_all_;      // last BRD of AL status that was a state
  std::uint32_t op_entries_all_ = 0;           // times state_all_ became OP
  bool last_frame_registers_ = false;
  std::vector<AlOpChange> op_changes_;  // the last frame's
  std::vector<AlCodeRead> code_reads_;  // the last frame's
};

}  // namespace ncservo
