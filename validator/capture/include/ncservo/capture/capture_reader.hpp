// Reads pcap and pcapng captures (libpcap) record by record, in constant memory; gzip- and
// zstd-compressed ones too (docs/protocol.md §8), recognised by their first bytes, not their names.
// A pcapng's interfaces may have different link types (docs/protocol.md §8): each record says its
// own, and a record of a link type the walker does not know is still a record.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/wire/capture_record.hpp"
#include "ncservo/wire/ethercat.hpp"

struct pcap;  // libpcap's handle, kept out of this header

namespace ncservo {

// The digits of a second the capture's timestamps hold (6: microseconds, 9: nanoseconds), from
// its first bytes: the pcap magic, or if_tsresol of the first pcapng interface (6 when absent).
int timestampDigits(const std::uint8_t* head, std::size_t size);

// How the capture's bytes are stored.
enum class Compression : std::uint8_t { None, Gzip, Zstd };
const char* compressionName(Compression compression);

// What a pcapng's interface statistics blocks say the capture dropped (docs/timing.md "Capture
// loss"): the last block's counters of each interface, summed over the interfaces.
struct CaptureDrops {
  std::optional<std::uint64_t> interface_dropped;  // isb_ifdrop: by the network interface
  std::optional<std::uint64_t> system_dropped;     // isb_osdrop: by the operating system
  std::uint64_t dropped() const {
    return interface_dropped.value_or(0) + system_dropped.value_or(0);
  }
};
// "12 frames (interface 12, system 0)".
std::string describeCaptureDrops(const CaptureDrops& drops);

class DecompressedStream;  // the decompressing source libpcap reads through (capture_reader.cpp)
class CaptureBytes;
class MappedBytes;
class RecordParser;
struct RecordFormat;

class CaptureReader {
 public:
  ~CaptureReader();
  CaptureReader(const CaptureReader&) = delete;
  CaptureReader& operator=(const CaptureReader&) = delete;

  // Opens PATH ("-" = standard input). An error names the file ("standard input" for "-").
  static Result<std::unique_ptr<CaptureReader>> open(const std::string& path);

  // Fills `record` with the next record and returns true; false at the end of the capture.
  // An error names the file and the frame that could not be read; the records before it
  // were good.
  // The record's bytes stay valid until the next call. A plain file's records are read in place
  // in the mapped file (docs/benchmarks.md "Reading captures"): their bytes stay valid as long
  // as the reader (pages released behind the reading are read again from the file if touched).
  // The records come in the file's order (frame numbers count up), each with its interface and
  // link type.
  Result<bool> next(CaptureRecord& record);

  // The first interface's link type (a pcap's only one).
  int dlt() const { return dlt_; }
  // How many interfaces the pcapng section being read has described so far; 1 for a pcap, and
  // for a pcapng libpcap reads (it opens only those whose interfaces share one link type, and
  // does not say which interface a record came from).
  std::size_t sectionInterfaces() const { return section_interfaces_; }
  Compression compression() const { return compression_; }
  const std::string& path() const { return path_; }
  int timestampDigits() const { return timestamp_digits_; }
  // A pcapng (of any compression), not a pcap.
  bool pcapng() const { return pcapng_format_; }
  // The drop counts of the interface statistics blocks read so far, once one gave any: of a plain
  // pcapng file, a compressed one and one from standard input alike.
  std::optional<CaptureDrops> drops() const;

 private:
  CaptureReader() = default;
  Error failure(std::uint64_t frame, const char* pcap_message) const;
  std::optional<RecordSpan> storedSpan();
  // The blocks in [from, to) of a plain pcapng, between records: interface statistics.
  void scanBlocks(std::uint64_t from, std::uint64_t to);
  // One interface statistics block, whole, in its section's byte order.
  void readStatistics(const std::uint8_t* block, std::size_t length, bool big);

  Result<bool> nextInPlace(CaptureRecord& record);
  void readInPlace(std::unique_ptr<CaptureBytes> bytes, const RecordFormat& format);

  // open's steps. The FILE's buffer, set before its first read.
  void bufferSource(std::FILE* file);
  // A source that is compressed or cannot be rewound, read through a DecompressedStream: in
  // place when libpcap reads its file header, else by libpcap. The FILE libpcap is to read
  // (nullptr when in place), or why the stream cannot be read.
  Result<std::FILE*> openStream(std::FILE* file, const std::uint8_t* head, std::size_t head_size,
                                bool in_place);
  // What the stream's first bytes say: the timestamps' digits, and whether it is a pcapng.
  void noteStreamHead(const std::uint8_t* ahead, std::size_t ahead_size);
  // The stream's first window to the record parser when libpcap reads its file header; else
  // back into the stream.
  void readStreamInPlace();
  // libpcap's handle on `pcap_file`, then a plain file's records in place in the mapped file.
  Status openWithLibpcap(std::FILE* pcap_file, const std::uint8_t* head, std::size_t head_size,
                         bool in_place);

  static constexpr std::size_t kReadBufferSize = 1 << 16;
  // In place (without libpcap's copies): the capture's bytes and the parser reading them.
  std::unique_ptr<CaptureBytes> bytes_;
  std::unique_ptr<RecordParser> parser_;
  MappedBytes* mapped_ = nullptr;               // bytes_, when it is the mapped file
  std::unique_ptr<char[]> buffer_;              // the FILE's buffer: outlives the handle
  std::unique_ptr<DecompressedStream> stream_;  // outlives the handle that reads it
  std::FILE* source_ = nullptr;                 // the file opened here, closed here
  ::pcap* handle_ = nullptr;
  std::string path_;
  LinkType link_ = LinkType::Unsupported;  // the first interface's, for libpcap's records
  int dlt_ = 0;
  Compression compression_ = Compression::None;
  std::uint64_t frames_ = 0;
  std::size_t section_interfaces_ = 1;  // the parser's, after the last record
  int timestamp_digits_ = 6;
  bool pcapng_ = false;           // a plain pcapng file, whose records are located
  bool pcapng_format_ = false;    // a pcapng, plain or not
  std::uint64_t record_end_ = 0;  // in the file, of the last record read
  bool tail_scanned_ = false;     // the blocks after the last record
  struct InterfaceDrops {
    std::uint32_t interface = 0;
    std::optional<std::uint64_t> interface_dropped;
    std::optional<std::uint64_t> system_dropped;
  };
  std::vector<InterfaceDrops> interface_drops_;  // the last statistics of each interface
};

// Where the records of `frames` (1-based, sorted, each once) are stored in the file at `path`,
// in frame order: read again from the start. Empty for standard input ("-") and for a
// compressed capture, whose records have no place in the file.
Result<std::vector<std::pair<std::uint64_t, RecordSpan>>> locateRecords(
    const std::string& path, const std::vector<std::uint64_t>& frames);

}  // namespace ncservo
