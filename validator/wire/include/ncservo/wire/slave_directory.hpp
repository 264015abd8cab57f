// Which slave a register datagram addresses (docs/protocol.md §8), for the trackers that follow the
// slaves through a capture: the AL state tracker and the layout learner. A slave is known by its
// configured station address, its ring position, or both once an APWR/APRW of 0x0010 assigned the
// one to the other. Bounded: at most kMaxSlaves records, each with the tracker's own data T
// (which provides `void absorb(const T& other)` to merge what two records of one slave knew).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo {

// How a datagram addresses slaves.
enum class SlaveTarget : std::uint8_t { None, Station, Position, All };
struct SlaveAddress {
  SlaveTarget target = SlaveTarget::None;
  std::uint16_t value = 0;  // station address or ring position
};

// Offset in the captured bytes of register `reg` when the datagram's captured data holds all
// `size` bytes of it.
inline std::optional<std::size_t> registerAt(const Datagram& dg, std::uint16_t reg,
                                             std::size_t size) {
  const std::uint16_t ado = dg.ado();
  if (ado > reg) return std::nullopt;
  const std::size_t relative = std::size_t{reg} - ado;
  if (relative + size > dg.data_captured) return std::nullopt;
  return dg.data_offset + relative;
}

// Whether the datagram's captured data overlaps the registers [from, to). Logical commands do not
// address registers.
inline bool reachesRegisters(const Datagram& dg, std::uint16_t from, std::uint16_t to) {
  if (ecat::isLogical(dg.command)) return false;
  const std::size_t ado = dg.ado();
  return ado < to && ado + dg.data_captured > from;
}

// One frame's slave addressing, worked out once per frame and read by every tracker that follows
// the slaves through it (the AL state tracker and the DC clock share one): which copy it is,
// and the master copy's auto-increment addresses, since a returned copy's ADP was incremented by
// every slave (docs/protocol.md §8).
class FrameAddressing {
 public:
  // Call once per walked frame, in capture order, before addressing its datagrams. `paired`: a
  // returned copy whose master's copy was the frame just before.
  void beginFrame(const EcatFrame& frame, bool returned, bool paired) {
    returned_ = returned;
    paired_ = returned && paired;
    if (returned) return;
    master_count_ = std::min(frame.count, master_.size());
    for (std::size_t i = 0; i < master_count_; ++i) {
      master_[i] = {frame.datagrams[i].command, frame.datagrams[i].adp()};
    }
  }

  bool returned() const { return returned_; }
  bool paired() const { return paired_; }
  // Writes are taken from a master copy, and from a returned copy whose master copy was not
  // captured (a paired returned copy carries the same writes again).
  bool takesWrites() const { return !returned_ || !paired_; }
  // Reads are taken from a returned copy, of datagrams some slave answered: only a returned copy
  // holds what the slaves wrote into it.
  bool takesRead(const Datagram& dg) const {
    return returned_ && ecat::readsRegisters(dg.command) && dg.has_wkc && dg.wkc > 0;
  }

  SlaveAddress addressOf(const Datagram& dg, std::size_t index) const {
    if (ecat::isConfiguredAddress(dg.command)) return {SlaveTarget::Station, dg.adp()};
    if (ecat::isBroadcast(dg.command)) return {SlaveTarget::All, 0};
    if (!ecat::isAutoIncrement(dg.command)) return {};
    std::uint16_t adp = dg.adp();
    if (returned_) {
      if (!paired_ || index >= master_count_ || master_[index].command != dg.command) return {};
      adp = master_[index].adp;
    }
    return {SlaveTarget::Position, static_cast<std::uint16_t>((0x10000u - adp) & 0xFFFFu)};
  }

 private:
  struct MasterDatagram {
    std::uint8_t command = 0;
    std::uint16_t adp = 0;
  };
  bool returned_ = false;
  bool paired_ = false;
  std::array<MasterDatagram, ecat::kMaxDatagrams> master_{};
  std::size_t master_count_ = 0;
};

template <typename T>
class SlaveDirectory {
 public:
  static constexpr std::size_t kMaxSlaves = 4096;
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);

  struct Slave {
    std::optional<std::uint16_t> station;
    std::optional<std::uint16_t> position;
    std::optional<std::uint16_t> alias;  // configured station alias (0x0012), when seen
    T data{};
  };

  // For a tracker that addresses frames itself (FrameAddressing::beginFrame).
  void beginFrame(const EcatFrame& frame, bool returned) {
    addressing_.beginFrame(frame, returned, true);
  }
  SlaveAddress addressOf(const Datagram& dg, std::size_t index, bool returned, bool paired) const {
    if (returned && !paired && ecat::isAutoIncrement(dg.command)) return {};
    return addressing_.addressOf(dg, index);
  }

  // The station address an APWR/APRW of 0x0010 assigns (taken from the write's data).
  template <typename Fresh>
  void noteStationWrite(const Datagram& dg, const ByteReader& bytes, const SlaveAddress& address,
                        Fresh fresh) {
    if (address.target != SlaveTarget::Position || !ecat::writesSlaves(dg.command)) return;
    if (auto at = registerAt(dg, ecat::kRegStationAddress, 2)) {
      if (auto station = bytes.le16(*at)) assignStation(address.value, *station, fresh);
    }
  }
  void noteStationWrite(const Datagram& dg, const ByteReader& bytes, const SlaveAddress& address) {
    noteStationWrite(dg, bytes, address, [](T&) {});
  }

  // By configured station address, else by station alias: a master may address a slave by its
  // alias once it enabled it (DL control), which the capture seldom shows; an address that is
  // no slave's station but is one's alias is taken for that slave.
  std::size_t findStation(std::uint16_t station) const {
    for (std::size_t i = 0; i < slaves_.size(); ++i) {
      if (slaves_[i].station == station) return i;
    }
    for (std::size_t i = 0; i < slaves_.size(); ++i) {
      if (slaves_[i].alias == station) return i;
    }
    return kNone;
  }
  // A slave's station alias, written to 0x0012 or read back from it (not zero: no alias).
  void noteAlias(const Datagram& dg, const ByteReader& bytes, const SlaveAddress& address) {
    if (address.target != SlaveTarget::Station && address.target != SlaveTarget::Position) return;
    auto at = registerAt(dg, ecat::kRegStationAlias, 2);
    auto alias = at ? bytes.le16(*at) : std::nullopt;
    if (!alias || *alias == 0) return;
    const std::size_t i = slaveFor(address);
    if (i != kNone) slaves_[i].alias = *alias;
  }
  std::size_t findPosition(std::uint16_t position) const {
    for (std::size_t i = 0; i < slaves_.size(); ++i) {
      if (slaves_[i].position == position) return i;
    }
    return kNone;
  }
  // Finds or adds the slave a station or position addresses; kNone for none (or when full).
  // `fresh` initialises the data of a slave first seen now.
  template <typename Fresh>
  std::size_t slaveFor(const SlaveAddress& address, Fresh fresh) {
    std::size_t i = kNone;
    if (address.target == SlaveTarget::Station) {
      i = findStation(address.value);
      if (i == kNone && (i = add(fresh)) != kNone) slaves_[i].station = address.value;
    } else if (address.target == SlaveTarget::Position) {
      i = findPosition(address.value);
      if (i == kNone && (i = add(fresh)) != kNone) slaves_[i].position = address.value;
    }
    return i;
  }
  std::size_t slaveFor(const SlaveAddress& address) {
    return slaveFor(address, [](T&) {});
  }

  std::vector<Slave>& slaves() { return slaves_; }
  const std::vector<Slave>& slaves() const { return slaves_; }

 private:
  template <typename Fresh>
  std::size_t add(Fresh fresh) {
    if (slaves_.size() >= kMaxSlaves) return kNone;
    slaves_.push_back(Slave{});
    fresh(slaves_.back().data);
    return slaves_.size() - 1;
  }
  template <typename Fresh>
  void assignStation(std::uint16_t position, std::uint16_t station, Fresh fresh) {
    std::size_t at = findPosition(position);
    std::size_t named = findStation(station);
    if (at != kNone && at == named) return;
    if (named != kNone && slaves_[named].position) {
      // The address moves to another slave: the old holder keeps only its position.
      slaves_[named].station.reset();
      named = kNone;
    }
    if (at == kNone && named == kNone) {
      at = add(fresh);
      if (at == kNone) return;
      slaves_[at].position = position;
    } else if (at == kNone) {
      slaves_[named].position = position;
      return;
    } else if (named != kNone) {
      // The same slave was seen by station before the assignment: one record keeps both.
      slaves_[at].data.absorb(slaves_[named].data);
      slaves_.erase(slaves_.begin() + static_cast<std::ptrdiff_t>(named));
      if (named < at) --at;
    }
    slaves_[at].station = station;
  }

  std::vector<Slave> slaves_;
  FrameAddressing addressing_;
};

}  // namespace ncservo
