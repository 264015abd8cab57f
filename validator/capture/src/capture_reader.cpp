#include "ncservo/capture/capture_reader.hpp"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <isa-l/igzip_lib.h>
#include <pcap/pcap.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <optional>
#include <vector>

#include "ncservo/capture/record_parser.hpp"

namespace ncservo {

namespace {

constexpr std::size_t kMagicSize = 4;

struct CompressionMagic {
  Compression compression;
  const char* name;
  std::size_t size;
  std::array<std::uint8_t, kMagicSize> bytes;
};
// RFC 1952 §2.3.1 (ID1 ID2) and RFC 8878 §3.1.1 (zstd frame magic, little-endian 0xFD2FB528).
constexpr CompressionMagic kMagics[] = {
    {.compression = Compression::Gzip, .name = "gzip", .size = 2, .bytes = {0x1F, 0x8B, 0, 0}},
    {.compression = Compression::Zstd,
     .name = "zstd",
     .size = 4,
     .bytes = {0x28, 0xB5, 0x2F, 0xFD}},
};

Compression sniff(const std::uint8_t* head, std::size_t size) {
  for (const CompressionMagic& m : kMagics) {
    if (size >= m.size && std::equal(m.bytes.begin(), m.bytes.begin() + m.size, head)) {
      return m.compression;
    }
  }
  return Compression::None;
}

// Enough of a capture's beginning to hold a pcapng section header and its first interface.
constexpr std::size_t kHeadSize = 1024;

std::uint32_t load32(const std::uint8_t* p, bool big_endian) {
  return big_endian ? (std::uint32_t{p[0]} << 24 | std::uint32_t{p[1]} << 16 |
                       std::uint32_t{p[2]} << 8 | p[3])
                    : (std::uint32_t{p[3]} << 24 | std::uint32_t{p[2]} << 16 |
                       std::uint32_t{p[1]} << 8 | p[0]);
}

std::uint16_t load16(const std::uint8_t* p, bool big_endian) {
  return static_cast<std::uint16_t>(big_endian ? (p[0] << 8 | p[1]) : (p[1] << 8 | p[0]));
}

// pcap file header magics (pcap-savefile(5)) and pcapng's block types and option
// (draft-ietf-opsawg-pcapng §4.1, §4.2: if_tsresol is option 9).
constexpr std::uint32_t kPcapMicroMagic = 0xA1B2C3D4;
constexpr std::uint32_t kPcapNanoMagic = 0xA1B23C4D;
constexpr std::uint32_t kSectionHeaderBlock = 0x0A0D0D0A;
constexpr std::uint32_t kByteOrderMagic = 0x1A2B3C4D;
constexpr std::uint32_t kInterfaceBlock = 1;
constexpr std::uint32_t kStatisticsBlock = 5;
constexpr std::uint16_t kOptionEnd = 0;
constexpr std::uint16_t kOptionTsresol = 9;
constexpr int kMicrosecondDigits = 6;
constexpr int kNanosecondDigits = 9;

// pcapng's if_tsresol: 10^-v, or 2^-v when the top bit is set; as decimal digits, at most 9.
int tsresolDigits(std::uint8_t value) {
  const int exponent = value & 0x7F;
  const int digits = (value & 0x80) != 0 ? (exponent * 30103 + 99999) / 100000 : exponent;
  return std::min(digits, kNanosecondDigits);
}

}  // namespace

int timestampDigits(const std::uint8_t* head, std::size_t size) {
  if (size < 12) return kMicrosecondDigits;
  for (const bool big : {false, true}) {
    const std::uint32_t magic = load32(head, big);
    if (magic == kPcapMicroMagic) return kMicrosecondDigits;
    if (magic == kPcapNanoMagic) return kNanosecondDigits;
  }
  if (load32(head, false) != kSectionHeaderBlock) return kMicrosecondDigits;
  const bool big = load32(head + 8, true) == kByteOrderMagic;
  const std::size_t idb = load32(head + 4, big);
  if (idb + 16 > size || load32(head + idb, big) != kInterfaceBlock) return kMicrosecondDigits;
  const std::size_t end = std::min<std::size_t>(size, idb + load32(head + idb + 4, big) - 4);
  for (std::size_t at = idb + 16; at + 4 <= end;) {
    const std::uint16_t code = load16(head + at, big);
    const std::uint16_t length = load16(head + at + 2, big);
    if (code == kOptionEnd) break;
    if (code == kOptionTsresol && length == 1 && at + 5 <= end) return tsresolDigits(head[at + 4]);
    at += 4 + (length + 3u) / 4 * 4;
  }
  return kMicrosecondDigits;
}

const char* compressionName(Compression compression) {
  for (const CompressionMagic& m : kMagics) {
    if (m.compression == compression) return m.name;
  }
  return "none";
}

namespace {

// Follows the pcapng blocks of a stream as it is read, in pieces of any size (each block: type,
// total length, body, total length again; a section header gives the byte order), and hands each
// interface statistics block whole to its sink: a compressed or piped pcapng cannot be read
// again at its blocks' places, as a plain file is. Other blocks are skipped by their length;
// anything that is no pcapng (a pcap) or a block that makes no sense ends the walk.
class PcapngBlockWalker {
 public:
  using Sink = std::function<void(const std::uint8_t* block, std::size_t length, bool big)>;
  explicit PcapngBlockWalker(Sink sink) : sink_(std::move(sink)) {}

  void feed(const std::uint8_t* data, std::size_t size) {
    while (size > 0 && !lost_) {
      if (skip_ > 0) {
        const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(skip_, size));
        skip_ -= n;
        data += n;
        size -= n;
        continue;
      }
      const std::size_t n = std::min(want_ - block_.size(), size);
      block_.insert(block_.end(), data, data + n);
      data += n;
      size -= n;
      if (block_.size() == want_) advance();
    }
  }

 private:
  static constexpr std::size_t kHeader = 8;         // type and total length
  static constexpr std::size_t kSectionHead = 12;   // and the byte-order magic
  static constexpr std::size_t kMaxKept = 1 << 16;  // a statistics block is far smaller

  // block_ holds want_ bytes: a block's head, or a whole statistics block.
  void advance() {
    if (body_) {
      sink_(block_.data(), block_.size(), big_);
      body_ = false;
      restart();
      return;
    }
    // The section header's type reads the same in either byte order.
    const bool section = load32(block_.data(), false) == kSectionHeaderBlock;
    if (!section && !started_) {
      lost_ = true;
      return;
    }
    if (section && block_.size() < kSectionHead) {
      want_ = kSectionHead;
      return;
    }
    if (section) {
      if (load32(block_.data() + kHeader, false) == kByteOrderMagic) {
        big_ = false;
      } else if (load32(block_.data() + kHeader, true) == kByteOrderMagic) {
        big_ = true;
      } else {
        lost_ = true;
        return;
      }
      started_ = true;
    }
    const std::uint32_t length = load32(block_.data() + 4, big_);
    if (length < kSectionHead || length % 4 != 0 || length < block_.size()) {
      lost_ = true;
      return;
    }
    if (!section && load32(block_.data(), big_) == kStatisticsBlock && length <= kMaxKept) {
      body_ = true;
      want_ = length;
      return;
    }
    skip_ = length - block_.size();
    restart();
  }
  void restart() {
    block_.clear();
    want_ = kHeader;
  }

  Sink sink_;
  std::vector<std::uint8_t> block_;
  std::size_t want_ = kHeader;
  std::uint64_t skip_ = 0;  // of the block being passed over
  bool body_ = false;       // block_ is collecting a statistics block
  bool big_ = false;
  bool started_ = false;  // a section header was seen
  bool lost_ = false;
};

}  // namespace

// The capture's bytes as libpcap reads them: the bytes already read to recognise the format,
// then the rest of the file, decompressed on the fly in fixed-size buffers (constant memory).
// libpcap gets it as a FILE (glibc fopencookie).
class DecompressedStream {
 public:
  DecompressedStream(std::FILE* raw, Compression compression, const std::uint8_t* head,
                     std::size_t head_size)
      : raw_(raw),
        compression_(compression),
        input_(new std::uint8_t[kInputSize]),
        output_(new char[kOutputSize]) {
    std::memcpy(input_.get(), head, head_size);
    input_end_ = head_size;
    if (compression_ == Compression::Gzip) {
      // ISA-L's igzip inflates gzip twice as fast as zlib (docs/benchmarks.md "Reading captures").
      gzip_ = std::make_unique<inflate_state>();
    } else if (compression_ == Compression::Zstd) {
      zstd_ = ZSTD_createDStream();
    }
  }
  ~DecompressedStream() {
    if (zstd_ != nullptr) ZSTD_freeDStream(zstd_);
  }
  DecompressedStream(const DecompressedStream&) = delete;
  DecompressedStream& operator=(const DecompressedStream&) = delete;

  // A FILE reading this stream; closing it leaves the stream and the raw file open.
  std::FILE* file() {
    cookie_io_functions_t io{};
    io.read = [](void* self, char* out, std::size_t size) -> ssize_t {
      return static_cast<DecompressedStream*>(self)->read(out, size);
    };
    std::FILE* file = fopencookie(this, "rb", io);
    // Decoding in large blocks: each call into the decoder has a fixed cost.
    if (file != nullptr) std::setvbuf(file, output_.get(), _IOFBF, kOutputSize);
    return file;
  }

  // Decodes the capture's first `size` bytes ahead, so its header can be looked at; reads give
  // them first.
  const std::string& peek(std::size_t size) {
    ahead_.resize(size);
    const ssize_t got = decodeInto(ahead_.data(), size);
    ahead_.resize(got > 0 ? static_cast<std::size_t>(got) : 0);
    return ahead_;
  }

  // The stream's next bytes, decoded into `out` (at most `size`); 0 at the end, -1 on damage.
  ssize_t readInto(std::uint8_t* out, std::size_t size) {
    return read(reinterpret_cast<char*>(out), size);
  }

  // Bytes already read from here that reads give again first (the in-place reader's window,
  // when the capture goes to libpcap after all).
  void unread(const std::uint8_t* data, std::size_t size) {
    ahead_.assign(reinterpret_cast<const char*>(data), size);
    ahead_pos_ = 0;
  }

  // What went wrong, if reading stopped before the end of the compressed data.
  const std::optional<std::string>& error() const { return error_; }

  // The bytes read from here on are followed as pcapng blocks, each interface statistics block
  // given to `sink`.
  void followBlocks(PcapngBlockWalker::Sink sink) { walker_.emplace(std::move(sink)); }

 private:
  static constexpr std::size_t kInputSize = 1 << 17;
  int read_errno_ = 0;  // of the last read
  static constexpr std::size_t kOutputSize = 1 << 17;

  ssize_t read(char* out, std::size_t size) {
    ssize_t got = 0;
    if (ahead_pos_ < ahead_.size()) {
      const std::size_t n = std::min(size, ahead_.size() - ahead_pos_);
      std::memcpy(out, ahead_.data() + ahead_pos_, n);
      ahead_pos_ += n;
      got = static_cast<ssize_t>(n);
    } else {
      got = decodeInto(out, size);
    }
    if (walker_ && got > 0) {
      walker_->feed(reinterpret_cast<const std::uint8_t*>(out), static_cast<std::size_t>(got));
    }
    return got;
  }

  ssize_t decodeInto(char* out, std::size_t size) {
    if (error_) return -1;
    std::size_t done = 0;
    while (done < size) {
      if (input_pos_ == input_end_ && !refill()) break;
      done += decode(reinterpret_cast<std::uint8_t*>(out) + done, size - done);
      if (error_) break;
    }
    // The bytes decoded before the damage are given; the next read reports it.
    if (done == 0 && error_) return -1;
    return static_cast<ssize_t>(done);
  }

  // More compressed input; false at the end of the file (after checking nothing was cut).
  bool refill() {
    input_pos_ = 0;
    input_end_ = 0;
    // A read that failed after giving some bytes (one Ctrl-C cut short) is not tried again.
    if (!std::ferror(raw_)) {
      errno = 0;
      input_end_ = std::fread(input_.get(), 1, kInputSize, raw_);
      read_errno_ = errno;
    }
    if (input_end_ > 0) return true;
    if (std::ferror(raw_)) {
      error_ = fmt::format("read error: {}", std::strerror(read_errno_));
    } else if (inside_frame_) {
      error_ = fmt::format("the {} stream is cut short (truncated compressed file)",
                           compressionName(compression_));
    }
    return false;
  }

  // Decodes from the input buffer into `out`; returns the bytes written.
  std::size_t decode(std::uint8_t* out, std::size_t size) {
    const std::uint8_t* in = input_.get() + input_pos_;
    const std::size_t available = input_end_ - input_pos_;
    switch (compression_) {
      case Compression::None: {
        const std::size_t n = std::min(size, available);
        std::memcpy(out, in, n);
        input_pos_ += n;
        return n;
      }
      case Compression::Gzip:
        return inflateSome(in, available, out, size);
      case Compression::Zstd:
        return zstdSome(in, available, out, size);
    }
    return 0;
  }

  std::size_t inflateSome(const std::uint8_t* in, std::size_t available, std::uint8_t* out,
                          std::size_t size) {
    // A gzip file may hold several members: each begins with a fresh state.
    if (!inside_frame_) {
      isal_inflate_init(gzip_.get());
      gzip_->crc_flag = ISAL_GZIP;
    }
    gzip_->next_in = const_cast<std::uint8_t*>(in);
    gzip_->avail_in = static_cast<std::uint32_t>(std::min<std::size_t>(available, 1u << 30));
    gzip_->next_out = out;
    gzip_->avail_out = static_cast<std::uint32_t>(std::min<std::size_t>(size, 1u << 30));
    const int rc = isal_inflate(gzip_.get());
    input_pos_ += static_cast<std::size_t>(gzip_->next_in - in);
    const std::size_t written = static_cast<std::size_t>(gzip_->next_out - out);
    if (rc < 0) {
      error_ = fmt::format("corrupt gzip data ({})", isalError(rc));
    } else {
      inside_frame_ = gzip_->block_state != ISAL_BLOCK_FINISH;
    }
    return written;
  }

  // ISA-L's errors in zlib's words (igzip_lib.h).
  static const char* isalError(int rc) {
    switch (rc) {
      case ISAL_INVALID_BLOCK:
        return "invalid block type";
      case ISAL_INVALID_SYMBOL:
        return "invalid code";
      case ISAL_INVALID_LOOKBACK:
        return "invalid distance too far back";
      case ISAL_INVALID_WRAPPER:
        return "incorrect header check";
      case ISAL_UNSUPPORTED_METHOD:
        return "unknown compression method";
      case ISAL_INCORRECT_CHECKSUM:
        return "incorrect data check";
      default:
        return "data error";
    }
  }

  std::size_t zstdSome(const std::uint8_t* in, std::size_t available, std::uint8_t* out,
                       std::size_t size) {
    if (zstd_ == nullptr) {
      error_ = "cannot start the zstd decoder";
      return 0;
    }
    ZSTD_inBuffer input{in, available, 0};
    ZSTD_outBuffer output{out, size, 0};
    const std::size_t rc = ZSTD_decompressStream(zstd_, &output, &input);
    input_pos_ += input.pos;
    if (ZSTD_isError(rc)) {
      error_ = fmt::format("corrupt zstd data ({})", ZSTD_getErrorName(rc));
      return output.pos;
    }
    inside_frame_ = rc != 0;  // 0: a frame is complete and flushed (zstd.h)
    return output.pos;
  }

  std::FILE* raw_;
  Compression compression_;
  std::unique_ptr<std::uint8_t[]> input_;
  std::unique_ptr<char[]> output_;  // the FILE's buffer
  std::size_t input_pos_ = 0;
  std::size_t input_end_ = 0;
  bool inside_frame_ = false;            // a compressed frame or member is begun and not ended
  std::unique_ptr<inflate_state> gzip_;  // ISA-L's, large (about 40 KiB): on the heap
  ZSTD_DStream* zstd_ = nullptr;
  std::optional<std::string> error_;
  std::string ahead_;  // peek()'s bytes
  std::size_t ahead_pos_ = 0;
  std::optional<PcapngBlockWalker> walker_;
};

namespace {

// NCSERVO_CAPTURE_READER=libpcap: every record through libpcap, the reference the in-place reader
// is checked against (docs/benchmarks.md "Reading captures").
bool libpcapForced() {
  const char* value = std::getenv("NCSERVO_CAPTURE_READER");
  return value != nullptr && std::strcmp(value, "libpcap") == 0;
}

// A decompressed (or piped) capture in one large buffer that moves forward as it is read: the
// record parser reads records in it, and a record's bytes stay until the next one is asked for.
class StreamBytes final : public CaptureBytes {
 public:
  // 256 KiB: large enough that each call into the decoder does much work, small enough that the
  // bytes decoded are still in the core's cache when they are parsed.
  static constexpr std::size_t kWindowSize = 1 << 18;

  explicit StreamBytes(DecompressedStream& stream) : stream_(stream), buffer_(kWindowSize) {
    data_ = buffer_.data();
  }

  // The window from the capture's start, filled as far as the stream gives.
  void fill() { extend(0, buffer_.size()); }
  const std::uint8_t* data() const { return data_; }
  std::size_t size() const { return size_; }

 protected:
  void extend(std::uint64_t offset, std::size_t n) override {
    if (offset < base_) return;  // gone (the parser only reads forward)
    if (offset > base_) {        // what is before `offset` was read: keep only the rest
      const auto drop = static_cast<std::size_t>(std::min<std::uint64_t>(offset - base_, size_));
      std::memmove(buffer_.data(), buffer_.data() + drop, size_ - drop);
      size_ -= drop;
      base_ += drop;
    }
    const std::size_t want = static_cast<std::size_t>(offset - base_) + n;
    // A block larger than the window (pcapng allows up to 16 MiB, the parser checks first).
    if (want > buffer_.size()) buffer_.resize(want);
    data_ = buffer_.data();
    while (size_ < want && !ended_) {
      const ssize_t got = stream_.readInto(buffer_.data() + size_, buffer_.size() - size_);
      if (got <= 0) {
        ended_ = true;
      } else {
        size_ += static_cast<std::size_t>(got);
      }
    }
  }

 private:
  DecompressedStream& stream_;
  std::vector<std::uint8_t> buffer_;
  bool ended_ = false;
};

}  // namespace

// A plain capture file mapped into memory: records are read where they lie.
class MappedBytes final : public CaptureBytes {
 public:
  static std::unique_ptr<MappedBytes> map(int fd) {
    struct stat info {};
    if (fstat(fd, &info) != 0 || !S_ISREG(info.st_mode) || info.st_size <= 0) return nullptr;
    const auto size = static_cast<std::size_t>(info.st_size);
    void* at = mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
    if (at == MAP_FAILED) return nullptr;
    madvise(at, size, MADV_SEQUENTIAL);
    return std::unique_ptr<MappedBytes>(
        new MappedBytes(static_cast<const std::uint8_t*>(at), size));
  }
  ~MappedBytes() override { munmap(const_cast<std::uint8_t*>(data_), size_); }
  MappedBytes(const MappedBytes&) = delete;
  MappedBytes& operator=(const MappedBytes&) = delete;

  // The pages before `offset` leave the process (its resident memory stays flat over a long
  // file); they are still the file's, read again from the page cache if touched.
  void releaseBefore(std::uint64_t offset) {
    constexpr std::uint64_t kStep = 1 << 20;
    if (offset < released_ + 2 * kStep) return;
    const std::uint64_t until = (offset - kStep) & ~(kStep - 1);
    madvise(const_cast<std::uint8_t*>(data_) + released_, until - released_, MADV_DONTNEED);
    released_ = until;
  }

 protected:
  void extend(std::uint64_t /*offset*/, std::size_t /*n*/) override {}

 private:
  MappedBytes(const std::uint8_t* data, std::size_t size) {
    data_ = data;
    size_ = size;
  }
  std::uint64_t released_ = 0;
};

namespace {

// What libpcap read of the file header, for the record parser; nullopt for what it does not
// read (the patched-pcap magics' longer record header; a byte-swapped Linux cooked capture,
// whose CAN headers libpcap swaps).
std::optional<RecordFormat> inPlaceFormat(::pcap* handle, const std::uint8_t* head,
                                          std::size_t size) {
  RecordFormat format;
  format.pcapng = size >= 4 && load32(head, false) == kSectionHeaderBlock;
  const bool swapped = pcap_is_swapped(handle) == 1;
  format.big_endian = (htonl(1) == 1) != swapped;
  format.dlt = pcap_datalink(handle);
  format.snapshot = static_cast<std::uint32_t>(pcap_snapshot(handle));
  format.version_major = pcap_major_version(handle);
  format.version_minor = pcap_minor_version(handle);
  if (swapped && format.dlt != DLT_EN10MB) return std::nullopt;
  if (!format.pcapng) {
    if (size < 4) return std::nullopt;
    const std::uint32_t magic = load32(head, format.big_endian);
    if (magic != kPcapMicroMagic && magic != kPcapNanoMagic) return std::nullopt;
    format.nanoseconds = magic == kPcapNanoMagic;
  }
  return format;
}

}  // namespace

CaptureReader::~CaptureReader() {
  parser_.reset();
  bytes_.reset();
  if (handle_ != nullptr) pcap_close(handle_);
  if (source_ != nullptr && source_ != stdin) std::fclose(source_);
}

void CaptureReader::readInPlace(std::unique_ptr<CaptureBytes> bytes, const RecordFormat& format) {
  bytes_ = std::move(bytes);
  parser_ = std::make_unique<RecordParser>(
      *bytes_, format, [this](const std::uint8_t* block, std::size_t length, bool big) {
        readStatistics(block, length, big);
      });
}

namespace {

// libpcap's words for these ("truncated dump file; tried to read 4 file header bytes") do not say
// what is wrong with the file; nullptr for a file that may be a capture.
const char* notACapture(std::FILE* file) {
  struct stat info {};
  if (fstat(fileno(file), &info) != 0) return nullptr;
  if (S_ISDIR(info.st_mode)) return "is a directory";
  if (S_ISREG(info.st_mode) && info.st_size == 0) return "empty file";
  return nullptr;
}

Error unsupportedLinkType(const std::string& name, int dlt) {
  const char* dlt_name = pcap_datalink_val_to_name(dlt);
  return Error{name,
               0,
               0,
               {},
               fmt::format("unsupported link type {} ({}); ncservo reads Ethernet and "
                           "Linux cooked (SLL, SLL2) captures",
                           dlt, dlt_name != nullptr ? dlt_name : "unknown")};
}

}  // namespace

Result<std::unique_ptr<CaptureReader>> CaptureReader::open(const std::string& path) {
  const std::string name = path == "-" ? "standard input" : path;
  auto cannot = [&](std::string why) {
    return fail(Error{name, 0, 0, {}, "cannot read capture: " + std::move(why)});
  };
  std::unique_ptr<CaptureReader> reader(new CaptureReader());
  reader->path_ = name;
  std::FILE* file = path == "-" ? stdin : std::fopen(path.c_str(), "rb");
  if (file == nullptr) return cannot(std::strerror(errno));
  reader->source_ = file;
  if (const char* why = notACapture(file)) return cannot(why);
  reader->bufferSource(file);
  std::uint8_t head[kHeadSize] = {};
  const std::size_t head_size = std::fread(head, 1, sizeof head, file);
  reader->compression_ = sniff(head, head_size);
  const bool in_place = !libpcapForced();
  std::FILE* pcap_file = file;
  // A plain file goes to libpcap as it is; anything else (compressed, or a pipe that cannot
  // be rewound past the bytes just read) through a DecompressedStream.
  if (reader->compression_ != Compression::None || std::fseek(file, 0, SEEK_SET) != 0) {
    const Result<std::FILE*> streamed = reader->openStream(file, head, head_size, in_place);
    if (!streamed) return cannot(streamed.error().message);
    pcap_file = *streamed;
  } else {
    reader->timestamp_digits_ = ncservo::timestampDigits(head, head_size);
    reader->pcapng_ = head_size >= 4 && load32(head, false) == kSectionHeaderBlock;
    reader->pcapng_format_ = reader->pcapng_;
    reader->source_ = nullptr;  // libpcap closes it with its handle
  }
  if (!reader->parser_) {
    if (Status opened = reader->openWithLibpcap(pcap_file, head, head_size, in_place); !opened) {
      return cannot(opened.error().message);
    }
  }
  reader->link_ = linkTypeFromDlt(reader->dlt_);
  // A pcapng read in place may hold other interfaces after its first (docs/protocol.md §8): its
  // records of a link type the walker does not know are counted, not refused.
  const bool each_interface = reader->parser_ && reader->pcapng_format_;
  if (reader->link_ == LinkType::Unsupported && !each_interface) {
    return fail(unsupportedLinkType(name, reader->dlt_));
  }
  return reader;
}

void CaptureReader::bufferSource(std::FILE* file) {
  // A 64 KiB stdio buffer: 16 times fewer system calls than stdio's 4 KiB, and the bytes just
  // read are still in the core's cache when they are parsed. (A buffer the size of the L2
  // cache, 1 MiB, measured 15 % slower: each refill evicts what the next frames need.)
  // Standard input may outlive this reader (when it is not handed to libpcap, which closes
  // it): its buffer lives as long as the process, and is set before its first read.
  if (file == stdin) {
    static char stdin_buffer[kReadBufferSize];
    static const bool stdin_buffered =
        std::setvbuf(stdin, stdin_buffer, _IOFBF, kReadBufferSize) == 0;
    (void)stdin_buffered;
  } else {
    buffer_ = std::make_unique<char[]>(kReadBufferSize);
    std::setvbuf(file, buffer_.get(), _IOFBF, kReadBufferSize);
  }
}

Result<std::FILE*> CaptureReader::openStream(std::FILE* file, const std::uint8_t* head,
                                             std::size_t head_size, bool in_place) {
  stream_ = std::make_unique<DecompressedStream>(file, compression_, head, head_size);
  if (in_place) {
    readStreamInPlace();
  } else {
    const std::string& peeked = stream_->peek(kHeadSize);
    noteStreamHead(reinterpret_cast<const std::uint8_t*>(peeked.data()), peeked.size());
  }
  if (parser_) return nullptr;
  // Its interface statistics as they pass, read as a plain file's are (docs/timing.md).
  if (pcapng_format_) {
    stream_->followBlocks([this](const std::uint8_t* block, std::size_t length, bool big) {
      readStatistics(block, length, big);
    });
  }
  std::FILE* pcap_file = stream_->file();
  if (pcap_file == nullptr) return fail(std::strerror(errno));
  return pcap_file;
}

void CaptureReader::noteStreamHead(const std::uint8_t* ahead, std::size_t ahead_size) {
  timestamp_digits_ = ncservo::timestampDigits(ahead, ahead_size);
  pcapng_ = false;  // records are not located in a stream
  pcapng_format_ = ahead_size >= 4 && load32(ahead, false) == kSectionHeaderBlock;
}

void CaptureReader::readStreamInPlace() {
  auto window = std::make_unique<StreamBytes>(*stream_);
  window->fill();
  noteStreamHead(window->data(), window->size());
  // libpcap reads the file header from the window's first bytes; the records are read in
  // the window. Anything it cannot open there goes to libpcap whole, after, for its words.
  std::FILE* header =
      window->size() > 0 ? fmemopen(const_cast<std::uint8_t*>(window->data()), window->size(), "rb")
                         : nullptr;
  char errbuf[PCAP_ERRBUF_SIZE] = {};
  ::pcap* checked = header != nullptr ? pcap_fopen_offline_with_tstamp_precision(
                                            header, PCAP_TSTAMP_PRECISION_NANO, errbuf)
                                      : nullptr;
  std::optional<RecordFormat> format;
  if (checked != nullptr) {
    format = inPlaceFormat(checked, window->data(), window->size());
    dlt_ = pcap_datalink(checked);
    pcap_close(checked);  // and its FILE
  } else if (header != nullptr) {
    std::fclose(header);
  }
  if (format) {
    readInPlace(std::move(window), *format);
  } else {
    stream_->unread(window->data(), window->size());
  }
}

Status CaptureReader::openWithLibpcap(std::FILE* pcap_file, const std::uint8_t* head,
                                      std::size_t head_size, bool in_place) {
  char errbuf[PCAP_ERRBUF_SIZE] = {};
  handle_ = pcap_fopen_offline_with_tstamp_precision(pcap_file, PCAP_TSTAMP_PRECISION_NANO, errbuf);
  if (handle_ == nullptr) {
    if (pcap_file != stdin) std::fclose(pcap_file);  // the raw file under a stream: by source_
    if (stream_ && stream_->error()) return fail(*stream_->error());
    if (compression_ != Compression::None) {
      return fail(
          fmt::format("{} (after {} decompression)", errbuf, compressionName(compression_)));
    }
    return fail(errbuf);
  }
  dlt_ = pcap_datalink(handle_);
  // A plain file libpcap opened: its records are read where they lie, in the mapped file.
  if (in_place && !stream_) {
    std::optional<RecordFormat> format = inPlaceFormat(handle_, head, head_size);
    std::unique_ptr<MappedBytes> mapped;
    if (format) mapped = MappedBytes::map(fileno(pcap_file));
    if (mapped) {
      mapped_ = mapped.get();
      readInPlace(std::move(mapped), *format);
    }
  }
  return {};
}

Error CaptureReader::failure(std::uint64_t frame, const char* pcap_message) const {
  // A broken compressed stream is what libpcap saw as a short read: say which.
  if (stream_ && stream_->error()) return Error{path_, 0, frame, {}, *stream_->error()};
  return Error{path_, 0, frame, {}, pcap_message};
}

// A plain file is read by libpcap record by record, so its position is the record's end. pcap
// records follow each other from the end of the 24-byte file header (pcap-savefile(5)); a pcapng
// block, which other blocks may precede, ends with its total length (pcapng §3.1).
std::string describeCaptureDrops(const CaptureDrops& drops) {
  std::vector<std::string> parts;
  if (drops.interface_dropped)
    parts.push_back(fmt::format("interface {}", *drops.interface_dropped));
  if (drops.system_dropped) parts.push_back(fmt::format("system {}", *drops.system_dropped));
  return fmt::format("{} frames ({})", drops.dropped(), fmt::join(parts, ", "));
}

std::optional<CaptureDrops> CaptureReader::drops() const {
  if (interface_drops_.empty()) return std::nullopt;
  CaptureDrops total;
  for (const InterfaceDrops& d : interface_drops_) {
    if (d.interface_dropped)
      total.interface_dropped = total.interface_dropped.value_or(0) + *d.interface_dropped;
    if (d.system_dropped)
      total.system_dropped = total.system_dropped.value_or(0) + *d.system_dropped;
  }
  return total;
}

// An interface statistics block (the pcapng specification), whole: type, total length, interface
// id, timestamp (8 bytes), then options of code, length and a value padded to 4 bytes; isb_ifdrop
// (5) and isb_osdrop (7) are 64-bit counters since the capture started.
void CaptureReader::readStatistics(const std::uint8_t* block, std::size_t length, bool big) {
  constexpr std::uint16_t kEndOfOptions = 0, kIfDrop = 5, kOsDrop = 7;
  if (length < 24) return;
  const auto load64 = [&](const std::uint8_t* p) {
    const std::uint64_t first = load32(p, big), second = load32(p + 4, big);
    return big ? first << 32 | second : second << 32 | first;
  };
  const std::size_t end = length - 4;  // before the trailing length
  InterfaceDrops drops{load32(block + 8, big), std::nullopt, std::nullopt};
  for (std::size_t option = 20; option + 4 <= end;) {
    const std::uint16_t code = load16(block + option, big);
    const std::uint16_t size = load16(block + option + 2, big);
    if (code == kEndOfOptions || option + 4 + size > end) break;
    if (size == 8 && code == kIfDrop) drops.interface_dropped = load64(block + option + 4);
    if (size == 8 && code == kOsDrop) drops.system_dropped = load64(block + option + 4);
    option += 4 + (size + 3u) / 4 * 4;
  }
  if (!drops.interface_dropped && !drops.system_dropped) return;
  const auto same =
      std::find_if(interface_drops_.begin(), interface_drops_.end(),
                   [&](const InterfaceDrops& d) { return d.interface == drops.interface; });
  if (same != interface_drops_.end()) {
    *same = drops;
  } else if (interface_drops_.size() < 64) {
    interface_drops_.push_back(drops);
  }
}

// The blocks in [from, to) of a plain pcapng file, read again at their place.
void CaptureReader::scanBlocks(std::uint64_t from, std::uint64_t to) {
  constexpr std::uint64_t kMaxScanned = 1 << 20;  // blocks between records are small
  if (to <= from || to - from > kMaxScanned) return;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(to - from));
  if (pread(fileno(pcap_file(handle_)), bytes.data(), bytes.size(), static_cast<off_t>(from)) !=
      static_cast<ssize_t>(bytes.size())) {
    return;
  }
  const bool big = (htonl(1) == 1) != (pcap_is_swapped(handle_) == 1);
  std::size_t at = 0;
  while (at + 12 <= bytes.size()) {
    const std::uint32_t type = load32(&bytes[at], big);
    const std::uint32_t length = load32(&bytes[at + 4], big);
    if (length < 12 || length % 4 != 0 || length > bytes.size() - at) return;
    if (type == kStatisticsBlock) readStatistics(&bytes[at], length, big);
    at += length;
  }
}

std::optional<RecordSpan> CaptureReader::storedSpan() {
  constexpr std::uint64_t kPcapFileHeader = 24;
  std::FILE* file = pcap_file(handle_);
  const long end = file != nullptr ? std::ftell(file) : -1;
  if (end < 0) return std::nullopt;
  const auto at = static_cast<std::uint64_t>(end);
  const std::uint64_t start = record_end_ == 0 ? kPcapFileHeader : record_end_;
  record_end_ = at;
  std::uint64_t length = at - std::min(at, start);
  if (pcapng_) {
    std::uint8_t trailer[4];
    if (at < sizeof trailer ||
        pread(fileno(file), trailer, sizeof trailer, static_cast<off_t>(at - sizeof trailer)) !=
            static_cast<ssize_t>(sizeof trailer)) {
      return std::nullopt;
    }
    const bool host_big = htonl(1) == 1;
    length = load32(trailer, host_big != (pcap_is_swapped(handle_) == 1));
  }
  if (length == 0 || length > at) return std::nullopt;
  if (pcapng_ && at - length > start) scanBlocks(start == kPcapFileHeader ? 0 : start, at - length);
  return RecordSpan{at - length, length};
}

Result<bool> CaptureReader::nextInPlace(CaptureRecord& record) {
  switch (parser_->next(record)) {
    case RecordParser::Outcome::Record:
      record.frame = ++frames_;
      section_interfaces_ = parser_->sectionInterfaces();
      if (stream_) {
        record.stored.reset();
      } else if (mapped_ != nullptr) {
        mapped_->releaseBefore(record.stored->offset);
      }
      return true;
    case RecordParser::Outcome::End:
      if (stream_ && stream_->error()) return fail(failure(frames_ + 1, ""));
      return false;
    case RecordParser::Outcome::Failed:
      break;
  }
  return fail(failure(frames_ + 1, parser_->error().c_str()));
}

Result<bool> CaptureReader::next(CaptureRecord& record) {
  if (parser_) return nextInPlace(record);
  pcap_pkthdr* header = nullptr;
  const u_char* data = nullptr;
  const int rc = pcap_next_ex(handle_, &header, &data);
  if (rc == PCAP_ERROR_BREAK) {
    if (stream_ && stream_->error()) return fail(failure(frames_ + 1, ""));
    std::FILE* file = pcap_file(handle_);
    struct stat info {};
    if (pcapng_ && !stream_ && !tail_scanned_ && file != nullptr &&
        fstat(fileno(file), &info) == 0 && S_ISREG(info.st_mode)) {
      tail_scanned_ = true;
      scanBlocks(record_end_, static_cast<std::uint64_t>(info.st_size));
    }
    return false;
  }
  if (rc != 1) return fail(failure(frames_ + 1, pcap_geterr(handle_)));
  record.frame = ++frames_;
  // pcapng stores 64-bit timestamps: seconds are clamped to pcap's unsigned 32-bit range (up to
  // the year 2106), so nanoseconds and their differences fit in 64 bits.
  constexpr std::int64_t kMaxSeconds = 0xFFFFFFFF;
  const std::int64_t seconds =
      std::clamp<std::int64_t>(static_cast<std::int64_t>(header->ts.tv_sec), 0, kMaxSeconds);
  record.time_ns = seconds * 1000000000 + static_cast<std::int64_t>(header->ts.tv_usec);
  record.data = data;
  record.captured = header->caplen;
  record.original = header->len;
  record.stored = stream_ ? std::nullopt : storedSpan();
  record.interface = 0;
  record.link_type = dlt_;
  record.link = link_;
  return true;
}

Result<std::vector<std::pair<std::uint64_t, RecordSpan>>> locateRecords(
    const std::string& path, const std::vector<std::uint64_t>& frames) {
  std::vector<std::pair<std::uint64_t, RecordSpan>> spans;
  if (frames.empty() || path == "-") return spans;
  auto opened = CaptureReader::open(path);
  if (!opened) return fail(opened.error());
  CaptureRecord record;
  auto wanted = frames.begin();
  Result<bool> more;
  // The frames asked for were read before any damage, which the caller's run already names.
  while (wanted != frames.end() && (more = (*opened)->next(record)) && *more) {
    if (!record.stored) return std::vector<std::pair<std::uint64_t, RecordSpan>>{};
    if (record.frame != *wanted) continue;
    spans.emplace_back(record.frame, *record.stored);
    ++wanted;
  }
  return spans;
}

}  // namespace ncservo
