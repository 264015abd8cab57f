#include "ncservo/sim/frame_encoder.hpp"

#include "ncservo/base/little_endian.hpp"

namespace ncservo::sim {
namespace {

constexpr std::uint16_t kEtherTypeIpv4 = 0x0800;
constexpr std::size_t kIpv4HeaderSize = 20;
constexpr std::size_t kIpv4TotalLength = 2;  // field offsets in the IPv4 and UDP headers
constexpr std::size_t kUdpLength = 4;
constexpr std::uint8_t kIpProtocolUdp = 17;
// Linux cooked capture headers (LINKTYPE_LINUX_SLL, LINKTYPE_LINUX_SLL2).
constexpr std::uint16_t kSllOutgoing = 4;  // packet type: sent by this host
constexpr std::uint16_t kArphrdEther = 1;
constexpr std::uint32_t kSll2InterfaceIndex = 1;

void putBe16(std::vector<std::uint8_t>& out, std::uint16_t value) {
  out.push_back(static_cast<std::uint8_t>(value >> 8));
  out.push_back(static_cast<std::uint8_t>(value));
}
void setBe16(std::vector<std::uint8_t>& out, std::size_t at, std::uint16_t value) {
  out[at] = static_cast<std::uint8_t>(value >> 8);
  out[at + 1] = static_cast<std::uint8_t>(value);
}
// The link-layer address field of the cooked headers: 8 bytes, the MAC then zeros.
void putLinkAddress(std::vector<std::uint8_t>& out, const MacAddress& mac) {
  out.insert(out.end(), mac.begin(), mac.end());
  out.insert(out.end(), 2, 0);
}

}  // namespace

FrameEncoder::FrameEncoder(const Framing& framing, std::vector<std::uint8_t>& out)
    : framing_(framing), out_(out) {
  out_.clear();
  const std::uint16_t inner = framing.udp ? kEtherTypeIpv4 : framing.ether_type;
  const std::uint16_t outer = framing.tags.empty() ? inner : framing.tags.front().tpid;
  switch (framing.link) {
    case LinkType::LinuxSll:  // packet type, ARPHRD, address length, address, protocol
      putBe16(out_, kSllOutgoing);
      putBe16(out_, kArphrdEther);
      putBe16(out_, static_cast<std::uint16_t>(framing.source.size()));
      putLinkAddress(out_, framing.source);
      putBe16(out_, outer);
      break;
    case LinkType::LinuxSll2:  // protocol, reserved, interface index, ARPHRD, packet type, address
      putBe16(out_, outer);
      putBe16(out_, 0);
      putBe16(out_, static_cast<std::uint16_t>(kSll2InterfaceIndex >> 16));
      putBe16(out_, static_cast<std::uint16_t>(kSll2InterfaceIndex));
      putBe16(out_, kArphrdEther);
      out_.push_back(static_cast<std::uint8_t>(kSllOutgoing));
      out_.push_back(static_cast<std::uint8_t>(framing.source.size()));
      putLinkAddress(out_, framing.source);
      break;
    default:  // Ethernet II
      out_.insert(out_.end(), framing.destination.begin(), framing.destination.end());
      out_.insert(out_.end(), framing.source.begin(), framing.source.end());
      putBe16(out_, outer);
      break;
  }
  // Each tag's TCI and the type it carries, outside in.
  for (std::size_t i = 0; i < framing.tags.size(); ++i) {
    putBe16(out_, framing.tags[i].tci);
    putBe16(out_, i + 1 < framing.tags.size() ? framing.tags[i + 1].tpid : inner);
  }
  if (framing.udp) {
    ip_offset_ = out_.size();
    out_.push_back(0x45);  // IPv4, 5 words of header
    out_.push_back(0);
    putBe16(out_, 0);       // total length, in finish()
    putBe16(out_, 0x1234);  // identification
    putBe16(out_, framing.udp->fragment);
    out_.push_back(64);  // TTL
    out_.push_back(kIpProtocolUdp);
    putBe16(out_, 0);  // header checksum: not checked by readers of captures
    for (std::uint8_t b : {192, 168, 0, 1, 192, 168, 0, 2}) out_.push_back(b);
    putBe16(out_, ecat::kUdpPort);  // source port
    putBe16(out_, framing.udp->port);
    putBe16(out_, 0);  // UDP length, in finish()
    putBe16(out_, 0);  // checksum: none
  }
  ecat_offset_ = out_.size();
  out_.insert(out_.end(), ecat::kFrameHeaderSize, 0);
}

void FrameEncoder::add(const DatagramFields& fields, const std::uint8_t* data, std::size_t size) {
  if (last_length_field_) out_[*last_length_field_ + 1] |= ecat::kMoreBit >> 8;
  last_length_field_.reset();
  out_.push_back(fields.command);
  out_.push_back(fields.index);
  appendLe(out_, fields.address, 4);
  if (!fields.more) last_length_field_ = out_.size();
  const std::uint16_t length = fields.length.value_or(static_cast<std::uint16_t>(size));
  appendLe(out_, (length & ecat::kLengthMask) | (fields.more.value_or(false) ? ecat::kMoreBit : 0),
           2);
  appendLe(out_, fields.irq, 2);
  out_.insert(out_.end(), data, data + size);
  appendLe(out_, fields.wkc, ecat::kWkcSize);
}

void FrameEncoder::finish() {
  const std::size_t chain = out_.size() - ecat_offset_ - ecat::kFrameHeaderSize;
  const std::uint16_t length = framing_.header_length.value_or(static_cast<std::uint16_t>(chain));
  const auto header =
      static_cast<std::uint16_t>((length & ecat::kLengthMask) | (framing_.frame_type << 12));
  storeLe<2>(&out_[ecat_offset_], header);
  if (framing_.udp) {
    const std::size_t udp_length = out_.size() - ip_offset_ - kIpv4HeaderSize;
    setBe16(out_, ip_offset_ + kIpv4TotalLength,
            static_cast<std::uint16_t>(kIpv4HeaderSize + udp_length));
    setBe16(out_, ip_offset_ + kIpv4HeaderSize + kUdpLength,
            static_cast<std::uint16_t>(udp_length));
  }
  if (out_.size() < framing_.min_size) out_.resize(framing_.min_size, 0);
}

}  // namespace ncservo::sim
