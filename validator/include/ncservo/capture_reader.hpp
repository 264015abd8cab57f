// Reads pcap and pcapng captures (libpcap) record by record, in constant memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "ncservo/ethercat.hpp"

struct pcap;  // libpcap's handle, kept out of this header

namespace ncservo {

struct CaptureRecord {
  std::uint64_t frame = 0;   // 1-based, as Wireshark numbers frames
  std::int64_t time_ns = 0;  // absolute capture time in nanoseconds
  const std::uint8_t* data = nullptr;
  std::size_t captured = 0;
  std::size_t original = 0;
};

class CaptureReader {
 public:
  enum class Next { Record, End, Error };

  ~CaptureReader();
  CaptureReader(const CaptureReader&) = delete;
  CaptureReader& operator=(const CaptureReader&) = delete;

  // Opens PATH ("-" = standard input); on failure returns null and a message naming the file.
  static std::unique_ptr<CaptureReader> open(const std::string& path, std::string& error);

  // The next record; on Error, error() says what went wrong and at which frame.
  Next next(CaptureRecord& record);

  LinkType link() const { return link_; }
  int dlt() const { return dlt_; }
  const std::string& error() const { return error_; }
  const std::string& path() const { return path_; }

 private:
  CaptureReader() = default;
  static constexpr std::size_t kReadBufferSize = 1 << 16;
  std::unique_ptr<char[]> buffer_;  // the FILE's buffer: outlives the handle that closes it
  ::pcap* handle_ = nullptr;
  std::string path_;
  std::string error_;
  LinkType link_ = LinkType::Unsupported;
  int dlt_ = 0;
  std::uint64_t frames_ = 0;
};

}  // namespace ncservo
