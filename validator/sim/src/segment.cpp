#include "segment.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>

#include "le_bytes.hpp"
#include "ncservo/ethercat.hpp"
#include "ncservo/pdo_layout.hpp"

namespace ncservo::sim {
namespace {

constexpr auto kSafeOp = ecat::kAlSafeOp;
constexpr auto kOp = ecat::kAlOp;
constexpr std::uint8_t kEscTypeValue = 0x11;
// AL status codes (register 0x0134, ETG.1000.6).
constexpr std::uint16_t kCodeInvalidTransition = 0x0011;  // invalid requested state change
constexpr std::uint16_t kCodeInvalidOutputs = 0x001D;     // invalid output configuration
constexpr std::uint16_t kCodePowerUp = 0x0050;            // EEPROM no access (left from power-up)
constexpr std::size_t kAlStatusRegisters = 6;             // AL status to AL status code: read-only
constexpr std::size_t kActiveFmmus = 3;

// Process RAM of the slaves.
constexpr std::uint16_t kServoRxPhys = 0x1100;
constexpr std::uint16_t kServoTxPhys = 0x1180;
constexpr std::uint16_t kOutTerminalPhys = 0x0F00;
constexpr std::uint16_t kInTerminalPhys = 0x1000;
// The master's process image: one region per cyclic frame.
constexpr std::uint32_t kLogicalBase = 0x00010000;
constexpr std::uint32_t kLogicalFrameStride = 0x1000;
constexpr std::size_t kMaxLrwData = 1450;  // 29 axes of 50 bytes (PROTOCOL.md §9.4)
constexpr int kMaxServosPerFrame = 29;

}  // namespace

// --- one ESC ---

std::size_t Esc::outputBytes() const {
  return kind == SlaveKind::Servo ? kRxPdoSize : kind == SlaveKind::OutputTerminal ? 1 : 0;
}
std::size_t Esc::inputBytes() const {
  return kind == SlaveKind::Servo ? kTxPdoSize : kind == SlaveKind::InputTerminal ? 1 : 0;
}
std::uint16_t Esc::outputsPhysical() const {
  return kind == SlaveKind::Servo ? kServoRxPhys : kOutTerminalPhys;
}
std::uint16_t Esc::inputsPhysical() const {
  return kind == SlaveKind::Servo ? kServoTxPhys : kInTerminalPhys;
}

std::uint16_t Esc::station() const {
  return static_cast<std::uint16_t>(getLe(&mem[ecat::kRegStationAddress], 2));
}
bool Esc::processData() const {
  return state == kSafeOp || state == kOp;
}
void Esc::publishAlStatus() {
  putLe(&mem[ecat::kRegAlStatus],
        static_cast<std::uint16_t>(state | (error_ ? ecat::kAlErrorBit : 0)), 2);
  putLe(&mem[ecat::kRegAlStatusCode], code_, 2);
}
void Esc::powerUpError() {
  error_ = true;
  code_ = kCodePowerUp;
  publishAlStatus();
}

void Esc::startInOp(std::uint16_t station_address) {
  state = kOp;
  publishAlStatus();
  putLe(&mem[ecat::kRegStationAddress], station_address, 2);
  std::size_t f = 0;
  auto fmmu = [&](std::uint32_t logical, std::size_t length, std::uint16_t phys,
                  std::uint8_t type) {
    std::uint8_t* p = &mem[ecat::kRegFmmu0 + ecat::kFmmuStride * f++];
    putLe(p + ecat::kFmmuLogicalAt, logical, 4);
    putLe(p + ecat::kFmmuLengthAt, length, 2);
    p[ecat::kFmmuStopBitAt] = 7;
    putLe(p + ecat::kFmmuPhysicalAt, phys, 2);
    p[ecat::kFmmuTypeAt] = type;
    p[ecat::kFmmuActivateAt] = 1;
  };
  if (outputBytes() > 0) {
    fmmu(outputs_logical, outputBytes(), outputsPhysical(), ecat::kFmmuWrite);
  }
  if (inputBytes() > 0) fmmu(inputs_logical, inputBytes(), inputsPhysical(), ecat::kFmmuRead);
}

void Esc::onAlControl(std::uint16_t value) {
  const auto requested = static_cast<std::uint8_t>(value & ecat::kAlStateMask);
  if (error_) {
    if ((value & ecat::kAlErrorBit) == 0) return;  // an error must be acknowledged first
    error_ = false;
    code_ = 0;
  }
  pending_ = 0;
  if (requested == state) {
    publishAlStatus();
    return;
  }
  const bool allowed = alTransitionAllowed(state, requested);  // PROTOCOL.md §8
  if (!allowed || (requested == kOp && refuse_next_op)) {
    if (requested == kOp && refuse_next_op && allowed) {
      refuse_next_op = false;
      code_ = kCodeInvalidOutputs;
    } else {
      code_ = kCodeInvalidTransition;
    }
    error_ = true;
  } else {
    pending_ = requested;
    pending_frames_ = transition_frames;
  }
  publishAlStatus();
}

void Esc::endOfFrame() {
  skip_next_lrw = false;
  if (pending_ != 0 && --pending_frames_ <= 0) {
    state = pending_;
    pending_ = 0;
    publishAlStatus();
  }
}

void Esc::readRegisters(RingDatagram& dg) const {
  for (std::size_t i = 0; i < dg.data.size(); ++i) {
    const std::size_t reg = dg.ado + i;
    dg.data[i] = reg < kEscMemory ? mem[reg] : 0;
  }
}
void Esc::writeRegisters(const RingDatagram& dg) {
  for (std::size_t i = 0; i < dg.data.size(); ++i) {
    const std::size_t reg = dg.ado + i;
    if (reg >= kEscMemory ||
        (reg >= ecat::kRegAlStatus && reg < ecat::kRegAlStatus + kAlStatusRegisters)) {
      continue;
    }
    mem[reg] = dg.data[i];
  }
  if (dg.ado <= ecat::kRegAlControl && dg.ado + dg.data.size() >= ecat::kRegAlControl + 2u) {
    onAlControl(static_cast<std::uint16_t>(getLe(&mem[ecat::kRegAlControl], 2)));
  }
}

std::uint16_t Esc::logicalAccess(RingDatagram& dg) {
  if (!processData() || (skip_next_lrw && dg.command == ecat::kLrw)) return 0;
  bool read = false, wrote = false;
  const std::uint64_t start = dg.logical();
  const std::uint64_t end = start + dg.data.size();
  for (std::size_t f = 0; f < kActiveFmmus; ++f) {
    const std::uint8_t* fmmu = &mem[ecat::kRegFmmu0 + ecat::kFmmuStride * f];
    if ((fmmu[ecat::kFmmuActivateAt] & 1) == 0) continue;
    const std::uint64_t lstart = getLe(fmmu + ecat::kFmmuLogicalAt, 4);
    const std::uint64_t lend = lstart + getLe(fmmu + ecat::kFmmuLengthAt, 2);
    const std::uint64_t from = std::max(start, lstart), to = std::min(end, lend);
    if (from >= to) continue;
    const std::size_t phys = getLe(fmmu + ecat::kFmmuPhysicalAt, 2) + (from - lstart);
    const std::size_t offset = from - start;
    const std::size_t count = to - from;
    if (phys + count > kEscMemory) continue;
    const std::uint8_t type = fmmu[ecat::kFmmuTypeAt];
    if (type == ecat::kFmmuRead && ecat::readsSlaves(dg.command)) {
      std::memcpy(&dg.data[offset], &mem[phys], count);
      read = true;
    } else if (type == ecat::kFmmuWrite && ecat::writesSlaves(dg.command)) {
      std::memcpy(&mem[phys], &dg.data[offset], count);
      wrote = true;
      outputs_taken = true;
    }
  }
  if (dg.command == ecat::kLrw) return static_cast<std::uint16_t>((read ? 1 : 0) + (wrote ? 2 : 0));
  return static_cast<std::uint16_t>(read || wrote ? 1 : 0);
}

void Esc::process(RingDatagram& dg) {
  switch (dg.command) {
    case ecat::kAprd:
    case ecat::kApwr:
      if (dg.adp == 0) {
        if (dg.command == ecat::kAprd)
          readRegisters(dg);
        else
          writeRegisters(dg);
        ++dg.wkc;
      }
      ++dg.adp;
      break;
    case ecat::kFprd:
    case ecat::kFpwr:
      if (dg.adp == station()) {
        if (dg.command == ecat::kFprd)
          readRegisters(dg);
        else
          writeRegisters(dg);
        ++dg.wkc;
      }
      break;
    case ecat::kBrd:
      for (std::size_t i = 0; i < dg.data.size(); ++i) {
        const std::size_t reg = dg.ado + i;
        dg.data[i] |= reg < kEscMemory ? mem[reg] : 0;
      }
      ++dg.wkc;
      ++dg.adp;
      break;
    case ecat::kBwr:
      writeRegisters(dg);
      ++dg.wkc;
      ++dg.adp;
      break;
    case ecat::kFrmw:
      if (dg.adp == station())
        readRegisters(dg);
      else
        writeRegisters(dg);
      ++dg.wkc;
      break;
    case ecat::kLrd:
    case ecat::kLwr:
    case ecat::kLrw:
      dg.wkc = static_cast<std::uint16_t>(dg.wkc + logicalAccess(dg));
      break;
    default:
      break;
  }
}

// --- the segment ---

Segment::Segment(const SimOptions& o, Rng& rng) {
  const int total = o.axes + o.io_slaves;
  int servo_count = 0, terminal = 0;
  for (int pos = 0; pos < total; ++pos) {
    Esc esc;
    const bool take_servo =
        servo_count < o.axes && (terminal >= o.io_slaves || servo_count <= terminal);
    if (take_servo) {
      esc.kind = SlaveKind::Servo;
      esc.axis = servo_count++;
      servo_slave.push_back(pos);
    } else {
      esc.kind = terminal % 2 == 0 ? SlaveKind::OutputTerminal : SlaveKind::InputTerminal;
      ++terminal;
    }
    esc.mem[ecat::kRegType] = kEscTypeValue;
    esc.transition_frames = static_cast<int>(rng.between(1, 3));
    esc.publishAlStatus();
    escs.push_back(std::move(esc));
  }
  // Frames: at most 29 servos and 1450 bytes of process data each.
  FrameGroup group;
  int servos_in_group = 0;
  for (int pos = 0; pos < total; ++pos) {
    const Esc& esc = escs[static_cast<std::size_t>(pos)];
    const std::size_t need = esc.outputBytes() + esc.inputBytes();
    const bool is_servo = esc.kind == SlaveKind::Servo;
    if (!group.slaves.empty() &&
        (group.size + need > kMaxLrwData || (is_servo && servos_in_group == kMaxServosPerFrame))) {
      groups.push_back(std::move(group));
      group = FrameGroup{};
      servos_in_group = 0;
    }
    group.slaves.push_back(pos);
    group.size += need;
    if (is_servo) ++servos_in_group;
  }
  groups.push_back(std::move(group));
  // Logical addresses of each slave's outputs and inputs.
  for (std::size_t g = 0; g < groups.size(); ++g) {
    FrameGroup& fg = groups[g];
    fg.base = kLogicalBase + static_cast<std::uint32_t>(g) * kLogicalFrameStride;
    std::uint32_t cursor = fg.base;
    auto place = [&](std::uint32_t& address, std::size_t bytes) {
      address = cursor;
      cursor += static_cast<std::uint32_t>(bytes);
    };
    if (o.layout == LayoutKind::Default) {
      for (int pos : fg.slaves) {
        Esc& esc = escs[static_cast<std::size_t>(pos)];
        place(esc.outputs_logical, esc.outputBytes());
      }
      for (int pos : fg.slaves) {
        Esc& esc = escs[static_cast<std::size_t>(pos)];
        place(esc.inputs_logical, esc.inputBytes());
      }
    } else {
      for (int pos : fg.slaves) {
        Esc& esc = escs[static_cast<std::size_t>(pos)];
        place(esc.outputs_logical, esc.outputBytes());
        place(esc.inputs_logical, esc.inputBytes());
      }
    }
  }
}

std::vector<SimAxisLayout> Segment::axisLayout() const {
  std::vector<SimAxisLayout> layout;
  for (std::size_t a = 0; a < servo_slave.size(); ++a) {
    const auto pos = static_cast<std::size_t>(servo_slave[a]);
    layout.push_back({static_cast<int>(a), fmt::format("axis{}", a),
                      static_cast<std::uint16_t>(kFirstStation + pos), escs[pos].outputs_logical,
                      escs[pos].inputs_logical});
  }
  return layout;
}

void Segment::pass(std::vector<RingDatagram>& frame, std::int64_t now_ns) {
  for (Esc& esc : escs) {
    putLe(&esc.mem[ecat::kRegDcSystemTime], static_cast<std::uint64_t>(now_ns - kEpochNs), 8);
    for (RingDatagram& dg : frame) esc.process(dg);
    esc.endOfFrame();
  }
}

}  // namespace ncservo::sim
