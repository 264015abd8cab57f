// The mailbox (PROTOCOL.md §11): one mailbox decoded byte by byte (mailbox.hpp), and what the
// tracker makes of a slave's mailbox traffic (mailbox_tracker.hpp): areas from the start-up or
// seen in use, emergencies, SDO answers paired with their requests, other protocols counted, and
// hostile input as notes. The bytes are written out from PROTOCOL.md §11, not by the code under
// test.
#include "ncservo/wire/mailbox.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/model/mailbox_tracker.hpp"
#include "ncservo/wire/diagnosis_texts.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

using test::Bytes;
using test::Dg;
using test::FrameBuilder;
using test::physical;

constexpr std::uint16_t kStation = 0x03E9;
constexpr std::uint16_t kOut = 0x1000;  // SM0
constexpr std::uint16_t kIn = 0x1080;   // SM1
constexpr std::size_t kArea = 48;

using test::coe;
using test::emcy;
using test::mbx;
using test::sdo;

MailboxMessage decode(const Bytes& data) {
  return decodeMailbox(ByteReader(data.data(), data.size()), 0, data.size());
}

// --- One mailbox, decoded ---

TEST(MailboxDecode, Emergency) {
  // 0x8611 following error, register 0x21, manufacturer data 0d 00 00 00 00.
  const MailboxMessage m = decode(mbx(3, 1, coe(1, emcy(0x8611, 0x21, {0x0D, 0, 0, 0, 0}))));
  ASSERT_EQ(m.status, MailboxStatus::Ok);
  EXPECT_EQ(m.length, 10);
  EXPECT_EQ(m.counter, 1);
  EXPECT_EQ(m.coe_service, 1);
  ASSERT_TRUE(m.emergency);
  EXPECT_EQ(m.emergency->code, 0x8611);
  EXPECT_EQ(m.emergency->error_register, 0x21);
  EXPECT_EQ(m.emergency->data[0], 0x0D);
}

struct SdoRow {
  std::string name;
  Bytes mailbox;
  SdoKind kind;
  bool request;
  std::uint16_t index;
  std::uint8_t sub;
  std::optional<std::uint64_t> value;
  std::optional<std::uint32_t> size;
  std::uint32_t abort = 0;
};
class MailboxSdo : public ::testing::TestWithParam<SdoRow> {};
TEST_P(MailboxSdo, Decodes) {
  const SdoRow& row = GetParam();
  const MailboxMessage m = decode(row.mailbox);
  ASSERT_EQ(m.status, MailboxStatus::Ok);
  ASSERT_TRUE(m.sdo);
  EXPECT_EQ(m.sdo->kind, row.kind);
  EXPECT_EQ(m.sdo->request, row.request);
  EXPECT_EQ(m.sdo->value, row.value);
  EXPECT_EQ(m.sdo->size, row.size);
  EXPECT_EQ(m.sdo->abort_code, row.abort);
  if (row.kind != SdoKind::UploadSegment && row.kind != SdoKind::DownloadSegment) {
    EXPECT_EQ(m.sdo->index, row.index);
    EXPECT_EQ(m.sdo->subindex, row.sub);
  }
}
INSTANTIATE_TEST_SUITE_P(
    Mailbox, MailboxSdo,
    ::testing::Values(
        // Upload request 0x40, 1003h:0.
        SdoRow{"upload_request", mbx(3, 1, coe(2, sdo(0x40, 0x1003, 0, 0))),
               SdoKind::InitiateUpload, true, 0x1003, 0, std::nullopt, std::nullopt},
        // Expedited upload response, 1 byte (0x4F: 3 unused, size indicated, expedited).
        SdoRow{"expedited_upload_1_byte", mbx(3, 2, coe(3, sdo(0x4F, 0x1003, 0, 0xAABBCC01))),
               SdoKind::InitiateUpload, false, 0x1003, 0, 0x01, 1u},
        // Expedited upload response, 4 bytes (0x43): a 1003h entry.
        SdoRow{"expedited_upload_4_bytes", mbx(3, 3, coe(3, sdo(0x43, 0x1003, 1, 0x0D218611))),
               SdoKind::InitiateUpload, false, 0x1003, 1, 0x0D218611, 4u},
        // Expedited download request, 2 bytes (0x2B).
        SdoRow{"expedited_download_2_bytes", mbx(3, 1, coe(2, sdo(0x2B, 0x1C12, 1, 0x1600))),
               SdoKind::InitiateDownload, true, 0x1C12, 1, 0x1600, 2u},
        // Download response 0x60.
        SdoRow{"download_response", mbx(3, 1, coe(3, sdo(0x60, 0x1C12, 1, 0))),
               SdoKind::InitiateDownload, false, 0x1C12, 1, std::nullopt, std::nullopt},
        // Normal upload response (0x41): size 2, then the 2 bytes in the same message.
        SdoRow{"normal_upload_whole",
               mbx(3, 1, coe(3, test::concat({sdo(0x41, 0x10F3, 1, 2), Bytes{0x34, 0x12}}))),
               SdoKind::InitiateUpload, false, 0x10F3, 1, 0x1234, 2u},
        // Abort 0x80 with 0x08000024.
        SdoRow{"abort", mbx(3, 1, coe(3, sdo(0x80, 0x1003, 2, 0x08000024))), SdoKind::Abort, false,
               0x1003, 2, std::nullopt, std::nullopt, 0x08000024},
        // Upload segment response 0x00: toggle 0, 7 bytes, more to come.
        SdoRow{"upload_segment", mbx(3, 1, coe(3, Bytes{0x00, 1, 2, 3, 4, 5, 6, 7})),
               SdoKind::UploadSegment, false, 0, 0, 0x07060504030201, std::nullopt}),
    test::rowName<SdoRow>);

TEST(MailboxDecode, LengthBeyondTheDatagram) {
  // The header says 200 bytes; the datagram holds 48.
  const MailboxMessage m = decode(mbx(3, 1, coe(1, emcy(0x8611, 0x21, {})), kArea, 200));
  EXPECT_EQ(m.status, MailboxStatus::LengthBeyondData);
  EXPECT_FALSE(m.emergency);
}

TEST(MailboxDecode, OtherProtocolsAreOnlyTyped) {
  const MailboxMessage m = decode(mbx(2, 1, Bytes(20, 0xAB)));  // EoE
  EXPECT_EQ(m.status, MailboxStatus::Ok);
  EXPECT_EQ(m.type, 2);
  EXPECT_FALSE(m.emergency);
  EXPECT_FALSE(m.sdo);
}

TEST(MailboxDecode, CutAnywhereIsNeverRead) {
  const Bytes whole = mbx(3, 1, coe(3, sdo(0x43, 0x1003, 1, 0x0D218611)));
  for (std::size_t cut = 0; cut <= whole.size(); ++cut) {
    std::vector<std::uint8_t> copy(whole.begin(), whole.begin() + static_cast<long>(cut));
    const MailboxMessage m = decodeMailbox(ByteReader(copy.data(), copy.size()), 0, copy.size());
    if (cut < 6) {
      EXPECT_EQ(m.status, MailboxStatus::NotMailbox) << cut;
    }
  }
}

// --- Texts (seed 002, CiA 301, ETG.1000.6) ---

TEST(DiagnosisTexts, FromTheirTables) {
  EXPECT_STREQ(diag::errorCodeText(0x8611), "following error too large");
  EXPECT_STREQ(diag::errorCodeText(0x2300), "current at the controller output too large");
  EXPECT_STREQ(diag::errorCodeText(0x2310), "current");  // CiA 301 family
  EXPECT_STREQ(diag::errorNumberText(13), "following error window and time out exceeded");
  EXPECT_STREQ(diag::abortText(0x08000024), "no data available");
  EXPECT_STREQ(diag::abortText(0x06020000), "object does not exist");
  EXPECT_EQ(diag::abortText(0x12345678), nullptr);
  EXPECT_STREQ(diag::objectName(0x1003), "pre-defined error field");
  EXPECT_STREQ(diag::objectName(0x603F), "error code");
  ASSERT_NE(diag::alStatusCode(0x001A), nullptr);
  EXPECT_STREQ(diag::alStatusCode(0x001A)->text, "synchronization error");
  EXPECT_TRUE(diag::alStatusCode(0x001B)->sync);
  EXPECT_TRUE(diag::alStatusCode(0x0032)->sync);
  EXPECT_FALSE(diag::alStatusCode(0x0011)->sync);
  const diag::ErrorFieldEntry e = diag::errorFieldEntry(220300817);  // INTERFACES.md's example
  EXPECT_EQ(e.number, 13);
  EXPECT_EQ(e.error_class, 33);
  EXPECT_EQ(e.code, 34321);
}

// The error register (1001h) a code sets: generic, and its CiA 301 family's bit (INTERFACES.md's
// example: 0x8611 with class 0x21).
TEST(DiagnosisTexts, ErrorRegisterOfACode) {
  const std::pair<std::uint16_t, std::uint8_t> rows[] = {
      {0x0000, 0x00}, {0x1000, 0x01}, {0x2300, 0x03}, {0x3100, 0x05}, {0x4200, 0x09},
      {0x6010, 0x01}, {0x7305, 0x01}, {0x8100, 0x11}, {0x8130, 0x11}, {0x8210, 0x11},
      {0x8400, 0x21}, {0x8611, 0x21}, {0xFF00, 0x81},
  };
  for (const auto& [code, error_register] : rows) {
    EXPECT_EQ(diag::errorRegisterFor(code), error_register) << std::hex << code;
  }
}

// --- The tracker ---

// Feeds master copies and returned copies to one tracker; frames numbered from 1.
struct Harness {
  MailboxTracker tracker;
  FrameAddressing addressing;
  std::vector<BusEvent> events;
  std::uint64_t frame = 0;

  void feed(const Dg& dg, bool returned) {
    FrameBuilder builder;
    builder.add(dg);
    const Bytes bytes = builder.bytes();
    const test::Walked w = test::walk(bytes);
    addressing.beginFrame(*w.frame, returned, true);
    ++frame;
    tracker.onFrame(*w.frame, w.reader(), addressing, Stamp{frame, std::int64_t(frame) * 1000},
                    std::int64_t(frame) * 1000, events);
  }
  // The start-up's SM0 and SM1 writes (control 0x26 and 0x22: mailbox mode).
  void startUp() {
    const Bytes sms =
        test::concat({test::smBlock(kOut, kArea, 0x26), test::smBlock(kIn, kArea, 0x22)});
    Dg dg{ecat::kFpwr, 0, physical(kStation, ecat::kRegSyncManager0), sms, 0};
    feed(dg, false);
    dg.wkc = 1;
    feed(dg, true);
  }
  void write(const Bytes& mailbox) {
    Dg dg{ecat::kFpwr, 0, physical(kStation, kOut), mailbox, 0};
    feed(dg, false);
    dg.wkc = 1;
    feed(dg, true);
  }
  void read(const Bytes& mailbox, std::uint16_t wkc = 1) {
    feed(Dg{ecat::kFprd, 0, physical(kStation, kIn), Bytes(mailbox.size(), 0), 0}, false);
    feed(Dg{ecat::kFprd, 0, physical(kStation, kIn), mailbox, wkc}, true);
  }
  std::vector<std::string> noteTexts() const {
    std::vector<std::string> out;
    for (const MailboxNote& n : tracker.notes()) out.push_back(n.text);
    return out;
  }
};

TEST(MailboxTracker, EmergencyFromTheStartUpsArea) {
  Harness h;
  h.startUp();
  h.read(mbx(3, 1, coe(1, emcy(0x8611, 0x21, {0x0D, 0, 0, 0, 0}))));
  ASSERT_EQ(h.tracker.messages().size(), 1u);
  const DriveMessage& m = h.tracker.messages()[0];
  EXPECT_EQ(m.kind, DriveMessage::Kind::Emergency);
  EXPECT_EQ(m.frame, 4u);  // the returned copy of the read
  EXPECT_EQ(m.slave.station, kStation);
  EXPECT_EQ(m.emergency.code, 0x8611);
  ASSERT_EQ(h.events.size(), 1u);
  EXPECT_EQ(std::get<EmergencyEvent>(h.events[0].data).code, 0x8611);
  // The same message read again (same counter) is a repeat, not a second emergency.
  h.read(mbx(3, 1, coe(1, emcy(0x8611, 0x21, {0x0D, 0, 0, 0, 0}))));
  EXPECT_EQ(h.tracker.messages().size(), 1u);
  EXPECT_EQ(h.tracker.counts().repeats, 1u);
}

TEST(MailboxTracker, AReadWithWkcZeroHoldsNothing) {
  Harness h;
  h.startUp();
  h.read(mbx(3, 1, coe(1, emcy(0x8611, 0x21, {}))), 0);
  EXPECT_TRUE(h.tracker.messages().empty());
}

TEST(MailboxTracker, ExpeditedUploadPairedWithItsRequest) {
  Harness h;
  h.startUp();
  h.write(mbx(3, 1, coe(2, sdo(0x40, 0x1003, 1, 0))));          // frames 3, 4
  h.read(mbx(3, 2, coe(3, sdo(0x43, 0x1003, 1, 0x0D218611))));  // frames 5, 6
  ASSERT_EQ(h.tracker.messages().size(), 1u);
  const DriveMessage& m = h.tracker.messages()[0];
  EXPECT_EQ(m.kind, DriveMessage::Kind::SdoUpload);
  EXPECT_EQ(m.frame, 6u);
  EXPECT_EQ(m.request_frame, 3u);
  EXPECT_EQ(m.index, 0x1003);
  EXPECT_EQ(m.subindex, 1);
  EXPECT_EQ(m.value, 0x0D218611u);
}

TEST(MailboxTracker, SegmentedUploadJoined) {
  Harness h;
  h.startUp();
  h.write(mbx(3, 1, coe(2, sdo(0x40, 0x10F3, 6, 0))));
  // Normal upload response: size 12, none of it in this message (the length says so).
  h.read(mbx(3, 1, coe(3, sdo(0x41, 0x10F3, 6, 12))));
  h.write(mbx(3, 2, coe(2, Bytes{0x60, 0, 0, 0, 0, 0, 0, 0})));
  h.read(mbx(3, 2, coe(3, Bytes{0x00, 1, 2, 3, 4, 5, 6, 7})));  // toggle 0, 7 bytes
  h.write(mbx(3, 3, coe(2, Bytes{0x70, 0, 0, 0, 0, 0, 0, 0})));
  h.read(mbx(3, 3, coe(3, Bytes{0x15, 8, 9, 10, 11, 12, 0, 0})));  // toggle 1, 2 unused, last
  ASSERT_EQ(h.tracker.messages().size(), 1u);
  const DriveMessage& m = h.tracker.messages()[0];
  EXPECT_EQ(m.kind, DriveMessage::Kind::SdoUpload);
  EXPECT_EQ(m.index, 0x10F3);
  EXPECT_EQ(m.size, 12u);
  EXPECT_EQ(m.request_frame, 3u);
  EXPECT_FALSE(m.value);  // more than 8 bytes
  EXPECT_TRUE(h.tracker.notes().empty());
}

TEST(MailboxTracker, ToggleOutOfOrderIsANote) {
  Harness h;
  h.startUp();
  h.write(mbx(3, 1, coe(2, sdo(0x40, 0x10F3, 6, 0))));
  h.read(mbx(3, 1, coe(3, sdo(0x41, 0x10F3, 6, 20))));
  h.read(mbx(3, 2, coe(3, Bytes{0x10, 1, 2, 3, 4, 5, 6, 7})));  // toggle 1 first
  EXPECT_TRUE(h.tracker.messages().empty());
  EXPECT_EQ(h.noteTexts(), std::vector<std::string>{
                               "SDO upload of 0x10F3:6: segment toggle 1 where 0 was due: transfer "
                               "dropped"});
}

TEST(MailboxTracker, SegmentedUploadThatNeverEnds) {
  Harness h;
  h.startUp();
  h.write(mbx(3, 1, coe(2, sdo(0x40, 0x10F3, 6, 0))));
  h.read(mbx(3, 1, coe(3, sdo(0x41, 0x10F3, 6, 10))));
  bool toggle = false;
  for (int i = 0; i < 50; ++i) {
    const auto command = static_cast<std::uint8_t>(toggle ? 0x10 : 0x00);
    h.read(
        mbx(3, static_cast<std::uint8_t>(2 + i % 6), coe(3, Bytes{command, 1, 2, 3, 4, 5, 6, 7})));
    toggle = !toggle;
  }
  EXPECT_TRUE(h.tracker.messages().empty());
  EXPECT_EQ(h.noteTexts(),
            std::vector<std::string>{"SDO upload of 0x10F3:6 runs past its 10 bytes: transfer "
                                     "dropped"});
}

TEST(MailboxTracker, MailboxLongerThanItsDatagram) {
  Harness h;
  h.startUp();
  h.read(mbx(3, 1, coe(1, emcy(0x8611, 0x21, {})), kArea, 0x7FFF));
  h.read(mbx(3, 2, coe(1, emcy(0x8611, 0x21, {})), kArea, 0x7FFF));
  EXPECT_TRUE(h.tracker.messages().empty());
  EXPECT_EQ(h.noteTexts(), std::vector<std::string>{"mailbox length 32767 larger than the 42 "
                                                    "bytes the datagram holds after the header: "
                                                    "not decoded"});
}

TEST(MailboxTracker, AbortOfAnEmptyHistoryIsExpected) {
  Harness h;
  h.startUp();
  h.write(mbx(3, 1, coe(2, sdo(0x40, 0x1003, 1, 0))));
  h.read(mbx(3, 1, coe(3, sdo(0x80, 0x1003, 1, 0x08000024))));
  h.write(mbx(3, 2, coe(2, sdo(0x40, 0x6099, 1, 0))));
  h.read(mbx(3, 2, coe(3, sdo(0x80, 0x6099, 1, 0x06020000))));
  ASSERT_EQ(h.tracker.messages().size(), 2u);
  EXPECT_EQ(h.tracker.messages()[0].kind, DriveMessage::Kind::SdoAbort);
  EXPECT_EQ(h.tracker.messages()[0].request_frame, 3u);
  ASSERT_EQ(h.events.size(), 2u);
  EXPECT_TRUE(std::get<SdoAbortEvent>(h.events[0].data).expected);
  EXPECT_FALSE(std::get<SdoAbortEvent>(h.events[1].data).expected);
  EXPECT_EQ(std::get<SdoAbortEvent>(h.events[1].data).code, 0x06020000u);
}

// ETG.1000.6: an abort is an SDO request (service 2) whoever sends it; the area it was read from
// tells the drive's from the master's.
TEST(MailboxTracker, AbortWithTheRequestServiceIsTheDrives) {
  Harness h;
  h.startUp();
  h.write(mbx(3, 1, coe(2, sdo(0x40, 0x2000, 0, 0))));
  h.read(mbx(3, 1, coe(2, sdo(0x80, 0x2000, 0, 0x06020000))));
  h.write(mbx(3, 2, coe(2, sdo(0x40, 0x6099, 1, 0))));
  h.write(mbx(3, 3, coe(2, sdo(0x80, 0x6099, 1, 0x05040000))));  // the master gives up
  ASSERT_EQ(h.tracker.messages().size(), 1u);
  EXPECT_EQ(h.tracker.messages()[0].kind, DriveMessage::Kind::SdoAbort);
  EXPECT_EQ(h.tracker.messages()[0].abort_code, 0x06020000u);
  EXPECT_EQ(h.tracker.messages()[0].request_frame, 3u);
  ASSERT_EQ(h.events.size(), 1u);
  EXPECT_EQ(std::get<SdoAbortEvent>(h.events[0].data).code, 0x06020000u);
}

TEST(MailboxTracker, ErrorHistoryShrinks) {
  Harness h;
  h.startUp();
  auto readCount = [&](std::uint8_t counter, std::uint32_t count) {
    h.write(mbx(3, counter, coe(2, sdo(0x40, 0x1003, 0, 0))));
    h.read(mbx(3, counter, coe(3, sdo(0x4F, 0x1003, 0, count))));
  };
  readCount(1, 3);
  readCount(2, 4);  // grew: nothing
  EXPECT_TRUE(h.events.empty());
  readCount(3, 2);  // shrank with no clear
  ASSERT_EQ(h.events.size(), 1u);
  const auto& shrunk = std::get<ErrorHistoryShrunkEvent>(h.events[0].data);
  EXPECT_EQ(shrunk.before, 4u);
  EXPECT_EQ(shrunk.now, 2u);
  // Writing 0 to 1003h:0 clears it: a lower count after that is no finding.
  h.write(mbx(3, 4, coe(2, sdo(0x2F, 0x1003, 0, 0))));
  h.read(mbx(3, 4, coe(3, sdo(0x60, 0x1003, 0, 0))));
  readCount(5, 1);
  EXPECT_EQ(h.events.size(), 1u);
}

TEST(MailboxTracker, OtherProtocolsCounted) {
  Harness h;
  h.startUp();
  h.read(mbx(2, 1, Bytes(20, 0xAB)));  // EoE
  h.read(mbx(4, 2, Bytes(20, 0xAB)));  // FoE
  h.read(mbx(5, 3, Bytes(20, 0xAB)));  // SoE
  EXPECT_TRUE(h.tracker.messages().empty());
  EXPECT_EQ(h.tracker.counts().eoe, 1u);
  EXPECT_EQ(h.tracker.counts().foe, 1u);
  EXPECT_EQ(h.tracker.counts().soe, 1u);
}

TEST(MailboxTracker, AreasSeenInUse) {
  Harness h;  // no start-up
  h.write(mbx(3, 1, coe(2, sdo(0x40, 0x1001, 0, 0))));
  h.read(mbx(3, 1, coe(3, sdo(0x4F, 0x1001, 0, 0x21))));
  ASSERT_EQ(h.tracker.messages().size(), 1u);
  EXPECT_EQ(h.tracker.messages()[0].value, 0x21u);
  EXPECT_EQ(h.tracker.messages()[0].request_frame, 1u);
}

// PROTOCOL.md §11: the start-up's SM writes, else the ENI's areas, else seen in use.
TEST(MailboxTracker, AreasFromTheEni) {
  Harness without;  // no start-up, no write seen: a read alone is nobody's mailbox
  without.read(mbx(3, 1, coe(1, emcy(0x8611, 0x21, {0x0D, 0, 0, 0, 0}))));
  EXPECT_TRUE(without.tracker.messages().empty());
  Harness h;
  h.tracker.configure({MailboxArea{kStation, kOut, kIn}});
  h.read(mbx(3, 1, coe(1, emcy(0x8611, 0x21, {0x0D, 0, 0, 0, 0}))));
  ASSERT_EQ(h.tracker.messages().size(), 1u);
  EXPECT_EQ(h.tracker.messages()[0].emergency.code, 0x8611);
  EXPECT_EQ(h.tracker.messages()[0].slave.station, kStation);
}

TEST(MailboxTracker, TheStartUpsAreasWinOverTheEnis) {
  Harness h;
  h.tracker.configure({MailboxArea{kStation, 0x1800, 0x1880}});
  h.startUp();
  h.read(mbx(3, 1, coe(1, emcy(0x8611, 0x21, {0x0D, 0, 0, 0, 0}))));
  EXPECT_EQ(h.tracker.messages().size(), 1u);
}

TEST(MailboxTracker, ProcessDataIsNotAMailbox) {
  Harness h;
  h.startUp();
  // An FPRD of process RAM elsewhere, and a datagram whose bytes would decode as an emergency.
  h.feed(
      Dg{ecat::kFprd, 0, physical(kStation, 0x1100), mbx(3, 1, coe(1, emcy(0x8611, 0x21, {}))), 1},
      true);
  EXPECT_TRUE(h.tracker.messages().empty());
  EXPECT_EQ(h.tracker.counts().messages, 0u);
}

TEST(MailboxTracker, PendingRequestsAreBounded) {
  Harness h;
  h.startUp();
  for (std::uint8_t sub = 1; sub <= 20; ++sub) {
    h.write(mbx(3, static_cast<std::uint8_t>(1 + sub % 7), coe(2, sdo(0x40, 0x1003, sub, 0))));
  }
  // The oldest gave way: an answer to subindex 1 has no request any more, one to 20 has.
  h.read(mbx(3, 1, coe(3, sdo(0x43, 0x1003, 1, 5))));
  h.read(mbx(3, 2, coe(3, sdo(0x43, 0x1003, 20, 5))));
  ASSERT_EQ(h.tracker.messages().size(), 2u);
  EXPECT_FALSE(h.tracker.messages()[0].request_frame);
  EXPECT_TRUE(h.tracker.messages()[1].request_frame);
}

}  // namespace
}  // namespace ncservo
