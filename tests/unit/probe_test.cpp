// ESL probe frames (docs/protocol.md §8): the walker finds the header before or after the Ethernet
// frame, and FrameClock times frames by the probe or the capture (docs/cli.md, --timestamps).
#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "ncservo/wire/frame_clock.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

using test::Bytes;
using test::Dg;
using test::FrameBuilder;

Bytes eslHeader(std::uint16_t flags, std::uint64_t timestamp_ns, std::uint8_t kind = 0x10) {
  Bytes h = {0x01, 0x01, 0x05, kind, 0x00, 0x00};
  h.push_back(static_cast<std::uint8_t>(flags));
  h.push_back(static_cast<std::uint8_t>(flags >> 8));
  for (int i = 0; i < 8; ++i) h.push_back(static_cast<std::uint8_t>(timestamp_ns >> (8 * i)));
  return h;
}

Bytes ethercatFrame() {
  return FrameBuilder().add(Dg{ecat::kLrw, 1, 0x00010000, Bytes(50, 0x11), 3}).bytes();
}

enum class Place { None, Before, After };

struct EslRow {
  const char* name;
  Place place;
  std::uint16_t flags;
  std::uint8_t kind;
  WalkStatus status;
  std::optional<std::uint8_t> port;
  bool timestamp_valid;
};

class EslWalk : public ::testing::TestWithParam<EslRow> {};

TEST_P(EslWalk, FindsTheHeader) {
  const EslRow& row = GetParam();
  const Bytes frame = ethercatFrame();
  const Bytes header = eslHeader(row.flags, 0x0123456789ABCDEFull, row.kind);
  Bytes bytes;
  if (row.place == Place::Before) bytes = header;
  bytes.insert(bytes.end(), frame.begin(), frame.end());
  if (row.place == Place::After) bytes.insert(bytes.end(), header.begin(), header.end());
  const test::Walked w = test::walk(bytes);
  EXPECT_EQ(w.frame->status, row.status);
  EXPECT_EQ(w.frame->probe.present, row.place != Place::None);
  EXPECT_EQ(w.frame->count, 1u);
  EXPECT_EQ(w.frame->ecat_offset, 14u + (row.place == Place::Before ? 16u : 0u));
  if (row.place == Place::None) return;
  EXPECT_EQ(w.frame->probe.before, row.place == Place::Before);
  EXPECT_EQ(w.frame->probe.flags, row.flags);
  EXPECT_EQ(w.frame->probe.timestamp_ns, 0x0123456789ABCDEFull);
  EXPECT_EQ(w.frame->probe.port(), row.port);
  EXPECT_EQ(w.frame->probe.timestampValid(), row.timestamp_valid);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, EslWalk,
    ::testing::Values(
        EslRow{"no header", Place::None, 0, 0x10, WalkStatus::Ok, std::nullopt, false},
        EslRow{"before, port 0", Place::Before, 0x2080, 0x10, WalkStatus::Ok, 0, true},
        EslRow{"after, port 1", Place::After, 0x2040, 0x10, WalkStatus::Ok, 1, true},
        EslRow{"before, kind 0x11, port 7", Place::Before, 0x2001, 0x11, WalkStatus::Ok, 7, true},
        EslRow{"after, port 8", Place::After, 0xA000, 0x10, WalkStatus::Ok, 8, true},
        EslRow{"before, port 11", Place::Before, 0x2200, 0x10, WalkStatus::Ok, 11, true},
        EslRow{"no port, no timestamp", Place::Before, 0x0000, 0x10, WalkStatus::Ok, std::nullopt,
               false},
        EslRow{"CRC error before: bus fault", Place::Before, 0x3080, 0x10, WalkStatus::BusFault, 0,
               true},
        EslRow{"CRC error after: bus fault", Place::After, 0x3040, 0x10, WalkStatus::BusFault, 1,
               true},
        EslRow{"alignment error only", Place::After, 0x2840, 0x10, WalkStatus::Ok, 1, true}),
    test::rowName<EslRow>);

TEST(EslWalk, TrailerBytesInsideTheChainAreData) {
  // A datagram whose data ends with the six ESL bytes and ten more: not a header, since taking
  // it as one would cut the EtherCAT frame.
  Bytes data(40, 0x22);
  const Bytes look_alike = eslHeader(0x2080, 7);
  std::copy(look_alike.begin(), look_alike.end(), data.end() - 16);
  Bytes bytes = FrameBuilder().add(Dg{ecat::kLrw, 1, 0x00010000, data, 3}).bytes();
  bytes.resize(bytes.size() - 2);  // end the frame with the data (the WKC is cut)
  const test::Walked w = test::walk(bytes);
  EXPECT_FALSE(w.frame->probe.present);
  EXPECT_EQ(w.frame->status, WalkStatus::Truncated);
}

TEST(EslWalk, OnlyOnTheEthernetLink) {
  const Bytes frame =
      FrameBuilder().link(test::Link::Sll).add(Dg{ecat::kLrw, 1, 0, Bytes(8), 0}).bytes();
  Bytes bytes = eslHeader(0x2080, 1);
  bytes.insert(bytes.end(), frame.begin(), frame.end());
  EXPECT_FALSE(test::walk(bytes, test::Link::Sll).frame->probe.present);
}

// FrameClock over a sequence of EtherCAT frames: (capture time, probe timestamp if any).
struct ClockFrame {
  std::int64_t capture_ns;
  std::optional<std::uint64_t> probe_ns;
  std::uint16_t extra_flags = 0;
};
struct ClockRow {
  const char* name;
  TimestampMode mode;
  std::vector<ClockFrame> frames;
  std::vector<std::int64_t> times;
  TimestampSource source;
  std::uint64_t unstamped;
  std::uint64_t first_unstamped;
  std::uint64_t crc_errors;
};
class Clock : public ::testing::TestWithParam<ClockRow> {};

TEST_P(Clock, TimesFrames) {
  const ClockRow& row = GetParam();
  FrameClock clock(row.mode);
  std::vector<std::int64_t> times;
  for (std::size_t i = 0; i < row.frames.size(); ++i) {
    const ClockFrame& f = row.frames[i];
    ProbeHeader probe;
    probe.present = f.probe_ns.has_value() || f.extra_flags != 0;
    probe.flags =
        static_cast<std::uint16_t>((f.probe_ns ? esl::kFlagTimestampValid : 0) | f.extra_flags);
    probe.timestamp_ns = f.probe_ns.value_or(0);
    times.push_back(clock.time(i + 1, f.capture_ns, probe));
  }
  EXPECT_EQ(times, row.times);
  EXPECT_EQ(clock.source(), row.source);
  EXPECT_EQ(clock.counts().unstamped, row.unstamped);
  EXPECT_EQ(clock.counts().first_unstamped, row.first_unstamped);
  EXPECT_EQ(clock.counts().crc_errors, row.crc_errors);
  EXPECT_EQ(clock.note().empty(),
            row.unstamped == 0 && row.crc_errors == 0 &&
                !(row.source == TimestampSource::Capture && clock.counts().stamped > 0));
}

// Capture times carry noise; the probe's intervals are exact 1000 ns.
const std::vector<ClockFrame> kStamped = {
    {5'000, 900'000}, {6'300, 901'000}, {6'800, 902'000}, {8'100, 903'000}};
const std::vector<ClockFrame> kGap = {
    {5'000, 900'000}, {6'300, std::nullopt}, {6'800, 902'000}, {8'100, 903'000}};
const std::vector<ClockFrame> kLateProbe = {
    {5'000, std::nullopt}, {6'300, 901'000}, {6'800, 902'000}};
const std::vector<ClockFrame> kCrc = {
    {5'000, 900'000}, {6'300, 901'000, esl::kFlagCrcError}, {6'800, 902'000}};

INSTANTIATE_TEST_SUITE_P(
    Rows, Clock,
    ::testing::Values(ClockRow{"auto, all stamped: probe",
                               TimestampMode::Auto,
                               kStamped,
                               {5'000, 6'000, 7'000, 8'000},
                               TimestampSource::Probe,
                               0,
                               0,
                               0},
                      ClockRow{"capture, all stamped: capture",
                               TimestampMode::Capture,
                               kStamped,
                               {5'000, 6'300, 6'800, 8'100},
                               TimestampSource::Capture,
                               0,
                               0,
                               0},
                      ClockRow{"probe, all stamped",
                               TimestampMode::Probe,
                               kStamped,
                               {5'000, 6'000, 7'000, 8'000},
                               TimestampSource::Probe,
                               0,
                               0,
                               0},
                      ClockRow{"auto, one unstamped: timed from the frame before",
                               TimestampMode::Auto,
                               kGap,
                               {5'000, 6'300, 7'000, 8'000},
                               TimestampSource::Probe,
                               1,
                               2,
                               0},
                      ClockRow{"auto, first unstamped: capture to the end",
                               TimestampMode::Auto,
                               kLateProbe,
                               {5'000, 6'300, 6'800},
                               TimestampSource::Capture,
                               0,
                               0,
                               0},
                      ClockRow{"probe, first unstamped: probe from the first stamped",
                               TimestampMode::Probe,
                               kLateProbe,
                               {5'000, 6'300, 7'300},
                               TimestampSource::Probe,
                               0,
                               0,
                               0},
                      ClockRow{"auto, no probe at all",
                               TimestampMode::Auto,
                               {{5'000, std::nullopt}, {6'300, std::nullopt}},
                               {5'000, 6'300},
                               TimestampSource::Capture,
                               0,
                               0,
                               0},
                      ClockRow{"probe, no probe at all: capture",
                               TimestampMode::Probe,
                               {{5'000, std::nullopt}, {6'300, std::nullopt}},
                               {5'000, 6'300},
                               TimestampSource::Capture,
                               0,
                               0,
                               0},
                      ClockRow{"CRC errors counted",
                               TimestampMode::Auto,
                               kCrc,
                               {5'000, 6'000, 7'000},
                               TimestampSource::Probe,
                               0,
                               0,
                               1}),
    test::rowName<ClockRow>);

TEST(Clock, ModeNames) {
  EXPECT_EQ(timestampModeFromName("capture"), TimestampMode::Capture);
  EXPECT_EQ(timestampModeFromName("probe"), TimestampMode::Probe);
  EXPECT_EQ(timestampModeFromName("auto"), TimestampMode::Auto);
  EXPECT_EQ(timestampModeFromName("pc"), std::nullopt);
  EXPECT_STREQ(timestampSourceName(TimestampSource::Probe), "probe");
  EXPECT_STREQ(timestampSourceName(TimestampSource::Capture), "capture");
}

}  // namespace
}  // namespace ncservo
