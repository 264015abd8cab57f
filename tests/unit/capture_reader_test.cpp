// CaptureReader (capture_reader.hpp) over plain, gzip and zstd pcap and pcapng, from a file and
// from a pipe on standard input; cut and corrupt compressed streams (docs/protocol.md §8); a
// pcapng's interfaces of their own, and RecordMerge (record_merge.hpp) merging them by time
// (docs/protocol.md §8).
#include "ncservo/capture/capture_reader.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>
#include <zstd.h>

#include <cstdint>
#include <cstdio>
#include <optional>
#include <ostream>
#include <string>
#include <thread>
#include <vector>

#include "capture_builder.hpp"
#include "ncservo/capture/capture_writer.hpp"
#include "ncservo/capture/record_merge.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

using Bytes = std::vector<std::uint8_t>;
using test::PcapngFile;

struct Frame {
  std::int64_t time_ns;
  Bytes bytes;
};

// Frames of varied sizes and contents (they need not be EtherCAT: the reader does not look).
std::vector<Frame> someFrames() {
  std::vector<Frame> frames;
  std::uint32_t x = 12345;
  for (std::size_t i = 0; i < 3000; ++i) {
    Bytes bytes(60 + (i * 37) % 1400);
    for (std::uint8_t& b : bytes) {
      x = x * 1103515245u + 12345u;
      b = static_cast<std::uint8_t>(x >> 24 & 0x0F);  // compressible, not trivially
    }
    frames.push_back({1'700'000'000'000'000'000 + static_cast<std::int64_t>(i) * 1'000'123, bytes});
  }
  return frames;
}

Bytes readFile(const std::string& path) {
  Bytes out;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return out;
  std::uint8_t chunk[1 << 16];
  std::size_t n;
  while ((n = std::fread(chunk, 1, sizeof chunk, f)) > 0) out.insert(out.end(), chunk, chunk + n);
  std::fclose(f);
  return out;
}

void writeFile(const std::string& path, const Bytes& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fwrite(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
}

Bytes gzipOf(const Bytes& plain) {
  z_stream z{};
  EXPECT_EQ(deflateInit2(&z, 6, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY), Z_OK);
  Bytes out(deflateBound(&z, plain.size()) + 64);
  z.next_in = const_cast<Bytef*>(plain.data());
  z.avail_in = static_cast<uInt>(plain.size());
  z.next_out = out.data();
  z.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(deflate(&z, Z_FINISH), Z_STREAM_END);
  out.resize(z.total_out);
  deflateEnd(&z);
  return out;
}

Bytes zstdOf(const Bytes& plain) {
  Bytes out(ZSTD_compressBound(plain.size()));
  const std::size_t n = ZSTD_compress(out.data(), out.size(), plain.data(), plain.size(), 3);
  EXPECT_FALSE(ZSTD_isError(n));
  out.resize(n);
  return out;
}

std::string tempPath() {
  char path[] = "/tmp/ncservo_reader_XXXXXX";
  const int fd = mkstemp(path);
  close(fd);
  return path;
}

// The capture's bytes, as the writer makes them, then compressed as asked.
Bytes captureBytes(CaptureFormat format, Compression compression,
                   const std::vector<Frame>& frames) {
  const std::string path = tempPath();
  auto opened = CaptureWriter::open(path, format);
  EXPECT_TRUE(opened) << opened.error().text();
  CaptureWriter& writer = **opened;
  for (const Frame& f : frames) writer.write(f.time_ns, f.bytes.data(), f.bytes.size());
  const Status closed = writer.close();
  EXPECT_TRUE(closed) << closed.error().text();
  Bytes plain = readFile(path);
  std::remove(path.c_str());
  switch (compression) {
    case Compression::Gzip:
      return gzipOf(plain);
    case Compression::Zstd:
      return zstdOf(plain);
    case Compression::None:
      break;
  }
  return plain;
}

// Puts `bytes` behind a pipe on standard input (fd 0), written from a thread.
class StdinPipe {
 public:
  explicit StdinPipe(Bytes bytes) : bytes_(std::move(bytes)) {
    int fds[2];
    EXPECT_EQ(pipe(fds), 0);
    saved_ = dup(0);
    dup2(fds[0], 0);
    close(fds[0]);
    std::clearerr(stdin);
    writer_ = std::thread([this, fd = fds[1]] {
      std::size_t done = 0;
      while (done < bytes_.size()) {
        const ssize_t n = write(fd, bytes_.data() + done, bytes_.size() - done);
        if (n <= 0) break;
        done += static_cast<std::size_t>(n);
      }
      close(fd);
    });
  }
  ~StdinPipe() {
    // Drain what the reader left (after an error), so that the writer ends.
    char sink[4096];
    while (std::fread(sink, 1, sizeof sink, stdin) > 0) {
    }
    writer_.join();
    dup2(saved_, 0);
    close(saved_);
    std::clearerr(stdin);
  }

 private:
  Bytes bytes_;
  int saved_ = -1;
  std::thread writer_;
};

// What a reader gave: the frames read, and how it ended.
struct ReadBack {
  std::vector<Frame> frames;
  std::optional<Error> error;
};
ReadBack readAll(CaptureReader& reader) {
  ReadBack out;
  CaptureRecord record;
  Result<bool> next;
  while ((next = reader.next(record)) && *next) {
    out.frames.push_back({record.time_ns, Bytes(record.data, record.data + record.captured)});
  }
  if (!next) out.error = next.error();
  return out;
}

struct ReaderRow {
  const char* name;
  CaptureFormat format;
  Compression compression;
  bool via_stdin;
};
class ReaderFormats : public ::testing::TestWithParam<ReaderRow> {};

TEST_P(ReaderFormats, ReadsEveryFrame) {
  const ReaderRow& row = GetParam();
  const std::vector<Frame> frames = someFrames();
  const Bytes bytes = captureBytes(row.format, row.compression, frames);
  const std::string path = tempPath();
  writeFile(path, bytes);
  std::optional<StdinPipe> pipe;
  if (row.via_stdin) pipe.emplace(bytes);
  auto opened = CaptureReader::open(row.via_stdin ? "-" : path);
  ASSERT_TRUE(opened) << opened.error().text();
  CaptureReader& reader = **opened;
  EXPECT_EQ(reader.compression(), row.compression);
  EXPECT_EQ(reader.dlt(), 1);
  EXPECT_EQ(reader.path(), row.via_stdin ? "standard input" : path);
  const ReadBack got = readAll(reader);
  EXPECT_FALSE(got.error) << got.error->text();
  ASSERT_EQ(got.frames.size(), frames.size());
  const std::int64_t resolution = row.format == CaptureFormat::Pcap ? 1000 : 1;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(got.frames[i].time_ns, frames[i].time_ns / resolution * resolution) << i;
    ASSERT_EQ(got.frames[i].bytes, frames[i].bytes) << "frame " << i + 1;
  }
  std::remove(path.c_str());
}

INSTANTIATE_TEST_SUITE_P(
    Rows, ReaderFormats,
    ::testing::Values(
        ReaderRow{"pcap_plain_file", CaptureFormat::Pcap, Compression::None, false},
        ReaderRow{"pcapng_plain_file", CaptureFormat::Pcapng, Compression::None, false},
        ReaderRow{"pcap_gzip_file", CaptureFormat::Pcap, Compression::Gzip, false},
        ReaderRow{"pcapng_gzip_file", CaptureFormat::Pcapng, Compression::Gzip, false},
        ReaderRow{"pcap_zstd_file", CaptureFormat::Pcap, Compression::Zstd, false},
        ReaderRow{"pcapng_zstd_file", CaptureFormat::Pcapng, Compression::Zstd, false},
        ReaderRow{"pcap_plain_stdin", CaptureFormat::Pcap, Compression::None, true},
        ReaderRow{"pcapng_plain_stdin", CaptureFormat::Pcapng, Compression::None, true},
        ReaderRow{"pcap_gzip_stdin", CaptureFormat::Pcap, Compression::Gzip, true},
        ReaderRow{"pcapng_gzip_stdin", CaptureFormat::Pcapng, Compression::Gzip, true},
        ReaderRow{"pcap_zstd_stdin", CaptureFormat::Pcap, Compression::Zstd, true},
        ReaderRow{"pcapng_zstd_stdin", CaptureFormat::Pcapng, Compression::Zstd, true}),
    test::rowName<ReaderRow>);

// A damaged compressed capture: the error names the file and the damage, and the frames
// before it were read.
struct DamageRow {
  const char* name;
  Compression compression;
  // Flip: bytes in the middle changed (zstd's entropy decoder notices; deflate decodes them to
  // other bytes, so for gzip only the trailer's CRC-32 tells: FlipTrailer).
  enum { Cut, Flip, FlipTrailer, CutHeader } damage;
  const char* message;  // what the error says
  bool at_open;         // the damage is found before the first frame
};
class ReaderDamage : public ::testing::TestWithParam<DamageRow> {};

TEST_P(ReaderDamage, SaysWhatAndKeepsWhatWasRead) {
  const DamageRow& row = GetParam();
  const std::vector<Frame> frames = someFrames();
  Bytes bytes = captureBytes(CaptureFormat::Pcap, row.compression, frames);
  switch (row.damage) {
    case DamageRow::Cut:
      bytes.resize(bytes.size() / 2);
      break;
    case DamageRow::Flip:
      for (std::size_t i = bytes.size() / 2; i < bytes.size() / 2 + 64; ++i) bytes[i] ^= 0xA5;
      break;
    case DamageRow::FlipTrailer:
      bytes[bytes.size() - 8] ^= 0xA5;
      break;
    case DamageRow::CutHeader:
      bytes.resize(10);
      break;
  }
  const std::string path = tempPath();
  writeFile(path, bytes);
  auto opened = CaptureReader::open(path);
  if (row.at_open) {
    ASSERT_FALSE(opened);
    EXPECT_EQ(opened.error().path, path);
    EXPECT_NE(opened.error().text().find(row.message), std::string::npos) << opened.error().text();
  } else {
    ASSERT_TRUE(opened) << opened.error().text();
    const ReadBack got = readAll(**opened);
    ASSERT_TRUE(got.error);
    EXPECT_EQ(got.error->path, path);
    EXPECT_EQ(got.error->frame, got.frames.size() + 1);
    EXPECT_NE(got.error->text().find(row.message), std::string::npos) << got.error->text();
    if (row.damage == DamageRow::FlipTrailer) {
      EXPECT_EQ(got.frames.size(), frames.size());
    } else {
      EXPECT_GT(got.frames.size(), frames.size() / 4);
      EXPECT_LT(got.frames.size(), frames.size());
    }
    for (std::size_t i = 0; i + 1 < got.frames.size(); ++i) {
      ASSERT_EQ(got.frames[i].bytes, frames[i].bytes) << "frame " << i + 1;
    }
  }
  std::remove(path.c_str());
}

INSTANTIATE_TEST_SUITE_P(
    Rows, ReaderDamage,
    ::testing::Values(DamageRow{"gzip_cut", Compression::Gzip, DamageRow::Cut,
                                "the gzip stream is cut short (truncated compressed file)", false},
                      DamageRow{"zstd_cut", Compression::Zstd, DamageRow::Cut,
                                "the zstd stream is cut short (truncated compressed file)", false},
                      DamageRow{"gzip_corrupt", Compression::Gzip, DamageRow::FlipTrailer,
                                "corrupt gzip data (incorrect data check)", false},
                      DamageRow{"zstd_corrupt", Compression::Zstd, DamageRow::Flip,
                                "corrupt zstd data", false},
                      DamageRow{"gzip_header_only", Compression::Gzip, DamageRow::CutHeader,
                                "cannot read capture: the gzip stream is cut short", true},
                      DamageRow{"zstd_header_only", Compression::Zstd, DamageRow::CutHeader,
                                "cannot read capture: the zstd stream is cut short", true}),
    test::rowName<DamageRow>);

TEST(CaptureReader, CompressedNotACaptureSaysSo) {
  const Bytes text(5000, 'x');
  const std::string path = tempPath();
  writeFile(path, zstdOf(text));
  auto opened = CaptureReader::open(path);
  ASSERT_FALSE(opened);
  EXPECT_NE(opened.error().text().find("(after zstd decompression)"), std::string::npos)
      << opened.error().text();
  std::remove(path.c_str());
}

// A pcapng of several interfaces, read by the reader alone (file order) or merged by time: each
// row from a plain file, a gzip file and zstd on standard input, which must all give the same.
struct Delivered {
  std::uint64_t frame;
  std::uint32_t interface;
  int link_type;
  std::int64_t time_ns;
};
bool operator==(const Delivered& a, const Delivered& b) {
  return a.frame == b.frame && a.interface == b.interface && a.link_type == b.link_type &&
         a.time_ns == b.time_ns;
}
std::ostream& operator<<(std::ostream& out, const Delivered& d) {
  return out << "{frame " << d.frame << ", interface " << d.interface << ", link type "
             << d.link_type << ", " << d.time_ns << " ns}";
}

struct InterfacesRow {
  const char* name;
  Bytes file;
  bool merged;  // through RecordMerge, else the reader's own order
  std::vector<Delivered> want;
  std::optional<std::uint64_t> error_frame = std::nullopt;  // the frame the error names
  const char* error = nullptr;                              // and what it says
  MergeLimits limits = {};
};

constexpr std::int64_t kUs = 1000, kMs = 1000000;

// Interfaces with nanosecond timestamps, each record's bytes its frame number (to check the bytes
// that come are the record's).
PcapngFile twoInterfaces(std::uint16_t second = 1) {
  PcapngFile file(false);
  file.interface(1, 65535, 9).interface(second, 65535, 9);
  return file;
}
PcapngFile& at(PcapngFile& file, std::uint32_t interface, std::int64_t ns, std::uint8_t frame) {
  return file.enhanced(interface, static_cast<std::uint64_t>(ns), 60, 60, 60, frame);
}

std::vector<InterfacesRow> interfacesRows() {
  std::vector<InterfacesRow> r;
  {
    PcapngFile f(false);
    f.interface(1, 65535, 6).interface(113, 65535, 9, 100);
    f.enhanced(0, 1500000, 60, 60, 60, 1).enhanced(1, 2000000007, 60, 60, 60, 2);
    f.enhanced(0, 1500001, 60, 60, 60, 3);
    r.push_back(
        {"link_types_resolutions_and_offset_of_their_own",
         f.w.out,
         false,
         {{1, 0, 1, 1500 * kMs}, {2, 1, 113, 102'000'000'007}, {3, 0, 1, 1500 * kMs + 1 * kUs}}});
  }
  {
    PcapngFile f(false);
    f.interface(147, 65535, 9).interface(1, 65535, 9);
    at(f, 0, 0, 1);
    at(f, 1, 10, 2);
    r.push_back({"first_interface_of_a_link_type_not_walked",
                 f.w.out,
                 false,
                 {{1, 0, 147, 0}, {2, 1, 1, 10}}});
  }
  {
    // A TAP's two directions, the returned copy of the second cycle written before its master.
    PcapngFile f = twoInterfaces();
    at(f, 0, 0, 1);
    at(f, 1, 50 * kUs, 2);
    at(f, 1, 1050 * kUs, 3);
    at(f, 0, 1000 * kUs, 4);
    at(f, 0, 2000 * kUs, 5);
    at(f, 1, 2050 * kUs, 6);
    r.push_back({"tap_directions_merged_by_time",
                 f.w.out,
                 true,
                 {{1, 0, 1, 0},
                  {2, 1, 1, 50 * kUs},
                  {4, 0, 1, 1000 * kUs},
                  {3, 1, 1, 1050 * kUs},
                  {5, 0, 1, 2000 * kUs},
                  {6, 1, 1, 2050 * kUs}}});
    r.push_back({"tap_directions_in_file_order_without_the_merge",
                 f.w.out,
                 false,
                 {{1, 0, 1, 0},
                  {2, 1, 1, 50 * kUs},
                  {3, 1, 1, 1050 * kUs},
                  {4, 0, 1, 1000 * kUs},
                  {5, 0, 1, 2000 * kUs},
                  {6, 1, 1, 2050 * kUs}}});
  }
  {
    // One interface: its records as they are, a jump back included (the capture's own).
    PcapngFile f(false);
    f.interface(1, 65535, 9);
    at(f, 0, 0, 1);
    at(f, 0, 10 * kMs, 2);
    at(f, 0, 5 * kMs, 3);
    r.push_back({"one_interface_in_file_order",
                 f.w.out,
                 true,
                 {{1, 0, 1, 0}, {2, 0, 1, 10 * kMs}, {3, 0, 1, 5 * kMs}}});
  }
  {
    PcapngFile f = twoInterfaces(113);
    at(f, 0, 3 * kMs, 1);
    at(f, 0, 1 * kMs, 2);
    at(f, 1, 2 * kMs, 3);
    r.push_back({"each_interface_keeps_its_own_order",
                 f.w.out,
                 true,
                 {{3, 1, 113, 2 * kMs}, {1, 0, 1, 3 * kMs}, {2, 0, 1, 1 * kMs}}});
  }
  {
    // Another recording appended (a jump back by more than the window): never merged across,
    // the merge starts again after it.
    PcapngFile f = twoInterfaces();
    at(f, 0, 20 * kMs, 1);
    at(f, 1, 21 * kMs, 2);
    at(f, 1, 1 * kMs + 50 * kUs, 3);
    at(f, 0, 1 * kMs, 4);
    at(f, 0, 22 * kMs, 5);
    r.push_back({"a_jump_back_is_not_merged_across",
                 f.w.out,
                 true,
                 {{1, 0, 1, 20 * kMs},
                  {2, 1, 1, 21 * kMs},
                  {4, 0, 1, 1 * kMs},
                  {3, 1, 1, 1 * kMs + 50 * kUs},
                  {5, 0, 1, 22 * kMs}}});
  }
  {
    PcapngFile f = twoInterfaces();
    for (std::uint8_t i = 1; i <= 4; ++i) at(f, 0, i * kMs, i);
    at(f, 1, 0, 5);
    r.push_back({"look_ahead_bounded_by_its_count",
                 f.w.out,
                 true,
                 {{1, 0, 1, 1 * kMs},
                  {2, 0, 1, 2 * kMs},
                  {3, 0, 1, 3 * kMs},
                  {5, 1, 1, 0},
                  {4, 0, 1, 4 * kMs}},
                 std::nullopt,
                 nullptr,
                 {.records = 2, .window_ns = 1000 * kMs}});
  }
  {
    PcapngFile f = twoInterfaces();
    at(f, 0, 0, 1);
    at(f, 0, 2 * kMs, 2);
    at(f, 0, 4 * kMs, 3);
    at(f, 1, 1500 * kUs, 4);
    r.push_back({"further_back_than_the_window_not_merged",
                 f.w.out,
                 true,
                 {{1, 0, 1, 0}, {2, 0, 1, 2 * kMs}, {3, 0, 1, 4 * kMs}, {4, 1, 1, 1500 * kUs}},
                 std::nullopt,
                 nullptr,
                 {.records = 64, .window_ns = 1 * kMs}});
  }
  {
    PcapngFile f = twoInterfaces(113);
    at(f, 0, 2 * kMs, 1);
    at(f, 1, 1 * kMs, 2);
    f.section().interface(276, 65535, 9);
    at(f, 0, 3 * kMs, 3);
    at(f, 0, 4 * kMs, 4);
    r.push_back(
        {"a_later_section_of_one_interface",
         f.w.out,
         true,
         {{2, 1, 113, 1 * kMs}, {1, 0, 1, 2 * kMs}, {3, 2, 276, 3 * kMs}, {4, 2, 276, 4 * kMs}}});
  }
  {
    // Cut inside the fifth record's block: the four before it come (merged), then the error.
    PcapngFile f = twoInterfaces();
    at(f, 0, 0, 1);
    at(f, 1, 300 * kUs, 2);
    at(f, 0, 200 * kUs, 3);
    at(f, 0, 400 * kUs, 4);
    at(f, 1, 500 * kUs, 5);
    f.cut(20);
    const Bytes cut = f.w.out;
    r.push_back({"a_truncated_block_names_its_frame_merged",
                 cut,
                 true,
                 {{1, 0, 1, 0}, {3, 0, 1, 200 * kUs}, {2, 1, 1, 300 * kUs}, {4, 0, 1, 400 * kUs}},
                 5,
                 "truncated pcapng dump file"});
    r.push_back({"a_truncated_block_names_its_frame",
                 cut,
                 false,
                 {{1, 0, 1, 0}, {2, 1, 1, 300 * kUs}, {3, 0, 1, 200 * kUs}, {4, 0, 1, 400 * kUs}},
                 5,
                 "truncated pcapng dump file"});
  }
  return r;
}

class ReaderInterfaces : public ::testing::TestWithParam<InterfacesRow> {};

TEST_P(ReaderInterfaces, EachRecordWithItsInterfaceInTimeWhereMerged) {
  const InterfacesRow& row = GetParam();
  enum class Source { File, GzipFile, ZstdStdin };
  for (const Source source : {Source::File, Source::GzipFile, Source::ZstdStdin}) {
    SCOPED_TRACE(source == Source::File ? "file" : source == Source::GzipFile ? "gzip" : "stdin");
    const Bytes bytes = source == Source::File       ? row.file
                        : source == Source::GzipFile ? gzipOf(row.file)
                                                     : zstdOf(row.file);
    const std::string path = tempPath();
    writeFile(path, bytes);
    std::optional<StdinPipe> pipe;
    if (source == Source::ZstdStdin) pipe.emplace(bytes);
    auto opened = CaptureReader::open(source == Source::ZstdStdin ? "-" : path);
    ASSERT_TRUE(opened) << opened.error().text();
    CaptureReader& reader = **opened;
    RecordMerge merge(reader, row.limits);
    std::vector<Delivered> got;
    CaptureRecord record;
    Result<bool> next;
    while ((next = row.merged ? merge.next(record) : reader.next(record)) && *next) {
      got.push_back({record.frame, record.interface, record.link_type, record.time_ns});
      EXPECT_EQ(record.link, linkTypeFromDlt(record.link_type));
      ASSERT_EQ(record.captured, 60u);
      for (std::size_t i = 0; i < record.captured; ++i) {
        ASSERT_EQ(record.data[i], record.frame) << "frame " << record.frame << " byte " << i;
      }
    }
    EXPECT_EQ(got, row.want);
    if (row.error == nullptr) {
      EXPECT_TRUE(next) << next.error().text();
    } else {
      ASSERT_FALSE(next);
      EXPECT_EQ(next.error().path, source == Source::ZstdStdin ? "standard input" : path);
      EXPECT_EQ(next.error().frame, *row.error_frame);
      EXPECT_NE(next.error().text().find(row.error), std::string::npos) << next.error().text();
    }
    std::remove(path.c_str());
  }
}

INSTANTIATE_TEST_SUITE_P(Rows, ReaderInterfaces, ::testing::ValuesIn(interfacesRows()),
                         test::rowName<InterfacesRow>);

}  // namespace
}  // namespace ncservo
