// Writing captures: pcap through libpcap (microsecond timestamps), pcapng with nanosecond
// timestamps by default, packet comments and, when asked, several interfaces (libpcap cannot
// write pcapng; the three blocks it needs are written here).
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/capture/capture_reader.hpp"

namespace ncservo {

enum class CaptureFormat : std::uint8_t { Pcap, Pcapng };

// A pcapng's interface: its link type (DLT) and the digits of a second its timestamps hold
// (if_tsresol: 6 or 9), so a copy of a capture keeps its resolution.
struct PcapngInterface {
  int dlt = 1;  // DLT_EN10MB
  int timestamp_digits = 9;
};

// One record as a copy of a capture writes it: what was captured, the frame's length on the
// wire, and its packet comments (pcapng opt_comment; a pcap has none).
struct PacketRecord {
  std::int64_t time_ns = 0;
  const std::uint8_t* data = nullptr;
  std::size_t captured = 0;
  std::size_t original = 0;
  const std::vector<std::string>* comments = nullptr;
  std::uint32_t interface_id = 0;  // the pcapng interface it was captured on (a pcap has one)
};

class CaptureWriter {
 public:
  // "-" writes to standard output; `compression` compresses the stream (compressed_output.hpp).
  // A pcapng has the `interfaces` given, in that order, or one Ethernet interface when none is;
  // a pcap holds one Ethernet interface only. An error names the file and the reason.
  static Result<std::unique_ptr<CaptureWriter>> open(
      const std::string& path, CaptureFormat format, Compression compression = Compression::None,
      const std::vector<PcapngInterface>& interfaces = {});
  // A pcapng of that one interface (uncompressed; "-" writes to standard output).
  static Result<std::unique_ptr<CaptureWriter>> openPcapng(const std::string& path,
                                                           const PcapngInterface& interface);
  virtual ~CaptureWriter() = default;
  // One Ethernet frame; false once a write failed (close() says why).
  virtual bool write(std::int64_t time_ns, const std::uint8_t* data, std::size_t size) = 0;
  // One record as captured, with its comments, on its interface; false once a write failed or
  // when the file has no such interface.
  virtual bool write(const PacketRecord& record) = 0;
  // Flushes and closes; an error if anything failed.
  virtual Status close() = 0;
};

}  // namespace ncservo
