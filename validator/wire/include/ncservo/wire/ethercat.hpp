// The bounds-checked EtherCAT frame walker and what it needs of the wire (docs/protocol.md §8).
// The walker turns captured bytes into datagram views; it never reads past the captured bytes
// and never allocates.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/wire/ecat_wire.hpp"

namespace ncservo {

namespace ecat {
// What the wire facts say of a command; an unknown code addresses nothing, reads and writes
// nothing.
inline constexpr CommandFacts kUnknownCommand{"unknown", Addressing::None, false, false};
constexpr const CommandFacts& commandFacts(std::uint8_t cmd) {
  return cmd < kCommands.size() ? kCommands[cmd] : kUnknownCommand;
}
constexpr const char* commandName(std::uint8_t cmd) {
  return commandFacts(cmd).name;
}

constexpr bool isLogical(std::uint8_t cmd) {
  return commandFacts(cmd).addressing == Addressing::Logical;
}
constexpr bool isConfiguredAddress(std::uint8_t cmd) {
  return commandFacts(cmd).addressing == Addressing::Configured;
}
constexpr bool isAutoIncrement(std::uint8_t cmd) {
  return commandFacts(cmd).addressing == Addressing::AutoIncrement;
}
constexpr bool isBroadcast(std::uint8_t cmd) {
  return commandFacts(cmd).addressing == Addressing::Broadcast;
}
// Slaves increment the ADP of auto-increment and broadcast commands on the way round the ring;
// other commands come back with the address they were sent with (docs/protocol.md §8).
constexpr bool addressSurvivesRing(std::uint8_t cmd) {
  return isLogical(cmd) || isConfiguredAddress(cmd);
}
// Whether the addressed slaves' memory is written, and read, by a command (docs/protocol.md §8).
constexpr bool writesSlaves(std::uint8_t cmd) {
  return commandFacts(cmd).writes;
}
constexpr bool readsSlaves(std::uint8_t cmd) {
  return commandFacts(cmd).reads;
}
// Register access reaches slaves through the physical commands, not the logical ones.
constexpr bool readsRegisters(std::uint8_t cmd) {
  return readsSlaves(cmd) && !isLogical(cmd);
}
constexpr bool writesRegisters(std::uint8_t cmd) {
  return writesSlaves(cmd) && !isLogical(cmd);
}
}  // namespace ecat

// The 16-byte header an ET2000 probe or an EtherCAT switch-link port puts before or after the
// Ethernet frame (docs/protocol.md §8; Wireshark's `esl` dissector).
namespace esl {
inline constexpr std::size_t kHeaderSize = 16;
// The header's first 6 bytes; the fourth is 0x10 or 0x11.
inline constexpr std::array<std::uint8_t, 6> kMagic{0x01, 0x01, 0x05, 0x10, 0x00, 0x00};
inline constexpr std::uint8_t kMagicVariant = 0x11;
inline constexpr std::size_t kMagicVariantAt = 3;
inline constexpr std::size_t kFlagsOffset = 6;
inline constexpr std::size_t kTimestampOffset = 8;
inline constexpr std::uint16_t kFlagCrcError = 0x1000;
inline constexpr std::uint16_t kFlagAlignmentError = 0x0800;
inline constexpr std::uint16_t kFlagTimestampValid = 0x2000;
struct PortBit {
  std::uint16_t mask;
  std::uint8_t port;
};
inline constexpr PortBit kPortBits[] = {
    {0x0080, 0}, {0x0040, 1}, {0x0020, 2}, {0x0010, 3}, {0x0008, 4},  {0x0004, 5},
    {0x0002, 6}, {0x0001, 7}, {0x8000, 8}, {0x4000, 9}, {0x0400, 10}, {0x0200, 11},
};
}  // namespace esl

// What the probe recorded about a frame, when it came with an ESL header.
struct ProbeHeader {
  bool present = false;
  bool before = false;  // the header precedes the Ethernet frame (else it is appended)
  std::uint16_t flags = 0;
  std::uint64_t timestamp_ns = 0;  // the probe's clock: only differences mean anything

  bool crcError() const { return (flags & esl::kFlagCrcError) != 0; }
  bool alignmentError() const { return (flags & esl::kFlagAlignmentError) != 0; }
  bool timestampValid() const { return (flags & esl::kFlagTimestampValid) != 0; }
  // The probe port the frame was seen on; none when no port bit is set.
  std::optional<std::uint8_t> port() const {
    for (const esl::PortBit& bit : esl::kPortBits) {
      if ((flags & bit.mask) != 0) return bit.port;
    }
    return std::nullopt;
  }
};

struct Datagram {
  std::uint8_t command = 0;
  std::uint8_t index = 0;
  std::uint32_t address = 0;  // logical address, or ADP (low 16 bits) and ADO (high 16 bits)
  std::uint16_t length = 0;   // data length the header declares
  bool circulating = false;
  std::uint16_t irq = 0;
  std::size_t header_offset = 0;  // in the buffer given to the walker
  std::size_t data_offset = 0;
  std::size_t data_captured = 0;  // bytes of data actually captured (<= length)
  bool has_wkc = false;           // false when the frame is cut before the working counter
  std::uint16_t wkc = 0;

  std::uint16_t adp() const { return static_cast<std::uint16_t>(address & 0xFFFF); }
  std::uint16_t ado() const { return static_cast<std::uint16_t>(address >> 16); }
  bool complete() const { return data_captured == length && has_wkc; }
};

enum class WalkStatus : std::uint8_t {
  Ok,
  NotEtherCat,   // no EtherCAT frame in these bytes (other traffic)
  NotDatagrams,  // an EtherCAT frame of another type (not process data)
  Truncated,     // the captured bytes end inside the chain: datagrams before it are valid
  BusFault,      // an EtherCAT frame the probe saw with a CRC error: walked, not process data
};

struct EcatFrame {
  WalkStatus status = WalkStatus::NotEtherCat;
  std::size_t ecat_offset = 0;      // offset of the EtherCAT frame header
  std::uint16_t header_length = 0;  // chain length the frame header declares
  std::size_t chain_length = 0;     // bytes the walked chain really spans
  std::size_t truncated_at = 0;     // offset where the captured bytes ran out (Truncated)
  std::size_t count = 0;            // datagrams in `datagrams`, a partial last one included
  std::array<Datagram, ecat::kMaxDatagrams> datagrams{};
  ProbeHeader probe;  // present when the frame came through an ESL probe (Ethernet link only)

  // Same datagram list: what pairs a master's frame with its returned copy (docs/protocol.md §8).
  bool sameDatagramList(const EcatFrame& other) const;
  bool anyWkcAboveZero() const;
  // Whether the frame may carry a servo's PDOs once the layout is known: a logical datagram, or
  // one addressed to a slave's process memory (above its registers), as a physical exchange is.
  bool mayCarryProcessData() const;
};

// Link-layer framings the walker can start from.
enum class LinkType : std::uint8_t { Ethernet, LinuxSll, LinuxSll2, Unsupported };
LinkType linkTypeFromDlt(int dlt);

// Walks the EtherCAT frame that starts at `offset` (its 2-byte frame header).
void walkEcat(const ByteReader& bytes, std::size_t offset, EcatFrame& out);

// Finds the EtherCAT frame in a captured packet (Ethernet II with any number of 802.1Q/802.1ad
// tags, or IPv4/IPv6 UDP to port 34980; on the Ethernet link type behind or before an ESL
// probe header) and walks it.
void walkPacket(LinkType link, const ByteReader& bytes, EcatFrame& out);

}  // namespace ncservo
