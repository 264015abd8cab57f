#include "ncservo/capture/capture_annotation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/capture/capture_writer.hpp"

namespace ncservo {
namespace {

// pcapng block types and options (draft-ietf-opsawg-pcapng §3.5, §4.3, §4.4, appendix A).
constexpr std::uint32_t kPacketBlock = 2;  // obsolete, but read by libpcap and Wireshark
constexpr std::uint32_t kEnhancedPacketBlock = 6;
constexpr std::size_t kPacketHeader = 28;  // type, length, interface, timestamp, two lengths
constexpr std::size_t kCapturedLengthAt = 20;
constexpr std::uint16_t kOptionEnd = 0;
constexpr std::uint16_t kOptionComment = 1;
constexpr std::size_t kMaxOptionLength = 0xFFFF;
constexpr std::size_t kCopyBuffer = 1 << 16;

std::size_t padded(std::size_t size) {
  return (size + 3) & ~std::size_t{3};
}

struct Endian {
  bool big;
  std::uint32_t load32(const std::uint8_t* p) const {
    return big ? (std::uint32_t{p[0]} << 24 | std::uint32_t{p[1]} << 16 | std::uint32_t{p[2]} << 8 |
                  p[3])
               : (std::uint32_t{p[3]} << 24 | std::uint32_t{p[2]} << 16 | std::uint32_t{p[1]} << 8 |
                  p[0]);
  }
  std::uint16_t load16(const std::uint8_t* p) const {
    return static_cast<std::uint16_t>(big ? (p[0] << 8 | p[1]) : (p[1] << 8 | p[0]));
  }
  void put16(std::vector<std::uint8_t>& out, std::uint16_t v) const {
    const std::uint8_t hi = static_cast<std::uint8_t>(v >> 8), lo = static_cast<std::uint8_t>(v);
    out.push_back(big ? hi : lo);
    out.push_back(big ? lo : hi);
  }
  void put32(std::vector<std::uint8_t>& out, std::uint32_t v) const {
    put16(out, static_cast<std::uint16_t>(big ? v >> 16 : v));
    put16(out, static_cast<std::uint16_t>(big ? v : v >> 16));
  }
  void store32(std::uint8_t* p, std::uint32_t v) const {
    for (int i = 0; i < 4; ++i) p[big ? 3 - i : i] = static_cast<std::uint8_t>(v >> (8 * i));
  }
};

Error fileError(const std::string& path, std::string message) {
  return Error{path, 0, 0, {}, std::move(message)};
}

// Copies [from, to) of `in` to `out`.
Status copyRange(std::FILE* in, std::uint64_t from, std::uint64_t to, std::FILE* out,
                 const std::string& input) {
  static thread_local std::vector<char> buffer(kCopyBuffer);
  if (std::fseek(in, static_cast<long>(from), SEEK_SET) != 0) {
    return fail(fileError(input, fmt::format("cannot seek: {}", std::strerror(errno))));
  }
  for (std::uint64_t left = to - from; left > 0;) {
    const std::size_t chunk = static_cast<std::size_t>(std::min<std::uint64_t>(left, kCopyBuffer));
    const std::size_t got = std::fread(buffer.data(), 1, chunk, in);
    if (got == 0) return fail(fileError(input, "ended while being copied"));
    std::fwrite(buffer.data(), 1, got, out);
    left -= got;
  }
  return {};
}

// A pcapng file: its blocks copied as stored (libpcap locates each packet's block), the packets'
// with their comments added.
Status copyPcapng(CaptureReader& reader, const std::string& input, std::FILE* out,
                  const FrameComments& comments, const FrameFilter& keep,
                  const CommentFilter& replaced) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> raw(std::fopen(input.c_str(), "rb"), std::fclose);
  if (!raw) return fail(fileError(input, fmt::format("cannot read: {}", std::strerror(errno))));
  std::uint64_t copied = 0;
  std::vector<std::uint8_t> block;
  CaptureRecord record;
  Result<bool> more;
  while ((more = reader.next(record)) && *more) {
    if (!record.stored) {
      return fail(Error{input, 0, record.frame, {}, "its block could not be located in the file"});
    }
    if (Status gap = copyRange(raw.get(), copied, record.stored->offset, out, input); !gap) {
      return gap;
    }
    copied = record.stored->offset + record.stored->length;
    if (keep && !keep(record.frame, record.time_ns)) continue;
    const auto found = comments.find(record.frame);
    // A block with options may hold comments to replace; one without is copied as it is.
    const bool options = record.stored->length > kPacketHeader + padded(record.captured) + 4;
    if (found == comments.end() && !(replaced && options)) {
      if (Status same = copyRange(raw.get(), record.stored->offset, copied, out, input); !same) {
        return same;
      }
      continue;
    }
    block.resize(record.stored->length);
    if (std::fseek(raw.get(), static_cast<long>(record.stored->offset), SEEK_SET) != 0 ||
        std::fread(block.data(), 1, block.size(), raw.get()) != block.size()) {
      return fail(Error{input, 0, record.frame, {}, "its block could not be read again"});
    }
    static const std::vector<std::string> kNone;
    const auto annotated = withComments(block.data(), block.size(),
                                        found == comments.end() ? kNone : found->second, replaced);
    if (!annotated) {
      return fail(Error{input,
                        0,
                        record.frame,
                        {},
                        "a Simple Packet Block (or a malformed one), which holds no comments"});
    }
    std::fwrite(annotated->data(), 1, annotated->size(), out);
  }
  if (!more) return fail(more.error());
  std::fseek(raw.get(), 0, SEEK_END);
  const long end = std::ftell(raw.get());
  return copyRange(raw.get(), copied, static_cast<std::uint64_t>(std::max(end, 0L)), out, input);
}

// A pcap: each record as an Enhanced Packet Block of one interface with the pcap's link type and
// timestamp resolution.
Status convertPcap(CaptureReader& reader, const std::string& output, const FrameComments& comments,
                   const FrameFilter& keep) {
  auto writer = CaptureWriter::openPcapng(output, {reader.dlt(), reader.timestampDigits()});
  if (!writer) return fail(writer.error());
  CaptureRecord record;
  Result<bool> more;
  bool written = true;
  while ((more = reader.next(record)) && *more && written) {
    if (keep && !keep(record.frame, record.time_ns)) continue;
    const auto found = comments.find(record.frame);
    written =
        (*writer)->write(PacketRecord{record.time_ns, record.data, record.captured, record.original,
                                      found == comments.end() ? nullptr : &found->second});
  }
  const Status closed = (*writer)->close();
  if (!more) return fail(more.error());
  return closed;
}

}  // namespace

std::optional<std::vector<std::uint8_t>> withComments(const std::uint8_t* block, std::size_t size,
                                                      const std::vector<std::string>& comments,
                                                      const CommentFilter& replaced) {
  if (size < kPacketHeader + 4) return std::nullopt;
  const Endian endian{block[0] == 0};
  const std::uint32_t type = endian.load32(block);
  if ((type != kEnhancedPacketBlock && type != kPacketBlock) || endian.load32(block + 4) != size) {
    return std::nullopt;
  }
  const std::size_t options = kPacketHeader + padded(endian.load32(block + kCapturedLengthAt));
  const std::size_t trailer = size - 4;
  if (options > trailer) return std::nullopt;
  // The options it has, up to (not including) opt_endofopt, which may be absent; less the
  // comments replaced.
  std::vector<std::uint8_t> out(block, block + options);
  for (std::size_t at = options; at + 4 <= trailer;) {
    const std::uint16_t code = endian.load16(block + at);
    const std::size_t length = endian.load16(block + at + 2);
    const std::size_t next = at + 4 + padded(length);
    if (code == kOptionEnd || next > trailer) break;
    const std::string_view text(reinterpret_cast<const char*>(block + at + 4), length);
    if (!(replaced && code == kOptionComment && replaced(text))) {
      out.insert(out.end(), block + at, block + next);
    }
    at = next;
  }
  for (const std::string& comment : comments) {
    const std::size_t length = std::min(comment.size(), kMaxOptionLength);
    endian.put16(out, kOptionComment);
    endian.put16(out, static_cast<std::uint16_t>(length));
    out.insert(out.end(), comment.begin(), comment.begin() + static_cast<long>(length));
    out.resize(padded(out.size()), 0);
  }
  endian.put32(out, 0);  // opt_endofopt
  const auto total = static_cast<std::uint32_t>(out.size() + 4);
  endian.put32(out, total);
  endian.store32(out.data() + 4, total);
  return out;
}

Status annotateCapture(const std::string& input, const std::string& output,
                       const FrameComments& comments, const FrameFilter& keep,
                       const CommentFilter& replaced) {
  auto opened = CaptureReader::open(input);
  if (!opened) return fail(opened.error());
  CaptureReader& reader = **opened;
  if (!reader.pcapng()) return convertPcap(reader, output, comments, keep);
  if (reader.compression() != Compression::None) {
    return fail(fileError(input, fmt::format("a {}-compressed pcapng: its blocks are copied as "
                                             "stored, so decompress it first",
                                             compressionName(reader.compression()))));
  }
  std::FILE* out = output == "-" ? stdout : std::fopen(output.c_str(), "wb");
  if (out == nullptr) {
    return fail(fileError(output, fmt::format("cannot write: {}", std::strerror(errno))));
  }
  Status copied = copyPcapng(reader, input, out, comments, keep, replaced);
  const bool flushed = std::fflush(out) == 0 && std::ferror(out) == 0;
  if (out != stdout) std::fclose(out);
  if (copied && !flushed) {
    copied = fail(fileError(output, fmt::format("write failed: {}", std::strerror(errno))));
  }
  return copied;
}

}  // namespace ncservo
