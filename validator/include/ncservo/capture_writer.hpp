// Writing captures: pcap through libpcap (microsecond timestamps), pcapng with nanosecond
// timestamps (libpcap cannot write pcapng; the three blocks it needs are written here).
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "ncservo/capture_reader.hpp"
#include "ncservo/error.hpp"

namespace ncservo {

enum class CaptureFormat : std::uint8_t { Pcap, Pcapng };

class CaptureWriter {
 public:
  // "-" writes to standard output; `compression` compresses the stream (compressed_output.hpp).
  // An error names the file and the reason.
  static Result<std::unique_ptr<CaptureWriter>> open(const std::string& path, CaptureFormat format,
                                                     Compression compression = Compression::None);
  virtual ~CaptureWriter() = default;
  // One Ethernet frame; false once a write failed (close() says why).
  virtual bool write(std::int64_t time_ns, const std::uint8_t* data, std::size_t size) = 0;
  // Flushes and closes; an error if anything failed.
  virtual Status close() = 0;
};

}  // namespace ncservo
