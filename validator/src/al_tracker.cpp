#include "ncservo/al_tracker.hpp"

#include <fmt/format.h>

#include <array>
#include <utility>

namespace ncservo {

namespace {
// ESC registers (PROTOCOL.md §8).
constexpr std::uint16_t kRegStationAddress = 0x0010;
constexpr std::uint16_t kRegAlControl = 0x0120;
constexpr std::uint16_t kRegAlStatus = 0x0130;
constexpr std::uint16_t kRegAlStatusCode = 0x0134;
constexpr std::uint8_t kStateMask = 0x0F;
constexpr std::uint8_t kErrorBit = 0x10;  // error indicator in AL status, acknowledge in AL control

constexpr std::uint8_t kInit = static_cast<std::uint8_t>(AlState::Init);
constexpr std::uint8_t kPreOp = static_cast<std::uint8_t>(AlState::PreOp);
constexpr std::uint8_t kBoot = static_cast<std::uint8_t>(AlState::Boot);
constexpr std::uint8_t kSafeOp = static_cast<std::uint8_t>(AlState::SafeOp);
constexpr std::uint8_t kOp = static_cast<std::uint8_t>(AlState::Op);
constexpr std::array<std::uint8_t, 5> kStates{kInit, kPreOp, kBoot, kSafeOp, kOp};

// PROTOCOL.md §8: the requested transitions a slave accepts, besides staying where it is.
struct Transition {
  std::uint8_t from;
  std::uint8_t to;
};
constexpr std::array<Transition, 11> kTransitions{{
    {kInit, kPreOp},
    {kInit, kBoot},
    {kBoot, kInit},
    {kPreOp, kSafeOp},
    {kPreOp, kInit},
    {kSafeOp, kOp},
    {kSafeOp, kPreOp},
    {kSafeOp, kInit},
    {kOp, kSafeOp},
    {kOp, kPreOp},
    {kOp, kInit},
}};

constexpr bool isState(std::uint8_t state) {
  for (std::uint8_t s : kStates) {
    if (s == state) return true;
  }
  return false;
}
constexpr bool aboveInit(std::uint8_t state) {
  return isState(state) && state != kInit;
}

// Commands whose data the slaves write into (AL status is read by these) and commands whose data
// the slaves take (AL control and the station address are written by these).
// Register access reaches slaves through the physical commands, not the logical ones.
constexpr bool readsSlave(std::uint8_t cmd) {
  return ecat::readsSlaves(cmd) && !ecat::isLogical(cmd);
}
constexpr bool writesSlave(std::uint8_t cmd) {
  return ecat::writesSlaves(cmd) && !ecat::isLogical(cmd);
}
constexpr bool isAutoIncrement(std::uint8_t cmd) {
  return cmd == ecat::kAprd || cmd == ecat::kApwr || cmd == ecat::kAprw || cmd == ecat::kArmw;
}
constexpr bool isBroadcast(std::uint8_t cmd) {
  return cmd == ecat::kBrd || cmd == ecat::kBwr || cmd == ecat::kBrw;
}

// Offset in the captured bytes of register `reg` when the datagram's captured data holds all
// `size` bytes of it (ADO <= reg and reg + size <= ADO + data_captured).
std::optional<std::size_t> registerAt(const Datagram& dg, std::uint16_t reg, std::size_t size) {
  const std::uint16_t ado = dg.ado();
  if (ado > reg) return std::nullopt;
  const std::size_t relative = std::size_t{reg} - ado;
  if (relative + size > dg.data_captured) return std::nullopt;
  return dg.data_offset + relative;
}

// Whether any register read or written here lies in the datagram's captured data. Logical
// commands do not address registers.
constexpr std::uint16_t kFirstRegister = kRegStationAddress;
constexpr std::uint16_t kEndOfRegisters = kRegAlStatusCode + 2;
static_assert(kFirstRegister <= kRegAlControl && kRegAlControl < kEndOfRegisters &&
              kRegAlStatus < kEndOfRegisters);
bool reachesAlRegisters(const Datagram& dg) {
  if (ecat::isLogical(dg.command)) return false;
  const std::size_t ado = dg.ado();
  return ado < kEndOfRegisters && ado + dg.data_captured > kFirstRegister;
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

std::string allowedFrom(std::uint8_t from) {
  std::string out;
  for (std::uint8_t to : kStates) {
    if (!alTransitionAllowed(from, to)) continue;
    if (!out.empty()) out += ", ";
    out += alStateName(to);
  }
  return out;
}
}  // namespace

const char* alStateName(std::uint8_t state) {
  static constexpr std::array<const char*, 16> kNames{
      "0x0", "INIT", "PRE-OP", "BOOT", "SAFE-OP", "0x5", "0x6", "0x7",
      "OP",  "0x9",  "0xA",    "0xB",  "0xC",     "0xD", "0xE", "0xF"};
  return state < kNames.size() ? kNames[state] : "?";
}

bool alTransitionAllowed(std::uint8_t from, std::uint8_t to) {
  if (!isState(from) || !isState(to)) return false;
  if (from == to) return true;
  for (const Transition& t : kTransitions) {
    if (t.from == from && t.to == to) return true;
  }
  return false;
}

namespace {
std::string slaveName(const std::optional<std::uint16_t>& station,
                      const std::optional<std::uint16_t>& position) {
  if (station && position)
    return fmt::format("station 0x{:04X} (ring position {})", *station, *position);
  if (station) return fmt::format("station 0x{:04X}", *station);
  if (position) return fmt::format("ring position {}", *position);
  return "all slaves (broadcast)";
}
}  // namespace

AlTracker::Address AlTracker::addressOf(const Datagram& dg, std::size_t index, bool returned,
                                        bool paired) const {
  if (ecat::isConfiguredAddress(dg.command)) return {Target::Station, dg.adp()};
  if (isBroadcast(dg.command)) return {Target::All, 0};
  if (!isAutoIncrement(dg.command)) return {};
  std::uint16_t adp = dg.adp();
  if (returned) {
    // Every slave has incremented the returned ADP: only the master's copy says whom it meant.
    if (!paired || index >= master_.size() || master_[index].command != dg.command) return {};
    adp = master_[index].adp;
  }
  return {Target::Position, static_cast<std::uint16_t>((0x10000u - adp) & 0xFFFFu)};
}

std::size_t AlTracker::findStation(std::uint16_t station) const {
  for (std::size_t i = 0; i < slaves_.size(); ++i) {
    if (slaves_[i].station == station) return i;
  }
  return kNone;
}

std::size_t AlTracker::findPosition(std::uint16_t position) const {
  for (std::size_t i = 0; i < slaves_.size(); ++i) {
    if (slaves_[i].position == position) return i;
  }
  return kNone;
}

std::size_t AlTracker::addSlave() {
  if (slaves_.size() >= kMaxSlaves) return kNone;
  Slave slave;
  // What the last broadcasts told every slave on the ring applies to one first seen now.
  slave.state = state_all_;
  slave.requested = requested_all_;
  slaves_.push_back(slave);
  return slaves_.size() - 1;
}

std::size_t AlTracker::slaveFor(const Address& address) {
  std::size_t i = kNone;
  switch (address.target) {
    case Target::Station:
      i = findStation(address.value);
      if (i == kNone && (i = addSlave()) != kNone) slaves_[i].station = address.value;
      break;
    case Target::Position:
      i = findPosition(address.value);
      if (i == kNone && (i = addSlave()) != kNone) slaves_[i].position = address.value;
      break;
    case Target::None:
    case Target::All:
      break;
  }
  return i;
}

void AlTracker::assignStation(std::uint16_t position, std::uint16_t station) {
  std::size_t at = findPosition(position);
  std::size_t named = findStation(station);
  if (at != kNone && at == named) return;
  if (named != kNone && slaves_[named].position) {
    // The address moves to another slave: the old holder keeps only its position.
    slaves_[named].station.reset();
    named = kNone;
  }
  if (at == kNone && named == kNone) {
    at = addSlave();
    if (at == kNone) return;
    slaves_[at].position = position;
  } else if (at == kNone) {
    slaves_[named].position = position;
    return;
  } else if (named != kNone) {
    // The same slave was seen by station before the assignment: one record keeps what both knew.
    Slave& keep = slaves_[at];
    const Slave& gone = slaves_[named];
    if (!keep.state) keep.state = gone.state;
    if (!keep.requested) keep.requested = gone.requested;
    if (!keep.status_code) {
      keep.status_code = gone.status_code;
      keep.status_code_frame = gone.status_code_frame;
    }
    keep.error_reported = keep.error_reported || gone.error_reported;
    keep.entered_op = keep.entered_op || gone.entered_op;
    slaves_.erase(slaves_.begin() + static_cast<std::ptrdiff_t>(named));
    if (named < at) --at;
  }
  slaves_[at].station = station;
}

void AlTracker::onControlWrite(const Address& address, std::uint8_t requested, std::uint16_t raw,
                               std::vector<AlFinding>& out) {
  auto check = [&](const std::optional<std::uint8_t>& known,
                   const std::optional<std::uint16_t>& station,
                   const std::optional<std::uint16_t>& position) {
    if (!known || alTransitionAllowed(*known, requested)) return;
    out.push_back({RuleId::Esm001, station, position,
                   fmt::format("{}: AL control 0x{:04X} requests {} from known state {}; "
                               "allowed: {}",
                               slaveName(station, position), raw, alStateName(requested),
                               alStateName(*known), allowedFrom(*known))});
  };
  if (address.target == Target::All) {
    requested_all_ = requested;
    if (slaves_.empty()) check(state_all_, std::nullopt, std::nullopt);
    for (Slave& slave : slaves_) {
      check(slave.state, slave.station, slave.position);
      slave.requested = requested;
    }
    return;
  }
  const std::size_t i = slaveFor(address);
  if (i == kNone) return;
  Slave& slave = slaves_[i];
  check(slave.state, slave.station, slave.position);
  slave.requested = requested;
}

void AlTracker::setState(Slave& slave, std::uint8_t state) {
  const std::optional<std::uint8_t> previous = slave.state;
  if (isState(state)) {
    slave.state = state;
  } else {
    slave.state.reset();  // a slave that answers with a non-state: its state is not known
  }
  if (state == kOp && previous && *previous != kOp) {
    slave.entered_op = true;
    any_entered_op_ = true;
  }
}

void AlTracker::onStatusRead(const Address& address, std::uint16_t raw, const Stamp& now,
                             std::vector<AlFinding>& out) {
  const std::uint8_t state = raw & kStateMask;
  const bool error = (raw & kErrorBit) != 0;
  if (address.target == Target::All) {
    // The OR of all slaves: a state only when they all agree; no error bit means none has one.
    if (isState(state)) {
      if (state == kOp && state_all_ && *state_all_ != kOp) entered_op_all_ = true;
      state_all_ = state;
      for (Slave& slave : slaves_) setState(slave, state);
    }
    if (!error) {
      for (Slave& slave : slaves_) slave.error_reported = false;
    }
    return;
  }
  const std::size_t i = slaveFor(address);
  if (i == kNone) return;
  Slave& slave = slaves_[i];
  const std::optional<std::uint8_t> previous = slave.state;
  setState(slave, state);
  if (!error) {
    slave.error_reported = false;
    return;
  }
  if (slave.error_reported) return;
  slave.error_reported = true;

  RuleId rule = RuleId::Esm004;
  std::string context;
  if (slave.requested) {
    if (aboveInit(*slave.requested)) rule = RuleId::Esm003;
    context = fmt::format("while {} requested", alStateName(*slave.requested));
  } else if (previous) {
    if (aboveInit(*previous)) rule = RuleId::Esm003;
    context = fmt::format("with no request seen, previous state {}", alStateName(*previous));
  } else {
    context = "with no request seen and no previous state";
  }
  std::string code;
  if (slave.status_code) {
    code = fmt::format("; AL status code 0x{:04X}", *slave.status_code);
    if (slave.status_code_frame != now.frame) {
      code += fmt::format(" (read in frame {})", slave.status_code_frame);
    }
  } else {
    code = "; AL status code not read";
  }
  out.push_back({rule, slave.station, slave.position,
                 fmt::format("{}: AL status 0x{:04X} ({} + error) {}{}",
                             slaveName(slave.station, slave.position), raw, alStateName(state),
                             context, code)});
}

void AlTracker::onFrame(const EcatFrame& frame, const ByteReader& bytes, bool returned, bool paired,
                        const Stamp& now, std::vector<AlFinding>& out) {
  if (any_entered_op_) {
    for (Slave& slave : slaves_) slave.entered_op = false;
    any_entered_op_ = false;
  }
  entered_op_all_ = false;
  const bool walked = frame.status == WalkStatus::Ok || frame.status == WalkStatus::Truncated;
  const std::size_t count = walked ? frame.count : 0;
  if (!returned) {
    master_.clear();
    for (std::size_t i = 0; i < count; ++i) {
      master_.push_back({frame.datagrams[i].command, frame.datagrams[i].adp()});
    }
  }
  // A frame whose datagrams reach none of these registers (the cyclic process data, the DC
  // time) has nothing for the state machines.
  bool registers = false;
  for (std::size_t i = 0; i < count && !registers; ++i)
    registers = reachesAlRegisters(frame.datagrams[i]);
  if (!registers) return;

  // Writes from the master's copy, or from a returned copy whose master copy was not captured;
  // reads from a returned copy, of datagrams that some slave answered.
  const bool take_writes = !returned || !paired;
  auto takeRead = [returned](const Datagram& dg) {
    return returned && readsSlave(dg.command) && dg.has_wkc && dg.wkc > 0;
  };

  // First station addresses and AL status codes, so that the rest of the frame can use them.
  for (std::size_t i = 0; i < count; ++i) {
    const Datagram& dg = frame.datagrams[i];
    const Address address = addressOf(dg, i, returned, paired);
    if (take_writes && writesSlave(dg.command) && address.target == Target::Position) {
      if (auto at = registerAt(dg, kRegStationAddress, 2)) {
        if (auto station = bytes.le16(*at)) assignStation(address.value, *station);
      }
    }
    if (takeRead(dg) && (address.target == Target::Station || address.target == Target::Position)) {
      if (auto at = registerAt(dg, kRegAlStatusCode, 2)) {
        auto code = bytes.le16(*at);
        const std::size_t s = code ? slaveFor(address) : kNone;
        if (s != kNone) {
          slaves_[s].status_code = *code;
          slaves_[s].status_code_frame = now.frame;
        }
      }
    }
  }
  // Then AL control writes and AL status reads, in the order of the datagrams.
  for (std::size_t i = 0; i < count; ++i) {
    const Datagram& dg = frame.datagrams[i];
    const Address address = addressOf(dg, i, returned, paired);
    if (address.target == Target::None) continue;
    if (take_writes && writesSlave(dg.command)) {
      if (auto raw = readStateRegister(dg, bytes, kRegAlControl)) {
        onControlWrite(address, *raw & kStateMask, *raw, out);
      }
    }
    if (takeRead(dg)) {
      if (auto raw = readStateRegister(dg, bytes, kRegAlStatus)) {
        onStatusRead(address, *raw, now, out);
      }
    }
  }
}

std::optional<std::uint8_t> AlTracker::stateOfStation(std::uint16_t station) const {
  const std::size_t i = findStation(station);
  return i == kNone ? state_all_ : slaves_[i].state;
}

bool AlTracker::enteredOp(std::uint16_t station) const {
  const std::size_t i = findStation(station);
  return i == kNone ? entered_op_all_ : slaves_[i].entered_op;
}

}  // namespace ncservo
