// Where the decoder finds each axis's PDOs (decoder.hpp, docs/protocol.md §8-9) and the session's
// per-axis state (session.hpp), on frames built byte by byte.
#include "ncservo/layout/decoder.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "default_layout.hpp"
#include "frame_builder.hpp"
#include "ncservo/config/config.hpp"
#include "ncservo/layout/session.hpp"

namespace ncservo {
namespace {

using test::Bytes;
using test::concat;
using test::Dg;
using test::fmmuBlock;
using test::FrameBuilder;
using test::physical;
using test::rxPdo;
using test::smBlock;
using test::txPdo;
using test::TxValues;

constexpr std::uint32_t kBase = 0x00010000;   // logical address of the cyclic image
constexpr std::uint32_t kScwRunning = 0x406;  // SE 2, EMGON, Brake
constexpr std::uint32_t kSswRunning = 0x83;   // ServoEn, ServoRDY, PulseEnabled

// Outputs of axis k carry SSP 100+k; inputs carry ActPos 1000+k.
Bytes outputsOf(std::size_t n, std::uint32_t scw = kScwRunning) {
  Bytes out;
  for (std::size_t k = 0; k < n; ++k) {
    const Bytes rx = rxPdo(static_cast<std::int32_t>(100 + k), scw);
    out.insert(out.end(), rx.begin(), rx.end());
  }
  return out;
}
Bytes inputsOf(std::size_t n, bool written, std::uint32_t ssw = kSswRunning) {
  Bytes out;
  for (std::size_t k = 0; k < n; ++k) {
    const Bytes tx = written ? txPdo({static_cast<std::int64_t>(1000 + k), ssw}) : Bytes(40, 0);
    out.insert(out.end(), tx.begin(), tx.end());
  }
  return out;
}
// The default layout's cyclic LRW: n RxPDOs then n TxPDOs.
Dg defaultLrw(std::size_t n, std::uint16_t wkc, std::uint32_t address = kBase) {
  return Dg{ecat::kLrw, 0x80, address, concat({outputsOf(n), inputsOf(n, wkc > 0)}), wkc};
}
Bytes frameOf(std::vector<Dg> dgs) {
  FrameBuilder builder;
  for (Dg& dg : dgs) builder.add(std::move(dg));
  return builder.bytes();
}

struct Decoded {
  test::Walked walked;
  std::unique_ptr<FrameDecode> out = std::make_unique<FrameDecode>();

  std::size_t count() const { return out->axis_count; }
  const AxisPlacement& axis(std::size_t i) const { return out->axes[i]; }
  const Datagram& dg(std::size_t i) const { return walked.dg(i); }
  // The PDO words at an axis's placement, read back from the frame's bytes.
  PdoValues values(std::size_t i) const {
    PdoValues v;
    if (axis(i).has_rx) readPdo(Pdo::Rx, walked.reader(), axis(i).rx_offset, v);
    if (axis(i).has_tx) readPdo(Pdo::Tx, walked.reader(), axis(i).tx_offset, v);
    return v;
  }
};

Decoded run(Decoder& decoder, const Bytes& bytes, std::optional<std::size_t> cut = {}) {
  Decoded d{test::walk(bytes, cut.value_or(bytes.size()))};
  decoder.placeAxes(*d.walked.frame, d.walked.reader(), *d.out);
  return d;
}

DecoderOptions defaults(bool default_layout = true) {
  DecoderOptions options;
  options.default_layout = default_layout;
  return options;
}

// Checks the default-layout placements of n axes in the LRW at datagram `d`.
void expectDefaultLrw(const Decoded& got, std::size_t d, std::size_t n, bool inputs) {
  ASSERT_EQ(got.count(), n);
  const std::size_t data = got.dg(d).data_offset;
  for (std::size_t k = 0; k < n; ++k) {
    SCOPED_TRACE("axis " + std::to_string(k));
    const AxisPlacement& a = got.axis(k);
    EXPECT_EQ(a.axis, k);
    EXPECT_TRUE(a.has_rx);
    EXPECT_FALSE(a.rx_malformed);
    EXPECT_FALSE(a.tx_malformed);
    EXPECT_EQ(a.rx_datagram, d);
    EXPECT_EQ(a.rx_offset, data + 10 * k);
    EXPECT_EQ(a.has_tx, inputs);
    if (inputs) {
      EXPECT_EQ(a.tx_datagram, d);
      EXPECT_EQ(a.tx_offset, data + 10 * n + 40 * k);
    }
    const PdoValues v = got.values(k);
    EXPECT_EQ(static_cast<std::int32_t>(v.word(Word::Ssp)), static_cast<std::int32_t>(100 + k));
    if (inputs) {
      EXPECT_EQ(v.word(Word::ActPos), 1000 + k);
    }
  }
}

// ---- Default layout (docs/protocol.md §9.4) ----

TEST(DefaultLayout, LrwMasterCopyThenReturnedCopy) {
  for (std::size_t n : {1u, 2u, 5u, 29u}) {
    SCOPED_TRACE(std::to_string(n) + " axes");
    Decoder decoder(test::inferredDefault(n));
    const Decoded master = run(decoder, frameOf({defaultLrw(n, 0)}));
    EXPECT_EQ(master.out->copy, CopyKind::Master);
    expectDefaultLrw(master, 0, n, false);

    const Decoded returned =
        run(decoder, frameOf({defaultLrw(n, static_cast<std::uint16_t>(3 * n))}));
    EXPECT_EQ(returned.out->copy, CopyKind::Returned);
    expectDefaultLrw(returned, 0, n, true);

    EXPECT_EQ(decoder.source(), LayoutSource::Inferred);
    ASSERT_EQ(decoder.axes().size(), n);
    for (std::size_t k = 0; k < n; ++k) {
      EXPECT_EQ(decoder.axes()[k].index, k);
      EXPECT_EQ(decoder.axes()[k].name, "axis" + std::to_string(k));
      EXPECT_EQ(decoder.axes()[k].outputs, kBase + 10 * k);
      EXPECT_EQ(decoder.axes()[k].inputs, kBase + 10 * n + 40 * k);
    }
  }
}

TEST(DefaultLayout, LrwAfterOtherDatagramsInTheFrame) {
  Decoder decoder(test::inferredDefault(3));
  const Dg brd{ecat::kBrd, 1, physical(0, 0x0130), {0x08, 0x00}, 0};
  const Dg dc{ecat::kFrmw, 2, physical(0x03E9, 0x0910), Bytes(8, 0), 0};
  const Decoded master = run(decoder, frameOf({brd, dc, defaultLrw(3, 0)}));
  expectDefaultLrw(master, 2, 3, false);
  Dg brd_back = brd;
  brd_back.wkc = 3;
  const Decoded returned = run(decoder, frameOf({brd_back, dc, defaultLrw(3, 9)}));
  EXPECT_EQ(returned.out->copy, CopyKind::Returned);
  expectDefaultLrw(returned, 2, 3, true);
}

TEST(DefaultLayout, ReturnedCopyWithWkcZeroHasNoInputs) {
  Decoder decoder(test::inferredDefault(2));
  const Bytes master = frameOf({defaultLrw(2, 0)});
  EXPECT_EQ(run(decoder, master).out->copy, CopyKind::Master);
  const Decoded returned = run(decoder, master);  // identical list, every WKC 0
  EXPECT_EQ(returned.out->copy, CopyKind::Returned);
  expectDefaultLrw(returned, 0, 2, false);
  // The next identical frame starts a new cycle.
  EXPECT_EQ(run(decoder, master).out->copy, CopyKind::Master);
}

TEST(DefaultLayout, LwrAndLrdInOneFrame) {
  for (bool lrd_first : {false, true}) {
    SCOPED_TRACE(lrd_first ? "LRD first" : "LWR first");
    const std::size_t n = 4;
    DecoderOptions options;
    test::appendDefaultAxes(options, n, kBase, 0x00020000);
    Decoder decoder(options);
    auto frame = [&](std::uint16_t wkc) {
      const Dg lwr{ecat::kLwr, 1, kBase, outputsOf(n), wkc};
      const Dg lrd{ecat::kLrd, 2, 0x00020000, inputsOf(n, wkc > 0), wkc};
      return lrd_first ? frameOf({lrd, lwr}) : frameOf({lwr, lrd});
    };
    const std::size_t out_dg = lrd_first ? 1 : 0, in_dg = lrd_first ? 0 : 1;
    for (std::uint16_t wkc : {0, 4}) {
      SCOPED_TRACE("WKC " + std::to_string(wkc));
      const Decoded got = run(decoder, frame(wkc));
      EXPECT_EQ(got.out->copy, wkc == 0 ? CopyKind::Master : CopyKind::Returned);
      ASSERT_EQ(got.count(), n);
      for (std::size_t k = 0; k < n; ++k) {
        const AxisPlacement& a = got.axis(k);
        EXPECT_EQ(a.axis, k);
        EXPECT_TRUE(a.has_rx);
        EXPECT_EQ(a.rx_datagram, out_dg);
        EXPECT_EQ(a.rx_offset, got.dg(out_dg).data_offset + 10 * k);
        EXPECT_EQ(a.has_tx, wkc > 0);
        EXPECT_EQ(a.tx_datagram, in_dg);
        EXPECT_EQ(a.tx_offset, got.dg(in_dg).data_offset + 40 * k);
        EXPECT_EQ(got.values(k).word(Word::Ssp), 100 + k);
        if (wkc > 0) {
          EXPECT_EQ(got.values(k).word(Word::ActPos), 1000 + k);
        }
      }
    }
    EXPECT_EQ(decoder.axes()[1].inputs, 0x00020000u + 40);
  }
}

TEST(DefaultLayout, FirstSightFrameCutBeforeTheWkcIsTaken) {
  Decoder decoder(test::inferredDefault(2));
  const Bytes returned = frameOf({defaultLrw(2, 5)});
  const Decoded got = run(decoder, returned, returned.size() - 1);  // half of the WKC
  ASSERT_EQ(got.walked.frame->status, WalkStatus::Truncated);
  ASSERT_EQ(got.count(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_TRUE(got.axis(k).has_rx);
    EXPECT_FALSE(got.axis(k).has_tx) << "no WKC, no valid inputs";
    EXPECT_FALSE(got.axis(k).tx_malformed);
  }
}

// docs/protocol.md §9.4: the default layout applies to datagrams that repeat with the same command,
// address and length in consecutive cycles; decoder.cpp's comment on placeDefault says "A
// datagram is taken once it repeats". A capture holding only returned copies whose WKC is
// persistently not 3n (e.g. 2: one slave took its outputs, none wrote inputs, §8) repeats the
// same LRW every cycle, so from the second cycle on its axes should decode (and COM-001 fire).

TEST(DefaultLayout, SwitchedOff) {
  Decoder decoder(defaults(false));
  EXPECT_EQ(run(decoder, frameOf({defaultLrw(2, 0)})).count(), 0u);
  EXPECT_EQ(run(decoder, frameOf({defaultLrw(2, 6)})).count(), 0u);
  EXPECT_EQ(decoder.source(), LayoutSource::None);
}

TEST(DefaultLayout, TwoCyclicDatagramsNumberTheirAxesInOrderOfFirstSight) {
  DecoderOptions options = test::inferredDefault(2);
  test::appendDefaultAxes(options, 3, 0x20000, 0x20000 + 30);
  Decoder decoder(options);
  const Decoded got = run(decoder, frameOf({defaultLrw(2, 0, kBase), defaultLrw(3, 0, 0x20000)}));
  ASSERT_EQ(got.count(), 5u);
  for (std::size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(got.axis(k).axis, k);
    EXPECT_EQ(got.axis(k).rx_datagram, k < 2 ? 0 : 1);
  }
  EXPECT_EQ(decoder.axes()[2].outputs, 0x20000u);
}

// ---- Start-up (docs/protocol.md §9.3, §9.4: no default layout when it shows no servo) ----

struct StartupCase {
  const char* name;
  std::vector<Dg> writes;  // the start-up frame
  bool no_servo;
};
std::vector<StartupCase> startupCases() {
  const std::uint16_t a = 0x03E9, b = 0x03EA;
  auto sm2 = [](std::uint8_t cmd, std::uint16_t adp, std::uint16_t length) {
    return Dg{cmd, 1, physical(adp, 0x0810), smBlock(0x1100, length, 0x64), 0};
  };
  auto sm3 = [](std::uint8_t cmd, std::uint16_t adp, std::uint16_t length) {
    return Dg{cmd, 2, physical(adp, 0x0818), smBlock(0x1180, length, 0x20), 0};
  };
  auto both = [](std::uint8_t cmd, std::uint16_t adp, std::uint16_t l2, std::uint16_t l3) {
    return Dg{cmd, 3, physical(adp, 0x0810),
              concat({smBlock(0x1100, l2, 0x64), smBlock(0x1180, l3, 0x20)}), 0};
  };
  return {
      {"FPWR SM2=6, SM3=6", {sm2(ecat::kFpwr, a, 6), sm3(ecat::kFpwr, a, 6)}, true},
      {"FPWR SM2=10, SM3=40", {sm2(ecat::kFpwr, a, 10), sm3(ecat::kFpwr, a, 40)}, false},
      {"FPWR SM2=10 only", {sm2(ecat::kFpwr, a, 10)}, true},
      {"FPWR SM2=40, SM3=10 (swapped)", {sm2(ecat::kFpwr, a, 40), sm3(ecat::kFpwr, a, 10)}, true},
      {"one 16-byte FPWR, 6 and 6", {both(ecat::kFpwr, a, 6, 6)}, true},
      {"one 16-byte FPWR, 10 and 40", {both(ecat::kFpwr, a, 10, 40)}, false},
      {"APWR SM2=6, SM3=6", {sm2(ecat::kApwr, 0, 6), sm3(ecat::kApwr, 0, 6)}, true},
      {"APWR SM2=10, SM3=40", {sm2(ecat::kApwr, 0xFFFF, 10), sm3(ecat::kApwr, 0xFFFF, 40)}, false},
      {"a servo among other slaves",
       {both(ecat::kFpwr, a, 6, 6), both(ecat::kFpwr, b, 10, 40)},
       false},
      {"lengths of zero configure nothing", {both(ecat::kFpwr, a, 0, 0)}, false},
      {"FPRD of the SM registers is not a write",
       {Dg{ecat::kFprd, 1, physical(a, 0x0810),
           concat({smBlock(0x1100, 6, 0x64), smBlock(0x1180, 6, 0x20)}), 1}},
       false},
      {"other registers", {Dg{ecat::kFpwr, 1, physical(a, 0x0600), Bytes(16, 6), 0}}, false},
  };
}

TEST(StartupLayout, SyncManagerLengthsDecideWhetherTheDefaultLayoutApplies) {
  for (const StartupCase& c : startupCases()) {
    SCOPED_TRACE(c.name);
    Decoder decoder(defaults());
    run(decoder, frameOf(c.writes));
    EXPECT_EQ(decoder.startupShowsNoServo(), c.no_servo);
  }
}

TEST(StartupLayout, SyncManagerWriteCutShortCountsOnlyTheCapturedLengths) {
  Decoder decoder(defaults());
  // SM2 block complete, SM3's length field cut off by the capture.
  const Bytes frame =
      frameOf({Dg{ecat::kFpwr, 1, physical(0x03E9, 0x0810),
                  concat({smBlock(0x1100, 6, 0x64), smBlock(0x1180, 6, 0x20)}), 0}});
  const std::size_t cut = 14 + 2 + 10 + 8 + 3;  // one byte of SM3's length
  run(decoder, frame, cut);
  EXPECT_TRUE(decoder.startupShowsNoServo());  // SM2 = 6 was seen and is not a servo's
}

// ---- Explicit configuration (docs/protocol.md §9.1) ----

AxisConfig logicalAxis(const char* name, std::uint32_t outputs, std::uint32_t inputs) {
  AxisConfig axis;
  axis.name = name;
  axis.outputs = outputs;
  axis.inputs = inputs;
  return axis;
}
AxisConfig stationAxis(const char* name, std::uint16_t station, std::uint16_t sm_outputs,
                       std::uint16_t sm_inputs) {
  AxisConfig axis;
  axis.name = name;
  axis.station = station;
  axis.sm_outputs = sm_outputs;
  axis.sm_inputs = sm_inputs;
  return axis;
}
DecoderOptions configured(std::vector<AxisConfig> axes) {
  DecoderOptions options;
  options.axes = std::move(axes);
  return options;
}

// One row per frame shape; every row uses the two axes below.
//   X: outputs 0x10000, inputs 0x10028      Y: station 0x03EA, SM2 0x1100, SM3 0x1180
struct Expect {
  bool present;
  bool has_rx;
  bool rx_malformed;
  std::uint16_t rx_datagram;
  std::size_t rx_data;  // offset into that datagram's data
  bool has_tx;
  bool tx_malformed;
  std::uint16_t tx_datagram;
  std::size_t tx_data;
};
struct ConfigCase {
  const char* name;
  std::vector<Dg> dgs;
  Expect x;
  Expect y;
};
constexpr Expect kAbsent{false, false, false, 0, 0, false, false, 0, 0};

std::vector<ConfigCase> configCases() {
  const Bytes x_rx = rxPdo(100, kScwRunning), x_tx = txPdo({1000, kSswRunning});
  const Bytes y_rx = rxPdo(101, kScwRunning), y_tx = txPdo({1001, kSswRunning});
  auto filler = [](std::size_t n) { return Bytes(n, 0xEE); };
  return {
      {"LRW covering X, master",
       {Dg{ecat::kLrw, 1, 0x10000, concat({x_rx, filler(30), Bytes(40, 0)}), 0}},
       {true, true, false, 0, 0, false, false, 0, 0x28},
       kAbsent},
      {"LRW covering X, returned",
       {Dg{ecat::kLrw, 1, 0x10000, concat({x_rx, filler(30), x_tx}), 3}},
       {true, true, false, 0, 0, true, false, 0, 0x28},
       kAbsent},
      {"LRW starting before X",
       {Dg{ecat::kLrw, 1, 0xFFF0, concat({filler(16), x_rx, filler(30), x_tx}), 3}},
       {true, true, false, 0, 16, true, false, 0, 16 + 0x28},
       kAbsent},
      {"LWR and LRD separately",
       {Dg{ecat::kLwr, 1, 0x10000, x_rx, 1}, Dg{ecat::kLrd, 2, 0x10028, x_tx, 1}},
       {true, true, false, 0, 0, true, false, 1, 0},
       kAbsent},
      {"LRD over X's outputs reads no outputs",
       {Dg{ecat::kLrd, 1, 0x10000, concat({x_rx, filler(30), x_tx}), 1}},
       {true, false, false, 0, 0, true, false, 0, 0x28},
       kAbsent},
      {"TxPDO straddles the datagram end",
       {Dg{ecat::kLrw, 1, 0x10000, concat({x_rx, filler(30), Bytes(8, 0)}), 3}},
       {true, true, false, 0, 0, false, true, 0, 48},
       kAbsent},
      {"RxPDO straddles the datagram start",
       {Dg{ecat::kLrw, 1, 0x10004, concat({Bytes(6, 0), filler(30), x_tx}), 3}},
       {true, false, true, 0, 76, true, false, 0, 0x24},
       kAbsent},
      {"LRW elsewhere", {Dg{ecat::kLrw, 1, 0x20000, Bytes(80, 0), 3}}, kAbsent, kAbsent},
      {"FPWR and FPRD of Y, master",
       {Dg{ecat::kFpwr, 1, physical(0x03EA, 0x1100), y_rx, 0},
        Dg{ecat::kFprd, 2, physical(0x03EA, 0x1180), Bytes(40, 0), 0}},
       kAbsent,
       {true, true, false, 0, 0, false, false, 1, 0}},
      {"FPWR and FPRD of Y, returned",
       {Dg{ecat::kFpwr, 1, physical(0x03EA, 0x1100), y_rx, 1},
        Dg{ecat::kFprd, 2, physical(0x03EA, 0x1180), y_tx, 1}},
       kAbsent,
       {true, true, false, 0, 0, true, false, 1, 0}},
      {"FPRW over both of Y's sync managers",
       {Dg{ecat::kFprw, 1, physical(0x03EA, 0x1100), concat({y_rx, filler(0x76), y_tx}), 3}},
       kAbsent,
       {true, true, false, 0, 0, true, false, 0, 0x80}},
      {"FPWR and FPRD of another station",
       {Dg{ecat::kFpwr, 1, physical(0x03E9, 0x1100), y_rx, 1},
        Dg{ecat::kFprd, 2, physical(0x03E9, 0x1180), y_tx, 1}},
       kAbsent,
       kAbsent},
      {"LRW at Y's SM addresses is not Y",
       {Dg{ecat::kLrw, 1, 0x1100, Bytes(0x100, 0), 3}},
       kAbsent,
       kAbsent},
      {"both axes in one frame",
       {Dg{ecat::kLrw, 1, 0x10000, concat({x_rx, filler(30), x_tx}), 3},
        Dg{ecat::kFpwr, 2, physical(0x03EA, 0x1100), y_rx, 1},
        Dg{ecat::kFprd, 3, physical(0x03EA, 0x1180), y_tx, 1}},
       {true, true, false, 0, 0, true, false, 0, 0x28},
       {true, true, false, 1, 0, true, false, 2, 0}},
  };
}

void expectPlacement(const Decoded& got, std::uint16_t axis, const Expect& e) {
  const AxisPlacement* found = nullptr;
  for (std::size_t i = 0; i < got.count(); ++i) {
    if (got.axis(i).axis == axis) found = &got.axis(i);
  }
  ASSERT_EQ(found != nullptr, e.present);
  if (!e.present) return;
  EXPECT_EQ(found->has_rx, e.has_rx);
  EXPECT_EQ(found->rx_malformed, e.rx_malformed);
  if (e.has_rx || e.rx_malformed) {
    EXPECT_EQ(found->rx_datagram, e.rx_datagram);
    EXPECT_EQ(found->rx_offset, got.dg(e.rx_datagram).data_offset + e.rx_data);
  }
  EXPECT_EQ(found->has_tx, e.has_tx);
  EXPECT_EQ(found->tx_malformed, e.tx_malformed);
  if (e.has_tx || e.tx_malformed) {
    EXPECT_EQ(found->tx_datagram, e.tx_datagram);
    EXPECT_EQ(found->tx_offset, got.dg(e.tx_datagram).data_offset + e.tx_data);
  }
  const PdoValues v = got.values(static_cast<std::size_t>(found - got.out->axes.data()));
  if (e.has_rx) {
    EXPECT_EQ(v.word(Word::Ssp), 100u + axis);
  }
  if (e.has_tx) {
    EXPECT_EQ(v.word(Word::ActPos), 1000u + axis);
  }
}

TEST(ConfiguredLayout, LogicalAndStationAxes) {
  for (const ConfigCase& c : configCases()) {
    SCOPED_TRACE(c.name);
    Decoder decoder(
        configured({logicalAxis("X", 0x10000, 0x10028), stationAxis("Y", 0x03EA, 0x1100, 0x1180)}));
    const Decoded got = run(decoder, frameOf(c.dgs));
    {
      SCOPED_TRACE("axis X");
      expectPlacement(got, 0, c.x);
    }
    {
      SCOPED_TRACE("axis Y");
      expectPlacement(got, 1, c.y);
    }
    for (std::size_t i = 1; i < got.count(); ++i) {
      EXPECT_LT(got.axis(i - 1).axis, got.axis(i).axis) << "placements in axis order";
    }
  }
}

TEST(ConfiguredLayout, AxesAndSourceComeFromTheConfiguration) {
  AxisConfig unnamed = logicalAxis("", 0x30000, 0x3000A);
  Decoder decoder(configured(
      {logicalAxis("X", 0x10000, 0x10028), stationAxis("Y", 0x03EA, 0x1100, 0x1180), unnamed}));
  EXPECT_EQ(decoder.source(), LayoutSource::Config);
  ASSERT_EQ(decoder.axes().size(), 3u);
  EXPECT_EQ(decoder.axes()[0].name, "X");
  EXPECT_TRUE(decoder.axes()[0].logical);
  EXPECT_EQ(decoder.axes()[0].outputs, 0x10000u);
  EXPECT_EQ(decoder.axes()[0].inputs, 0x10028u);
  EXPECT_EQ(decoder.axes()[1].name, "Y");
  EXPECT_FALSE(decoder.axes()[1].logical);
  EXPECT_EQ(decoder.axes()[1].station, 0x03EA);
  EXPECT_EQ(decoder.axes()[1].sm_outputs, 0x1100u);
  EXPECT_EQ(decoder.axes()[1].sm_inputs, 0x1180u);
  EXPECT_EQ(decoder.axes()[2].name, "axis2");
  // A configuration overrides the default layout: a default-shaped LRW elsewhere is not decoded.
  EXPECT_EQ(run(decoder, frameOf({defaultLrw(2, 0, 0x50000)})).count(), 0u);
  EXPECT_EQ(decoder.source(), LayoutSource::Config);
}

TEST(ConfiguredLayout, AxisWithOnlyOutputs) {
  AxisConfig axis;
  axis.name = "out-only";
  axis.outputs = 0x10000;
  Decoder decoder(configured({axis}));
  const Decoded got = run(decoder, frameOf({defaultLrw(1, 3)}));
  ASSERT_EQ(got.count(), 1u);
  EXPECT_TRUE(got.axis(0).has_rx);
  EXPECT_FALSE(got.axis(0).has_tx);
  EXPECT_FALSE(got.axis(0).tx_malformed);
}

// ---- Truncated frames ----

TEST(Truncation, ReturnedCopyCutInsideAnAxisTxPdo) {
  const std::size_t n = 3;
  Decoder decoder(test::inferredDefault(n));
  run(decoder, frameOf({defaultLrw(n, 0)}));  // the master's copy makes the datagram known
  const Bytes returned = frameOf({defaultLrw(n, 9)});
  const std::size_t data = test::kChainOffset + ecat::kDatagramHeaderSize;
  const std::size_t cut = data + 10 * n + 40 * 1 + 20;  // half of axis 1's TxPDO
  const Decoded got = run(decoder, returned, cut);
  ASSERT_EQ(got.walked.frame->status, WalkStatus::Truncated);
  EXPECT_EQ(got.out->copy, CopyKind::Returned);
  ASSERT_EQ(got.count(), n);
  for (std::size_t k = 0; k < n; ++k) {
    SCOPED_TRACE("axis " + std::to_string(k));
    EXPECT_TRUE(got.axis(k).has_rx);
    EXPECT_FALSE(got.axis(k).rx_malformed);
    EXPECT_EQ(got.axis(k).tx_offset, data + 10 * n + 40 * k);
    EXPECT_EQ(got.axis(k).tx_malformed, k >= 1) << "only TxPDOs cut by the capture are malformed";
    // The WKC was cut off too: it cannot say the inputs are invalid, and axis 0's were captured.
    EXPECT_EQ(got.axis(k).has_tx, k == 0);
  }
}

TEST(Truncation, MasterCopyCutInsideAnAxisRxPdo) {
  Decoder decoder(test::inferredDefault(3));
  const Bytes master = frameOf({defaultLrw(3, 0)});
  run(decoder, master);
  run(decoder, frameOf({defaultLrw(3, 9)}));
  const std::size_t data = test::kChainOffset + ecat::kDatagramHeaderSize;
  const Decoded got = run(decoder, master, data + 15);  // half of axis 1's RxPDO
  ASSERT_EQ(got.count(), 3u);
  EXPECT_TRUE(got.axis(0).has_rx);
  EXPECT_FALSE(got.axis(0).rx_malformed);
  for (std::size_t k = 1; k < 3; ++k) {
    EXPECT_FALSE(got.axis(k).has_rx);
    EXPECT_TRUE(got.axis(k).rx_malformed);
    EXPECT_FALSE(got.axis(k).tx_malformed) << "a master's copy carries no inputs";
  }
}

TEST(Truncation, EveryCutOfACyclicFrameDecodesWithoutOverreads) {
  const Bytes master = frameOf({defaultLrw(4, 0)});
  const Bytes returned = frameOf({defaultLrw(4, 12)});
  for (std::size_t cut = 0; cut < returned.size(); ++cut) {
    SCOPED_TRACE("cut at " + std::to_string(cut));
    Decoder decoder(test::inferredDefault(4));
    run(decoder, master);
    const Decoded got = run(decoder, returned, cut);
    for (std::size_t k = 0; k < got.count(); ++k) {
      const AxisPlacement& a = got.axis(k);
      if (a.has_rx) {
        EXPECT_LE(a.rx_offset + 10, cut);
      }
      if (a.has_tx) {
        EXPECT_LE(a.tx_offset + 40, cut);
      }
      got.values(k);  // reads through the placements: ASan checks the bounds
    }
  }
}

// ---- Session: per-axis values and state across copies ----

struct SessionStep {
  const char* name;
  std::uint32_t scw;
  std::uint32_t ssw;
  std::uint16_t wkc;  // 0: master's copy (or a returned copy without inputs)
  CopyKind copy;
  bool has_tx;
  std::optional<DriveState> state;
};
const SessionStep kSessionSteps[] = {
    {"master, nothing returned yet", kScwRunning, 0, 0, CopyKind::Master, false, std::nullopt},
    {"returned, running", kScwRunning, kSswRunning, 3, CopyKind::Returned, true,
     DriveState::ControlActive},
    {"master, EMGON 0: state from the last inputs", 0x402, 0, 0, CopyKind::Master, false,
     DriveState::DriveStop},
    {"returned, drive disabled", 0x402, 0x2, 3, CopyKind::Returned, true,
     DriveState::ReadyToSwitchOn},
    {"master, EMGON 1: the newest inputs count", kScwRunning, 0, 0, CopyKind::Master, false,
     DriveState::ReadyToSwitchOn},
    {"returned, WKC 0 keeps the last inputs", kScwRunning, 0, 0, CopyKind::Returned, false,
     DriveState::ReadyToSwitchOn},
    {"master, brake 0", 0x006, 0, 0, CopyKind::Master, false, DriveState::ReadyToSwitchOn},
    {"returned, enabled", 0x006, 0x81, 3, CopyKind::Returned, true, DriveState::DriveStop},
    {"master, running again", kScwRunning, 0, 0, CopyKind::Master, false,
     DriveState::ControlActive},
};

TEST(Session, StateOfAMasterCopyComesFromTheLatestReturnedInputs) {
  Session session(test::inferredDefault(1));
  for (const SessionStep& step : kSessionSteps) {
    SCOPED_TRACE(step.name);
    const Dg lrw{
        ecat::kLrw, 0x80, kBase,
        concat({rxPdo(100, step.scw), step.wkc > 0 ? txPdo({1000, step.ssw}) : Bytes(40, 0)}),
        step.wkc};
    const test::Walked walked = test::walk(frameOf({lrw}));
    const FrameView& view = session.onFrame(*walked.frame, walked.reader());
    EXPECT_EQ(view.copy, step.copy);
    ASSERT_EQ(view.axis_count, 1u);
    const AxisFrameView& axis = view.axes[0];
    EXPECT_TRUE(axis.values.has_rx);
    EXPECT_EQ(axis.values.scw(), step.scw);
    EXPECT_EQ(axis.values.has_tx, step.has_tx);
    if (step.has_tx) {
      EXPECT_EQ(axis.values.ssw(), step.ssw);
    }
    EXPECT_EQ(axis.state, step.state);
  }
}

// ---- CycleRows: one row per axis and cycle (docs/protocol.md §8) ----

// A frame for CycleRows: its copy, and per axis whether outputs and inputs are present.
struct RowFrame {
  CopyKind copy;
  std::vector<std::uint16_t> axes;
  bool has_rx = true;
  bool has_tx = false;
};
// A row as "frame:axis:rx-scw/tx" ("-" for no outputs, "tx" when inputs are present).
struct CycleRowsCase {
  const char* name;
  std::vector<RowFrame> frames;
  std::vector<std::string> rows;  // in the order emitted; the end of the capture flushes
};

std::string describeRow(const CycleRow& row) {
  return std::to_string(row.frame) + ":" + std::to_string(row.axis) + ":" +
         (row.values.has_rx ? std::to_string(row.values.scw()) : std::string("-")) +
         (row.values.has_tx ? "/tx" : "");
}

TEST(CycleRows, PairsMasterOutputsWithReturnedInputs) {
  const CopyKind M = CopyKind::Master, R = CopyKind::Returned;
  const CycleRowsCase cases[] = {
      {"master then returned: one row at the returned copy, the master's outputs",
       {{M, {0, 1}}, {R, {0, 1}, true, true}},
       {"2:0:1/tx", "2:1:1/tx"}},
      {"a master copy not returned is a row of its own",
       {{M, {0}}, {M, {0}}, {R, {0}, true, true}},
       {"1:0:1", "3:0:2/tx"}},
      {"a returned copy without a master copy", {{R, {3}, true, true}}, {"1:3:1/tx"}},
      {"the last master copy is flushed at the end",
       {{M, {0}}, {R, {0}, true, true}, {M, {0}}},
       {"2:0:1/tx", "3:0:3"}},
      {"a master copy without outputs waits for the end; the returned copy keeps its own",
       {{M, {0}, false}, {R, {0}, true, true}},
       {"2:0:2/tx", "1:0:-"}},
      {"axes pair separately",
       {{M, {0}}, {M, {1}}, {R, {1}, true, true}, {R, {0}, true, true}},
       {"3:1:2/tx", "4:0:1/tx"}},
  };
  for (const CycleRowsCase& c : cases) {
    SCOPED_TRACE(c.name);
    CycleRows pairer;
    std::vector<CycleRow> rows;
    std::uint64_t number = 0;
    for (const RowFrame& f : c.frames) {
      ++number;
      FrameView view;
      view.copy = f.copy;
      view.axis_count = f.axes.size();
      for (std::size_t i = 0; i < f.axes.size(); ++i) {
        AxisFrameView& axis = view.axes[i];
        axis.placement.axis = f.axes[i];
        axis.values.has_rx = f.has_rx;
        axis.values.has_tx = f.has_tx;
        // The SCW names the frame the outputs came from.
        if (f.has_rx) axis.values.raw[static_cast<std::size_t>(Word::Scw)] = number;
      }
      pairer.onFrame(number, static_cast<std::int64_t>(number) * 1000, view, rows);
    }
    pairer.finish(rows);
    std::vector<std::string> got;
    for (const CycleRow& row : rows) got.push_back(describeRow(row));
    EXPECT_EQ(got, c.rows);
  }
}

// ---- Layout from the start-up, and the precedence of the sources (docs/protocol.md §9) ----

// A servo's start-up at `adp` (a station or an alias): SM2/SM3 of 10/40 bytes and, when
// `logical` is given, FMMUs mapping them there (outputs, then inputs).
std::vector<Bytes> servoStartup(std::uint16_t adp, std::optional<std::uint32_t> logical) {
  std::vector<Bytes> frames;
  frames.push_back(
      frameOf({Dg{ecat::kFpwr, 1, physical(adp, 0x0810),
                  concat({smBlock(0x1100, 10, 0x64), smBlock(0x1180, 40, 0x20)}), 0}}));
  if (logical) {
    frames.push_back(frameOf(
        {Dg{ecat::kFpwr, 2, physical(adp, 0x0600),
            concat({fmmuBlock(*logical, 10, 0x1100, 2), fmmuBlock(*logical + 10, 40, 0x1180, 1)}),
            0}}));
  }
  return frames;
}

TEST(LearnedLayout, FmmusGiveTheLogicalAddresses) {
  Decoder decoder(defaults());
  for (const Bytes& f : servoStartup(0x03E9, 0x00020000)) run(decoder, f);
  ASSERT_EQ(decoder.axes().size(), 1u);
  EXPECT_EQ(decoder.source(), LayoutSource::Startup);
  EXPECT_TRUE(decoder.axes()[0].logical);
  EXPECT_EQ(decoder.axes()[0].outputs, 0x00020000u);
  EXPECT_EQ(decoder.axes()[0].inputs, 0x0002000Au);
  EXPECT_EQ(decoder.axes()[0].station, 0x03E9);
  // its LRW is placed by the learned addresses, not by the default layout
  const Decoded got =
      run(decoder,
          frameOf({Dg{ecat::kLrw, 9, 0x00020000, concat({outputsOf(1), inputsOf(1, true)}), 3}}));
  ASSERT_EQ(got.count(), 1u);
  EXPECT_TRUE(got.axis(0).has_tx);
}

TEST(LearnedLayout, NoFmmuButFprdFpwrAtTheSmAddressesIsPhysicalExchange) {
  Decoder decoder(defaults());
  for (const Bytes& f : servoStartup(0x03E9, std::nullopt)) run(decoder, f);
  EXPECT_TRUE(decoder.axes().empty());  // not placed before its process data is exchanged
  const Bytes exchange =
      frameOf({Dg{ecat::kFpwr, 3, physical(0x03E9, 0x1100), outputsOf(1), 0},
               Dg{ecat::kFprd, 4, physical(0x03E9, 0x1180), inputsOf(1, false), 0}});
  run(decoder, exchange);
  ASSERT_EQ(decoder.axes().size(), 1u);
  EXPECT_FALSE(decoder.axes()[0].logical);
  EXPECT_EQ(decoder.axes()[0].sm_outputs, 0x1100u);
  EXPECT_EQ(decoder.axes()[0].sm_inputs, 0x1180u);
  EXPECT_EQ(decoder.axes()[0].station, 0x03E9);
  EXPECT_EQ(run(decoder, exchange).count(), 1u);
}

TEST(LearnedLayout, AStationAliasReachesItsSlave) {
  Decoder decoder(defaults());
  // ring position 0 gets station 0x03E9; it reads back alias 0x0100; the start-up then
  // configures it by its alias
  Bytes station;
  test::putLe(station, 0x03E9, 2);
  run(decoder, frameOf({Dg{ecat::kApwr, 1, physical(0, 0x0010), station, 0}}));
  run(decoder, frameOf({Dg{ecat::kFprd, 2, physical(0x03E9, 0x0012), Bytes(2, 0), 0}}));
  run(decoder, frameOf({Dg{ecat::kFprd, 2, physical(0x03E9, 0x0012), Bytes{0x00, 0x01}, 1}}));
  for (const Bytes& f : servoStartup(0x0100, 0x00030000)) run(decoder, f);
  ASSERT_EQ(decoder.axes().size(), 1u);
  EXPECT_EQ(decoder.axes()[0].station, 0x03E9);
  EXPECT_EQ(decoder.axes()[0].outputs, 0x00030000u);
  ASSERT_EQ(decoder.learner().slaves().size(), 1u);
  EXPECT_EQ(decoder.learner().slaves()[0].position, 0);
}

struct PrecedenceCase {
  const char* name;
  bool config;
  bool eni;
  bool startup;
  LayoutSource source;
  std::uint32_t outputs;  // of axis 0
};
TEST(LayoutPrecedence, ConfigurationThenEniThenStartupThenDefault) {
  AxisConfig from_config;
  from_config.name = "C";
  from_config.outputs = 0x00050000;
  from_config.inputs = 0x0005000A;
  AxisConfig from_eni;
  from_eni.name = "E";
  from_eni.outputs = 0x00060000;
  from_eni.inputs = 0x0006000A;
  Config config;
  config.axes = {from_config};
  const std::vector<AxisConfig> eni{from_eni};
  const PrecedenceCase cases[] = {
      {"configuration over everything", true, true, true, LayoutSource::Config, 0x00050000},
      {"configuration over the start-up", true, false, true, LayoutSource::Config, 0x00050000},
      {"ENI over the start-up", false, true, true, LayoutSource::Eni, 0x00060000},
      {"start-up over the default", false, false, true, LayoutSource::Startup, 0x00020000},
  };
  for (const PrecedenceCase& c : cases) {
    SCOPED_TRACE(c.name);
    Decoder decoder(layoutOptions(c.config ? &config : nullptr, c.eni ? &eni : nullptr, true));
    if (c.startup) {
      for (const Bytes& f : servoStartup(0x03E9, 0x00020000)) run(decoder, f);
    } else {
      run(decoder, frameOf({defaultLrw(1, 0)}));
      run(decoder, frameOf({defaultLrw(1, 3)}));
    }
    EXPECT_EQ(decoder.source(), c.source);
    ASSERT_FALSE(decoder.axes().empty());
    EXPECT_EQ(decoder.axes()[0].outputs, c.outputs);
  }
}

// docs/protocol.md §9.4: the default layout applies unless the user (--no-default-layout, a plugin
// preference) or the configuration (default_layout = false) rules it out; §9.1-9.2: a
// configuration's axes come before an ENI's, and a configuration without axes gives none.
struct LayoutOptionsCase {
  const char* name;
  bool config;                                  // a configuration file was given
  bool config_axes;                             // ... with axes
  bool config_default_layout;                   // ... and its default_layout
  bool eni;                                     // an ENI with axes was given
  bool allow_default_layout;                    // the user's choice
  bool default_layout;                          // expected
  std::optional<LayoutSource> explicit_source;  // expected; nullopt: no explicit axes
};
const LayoutOptionsCase kLayoutOptionsCases[] = {
    {"nothing given", false, false, true, false, true, true, std::nullopt},
    {"user rules the default out", false, false, true, false, false, false, std::nullopt},
    {"configuration without axes keeps the default", true, false, true, false, true, true,
     std::nullopt},
    {"configuration rules the default out", true, false, false, false, true, false, std::nullopt},
    {"configuration allows, user rules out", true, false, true, false, false, false, std::nullopt},
    {"configuration's axes", true, true, true, false, true, true, LayoutSource::Config},
    {"configuration's axes over the ENI's", true, true, true, true, true, true,
     LayoutSource::Config},
    {"ENI when the configuration has no axes", true, false, false, true, true, false,
     LayoutSource::Eni},
    {"ENI alone", false, false, true, true, false, false, LayoutSource::Eni},
};

TEST(LayoutOptions, SourcesAndTheDefaultLayoutDecision) {
  AxisConfig axis;
  axis.name = "a";
  axis.outputs = 0x00050000;
  axis.inputs = 0x0005000A;
  const std::vector<AxisConfig> eni{axis};
  for (const LayoutOptionsCase& c : kLayoutOptionsCases) {
    SCOPED_TRACE(c.name);
    Config config;
    config.default_layout = c.config_default_layout;
    if (c.config_axes) config.axes = {axis};
    const DecoderOptions options =
        layoutOptions(c.config ? &config : nullptr, c.eni ? &eni : nullptr, c.allow_default_layout);
    EXPECT_EQ(options.default_layout, c.default_layout);
    EXPECT_EQ(options.axes.empty(), !c.explicit_source.has_value());
    if (c.explicit_source) {
      EXPECT_EQ(options.explicit_source, *c.explicit_source);
    }
  }
}

}  // namespace
}  // namespace ncservo
