#include "ncservo/model/al_tracker.hpp"

#include <fmt/format.h>

#include <array>
#include <utility>

namespace ncservo {

namespace {
using ecat::kAlBoot;
using ecat::kAlInit;
using ecat::kAlOp;
using ecat::kAlPreOp;
using ecat::kAlSafeOp;
using ecat::kAlStates;
using ecat::kRegAlControl;
using ecat::kRegAlStatus;
using ecat::kRegAlStatusCode;
using ecat::kRegStationAddress;

// docs/protocol.md §8: the requested transitions a slave accepts, besides staying where it is.
struct Transition {
  std::uint8_t from;
  std::uint8_t to;
};
constexpr std::array<Transition, 11> kTransitions{{
    {kAlInit, kAlPreOp},
    {kAlInit, kAlBoot},
    {kAlBoot, kAlInit},
    {kAlPreOp, kAlSafeOp},
    {kAlPreOp, kAlInit},
    {kAlSafeOp, kAlOp},
    {kAlSafeOp, kAlPreOp},
    {kAlSafeOp, kAlInit},
    {kAlOp, kAlSafeOp},
    {kAlOp, kAlPreOp},
    {kAlOp, kAlInit},
}};

constexpr bool isState(std::uint8_t state) {
  for (std::uint8_t s : kAlStates) {
    if (s == state) return true;
  }
  return false;
}

// Whether any register read or written here lies in the datagram's captured data.
constexpr std::uint16_t kFirstRegister = kRegStationAddress;
constexpr std::uint16_t kEndOfRegisters = kRegAlStatusCode + 2;
static_assert(kFirstRegister <= kRegAlControl && kRegAlControl < kEndOfRegisters &&
              kRegAlStatus < kEndOfRegisters);
bool reachesAlRegisters(const Datagram& dg) {
  return reachesRegisters(dg, kFirstRegister, kEndOfRegisters);
}

// The low byte of a register holds the state bits; the high byte is shown when captured.
std::optional<std::uint16_t> readStateRegister(const Datagram& dg, const ByteReader& bytes,
                                               std::uint16_t reg) {
  if (auto at = registerAt(dg, reg, 2)) return bytes.le16(*at);
  if (auto at = registerAt(dg, reg, 1)) {
    if (auto low = bytes.u8(*at)) return std::uint16_t{*low};
  }
  return std::nullopt;
}

}  // namespace

const char* alStateName(std::uint8_t state) {
  static constexpr std::array<const char*, 16> kNames{
      "0x0", "INIT", "PRE-OP", "BOOT", "SAFE-OP", "0x5", "0x6", "0x7",
      "OP",  "0x9",  "0xA",    "0xB",  "0xC",     "0xD", "0xE", "0xF"};
  return state < kNames.size() ? kNames[state] : "?";
}

bool alStateAboveInit(std::uint8_t state) {
  return isState(state) && state != kAlInit;
}

bool alTransitionAllowed(std::uint8_t from, std::uint8_t to) {
  if (!isState(from) || !isState(to)) return false;
  if (from == to) return true;
  for (const Transition& t : kTransitions) {
    if (t.from == from && t.to == to) return true;
  }
  return false;
}

std::string slaveName(const SlaveRef& slave) {
  if (slave.station && slave.position)
    return fmt::format("station 0x{:04X} (ring position {})", *slave.station, *slave.position);
  if (slave.station) return fmt::format("station 0x{:04X}", *slave.station);
  if (slave.position) return fmt::format("ring position {}", *slave.position);
  return "all slaves (broadcast)";
}

void AlTracker::AlData::absorb(const AlData& gone) {
  if (!state) state = gone.state;
  if (!requested) requested = gone.requested;
  if (!status_code) {
    status_code = gone.status_code;
    status_code_frame = gone.status_code_frame;
  }
  error_reported = error_reported || gone.error_reported;
  op_entries += gone.op_entries;
}

void AlTracker::fresh(AlData& data) const {
  // What the last broadcasts told every slave on the ring applies to one first seen now.
  data.state = state_all_;
  data.requested = requested_all_;
}

std::size_t AlTracker::slaveFor(const SlaveAddress& address) {
  return directory_.slaveFor(address, [this](AlData& data) { fresh(data); });
}

void AlTracker::onControlWrite(const SlaveAddress& address, std::uint8_t requested,
                               std::uint16_t raw, const Stamp& now, std::vector<BusEvent>& out) {
  auto write = [&](const std::optional<std::uint8_t>& known,
                   const std::optional<std::uint16_t>& station,
                   const std::optional<std::uint16_t>& position) {
    if (!known) return;  // docs/protocol.md §8: nothing that depends on an unknown state is checked
    out.push_back({now, AlControlEvent{SlaveRef{station, position}, raw, requested, *known}});
  };
  if (address.target == SlaveTarget::All) {
    requested_all_ = requested;
    if (directory_.slaves().empty()) write(state_all_, std::nullopt, std::nullopt);
    for (Slave& slave : directory_.slaves()) {
      write(slave.data.state, slave.station, slave.position);
      slave.data.requested = requested;
    }
    return;
  }
  const std::size_t i = slaveFor(address);
  if (i == directory_.kNone) return;
  Slave& slave = directory_.slaves()[i];
  write(slave.data.state, slave.station, slave.position);
  slave.data.requested = requested;
}

void AlTracker::setState(AlData& slave, std::uint8_t state) {
  const std::optional<std::uint8_t> previous = slave.state;
  if (isState(state)) {
    slave.state = state;
  } else {
    slave.state.reset();  // a slave that answers with a non-state: its state is not known
  }
  if (state == kAlOp && previous && *previous != kAlOp) ++slave.op_entries;
}

void AlTracker::onStatusRead(const SlaveAddress& address, std::uint16_t raw, const Stamp& now,
                             std::vector<BusEvent>& out) {
  const std::uint8_t state = raw & ecat::kAlStateMask;
  const bool error = (raw & ecat::kAlErrorBit) != 0;
  if (address.target == SlaveTarget::All) {
    // The OR of all slaves: a state only when they all agree; no error bit means none has one.
    if (isState(state)) {
      if (state == kAlOp && state_all_ && *state_all_ != kAlOp) ++op_entries_all_;
      state_all_ = state;
      for (Slave& slave : directory_.slaves()) setState(slave.data, state);
    }
    if (!error) {
      for (Slave& slave : directory_.slaves()) slave.data.error_reported = false;
    }
    return;
  }
  const std::size_t i = slaveFor(address);
  if (i == directory_.kNone) return;
  Slave& entry = directory_.slaves()[i];
  AlData& slave = entry.data;
  const std::optional<std::uint8_t> previous = slave.state;
  setState(slave, state);
  if (previous && isState(state) && (*previous == kAlOp) != (state == kAlOp)) {
    op_changes_.push_back(AlOpChange{SlaveRef{entry.station, entry.position}, *previous, state, raw,
                                     slave.status_code, slave.requested});
  }
  if (!error) {
    slave.error_reported = false;
    return;
  }
  if (slave.error_reported) return;
  slave.error_reported = true;
  out.push_back({now, AlErrorEvent{SlaveRef{entry.station, entry.position}, raw, slave.requested,
                                   previous, slave.status_code, slave.status_code_frame}});
}

void AlTracker::startSegment() {
  for (Slave& slave : directory_.slaves()) {
    slave.data.state.reset();
    slave.data.requested.reset();
    slave.data.status_code.reset();
    slave.data.status_code_frame = 0;
    slave.data.error_reported = false;
  }
  requested_all_.reset();
  state_all_.reset();
}

void AlTracker::onFrame(const EcatFrame& frame, const ByteReader& bytes, bool returned, bool paired,
                        const Stamp& now, std::vector<BusEvent>& out) {
  const bool walked = frame.status == WalkStatus::Ok || frame.status == WalkStatus::Truncated;
  if (!walked) {
    if (!op_changes_.empty()) op_changes_.clear();
    if (!code_reads_.empty()) code_reads_.clear();
    last_frame_registers_ = false;
    return;
  }
  addressing_.beginFrame(frame, returned, paired);
  onFrame(frame, bytes, addressing_, now, out);
}

void AlTracker::onFrame(const EcatFrame& frame, const ByteReader& bytes,
                        const FrameAddressing& addressing, const Stamp& now,
                        std::vector<BusEvent>& out) {
  if (!op_changes_.empty()) op_changes_.clear();
  if (!code_reads_.empty()) code_reads_.clear();
  const std::size_t count = frame.count;
  // Writes from the master's copy, or from a returned copy whose master copy was not captured;
  // reads from a returned copy, of datagrams that some slave answered. A frame whose datagrams
  // reach none of these registers (the cyclic process data, the DC time) has nothing for the
  // state machines, nor has one that reaches them with neither: a master copy's reads, say.
  const bool take_writes = addressing.takesWrites();
  bool registers = false;
  bool taken = false;
  for (std::size_t i = 0; i < count; ++i) {
    const Datagram& dg = frame.datagrams[i];
    if (!reachesAlRegisters(dg)) continue;
    registers = true;
    if ((take_writes && ecat::writesRegisters(dg.command)) || addressing.takesRead(dg)) {
      taken = true;
      break;
    }
  }
  last_frame_registers_ = registers;
  if (!taken) return;

  // First station addresses and AL status codes, so that the rest of the frame can use them.
  for (std::size_t i = 0; i < count; ++i) {
    const Datagram& dg = frame.datagrams[i];
    const SlaveAddress address = addressing.addressOf(dg, i);
    const bool read = addressing.takesRead(dg);
    if (take_writes && ecat::writesRegisters(dg.command)) {
      directory_.noteStationWrite(dg, bytes, address, [this](AlData& data) { fresh(data); });
      directory_.noteAlias(dg, bytes, address);
    }
    if (read) directory_.noteAlias(dg, bytes, address);
    if (read &&
        (address.target == SlaveTarget::Station || address.target == SlaveTarget::Position)) {
      if (auto at = registerAt(dg, kRegAlStatusCode, 2)) {
        auto code = bytes.le16(*at);
        const std::size_t s = code ? slaveFor(address) : directory_.kNone;
        if (s != directory_.kNone) {
          Slave& entry = directory_.slaves()[s];
          entry.data.status_code = *code;
          entry.data.status_code_frame = now.frame;
          code_reads_.push_back(AlCodeRead{SlaveRef{entry.station, entry.position}, *code});
        }
      }
    }
  }
  // Then AL control writes and AL status reads, in the order of the datagrams.
  for (std::size_t i = 0; i < count; ++i) {
    const Datagram& dg = frame.datagrams[i];
    const SlaveAddress address = addressing.addressOf(dg, i);
    if (address.target == SlaveTarget::None) continue;
    if (take_writes && ecat::writesRegisters(dg.command)) {
      if (auto raw = readStateRegister(dg, bytes, kRegAlControl)) {
        onControlWrite(address, *raw & ecat::kAlStateMask, *raw, now, out);
      }
    }
    if (addressing.takesRead(dg)) {
      if (auto raw = readStateRegister(dg, bytes, kRegAlStatus)) {
        onStatusRead(address, *raw, now, out);
      }
    }
  }
}

std::optional<std::uint8_t> AlTracker::stateOfStation(std::uint16_t station) const {
  const std::size_t i = directory_.findStation(station);
  return i == directory_.kNone ? state_all_ : directory_.slaves()[i].data.state;
}

std::uint32_t AlTracker::opEntries(std::uint16_t station) const {
  const std::size_t i = directory_.findStation(station);
  return i == directory_.kNone ? op_entries_all_ : directory_.slaves()[i].data.op_entries;
}

}  // namespace ncservo
