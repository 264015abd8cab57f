#include "ncservo/layout/layout_learner.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <tuple>

#include "ncservo/base/little_endian.hpp"
#include "ncservo/protocol/pdo_layout.hpp"

namespace ncservo {
namespace {

template <std::size_t N>
bool known(const std::bitset<N>& mask, std::size_t from, std::size_t count) {
  for (std::size_t i = from; i < from + count; ++i) {
    if (!mask[i]) return false;
  }
  return true;
}
template <std::size_t N>
std::uint32_t le(const std::array<std::uint8_t, N>& bytes, std::size_t at, std::size_t count) {
  return static_cast<std::uint32_t>(loadLe(bytes.data() + at, count));
}

// Copies the part of [ado, ado + count) that falls in a register block into its shadow.
template <std::size_t N>
bool copyBlock(std::array<std::uint8_t, N>& shadow, std::bitset<N>& mask, std::uint16_t block,
               const Datagram& dg, const ByteReader& bytes) {
  const std::size_t ado = dg.ado();
  const std::size_t from = std::max<std::size_t>(ado, block);
  const std::size_t to = std::min<std::size_t>(ado + dg.data_captured, std::size_t{block} + N);
  bool changed = false;
  for (std::size_t reg = from; reg < to; ++reg) {
    auto value = bytes.u8(dg.data_offset + (reg - ado));
    if (!value) break;
    const std::size_t i = reg - block;
    if (!mask[i] || shadow[i] != *value) changed = true;
    shadow[i] = *value;
    mask[i] = true;
  }
  return changed;
}

// The start of the slave's mailbox sync manager `index`, when the start-up configured one.
std::optional<std::uint16_t> mailboxAt(const SlaveRegisters& regs, std::size_t index) {
  const std::size_t at = index * ecat::kSyncManagerStride;
  if (!known(regs.sm_known, at, ecat::kSmControlAt + 1)) return std::nullopt;
  if ((regs.sm[at + ecat::kSmControlAt] & ecat::kSmModeMask) != ecat::kSmModeMailbox)
    return std::nullopt;
  return static_cast<std::uint16_t>(le(regs.sm, at + ecat::kSmStartAt, 2));
}

}  // namespace

void SlaveRegisters::absorb(const SlaveRegisters& other) {
  for (std::size_t i = 0; i < fmmu.size(); ++i) {
    if (!fmmu_known[i] && other.fmmu_known[i]) {
      fmmu[i] = other.fmmu[i];
      fmmu_known[i] = true;
    }
  }
  for (std::size_t i = 0; i < sm.size(); ++i) {
    if (!sm_known[i] && other.sm_known[i]) {
      sm[i] = other.sm[i];
      sm_known[i] = true;
    }
  }
  physical_exchange = physical_exchange || other.physical_exchange;
  coe.absorb(other.coe);
}

SlaveLayout describeSlave(const SlaveRegisters& regs, std::optional<std::uint16_t> station,
                          std::optional<std::uint16_t> position) {
  SlaveLayout out;
  out.station = station;
  out.position = position;
  for (std::size_t n = 0; n < ecat::kSyncManagerCount; ++n) {
    const std::size_t at = n * ecat::kSyncManagerStride;
    if (!known(regs.sm_known, at + ecat::kSmStartAt, 4)) continue;
    SyncManagerView sm;
    sm.index = n;
    sm.start = static_cast<std::uint16_t>(le(regs.sm, at + ecat::kSmStartAt, 2));
    sm.length = static_cast<std::uint16_t>(le(regs.sm, at + ecat::kSmLengthAt, 2));
    sm.control = regs.sm[at + ecat::kSmControlAt];
    sm.enabled = regs.sm_known[at + ecat::kSmActivateAt]
                     ? (regs.sm[at + ecat::kSmActivateAt] & 1) != 0
                     : true;
    if (sm.length == 0) continue;
    out.sync_managers.push_back(sm);
  }
  for (std::size_t n = 0; n < ecat::kFmmuCount; ++n) {
    const std::size_t at = n * ecat::kFmmuStride;
    if (!known(regs.fmmu_known, at, ecat::kFmmuActivateAt + 1)) continue;
    FmmuView f;
    f.index = n;
    f.logical = le(regs.fmmu, at + ecat::kFmmuLogicalAt, 4);
    f.length = static_cast<std::uint16_t>(le(regs.fmmu, at + ecat::kFmmuLengthAt, 2));
    f.physical = static_cast<std::uint16_t>(le(regs.fmmu, at + ecat::kFmmuPhysicalAt, 2));
    f.type = regs.fmmu[at + ecat::kFmmuTypeAt];
    f.active = (regs.fmmu[at + ecat::kFmmuActivateAt] & 1) != 0;
    if (f.length == 0 && !f.active) continue;
    out.fmmus.push_back(f);
  }
  auto smOf = [&](std::size_t index) -> const SyncManagerView* {
    for (const SyncManagerView& sm : out.sync_managers) {
      if (sm.index == index) return &sm;
    }
    return nullptr;
  };
  const SyncManagerView* rx = smOf(ecat::kOutputsSm);
  const SyncManagerView* tx = smOf(ecat::kInputsSm);
  out.coe_output_bits = regs.coe.assignedBits(ecat::kRxPdoAssignment);
  out.coe_input_bits = regs.coe.assignedBits(ecat::kTxPdoAssignment);
  const bool sm_servo =
      rx != nullptr && tx != nullptr && rx->length == kRxPdoSize && tx->length == kTxPdoSize;
  // The CoE assignment marks a servo where the SM lengths were not written (they are, in every
  // start-up seen so far; then they decide).
  const bool coe_servo =
      out.coe_output_bits == 8 * kRxPdoSize && out.coe_input_bits == 8 * kTxPdoSize;
  const bool sm_lengths = rx != nullptr || tx != nullptr;
  out.servo = sm_servo || (coe_servo && !sm_lengths);
  return out;
}

bool LayoutLearner::touch(SlaveRegisters& regs, const Datagram& dg, const ByteReader& bytes) {
  const bool fmmu = copyBlock(regs.fmmu, regs.fmmu_known, ecat::kRegFmmu0, dg, bytes);
  const bool sm = copyBlock(regs.sm, regs.sm_known, ecat::kRegSyncManager0, dg, bytes);
  return fmmu || sm;
}

bool LayoutLearner::observeMailbox(const Datagram& dg, const ByteReader& bytes,
                                   const SlaveAddress& address, std::size_t sm) {
  if (address.target != SlaveTarget::Station && address.target != SlaveTarget::Position) {
    return false;
  }
  const std::size_t s = address.target == SlaveTarget::Station
                            ? directory_.findStation(address.value)
                            : directory_.findPosition(address.value);
  if (s == directory_.kNone) return false;
  SlaveRegisters& regs = directory_.slaves()[s].data;
  const auto start = mailboxAt(regs, sm);
  if (!start || dg.ado() != *start) return false;
  regs.coe.onMailbox(bytes, dg.data_offset, dg.data_captured, sm == ecat::kMailboxOutSm);
  dirty_ = true;
  return true;
}

void LayoutLearner::onFrame(const EcatFrame& frame, const ByteReader& bytes, bool returned,
                            bool paired) {
  if (frame.status != WalkStatus::Ok && frame.status != WalkStatus::Truncated) return;
  // A cut frame that writes slaves' registers (distributed-clock registers aside, which cyclic
  // frames write too) belongs to a start-up; what it wrote after the cut is lost.
  if (frame.status == WalkStatus::Truncated && (!returned || !paired) &&
      std::any_of(
          frame.datagrams.begin(), frame.datagrams.begin() + frame.count, [](const Datagram& dg) {
            return !ecat::isLogical(dg.command) && ecat::writesSlaves(dg.command) &&
                   dg.ado() < ecat::kProcessRam && (dg.ado() >> 8) != (ecat::kRegDcSystemTime >> 8);
          })) {
    ++configuration_frames_cut_;
  }
  directory_.beginFrame(frame, returned);
  for (std::size_t i = 0; i < frame.count; ++i) {
    const Datagram& dg = frame.datagrams[i];
    if (ecat::isLogical(dg.command)) continue;
    const SlaveAddress address = directory_.addressOf(dg, i, returned, paired);
    // A station alias read back from a slave names it as well; a CoE answer in its mailbox (SM1)
    // says what its PDOs hold.
    if (returned && ecat::readsSlaves(dg.command) && dg.has_wkc && dg.wkc > 0) {
      directory_.noteAlias(dg, bytes, address);
      observeMailbox(dg, bytes, address, ecat::kMailboxInSm);
    }
    // What the master wrote configures the slave (a read-back would only repeat it).
    if (!ecat::writesSlaves(dg.command) || (returned && paired)) continue;
    directory_.noteStationWrite(dg, bytes, address);
    directory_.noteAlias(dg, bytes, address);
    if (observeMailbox(dg, bytes, address, ecat::kMailboxOutSm)) continue;
    const std::size_t ado = dg.ado();
    const std::size_t end = ado + dg.data_captured;
    if (ado >= ecat::kProcessRam && address.target == SlaveTarget::Station) {
      // Process data exchanged with FPRD/FPWR: a configured servo's SM addresses.
      const std::size_t s = directory_.findStation(address.value);
      if (s == directory_.kNone) continue;
      SlaveRegisters& regs = directory_.slaves()[s].data;
      const SlaveLayout layout = describeSlave(regs, std::nullopt, std::nullopt);
      if (!layout.servo || regs.physical_exchange) continue;
      for (const SyncManagerView& sm : layout.sync_managers) {
        if ((sm.index == ecat::kOutputsSm || sm.index == ecat::kInputsSm) &&
            ado < std::size_t{sm.start} + sm.length && end > sm.start) {
          regs.physical_exchange = true;
          dirty_ = true;
        }
      }
      continue;
    }
    const bool registers =
        (ado < ecat::kRegFmmu0 + ecat::kFmmuCount * ecat::kFmmuStride && end > ecat::kRegFmmu0) ||
        (ado < ecat::kRegSyncManager0 + ecat::kSyncManagerCount * ecat::kSyncManagerStride &&
         end > ecat::kRegSyncManager0);
    if (!registers) continue;
    if (address.target == SlaveTarget::All) {
      for (auto& slave : directory_.slaves()) dirty_ = touch(slave.data, dg, bytes) || dirty_;
      continue;
    }
    const std::size_t s = directory_.slaveFor(address);
    if (s == directory_.kNone) continue;
    dirty_ = touch(directory_.slaves()[s].data, dg, bytes) || dirty_;
  }
  if (dirty_) rebuild();
}

std::vector<SlaveLayout> LayoutLearner::slaves() const {
  std::vector<SlaveLayout> out;
  for (const auto& slave : directory_.slaves()) {
    out.push_back(describeSlave(slave.data, slave.station, slave.position));
  }
  // Ring order where known; slaves known only by station after them, by station.
  std::stable_sort(out.begin(), out.end(), [](const SlaveLayout& a, const SlaveLayout& b) {
    return std::make_tuple(!a.position.has_value(), a.position.value_or(0), a.station.value_or(0)) <
           std::make_tuple(!b.position.has_value(), b.position.value_or(0), b.station.value_or(0));
  });
  return out;
}

void LayoutLearner::rebuild() {
  dirty_ = false;
  std::vector<AxisConfig> axes;
  for (const SlaveLayout& slave : slaves()) {
    if (!slave.sync_managers.empty()) saw_configuration_ = true;  // non-zero lengths only
    if (!slave.servo) continue;
    saw_servo_ = true;
    const SyncManagerView* rx = nullptr;
    const SyncManagerView* tx = nullptr;
    for (const SyncManagerView& sm : slave.sync_managers) {
      if (sm.index == ecat::kOutputsSm) rx = &sm;
      if (sm.index == ecat::kInputsSm) tx = &sm;
    }
    // The logical address an active FMMU of this direction gives the SM's first byte.
    auto mapped = [&](const SyncManagerView& sm,
                      std::uint8_t direction) -> std::optional<std::uint32_t> {
      for (const FmmuView& f : slave.fmmus) {
        if (!f.active || (f.type & direction) == 0) continue;
        if (sm.start < f.physical ||
            std::size_t{sm.start} + sm.length > std::size_t{f.physical} + f.length)
          continue;
        return f.logical + (sm.start - f.physical);
      }
      return std::nullopt;
    };
    AxisConfig axis;
    axis.name = fmt::format("axis{}", axes.size());
    axis.station = slave.station;
    if (rx == nullptr || tx == nullptr) continue;  // a servo by CoE, its SMs not configured yet
    const auto outputs = mapped(*rx, ecat::kFmmuWrite);
    const auto inputs = mapped(*tx, ecat::kFmmuRead);
    if (outputs && inputs) {
      axis.outputs = outputs;
      axis.inputs = inputs;
    } else if (slave.station && (outputs || inputs)) {
      // Only one direction mapped: the other is unknown; keep the mapped one.
      axis.outputs = outputs;
      axis.inputs = inputs;
    } else if (slave.station && slave.fmmus.empty()) {
      const std::size_t s = directory_.findStation(*slave.station);
      if (s == directory_.kNone || !directory_.slaves()[s].data.physical_exchange) continue;
      axis.sm_outputs = rx->start;
      axis.sm_inputs = tx->start;
    } else {
      continue;  // not placed yet
    }
    axes.push_back(std::move(axis));
  }
  auto same = [](const AxisConfig& a, const AxisConfig& b) {
    return a.station == b.station && a.outputs == b.outputs && a.inputs == b.inputs &&
           a.sm_outputs == b.sm_outputs && a.sm_inputs == b.sm_inputs;
  };
  if (axes.size() == axes_.size() && std::equal(axes.begin(), axes.end(), axes_.begin(), same))
    return;
  axes_ = std::move(axes);
  ++generation_;
}

std::string describeSlaveLayout(const SlaveLayout& slave) {
  std::string text;
  if (slave.position) text += fmt::format("{}", *slave.position);
  if (slave.station)
    text += fmt::format("{}station 0x{:04X}", text.empty() ? "" : " ", *slave.station);
  for (const SyncManagerView& sm : slave.sync_managers) {
    text += fmt::format("; SM{} 0x{:04X}+{} control 0x{:02X}{}", sm.index, sm.start, sm.length,
                        sm.control, sm.enabled ? "" : " (off)");
  }
  for (const FmmuView& f : slave.fmmus) {
    const char* type = f.type == ecat::kFmmuRead    ? "read"
                       : f.type == ecat::kFmmuWrite ? "write"
                                                    : "read/write";
    text += fmt::format("; FMMU{} 0x{:08X}+{} -> 0x{:04X} {}{}", f.index, f.logical, f.length,
                        f.physical, type, f.active ? "" : " (off)");
  }
  if (slave.coe_output_bits || slave.coe_input_bits) {
    auto bits = [](const std::optional<std::uint32_t>& b) {
      return b ? fmt::format("{}", *b) : std::string("?");
    };
    text += fmt::format("; CoE PDOs {} bits out, {} bits in", bits(slave.coe_output_bits),
                        bits(slave.coe_input_bits));
  }
  if (slave.servo) text += "; servo";
  return text;
}

}  // namespace ncservo
