// Test helper: builds captured frames (docs/protocol.md §8) with the simulator's frame encoder, and
// PDO images (§1) byte by byte. Only for tests: no checks, the caller decides what is well-formed.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/sim/frame_encoder.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo::test {

using Bytes = std::vector<std::uint8_t>;

inline void putLe(Bytes& out, std::uint64_t value, std::size_t size) {
  for (std::size_t i = 0; i < size; ++i) out.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
}
inline void putFloat(Bytes& out, float value) {
  std::uint32_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  putLe(out, bits, 4);
}

// The 10-byte RxPDO: SSP, SCW, extra data code word.
inline Bytes rxPdo(std::int32_t ssp, std::uint32_t scw, std::int16_t ext_code = 0) {
  Bytes out;
  putLe(out, static_cast<std::uint32_t>(ssp), 4);
  putLe(out, scw, 4);
  putLe(out, static_cast<std::uint16_t>(ext_code), 2);
  return out;
}

struct TxValues {
  TxValues(std::int64_t actpos_ = 0, std::uint32_t ssw_ = 0, std::uint32_t sew_ = 0,
           std::int32_t msg_code_ = 0, float msg_data_ = 0, std::array<float, 4> ext_ = {})
      : actpos(actpos_),
        ssw(ssw_),
        sew(sew_),
        msg_code(msg_code_),
        msg_data(msg_data_),
        ext(ext_) {}
  std::int64_t actpos;
  std::uint32_t ssw;
  std::uint32_t sew;
  std::int32_t msg_code;
  float msg_data;
  std::array<float, 4> ext;
};
// The 40-byte TxPDO.
inline Bytes txPdo(const TxValues& v) {
  Bytes out;
  putLe(out, static_cast<std::uint64_t>(v.actpos), 8);
  putLe(out, v.ssw, 4);
  putLe(out, v.sew, 4);
  putLe(out, static_cast<std::uint32_t>(v.msg_code), 4);
  putFloat(out, v.msg_data);
  for (float e : v.ext) putFloat(out, e);
  return out;
}

inline Bytes concat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const Bytes& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

// One datagram. `more` defaults to "set unless last"; `length` overrides the declared length.
struct Dg {
  Dg(std::uint8_t cmd_, std::uint8_t index_, std::uint32_t address_, Bytes data_,
     std::uint16_t wkc_)
      : cmd(cmd_), index(index_), address(address_), data(std::move(data_)), wkc(wkc_) {}
  std::uint8_t cmd;
  std::uint8_t index;
  std::uint32_t address;  // logical address, or ADP | ADO << 16
  Bytes data;
  std::uint16_t wkc;
  std::optional<bool> more;
  std::optional<std::uint16_t> length;
  std::uint16_t irq = 0;
};

inline std::uint32_t physical(std::uint16_t adp, std::uint16_t ado) {
  return sim::physicalAddress(adp, ado);
}

enum class Link { Ethernet, Sll, Sll2 };

inline LinkType linkType(Link l) {
  switch (l) {
    case Link::Sll:
      return LinkType::LinuxSll;
    case Link::Sll2:
      return LinkType::LinuxSll2;
    case Link::Ethernet:
      break;
  }
  return LinkType::Ethernet;
}

// Builds a whole captured frame: link header, optional VLAN tags or IPv4/UDP, the EtherCAT
// frame header and the datagram chain, optional padding.
class FrameBuilder {
 public:
  FrameBuilder() {
    framing_.destination = {0x01, 0x01, 0x05, 0x01, 0x00, 0x00};
    framing_.source = {0x02, 0x00, 0x00, 0x00, 0x00, 0x01};
  }
  FrameBuilder& add(Dg dg) {
    datagrams_.push_back(std::move(dg));
    return *this;
  }
  FrameBuilder& link(Link l) {
    framing_.link = linkType(l);
    return *this;
  }
  FrameBuilder& vlan(std::uint16_t tpid = 0x8100, std::uint16_t tci = 1) {
    framing_.tags.push_back({tpid, tci});
    return *this;
  }
  FrameBuilder& etherType(std::uint16_t type) {
    framing_.ether_type = type;
    return *this;
  }
  FrameBuilder& udp(std::uint16_t port = ecat::kUdpPort, std::uint16_t fragment_offset = 0) {
    framing_.udp = sim::UdpFraming{port, fragment_offset};
    return *this;
  }
  FrameBuilder& frameType(std::uint8_t type) {
    framing_.frame_type = type;
    return *this;
  }
  FrameBuilder& headerLength(std::uint16_t length) {
    framing_.header_length = length;
    return *this;
  }
  FrameBuilder& padTo(std::size_t size) {
    framing_.min_size = size;
    return *this;
  }

  Bytes bytes() const { return encode(framing_); }
  // The EtherCAT frame header and the chain alone.
  Bytes ecat() const {
    sim::Framing plain;
    plain.frame_type = framing_.frame_type;
    plain.header_length = framing_.header_length;
    Bytes out = encode(plain);
    out.erase(out.begin(), out.begin() + kEthernetHeader);
    return out;
  }

 private:
  static constexpr std::size_t kEthernetHeader = 14;

  Bytes encode(const sim::Framing& framing) const {
    Bytes out;
    sim::FrameEncoder encoder(framing, out);
    for (const Dg& dg : datagrams_) {
      sim::DatagramFields fields;
      fields.command = dg.cmd;
      fields.index = dg.index;
      fields.address = dg.address;
      fields.wkc = dg.wkc;
      fields.irq = dg.irq;
      fields.more = dg.more;
      fields.length = dg.length;
      encoder.add(fields, dg.data.data(), dg.data.size());
    }
    encoder.finish();
    return out;
  }

  sim::Framing framing_;
  std::vector<Dg> datagrams_;
};

// A frame walked over its own heap copy of exactly its size (so ASan sees any overread).
struct Walked {
  std::unique_ptr<std::uint8_t[]> storage;
  std::size_t size = 0;
  std::unique_ptr<EcatFrame> frame = std::make_unique<EcatFrame>();

  ByteReader reader() const { return ByteReader(storage.get(), size); }
  const Datagram& dg(std::size_t i) const { return frame->datagrams[i]; }
};

inline Walked walk(const Bytes& bytes, std::size_t size, Link link = Link::Ethernet) {
  Walked w;
  w.size = size;
  w.storage.reset(new std::uint8_t[size]);  // new[0] is valid and any access to it is an overread
  if (size > 0) std::memcpy(w.storage.get(), bytes.data(), size);
  walkPacket(linkType(link), w.reader(), *w.frame);
  return w;
}
inline Walked walk(const Bytes& bytes, Link link = Link::Ethernet) {
  return walk(bytes, bytes.size(), link);
}

// Offset of the EtherCAT frame header in an untagged Ethernet frame, and of the first datagram.
inline constexpr std::size_t kEcatOffset = 14;
inline constexpr std::size_t kChainOffset = kEcatOffset + ecat::kFrameHeaderSize;

// A sync manager's 8-byte register block: start, length, control, status, activate, PDI.
inline Bytes smBlock(std::uint16_t start, std::uint16_t length, std::uint8_t control) {
  Bytes out;
  putLe(out, start, 2);
  putLe(out, length, 2);
  out.push_back(control);
  out.push_back(0);
  out.push_back(1);
  out.push_back(0);
  return out;
}
// An FMMU's 16-byte register block.
inline Bytes fmmuBlock(std::uint32_t logical, std::uint16_t length, std::uint16_t phys,
                       std::uint8_t type) {
  Bytes out;
  putLe(out, logical, 4);
  putLe(out, length, 2);
  out.push_back(0);
  out.push_back(7);
  putLe(out, phys, 2);
  out.push_back(0);
  out.push_back(type);
  out.push_back(1);
  out.resize(16, 0);
  return out;
}

// A mailbox (PROTOCOL.md §11) as the tests' SM areas hold it: kMailboxArea bytes.
inline constexpr std::size_t kMailboxArea = 48;

// Mailbox header (length, address, channel 0, type | counter << 4) and the body, padded to the
// SM area.
inline Bytes mbx(std::uint8_t type, std::uint8_t counter, const Bytes& body,
                 std::size_t pad = kMailboxArea,
                 std::optional<std::uint16_t> length = std::nullopt) {
  Bytes out;
  putLe(out, length ? *length : body.size(), 2);
  putLe(out, 0, 2);
  out.push_back(0);
  out.push_back(static_cast<std::uint8_t>(type | (counter << 4)));
  out.insert(out.end(), body.begin(), body.end());
  if (out.size() < pad) out.resize(pad, 0);
  return out;
}
// CoE header (number 0, service) and the rest.
inline Bytes coe(std::uint8_t service, const Bytes& rest) {
  Bytes out;
  putLe(out, std::uint16_t(service) << 12, 2);
  out.insert(out.end(), rest.begin(), rest.end());
  return out;
}
inline Bytes sdo(std::uint8_t command, std::uint16_t index, std::uint8_t sub, std::uint32_t data) {
  Bytes out{command};
  putLe(out, index, 2);
  out.push_back(sub);
  putLe(out, data, 4);
  return out;
}
inline Bytes emcy(std::uint16_t code, std::uint8_t reg, const Bytes& data) {
  Bytes out;
  putLe(out, code, 2);
  out.push_back(reg);
  out.insert(out.end(), data.begin(), data.end());
  return out;
}

}  // namespace ncservo::test
