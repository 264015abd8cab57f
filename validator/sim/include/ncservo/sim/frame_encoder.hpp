// Writing EtherCAT frames (docs/protocol.md §8): the framing walkPacket reads (Ethernet II with
// 802.1Q/802.1ad tags, Linux cooked captures, IPv4/UDP to port 34980), the EtherCAT frame header
// and the datagram chain. The simulator writes its frames with it; the unit tests build theirs,
// well-formed or not, through the overrides.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "ncservo/wire/ethercat.hpp"

namespace ncservo::sim {

using MacAddress = std::array<std::uint8_t, 6>;

struct VlanTag {
  std::uint16_t tpid = 0x8100;  // 0x88A8 for an 802.1ad outer tag
  std::uint16_t tci = 1;
};

// IPv4/UDP carrying the EtherCAT frame (docs/protocol.md §8).
struct UdpFraming {
  std::uint16_t port = ecat::kUdpPort;  // destination port
  std::uint16_t fragment = 0;           // IPv4 flags (0x2000: more fragments) and offset
};

struct Framing {
  LinkType link = LinkType::Ethernet;  // Ethernet, LinuxSll or LinuxSll2
  MacAddress destination{};
  MacAddress source{};        // also the link-layer address of the Linux cooked headers
  std::vector<VlanTag> tags;  // outermost first
  std::uint16_t ether_type = ecat::kEtherType;  // inside the tags (IPv4 when `udp` is set)
  std::optional<UdpFraming> udp;
  std::uint8_t frame_type = ecat::kFrameTypeDatagrams;
  std::optional<std::uint16_t> header_length;  // default: the chain's length
  std::size_t min_size = 0;                    // zero padding up to this size
};

// One datagram's header fields; `more` and `length` default to what the chain implies.
struct DatagramFields {
  std::uint8_t command = 0;
  std::uint8_t index = 0;
  std::uint32_t address = 0;  // logical address, or ADP | ADO << 16
  std::uint16_t wkc = 0;
  std::uint16_t irq = 0;
  std::optional<bool> more;             // default: set unless last
  std::optional<std::uint16_t> length;  // default: the data's size
};

inline std::uint32_t physicalAddress(std::uint16_t adp, std::uint16_t ado) {
  return adp | (std::uint32_t{ado} << 16);
}

// Writes one frame into `out` (its bytes replaced; its capacity kept, so a buffer reused frame
// after frame allocates nothing): the link header first, then each datagram, then finish().
class FrameEncoder {
 public:
  FrameEncoder(const Framing& framing, std::vector<std::uint8_t>& out);
  void add(const DatagramFields& fields, const std::uint8_t* data, std::size_t size);
  // Fills in the lengths and the padding.
  void finish();

 private:
  const Framing& framing_;
  std::vector<std::uint8_t>& out_;
  std::size_t ip_offset_ = 0;    // IPv4 header, when `udp` is set
  std::size_t ecat_offset_ = 0;  // EtherCAT frame header
  std::optional<std::size_t>
      last_length_field_;  // the previous datagram's, if its more bit is implied
};

}  // namespace ncservo::sim
