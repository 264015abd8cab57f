// The EtherCAT frame walker (ethercat.hpp, docs/protocol.md §8) on frames built byte by byte.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo {
namespace {

using test::Bytes;
using test::Dg;
using test::FrameBuilder;
using test::kChainOffset;
using test::kEcatOffset;
using test::Link;
using test::physical;
using test::walk;

Bytes counting(std::size_t size, std::uint8_t first = 0) {
  Bytes out(size);
  for (std::size_t i = 0; i < size; ++i) out[i] = static_cast<std::uint8_t>(first + i);
  return out;
}

// Checks that the walked datagrams are `expected`, laid out one after the other from `chain`
// (and, unless `partial_may_follow`, that there are no others).
void expectChain(const test::Walked& w, const std::vector<Dg>& expected, std::size_t chain,
                 bool partial_may_follow = false) {
  if (partial_may_follow) {
    ASSERT_GE(w.frame->count, expected.size());
    ASSERT_LE(w.frame->count, expected.size() + 1);
  } else {
    ASSERT_EQ(w.frame->count, expected.size());
  }
  std::size_t pos = chain;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    SCOPED_TRACE("datagram " + std::to_string(i));
    const Datagram& dg = w.dg(i);
    const Dg& e = expected[i];
    EXPECT_EQ(dg.command, e.cmd);
    EXPECT_EQ(dg.index, e.index);
    EXPECT_EQ(dg.address, e.address);
    EXPECT_EQ(dg.length, e.data.size());
    EXPECT_EQ(dg.irq, e.irq);
    EXPECT_EQ(dg.header_offset, pos);
    EXPECT_EQ(dg.data_offset, pos + ecat::kDatagramHeaderSize);
    EXPECT_EQ(dg.data_captured, e.data.size());
    EXPECT_TRUE(dg.has_wkc);
    EXPECT_EQ(dg.wkc, e.wkc);
    EXPECT_TRUE(dg.complete());
    EXPECT_EQ(Bytes(w.storage.get() + dg.data_offset, w.storage.get() + dg.data_offset + dg.length),
              e.data);
    pos += ecat::kDatagramHeaderSize + e.data.size() + ecat::kWkcSize;
  }
  EXPECT_EQ(w.frame->chain_length, pos - chain);
}

TEST(Walker, SingleDatagram) {
  Dg lrw{ecat::kLrw, 0x42, 0x00010000, counting(20), 3};
  lrw.irq = 0x1234;
  const test::Walked w = walk(FrameBuilder().add(lrw).bytes());
  EXPECT_EQ(w.frame->status, WalkStatus::Ok);
  EXPECT_EQ(w.frame->ecat_offset, kEcatOffset);
  EXPECT_EQ(w.frame->header_length, 10 + 20 + 2);
  expectChain(w, {lrw}, kChainOffset);
  EXPECT_FALSE(w.dg(0).circulating);
  EXPECT_TRUE(w.frame->anyWkcAboveZero());
}

struct ChainCase {
  const char* name;
  std::vector<Dg> datagrams;
};
std::vector<ChainCase> chainCases() {
  return {
      {"startup mix",
       {{ecat::kFprd, 1, physical(0x03E9, 0x0130), counting(2), 1},
        {ecat::kLrw, 2, 0x00010000, counting(100, 7), 6},
        {ecat::kBrd, 3, physical(0, 0x0130), counting(2, 9), 2}}},
      {"LWR, LRD, FPWR, APRD",
       {{ecat::kLwr, 0, 0x00010000, counting(20), 2},
        {ecat::kLrd, 1, 0x00010014, counting(80), 2},
        {ecat::kFpwr, 2, physical(0x03EA, 0x0120), counting(2), 1},
        {ecat::kAprd, 3, physical(0xFFFF, 0x0130), counting(2), 1}}},
      {"zero-length datagrams between data",
       {{ecat::kNop, 0, 0, {}, 0},
        {ecat::kLrw, 1, 0x1000, counting(50), 0},
        {ecat::kNop, 2, 0, {}, 0},
        {ecat::kBrd, 3, physical(0, 0x0910), counting(8), 5},
        {ecat::kNop, 4, 0, {}, 0}}},
      {"ten datagrams",
       std::vector<Dg>(10, Dg{ecat::kFprd, 9, physical(0x1001, 0x0130), counting(2), 1})},
  };
}

TEST(Walker, MultiDatagramChainsFollowTheMoreBit) {
  for (const ChainCase& c : chainCases()) {
    SCOPED_TRACE(c.name);
    FrameBuilder builder;
    for (const Dg& dg : c.datagrams) builder.add(dg);
    const test::Walked w = walk(builder.bytes());
    EXPECT_EQ(w.frame->status, WalkStatus::Ok);
    expectChain(w, c.datagrams, kChainOffset);
  }
}

// How the EtherCAT frame is carried: one row per encapsulation, with where its header sits.
struct EncapCase {
  const char* name;
  FrameBuilder builder;
  Link link;
  WalkStatus status;
  std::size_t ecat_offset;
};
std::vector<EncapCase> encapCases() {
  const Dg dg{ecat::kLrw, 5, 0x00020000, counting(50), 3};
  auto base = [&dg] { return FrameBuilder().add(dg); };
  const std::size_t udp = 14 + 20 + 8;
  return {
      {"Ethernet II", base(), Link::Ethernet, WalkStatus::Ok, 14},
      {"802.1Q", base().vlan(0x8100), Link::Ethernet, WalkStatus::Ok, 18},
      {"QinQ 802.1ad", base().vlan(0x88A8).vlan(0x8100), Link::Ethernet, WalkStatus::Ok, 22},
      {"QinQ 0x9100", base().vlan(0x9100), Link::Ethernet, WalkStatus::Ok, 18},
      {"three tags", base().vlan(0x88A8).vlan(0x8100).vlan(0x8100), Link::Ethernet, WalkStatus::Ok,
       26},
      {"UDP to 34980", base().udp(), Link::Ethernet, WalkStatus::Ok, udp},
      {"UDP behind 802.1Q", base().vlan().udp(), Link::Ethernet, WalkStatus::Ok, udp + 4},
      {"UDP first fragment (MF set)", base().udp(ecat::kUdpPort, 0x2000), Link::Ethernet,
       WalkStatus::Ok, udp},
      {"UDP to another port", base().udp(34981), Link::Ethernet, WalkStatus::NotEtherCat, 0},
      {"UDP to port 0x88A5", base().udp(0x88A5), Link::Ethernet, WalkStatus::NotEtherCat, 0},
      {"IPv4 fragment with offset", base().udp(ecat::kUdpPort, 0x0001), Link::Ethernet,
       WalkStatus::NotEtherCat, 0},
      {"IPv4 last fragment with offset", base().udp(ecat::kUdpPort, 0x00B9), Link::Ethernet,
       WalkStatus::NotEtherCat, 0},
      {"ARP", base().etherType(0x0806), Link::Ethernet, WalkStatus::NotEtherCat, 0},
      {"IPv6 without UDP", base().etherType(0x86DD), Link::Ethernet, WalkStatus::NotEtherCat, 0},
      {"802.1Q then ARP", base().vlan().etherType(0x0806), Link::Ethernet, WalkStatus::NotEtherCat,
       0},
      {"Linux SLL", base().link(Link::Sll), Link::Sll, WalkStatus::Ok, 16},
      {"Linux SLL with 802.1Q", base().link(Link::Sll).vlan(), Link::Sll, WalkStatus::Ok, 20},
      {"Linux SLL2", base().link(Link::Sll2), Link::Sll2, WalkStatus::Ok, 20},
      {"Linux SLL2, UDP", base().link(Link::Sll2).udp(), Link::Sll2, WalkStatus::Ok, 20 + 28},
      {"Linux SLL, ARP", base().link(Link::Sll).etherType(0x0806), Link::Sll,
       WalkStatus::NotEtherCat, 0},
      {"frame type 4 (network variables)", base().frameType(4), Link::Ethernet,
       WalkStatus::NotDatagrams, 14},
      {"frame type 0", base().frameType(0), Link::Ethernet, WalkStatus::NotDatagrams, 14},
      {"frame type 5 over UDP", base().udp().frameType(5), Link::Ethernet, WalkStatus::NotDatagrams,
       udp},
      {"frame type 15 behind 802.1Q", base().vlan().frameType(15), Link::Ethernet,
       WalkStatus::NotDatagrams, 18},
  };
}

TEST(Walker, Encapsulations) {
  const Dg dg{ecat::kLrw, 5, 0x00020000, counting(50), 3};
  for (const EncapCase& c : encapCases()) {
    SCOPED_TRACE(c.name);
    const test::Walked w = walk(c.builder.bytes(), c.link);
    EXPECT_EQ(w.frame->status, c.status);
    if (c.status == WalkStatus::NotEtherCat) {
      EXPECT_EQ(w.frame->count, 0u);
      continue;
    }
    EXPECT_EQ(w.frame->ecat_offset, c.ecat_offset);
    if (c.status == WalkStatus::NotDatagrams) {
      EXPECT_EQ(w.frame->count, 0u);
      continue;
    }
    expectChain(w, {dg}, c.ecat_offset + ecat::kFrameHeaderSize);
  }
}

TEST(Walker, UnsupportedLinkTypeIsNotEtherCat) {
  const Bytes bytes = FrameBuilder().add(Dg{ecat::kLrw, 0, 0, counting(10), 0}).bytes();
  EcatFrame frame;
  walkPacket(LinkType::Unsupported, ByteReader(bytes.data(), bytes.size()), frame);
  EXPECT_EQ(frame.status, WalkStatus::NotEtherCat);
  EXPECT_EQ(frame.count, 0u);
}

TEST(Walker, LinkTypesFromDlt) {
  EXPECT_EQ(linkTypeFromDlt(1), LinkType::Ethernet);
  EXPECT_EQ(linkTypeFromDlt(113), LinkType::LinuxSll);
  EXPECT_EQ(linkTypeFromDlt(276), LinkType::LinuxSll2);
  EXPECT_EQ(linkTypeFromDlt(0), LinkType::Unsupported);
  EXPECT_EQ(linkTypeFromDlt(105), LinkType::Unsupported);
}

// Frame sizes and header lengths that differ from the chain: one row each.
struct SizeCase {
  const char* name;
  FrameBuilder builder;
  std::size_t header_length;
};
std::vector<SizeCase> sizeCases() {
  const Dg small{ecat::kFprd, 1, physical(0x03E9, 0x0130), counting(2), 1};
  return {
      {"under 60 bytes, no padding", FrameBuilder().add(small), 14},
      {"padded to 60 bytes", FrameBuilder().add(small).padTo(60), 14},
      {"padded to 1514 bytes", FrameBuilder().add(small).padTo(1514), 14},
      {"header length larger than the chain", FrameBuilder().add(small).headerLength(1000), 1000},
      {"header length 2047, padded", FrameBuilder().add(small).headerLength(2047).padTo(64), 2047},
      {"header length smaller than the chain", FrameBuilder().add(small).headerLength(4), 4},
  };
}

TEST(Walker, FrameSizeAndHeaderLengthDoNotBoundTheChain) {
  const Dg small{ecat::kFprd, 1, physical(0x03E9, 0x0130), counting(2), 1};
  for (const SizeCase& c : sizeCases()) {
    SCOPED_TRACE(c.name);
    const test::Walked w = walk(c.builder.bytes());
    EXPECT_EQ(w.frame->status, WalkStatus::Ok);
    EXPECT_EQ(w.frame->header_length, c.header_length);
    expectChain(w, {small}, kChainOffset);
  }
}

TEST(Walker, PaddingThatLooksLikeDatagramsIsIgnored) {
  const Dg first{ecat::kLrw, 1, 0x1000, counting(10), 3};
  Bytes bytes = FrameBuilder().add(first).bytes();
  // A whole plausible datagram after the chain: the more bit of the first one is clear.
  const Bytes more = FrameBuilder().add(Dg{ecat::kLrd, 2, 0x2000, counting(4), 1}).ecat();
  bytes.insert(bytes.end(), more.begin() + 2, more.end());
  const test::Walked w = walk(bytes);
  EXPECT_EQ(w.frame->status, WalkStatus::Ok);
  expectChain(w, {first}, kChainOffset);
}

TEST(Walker, ClearMoreBitStopsTheWalkEvenIfDatagramsFollow) {
  std::vector<Dg> dgs{{ecat::kLrw, 1, 0x1000, counting(10), 3},
                      {ecat::kLrd, 2, 0x2000, counting(4), 1},
                      {ecat::kLwr, 3, 0x3000, counting(4), 1}};
  dgs[1].more = false;  // the third is still in the bytes
  FrameBuilder builder;
  for (const Dg& dg : dgs) builder.add(dg);
  const test::Walked w = walk(builder.bytes());
  EXPECT_EQ(w.frame->status, WalkStatus::Ok);
  expectChain(w, {dgs[0], dgs[1]}, kChainOffset);
}

TEST(Walker, MoreBitOnTheLastDatagramRunsIntoTheEndAsTruncated) {
  Dg last{ecat::kLrw, 1, 0x1000, counting(10), 3};
  last.more = true;
  const Bytes bytes = FrameBuilder().add(last).bytes();
  const test::Walked w = walk(bytes);
  EXPECT_EQ(w.frame->status, WalkStatus::Truncated);
  EXPECT_EQ(w.frame->truncated_at, bytes.size());
  ASSERT_EQ(w.frame->count, 1u);
  EXPECT_TRUE(w.dg(0).complete());
}

TEST(Walker, RuntFramesAreNotEtherCat) {
  const Bytes ethernet = FrameBuilder().add(Dg{ecat::kLrw, 0, 0, counting(10), 0}).bytes();
  for (std::size_t size = 0; size < 14; ++size) {
    SCOPED_TRACE("Ethernet, " + std::to_string(size) + " bytes");
    const test::Walked w = walk(ethernet, size);
    EXPECT_EQ(w.frame->status, WalkStatus::NotEtherCat);
    EXPECT_EQ(w.frame->count, 0u);
  }
  const Bytes sll =
      FrameBuilder().link(Link::Sll).add(Dg{ecat::kLrw, 0, 0, counting(10), 0}).bytes();
  for (std::size_t size = 0; size < 16; ++size) {
    SCOPED_TRACE("SLL, " + std::to_string(size) + " bytes");
    const test::Walked w = walk(sll, size, Link::Sll);
    EXPECT_EQ(w.frame->status, WalkStatus::NotEtherCat);
    EXPECT_EQ(w.frame->count, 0u);
  }
}

// Cuts a 3-datagram frame at every length short of the whole: the walker stays inside the
// captured bytes (each cut is a heap buffer of exactly that size), says Truncated (or
// NotEtherCat before the EtherType), and reports the datagrams wholly before the cut intact.
void expectEveryCutIsClean(const Bytes& full, Link link, std::size_t ecat_offset,
                           const std::vector<Dg>& dgs) {
  std::vector<std::size_t> ends;  // end of each datagram (after its WKC)
  std::size_t pos = ecat_offset + ecat::kFrameHeaderSize;
  for (const Dg& dg : dgs) ends.push_back(pos += ecat::kDatagramHeaderSize + dg.data.size() + 2);
  ASSERT_EQ(ends.back(), full.size());
  for (std::size_t cut = 0; cut < full.size(); ++cut) {
    SCOPED_TRACE("cut at " + std::to_string(cut));
    const test::Walked w = walk(full, cut, link);
    if (cut < ecat_offset) {
      EXPECT_EQ(w.frame->status, WalkStatus::NotEtherCat);
      EXPECT_EQ(w.frame->count, 0u);
      continue;
    }
    ASSERT_EQ(w.frame->status, WalkStatus::Truncated);
    EXPECT_EQ(w.frame->truncated_at, cut);
    std::size_t complete = 0;
    while (complete < ends.size() && ends[complete] <= cut) ++complete;
    ASSERT_GE(w.frame->count, complete);
    ASSERT_LE(w.frame->count, complete + 1);
    expectChain(w, std::vector<Dg>(dgs.begin(), dgs.begin() + complete),
                ecat_offset + ecat::kFrameHeaderSize, true);
    if (w.frame->count > complete) {
      // The partial datagram: its header was captured, its data or WKC was not.
      const Datagram& partial = w.dg(complete);
      EXPECT_FALSE(partial.complete());
      EXPECT_FALSE(partial.has_wkc);
      EXPECT_EQ(partial.command, dgs[complete].cmd);
      EXPECT_EQ(partial.length, dgs[complete].data.size());
      EXPECT_LE(partial.data_offset + partial.data_captured, cut);
      EXPECT_LE(partial.data_captured, partial.length);
    }
  }
}

TEST(Walker, FrameCutAtEveryByteOffset) {
  const std::vector<Dg> dgs{{ecat::kFprd, 1, physical(0x03E9, 0x0130), counting(2), 1},
                            {ecat::kLrw, 2, 0x00010000, counting(100, 3), 6},
                            {ecat::kBrd, 3, physical(0, 0x0130), counting(2, 5), 2}};
  FrameBuilder builder;
  for (const Dg& dg : dgs) builder.add(dg);
  expectEveryCutIsClean(builder.bytes(), Link::Ethernet, 14, dgs);
}

TEST(Walker, FrameCutAtEveryByteOffsetBehindVlanAndUdp) {
  const std::vector<Dg> dgs{{ecat::kLwr, 1, 0x1000, counting(30), 3},
                            {ecat::kLrd, 2, 0x101E, counting(120), 3},
                            {ecat::kNop, 3, 0, {}, 0}};
  FrameBuilder builder;
  for (const Dg& dg : dgs) builder.add(dg);
  builder.vlan(0x88A8).vlan(0x8100).udp();
  // Cuts inside the IP/UDP headers are not EtherCAT yet.
  const Bytes full = builder.bytes();
  const std::size_t ecat_offset = 22 + 20 + 8;
  for (std::size_t cut = 0; cut < ecat_offset; ++cut) {
    SCOPED_TRACE("cut at " + std::to_string(cut));
    const test::Walked w = walk(full, cut);
    EXPECT_NE(w.frame->status, WalkStatus::Ok);
    EXPECT_EQ(w.frame->count, 0u);
  }
  // From the EtherCAT header on, the same guarantees as untagged.
  std::vector<std::size_t> ends;
  std::size_t pos = ecat_offset + 2;
  for (const Dg& dg : dgs) ends.push_back(pos += 12 + dg.data.size());
  for (std::size_t cut = ecat_offset; cut < full.size(); ++cut) {
    SCOPED_TRACE("cut at " + std::to_string(cut));
    const test::Walked w = walk(full, cut);
    ASSERT_EQ(w.frame->status, WalkStatus::Truncated);
    std::size_t complete = 0;
    while (complete < ends.size() && ends[complete] <= cut) ++complete;
    ASSERT_GE(w.frame->count, complete);
    expectChain(w, std::vector<Dg>(dgs.begin(), dgs.begin() + complete), ecat_offset + 2, true);
  }
}

// Pairing a master's frame with its returned copy (docs/protocol.md §8): one row per difference.
struct SameCase {
  const char* name;
  std::vector<Dg> a;
  std::vector<Dg> b;
  bool same;
};
std::vector<SameCase> sameCases() {
  const Dg lrw{ecat::kLrw, 1, 0x00010000, Bytes(50, 0), 0};
  const Dg brd{ecat::kBrd, 2, physical(0, 0x0130), Bytes(2, 0), 0};
  auto with = [](Dg dg, auto change) {
    change(dg);
    return dg;
  };
  return {
      {"identical", {lrw, brd}, {lrw, brd}, true},
      {"different WKC and data",
       {lrw, brd},
       {with(lrw,
             [](Dg& d) {
               d.wkc = 3;
               d.data = counting(50);
             }),
        with(brd,
             [](Dg& d) {
               d.wkc = 2;
               d.data = {0x08, 0x00};
             })},
       true},
      {"APRD whose ADP was incremented",
       {Dg{ecat::kAprd, 1, physical(0xFFFE, 0x0130), Bytes(2, 0), 0}},
       {Dg{ecat::kAprd, 1, physical(0x0001, 0x0130), Bytes(2, 0), 1}},
       true},
      {"BRD whose ADP was incremented",
       {brd},
       {with(brd, [](Dg& d) { d.address = physical(5, 0x0130); })},
       true},
      {"LRW with another logical address",
       {lrw},
       {with(lrw, [](Dg& d) { d.address = 0x00010050; })},
       false},
      {"FPRD to another station",
       {Dg{ecat::kFprd, 1, physical(0x03E9, 0x0130), Bytes(2, 0), 0}},
       {Dg{ecat::kFprd, 1, physical(0x03EA, 0x0130), Bytes(2, 0), 0}},
       false},
      {"APRD to another register",
       {Dg{ecat::kAprd, 1, physical(0, 0x0130), Bytes(2, 0), 0}},
       {Dg{ecat::kAprd, 1, physical(0, 0x0134), Bytes(2, 0), 0}},
       true},  // the address of auto-increment commands is not compared at all
      {"another command", {lrw}, {with(lrw, [](Dg& d) { d.cmd = ecat::kLrd; })}, false},
      {"another index", {lrw}, {with(lrw, [](Dg& d) { d.index = 9; })}, false},
      {"another length", {lrw}, {with(lrw, [](Dg& d) { d.data = Bytes(60, 0); })}, false},
      {"one datagram more", {lrw}, {lrw, brd}, false},
      {"order swapped", {lrw, brd}, {brd, lrw}, false},
  };
}

TEST(Walker, SameDatagramList) {
  for (const SameCase& c : sameCases()) {
    SCOPED_TRACE(c.name);
    FrameBuilder a, b;
    for (const Dg& dg : c.a) a.add(dg);
    for (const Dg& dg : c.b) b.add(dg);
    const test::Walked wa = walk(a.bytes());
    const test::Walked wb = walk(b.bytes());
    ASSERT_EQ(wa.frame->status, WalkStatus::Ok);
    ASSERT_EQ(wb.frame->status, WalkStatus::Ok);
    EXPECT_EQ(wa.frame->sameDatagramList(*wb.frame), c.same);
    EXPECT_EQ(wb.frame->sameDatagramList(*wa.frame), c.same);
  }
}

TEST(Walker, AnyWkcAboveZero) {
  const Dg zero{ecat::kLrw, 1, 0x1000, Bytes(50, 0), 0};
  Dg one = zero;
  one.wkc = 1;
  EXPECT_FALSE(walk(FrameBuilder().add(zero).add(zero).bytes()).frame->anyWkcAboveZero());
  EXPECT_TRUE(walk(FrameBuilder().add(zero).add(one).bytes()).frame->anyWkcAboveZero());
}

TEST(Walker, MaxDatagramsBoundsTheLongestLegalChain) {
  // 170 zero-length datagrams: 2040 bytes of chain, the most an 11-bit length allows.
  FrameBuilder builder;
  for (int i = 0; i < 170; ++i) {
    builder.add(Dg{ecat::kNop, static_cast<std::uint8_t>(i), 0, {}, static_cast<std::uint16_t>(i)});
  }
  const Bytes bytes = builder.padTo(14 + 2044).bytes();
  ASSERT_EQ(bytes.size(), 14u + 2044);
  const test::Walked w = walk(bytes);
  EXPECT_EQ(w.frame->status, WalkStatus::Ok);
  EXPECT_EQ(w.frame->header_length, 2040);
  ASSERT_EQ(w.frame->count, 170u);
  EXPECT_LE(w.frame->count, ecat::kMaxDatagrams);
  EXPECT_EQ(w.dg(169).index, 169);
  EXPECT_EQ(w.dg(169).wkc, 169);
  EXPECT_EQ(w.dg(169).header_offset, kChainOffset + 169 * 12);
  EXPECT_EQ(w.frame->chain_length, 2040u);
}

TEST(Walker, ChainLongerThanMaxDatagramsStopsAtTheBound) {
  // A hostile frame: more datagrams than any legal chain holds, every one with the more bit.
  FrameBuilder builder;
  const std::size_t n = ecat::kMaxDatagrams + 30;
  for (std::size_t i = 0; i < n; ++i) {
    Dg dg{ecat::kNop, static_cast<std::uint8_t>(i), 0, {}, 0};
    dg.more = true;
    builder.add(dg);
  }
  const test::Walked w = walk(builder.bytes());
  EXPECT_NE(w.frame->status, WalkStatus::NotEtherCat);
  EXPECT_EQ(w.frame->count, ecat::kMaxDatagrams);
}

// ByteReader::record: one bounds check for a fixed-size record, then its fields little-endian.
struct RecordCase {
  std::size_t size;    // captured bytes
  std::size_t offset;  // where the 10-byte record starts
  bool present;
};
class ByteRecordRead : public ::testing::TestWithParam<RecordCase> {};

TEST_P(ByteRecordRead, WholeOrNothing) {
  const RecordCase c = GetParam();
  // Exactly `size` bytes on the heap, so that a read past them is caught by ASan.
  const Bytes bytes = counting(c.size, 1);
  std::unique_ptr<std::uint8_t[]> buffer(new std::uint8_t[c.size > 0 ? c.size : 1]);
  std::copy(bytes.begin(), bytes.end(), buffer.get());
  const ByteReader reader(buffer.get(), c.size);
  const auto record = reader.record<10>(c.offset);
  ASSERT_EQ(record.has_value(), c.present);
  if (!record) return;
  const auto at = [&](std::size_t i) { return std::uint64_t{bytes[c.offset + i]}; };
  EXPECT_EQ(record->u8<0>(), at(0));
  EXPECT_EQ(record->u8<9>(), at(9));
  EXPECT_EQ(record->le16<1>(), at(1) | at(2) << 8);
  EXPECT_EQ(record->le32<2>(), at(2) | at(3) << 8 | at(4) << 16 | at(5) << 24);
  EXPECT_EQ(record->le64<2>(), at(2) | at(3) << 8 | at(4) << 16 | at(5) << 24 | at(6) << 32 |
                                   at(7) << 40 | at(8) << 48 | at(9) << 56);
  // The same values as the single reads.
  EXPECT_EQ(record->le16<8>(), reader.le16(c.offset + 8));
  EXPECT_EQ(record->le32<6>(), reader.le32(c.offset + 6));
}

INSTANTIATE_TEST_SUITE_P(Walker, ByteRecordRead,
                         ::testing::Values(RecordCase{10, 0, true}, RecordCase{20, 10, true},
                                           RecordCase{20, 5, true}, RecordCase{20, 11, false},
                                           RecordCase{9, 0, false}, RecordCase{0, 0, false},
                                           RecordCase{10, SIZE_MAX - 4, false},
                                           RecordCase{10, 10, false}));

TEST(Walker, CommandNames) {
  EXPECT_STREQ(ecat::commandName(ecat::kLrw), "LRW");
  EXPECT_STREQ(ecat::commandName(ecat::kFprd), "FPRD");
  EXPECT_STREQ(ecat::commandName(ecat::kFrmw), "FRMW");
  EXPECT_STREQ(ecat::commandName(15), "unknown");
  EXPECT_STREQ(ecat::commandName(255), "unknown");
}

// docs/protocol.md §8: how each command addresses slaves and whether it reads or writes them.
struct CommandCase {
  std::uint8_t command;
  const char* name;
  bool auto_increment, configured, broadcast, logical, reads, writes;
};
const CommandCase kCommandCases[] = {
    {ecat::kNop, "NOP", false, false, false, false, false, false},
    {ecat::kAprd, "APRD", true, false, false, false, true, false},
    {ecat::kApwr, "APWR", true, false, false, false, false, true},
    {ecat::kAprw, "APRW", true, false, false, false, true, true},
    {ecat::kFprd, "FPRD", false, true, false, false, true, false},
    {ecat::kFpwr, "FPWR", false, true, false, false, false, true},
    {ecat::kFprw, "FPRW", false, true, false, false, true, true},
    {ecat::kBrd, "BRD", false, false, true, false, true, false},
    {ecat::kBwr, "BWR", false, false, true, false, false, true},
    {ecat::kBrw, "BRW", false, false, true, false, true, true},
    {ecat::kLrd, "LRD", false, false, false, true, true, false},
    {ecat::kLwr, "LWR", false, false, false, true, false, true},
    {ecat::kLrw, "LRW", false, false, false, true, true, true},
    {ecat::kArmw, "ARMW", true, false, false, false, true, false},
    {ecat::kFrmw, "FRMW", false, true, false, false, true, false},
    {15, "unknown", false, false, false, false, false, false},
    {255, "unknown", false, false, false, false, false, false},
};

TEST(Walker, CommandFacts) {
  for (const CommandCase& c : kCommandCases) {
    SCOPED_TRACE(c.name);
    EXPECT_STREQ(ecat::commandName(c.command), c.name);
    EXPECT_EQ(ecat::isAutoIncrement(c.command), c.auto_increment);
    EXPECT_EQ(ecat::isConfiguredAddress(c.command), c.configured);
    EXPECT_EQ(ecat::isBroadcast(c.command), c.broadcast);
    EXPECT_EQ(ecat::isLogical(c.command), c.logical);
    EXPECT_EQ(ecat::addressSurvivesRing(c.command), c.configured || c.logical);
    EXPECT_EQ(ecat::readsSlaves(c.command), c.reads);
    EXPECT_EQ(ecat::writesSlaves(c.command), c.writes);
  }
}

}  // namespace
}  // namespace ncservo
