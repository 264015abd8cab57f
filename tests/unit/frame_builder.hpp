// Test helper: builds captured frames byte by byte (PROTOCOL.md §8) and PDO images (§1).
// Only for tests: no checks, the caller decides what is well-formed.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "ncservo/byte_reader.hpp"
#include "ncservo/ethercat.hpp"

namespace ncservo::test {

using Bytes = std::vector<std::uint8_t>;

inline void putLe(Bytes& out, std::uint64_t value, std::size_t size) {
  for (std::size_t i = 0; i < size; ++i) out.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
}
inline void putBe16(Bytes& out, std::uint16_t value) {
  out.push_back(static_cast<std::uint8_t>(value >> 8));
  out.push_back(static_cast<std::uint8_t>(value));
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
  return adp | (std::uint32_t{ado} << 16);
}

enum class Link { Ethernet, Sll, Sll2 };

// Builds a whole captured frame: link header, optional VLAN tags or IPv4/UDP, the EtherCAT
// frame header and the datagram chain, optional padding.
class FrameBuilder {
 public:
  FrameBuilder& add(Dg dg) {
    datagrams_.push_back(std::move(dg));
    return *this;
  }
  FrameBuilder& link(Link l) {
    link_ = l;
    return *this;
  }
  FrameBuilder& vlan(std::uint16_t tpid = 0x8100, std::uint16_t tci = 1) {
    tags_.push_back({tpid, tci});
    return *this;
  }
  FrameBuilder& etherType(std::uint16_t type) {
    ether_type_ = type;
    return *this;
  }
  FrameBuilder& udp(std::uint16_t port = ecat::kUdpPort, std::uint16_t fragment_offset = 0) {
    udp_ = Udp{port, fragment_offset};
    return *this;
  }
  FrameBuilder& frameType(std::uint8_t type) {
    frame_type_ = type;
    return *this;
  }
  FrameBuilder& headerLength(std::uint16_t length) {
    header_length_ = length;
    return *this;
  }
  FrameBuilder& padTo(std::size_t size) {
    pad_to_ = size;
    return *this;
  }

  // The EtherCAT frame header and the chain.
  Bytes ecat() const {
    Bytes chain;
    for (std::size_t i = 0; i < datagrams_.size(); ++i) {
      const Dg& dg = datagrams_[i];
      const bool more = dg.more.value_or(i + 1 < datagrams_.size());
      const auto length = dg.length.value_or(static_cast<std::uint16_t>(dg.data.size()));
      chain.push_back(dg.cmd);
      chain.push_back(dg.index);
      putLe(chain, dg.address, 4);
      putLe(chain, (length & ecat::kLengthMask) | (more ? ecat::kMoreBit : 0), 2);
      putLe(chain, dg.irq, 2);
      chain.insert(chain.end(), dg.data.begin(), dg.data.end());
      putLe(chain, dg.wkc, 2);
    }
    Bytes out;
    const auto length = header_length_.value_or(static_cast<std::uint16_t>(chain.size()));
    putLe(out, (length & ecat::kLengthMask) | (std::uint16_t{frame_type_} << 12), 2);
    out.insert(out.end(), chain.begin(), chain.end());
    return out;
  }

  Bytes bytes() const {
    Bytes out;
    switch (link_) {
      case Link::Ethernet:
        out = Bytes{0x01, 0x01, 0x05, 0x01, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x00, 0x01};
        break;
      case Link::Sll:  // packet type, ARPHRD, address length, 8 address bytes; protocol last
        out = Bytes{0x00, 0x04, 0x00, 0x01, 0x00, 0x06, 0x02, 0x00, 0x00, 0x00, 0x00, 0x01, 0, 0};
        break;
      case Link::Sll2:  // protocol first, then reserved, ifindex, ARPHRD, type, length, address
        break;
    }
    std::uint16_t type = ether_type_;
    if (udp_) type = 0x0800;
    // The outer type field, then each tag's TCI and the next type, outside in.
    std::vector<std::uint16_t> types;
    for (const auto& tag : tags_) types.push_back(tag.tpid);
    types.push_back(type);
    putBe16(out, types[0]);
    if (link_ == Link::Sll2) {
      Bytes sll2_rest{0, 0, 0, 0, 0, 1, 0, 1, 0, 6, 0x02, 0, 0, 0, 0, 1, 0, 0};
      out.insert(out.end(), sll2_rest.begin(), sll2_rest.end());
    }
    for (std::size_t i = 0; i < tags_.size(); ++i) {
      putBe16(out, tags_[i].tci);
      putBe16(out, types[i + 1]);
    }
    Bytes payload = ecat();
    if (udp_) {
      Bytes ip{0x45, 0x00};
      putBe16(ip, static_cast<std::uint16_t>(20 + 8 + payload.size()));
      putBe16(ip, 0x1234);                 // identification
      putBe16(ip, udp_->fragment_offset);  // flags (0x2000 MF) and offset in 8-byte units
      ip.push_back(64);                    // TTL
      ip.push_back(17);                    // UDP
      putBe16(ip, 0);                      // checksum, not checked
      Bytes addresses{192, 168, 0, 1, 192, 168, 0, 2};
      ip.insert(ip.end(), addresses.begin(), addresses.end());
      putBe16(ip, ecat::kUdpPort);  // source port
      putBe16(ip, udp_->port);
      putBe16(ip, static_cast<std::uint16_t>(8 + payload.size()));
      putBe16(ip, 0);
      out.insert(out.end(), ip.begin(), ip.end());
    }
    out.insert(out.end(), payload.begin(), payload.end());
    if (out.size() < pad_to_) out.resize(pad_to_, 0);
    return out;
  }

 private:
  struct Tag {
    std::uint16_t tpid;
    std::uint16_t tci;
  };
  struct Udp {
    std::uint16_t port;
    std::uint16_t fragment_offset;
  };
  std::vector<Dg> datagrams_;
  Link link_ = Link::Ethernet;
  std::vector<Tag> tags_;
  std::uint16_t ether_type_ = ecat::kEtherType;
  std::optional<Udp> udp_;
  std::uint8_t frame_type_ = ecat::kFrameTypeDatagrams;
  std::optional<std::uint16_t> header_length_;
  std::size_t pad_to_ = 0;
};

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

}  // namespace ncservo::test
