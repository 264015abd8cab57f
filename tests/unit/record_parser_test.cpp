// RecordParser (record_parser.hpp): pcap and pcapng records read in place, one row per capture
// built here byte by byte; rows where it must fail (with libpcap's words) and rows where it must
// not (docs/protocol.md §8).
#include "ncservo/capture/record_parser.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "capture_builder.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

using test::Bytes;
using test::PcapFile;
using test::PcapngFile;

constexpr std::uint32_t kMicro = 0xA1B2C3D4, kNano = 0xA1B23C4D;

struct Want {
  std::int64_t time_ns;
  std::size_t captured;
  std::size_t original;
  std::uint32_t interface = 0;  // in the file, across its sections
  int link_type = 1;
};

struct ParserRow {
  const char* name;
  Bytes file;
  RecordFormat format;
  std::vector<Want> records;              // what it reads before it ends or fails
  const char* error;                      // nullptr: it ends cleanly
  std::vector<std::uint64_t> drops = {};  // isb_ifdrop of each statistics block handed over
};

RecordFormat pcapFormat(bool big, bool nano, std::uint32_t snapshot = 65535, int minor = 4) {
  RecordFormat f;
  f.big_endian = big;
  f.dlt = 1;
  f.snapshot = snapshot;
  f.version_minor = minor;
  f.nanoseconds = nano;
  return f;
}
RecordFormat pcapngFormat(bool big, std::uint32_t snapshot = 65535) {
  RecordFormat f;
  f.pcapng = true;
  f.big_endian = big;
  f.dlt = 1;
  f.snapshot = snapshot;
  return f;
}

constexpr std::int64_t kSecond = 1000000000;

std::vector<ParserRow> rows() {
  std::vector<ParserRow> r;
  // pcap: must not fail.
  r.push_back({"pcap_microseconds",
               PcapFile(false, kMicro).record(10, 250, 60, 60, 60).record(11, 0, 70, 80, 70).w.out,
               pcapFormat(false, false),
               {{10 * kSecond + 250000, 60, 60}, {11 * kSecond, 70, 80}},
               nullptr});
  r.push_back({"pcap_big_endian_nanosecond_magic",
               PcapFile(true, kNano).record(10, 123456789, 64, 64, 64).w.out,
               pcapFormat(true, true),
               {{10 * kSecond + 123456789, 64, 64}},
               nullptr});
  r.push_back({"pcap_longer_than_snap_length_is_cut_to_it",
               PcapFile(false, kMicro, 4, 64).record(1, 0, 100, 100, 100).w.out,
               pcapFormat(false, false, 64),
               {{kSecond, 64, 100}},
               nullptr});
  r.push_back({"pcap_version_2_2_lengths_other_way_round",
               PcapFile(false, kMicro, 2).record(1, 0, 90, 60, 60).w.out,
               pcapFormat(false, false, 65535, 2),
               {{kSecond, 60, 90}},
               nullptr});
  r.push_back({"pcap_negative_seconds_clamped_to_zero",
               PcapFile(false, kMicro).record(0x80000000u, 5, 60, 60, 60).w.out,
               pcapFormat(false, false),
               {{5000, 60, 60}},
               nullptr});
  r.push_back(
      {"pcap_header_only", PcapFile(false, kMicro).w.out, pcapFormat(false, false), {}, nullptr});
  // pcap: must fail.
  r.push_back(
      {"pcap_truncated_record_header",
       PcapFile(false, kMicro).record(1, 0, 60, 60, 60).record(2, 0, 60, 60, 0).cut(7).w.out,
       pcapFormat(false, false),
       {{kSecond, 60, 60}},
       "truncated dump file; tried to read 16 header bytes, only got 9"});
  r.push_back({"pcap_length_beyond_the_file",
               PcapFile(false, kMicro).record(1, 0, 100, 100, 20).w.out,
               pcapFormat(false, false),
               {},
               "truncated dump file; tried to read 100 captured bytes, only got 20"});
  r.push_back({"pcap_absurd_captured_length",
               PcapFile(false, kMicro).record(1, 0, 0xFFFFFFF0u, 60, 60).w.out,
               pcapFormat(false, false),
               {},
               "invalid packet capture length 4294967280, bigger than snaplen of 65535"});
  r.push_back({"pcap_cut_beyond_snap_length",
               PcapFile(false, kMicro, 4, 64).record(1, 0, 100, 100, 80).w.out,
               pcapFormat(false, false, 64),
               {},
               "truncated dump file; tried to read 100 captured bytes, only got 80"});

  // pcapng: must not fail.
  r.push_back({"pcapng_enhanced_packets_microseconds",
               PcapngFile(false).interface().enhanced(0, 1500000, 60, 60, 60).w.out,
               pcapngFormat(false),
               {{kSecond + 500000000, 60, 60}},
               nullptr});
  r.push_back(
      {"pcapng_big_endian_section_nanoseconds_and_offset",
       PcapngFile(true).interface(1, 65535, 9, 100).enhanced(0, 2000000007, 61, 61, 61).w.out,
       pcapngFormat(true),
       {{102 * kSecond + 7, 61, 61}},
       nullptr});
  r.push_back(
      {"pcapng_binary_resolution",
       PcapngFile(false).interface(1, 65535, 0x80 | 10).enhanced(0, 1024 + 512, 60, 60, 60).w.out,
       pcapngFormat(false),
       {{kSecond + 500000000, 60, 60}},
       nullptr});
  r.push_back({"pcapng_simple_packet_cut_to_snap_length",
               PcapngFile(false).interface(1, 64).simple(100, 64).w.out,
               pcapngFormat(false, 64),
               {{0, 64, 100}},
               nullptr});
  r.push_back({"pcapng_obsolete_packet_block",
               PcapngFile(false).interface().obsolete(0, 3000000, 60, 60).w.out,
               pcapngFormat(false),
               {{3 * kSecond, 60, 60}},
               nullptr});
  r.push_back(
      {"pcapng_unknown_blocks_passed_over",
       PcapngFile(false).interface().block(0x0BAD, Bytes(10, 1)).enhanced(0, 0, 60, 60, 60).w.out,
       pcapngFormat(false),
       {{0, 60, 60}},
       nullptr});
  r.push_back({"pcapng_statistics_drop_counts",
               PcapngFile(false)
                   .interface()
                   .enhanced(0, 0, 60, 60, 60)
                   .statistics(12, 3)
                   .enhanced(0, 0, 60, 60, 60)
                   .statistics(15, 4)
                   .w.out,
               pcapngFormat(false),
               {{0, 60, 60}, {0, 60, 60}},
               nullptr,
               {12, 15}});
  r.push_back(
      {"pcapng_oversized_statistics_block_passed_over",
       PcapngFile(false).interface().block(5, Bytes(70000, 0)).enhanced(0, 0, 60, 60, 60).w.out,
       pcapngFormat(false),
       {{0, 60, 60}},
       nullptr});
  r.push_back({"pcapng_new_section_new_interfaces",
               PcapngFile(false)
                   .interface()
                   .enhanced(0, 0, 60, 60, 60)
                   .section()
                   .interface(1, 65535, 9)
                   .enhanced(0, 5, 60, 60, 60)
                   .w.out,
               pcapngFormat(false),
               {{0, 60, 60}, {5, 60, 60, 1}},
               nullptr});
  // Interfaces of their own (docs/protocol.md §8), as dumpcap -i eth0 -i any writes them.
  r.push_back({"pcapng_interfaces_of_their_own_link_type_resolution_and_offset",
               PcapngFile(false)
                   .interface(1, 65535, 6)
                   .interface(113, 65535, 9, 100)
                   .enhanced(0, 1500000, 60, 60, 60)
                   .enhanced(1, 2000000007, 44, 44, 44)
                   .enhanced(0, 1500001, 61, 61, 61)
                   .w.out,
               pcapngFormat(false),
               {{kSecond + 500000000, 60, 60},
                {102 * kSecond + 7, 44, 44, 1, 113},
                {kSecond + 500001000, 61, 61}},
               nullptr});
  r.push_back({"pcapng_big_endian_interfaces_of_their_own",
               PcapngFile(true)
                   .interface(276, 65535, 9, -1)
                   .interface(1)
                   .enhanced(1, 3000000, 60, 60, 60)
                   .enhanced(0, 4000000005, 50, 50, 50)
                   .w.out,
               pcapngFormat(true),
               {{3 * kSecond, 60, 60, 1, 1}, {3 * kSecond + 5, 50, 50, 0, 276}},
               nullptr});
  r.push_back({"pcapng_interfaces_of_their_own_snapshot_length",
               PcapngFile(false)
                   .interface(1, 64)
                   .interface(113, 1000)
                   .enhanced(1, 0, 600, 600, 600)
                   .simple(100, 64)
                   .w.out,
               pcapngFormat(false, 64),
               {{0, 600, 600, 1, 113}, {0, 64, 100}},
               nullptr});
  // A link type the walker does not know: its records are records, never held to a snapshot
  // length (only to their block).
  r.push_back({"pcapng_unknown_link_type_records_read",
               PcapngFile(false)
                   .interface(1, 64)
                   .interface(147, 64)
                   .enhanced(1, 0, 200, 200, 200)
                   .enhanced(0, 0, 60, 60, 60)
                   .w.out,
               pcapngFormat(false, 64),
               {{0, 200, 200, 1, 147}, {0, 60, 60}},
               nullptr});
  r.push_back({"pcapng_second_section_numbers_its_interfaces_on",
               PcapngFile(false)
                   .interface(1)
                   .interface(113)
                   .enhanced(1, 0, 60, 60, 60)
                   .section()
                   .interface(276)
                   .enhanced(0, 7, 60, 60, 60)
                   .w.out,
               pcapngFormat(false),
               {{0, 60, 60, 1, 113}, {7000, 60, 60, 2, 276}},
               nullptr});
  // pcapng: must fail.
  r.push_back({"pcapng_block_length_not_a_multiple_of_4",
               PcapngFile(false).interface().block(6, Bytes(24, 0), 38).w.out,
               pcapngFormat(false),
               {},
               "block in pcapng dump file has a length of 38 that is not a multiple of 4"});
  r.push_back({"pcapng_block_shorter_than_its_frame",
               PcapngFile(false).interface().block(6, Bytes(24, 0), 8).w.out,
               pcapngFormat(false),
               {},
               "block in pcapng dump file has a length of 8 < 12"});
  r.push_back({"pcapng_block_larger_than_allowed",
               PcapngFile(false).interface().block(6, Bytes(24, 0), 0x7FFFFFF0).w.out,
               pcapngFormat(false),
               {},
               "pcapng block size 2147483632 > maximum 16777216"});
  r.push_back({"pcapng_trailer_differs",
               PcapngFile(false).interface().block(6, Bytes(24, 0), std::nullopt, 40).w.out,
               pcapngFormat(false),
               {},
               "block total length in header and trailer don't match"});
  r.push_back({"pcapng_truncated_last_block",
               PcapngFile(false)
                   .interface()
                   .enhanced(0, 0, 60, 60, 60)
                   .enhanced(0, 0, 60, 60, 60)
                   .cut(10)
                   .w.out,
               pcapngFormat(false),
               {{0, 60, 60}},
               "truncated pcapng dump file; tried to read 84 bytes, only got 74"});
  r.push_back({"pcapng_truncated_block_header",
               PcapngFile(false).interface().raw({6, 0, 0}).w.out,
               pcapngFormat(false),
               {},
               "truncated pcapng dump file; tried to read 8 bytes, only got 3"});
  r.push_back({"pcapng_captured_length_beyond_its_block",
               PcapngFile(false).interface().enhanced(0, 0, 200, 200, 60).w.out,
               pcapngFormat(false),
               {},
               "block of type 6 in pcapng dump file is too short"});
  r.push_back({"pcapng_interface_out_of_range",
               PcapngFile(false).interface().enhanced(3, 0, 60, 60, 60).w.out,
               pcapngFormat(false),
               {},
               "a packet arrived on interface 3, but there's no Interface Description Block for "
               "that interface"});
  r.push_back({"pcapng_section_of_the_other_byte_order",
               PcapngFile(false).interface().section(0x4D3C2B1A).w.out,
               pcapngFormat(false),
               {},
               "the file has sections with different byte orders"});
  r.push_back({"pcapng_second_section_forgets_the_first_ones_interfaces",
               PcapngFile(false)
                   .interface(1)
                   .interface(113)
                   .section()
                   .interface(1)
                   .enhanced(1, 0, 60, 60, 60)
                   .w.out,
               pcapngFormat(false),
               {},
               "a packet arrived on interface 1, but there's no Interface Description Block for "
               "that interface"});
  r.push_back(
      {"pcapng_interface_beyond_its_snapshot_length",
       PcapngFile(false).interface(1).interface(113, 100).enhanced(1, 0, 101, 101, 101).w.out,
       pcapngFormat(false),
       {},
       "invalid packet capture length 101, bigger than snaplen of 100"});
  r.push_back({"pcapng_more_interfaces_than_a_section_may_describe",
               [] {
                 PcapngFile file(false);
                 for (std::size_t i = 0; i <= RecordParser::kMaxSectionInterfaces; ++i) {
                   file.interface();
                 }
                 return file.w.out;
               }(),
               pcapngFormat(false),
               {},
               "a section describes more than 65536 interfaces"});
  r.push_back({"pcapng_resolution_too_fine",
               PcapngFile(false).interface(1, 65535, 20).w.out,
               pcapngFormat(false),
               {},
               "Interface Description Block if_tsresol option resolution 10^-20 is too high"});
  // Statistics after the last record, then damage: not counted (as the libpcap path).
  r.push_back(
      {"pcapng_statistics_before_damage_not_counted",
       PcapngFile(false).interface().enhanced(0, 0, 60, 60, 60).statistics(9, 9).raw({1, 2}).w.out,
       pcapngFormat(false),
       {{0, 60, 60}},
       "truncated pcapng dump file; tried to read 8 bytes, only got 2"});
  return r;
}

class RecordParserRows : public ::testing::TestWithParam<ParserRow> {};

TEST_P(RecordParserRows, ReadsWhatIsThereAndSaysWhatIsNot) {
  const ParserRow& row = GetParam();
  MemoryBytes bytes(row.file.data(), row.file.size());
  std::vector<std::uint64_t> drops;
  RecordParser parser(bytes, row.format,
                      [&](const std::uint8_t* block, std::size_t length, bool big) {
                        ASSERT_GE(length, 32u);
                        std::uint64_t value = 0;
                        for (int i = 0; i < 8; ++i)
                          value |= std::uint64_t{block[24 + (big ? 7 - i : i)]} << (8 * i);
                        drops.push_back(value);
                      });
  std::vector<Want> got;
  CaptureRecord record;
  RecordParser::Outcome outcome;
  while ((outcome = parser.next(record)) == RecordParser::Outcome::Record) {
    ASSERT_NE(record.data, nullptr);
    ASSERT_TRUE(record.stored);
    // The bytes handed over lie inside the capture.
    ASSERT_GE(record.data, row.file.data());
    ASSERT_LE(record.data + record.captured, row.file.data() + row.file.size());
    got.push_back(
        {record.time_ns, record.captured, record.original, record.interface, record.link_type});
    EXPECT_EQ(record.link, linkTypeFromDlt(record.link_type)) << "record " << got.size();
  }
  ASSERT_EQ(got.size(), row.records.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].time_ns, row.records[i].time_ns) << "record " << i + 1;
    EXPECT_EQ(got[i].captured, row.records[i].captured) << "record " << i + 1;
    EXPECT_EQ(got[i].original, row.records[i].original) << "record " << i + 1;
    EXPECT_EQ(got[i].interface, row.records[i].interface) << "record " << i + 1;
    EXPECT_EQ(got[i].link_type, row.records[i].link_type) << "record " << i + 1;
  }
  if (row.error == nullptr) {
    EXPECT_EQ(outcome, RecordParser::Outcome::End) << parser.error();
  } else {
    ASSERT_EQ(outcome, RecordParser::Outcome::Failed);
    EXPECT_EQ(parser.error(), row.error);
  }
  EXPECT_EQ(drops, row.drops);
}

INSTANTIATE_TEST_SUITE_P(Rows, RecordParserRows, ::testing::ValuesIn(rows()),
                         test::rowName<ParserRow>);

}  // namespace
}  // namespace ncservo
