// PDOs read from bytes and the values of the field table's rows (pdo.hpp, docs/protocol.md §1-5).
#include "ncservo/protocol/pdo.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "frame_builder.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

using test::Bytes;
using test::rxPdo;
using test::txPdo;
using test::TxValues;

using Kind = FieldValue::Kind;

// Reads a 10-byte buffer as the RxPDO or a 40-byte one as the TxPDO.
PdoValues valuesOf(const Bytes& pdo) {
  PdoValues values;
  const Pdo which = pdo.size() == kRxPdoSize ? Pdo::Rx : Pdo::Tx;
  EXPECT_TRUE(readPdo(which, ByteReader(pdo.data(), pdo.size()), 0, values));
  return values;
}

std::uint64_t bitsOf(float f) {
  std::uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  return bits;
}

TEST(ReadPdo, RxFromLittleEndianBytes) {
  // Two bytes of something else, then SSP -1000, SCW 0x00000406, ext code -2, then a trailer.
  const Bytes bytes{0xAA, 0xBB, 0x18, 0xFC, 0xFF, 0xFF, 0x06, 0x04, 0x00, 0x00, 0xFE, 0xFF, 0xCC};
  PdoValues values;
  ASSERT_TRUE(readPdo(Pdo::Rx, ByteReader(bytes.data(), bytes.size()), 2, values));
  EXPECT_TRUE(values.has_rx);
  EXPECT_FALSE(values.has_tx);
  EXPECT_EQ(values.word(Word::Ssp), 0xFFFFFC18u);  // raw, zero-extended
  EXPECT_EQ(values.scw(), 0x406u);
  EXPECT_EQ(values.word(Word::ExtCode), 0xFFFEu);
  EXPECT_EQ(fieldValue(field("ncservo.ssp"), values).i, -1000);
  EXPECT_EQ(fieldValue(field("ncservo.ext_code"), values).i, -2);
}

TEST(ReadPdo, TxFromLittleEndianBytes) {
  const Bytes bytes{
      0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08,  // ActPos 0x0807060504030201
      0x83, 0x00, 0x00, 0x00,                          // SSW 0x83
      0x01, 0x00, 0x08, 0x00,                          // SEW 0x00080001
      0x03, 0x00, 0x00, 0x00,                          // message code 3
      0x00, 0x00, 0x0C, 0x44,                          // message data 560.0f
      0x00, 0x00, 0x80, 0x3F,                          // extra data 1: 1.0f
      0x00, 0x00, 0x00, 0xC0,                          // extra data 2: -2.0f
      0x00, 0x00, 0x00, 0x00,                          // extra data 3: 0.0f
      0x00, 0x00, 0x20, 0x41,                          // extra data 4: 10.0f
  };
  PdoValues values;
  ASSERT_TRUE(readPdo(Pdo::Tx, ByteReader(bytes.data(), bytes.size()), 0, values));
  EXPECT_TRUE(values.has_tx);
  EXPECT_FALSE(values.has_rx);
  EXPECT_EQ(values.word(Word::ActPos), 0x0807060504030201u);
  EXPECT_EQ(values.ssw(), 0x83u);
  EXPECT_EQ(values.sew(), 0x00080001u);
  EXPECT_EQ(values.msgCode(), 3);
  EXPECT_EQ(values.msgData(), 560.0f);
  EXPECT_EQ(fieldValue(field("ncservo.ext_data1"), values).f, 1.0);
  EXPECT_EQ(fieldValue(field("ncservo.ext_data2"), values).f, -2.0);
  EXPECT_EQ(fieldValue(field("ncservo.ext_data3"), values).f, 0.0);
  EXPECT_EQ(fieldValue(field("ncservo.ext_data4"), values).f, 10.0);
}

TEST(ReadPdo, BothPdosAccumulateInOneValues) {
  PdoValues values = valuesOf(rxPdo(7, 0x6));
  const Bytes tx = txPdo(TxValues{-1, 0x1, 0, 0, 0, {}});
  ASSERT_TRUE(readPdo(Pdo::Tx, ByteReader(tx.data(), tx.size()), 0, values));
  EXPECT_TRUE(values.has_rx);
  EXPECT_TRUE(values.has_tx);
  EXPECT_EQ(values.scw(), 0x6u);
  EXPECT_EQ(values.ssw(), 0x1u);
}

// Every length short of the PDO fails, on a heap buffer of exactly that length.
TEST(ReadPdo, FailsOnEveryShortLength) {
  for (Pdo pdo : {Pdo::Rx, Pdo::Tx}) {
    for (std::size_t length = 0; length < pdoSize(pdo); ++length) {
      SCOPED_TRACE(std::to_string(length) + " bytes");
      std::unique_ptr<std::uint8_t[]> buffer(new std::uint8_t[length]);
      for (std::size_t i = 0; i < length; ++i) buffer[i] = 0x5A;
      PdoValues values;
      values.raw[0] = 0x1234;
      EXPECT_FALSE(readPdo(pdo, ByteReader(buffer.get(), length), 0, values));
      EXPECT_FALSE(values.has_rx);
      EXPECT_FALSE(values.has_tx);
      EXPECT_EQ(values.raw[0], 0x1234u) << "values must stay untouched";
    }
  }
}

// A PDO that starts inside the buffer but runs past its end fails, even at huge offsets.
TEST(ReadPdo, FailsWhenOffsetRunsPastTheEnd) {
  const Bytes bytes(45, 0);
  const ByteReader reader(bytes.data(), bytes.size());
  struct Row {
    Pdo pdo;
    std::size_t offset;
    bool ok;
  };
  const Row rows[] = {
      {Pdo::Rx, 35, true},  {Pdo::Rx, 36, false},
      {Pdo::Tx, 5, true},   {Pdo::Tx, 6, false},
      {Pdo::Rx, 45, false}, {Pdo::Tx, std::numeric_limits<std::size_t>::max(), false},
  };
  for (const Row& row : rows) {
    PdoValues values;
    EXPECT_EQ(readPdo(row.pdo, reader, row.offset, values), row.ok) << row.offset;
  }
}

// --- writePdo: what it writes, readPdo reads back, word for word and field for field ---

struct WriteRow {
  const char* name;
  std::uint64_t (*bits)(Word w);  // the wire bits to give each word
};
const WriteRow kWriteRows[] = {
    {"zero", [](Word) { return std::uint64_t{0}; }},
    {"all_ones", [](Word) { return ~std::uint64_t{0}; }},
    {"distinct_bytes",  // each byte names its word and its place: a misplaced byte shows
     [](Word w) {
       std::uint64_t bits = 0;
       for (unsigned i = 0; i < 8; ++i) {
         bits |= std::uint64_t{(static_cast<unsigned>(w) + 1) << 4 | i} << (8 * i);
       }
       return bits;
     }},
    {"sign_bits_only", [](Word w) { return std::uint64_t{1} << (8 * wordDef(w).size - 1); }},
    {"float_nan_payload", [](Word) { return std::uint64_t{0x7FC00123}; }},
};
class WritePdo : public ::testing::TestWithParam<WriteRow> {};

TEST_P(WritePdo, ReadPdoReadsBackEveryWordAndField) {
  PdoValues written;
  for (const WordDef& def : kWords) written.set(def.word, GetParam().bits(def.word));
  written.has_rx = written.has_tx = true;
  // Both PDOs in one buffer with a guard byte around each: nothing is written outside.
  Bytes buffer(1 + kRxPdoSize + 1 + kTxPdoSize + 1, 0xEE);
  writePdo(Pdo::Rx, written, &buffer[1]);
  writePdo(Pdo::Tx, written, &buffer[1 + kRxPdoSize + 1]);
  EXPECT_EQ(buffer[0], 0xEE);
  EXPECT_EQ(buffer[1 + kRxPdoSize], 0xEE);
  EXPECT_EQ(buffer.back(), 0xEE);
  PdoValues read;
  const ByteReader reader(buffer.data(), buffer.size());
  ASSERT_TRUE(readPdo(Pdo::Rx, reader, 1, read));
  ASSERT_TRUE(readPdo(Pdo::Tx, reader, 1 + kRxPdoSize + 1, read));
  for (const WordDef& def : kWords)
    EXPECT_EQ(read.word(def.word), written.word(def.word)) << def.name;
}
INSTANTIATE_TEST_SUITE_P(Rows, WritePdo, ::testing::ValuesIn(kWriteRows), test::rowName<WriteRow>);

// --- Every field of the table against its bits as docs/protocol.md §1-4 gives them, by hand ---

struct HandField {
  const char* filter;
  Word word;
  std::uint64_t mask;  // the field's bits of its word
  Kind kind;
};
constexpr std::uint64_t bit(unsigned b) {
  return std::uint64_t{1} << b;
}
// clang-format off
const HandField kHandFields[] = {
    {"ncservo.ssp", Word::Ssp, 0xFFFFFFFF, Kind::Signed},
    {"ncservo.scw", Word::Scw, 0xFFFFFFFF, Kind::Unsigned},
    {"ncservo.scw.se", Word::Scw, 0x3, Kind::Unsigned},
    {"ncservo.scw.emgon", Word::Scw, bit(2), Kind::Unsigned},
    {"ncservo.scw.poslock", Word::Scw, bit(3), Kind::Unsigned},
    {"ncservo.scw.prmtbl", Word::Scw, 0x30, Kind::Unsigned},
    {"ncservo.scw.modesel", Word::Scw, 0xC0, Kind::Unsigned},
    {"ncservo.scw.sintlock", Word::Scw, bit(8), Kind::Unsigned},
    {"ncservo.scw.error_clear", Word::Scw, bit(9), Kind::Unsigned},
    {"ncservo.scw.brake", Word::Scw, bit(10), Kind::Unsigned},
    {"ncservo.scw.zpulse_request", Word::Scw, bit(11), Kind::Unsigned},
    {"ncservo.scw.ext_prmtbl", Word::Scw, bit(12), Kind::Unsigned},
    {"ncservo.scw.reserved", Word::Scw, 0x7FFFE000, Kind::Unsigned},
    {"ncservo.scw.prgdwn", Word::Scw, bit(31), Kind::Unsigned},
    {"ncservo.ext_code", Word::ExtCode, 0xFFFF, Kind::Signed},
    {"ncservo.actpos", Word::ActPos, ~std::uint64_t{0}, Kind::Signed},
    {"ncservo.actpos.incremental", Word::ActPos, 0xFFFFFFFF, Kind::Signed},
    {"ncservo.actpos.zero_pulse", Word::ActPos, 0xFFFFFFFF00000000, Kind::Signed},
    {"ncservo.ssw", Word::Ssw, 0xFFFFFFFF, Kind::Unsigned},
    {"ncservo.ssw.servo_en", Word::Ssw, bit(0), Kind::Unsigned},
    {"ncservo.ssw.servo_rdy", Word::Ssw, bit(1), Kind::Unsigned},
    {"ncservo.ssw.incremental", Word::Ssw, bit(2), Kind::Unsigned},
    {"ncservo.ssw.zpulse_ack", Word::Ssw, bit(3), Kind::Unsigned},
    {"ncservo.ssw.err_clear_ack", Word::Ssw, bit(4), Kind::Unsigned},
    {"ncservo.ssw.n_zero", Word::Ssw, bit(5), Kind::Unsigned},
    {"ncservo.ssw.n_setpoint", Word::Ssw, bit(6), Kind::Unsigned},
    {"ncservo.ssw.pulse_enabled", Word::Ssw, bit(7), Kind::Unsigned},
    {"ncservo.ssw.prmtbl", Word::Ssw, 0x300, Kind::Unsigned},
    {"ncservo.ssw.no_encoder", Word::Ssw, bit(10), Kind::Unsigned},
    {"ncservo.ssw.temp_warning", Word::Ssw, bit(11), Kind::Unsigned},
    {"ncservo.ssw.ext_prmtbl", Word::Ssw, bit(12), Kind::Unsigned},
    {"ncservo.ssw.reserved", Word::Ssw, 0xFFFFE000, Kind::Unsigned},
    {"ncservo.sew", Word::Sew, 0xFFFFFFFF, Kind::Unsigned},
    {"ncservo.sew.servo_errors", Word::Sew, bit(0), Kind::Unsigned},
    {"ncservo.sew.encoder", Word::Sew, bit(1), Kind::Unsigned},
    {"ncservo.sew.i2t_endat", Word::Sew, bit(2), Kind::Unsigned},
    {"ncservo.sew.ecat_config", Word::Sew, bit(3), Kind::Unsigned},
    {"ncservo.sew.reserved", Word::Sew, 0xFE000010, Kind::Unsigned},
    {"ncservo.sew.bus_voltage", Word::Sew, bit(5), Kind::Unsigned},
    {"ncservo.sew.current", Word::Sew, bit(6), Kind::Unsigned},
    {"ncservo.sew.current_offset", Word::Sew, bit(7), Kind::Unsigned},
    {"ncservo.sew.hall", Word::Sew, bit(8), Kind::Unsigned},
    {"ncservo.sew.hall_sequence", Word::Sew, bit(9), Kind::Unsigned},
    {"ncservo.sew.servo_runtime", Word::Sew, bit(10), Kind::Unsigned},
    {"ncservo.sew.can1_timeout", Word::Sew, bit(11), Kind::Unsigned},
    {"ncservo.sew.can2_timeout", Word::Sew, bit(12), Kind::Unsigned},
    {"ncservo.sew.can1_hw", Word::Sew, bit(13), Kind::Unsigned},
    {"ncservo.sew.can2_hw", Word::Sew, bit(14), Kind::Unsigned},
    {"ncservo.sew.ecat_timeout", Word::Sew, bit(15), Kind::Unsigned},
    {"ncservo.sew.pdpint", Word::Sew, bit(16), Kind::Unsigned},
    {"ncservo.sew.param_checksum", Word::Sew, bit(17), Kind::Unsigned},
    {"ncservo.sew.program_checksum", Word::Sew, bit(18), Kind::Unsigned},
    {"ncservo.sew.following", Word::Sew, bit(19), Kind::Unsigned},
    {"ncservo.sew.overload", Word::Sew, bit(20), Kind::Unsigned},
    {"ncservo.sew.flash", Word::Sew, bit(21), Kind::Unsigned},
    {"ncservo.sew.ecat_watchdog", Word::Sew, bit(22), Kind::Unsigned},
    {"ncservo.sew.overspeed", Word::Sew, bit(23), Kind::Unsigned},
    {"ncservo.sew.current_symmetry", Word::Sew, bit(24), Kind::Unsigned},
    {"ncservo.msg_code", Word::MsgCode, 0xFFFFFFFF, Kind::Signed},
    {"ncservo.msg_data", Word::MsgData, 0xFFFFFFFF, Kind::Float},
    {"ncservo.ext_data1", Word::ExtData1, 0xFFFFFFFF, Kind::Float},
    {"ncservo.ext_data2", Word::ExtData2, 0xFFFFFFFF, Kind::Float},
    {"ncservo.ext_data3", Word::ExtData3, 0xFFFFFFFF, Kind::Float},
    {"ncservo.ext_data4", Word::ExtData4, 0xFFFFFFFF, Kind::Float},
};
// clang-format on

const HandField* handField(const char* filter) {
  for (const HandField& h : kHandFields) {
    if (std::string(h.filter) == filter) return &h;
  }
  return nullptr;
}

// The field's bits of `word`, shifted down, sign-extended from their top bit when signed.
FieldValue handValue(const HandField& h, std::uint64_t word) {
  const std::uint64_t bits = (word & h.mask) >> std::countr_zero(h.mask);
  FieldValue v{h.kind};
  const int width = std::bit_width(h.mask >> std::countr_zero(h.mask));
  if (h.kind == Kind::Signed) v.i = static_cast<std::int64_t>(bits << (64 - width)) >> (64 - width);
  if (h.kind == Kind::Unsigned) v.u = bits;
  if (h.kind == Kind::Float) {
    float f;
    const auto low = static_cast<std::uint32_t>(bits);
    std::memcpy(&f, &low, sizeof f);
    v.f = f;
  }
  return v;
}

class FieldBits : public ::testing::TestWithParam<WriteRow> {};

TEST_P(FieldBits, EveryFieldIsItsDocumentedBits) {
  PdoValues values;
  for (const WordDef& def : kWords) values.set(def.word, GetParam().bits(def.word));
  values.has_rx = values.has_tx = true;
  for (const FieldDef& f : kFields) {
    const HandField* h = handField(f.filter);
    ASSERT_NE(h, nullptr) << f.filter << " has no row here: write its bits from docs/protocol.md";
    ASSERT_EQ(f.word, h->word) << f.filter;
    const FieldValue want = handValue(*h, values.word(h->word));
    const FieldValue got = fieldValue(f, values);
    ASSERT_EQ(got.kind, want.kind) << f.filter;
    EXPECT_EQ(got.i, want.i) << f.filter;
    EXPECT_EQ(got.u, want.u) << f.filter;
    EXPECT_EQ(bitsOf(static_cast<float>(got.f)), bitsOf(static_cast<float>(want.f))) << f.filter;
  }
}
INSTANTIATE_TEST_SUITE_P(Rows, FieldBits, ::testing::ValuesIn(kWriteRows), test::rowName<WriteRow>);

TEST(PdoValuesSet, DropsBitsBeyondTheWord) {
  PdoValues values;
  values.set(Word::ExtCode, 0xFFFFFFFFFFFF8001u);  // a 2-byte word
  values.set(Word::Ssp, static_cast<std::uint32_t>(-5));
  EXPECT_EQ(values.word(Word::ExtCode), 0x8001u);
  EXPECT_EQ(values.word(Word::Ssp), 0xFFFFFFFBu);
}

struct ValueCase {
  const char* name;
  const char* filter;
  Bytes pdo;  // 10 bytes: RxPDO, 40 bytes: TxPDO
  Kind kind;
  std::int64_t i = 0;
  std::uint64_t u = 0;
  double f = 0;
};

// Incremental encoder: words 0-1 and 2-3 of ActPos, each a signed 32-bit value.
std::int64_t actposHalves(std::int32_t low, std::int32_t high) {
  return static_cast<std::int64_t>(
      (static_cast<std::uint64_t>(static_cast<std::uint32_t>(high)) << 32) |
      static_cast<std::uint32_t>(low));
}

std::vector<ValueCase> valueCases() {
  constexpr std::uint32_t kIncr = 0x4;
  return {
      {"ssp negative", "ncservo.ssp", rxPdo(-1500, 0), Kind::Signed, -1500},
      {"ssp minimum", "ncservo.ssp", rxPdo(std::numeric_limits<std::int32_t>::min(), 0),
       Kind::Signed, std::numeric_limits<std::int32_t>::min()},
      {"ssp 16-bit NC", "ncservo.ssp", rxPdo(0x7FFF, 0), Kind::Signed, 0x7FFF},
      {"scw all ones is unsigned", "ncservo.scw", rxPdo(0, 0xFFFFFFFF), Kind::Unsigned, 0,
       0xFFFFFFFF},
      {"ext_code negative", "ncservo.ext_code", rxPdo(0, 0, -2), Kind::Signed, -2},
      {"ext_code minimum", "ncservo.ext_code", rxPdo(0, 0, -32768), Kind::Signed, -32768},
      {"ext_code maximum", "ncservo.ext_code", rxPdo(0, 0, 32767), Kind::Signed, 32767},
      {"scw.se 2", "ncservo.scw.se", rxPdo(0, 0x6), Kind::Unsigned, 0, 2},
      {"scw.se 3", "ncservo.scw.se", rxPdo(0, 0xFFFFFFFF), Kind::Unsigned, 0, 3},
      {"scw.emgon set", "ncservo.scw.emgon", rxPdo(0, 0x4), Kind::Unsigned, 0, 1},
      {"scw.emgon clear", "ncservo.scw.emgon", rxPdo(0, 0xFFFFFFFB), Kind::Unsigned, 0, 0},
      {"scw.prmtbl 2", "ncservo.scw.prmtbl", rxPdo(0, 0x20), Kind::Unsigned, 0, 2},
      {"scw.modesel 3", "ncservo.scw.modesel", rxPdo(0, 0xC0), Kind::Unsigned, 0, 3},
      {"scw.reserved all", "ncservo.scw.reserved", rxPdo(0, 0x7FFFE000), Kind::Unsigned, 0,
       0x3FFFF},
      {"scw.prgdwn", "ncservo.scw.prgdwn", rxPdo(0, 0x80000000), Kind::Unsigned, 0, 1},
      {"actpos above 2^32", "ncservo.actpos", txPdo({(1ll << 32) + 5}), Kind::Signed,
       (1ll << 32) + 5},
      {"actpos negative", "ncservo.actpos", txPdo({-3}), Kind::Signed, -3},
      {"actpos minimum", "ncservo.actpos", txPdo({std::numeric_limits<std::int64_t>::min()}),
       Kind::Signed, std::numeric_limits<std::int64_t>::min()},
      {"actpos.incremental positive", "ncservo.actpos.incremental",
       txPdo({actposHalves(123456, 7), kIncr}), Kind::Signed, 123456},
      {"actpos.incremental negative", "ncservo.actpos.incremental",
       txPdo({actposHalves(-7, 99), kIncr}), Kind::Signed, -7},
      {"actpos.zero_pulse positive", "ncservo.actpos.zero_pulse",
       txPdo({actposHalves(-7, 99), kIncr}), Kind::Signed, 99},
      {"actpos.zero_pulse negative", "ncservo.actpos.zero_pulse",
       txPdo({actposHalves(5, -100000), kIncr}), Kind::Signed, -100000},
      {"actpos.zero_pulse minimum", "ncservo.actpos.zero_pulse",
       txPdo({actposHalves(0, std::numeric_limits<std::int32_t>::min()), kIncr}), Kind::Signed,
       std::numeric_limits<std::int32_t>::min()},
      {"ssw top bit is unsigned", "ncservo.ssw", txPdo({0, 0x80000001}), Kind::Unsigned, 0,
       0x80000001},
      {"ssw.prmtbl 2", "ncservo.ssw.prmtbl", txPdo({0, 0x200}), Kind::Unsigned, 0, 2},
      {"ssw.zpulse_ack", "ncservo.ssw.zpulse_ack", txPdo({0, 0x8}), Kind::Unsigned, 0, 1},
      {"ssw.reserved all", "ncservo.ssw.reserved", txPdo({0, 0xFFFFE000}), Kind::Unsigned, 0,
       0x7FFFF},
      {"sew unsigned", "ncservo.sew", txPdo({0, 0, 0xFE000010}), Kind::Unsigned, 0, 0xFE000010},
      {"sew.following", "ncservo.sew.following", txPdo({0, 0, 0x80001}), Kind::Unsigned, 0, 1},
      {"sew.reserved bit 4 and 31..25", "ncservo.sew.reserved", txPdo({0, 0, 0xFE000010}),
       Kind::Unsigned, 0, 0xFE00001},
      {"sew.reserved bit 4 only", "ncservo.sew.reserved", txPdo({0, 0, 0x10}), Kind::Unsigned, 0,
       1},
      {"msg_code negative", "ncservo.msg_code", txPdo({0, 0, 0, -5}), Kind::Signed, -5},
      {"msg_data", "ncservo.msg_data", txPdo({0, 0, 0, 0, 1500.0f}), Kind::Float, 0, 0, 1500.0},
      {"msg_data negative", "ncservo.msg_data", txPdo({0, 0, 0, 1, -2.25f}), Kind::Float, 0, 0,
       -2.25},
      {"ext_data1", "ncservo.ext_data1", txPdo({0, 0, 0, 0, 0, {0.5f, 1, 2, 3}}), Kind::Float, 0, 0,
       0.5},
      {"ext_data2", "ncservo.ext_data2", txPdo({0, 0, 0, 0, 0, {0.5f, -1e6f, 2, 3}}), Kind::Float,
       0, 0, -1e6},
      {"ext_data3", "ncservo.ext_data3", txPdo({0, 0, 0, 0, 0, {0, 0, 0.125f, 3}}), Kind::Float, 0,
       0, 0.125},
      {"ext_data4", "ncservo.ext_data4", txPdo({0, 0, 0, 0, 0, {0, 0, 0, 3.5f}}), Kind::Float, 0, 0,
       3.5},
  };
}

TEST(FieldValue, EachKindFromBytes) {
  for (const ValueCase& c : valueCases()) {
    SCOPED_TRACE(c.name);
    const PdoValues values = valuesOf(c.pdo);
    const FieldValue v = fieldValue(field(c.filter), values);
    ASSERT_EQ(v.kind, c.kind);
    switch (c.kind) {
      case Kind::Signed:
        EXPECT_EQ(v.i, c.i);
        break;
      case Kind::Unsigned:
        EXPECT_EQ(v.u, c.u);
        break;
      case Kind::Float:
        EXPECT_EQ(v.f, c.f);
        break;
    }
  }
}

TEST(FieldValue, FloatNanKeepsItsBits) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const PdoValues values = valuesOf(txPdo({0, 0, 0, 0, nan}));
  EXPECT_EQ(values.word(Word::MsgData), bitsOf(nan));
  EXPECT_TRUE(std::isnan(fieldValue(field("ncservo.msg_data"), values).f));
}

struct AppliesCase {
  const char* name;
  const char* filter;
  bool has_rx;
  bool has_tx;
  std::uint32_t ssw;
  bool applies;
};
const AppliesCase kAppliesCases[] = {
    {"incremental shown on incremental encoder", "ncservo.actpos.incremental", false, true, 0x4,
     true},
    {"zero_pulse shown on incremental encoder", "ncservo.actpos.zero_pulse", false, true, 0x4,
     true},
    {"incremental hidden on absolute encoder", "ncservo.actpos.incremental", false, true, 0x0,
     false},
    {"zero_pulse hidden on absolute encoder", "ncservo.actpos.zero_pulse", false, true, 0xFFFFFFFB,
     false},
    {"incremental hidden without TxPDO", "ncservo.actpos.incremental", true, false, 0x4, false},
    {"actpos shown on absolute encoder", "ncservo.actpos", false, true, 0x0, true},
    {"actpos shown on incremental encoder", "ncservo.actpos", false, true, 0x4, true},
    {"tx field hidden without TxPDO", "ncservo.ssw.servo_en", true, false, 0, false},
    {"rx field shown with RxPDO", "ncservo.scw.se", true, false, 0, true},
    {"rx field hidden without RxPDO", "ncservo.ssp", false, true, 0, false},
    {"nothing shown without PDOs", "ncservo.sew", false, false, 0, false},
};

TEST(FieldApplies, PdoPresenceAndIncrementalEncoderCondition) {
  for (const AppliesCase& c : kAppliesCases) {
    SCOPED_TRACE(c.name);
    PdoValues values;
    values.has_rx = c.has_rx;
    values.has_tx = c.has_tx;
    values.raw[static_cast<std::size_t>(Word::Ssw)] = c.ssw;
    EXPECT_EQ(fieldApplies(field(c.filter), values), c.applies);
  }
}

struct SpanCase {
  const char* filter;
  std::size_t offset;
  std::size_t length;
};
const SpanCase kSpanCases[] = {
    {"ncservo.ssp", 0, 4},
    {"ncservo.scw", 4, 4},
    {"ncservo.scw.se", 4, 4},
    {"ncservo.ext_code", 8, 2},
    {"ncservo.actpos", 0, 8},
    {"ncservo.actpos.incremental", 0, 4},
    {"ncservo.actpos.zero_pulse", 4, 4},
    {"ncservo.ssw", 8, 4},
    {"ncservo.sew.following", 12, 4},
    {"ncservo.msg_code", 16, 4},
    {"ncservo.msg_data", 20, 4},
    {"ncservo.ext_data4", 36, 4},
};

TEST(FieldSpan, BytesOfTheRowInsideItsPdo) {
  for (const SpanCase& c : kSpanCases) {
    SCOPED_TRACE(c.filter);
    const FieldSpan span = fieldSpan(field(c.filter));
    EXPECT_EQ(span.offset, c.offset);
    EXPECT_EQ(span.length, c.length);
  }
}

struct MessageCase {
  std::int32_t code;
  float data;
  const char* expected;  // exact text, or a text it must contain when `exact` is false
  bool exact;
};
const MessageCase kMessageCases[] = {
    {0, 1500.0f, "motor speed 1500.0 rpm", true},
    {1, 2.5f, "motor current 2.5 A", true},
    {2, 87.5f, "relative current I/In 87.5 %", true},
    {3, 560.0f, "bus voltage 560.0 V", true},
    {4, 41.0f, "motor temperature 41.0 °C", true},
    {5, 0.5f, "motor power 0.5 kW", true},
    {0, -300.0f, "motor speed -300.0 rpm", true},
    {6, 1.0f, "undefined", false},
    {7, 1.0f, "undefined", false},
    {9, 1.0f, "undefined", false},
    {-1, 1.0f, "undefined", false},
    {std::numeric_limits<std::int32_t>::min(), 0.0f, "undefined", false},
    {1000, 0.0f, "1000", false},
};

TEST(FormatMessage, MeaningAndUnitOrUndefined) {
  for (const MessageCase& c : kMessageCases) {
    SCOPED_TRACE(std::to_string(c.code));
    char buf[128];
    formatMessage(buf, sizeof buf, c.code, c.data);
    if (c.exact) {
      EXPECT_STREQ(buf, c.expected);
    } else {
      EXPECT_NE(std::string(buf).find(c.expected), std::string::npos) << buf;
    }
  }
}

TEST(FormatMessage, SmallBuffersAreTerminatedAndNotOverrun) {
  for (std::size_t size = 1; size < 24; ++size) {
    SCOPED_TRACE(size);
    std::vector<char> buf(size + 4, '#');
    formatMessage(buf.data(), size, 0, 1500.0f);
    EXPECT_EQ(std::string(buf.data()), std::string("motor speed 1500.0 rpm").substr(0, size - 1));
    for (std::size_t i = size; i < buf.size(); ++i) EXPECT_EQ(buf[i], '#') << i;
  }
  char untouched = '#';
  formatMessage(&untouched, 0, 0, 1.0f);
  EXPECT_EQ(untouched, '#');
}

}  // namespace
}  // namespace ncservo
