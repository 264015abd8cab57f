#include "ncservo/capture/record_parser.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <limits>

namespace ncservo {

namespace {

std::uint32_t load32(const std::uint8_t* p, bool big) {
  return big ? (std::uint32_t{p[0]} << 24 | std::uint32_t{p[1]} << 16 | std::uint32_t{p[2]} << 8 |
                p[3])
             : (std::uint32_t{p[3]} << 24 | std::uint32_t{p[2]} << 16 | std::uint32_t{p[1]} << 8 |
                p[0]);
}

std::uint16_t load16(const std::uint8_t* p, bool big) {
  return static_cast<std::uint16_t>(big ? (p[0] << 8 | p[1]) : (p[1] << 8 | p[0]));
}

std::uint64_t load64(const std::uint8_t* p, bool big) {
  const std::uint64_t first = load32(p, big), second = load32(p + 4, big);
  return big ? first << 32 | second : second << 32 | first;
}

// libpcap's max_snaplen_for_dlt for the link types ncservo opens (Ethernet, SLL, SLL2).
constexpr std::uint32_t kMaxSnaplen = 262144;
constexpr std::size_t kPcapFileHeader = 24;
constexpr std::size_t kPcapRecordHeader = 16;
// pcapng (draft-ietf-opsawg-pcapng §4): block types, the byte-order magic, IDB options.
constexpr std::uint32_t kSectionHeaderBlock = 0x0A0D0D0A;
constexpr std::uint32_t kInterfaceBlock = 1;
constexpr std::uint32_t kPacketBlock = 2;  // obsolete
constexpr std::uint32_t kSimplePacketBlock = 3;
constexpr std::uint32_t kStatisticsBlock = 5;
constexpr std::uint32_t kEnhancedPacketBlock = 6;
constexpr std::uint32_t kByteOrderMagic = 0x1A2B3C4D;
constexpr std::uint32_t kByteOrderSwapped = 0x4D3C2B1A;
constexpr std::uint16_t kOptionEnd = 0, kOptionTsresol = 9, kOptionTsoffset = 14;
constexpr std::size_t kBlockHeader = 8, kBlockTrailer = 4;
// libpcap's largest block: 16 MiB, or an EPB of the largest snapshot and 128 KiB of options.
constexpr std::uint32_t kMaxBlock =
    std::max<std::uint32_t>(16 * 1024 * 1024, 8 + 20 + kMaxSnaplen + 131072 + 4);
constexpr std::uint64_t kNanosecond = 1000000000;
constexpr std::size_t kMaxStatistics = 1 << 16;
constexpr std::size_t kMaxPending = 1 << 20;

// pcap's and libpcap's time to nanoseconds as CaptureReader's libpcap path computes it from the
// pcap_pkthdr (seconds clamped to pcap's unsigned 32-bit range; tv_usec holds nanoseconds).
std::int64_t nanoseconds(std::int64_t seconds, std::int64_t fraction) {
  constexpr std::int64_t kMaxSeconds = 0xFFFFFFFF;
  return std::clamp<std::int64_t>(seconds, 0, kMaxSeconds) * 1000000000 + fraction;
}

}  // namespace

const std::uint8_t* CaptureBytes::slowAt(std::uint64_t offset, std::size_t n, std::size_t& got) {
  extend(offset, n);
  if (offset >= base_ && offset - base_ <= size_) {
    const std::size_t there = size_ - static_cast<std::size_t>(offset - base_);
    if (n <= there) return data_ + (offset - base_);
    got = there;
  } else {
    got = 0;
  }
  return nullptr;
}

RecordParser::RecordParser(CaptureBytes& bytes, const RecordFormat& format,
                           StatisticsSink statistics)
    : bytes_(bytes),
      format_(format),
      statistics_(std::move(statistics)),
      at_(format.pcapng ? 0 : kPcapFileHeader),
      big_(format.big_endian),
      pcap_link_(linkTypeFromDlt(format.dlt)) {
  if (format.pcapng) section_interfaces_ = 0;
  // Versions before 2.3 wrote the two lengths the other way round; 2.3 did either (sf-pcap.c).
  if (format.version_major == 543 || (format.version_major == 2 && format.version_minor < 3)) {
    lengths_ = Lengths::Swapped;
  } else if (format.version_major == 2 && format.version_minor == 3) {
    lengths_ = Lengths::MaybeSwapped;
  }
}

RecordParser::Outcome RecordParser::failed(std::string why) {
  error_ = std::move(why);
  return Outcome::Failed;
}

void RecordParser::flushStatistics() {
  std::size_t at = 0;
  while (at + 8 <= pending_statistics_.size()) {
    const std::uint32_t length = load32(&pending_statistics_[at], false);  // host order, below
    const bool big = pending_statistics_[at + 4] != 0;
    if (statistics_) statistics_(&pending_statistics_[at + 8], length, big);
    at += 8 + length;
  }
  pending_statistics_.clear();
}

RecordParser::Outcome RecordParser::next(CaptureRecord& record) {
  const Outcome outcome = format_.pcapng ? nextPcapng(record) : nextPcap(record);
  if (outcome != Outcome::Failed && !pending_statistics_.empty()) flushStatistics();
  return outcome;
}

// pcap-savefile(5): a 16-byte record header (seconds, fraction, captured and original length)
// and the captured bytes; checked and worded as libpcap's sf-pcap.c does.
RecordParser::Outcome RecordParser::nextPcap(CaptureRecord& record) {
  std::size_t got = 0;
  const std::uint8_t* head = bytes_.at(at_, kPcapRecordHeader, got);
  if (head == nullptr) {
    if (got == 0) return Outcome::End;
    return failed(fmt::format("truncated dump file; tried to read {} header bytes, only got {}",
                              kPcapRecordHeader, got));
  }
  const bool big = big_;
  // Seconds and fraction are signed 32-bit fields (struct pcap_timeval).
  const auto seconds = static_cast<std::int32_t>(load32(head, big));
  std::int64_t fraction = static_cast<std::int32_t>(load32(head + 4, big));
  std::uint32_t captured = load32(head + 8, big);
  std::uint32_t original = load32(head + 12, big);
  if (!format_.nanoseconds) fraction *= 1000;
  if (lengths_ == Lengths::Swapped || (lengths_ == Lengths::MaybeSwapped && captured > original)) {
    std::swap(captured, original);
  }
  const std::uint32_t snapshot = format_.snapshot;
  if (captured > kMaxSnaplen) {
    if (captured > snapshot) {
      return failed(fmt::format("invalid packet capture length {}, bigger than snaplen of {}",
                                captured, static_cast<std::int32_t>(snapshot)));
    }
    return failed(fmt::format("invalid packet capture length {}, bigger than maximum of {}",
                              captured, kMaxSnaplen));
  }
  const std::uint64_t start = at_;
  const std::uint8_t* data = nullptr;
  std::size_t kept = captured;
  if (captured > snapshot) {
    // Longer than the snapshot length: its first bytes are kept, the rest passed over.
    if (bytes_.at(start + kPcapRecordHeader, snapshot, got) == nullptr) {
      return failed(fmt::format("truncated dump file; tried to read {} captured bytes, only got {}",
                                static_cast<std::int32_t>(snapshot), got));
    }
    kept = snapshot;
  }
  data = bytes_.at(start + kPcapRecordHeader, captured, got);
  if (data == nullptr) {
    return failed(fmt::format("truncated dump file; tried to read {} captured bytes, only got {}",
                              captured, got));
  }
  at_ = start + kPcapRecordHeader + captured;
  record.time_ns = nanoseconds(seconds, fraction);
  record.data = data;
  record.captured = kept;
  record.original = original;
  record.stored = RecordSpan{start, kPcapRecordHeader + std::uint64_t{captured}};
  record.interface = 0;
  record.link_type = format_.dlt;
  record.link = pcap_link_;
  return Outcome::Record;
}

// pcapng blocks (type, total length, body, total length again) read as libpcap's sf-pcapng.c
// does: packets from enhanced, simple and obsolete packet blocks; interfaces and sections as they
// come; other blocks passed over by their length.
RecordParser::Outcome RecordParser::nextPcapng(CaptureRecord& record) {
  for (;;) {
    PcapngBlock block;
    if (const Outcome read = readBlock(block); read != Outcome::Record) return read;
    switch (block.type) {
      case kEnhancedPacketBlock:
      case kPacketBlock:
      case kSimplePacketBlock:
        return readPacket(block, record);
      case kInterfaceBlock:
        if (!readInterface(block)) return Outcome::Failed;
        continue;
      case kSectionHeaderBlock:
        if (!readSectionHeader(block)) return Outcome::Failed;
        continue;
      case kStatisticsBlock:
        keepStatistics(block);
        continue;
      default:
        continue;
    }
  }
}

RecordParser::Outcome RecordParser::readBlock(PcapngBlock& block) {
  std::size_t got = 0;
  const std::uint64_t start = at_;
  const std::uint8_t* head = bytes_.at(start, kBlockHeader, got);
  if (head == nullptr) {
    if (got == 0) return Outcome::End;
    return failed(fmt::format("truncated pcapng dump file; tried to read {} bytes, only got {}",
                              kBlockHeader, got));
  }
  const std::uint32_t type = load32(head, big_);
  const std::uint32_t length = load32(head + 4, big_);
  if (length < kBlockHeader + kBlockTrailer) {
    return failed(fmt::format("block in pcapng dump file has a length of {} < {}", length,
                              kBlockHeader + kBlockTrailer));
  }
  if (length % 4 != 0) {
    return failed(fmt::format(
        "block in pcapng dump file has a length of {} that is not a multiple of 4", length));
  }
  if (length > kMaxBlock) {
    return failed(fmt::format("pcapng block size {} > maximum {}", length, kMaxBlock));
  }
  const std::uint8_t* bytes = bytes_.at(start, length, got);
  if (bytes == nullptr) {
    return failed(fmt::format("truncated pcapng dump file; tried to read {} bytes, only got {}",
                              length - kBlockHeader, got - kBlockHeader));
  }
  if (load32(bytes + length - kBlockTrailer, big_) != length) {
    return failed("block total length in header and trailer don't match");
  }
  at_ = start + length;
  block = {.start = start,
           .type = type,
           .length = length,
           .bytes = bytes,
           .body = bytes + kBlockHeader,
           .size = length - kBlockHeader - kBlockTrailer};
  return Outcome::Record;
}

RecordParser::Outcome RecordParser::noInterface(std::uint32_t interface) {
  return failed(
      fmt::format("a packet arrived on interface {}, but there's no Interface "
                  "Description Block for that interface",
                  interface));
}

RecordParser::Outcome RecordParser::tooShort(const PcapngBlock& block) {
  return failed(fmt::format("block of type {} in pcapng dump file is too short", block.type));
}

RecordParser::Outcome RecordParser::readPacket(const PcapngBlock& block, CaptureRecord& record) {
  const std::uint8_t* body = block.body;
  std::uint32_t interface = 0;
  std::uint64_t ticks = 0;
  std::uint32_t captured = 0;
  std::uint32_t original = 0;
  std::size_t fixed = 0;  // the packet's bytes follow
  if (block.type == kSimplePacketBlock) {
    fixed = 4;
    if (block.size < fixed) return tooShort(block);
    original = load32(body, big_);
    // Of interface 0, whose snapshot length says what was kept.
    if (interfaces_.empty()) return noInterface(0);
    captured = std::min(original, interfaces_.front().snapshot);
  } else {
    fixed = 20;
    if (block.size < fixed) return tooShort(block);
    interface = block.type == kEnhancedPacketBlock ? load32(body, big_) : load16(body, big_);
    ticks = std::uint64_t{load32(body + 4, big_)} << 32 | load32(body + 8, big_);
    captured = load32(body + 12, big_);
    original = load32(body + 16, big_);
  }
  if (interface >= interfaces_.size()) return noInterface(interface);
  const Interface& at = interfaces_[interface];
  // Only a record that will be walked is held to its snapshot length (as libpcap holds every
  // record to the first interface's); any record is held to its block.
  if (at.limited && captured > at.snapshot) {
    return failed(fmt::format("invalid packet capture length {}, bigger than snaplen of {}",
                              captured, static_cast<std::int32_t>(at.snapshot)));
  }
  const std::int64_t time_ns = packetTime(at, ticks);
  if (block.size - fixed < captured) return tooShort(block);
  record.time_ns = time_ns;
  record.data = body + fixed;
  record.captured = captured;
  record.original = original;
  record.stored = RecordSpan{block.start, block.length};
  record.interface = at.id;
  record.link_type = at.link_type;
  record.link = at.link;
  return Outcome::Record;
}

// libpcap's arithmetic: unsigned 64-bit, the fraction scaled to nanoseconds, then handed over as
// a time_t and an int.
std::int64_t RecordParser::packetTime(const Interface& at, std::uint64_t ticks) {
  const std::uint64_t seconds = ticks / at.resolution + static_cast<std::uint64_t>(at.offset);
  std::uint64_t fraction = ticks % at.resolution;
  if (at.resolution != kNanosecond) {
    if (at.binary) {
      fraction = fraction * kNanosecond / at.resolution;
    } else if (at.resolution > kNanosecond) {
      fraction /= at.resolution / kNanosecond;
    } else {
      fraction *= kNanosecond / at.resolution;
    }
  }
  return nanoseconds(static_cast<std::int64_t>(seconds),
                     static_cast<std::int32_t>(static_cast<std::uint32_t>(fraction)));
}

// Each interface with its own link type and snapshot length, as Wireshark reads them (libpcap
// refuses a second interface whose link type or snapshot length is not the first one's):
// docs/protocol.md §8.
bool RecordParser::readInterface(const PcapngBlock& block) {
  if (block.size < 8) {
    tooShort(block);
    return false;
  }
  if (interfaces_.size() >= kMaxSectionInterfaces) {
    failed(fmt::format("a section describes more than {} interfaces", kMaxSectionInterfaces));
    return false;
  }
  Interface added;
  added.link_type = load16(block.body, big_);
  added.link = linkTypeFromDlt(added.link_type);
  const std::uint32_t snaplen = load32(block.body + 4, big_);
  // The capture's first interface keeps libpcap's snapshot length (it opened the file with it).
  added.snapshot = first_interface_                        ? format_.snapshot
                   : snaplen == 0 || snaplen > kMaxSnaplen ? kMaxSnaplen
                                                           : snaplen;
  added.limited = added.link != LinkType::Unsupported;
  added.id = interfaces_seen_;
  first_interface_ = false;
  if (!addInterface(block.body + 8, block.size - 8, block.type, added)) return false;
  if (interfaces_seen_ < std::numeric_limits<std::uint32_t>::max()) ++interfaces_seen_;
  section_interfaces_ = interfaces_.size();
  return true;
}

bool RecordParser::readSectionHeader(const PcapngBlock& block) {
  if (block.size < 16) {
    tooShort(block);
    return false;
  }
  // In the byte order of the section before: a new one may not change it.
  const std::uint32_t magic = load32(block.body, big_);
  if (magic == kByteOrderSwapped) {
    failed("the file has sections with different byte orders");
    return false;
  }
  if (magic != kByteOrderMagic) {
    failed("the file has a section with a bad byte order magic field");
    return false;
  }
  const std::uint16_t major = load16(block.body + 4, big_);
  if (major != 1) {
    failed(fmt::format("unknown pcapng savefile major version number {}", major));
    return false;
  }
  interfaces_.clear();
  section_interfaces_ = 0;
  return true;
}

// Kept with its length and byte order in front, for flushStatistics. A statistics block is small:
// larger ones are passed over, and many between two records are counted at once.
void RecordParser::keepStatistics(const PcapngBlock& block) {
  if (block.length > kMaxStatistics) return;
  if (pending_statistics_.size() > kMaxPending) flushStatistics();
  const std::size_t was = pending_statistics_.size();
  pending_statistics_.resize(was + 8 + block.length);
  const std::uint32_t kept = block.length;
  std::memcpy(&pending_statistics_[was], &kept, 4);
  pending_statistics_[was + 4] = big_ ? 1 : 0;
  std::copy(block.bytes, block.bytes + block.length,
            pending_statistics_.begin() + static_cast<long>(was) + 8);
}

// An interface description's options: if_tsresol and if_tsoffset say how to read its times;
// checked and worded as libpcap's process_idb_options.
bool RecordParser::addInterface(const std::uint8_t* options, std::size_t size, std::uint32_t type,
                                Interface added) {
  bool saw_resolution = false, saw_offset = false;
  std::size_t at = 0;
  while (at < size) {
    if (size - at < 4) {
      failed(fmt::format("block of type {} in pcapng dump file is too short", type));
      return false;
    }
    const std::uint16_t code = load16(options + at, big_);
    const std::uint16_t length = load16(options + at + 2, big_);
    const std::size_t padded = (std::size_t{length} + 3) / 4 * 4;
    at += 4;
    if (size - at < padded) {
      failed(fmt::format("block of type {} in pcapng dump file is too short", type));
      return false;
    }
    const std::uint8_t* value = options + at;
    at += padded;
    if (code == kOptionEnd) {
      if (length != 0) {
        failed(fmt::format(
            "Interface Description Block has opt_endofopt option with length {} != 0", length));
        return false;
      }
      break;
    }
    if (code == kOptionTsresol) {
      if (length != 1) {
        failed(fmt::format("Interface Description Block has if_tsresol option with length {} != 1",
                           length));
        return false;
      }
      if (saw_resolution) {
        failed("Interface Description Block has more than one if_tsresol option");
        return false;
      }
      saw_resolution = true;
      const std::uint8_t resolution = value[0];
      if ((resolution & 0x80) != 0) {
        const unsigned shift = resolution & 0x7F;
        if (shift > 63) {
          failed(fmt::format(
              "Interface Description Block if_tsresol option resolution 2^-{} is too high", shift));
          return false;
        }
        added.binary = true;
        added.resolution = std::uint64_t{1} << shift;
      } else {
        if (resolution > 19) {
          failed(fmt::format(
              "Interface Description Block if_tsresol option resolution 10^-{} is too high",
              resolution));
          return false;
        }
        added.binary = false;
        added.resolution = 1;
        for (unsigned i = 0; i < resolution; ++i) added.resolution *= 10;
      }
    } else if (code == kOptionTsoffset) {
      if (length != 8) {
        failed(fmt::format("Interface Description Block has if_tsoffset option with length {} != 8",
                           length));
        return false;
      }
      if (saw_offset) {
        failed("Interface Description Block has more than one if_tsoffset option");
        return false;
      }
      saw_offset = true;
      added.offset = static_cast<std::int64_t>(load64(value, big_));
    }
  }
  interfaces_.push_back(added);
  return true;
}

}  // namespace ncservo
