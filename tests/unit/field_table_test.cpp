// The field table (fields.hpp) and the PDO layout (pdo_layout.hpp) against docs/protocol.md §1-4.
#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <string_view>

#include "ncservo/protocol/fields.hpp"
#include "ncservo/protocol/pdo.hpp"
#include "ncservo/protocol/pdo_layout.hpp"

namespace ncservo {
namespace {

bool isBitField(const FieldDef& f) {
  return f.kind == FieldKind::Flag || f.kind == FieldKind::BitRange;
}

// Every filter name of docs/fields.md, written out by hand in the order of docs/protocol.md §1-4.
const char* const kSpecFilterNames[] = {
    // §1 RxPDO and TxPDO words
    "ncservo.ssp", "ncservo.scw", "ncservo.ext_code", "ncservo.actpos", "ncservo.ssw",
    "ncservo.sew", "ncservo.msg_code", "ncservo.msg_data", "ncservo.ext_data1", "ncservo.ext_data2",
    "ncservo.ext_data3", "ncservo.ext_data4", "ncservo.actpos.incremental",
    "ncservo.actpos.zero_pulse",
    // §2 SCW
    "ncservo.scw.se", "ncservo.scw.emgon", "ncservo.scw.poslock", "ncservo.scw.prmtbl",
    "ncservo.scw.modesel", "ncservo.scw.sintlock", "ncservo.scw.error_clear", "ncservo.scw.brake",
    "ncservo.scw.zpulse_request", "ncservo.scw.ext_prmtbl", "ncservo.scw.reserved",
    "ncservo.scw.prgdwn",
    // §3 SSW
    "ncservo.ssw.servo_en", "ncservo.ssw.servo_rdy", "ncservo.ssw.incremental",
    "ncservo.ssw.zpulse_ack", "ncservo.ssw.err_clear_ack", "ncservo.ssw.n_zero",
    "ncservo.ssw.n_setpoint", "ncservo.ssw.pulse_enabled", "ncservo.ssw.prmtbl",
    "ncservo.ssw.no_encoder", "ncservo.ssw.temp_warning", "ncservo.ssw.ext_prmtbl",
    "ncservo.ssw.reserved",
    // §4 SEW
    "ncservo.sew.servo_errors", "ncservo.sew.encoder", "ncservo.sew.i2t_endat",
    "ncservo.sew.ecat_config", "ncservo.sew.reserved", "ncservo.sew.bus_voltage",
    "ncservo.sew.current", "ncservo.sew.current_offset", "ncservo.sew.hall",
    "ncservo.sew.hall_sequence", "ncservo.sew.servo_runtime", "ncservo.sew.can1_timeout",
    "ncservo.sew.can2_timeout", "ncservo.sew.can1_hw", "ncservo.sew.can2_hw",
    "ncservo.sew.ecat_timeout", "ncservo.sew.pdpint", "ncservo.sew.param_checksum",
    "ncservo.sew.program_checksum", "ncservo.sew.following", "ncservo.sew.overload",
    "ncservo.sew.flash", "ncservo.sew.ecat_watchdog", "ncservo.sew.overspeed",
    "ncservo.sew.current_symmetry"};

TEST(FieldTable, FilterNamesAreUnique) {
  std::set<std::string_view> seen;
  for (const FieldDef& f : kFields) {
    EXPECT_TRUE(seen.insert(f.filter).second) << "duplicate filter name " << f.filter;
  }
}

TEST(FieldTable, FilterNamesStartWithProtocolName) {
  for (const FieldDef& f : kFields) {
    EXPECT_EQ(std::string_view(f.filter).substr(0, 8), "ncservo.") << f.filter;
  }
  for (const DerivedFieldDef& f : kDerivedFields) {
    EXPECT_EQ(std::string_view(f.filter).substr(0, 8), "ncservo.") << f.filter;
  }
}

TEST(FieldTable, MasksLieInsideTheirWord) {
  for (const FieldDef& f : kFields) {
    EXPECT_EQ(f.mask & ~wordMask(f.word), 0u) << f.filter;
    EXPECT_EQ(f.kind == FieldKind::Word, f.mask == 0) << f.filter;
  }
}

TEST(FieldTable, FlagRowsAreSingleBit) {
  for (const FieldDef& f : kFields) {
    if (f.kind == FieldKind::Flag) {
      EXPECT_EQ(popcount64(f.mask), 1u) << f.filter;
    }
    if (f.kind == FieldKind::BitRange) {
      EXPECT_GE(popcount64(f.mask), 2u) << f.filter;
    }
  }
}

TEST(FieldTable, BitFieldsOfOneWordAreDisjoint) {
  for (const FieldDef& a : kFields) {
    for (const FieldDef& b : kFields) {
      if (&a == &b || a.word != b.word || !isBitField(a) || !isBitField(b)) continue;
      EXPECT_EQ(a.mask & b.mask, 0u) << a.filter << " overlaps " << b.filter;
    }
  }
}

// SCW, SSW and SEW: the bit fields together cover all 32 bits (reserved bits included).
TEST(FieldTable, BitFieldsCoverTheWholeControlAndStatusWords) {
  for (Word w : {Word::Scw, Word::Ssw, Word::Sew}) {
    std::uint64_t covered = 0;
    for (const FieldDef& f : kFields) {
      if (f.word == w && isBitField(f)) covered |= f.mask;
    }
    EXPECT_EQ(covered, 0xFFFFFFFFu) << wordDef(w).name;
  }
}

TEST(FieldTable, EveryWordHasExactlyOneWordRow) {
  for (const WordDef& def : kWords) {
    int rows = 0;
    for (const FieldDef& f : kFields) rows += f.word == def.word && f.kind == FieldKind::Word;
    EXPECT_EQ(rows, 1) << def.name;
  }
}

TEST(FieldTable, FilterNamesAreExactlyThoseOfTheSpec) {
  std::set<std::string> expected(std::begin(kSpecFilterNames), std::end(kSpecFilterNames));
  std::set<std::string> actual;
  for (const FieldDef& f : kFields) actual.insert(f.filter);
  for (const std::string& name : expected) EXPECT_EQ(actual.count(name), 1u) << "missing " << name;
  for (const std::string& name : actual) EXPECT_EQ(expected.count(name), 1u) << "extra " << name;
  EXPECT_EQ(kFieldCount, std::size(kSpecFilterNames));
}

// The bits a view may gather as "at rest": a clear flag whose clear value means nothing happens,
// reserved bits zero; a clear value that says something (emergency, internal braking, an
// absolute encoder, the drive's state: not enabled, not ready, turning, pulses off), a
// multi-valued selection and the SEW (whose clear causes are gathered on their own) are not.
TEST(FieldTable, AtRestValuesMarkOnlyQuietBitsOfTheControlAndStatusWords) {
  struct Row {
    std::string_view filter;
    std::optional<std::uint32_t> at_rest;
  };
  const Row rows[] = {
      {"ncservo.scw.poslock", 0},
      {"ncservo.scw.error_clear", 0},
      {"ncservo.scw.reserved", 0},
      {"ncservo.scw.prgdwn", 0},
      {"ncservo.ssw.zpulse_ack", 0},
      {"ncservo.ssw.err_clear_ack", 0},
      {"ncservo.ssw.no_encoder", 0},
      {"ncservo.ssw.reserved", 0},
      {"ncservo.ssw.temp_warning", 0},
      {"ncservo.scw.emgon", std::nullopt},
      {"ncservo.scw.brake", std::nullopt},
      {"ncservo.scw.se", std::nullopt},
      {"ncservo.scw.prmtbl", std::nullopt},
      {"ncservo.scw.ext_prmtbl", std::nullopt},
      {"ncservo.ssw.incremental", std::nullopt},
      {"ncservo.ssw.servo_en", std::nullopt},
      {"ncservo.ssw.servo_rdy", std::nullopt},
      {"ncservo.ssw.n_zero", std::nullopt},
      {"ncservo.ssw.n_setpoint", std::nullopt},
      {"ncservo.ssw.pulse_enabled", std::nullopt},
      {"ncservo.sew.following", std::nullopt},
      {"ncservo.sew.reserved", std::nullopt},
      {"ncservo.scw", std::nullopt},
  };
  for (const Row& row : rows) EXPECT_EQ(field(row.filter).at_rest, row.at_rest) << row.filter;
  for (const FieldDef& f : kFields) {
    EXPECT_TRUE(!f.at_rest || f.word == Word::Scw || f.word == Word::Ssw) << f.filter;
  }
}

TEST(FieldTable, DerivedFieldsIncludeTheInterfaceNames) {
  std::set<std::string> actual;
  for (const DerivedFieldDef& f : kDerivedFields) actual.insert(f.filter);
  for (const char* name :
       {"ncservo.axis", "ncservo.axis_name", "ncservo.state", "ncservo.message",
        "ncservo.cycle.interval", "ncservo.cycle.deviation", "ncservo.latency"}) {
    EXPECT_EQ(actual.count(name), 1u) << "missing " << name;
  }
  for (const FieldDef& f : kFields) EXPECT_EQ(actual.count(f.filter), 0u) << f.filter;
}

// docs/protocol.md §1: offset, size and type of every word.
struct WordRow {
  Word word;
  Pdo pdo;
  std::size_t offset;
  std::size_t size;
  WireType type;
};
const WordRow kWordRows[] = {
    {Word::Ssp, Pdo::Rx, 0, 4, WireType::I32},
    {Word::Scw, Pdo::Rx, 4, 4, WireType::U32},
    {Word::ExtCode, Pdo::Rx, 8, 2, WireType::I16},
    {Word::ActPos, Pdo::Tx, 0, 8, WireType::I64},
    {Word::Ssw, Pdo::Tx, 8, 4, WireType::U32},
    {Word::Sew, Pdo::Tx, 12, 4, WireType::U32},
    {Word::MsgCode, Pdo::Tx, 16, 4, WireType::I32},
    {Word::MsgData, Pdo::Tx, 20, 4, WireType::F32},
    {Word::ExtData1, Pdo::Tx, 24, 4, WireType::F32},
    {Word::ExtData2, Pdo::Tx, 28, 4, WireType::F32},
    {Word::ExtData3, Pdo::Tx, 32, 4, WireType::F32},
    {Word::ExtData4, Pdo::Tx, 36, 4, WireType::F32},
};

TEST(PdoLayout, SizesAreTenAndForty) {
  EXPECT_EQ(kRxPdoSize, 10u);
  EXPECT_EQ(kTxPdoSize, 40u);
  EXPECT_EQ(pdoSize(Pdo::Rx), 10u);
  EXPECT_EQ(pdoSize(Pdo::Tx), 40u);
}

TEST(PdoLayout, WordOffsetsSizesAndTypesFollowTheSpec) {
  ASSERT_EQ(std::size(kWordRows), kWordCount);
  for (const WordRow& row : kWordRows) {
    const WordDef& def = wordDef(row.word);
    SCOPED_TRACE(def.name);
    EXPECT_EQ(def.word, row.word);
    EXPECT_EQ(def.pdo, row.pdo);
    EXPECT_EQ(wordOffset(row.word), row.offset);
    EXPECT_EQ(def.size, row.size);
    EXPECT_EQ(def.type, row.type);
    EXPECT_EQ(wordMask(row.word), row.size == 8 ? ~0ull : (1ull << (8 * row.size)) - 1);
  }
}

// docs/protocol.md §1-4: kind and mask of every row that is not a whole word.
struct MaskRow {
  const char* filter;
  FieldKind kind;
  std::uint64_t mask;
};
const MaskRow kMaskRows[] = {
    {"ncservo.actpos.incremental", FieldKind::Part, 0xFFFFFFFFull},
    {"ncservo.actpos.zero_pulse", FieldKind::Part, 0xFFFFFFFF00000000ull},
    {"ncservo.scw.se", FieldKind::BitRange, 0x3},
    {"ncservo.scw.emgon", FieldKind::Flag, 0x4},
    {"ncservo.scw.poslock", FieldKind::Flag, 0x8},
    {"ncservo.scw.prmtbl", FieldKind::BitRange, 0x30},
    {"ncservo.scw.modesel", FieldKind::BitRange, 0xC0},
    {"ncservo.scw.sintlock", FieldKind::Flag, 0x100},
    {"ncservo.scw.error_clear", FieldKind::Flag, 0x200},
    {"ncservo.scw.brake", FieldKind::Flag, 0x400},
    {"ncservo.scw.zpulse_request", FieldKind::Flag, 0x800},
    {"ncservo.scw.ext_prmtbl", FieldKind::Flag, 0x1000},
    {"ncservo.scw.reserved", FieldKind::BitRange, 0x7FFFE000},
    {"ncservo.scw.prgdwn", FieldKind::Flag, 0x80000000},
    {"ncservo.ssw.servo_en", FieldKind::Flag, 0x1},
    {"ncservo.ssw.servo_rdy", FieldKind::Flag, 0x2},
    {"ncservo.ssw.incremental", FieldKind::Flag, 0x4},
    {"ncservo.ssw.zpulse_ack", FieldKind::Flag, 0x8},
    {"ncservo.ssw.err_clear_ack", FieldKind::Flag, 0x10},
    {"ncservo.ssw.n_zero", FieldKind::Flag, 0x20},
    {"ncservo.ssw.n_setpoint", FieldKind::Flag, 0x40},
    {"ncservo.ssw.pulse_enabled", FieldKind::Flag, 0x80},
    {"ncservo.ssw.prmtbl", FieldKind::BitRange, 0x300},
    {"ncservo.ssw.no_encoder", FieldKind::Flag, 0x400},
    {"ncservo.ssw.temp_warning", FieldKind::Flag, 0x800},
    {"ncservo.ssw.ext_prmtbl", FieldKind::Flag, 0x1000},
    {"ncservo.ssw.reserved", FieldKind::BitRange, 0xFFFFE000},
    {"ncservo.sew.servo_errors", FieldKind::Flag, 0x1},
    {"ncservo.sew.encoder", FieldKind::Flag, 0x2},
    {"ncservo.sew.i2t_endat", FieldKind::Flag, 0x4},
    {"ncservo.sew.ecat_config", FieldKind::Flag, 0x8},
    {"ncservo.sew.reserved", FieldKind::BitRange, 0xFE000010},
    {"ncservo.sew.bus_voltage", FieldKind::Flag, 0x20},
    {"ncservo.sew.current", FieldKind::Flag, 0x40},
    {"ncservo.sew.current_offset", FieldKind::Flag, 0x80},
    {"ncservo.sew.hall", FieldKind::Flag, 0x100},
    {"ncservo.sew.hall_sequence", FieldKind::Flag, 0x200},
    {"ncservo.sew.servo_runtime", FieldKind::Flag, 0x400},
    {"ncservo.sew.can1_timeout", FieldKind::Flag, 0x800},
    {"ncservo.sew.can2_timeout", FieldKind::Flag, 0x1000},
    {"ncservo.sew.can1_hw", FieldKind::Flag, 0x2000},
    {"ncservo.sew.can2_hw", FieldKind::Flag, 0x4000},
    {"ncservo.sew.ecat_timeout", FieldKind::Flag, 0x8000},
    {"ncservo.sew.pdpint", FieldKind::Flag, 0x10000},
    {"ncservo.sew.param_checksum", FieldKind::Flag, 0x20000},
    {"ncservo.sew.program_checksum", FieldKind::Flag, 0x40000},
    {"ncservo.sew.following", FieldKind::Flag, 0x80000},
    {"ncservo.sew.overload", FieldKind::Flag, 0x100000},
    {"ncservo.sew.flash", FieldKind::Flag, 0x200000},
    {"ncservo.sew.ecat_watchdog", FieldKind::Flag, 0x400000},
    {"ncservo.sew.overspeed", FieldKind::Flag, 0x800000},
    {"ncservo.sew.current_symmetry", FieldKind::Flag, 0x1000000},
};

TEST(FieldTable, KindsAndMasksFollowTheSpec) {
  std::size_t sub_fields = 0;
  for (const FieldDef& f : kFields) sub_fields += f.kind != FieldKind::Word;
  EXPECT_EQ(sub_fields, std::size(kMaskRows));
  for (const MaskRow& row : kMaskRows) {
    SCOPED_TRACE(row.filter);
    const FieldDef& f = field(row.filter);
    EXPECT_EQ(f.kind, row.kind);
    EXPECT_EQ(f.mask, row.mask);
  }
}

// docs/protocol.md §3, §1: the whole-word rows name the word they sit on.
struct WordOfRow {
  const char* filter;
  Word word;
};
const WordOfRow kWordOfRows[] = {
    {"ncservo.ssp", Word::Ssp},
    {"ncservo.scw", Word::Scw},
    {"ncservo.ext_code", Word::ExtCode},
    {"ncservo.actpos", Word::ActPos},
    {"ncservo.ssw", Word::Ssw},
    {"ncservo.sew", Word::Sew},
    {"ncservo.msg_code", Word::MsgCode},
    {"ncservo.msg_data", Word::MsgData},
    {"ncservo.ext_data1", Word::ExtData1},
    {"ncservo.ext_data2", Word::ExtData2},
    {"ncservo.ext_data3", Word::ExtData3},
    {"ncservo.ext_data4", Word::ExtData4},
};

TEST(FieldTable, WordRowsSitOnTheirWord) {
  for (const WordOfRow& row : kWordOfRows) {
    SCOPED_TRACE(row.filter);
    EXPECT_EQ(field(row.filter).word, row.word);
    EXPECT_EQ(field(row.filter).kind, FieldKind::Word);
  }
}

TEST(FieldTable, OnlyTheIncrementalPositionsAreConditional) {
  for (const FieldDef& f : kFields) {
    const bool incremental = std::string_view(f.filter) == "ncservo.actpos.incremental" ||
                             std::string_view(f.filter) == "ncservo.actpos.zero_pulse";
    EXPECT_EQ(f.when, incremental ? FieldWhen::IncrementalEncoder : FieldWhen::Always) << f.filter;
  }
}

// Value names: one row per (field, value), with a text the name must contain.
struct ValueNameRow {
  const char* filter;
  std::uint64_t value;
  const char* contains;  // nullptr: the value has no name
};
const ValueNameRow kValueNameRows[] = {
    {"ncservo.scw.se", 0, "disabled"},
    {"ncservo.scw.se", 1, "disabled"},
    {"ncservo.scw.se", 2, "enable (only from 0x1)"},
    {"ncservo.scw.se", 3, "disabled"},
    {"ncservo.scw.emgon", 0, "emergency"},
    {"ncservo.scw.emgon", 1, "normal"},
    {"ncservo.scw.brake", 0, "braking"},
    {"ncservo.ssw.incremental", 1, "incremental"},
    {"ncservo.ssw.incremental", 0, "absolute"},
    {"ncservo.msg_code", 0, "motor speed"},
    {"ncservo.msg_code", 3, "bus voltage"},
    {"ncservo.msg_code", 5, "motor power"},
    {"ncservo.msg_code", 6, nullptr},
    {"ncservo.scw.se", 4, nullptr},
};

TEST(FieldTable, ValueNames) {
  for (const ValueNameRow& row : kValueNameRows) {
    SCOPED_TRACE(std::string(row.filter) + " = " + std::to_string(row.value));
    const ValueName* name = valueName(field(row.filter), row.value);
    if (row.contains == nullptr) {
      EXPECT_EQ(name, nullptr);
      continue;
    }
    ASSERT_NE(name, nullptr);
    EXPECT_NE(std::string(name->name).find(row.contains), std::string::npos) << name->name;
  }
  EXPECT_STREQ(valueName(field("ncservo.scw.se"), 2)->name, "enable (only from 0x1)");
  EXPECT_EQ(std::string(valueName(field("ncservo.scw.se"), 2)->name).find("disabled"),
            std::string::npos);
}

}  // namespace
}  // namespace ncservo
