// Writing captures: pcap through libpcap (microsecond timestamps), pcapng with nanosecond
// timestamps (libpcap cannot write pcapng; the three blocks it needs are written here).
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "ncservo/capture_reader.hpp"

namespace ncservo {

enum class CaptureFormat : std::uint8_t { Pcap, Pcapng };

class CaptureWriter {
 public:
  // "-" writes to standard output; `compression` compresses the stream (compressed_output.hpp).
  // On failure `error` names the file and the reason.
  static std::unique_ptr<CaptureWriter> open(const std::string& path, CaptureFormat format,
                                             std::string& error,
                                             Compression compression = Compression::None);
  virtual ~CaptureWriter() = default;
  // One Ethernet frame; false once a write failed.
  virtual bool write(std::int64_t time_ns, const std::uint8_t* data, std::size_t size) = 0;
  // Flushes and closes; false (with `error`) if anything failed.
  virtual bool close(std::string& error) = 0;
};

}  // namespace ncservo
