#include "ncservo/model/esc_errors.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace ncservo {
namespace {

using diag::EscCounter;
constexpr std::size_t kBlock = ecat::kRegErrorCounters;
constexpr std::size_t kBlockEnd = kBlock + ecat::kErrorCountersSize;
constexpr std::size_t kWatchdogs = ecat::kRegSmWatchdogCounter;
constexpr std::size_t kWatchdogsEnd = kWatchdogs + ecat::kWatchdogCountersSize;

// The counter registers a tracker keeps, each block at its place in Counters::value.
struct Block {
  std::size_t from, to, at;
};
constexpr std::array<Block, 2> kBlocks{
    {{kBlock, kBlockEnd, 0}, {kWatchdogs, kWatchdogsEnd, ecat::kErrorCountersSize}}};

// Where a register lies in Counters::value; none outside the blocks.
constexpr std::optional<std::size_t> slotOf(std::size_t reg) {
  for (const Block& block : kBlocks) {
    if (reg >= block.from && reg < block.to) return block.at + (reg - block.from);
  }
  return std::nullopt;
}
constexpr std::size_t slotOf(EscCounter counter, std::uint8_t port) {
  return *slotOf(diag::escCounterRegister(counter, port));
}

// What each place of Counters::value counts, and at which port, from the counter table; none
// for a reserved byte of 0x0300-0x0313.
struct CounterAt {
  EscCounter counter;
  std::uint8_t port;
};
constexpr auto kCounterAt = [] {
  std::array<std::optional<CounterAt>, ecat::kErrorCountersSize + ecat::kWatchdogCountersSize> at{};
  for (std::size_t c = 0; c < diag::kEscCounters.size(); ++c) {
    const auto counter = static_cast<EscCounter>(c);
    const std::size_t ports = diag::kEscCounters[c].port_stride == 0 ? 1 : ecat::kEscPorts;
    for (std::size_t port = 0; port < ports; ++port) {
      at[slotOf(counter, static_cast<std::uint8_t>(port))] =
          CounterAt{counter, static_cast<std::uint8_t>(port)};
    }
  }
  return at;
}();
std::optional<CounterAt> counterAt(std::size_t offset) {
  return kCounterAt[offset];
}

bool reachesCounters(const Datagram& dg) {
  if (ecat::isLogical(dg.command)) return false;
  return std::any_of(kBlocks.begin(), kBlocks.end(), [&](const Block& b) {
    return dg.ado() < b.to && std::size_t{dg.ado()} + dg.data_captured > b.from;
  });
}

std::string sideName(const SlaveRef& slave) {
  if (slave.station) return fmt::format("station 0x{:04X}", *slave.station);
  if (slave.position) return fmt::format("ring position {}", *slave.position);
  return "an unnamed slave";
}

}  // namespace

std::string linkFaultText(const LinkFault& fault) {
  if (!fault.upstream) {
    return fmt::format("the link into {} port {}", sideName(fault.reported), fault.reported_port);
  }
  return fmt::format("the link between {} port {} and {} port {}", sideName(*fault.upstream),
                     fault.upstream_port, sideName(fault.downstream), fault.downstream_port);
}

void EscErrorTracker::Counters::absorb(const Counters& other) {
  for (std::size_t i = 0; i < value.size(); ++i) {
    if (!known[i] && other.known[i]) {
      value[i] = other.value[i];
      known[i] = true;
    }
  }
  if (last_read.frame == 0) last_read = other.last_read;
}

SlaveRef EscErrorTracker::refOf(std::size_t slave) const {
  const auto& s = directory_.slaves()[slave];
  return SlaveRef{s.station, s.position};
}

bool EscErrorTracker::take(Counters& counters, const Datagram& dg, const ByteReader& bytes,
                           Read& read) {
  const std::size_t ado = dg.ado();
  bool any = false;
  for (const Block& block : kBlocks) {
    const std::size_t from = std::max(ado, block.from);
    const std::size_t to = std::min(ado + dg.data_captured, block.to);
    for (std::size_t reg = from; reg < to; ++reg) {
      auto value = bytes.u8(dg.data_offset + (reg - ado));
      if (!value) break;
      const std::size_t i = block.at + (reg - block.from);
      if (counters.known[i]) {
        any = true;
        // Saturating counters: lower than before means cleared since, and rose by the new value.
        read.delta[i] = *value >= counters.value[i] ? *value - counters.value[i] : *value;
      }
      counters.value[i] = *value;
      counters.known[i] = true;
    }
  }
  return any;
}

// A write to 0x0300-0x030B clears those counters, one to 0x0310-0x0313 the lost-link counters,
// one to 0x0442-0x0443 the watchdog counters.
void EscErrorTracker::clear(Counters& counters, const Datagram& dg) {
  const std::size_t ado = dg.ado();
  const std::size_t end = ado + dg.length;
  auto span = [&](std::size_t from, std::size_t to, std::size_t at) {
    if (ado >= to || end <= from) return;
    for (std::size_t reg = from; reg < to; ++reg) {
      counters.value[at + reg - from] = 0;
      counters.known[at + reg - from] = true;
    }
  };
  span(kBlock, ecat::kRegErrorCountersClearedEnd, 0);
  span(ecat::kRegLostLink0, kBlockEnd, ecat::kRegLostLink0 - kBlock);
  span(kWatchdogs, kWatchdogsEnd, ecat::kErrorCountersSize);
}

void EscErrorTracker::list(const EscErrorDelta& delta) {
  frame_deltas_.push_back(delta);
  if (deltas_.size() < kMaxListed) {
    deltas_.push_back(delta);
  } else {
    ++omitted_;
  }
}

void EscErrorTracker::onFrame(const EcatFrame& frame, const ByteReader& bytes,
                              const FrameAddressing& addressing, const Stamp& now,
                              std::vector<BusEvent>& out) {
  frame_deltas_.clear();
  frame_faults_.clear();
  frame_events_.clear();
  bool any = false;
  for (std::size_t i = 0; i < frame.count && !any; ++i) {
    any = reachesCounters(frame.datagrams[i]) ||
          (addressing.takesWrites() && ecat::writesRegisters(frame.datagrams[i].command) &&
           frame.datagrams[i].ado() == ecat::kRegStationAddress);
  }
  if (!any) return;
  reads_this_frame_.clear();
  const bool take_writes = addressing.takesWrites();
  for (std::size_t i = 0; i < frame.count; ++i) {
    const Datagram& dg = frame.datagrams[i];
    const SlaveAddress address = addressing.addressOf(dg, i);
    if (take_writes && ecat::writesRegisters(dg.command)) {
      directory_.noteStationWrite(dg, bytes, address);
      if (reachesCounters(dg)) {
        if (address.target == SlaveTarget::All) {
          clear(broadcast_, dg);
          for (auto& slave : directory_.slaves()) clear(slave.data, dg);
        } else {
          const std::size_t s = directory_.slaveFor(address);
          if (s != directory_.kNone) clear(directory_.slaves()[s].data, dg);
        }
      }
    }
    if (!reachesCounters(dg) || !addressing.takesRead(dg)) continue;
    Read read;
    read.since = now;
    if (address.target == SlaveTarget::All) {
      ++broadcast_reads_;
      if (!take(broadcast_, dg, bytes, read)) continue;
      for (std::size_t k = 0; k < read.delta.size(); ++k) {
        const auto at = counterAt(k);
        if (!at || read.delta[k] == 0) continue;
        list(EscErrorDelta{SlaveRef{}, true, at->port, at->counter, read.delta[k], now.frame});
      }
      continue;
    }
    const std::size_t s = directory_.slaveFor(address);
    if (s == directory_.kNone) continue;
    ++reads_;
    Counters& counters = directory_.slaves()[s].data;
    read.slave = s;
    read.since = counters.last_read;
    const bool compared = take(counters, dg, bytes, read);
    counters.last_read = now;
    if (!compared) continue;
    const SlaveRef ref = refOf(s);
    for (std::size_t k = 0; k < read.delta.size(); ++k) {
      const auto at = counterAt(k);
      if (!at || read.delta[k] == 0) continue;
      list(EscErrorDelta{ref, false, at->port, at->counter, read.delta[k], now.frame});
      if (at->counter == EscCounter::LostLink) {
        LinkErrorEvent event;
        event.link = linkAt(s, at->port);
        event.link.errors = read.delta[k];
        event.link.frame = now.frame;
        event.lost = true;
        event.previous_read_frame = read.since.frame;
        frame_events_.push_back(event);
        out.push_back(BusEvent{now, event});
      }
    }
    reads_this_frame_.push_back(read);
  }
  localise(now, out);
}

LinkFault EscErrorTracker::linkAt(std::size_t slave, std::uint8_t port) const {
  LinkFault fault;
  fault.reported = refOf(slave);
  fault.reported_port = port;
  fault.downstream = fault.reported;
  fault.downstream_port = port;
  const auto position = directory_.slaves()[slave].position;
  if (!position || port > 1) return fault;
  // Port 0 faces the slave before in the ring, port 1 the one after.
  const bool into = port == 0;
  if (into && *position == 0) return fault;
  const std::size_t n =
      directory_.findPosition(static_cast<std::uint16_t>(into ? *position - 1 : *position + 1));
  if (n == directory_.kNone && into) return fault;
  const SlaveRef neighbour =
      n != directory_.kNone ? refOf(n)
                            : SlaveRef{std::nullopt, static_cast<std::uint16_t>(*position + 1)};
  if (into) {
    fault.upstream = neighbour;
    fault.upstream_port = 1;
  } else {
    fault.upstream = fault.reported;
    fault.upstream_port = 1;
    fault.downstream = neighbour;
    fault.downstream_port = 0;
  }
  return fault;
}

// Each slave port with RX errors no upstream slave forwarded names the link into it, in processing
// order (the slaves downstream of a bad link count its errors as forwarded, not as their own).
void EscErrorTracker::localise(const Stamp& now, std::vector<BusEvent>& out) {
  // Slaves of unknown position keep the order they were read in, after those of known one.
  auto order = [&](std::size_t k) -> std::uint32_t {
    const auto position = directory_.slaves()[reads_this_frame_[k].slave].position;
    return position ? *position : 0x10000u + static_cast<std::uint32_t>(k);
  };
  for (std::size_t k = 0; k < reads_this_frame_.size(); ++k) reads_this_frame_[k].order = order(k);
  std::sort(reads_this_frame_.begin(), reads_this_frame_.end(),
            [](const Read& a, const Read& b) { return a.order < b.order; });
  for (const Read& read : reads_this_frame_) {
    for (std::uint8_t port = 0; port < ecat::kEscPorts; ++port) {
      const std::uint32_t received =
          read.delta[slotOf(EscCounter::Invalid, port)] + read.delta[slotOf(EscCounter::Rx, port)];
      const std::uint32_t forwarded = read.delta[slotOf(EscCounter::Forwarded, port)];
      if (received <= forwarded) continue;
      LinkFault fault = linkAt(read.slave, port);
      fault.errors = received - forwarded;
      fault.frame = now.frame;
      frame_events_.push_back(LinkErrorEvent{fault, false, read.since.frame});
      out.push_back(BusEvent{now, frame_events_.back()});
      frame_faults_.push_back(fault);
      if (faults_.size() < kMaxListed) {
        faults_.push_back(fault);
      } else {
        ++omitted_;
      }
    }
  }
}

}  // namespace ncservo
