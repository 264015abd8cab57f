// The CoE PDO assignment and mapping read from mailboxes (coe_pdo.hpp), one row per mailbox shape.
#include "ncservo/wire/coe_pdo.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <optional>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/layout/decoder.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

using test::Bytes;

// A CoE mailbox: header (length, address, channel, type 3), CoE header (service), SDO command,
// index, subindex, then the data.
Bytes mailbox(std::uint8_t service, std::uint8_t command, std::uint16_t index, std::uint8_t sub,
              const Bytes& data, std::uint8_t type = 3) {
  Bytes out;
  test::putLe(out, 2 + 4 + data.size(), 2);  // after the 6-byte header
  test::putLe(out, 0, 2);
  out.push_back(0);
  out.push_back(type);
  test::putLe(out, std::uint16_t(service) << 12, 2);
  out.push_back(command);
  test::putLe(out, index, 2);
  out.push_back(sub);
  out.insert(out.end(), data.begin(), data.end());
  out.resize(std::max<std::size_t>(out.size(), 48), 0);  // the rest of the SM buffer
  return out;
}
Bytes le(std::uint64_t v, std::size_t n) {
  Bytes b;
  test::putLe(b, v, n);
  return b;
}
// An expedited download request of `size` bytes (SDO command 0x23/0x27/0x2B/0x2F).
Bytes download(std::uint16_t index, std::uint8_t sub, std::uint32_t value, std::size_t size) {
  const auto command = static_cast<std::uint8_t>(0x23 | ((4 - size) << 2));
  return mailbox(2, command, index, sub, le(value, 4));
}
// An expedited upload response.
Bytes uploaded(std::uint16_t index, std::uint8_t sub, std::uint32_t value, std::size_t size) {
  const auto command = static_cast<std::uint8_t>(0x43 | ((4 - size) << 2));
  return mailbox(3, command, index, sub, le(value, 4));
}

// The protocol's RxPDO (SSP 32, SCW 32, ext code 16 bits) in 0x1600 and TxPDO (ActPos 64, SSW, SEW,
// message code, message data, four extra data: 32 each) in 0x1A00.
std::vector<Bytes> servoMapping(
    const std::function<Bytes(std::uint16_t, std::uint8_t, std::uint32_t, std::size_t)>& make) {
  std::vector<Bytes> m = {make(0x1C12, 0, 1, 1),          make(0x1C12, 1, 0x1600, 2),
                          make(0x1600, 0, 3, 1),          make(0x1600, 1, 0x20000120, 4),
                          make(0x1600, 2, 0x20000220, 4), make(0x1600, 3, 0x20000310, 4),
                          make(0x1C13, 0, 1, 1),          make(0x1C13, 1, 0x1A00, 2),
                          make(0x1A00, 0, 9, 1),          make(0x1A00, 1, 0x30000140, 4)};
  for (std::uint8_t k = 2; k <= 9; ++k) m.push_back(make(0x1A00, k, 0x30000020u | (k << 8), 4));
  return m;
}

struct CoeCase {
  const char* name;
  std::vector<Bytes> mailboxes;
  bool request;  // written by the master (SM0), else read back (SM1)
  std::optional<std::uint32_t> out_bits, in_bits;
  std::size_t cut = 0;  // bytes of each mailbox captured, 0: all
};

std::vector<CoeCase> cases() {
  Bytes complete;  // 0x1C12 by complete access from subindex 0: count 2, pad, 0x1600, 0x1601
  complete = mailbox(2, 0x21 | 0x10, 0x1C12, 0, Bytes{6, 0, 0, 0, 2, 0, 0x00, 0x16, 0x01, 0x16});
  return {
      {"expedited downloads", servoMapping(download), true, 80, 320},
      {"expedited upload responses", servoMapping(uploaded), false, 80, 320},
      {"upload responses are not requests", servoMapping(uploaded), true, std::nullopt,
       std::nullopt},
      {"a PDO not mapped yet",
       {download(0x1C12, 0, 1, 1), download(0x1C12, 1, 0x1600, 2)},
       true,
       std::nullopt,
       std::nullopt},
      {"nothing assigned", {download(0x1C12, 0, 0, 1), download(0x1C13, 0, 0, 1)}, true, 0, 0},
      {"not CoE (EoE type 2)",
       {mailbox(2, 0x2F, 0x1C12, 0, le(0, 4), 2)},
       true,
       std::nullopt,
       std::nullopt},
      {"other objects are not kept",
       {download(0x6040, 0, 15, 2)},
       true,
       std::nullopt,
       std::nullopt},
      {"complete access, then the mapping",
       {complete, download(0x1600, 0, 1, 1), download(0x1600, 1, 0x20000120, 4),
        download(0x1601, 0, 1, 1), download(0x1601, 1, 0x20000230, 4)},
       true,
       80,
       std::nullopt},
      {"mailboxes cut short in the capture", servoMapping(download), true, std::nullopt,
       std::nullopt, 11},
  };
}

class CoePdo : public ::testing::TestWithParam<CoeCase> {};
TEST_P(CoePdo, SizesTheProcessData) {
  const CoeCase& c = GetParam();
  CoePdoObjects objects;
  for (const Bytes& m : c.mailboxes) {
    const std::size_t captured = c.cut ? std::min(c.cut, m.size()) : m.size();
    objects.onMailbox(ByteReader(m.data(), captured), 0, captured, c.request);
  }
  EXPECT_EQ(objects.assignedBits(0x1C12), c.out_bits);
  EXPECT_EQ(objects.assignedBits(0x1C13), c.in_bits);
}
INSTANTIATE_TEST_SUITE_P(Mailboxes, CoePdo, ::testing::ValuesIn(cases()), test::rowName<CoeCase>);

// Through the decoder: the mailboxes a master writes to a slave's SM0, once the start-up made SM0
// a mailbox, mark a servo when its SM lengths are not written (and so keep the default layout).
Bytes smBlock(std::uint16_t start, std::uint16_t length, std::uint8_t control) {
  Bytes out = le(start, 2);
  test::putLe(out, length, 2);
  out.insert(out.end(), {control, 0, 1, 0});
  return out;
}
// One exchange: the master's copy, then the copy the slave returns (WKC 1).
void decodes(Decoder& decoder, const Bytes& data, std::uint16_t ado) {
  for (std::uint16_t wkc : {0, 1}) {
    test::FrameBuilder builder;
    builder.add(test::Dg{ecat::kFpwr, 1, test::physical(0x03E9, ado), data, wkc});
    const Bytes bytes = builder.bytes();
    const test::Walked walked = test::walk(bytes, bytes.size());
    FrameDecode out;
    decoder.placeAxes(*walked.frame, walked.reader(), out);
  }
}
TEST(CoePdoLearned, MailboxesWrittenToSm0MarkAServo) {
  struct Row {
    const char* name;
    std::vector<Bytes> mailboxes;
    bool servo;
  };
  const Row rows[] = {
      {"the protocol's PDOs", servoMapping(download), true},
      {"an 8-bit terminal's",
       {download(0x1C12, 0, 1, 1), download(0x1C12, 1, 0x1600, 2), download(0x1600, 0, 1, 1),
        download(0x1600, 1, 0x70000108, 4), download(0x1C13, 0, 0, 1)},
       false},
  };
  for (const Row& row : rows) {
    SCOPED_TRACE(row.name);
    Decoder decoder(DecoderOptions{});
    decodes(decoder, test::concat({smBlock(0x1000, 128, 0x26), smBlock(0x1080, 128, 0x22)}),
            0x0800);
    // SM2/SM3 configured for this example with their lengths left at 0 (not written yet)
    decodes(decoder, test::concat({smBlock(0x1100, 0, 0x64), smBlock(0x1180, 0, 0x20)}), 0x0810);
    for (const Bytes& m : row.mailboxes) decodes(decoder, m, 0x1000);
    ASSERT_EQ(decoder.learner().slaves().size(), 1u);
    EXPECT_EQ(decoder.learner().slaves()[0].servo, row.servo);
    EXPECT_EQ(decoder.startupShowsNoServo(), !row.servo);
  }
}

}  // namespace
}  // namespace ncservo
