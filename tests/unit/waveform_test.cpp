// decode's waveforms (waveform.hpp) and axis selection (axis_selection.hpp): identifier codes,
// value texts, the signals derived from the field table, scope names and --axis.
#include "ncservo/report/waveform.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "ncservo/report/axis_selection.hpp"
#include "row_name.hpp"

namespace ncservo::report {
namespace {

struct IdCase {
  const char* name;
  std::size_t n;
  const char* code;
};

class IdCodeTest : public ::testing::TestWithParam<IdCase> {};

TEST_P(IdCodeTest, Code) {
  EXPECT_EQ(vcdIdCode(GetParam().n), GetParam().code);
}

INSTANTIATE_TEST_SUITE_P(Codes, IdCodeTest,
                         ::testing::Values(IdCase{"first", 0, "!"}, IdCase{"second", 1, "\""},
                                           IdCase{"last_of_one_char", 93, "~"},
                                           IdCase{"first_of_two_chars", 94, "!!"},
                                           IdCase{"second_of_two_chars", 95, "\"!"},
                                           IdCase{"next_high_char", 94 + 94, "!\""},
                                           IdCase{"last_of_two_chars", 94 + 94 * 94 - 1, "~~"},
                                           IdCase{"first_of_three_chars", 94 + 94 * 94, "!!!"}),
                         test::rowName<IdCase>);

TEST(IdCode, PrintableUniqueAndShortestFirst) {
  std::set<std::string> seen;
  for (std::size_t n = 0; n < 94 + 94 * 94 + 500; ++n) {
    const std::string code = vcdIdCode(n);
    for (char c : code) {
      EXPECT_GE(c, '!');
      EXPECT_LE(c, '~');
    }
    EXPECT_EQ(code.size(), n < 94 ? 1u : n < 94 + 94 * 94 ? 2u : 3u) << n;
    EXPECT_TRUE(seen.insert(code).second) << "code of " << n << " repeats: " << code;
  }
}

struct BitsCase {
  const char* name;
  std::uint64_t bits;
  unsigned width;
  std::string text;
};

class BitsTest : public ::testing::TestWithParam<BitsCase> {};

TEST_P(BitsTest, Text) {
  std::string out;
  appendVcdBits(out, GetParam().bits, GetParam().width);
  EXPECT_EQ(out, GetParam().text);
}

INSTANTIATE_TEST_SUITE_P(
    Values, BitsTest,
    ::testing::Values(BitsCase{"scalar_0", 0, 1, "0"}, BitsCase{"scalar_1", 1, 1, "1"},
                      BitsCase{"zero_vector", 0, 2, "b0"}, BitsCase{"se_0x2", 2, 2, "b10"},
                      BitsCase{"no_leading_zeros", 0x00010001, 32, "b10000000000000001"},
                      BitsCase{"minus_two_in_16_bits", 0xFFFE, 16, "b1111111111111110"},
                      BitsCase{"minus_one_in_64_bits", ~0ull, 64, "b" + std::string(64, '1')}),
    test::rowName<BitsCase>);

struct RealCase {
  const char* name;
  float value;
  const char* text;
};

class RealTest : public ::testing::TestWithParam<RealCase> {};

TEST_P(RealTest, Text) {
  std::string out;
  appendVcdReal(out, GetParam().value);
  EXPECT_EQ(out, GetParam().text);
}

INSTANTIATE_TEST_SUITE_P(
    Values, RealTest,
    ::testing::Values(RealCase{"zero", 0.0f, "r0"}, RealCase{"integral", 1500.0f, "r1500"},
                      RealCase{"shortest_that_reads_back", 0.1f, "r0.1"},
                      RealCase{"negative", -3.25f, "r-3.25"}, RealCase{"large", 1e20f, "r1e+20"},
                      RealCase{"infinity", std::numeric_limits<float>::infinity(), "rinf"},
                      RealCase{"nan", std::numeric_limits<float>::quiet_NaN(), "rnan"}),
    test::rowName<RealCase>);

struct StringCase {
  const char* name;
  const char* text;
  const char* vcd;
};

class StringTest : public ::testing::TestWithParam<StringCase> {};

TEST_P(StringTest, Text) {
  std::string out;
  appendVcdString(out, GetParam().text);
  EXPECT_EQ(out, GetParam().vcd);
}

INSTANTIATE_TEST_SUITE_P(Values, StringTest,
                         ::testing::Values(StringCase{"rule", "SE-001", "sSE-001"},
                                           StringCase{"rules", "SE-001,RDY-001", "sSE-001,RDY-001"},
                                           StringCase{"state_with_spaces", "ready to switch on",
                                                      "sready_to_switch_on"},
                                           StringCase{"none", "", "s\\000"}),
                         test::rowName<StringCase>);

// Every row of the field table is a signal, of the width and kind its values need.
TEST(VcdSignals, OnePerFieldRow) {
  const std::vector<VcdSignal>& signals = vcdSignals();
  ASSERT_EQ(signals.size(), kFieldCount);
  for (std::size_t i = 0; i < kFieldCount; ++i) {
    EXPECT_EQ(signals[i].field, &kFields[i]);
  }
}

struct SignalCase {
  const char* name;
  const char* filter;
  VcdVarKind kind;
  unsigned width;
  const char* scope;
  const char* signal;
};

class SignalTest : public ::testing::TestWithParam<SignalCase> {};

TEST_P(SignalTest, Declared) {
  const SignalCase& c = GetParam();
  for (const VcdSignal& s : vcdSignals()) {
    if (std::string(s.field->filter) != c.filter) continue;
    EXPECT_EQ(s.kind, c.kind);
    EXPECT_EQ(s.width, c.width);
    EXPECT_EQ(s.scope, c.scope);
    EXPECT_EQ(s.name, c.signal);
    return;
  }
  FAIL() << "no signal for " << c.filter;
}

INSTANTIATE_TEST_SUITE_P(
    Rows, SignalTest,
    ::testing::Values(
        SignalCase{"se", "ncservo.scw.se", VcdVarKind::Wire, 2, "scw", "se"},
        SignalCase{"servo_en", "ncservo.ssw.servo_en", VcdVarKind::Wire, 1, "ssw", "servo_en"},
        SignalCase{"scw_word", "ncservo.scw", VcdVarKind::Wire, 32, "scw", "scw"},
        SignalCase{"set_point", "ncservo.ssp", VcdVarKind::Integer, 32, "", "ssp"},
        SignalCase{"actpos", "ncservo.actpos", VcdVarKind::Integer, 64, "actpos", "actpos"},
        SignalCase{"actpos_part", "ncservo.actpos.zero_pulse", VcdVarKind::Integer, 32, "actpos",
                   "zero_pulse"},
        SignalCase{"ext_code", "ncservo.ext_code", VcdVarKind::Integer, 16, "", "ext_code"},
        SignalCase{"message_data", "ncservo.msg_data", VcdVarKind::Real, 64, "", "msg_data"},
        // Bits 4 and 25..31, shifted down to bit 4 with the gap kept, as fieldValue gives them.
        SignalCase{"sew_reserved_with_gap", "ncservo.sew.reserved", VcdVarKind::Wire, 28, "sew",
                   "reserved"}),
    test::rowName<SignalCase>);

AxisInfo axis(std::uint16_t index, std::string name) {
  AxisInfo info;
  info.index = index;
  info.name = std::move(name);
  return info;
}

struct ScopeCase {
  const char* name;
  std::vector<std::string> axes;
  std::vector<std::string> scopes;
};

class ScopeNameTest : public ::testing::TestWithParam<ScopeCase> {};

TEST_P(ScopeNameTest, Names) {
  std::vector<AxisInfo> axes;
  for (const std::string& name : GetParam().axes) {
    axes.push_back(axis(static_cast<std::uint16_t>(axes.size()), name));
  }
  EXPECT_EQ(vcdScopeNames(axes), GetParam().scopes);
}

INSTANTIATE_TEST_SUITE_P(
    Names, ScopeNameTest,
    ::testing::Values(ScopeCase{"as_named", {"axis0", "x-axis"}, {"axis0", "x-axis"}},
                      ScopeCase{"spaces_and_dots", {"spindle 1", "a.b"}, {"spindle_1", "a_b"}},
                      ScopeCase{"empty", {""}, {"axis0"}},
                      ScopeCase{"clash", {"a b", "a_b"}, {"a_b", "a_b_1"}},
                      ScopeCase{"bus_is_taken", {"bus"}, {"bus_0"}}),
    test::rowName<ScopeCase>);

struct SelectionCase {
  const char* name;
  std::vector<std::string> wanted;
  std::vector<bool> selected;  // of axis0 "x", axis1 "y", axis2 "2"
  bool valid;
};

class AxisSelectionTest : public ::testing::TestWithParam<SelectionCase> {};

TEST_P(AxisSelectionTest, Selects) {
  const SelectionCase& c = GetParam();
  const std::vector<AxisInfo> axes = {axis(0, "x"), axis(1, "y"), axis(2, "2")};
  for (std::size_t i = 0; i < axes.size(); ++i) {
    EXPECT_EQ(axisSelected(c.wanted, axes[i]), c.selected[i]) << axes[i].name;
  }
  EXPECT_EQ(checkAxisSelection(c.wanted, axes).has_value(), c.valid);
}

INSTANTIATE_TEST_SUITE_P(
    Entries, AxisSelectionTest,
    ::testing::Values(SelectionCase{"none_is_all", {}, {true, true, true}, true},
                      SelectionCase{"by_name", {"y"}, {false, true, false}, true},
                      SelectionCase{"by_index", {"0"}, {true, false, false}, true},
                      SelectionCase{"a_name_that_is_a_number", {"2"}, {false, false, true}, true},
                      SelectionCase{"mixed", {"x", "1"}, {true, true, false}, true},
                      SelectionCase{"unknown", {"z"}, {false, false, false}, false},
                      SelectionCase{"index_out_of_range", {"7"}, {false, false, false}, false}),
    test::rowName<SelectionCase>);

TEST(AxisSelection, ErrorNamesTheUnknownAndTheAxes) {
  const Status status = checkAxisSelection({"x", "z"}, {axis(0, "x"), axis(1, "y")});
  ASSERT_FALSE(status);
  EXPECT_EQ(status.error().text(), "--axis z: no such axis; the axes are 0 (x), 1 (y)");
}

TEST(GtkwPath, BesideTheVcd) {
  EXPECT_EQ(gtkwPathFor("run/waves.vcd"), "run/waves.gtkw");
  EXPECT_EQ(gtkwPathFor("waves"), "waves.gtkw");
  EXPECT_EQ(gtkwPathFor(".vcd"), ".vcd.gtkw");
}

}  // namespace
}  // namespace ncservo::report
