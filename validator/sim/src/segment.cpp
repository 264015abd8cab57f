#include "segment.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>

#include "ncservo/base/little_endian.hpp"
#include "ncservo/protocol/pdo_layout.hpp"
#include "ncservo/wire/ethercat.hpp"

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
constexpr std::uint16_t kRxPhys = 0x1100;
constexpr std::uint16_t kTxPhys = 0x1180;
constexpr std::uint16_t kOutTerminalPhys = 0x0F00;
constexpr std::uint16_t kInTerminalPhys = 0x1000;
constexpr SlaveModel kServo = {.name = "servo",
                               .role = SlaveRole::Servo,
                               .output_bytes = kRxPdoSize,
                               .input_bytes = kTxPdoSize,
                               .output_sm = 2,
                               .input_sm = 3,
                               .output_phys = kRxPhys,
                               .input_phys = kTxPhys};
// The terminals of the SOEM and EtherLab set-ups, in turn.
constexpr SlaveModel kDigitalOut = {.name = "EL2008",
                                    .role = SlaveRole::Digital,
                                    .output_bytes = 1,
                                    .input_bytes = 0,
                                    .output_sm = 0,
                                    .input_sm = 0,
                                    .output_phys = kOutTerminalPhys,
                                    .input_phys = 0};
constexpr SlaveModel kDigitalIn = {.name = "EL1008",
                                   .role = SlaveRole::Digital,
                                   .output_bytes = 0,
                                   .input_bytes = 1,
                                   .output_sm = 0,
                                   .input_sm = 0,
                                   .output_phys = 0,
                                   .input_phys = kInTerminalPhys};
// The mixed and TwinCAT set-ups draw from all of these: sizes a servo's 10 and 40 bytes are not,
// output-only, input-only, and a drive of another protocol.
constexpr SlaveModel kTerminalModels[] = {
    kDigitalOut,
    kDigitalIn,
    {.name = "EL2809",
     .role = SlaveRole::Digital,
     .output_bytes = 2,
     .input_bytes = 0,
     .output_sm = 0,
     .input_sm = 0,
     .output_phys = kOutTerminalPhys,
     .input_phys = 0},
    {.name = "EL1809",
     .role = SlaveRole::Digital,
     .output_bytes = 0,
     .input_bytes = 2,
     .output_sm = 0,
     .input_sm = 0,
     .output_phys = 0,
     .input_phys = kInTerminalPhys},
    {.name = "EL4004",
     .role = SlaveRole::Analog,
     .output_bytes = 8,
     .input_bytes = 0,
     .output_sm = 2,
     .input_sm = 0,
     .output_phys = kRxPhys,
     .input_phys = 0},
    {.name = "EL3064",
     .role = SlaveRole::Analog,
     .output_bytes = 0,
     .input_bytes = 16,
     .output_sm = 0,
     .input_sm = 3,
     .output_phys = 0,
     .input_phys = kTxPhys},
    {.name = "EL3102",
     .role = SlaveRole::Analog,
     .output_bytes = 0,
     .input_bytes = 4,
     .output_sm = 0,
     .input_sm = 3,
     .output_phys = 0,
     .input_phys = kTxPhys},
    {.name = "EL5101",
     .role = SlaveRole::Analog,
     .output_bytes = 4,
     .input_bytes = 6,
     .output_sm = 2,
     .input_sm = 3,
     .output_phys = kRxPhys,
     .input_phys = kTxPhys},
    {.name = "CiA 402 drive",
     .role = SlaveRole::Drive,
     .output_bytes = 12,
     .input_bytes = 28,
     .output_sm = 2,
     .input_sm = 3,
     .output_phys = kRxPhys,
     .input_phys = kTxPhys},
    {.name = "EL6692",
     .role = SlaveRole::Bridge,
     .output_bytes = 32,
     .input_bytes = 32,
     .output_sm = 2,
     .input_sm = 3,
     .output_phys = kRxPhys,
     .input_phys = kTxPhys},
};
// A neighbour that looks alike: another protocol's drive with PDOs of a servo's sizes.
constexpr SlaveModel kCia402 = {.name = "CiA 402 drive (10/40)",
                                .role = SlaveRole::Drive,
                                .output_bytes = kRxPdoSize,
                                .input_bytes = kTxPdoSize,
                                .output_sm = 2,
                                .input_sm = 3,
                                .output_phys = kRxPhys,
                                .input_phys = kTxPhys};
constexpr std::uint64_t kMixSeedSalt = 0x6D69786564ULL;  // the set-up's own random stream

// The master's process image: one region per cyclic frame.
constexpr std::uint32_t kLogicalBase = 0x00010000;
constexpr std::uint32_t kLogicalFrameStride = 0x1000;
// TwinCAT-like: the outputs and the inputs in areas of their own, far apart.
constexpr std::uint32_t kOutputArea = 0x01000000;
constexpr std::uint32_t kInputArea = 0x01008000;
constexpr std::size_t kMaxLrwData = 1450;  // 29 axes of 50 bytes (docs/protocol.md §9.4)
// Several datagrams' headers, the DC FRMW and the status BRD must fit too (1498 bytes in all).
constexpr std::size_t kMaxSplitData = 1400;
constexpr int kMaxServosPerFrame = 29;
constexpr std::uint64_t kOutputPatternCycles = 100;  // the lit output moves this often

}  // namespace

const SlaveModel& servoModel() {
  return kServo;
}

void writeTerminalOutputs(const SlaveModel& model, std::uint64_t cycle, std::uint8_t* out) {
  const std::size_t size = model.output_bytes;
  switch (model.role) {
    case SlaveRole::Servo:
      break;
    case SlaveRole::Digital:
      storeLe(out, std::uint64_t{1} << (cycle / kOutputPatternCycles % (8 * size)), size);
      break;
    case SlaveRole::Analog:
      for (std::size_t c = 0; c + 2 <= size; c += 2) storeLe(out + c, cycle * (c + 1) * 37, 2);
      break;
    case SlaveRole::Drive:  // control word "enable operation", target position, velocity, mode
      storeLe(out, 0x000F, 2);
      storeLe(out + 2, cycle * 100, 4);
      storeLe(out + 6, 1000, 4);
      if (size < 12) break;  // a 10-byte RxPDO has no room for the mode
      out[10] = 8;           // cyclic synchronous position
      out[11] = 0;
      break;
    case SlaveRole::Bridge:
      for (std::size_t i = 0; i < size; ++i) out[i] = static_cast<std::uint8_t>(cycle + i);
      break;
  }
}

// --- one ESC ---

void Esc::updateTerminalInputs(std::int64_t now_ns) {
  if (inputBytes() == 0) return;
  std::uint8_t* in = &mem[inputsPhysical()];
  const std::size_t size = inputBytes();
  if (input_step_ns == 0 && model->role != SlaveRole::Drive) {
    // Busy inputs: every byte new every cycle, drawn from the time and the slave's address.
    std::uint64_t x = static_cast<std::uint64_t>(now_ns) / cycle_ns * 0x9E3779B97F4A7C15ULL ^
                      (std::uint64_t{inputs_logical} << 32);
    for (std::size_t i = 0; i < size; ++i) {
      x ^= x >> 29;
      x *= 0xBF58476D1CE4E5B9ULL;
      x ^= x >> 32;
      in[i] = static_cast<std::uint8_t>(x);
    }
    return;
  }
  const auto step = static_cast<std::uint64_t>(
      now_ns / (input_step_ns != 0 ? input_step_ns : static_cast<std::int64_t>(cycle_ns)));
  const auto us = static_cast<std::uint64_t>(now_ns / kUs);
  switch (model->role) {
    case SlaveRole::Servo:
      break;
    case SlaveRole::Digital:
      storeLe(in, step, size);
      break;
    case SlaveRole::Analog:  // triangles of 16-bit values, one channel after the other
      for (std::size_t c = 0; c + 2 <= size; c += 2) {
        const std::uint64_t phase = (step + 7 * c) % 64;
        storeLe(in + c, (phase < 32 ? phase : 64 - phase) * 1000, 2);
      }
      break;
    case SlaveRole::Drive:  // status word, actual position and velocity, torque, the rest zero
      std::fill(in, in + size, 0);
      storeLe(in, 0x1237, 2);
      storeLe(in + 2, us / 10, 4);
      storeLe(in + 6, 1000, 4);
      storeLe(in + 10, step % 200, 2);
      break;
    case SlaveRole::Bridge:
      for (std::size_t i = 0; i < size; ++i) in[i] = static_cast<std::uint8_t>(step + 3 * i);
      break;
  }
}

std::uint16_t Esc::station() const {
  return static_cast<std::uint16_t>(loadLe(&mem[ecat::kRegStationAddress], 2));
}
bool Esc::processData() const {
  return state == kSafeOp || state == kOp;
}
void Esc::publishAlStatus() {
  storeLe(&mem[ecat::kRegAlStatus],
          static_cast<std::uint16_t>(state | (error_ ? ecat::kAlErrorBit : 0)), 2);
  storeLe(&mem[ecat::kRegAlStatusCode], code_, 2);
}
void Esc::powerUpError() {
  error_ = true;
  code_ = kCodePowerUp;
  publishAlStatus();
}

void Esc::fallFromOp(std::uint16_t code) {
  state = kSafeOp;
  pending_ = 0;
  error_ = true;
  code_ = code;
  publishAlStatus();
}

void Esc::startInOp(std::uint16_t station_address) {
  state = kOp;
  publishAlStatus();
  storeLe(&mem[ecat::kRegStationAddress], station_address, 2);
  std::size_t f = 0;
  auto fmmu = [&](std::uint32_t logical, std::size_t length, std::uint16_t phys,
                  std::uint8_t type) {
    std::uint8_t* p = &mem[ecat::kRegFmmu0 + ecat::kFmmuStride * f++];
    storeLe(p + ecat::kFmmuLogicalAt, logical, 4);
    storeLe(p + ecat::kFmmuLengthAt, length, 2);
    p[ecat::kFmmuStopBitAt] = 7;
    storeLe(p + ecat::kFmmuPhysicalAt, phys, 2);
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
  const bool allowed = alTransitionAllowed(state, requested);  // docs/protocol.md §8
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

void writeMailboxSyncManagers(std::uint8_t* registers) {
  // SM0 written by the master, SM1 read by it, both in mailbox mode (ETG.1000.4)
  constexpr std::uint8_t kSmMailboxOut = 0x26, kSmMailboxIn = 0x22;
  for (std::size_t sm = 0; sm < 2; ++sm) {
    std::uint8_t* regs = registers + sm * ecat::kSyncManagerStride;
    storeLe(regs + ecat::kSmStartAt, sm == 0 ? kMailboxOutPhys : kMailboxInPhys, 2);
    storeLe(regs + ecat::kSmLengthAt, kMailboxBytes, 2);
    regs[ecat::kSmControlAt] = sm == 0 ? kSmMailboxOut : kSmMailboxIn;
    regs[ecat::kSmActivateAt] = 0x01;
  }
}

void Esc::countError(diag::EscCounter counter, std::uint8_t port) {
  const std::uint16_t reg = diag::escCounterRegister(counter, port);
  if (mem[reg] < 0xFF) ++mem[reg];
  ++counted[static_cast<std::size_t>(counter)][port];
}

void Esc::watchOutputs(std::int64_t now_ns, bool processed) {
  constexpr std::int64_t kSmWatchdogNs = 100 * kMs;
  if (state != kOp || outputBytes() == 0) {
    outputs_ns_ = -1;
  } else if (processed) {  // the frame has passed: its outputs restart the watchdog
    if (outputs_taken || outputs_ns_ < 0) {
      outputs_ns_ = now_ns;
      watchdog_expired_ = false;
    }
  } else if (outputs_ns_ >= 0 && !watchdog_expired_ && now_ns - outputs_ns_ > kSmWatchdogNs) {
    countError(diag::EscCounter::SmWatchdog, 0);  // it expired before this frame came
    watchdog_expired_ = true;
  }
}

void Esc::setTimeDifference(std::int32_t ns) {
  // sign and magnitude: bit 31 set when the slave's copy is smaller (docs/protocol.md §11)
  const std::uint32_t magnitude = static_cast<std::uint32_t>(ns < 0 ? -ns : ns) & 0x7FFFFFFFu;
  storeLe(&mem[ecat::kRegDcSystemTimeDifference],
          magnitude | (ns < 0 ? ecat::kDcDifferenceSignBit : 0u), 4);
}

std::optional<std::uint16_t> Esc::mailboxArea(std::size_t sm) const {
  const std::uint8_t* regs = &mem[ecat::kRegSyncManager0 + sm * ecat::kSyncManagerStride];
  if ((regs[ecat::kSmControlAt] & ecat::kSmModeMask) != ecat::kSmModeMailbox ||
      (regs[ecat::kSmActivateAt] & 1) == 0) {
    return std::nullopt;
  }
  return static_cast<std::uint16_t>(loadLe(regs + ecat::kSmStartAt, 2));
}

bool Esc::mailboxAccess(RingDatagram& dg) {
  if (dg.ado < ecat::kProcessRam) return false;
  const bool write = dg.command == ecat::kFpwr || dg.command == ecat::kApwr;
  const std::optional<std::uint16_t> area =
      mailboxArea(write ? ecat::kMailboxOutSm : ecat::kMailboxInSm);
  if (!area || dg.ado != *area) return false;
  if (write) {
    mailbox_written.push_back(dg.data);
    ++dg.wkc;
  } else if (!mailbox_answers.empty()) {
    // SM1 full: the read takes the message, and the SM is empty again
    const std::vector<std::uint8_t>& answer = mailbox_answers.front().bytes;
    std::fill(dg.data.begin(), dg.data.end(), 0);
    std::copy_n(answer.begin(), std::min(answer.size(), dg.data.size()), dg.data.begin());
    mailbox_taken.push_back(std::move(mailbox_answers.front()));
    mailbox_answers.pop_front();
    ++dg.wkc;
  }
  return true;
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
    // a write to the first error counters clears them all, one to a watchdog counter it
    // (ESC datasheets)
    if (reg >= ecat::kRegErrorCounters && reg < ecat::kRegErrorCountersClearedEnd) {
      std::fill_n(&mem[ecat::kRegErrorCounters], ecat::kErrorCountersSize, 0);
      continue;
    }
    if (reg == ecat::kRegSmWatchdogCounter || reg == ecat::kRegPdiWatchdogCounter) {
      mem[reg] = 0;
      continue;
    }
    mem[reg] = dg.data[i];
  }
  if (dg.ado <= ecat::kRegAlControl && dg.ado + dg.data.size() >= ecat::kRegAlControl + 2u) {
    onAlControl(static_cast<std::uint16_t>(loadLe(&mem[ecat::kRegAlControl], 2)));
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
    const std::uint64_t lstart = loadLe(fmmu + ecat::kFmmuLogicalAt, 4);
    const std::uint64_t lend = lstart + loadLe(fmmu + ecat::kFmmuLengthAt, 2);
    const std::uint64_t from = std::max(start, lstart), to = std::min(end, lend);
    if (from >= to) continue;
    const std::size_t phys = loadLe(fmmu + ecat::kFmmuPhysicalAt, 2) + (from - lstart);
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
        if (mailboxAccess(dg)) break;
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

std::optional<ImagePlace> FrameGroup::place(std::uint32_t logical) const {
  for (std::size_t d = 0; d < datagrams.size(); ++d) {
    const ImageDatagram& dg = datagrams[d];
    if (logical >= dg.logical && logical < dg.logical + dg.size) {
      return ImagePlace{d, logical - dg.logical};
    }
  }
  return std::nullopt;
}

namespace {

// Ring order: SOEM and EtherLab alternate servos and 8-bit digital terminals; mixed and TwinCAT
// draw each position and each terminal's model.
std::vector<const SlaveModel*> ringOrder(const SimOptions& o, Rng& mix) {
  const int io_slaves = *o.io_slaves;
  const bool drawn = o.image == ImageStyle::Mixed || o.image == ImageStyle::TwinCat;
  std::vector<const SlaveModel*> ring;
  int servos = 0, terminals = 0;
  for (int pos = 0; pos < o.axes + io_slaves; ++pos) {
    const int servos_left = o.axes - servos, terminals_left = io_slaves - terminals;
    const bool take_servo =
        drawn ? mix.between(1, servos_left + terminals_left) <= servos_left
              : servos < o.axes && (terminals >= io_slaves || servos <= terminals);
    if (take_servo) {
      ring.push_back(&kServo);
      ++servos;
      continue;
    }
    if (drawn) {
      const auto model = mix.between(0, static_cast<std::int64_t>(std::size(kTerminalModels)) - 1);
      ring.push_back(&kTerminalModels[static_cast<std::size_t>(model)]);
    } else {
      ring.push_back(terminals % 2 == 0 ? &kDigitalOut : &kDigitalIn);
    }
    ++terminals;
  }
  // --cia402: a drive of another protocol after each of the first servos, then after the last.
  int placed = 0;
  for (std::size_t pos = 0; pos < ring.size() && placed < o.cia402_drives; ++pos) {
    if (ring[pos] != &kServo) continue;
    ring.insert(ring.begin() + static_cast<std::ptrdiff_t>(pos) + 1, &kCia402);
    ++placed;
  }
  for (; placed < o.cia402_drives; ++placed) ring.push_back(&kCia402);
  return ring;
}

// With --io-task-us the terminals go in a frame of their own; the drives stay with the servos.
bool inIoTask(const SimOptions& o, const SlaveModel& model) {
  return o.io_task_us != 0 && model.role != SlaveRole::Servo && model.role != SlaveRole::Drive;
}

// TwinCAT-like: one area split in two datagrams at a slave boundary once it holds two slaves.
void splitArea(std::vector<ImageDatagram>& out, std::uint8_t command, std::uint32_t base,
               const std::vector<std::size_t>& sizes) {
  if (sizes.empty()) return;
  const std::size_t first = (sizes.size() + 1) / 2;
  std::uint32_t cursor = base;
  for (std::size_t part = 0; part < 2; ++part) {
    const std::size_t from = part == 0 ? 0 : first, to = part == 0 ? first : sizes.size();
    if (from == to) continue;
    ImageDatagram dg{command, cursor, 0};
    for (std::size_t i = from; i < to; ++i) dg.size += sizes[i];
    cursor += static_cast<std::uint32_t>(dg.size);
    out.push_back(dg);
  }
}

}  // namespace

Segment::Segment(const SimOptions& o, Rng& rng) : style(o.image), dc_drift_ppm(o.dc_drift_ppm) {
  Rng mix(o.seed ^ kMixSeedSalt);
  const std::vector<const SlaveModel*> ring = ringOrder(o, mix);
  for (std::size_t pos = 0; pos < ring.size(); ++pos) {
    Esc esc;
    esc.model = ring[pos];
    if (esc.servo()) {
      esc.axis = static_cast<int>(servo_slave.size());
      servo_slave.push_back(static_cast<int>(pos));
    }
    esc.mem[ecat::kRegType] = kEscTypeValue;
    esc.transition_frames = static_cast<int>(rng.between(1, 3));
    esc.cycle_ns = static_cast<std::uint64_t>(o.cycle_us) * kUs;
    if (o.terminal_inputs == TerminalInputs::EveryCycle) esc.input_step_ns = 0;
    esc.publishAlStatus();
    escs.push_back(std::move(esc));
  }
  const bool split = style == ImageStyle::TwinCat;
  outputs_first =
      style == ImageStyle::Soem || split || (style == ImageStyle::Mixed && mix.between(0, 1) == 0);
  status_poll = split;
  // Frames: at most 29 servos and 1450 bytes of process data each (1400 when split).
  const std::size_t max_data = split ? kMaxSplitData : kMaxLrwData;
  // The servo task's frames first, then (--io-task-us) the slower task's.
  for (const bool io_task : {false, true}) {
    FrameGroup group;
    group.every_cycles = io_task ? static_cast<std::uint64_t>(o.io_task_us / o.cycle_us) : 1;
    int servos_in_group = 0;
    for (std::size_t pos = 0; pos < escs.size(); ++pos) {
      const Esc& esc = escs[pos];
      if (inIoTask(o, *esc.model) != io_task) continue;
      const std::size_t need = esc.outputBytes() + esc.inputBytes();
      if (!group.slaves.empty() && (group.bytes + need > max_data ||
                                    (esc.servo() && servos_in_group == kMaxServosPerFrame))) {
        const std::uint64_t every = group.every_cycles;
        groups.push_back(std::move(group));
        group = FrameGroup{};
        group.every_cycles = every;
        servos_in_group = 0;
      }
      group.slaves.push_back(static_cast<int>(pos));
      group.bytes += need;
      if (esc.servo()) ++servos_in_group;
    }
    if (!group.slaves.empty()) groups.push_back(std::move(group));
  }
  // Logical addresses of each slave's outputs and inputs, and the datagrams over them.
  for (std::size_t g = 0; g < groups.size(); ++g) {
    FrameGroup& fg = groups[g];
    const auto stride = static_cast<std::uint32_t>(g) * kLogicalFrameStride;
    if (split) {
      std::vector<std::size_t> output_sizes, input_sizes;
      std::uint32_t out_cursor = kOutputArea + stride, in_cursor = kInputArea + stride;
      for (int pos : fg.slaves) {
        Esc& esc = escs[static_cast<std::size_t>(pos)];
        esc.outputs_logical = out_cursor;
        esc.inputs_logical = in_cursor;
        out_cursor += static_cast<std::uint32_t>(esc.outputBytes());
        in_cursor += static_cast<std::uint32_t>(esc.inputBytes());
        if (esc.outputBytes() > 0) output_sizes.push_back(esc.outputBytes());
        if (esc.inputBytes() > 0) input_sizes.push_back(esc.inputBytes());
      }
      splitArea(fg.datagrams, ecat::kLwr, kOutputArea + stride, output_sizes);
      splitArea(fg.datagrams, ecat::kLrd, kInputArea + stride, input_sizes);
      continue;
    }
    const std::uint32_t base = kLogicalBase + stride;
    std::uint32_t cursor = base;
    auto place = [&](std::uint32_t& address, std::size_t bytes) {
      address = cursor;
      cursor += static_cast<std::uint32_t>(bytes);
    };
    if (outputs_first) {
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
    fg.datagrams.push_back({ecat::kLrw, base, fg.bytes});
  }
}

std::uint16_t Segment::expectedWkc(const ImageDatagram& dg) const {
  const std::uint64_t start = dg.logical, end = start + dg.size;
  auto overlaps = [&](std::uint32_t logical, std::size_t bytes) {
    return bytes > 0 && logical < end && logical + bytes > start;
  };
  std::uint16_t wkc = 0;
  for (const Esc& esc : escs) {
    const bool writes =
        ecat::writesSlaves(dg.command) && overlaps(esc.outputs_logical, esc.outputBytes());
    const bool reads =
        ecat::readsSlaves(dg.command) && overlaps(esc.inputs_logical, esc.inputBytes());
    if (dg.command == ecat::kLrw) {
      wkc = static_cast<std::uint16_t>(wkc + (writes ? 2 : 0) + (reads ? 1 : 0));
    } else if (writes || reads) {
      ++wkc;
    }
  }
  return wkc;
}

std::string Segment::describe() const {
  const ImageStyleName& row = imageStyleRow(style);
  if (style == ImageStyle::Mixed) {
    return fmt::format("mixed ({}) layout", outputs_first ? "outputs first" : "per slave");
  }
  return fmt::format("{} layout", row.layout_alias != nullptr ? row.layout_alias : row.name);
}

std::vector<AxisConfig> Segment::axisLayout() const {
  std::vector<AxisConfig> layout;
  for (std::size_t a = 0; a < servo_slave.size(); ++a) {
    const auto pos = static_cast<std::size_t>(servo_slave[a]);
    AxisConfig axis;
    axis.name = fmt::format("axis{}", a);
    axis.station = static_cast<std::uint16_t>(kFirstStation + pos);
    axis.outputs = escs[pos].outputs_logical;
    axis.inputs = escs[pos].inputs_logical;
    layout.push_back(std::move(axis));
  }
  return layout;
}

bool Segment::pass(std::vector<RingDatagram>& frame, std::int64_t now_ns,
                   std::optional<std::size_t> corrupted_into) {
  // The slaves keep the reference clock's time (the FRMW distributes it), which runs
  // dc_drift_ppm fast against the master's clock, the one the capture's stamps follow.
  const std::int64_t since_epoch_ns = now_ns - kEpochNs;
  const std::int64_t system_time_ns =
      since_epoch_ns + std::llround(static_cast<double>(since_epoch_ns) * dc_drift_ppm * 1e-6);
  for (std::size_t pos = 0; pos < escs.size(); ++pos) {
    Esc& esc = escs[pos];
    storeLe(&esc.mem[ecat::kRegDcSystemTime], static_cast<std::uint64_t>(system_time_ns), 8);
    if (corrupted_into && pos >= *corrupted_into) {
      // The frame's CRC fails: the slave at the bad link counts an invalid frame, every slave
      // after it one that came marked, as forwarded
      // (docs/drive-messages.md#the-esc-error-counters).
      esc.countError(diag::EscCounter::Invalid, 0);
      if (pos == *corrupted_into) {
        ++esc.corrupted_frames;
      } else {
        esc.countError(diag::EscCounter::Forwarded, 0);
      }
      continue;
    }
    if (watchdogs) esc.watchOutputs(since_epoch_ns, false);
    for (RingDatagram& dg : frame) esc.process(dg);
    if (watchdogs) esc.watchOutputs(since_epoch_ns, true);
    esc.endOfFrame();
  }
  if (!corrupted_into) return true;
  // On its way back every slave but the last receives the marked frame at port 1.
  for (std::size_t pos = 0; pos + 1 < escs.size(); ++pos) {
    escs[pos].countError(diag::EscCounter::Invalid, 1);
    escs[pos].countError(diag::EscCounter::Forwarded, 1);
  }
  return false;
}

}  // namespace ncservo::sim
