#include "ncservo/capture_reader.hpp"

#include <fmt/format.h>
#include <pcap/pcap.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

namespace ncservo {

CaptureReader::~CaptureReader() {
  if (handle_ != nullptr) pcap_close(handle_);
}

std::unique_ptr<CaptureReader> CaptureReader::open(const std::string& path, std::string& error) {
  const std::string name = path == "-" ? "standard input" : path;
  std::FILE* file = path == "-" ? stdin : std::fopen(path.c_str(), "rb");
  if (file == nullptr) {
    error = fmt::format("{}: cannot read capture: {}", name, std::strerror(errno));
    return nullptr;
  }
  // libpcap's words for these ("truncated dump file; tried to read 4 file header bytes") do not
  // say what is wrong with the file.
  struct stat info {};
  if (fstat(fileno(file), &info) == 0 &&
      (S_ISDIR(info.st_mode) || (S_ISREG(info.st_mode) && info.st_size == 0))) {
    if (file != stdin) std::fclose(file);
    error = fmt::format("{}: cannot read capture: {}", name,
                        S_ISDIR(info.st_mode) ? "is a directory" : "empty file");
    return nullptr;
  }
  std::unique_ptr<CaptureReader> reader(new CaptureReader());
  // A 64 KiB stdio buffer: 16 times fewer system calls than stdio's 4 KiB, and the bytes just
  // read are still in the core's cache when they are parsed. (A buffer the size of the L2
  // cache, 1 MiB, measured 15 % slower: each refill evicts what the next frames need.)
  reader->buffer_ = std::make_unique<char[]>(kReadBufferSize);
  std::setvbuf(file, reader->buffer_.get(), _IOFBF, kReadBufferSize);
  char errbuf[PCAP_ERRBUF_SIZE] = {};
  pcap_t* handle =
      pcap_fopen_offline_with_tstamp_precision(file, PCAP_TSTAMP_PRECISION_NANO, errbuf);
  if (handle == nullptr) {
    if (file != stdin) std::fclose(file);
    error = fmt::format("{}: cannot read capture: {}", name, errbuf);
    return nullptr;
  }
  reader->handle_ = handle;
  reader->path_ = name;
  reader->dlt_ = pcap_datalink(handle);
  reader->link_ = linkTypeFromDlt(reader->dlt_);
  if (reader->link_ == LinkType::Unsupported) {
    const char* dlt_name = pcap_datalink_val_to_name(reader->dlt_);
    error = fmt::format(
        "{}: unsupported link type {} ({}); ncservo reads Ethernet and Linux "
        "cooked (SLL, SLL2) captures",
        name, reader->dlt_, dlt_name != nullptr ? dlt_name : "unknown");
    return nullptr;
  }
  return reader;
}

CaptureReader::Next CaptureReader::next(CaptureRecord& record) {
  pcap_pkthdr* header = nullptr;
  const u_char* data = nullptr;
  const int rc = pcap_next_ex(handle_, &header, &data);
  if (rc == PCAP_ERROR_BREAK) return Next::End;
  if (rc != 1) {
    error_ = fmt::format("{}: frame {}: {}", path_, frames_ + 1, pcap_geterr(handle_));
    return Next::Error;
  }
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
  return Next::Record;
}

}  // namespace ncservo
