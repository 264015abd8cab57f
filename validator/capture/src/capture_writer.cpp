#include "ncservo/capture/capture_writer.hpp"

#include <fmt/format.h>
#include <pcap/pcap.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <memory>
#include <vector>

#include "ncservo/base/little_endian.hpp"
#include "ncservo/capture/compressed_output.hpp"
#include "ncservo/wire/ecat_wire.hpp"

namespace ncservo {
namespace {

constexpr int kSnapLength = 65535;
constexpr std::size_t kWriteBuffer = 1 << 20;
constexpr std::uint16_t kOptionComment = 1;  // opt_comment (pcapng §3.5)
constexpr std::size_t kMaxOptionLength = 0xFFFF;

Error writeError(const std::string& path, std::string message) {
  return Error{path, 0, 0, {}, std::move(message)};
}

// The file's stdio buffer, kWriteBuffer bytes, owned by its writer until the file is closed:
// glibc ignores setvbuf's size when it is given no buffer, and writes in blocks of st_blksize
// (4 KiB to a pipe, a write and a wake-up of the reader each). Standard output, never closed,
// gets one for the process.
std::unique_ptr<char[]> bufferFile(std::FILE* file) {
  if (file == stdout) {
    static char* const kStdoutBuffer = new char[kWriteBuffer];
    std::fflush(stdout);
    std::setvbuf(stdout, kStdoutBuffer, _IOFBF, kWriteBuffer);
    return nullptr;
  }
  auto buffer = std::make_unique<char[]>(kWriteBuffer);
  std::setvbuf(file, buffer.get(), _IOFBF, kWriteBuffer);
  return buffer;
}

Result<std::FILE*> openFile(const std::string& path) {
  if (path == "-") return stdout;
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) {
    return fail(writeError(path, fmt::format("cannot write: {}", std::strerror(errno))));
  }
  return file;
}

class PcapWriter final : public CaptureWriter {
 public:
  PcapWriter(std::string path, std::FILE* file, std::unique_ptr<char[]> buffer, pcap_t* dead,
             pcap_dumper_t* dumper)
      : path_(std::move(path)),
        file_(file),
        buffer_(std::move(buffer)),
        dead_(dead),
        dumper_(dumper) {}
  ~PcapWriter() override { (void)close(); }
  bool write(std::int64_t time_ns, const std::uint8_t* data, std::size_t size) override {
    if (dumper_ == nullptr) return false;
    pcap_pkthdr header{};
    header.ts.tv_sec = static_cast<time_t>(time_ns / 1'000'000'000);
    header.ts.tv_usec = static_cast<suseconds_t>(time_ns % 1'000'000'000 / 1000);
    header.caplen = header.len = static_cast<bpf_u_int32>(size);
    pcap_dump(reinterpret_cast<u_char*>(dumper_), &header, data);
    return std::ferror(file_) == 0;
  }
  bool write(const PacketRecord& record) override {
    if (dumper_ == nullptr || record.interface_id != 0) return false;
    pcap_pkthdr header{};
    header.ts.tv_sec = static_cast<time_t>(record.time_ns / 1'000'000'000);
    header.ts.tv_usec = static_cast<suseconds_t>(record.time_ns % 1'000'000'000 / 1000);
    header.caplen = static_cast<bpf_u_int32>(record.captured);
    header.len = static_cast<bpf_u_int32>(record.original);
    pcap_dump(reinterpret_cast<u_char*>(dumper_), &header, record.data);
    return std::ferror(file_) == 0;
  }
  Status close() override {
    if (dumper_ == nullptr) return closed();
    const bool flushed = pcap_dump_flush(dumper_) == 0 && std::ferror(file_) == 0;
    if (file_ == stdout) {
      dumper_ = nullptr;  // standard output stays open for the process
    } else {
      pcap_dump_close(dumper_);  // closes the file
      dumper_ = nullptr;
    }
    pcap_close(dead_);
    if (!flushed) {
      failed_ = true;
      error_ = writeError(path_, fmt::format("write failed: {}", std::strerror(errno)));
    }
    return closed();
  }

 private:
  Status closed() const {
    if (failed_) return fail(error_);
    return {};
  }

  std::string path_;
  std::FILE* file_;
  std::unique_ptr<char[]> buffer_;  // file_'s, freed after it is closed
  pcap_t* dead_;
  pcap_dumper_t* dumper_;
  bool failed_ = false;
  Error error_;
};

// pcapng: a Section Header Block, an Interface Description Block per interface with
// if_tsresol (10^-6 or 10^-9 s), then one Enhanced Packet Block per frame, naming its interface
// by its IDB's place (pcapng specification, §4).
class PcapngWriter final : public CaptureWriter {
 public:
  PcapngWriter(std::string path, std::FILE* file, std::unique_ptr<char[]> buffer,
               const std::vector<PcapngInterface>& interfaces)
      : path_(std::move(path)), file_(file), buffer_(std::move(buffer)) {
    block_.reserve(2048);
    begin(0x0A0D0D0A);  // SHB
    put32(0x1A2B3C4D);  // byte-order magic
    put16(1);           // version 1.0
    put16(0);
    put32(0xFFFFFFFF);  // section length unknown
    put32(0xFFFFFFFF);
    finish();
    for (const PcapngInterface& interface : interfaces) describe(interface);
  }
  ~PcapngWriter() override { (void)close(); }
  bool write(std::int64_t time_ns, const std::uint8_t* data, std::size_t size) override {
    return write(PacketRecord{time_ns, data, size, size, nullptr});
  }
  bool write(const PacketRecord& record) override {
    if (file_ == nullptr || record.interface_id >= ticks_per_second_.size()) return false;
    const auto ts = static_cast<std::uint64_t>(record.time_ns) /
                    (std::uint64_t{1'000'000'000} / ticks_per_second_[record.interface_id]);
    begin(0x00000006);  // EPB
    put32(record.interface_id);
    put32(static_cast<std::uint32_t>(ts >> 32));
    put32(static_cast<std::uint32_t>(ts));
    put32(static_cast<std::uint32_t>(record.captured));
    put32(static_cast<std::uint32_t>(record.original));
    block_.insert(block_.end(), record.data, record.data + record.captured);
    pad();
    if (record.comments != nullptr && !record.comments->empty()) {
      for (const std::string& comment : *record.comments) {
        const std::size_t length = std::min<std::size_t>(comment.size(), kMaxOptionLength);
        put16(kOptionComment);
        put16(static_cast<std::uint16_t>(length));
        block_.insert(block_.end(), comment.begin(), comment.begin() + length);
        pad();
      }
      put32(0);  // opt_endofopt
    }
    finish();
    return !failed_;
  }
  Status close() override {
    if (file_ == nullptr) return closed();
    if (std::fflush(file_) != 0 || std::ferror(file_) != 0) failed_ = true;
    if (file_ != stdout && std::fclose(file_) != 0) failed_ = true;
    file_ = nullptr;
    if (failed_) error_ = writeError(path_, fmt::format("write failed: {}", std::strerror(errno)));
    return closed();
  }

 private:
  // An Interface Description Block: the interface's link type and timestamp resolution.
  void describe(const PcapngInterface& interface) {
    std::uint64_t ticks = 1;
    for (int i = 0; i < interface.timestamp_digits; ++i) ticks *= 10;
    ticks_per_second_.push_back(ticks);
    begin(0x00000001);  // IDB
    put16(static_cast<std::uint16_t>(interface.dlt));
    put16(0);
    put32(kSnapLength);
    put16(9);  // if_tsresol
    put16(1);
    block_.push_back(static_cast<std::uint8_t>(interface.timestamp_digits));  // 10^-digits s
    block_.resize(block_.size() + 3, 0);
    put16(0);  // opt_endofopt
    put16(0);
    finish();
  }
  void put16(std::uint16_t v) { appendLe(block_, v, 2); }
  void put32(std::uint32_t v) { appendLe(block_, v, 4); }
  void pad() { block_.resize((block_.size() + 3) & ~std::size_t{3}, 0); }
  void begin(std::uint32_t type) {
    block_.clear();
    put32(type);
    put32(0);  // total length, set by finish()
  }
  void finish() {
    const auto total = static_cast<std::uint32_t>(block_.size() + 4);
    storeLe<4>(&block_[4], total);
    put32(total);
    if (std::fwrite(block_.data(), 1, block_.size(), file_) != block_.size()) failed_ = true;
  }

  Status closed() const {
    if (failed_) return fail(error_);
    return {};
  }

  std::string path_;
  std::FILE* file_;
  std::unique_ptr<char[]> buffer_;  // file_'s, freed after it is closed
  std::vector<std::uint8_t> block_;
  std::vector<std::uint64_t> ticks_per_second_;  // per interface, in the order of their IDBs
  bool failed_ = false;
  Error error_;
};

}  // namespace

Result<std::unique_ptr<CaptureWriter>> CaptureWriter::open(
    const std::string& path, CaptureFormat format, Compression compression,
    const std::vector<PcapngInterface>& interfaces) {
  if (format == CaptureFormat::Pcap &&
      (interfaces.size() > 1 ||
       (interfaces.size() == 1 && interfaces[0].dlt != PcapngInterface{}.dlt))) {
    return fail(writeError(path, "a pcap holds one Ethernet interface: write a pcapng"));
  }
  const Result<std::FILE*> opened = openFile(path);
  if (!opened) return fail(opened.error());
  std::FILE* file = *opened;
  if (compression != Compression::None) {
    Result<std::FILE*> compressed = openCompressedOutput(file, file != stdout, compression);
    if (!compressed) {
      if (file != stdout) std::fclose(file);
      Error error = compressed.error();
      error.path = path;
      return fail(std::move(error));
    }
    file = *compressed;
  }
  std::unique_ptr<char[]> buffer = bufferFile(file);
  if (format == CaptureFormat::Pcapng) {
    return std::make_unique<PcapngWriter>(
        path, file, std::move(buffer),
        interfaces.empty() ? std::vector<PcapngInterface>{PcapngInterface{}} : interfaces);
  }
  pcap_t* dead =
      pcap_open_dead_with_tstamp_precision(DLT_EN10MB, kSnapLength, PCAP_TSTAMP_PRECISION_MICRO);
  pcap_dumper_t* dumper = dead != nullptr ? pcap_dump_fopen(dead, file) : nullptr;
  if (dumper == nullptr) {
    Error error =
        writeError(path, fmt::format("cannot write a pcap: {}",
                                     dead != nullptr ? pcap_geterr(dead) : "libpcap failed"));
    if (dead != nullptr) pcap_close(dead);
    if (file != stdout) std::fclose(file);
    return fail(std::move(error));
  }
  return std::make_unique<PcapWriter>(path, file, std::move(buffer), dead, dumper);
}

Result<std::unique_ptr<CaptureWriter>> CaptureWriter::openPcapng(const std::string& path,
                                                                 const PcapngInterface& interface) {
  const Result<std::FILE*> opened = openFile(path);
  if (!opened) return fail(opened.error());
  std::unique_ptr<char[]> buffer = bufferFile(*opened);
  return std::make_unique<PcapngWriter>(path, *opened, std::move(buffer),
                                        std::vector<PcapngInterface>{interface});
}

}  // namespace ncservo
