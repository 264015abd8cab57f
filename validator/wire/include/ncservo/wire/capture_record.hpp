// One record of a capture as it was read, from a file or a live interface: the bytes, the time,
// the interface it came from and where it is stored. Plain data: whoever reads captures (libpcap)
// fills it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

#include "ncservo/wire/ethercat.hpp"

namespace ncservo {

// Where a record is stored in the capture file: the pcap record (its 16-byte header and the
// packet) or the pcapng block that holds the packet.
struct RecordSpan {
  std::uint64_t offset = 0;
  std::uint64_t length = 0;
};

struct CaptureRecord {
  std::uint64_t frame = 0;   // 1-based, as Wireshark numbers frames
  std::int64_t time_ns = 0;  // absolute capture time in nanoseconds
  const std::uint8_t* data = nullptr;
  std::size_t captured = 0;
  std::size_t original = 0;
  std::optional<RecordSpan> stored;  // none when the capture is compressed or not a plain file
  // The interface it was captured on: a pcapng's interfaces numbered in file order across its
  // sections (as capinfos lists them), 0 in a pcap. Each has its own link type
  // (docs/protocol.md §8): its number (tcpdump.org's LINKTYPE_, the same as the DLT for
  // Ethernet 1, Linux cooked 113 and 276) and what the walker makes of it.
  std::uint32_t interface = 0;
  int link_type = 0;
  LinkType link = LinkType::Unsupported;
};

}  // namespace ncservo
