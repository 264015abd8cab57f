// The records of a pcap or pcapng capture read in place from its bytes (docs/protocol.md §8):
// the same records, times and error texts as libpcap 1.10's offline reader, without its two
// copies of every record. A pcapng is read as Wireshark reads it, beyond what libpcap opens
// (docs/protocol.md §8): its interfaces may have different link types and snapshot lengths, and
// each record carries its interface and link type. The file header was already checked (libpcap
// opened it); what follows is untrusted: every length is checked against the bytes that are there
// before it is used.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "ncservo/wire/capture_record.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo {

// A capture's bytes seen through a window [base, base + size) that its source moves forward and
// extends on request: the whole file when it is mapped, a buffer of decompressed bytes otherwise.
class CaptureBytes {
 public:
  virtual ~CaptureBytes() = default;

  // The `n` bytes at `offset`, or nullptr when the capture ends before (`got`: how many are
  // there). Asking for bytes at `offset` may drop those before it from a buffered window.
  const std::uint8_t* at(std::uint64_t offset, std::size_t n, std::size_t& got) {
    if (offset >= base_ && offset - base_ <= size_ && n <= size_ - (offset - base_)) {
      return data_ + (offset - base_);
    }
    return slowAt(offset, n, got);
  }

 protected:
  // Makes the window start at or before `offset` and hold the `n` bytes from there, or all the
  // capture has up to its end.
  virtual void extend(std::uint64_t offset, std::size_t n) = 0;

  const std::uint8_t* data_ = nullptr;
  std::uint64_t base_ = 0;
  std::size_t size_ = 0;

 private:
  const std::uint8_t* slowAt(std::uint64_t offset, std::size_t n, std::size_t& got);
};

// Bytes that are all in memory already (a mapped file, a test's buffer).
class MemoryBytes : public CaptureBytes {
 public:
  MemoryBytes(const std::uint8_t* data, std::size_t size) {
    data_ = data;
    size_ = size;
  }

 protected:
  void extend(std::uint64_t /*offset*/, std::size_t /*n*/) override {}
};

// What the file header said (libpcap read it: pcap_datalink, pcap_snapshot, pcap_is_swapped,
// the version).
struct RecordFormat {
  bool pcapng = false;
  bool big_endian = false;     // the byte order of the file (of its first section)
  int dlt = 0;                 // a pcap's link type (a pcapng's interfaces say their own)
  std::uint32_t snapshot = 0;  // libpcap's snapshot length (0 and too large already adjusted)
  int version_major = 2;       // pcap: old versions stored the two lengths the other way round
  int version_minor = 4;
  bool nanoseconds = false;  // pcap: the nanosecond magic
};

class RecordParser {
 public:
  // An interface statistics block, whole, in its section's byte order.
  using StatisticsSink =
      std::function<void(const std::uint8_t* block, std::size_t length, bool big)>;

  RecordParser(CaptureBytes& bytes, const RecordFormat& format, StatisticsSink statistics);

  enum class Outcome : std::uint8_t { Record, End, Failed };
  // The next record: its time, bytes (valid until the next call; longer where the window is a
  // mapped file), lengths and place in the capture (`stored`). `frame` is left to the caller.
  // Failed: error() says why in libpcap's words.
  Outcome next(CaptureRecord& record);
  const std::string& error() const { return error_; }
  // The interfaces of the current pcapng section described so far (1 for a pcap).
  std::size_t sectionInterfaces() const { return section_interfaces_; }

  // The most interfaces one section may describe: their descriptions are kept while the section
  // lasts, so a file of nothing else must not take memory without bound.
  static constexpr std::size_t kMaxSectionInterfaces = 1 << 16;

 private:
  struct Interface {
    std::uint64_t resolution = 1000000;  // units of a second
    std::int64_t offset = 0;             // seconds added (if_tsoffset)
    bool binary = false;                 // resolution is a power of 2
    int link_type = 0;
    LinkType link = LinkType::Unsupported;
    std::uint32_t snapshot = 0;  // the longest record it may hold (a simple packet's length)
    bool limited = false;        // a longer record is an error (else only counted, never walked)
    std::uint32_t id = 0;        // in the file, across sections
  };

  // A pcapng block, whole and checked: its place, type and length, its bytes and body.
  struct PcapngBlock {
    std::uint64_t start = 0;
    std::uint32_t type = 0;
    std::uint32_t length = 0;
    const std::uint8_t* bytes = nullptr;
    const std::uint8_t* body = nullptr;
    std::size_t size = 0;  // of the body
  };

  Outcome nextPcap(CaptureRecord& record);
  Outcome nextPcapng(CaptureRecord& record);
  // The next block into `block` (Record), or the end, or why it cannot be read.
  Outcome readBlock(PcapngBlock& block);
  Outcome readPacket(const PcapngBlock& block, CaptureRecord& record);
  static std::int64_t packetTime(const Interface& at, std::uint64_t ticks);
  // The blocks that are no packet: false (error() says why) when one is malformed.
  bool readInterface(const PcapngBlock& block);
  bool readSectionHeader(const PcapngBlock& block);
  void keepStatistics(const PcapngBlock& block);
  Outcome tooShort(const PcapngBlock& block);
  Outcome noInterface(std::uint32_t interface);
  Outcome failed(std::string why);
  bool addInterface(const std::uint8_t* options, std::size_t size, std::uint32_t type,
                    Interface added);
  void flushStatistics();

  CaptureBytes& bytes_;
  RecordFormat format_;
  StatisticsSink statistics_;
  std::uint64_t at_ = 0;  // the next record's (block's) offset
  bool big_ = false;
  enum class Lengths : std::uint8_t { Kept, Swapped, MaybeSwapped } lengths_ = Lengths::Kept;
  bool first_interface_ = true;         // the next interface description is the capture's first
  std::vector<Interface> interfaces_;   // of the current section
  std::size_t section_interfaces_ = 1;  // interfaces_.size() for a pcapng, asked every record
  std::uint32_t interfaces_seen_ = 0;   // in the sections before and this one: the next one's id
  LinkType pcap_link_ = LinkType::Unsupported;
  // Statistics blocks passed since the last record: counted once a record or the end follows
  // (as the libpcap path counts them).
  std::vector<std::uint8_t> pending_statistics_;
  std::string error_;
};

}  // namespace ncservo
