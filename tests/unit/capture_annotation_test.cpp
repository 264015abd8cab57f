// Packet comments added to stored pcapng packet blocks (capture_annotation.hpp): the block's
// options kept, its lengths right, in either byte order; blocks that hold no options refused.
#include "ncservo/capture/capture_annotation.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ncservo {
namespace {

struct Option {
  std::uint16_t code;
  std::string value;
};

// A pcapng packet block as a writer stores it (pcapng §4.3; the obsolete Packet Block has the
// same layout), with `packet` bytes of packet data and these options.
std::vector<std::uint8_t> packetBlock(bool big, std::uint32_t type, std::size_t packet,
                                      const std::vector<Option>& options, bool end_of_options) {
  std::vector<std::uint8_t> out;
  auto put = [&](std::uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) {
      const int shift = 8 * (big ? bytes - 1 - i : i);
      out.push_back(static_cast<std::uint8_t>(v >> shift));
    }
  };
  auto pad = [&] { out.resize((out.size() + 3) & ~std::size_t{3}, 0); };
  put(type, 4);
  put(0, 4);
  put(0, 4);           // interface
  put(0x12345678, 8);  // timestamp (two words)
  put(packet, 4);
  put(packet + 7, 4);
  for (std::size_t i = 0; i < packet; ++i) out.push_back(static_cast<std::uint8_t>(i));
  pad();
  for (const Option& o : options) {
    put(o.code, 2);
    put(o.value.size(), 2);
    out.insert(out.end(), o.value.begin(), o.value.end());
    pad();
  }
  if (end_of_options) put(0, 4);
  const std::size_t total = out.size() + 4;
  put(total, 4);
  for (int i = 0; i < 4; ++i)
    out[4 + i] = static_cast<std::uint8_t>(total >> (8 * (big ? 3 - i : i)));
  return out;
}

constexpr std::uint32_t kEpb = 6, kPb = 2, kSpb = 3;
const Option kHash{3, "0123456789ab"};  // epb_hash: any other option is kept as it is

struct Case {
  const char* name;
  bool big;
  std::uint32_t type;
  std::size_t packet;
  std::vector<Option> options;
  bool end_of_options;
  std::vector<std::string> comments;
};
const Case kCases[] = {
    {"no options", false, kEpb, 60, {}, false, {"SE-001 illegal-enable-edge axis X: seen"}},
    {"unpadded packet", false, kEpb, 61, {}, false, {"a", "two comments"}},
    {"existing comment kept", false, kEpb, 64, {{1, "by hand"}}, true, {"SE-002 x"}},
    {"options without end", false, kEpb, 62, {kHash}, false, {"COM-001 y"}},
    {"big-endian section", true, kEpb, 63, {{1, "kept"}, kHash}, true, {"EC-002 z"}},
    {"obsolete Packet Block", false, kPb, 60, {}, true, {"ZP-001 w"}},
};

TEST(CaptureAnnotation, CommentsFollowTheBlocksOptions) {
  for (const Case& c : kCases) {
    SCOPED_TRACE(c.name);
    const auto block = packetBlock(c.big, c.type, c.packet, c.options, c.end_of_options);
    std::vector<Option> all = c.options;
    for (const std::string& comment : c.comments) all.push_back({1, comment});
    const auto annotated = withComments(block.data(), block.size(), c.comments);
    ASSERT_TRUE(annotated.has_value());
    EXPECT_EQ(*annotated, packetBlock(c.big, c.type, c.packet, all, true));
  }
}

// Annotating again: the comments `replaced` picks go, the rest of the options stay in order.
TEST(CaptureAnnotation, ReplacedCommentsGoAndOthersStay) {
  const auto ours = [](std::string_view c) { return c.substr(0, 4) == "OUR "; };
  struct Row {
    const char* name;
    bool big;
    std::vector<Option> options;
    std::vector<std::string> comments;
    std::vector<Option> kept;
  };
  const Row rows[] = {
      {"ours replaced", false, {{1, "OUR old"}}, {"OUR new"}, {}},
      {"someone else's kept",
       false,
       {{1, "by hand"}, {1, "OUR old"}, kHash},
       {"OUR new"},
       {{1, "by hand"}, kHash}},
      {"ours gone, none new", true, {kHash, {1, "OUR old"}}, {}, {kHash}},
      {"nothing of ours", false, {{1, "OUR"}}, {"OUR new"}, {{1, "OUR"}}},
  };
  for (const Row& row : rows) {
    SCOPED_TRACE(row.name);
    const auto block = packetBlock(row.big, kEpb, 60, row.options, true);
    std::vector<Option> all = row.kept;
    for (const std::string& comment : row.comments) all.push_back({1, comment});
    const auto annotated = withComments(block.data(), block.size(), row.comments, ours);
    ASSERT_TRUE(annotated.has_value());
    EXPECT_EQ(*annotated, packetBlock(row.big, kEpb, 60, all, true));
  }
}

TEST(CaptureAnnotation, BlocksWithoutOptionsAreRefused) {
  const auto simple = packetBlock(false, kSpb, 60, {}, false);
  EXPECT_FALSE(withComments(simple.data(), simple.size(), {"c"}).has_value());
  auto wrong_length = packetBlock(false, kEpb, 60, {}, false);
  wrong_length[4] ^= 4;
  EXPECT_FALSE(withComments(wrong_length.data(), wrong_length.size(), {"c"}).has_value());
  const auto cut = packetBlock(false, kEpb, 60, {}, false);
  EXPECT_FALSE(withComments(cut.data(), 20, {"c"}).has_value());
}

}  // namespace
}  // namespace ncservo
