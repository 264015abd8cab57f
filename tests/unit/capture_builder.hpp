// Captures built byte by byte for the capture reader's tests (record_parser_test.cpp,
// record_merge_test.cpp): pcap records and pcapng blocks in either byte order, with the fields
// a test wants to get wrong.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

namespace ncservo::test {

using Bytes = std::vector<std::uint8_t>;

// Writes fields in one byte order.
struct Writer {
  bool big = false;
  Bytes out;
  void u8(std::uint8_t v) { out.push_back(v); }
  void u16(std::uint16_t v) {
    if (big) {
      u8(static_cast<std::uint8_t>(v >> 8));
      u8(static_cast<std::uint8_t>(v));
    } else {
      u8(static_cast<std::uint8_t>(v));
      u8(static_cast<std::uint8_t>(v >> 8));
    }
  }
  void u32(std::uint32_t v) {
    if (big) {
      u16(static_cast<std::uint16_t>(v >> 16));
      u16(static_cast<std::uint16_t>(v));
    } else {
      u16(static_cast<std::uint16_t>(v));
      u16(static_cast<std::uint16_t>(v >> 16));
    }
  }
  void u64(std::uint64_t v) {
    if (big) {
      u32(static_cast<std::uint32_t>(v >> 32));
      u32(static_cast<std::uint32_t>(v));
    } else {
      u32(static_cast<std::uint32_t>(v));
      u32(static_cast<std::uint32_t>(v >> 32));
    }
  }
  void fill(std::size_t n, std::uint8_t value = 0xAB) { out.insert(out.end(), n, value); }
};

// pcap-savefile(5): the file header, then records of seconds, fraction, lengths and data.
struct PcapFile {
  Writer w;
  PcapFile(bool big, std::uint32_t magic, std::uint16_t minor = 4, std::uint32_t snaplen = 65535) {
    w.big = big;
    w.u32(magic);
    w.u16(2);
    w.u16(minor);
    w.u32(0);
    w.u32(0);
    w.u32(snaplen);
    w.u32(1);  // Ethernet
  }
  PcapFile& record(std::uint32_t seconds, std::uint32_t fraction, std::uint32_t captured,
                   std::uint32_t original, std::size_t data) {
    w.u32(seconds);
    w.u32(fraction);
    w.u32(captured);
    w.u32(original);
    w.fill(data);
    return *this;
  }
  PcapFile& cut(std::size_t bytes) {
    w.out.resize(w.out.size() - bytes);
    return *this;
  }
};

// pcapng blocks: type, total length, body padded to 4 bytes, total length.
struct PcapngFile {
  Writer w;
  explicit PcapngFile(bool big) {
    w.big = big;
    section();
  }
  PcapngFile& block(std::uint32_t type, const Bytes& body, std::optional<std::uint32_t> length = {},
                    std::optional<std::uint32_t> trailer = {}) {
    const auto padded = static_cast<std::uint32_t>((body.size() + 3) / 4 * 4);
    w.u32(type);
    w.u32(length.value_or(12 + padded));
    w.out.insert(w.out.end(), body.begin(), body.end());
    w.fill(padded - body.size(), 0);
    w.u32(trailer.value_or(length.value_or(12 + padded)));
    return *this;
  }
  Writer body() const { return Writer{w.big, {}}; }
  PcapngFile& section(std::uint32_t magic = 0x1A2B3C4D) {
    Writer b = body();
    b.u32(magic);
    b.u16(1);
    b.u16(0);
    b.u64(~std::uint64_t{0});
    return block(0x0A0D0D0A, b.out);
  }
  // An interface: link type, snap length, and if_tsresol / if_tsoffset when given.
  PcapngFile& interface(std::uint16_t link = 1, std::uint32_t snaplen = 65535,
                        std::optional<std::uint8_t> tsresol = {},
                        std::optional<std::int64_t> tsoffset = {}) {
    Writer b = body();
    b.u16(link);
    b.u16(0);
    b.u32(snaplen);
    if (tsresol) {
      b.u16(9);
      b.u16(1);
      b.u8(*tsresol);
      b.fill(3, 0);
    }
    if (tsoffset) {
      b.u16(14);
      b.u16(8);
      b.u64(static_cast<std::uint64_t>(*tsoffset));
    }
    b.u16(0);
    b.u16(0);
    return block(1, b.out);
  }
  PcapngFile& enhanced(std::uint32_t interface, std::uint64_t ticks, std::uint32_t captured,
                       std::uint32_t original, std::size_t data, std::uint8_t value = 0xAB) {
    Writer b = body();
    b.u32(interface);
    b.u32(static_cast<std::uint32_t>(ticks >> 32));
    b.u32(static_cast<std::uint32_t>(ticks));
    b.u32(captured);
    b.u32(original);
    b.fill(data, value);
    return block(6, b.out);
  }
  PcapngFile& simple(std::uint32_t original, std::size_t data) {
    Writer b = body();
    b.u32(original);
    b.fill(data);
    return block(3, b.out);
  }
  PcapngFile& obsolete(std::uint16_t interface, std::uint64_t ticks, std::uint32_t captured,
                       std::size_t data) {
    Writer b = body();
    b.u16(interface);
    b.u16(0);
    b.u32(static_cast<std::uint32_t>(ticks >> 32));
    b.u32(static_cast<std::uint32_t>(ticks));
    b.u32(captured);
    b.u32(captured);
    b.fill(data);
    return block(2, b.out);
  }
  // Interface statistics: isb_ifdrop (option 5) and isb_osdrop (7).
  PcapngFile& statistics(std::uint64_t ifdrop, std::uint64_t osdrop) {
    Writer b = body();
    b.u32(0);
    b.u64(0);
    b.u16(5);
    b.u16(8);
    b.u64(ifdrop);
    b.u16(7);
    b.u16(8);
    b.u64(osdrop);
    b.u16(0);
    b.u16(0);
    return block(5, b.out);
  }
  PcapngFile& raw(const Bytes& bytes) {
    w.out.insert(w.out.end(), bytes.begin(), bytes.end());
    return *this;
  }
  PcapngFile& cut(std::size_t bytes) {
    w.out.resize(w.out.size() - bytes);
    return *this;
  }
};

}  // namespace ncservo::test
