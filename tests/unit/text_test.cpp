// Matching typed names ("did you mean", IDs in any case) and quoting CSV fields (text.hpp).
#include "ncservo/base/text.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <vector>

namespace ncservo {
namespace {

const std::vector<std::string> kCommands{"decode", "validate", "rules", "fields", "simulate"};
const std::vector<std::string> kRuleIds{"SE-001", "SE-002", "MSG-001", "COM-005", "ESM-004"};
const std::vector<std::string> kOptions{"--format",   "--fail-on", "--disable",
                                        "--severity", "--timeout", "--output"};

struct ClosestCase {
  const char* typed;
  const std::vector<std::string>* candidates;
  std::optional<std::string> closest;
};
const ClosestCase kClosestCases[] = {
    {"valdate", &kCommands, "validate"},   // a letter left out
    {"valiadte", &kCommands, "validate"},  // two letters swapped
    {"decdoe", &kCommands, "decode"},
    {"rule", &kCommands, "rules"},
    {"simulat", &kCommands, "simulate"},
    {"VALIDATE", &kCommands, std::nullopt},  // a name in another case is the name itself
    {"validate", &kCommands, std::nullopt},
    {"xyz", &kCommands, std::nullopt},  // nothing close
    {"", &kCommands, std::nullopt},
    {"se-01", &kRuleIds, "SE-001"},
    {"MSG-01", &kRuleIds, "MSG-001"},
    {"COM-0005", &kRuleIds, "COM-005"},
    {"XX-999", &kRuleIds, std::nullopt},
    {"--formt", &kOptions, "--format"},
    {"--disble", &kOptions, "--disable"},
    {"--timeouts", &kOptions, "--timeout"},
    {"--fail", &kOptions, "--fail-on"},
    {"--colour", &kOptions, std::nullopt},
};

TEST(Text, ClosestName) {
  for (const ClosestCase& c : kClosestCases) {
    SCOPED_TRACE(c.typed);
    EXPECT_EQ(closestName(c.typed, *c.candidates), c.closest);
  }
}

TEST(Text, DidYouMean) {
  EXPECT_EQ(didYouMean("valdate", kCommands), "; did you mean 'validate'?");
  EXPECT_EQ(didYouMean("xyz", kCommands), "");
}

struct CaseCase {
  const char* a;
  const char* b;
  bool equal;
};
const CaseCase kCaseCases[] = {
    {"MSG-001", "msg-001", true}, {"MSG-001", "MSG-001", true},  {"Se-001", "sE-001", true},
    {"MSG-001", "MSG-01", false}, {"MSG-001", "MSG_001", false}, {"", "", true},
};

TEST(Text, EqualsIgnoringCase) {
  for (const CaseCase& c : kCaseCases) EXPECT_EQ(equalsIgnoringCase(c.a, c.b), c.equal) << c.a;
}

// RFC 4180: a field holding a comma, a quote or a line break is quoted, its quotes doubled.
struct CsvCase {
  const char* name;
  std::string text;
  bool always;
  std::string field;
};
const CsvCase kCsvCases[] = {
    {"plain", "X", false, "X"},
    {"empty", "", false, ""},
    {"comma", "X,1", false, "\"X,1\""},
    {"quote", "the \"X\" axis", false, "\"the \"\"X\"\" axis\""},
    {"newline", "X\nY", false, "\"X\nY\""},
    {"carriage return", "X\rY", false, "\"X\rY\""},
    {"only a quote", "\"", false, "\"\"\"\""},
    {"spaces stay as they are", " X ", false, " X "},
    {"always quoted", "motor speed 1500.0 rpm", true, "\"motor speed 1500.0 rpm\""},
    {"always quoted, empty", "", true, "\"\""},
    {"always quoted, with a quote", "a\"b", true, "\"a\"\"b\""},
};

TEST(Text, CsvField) {
  for (const CsvCase& c : kCsvCases) EXPECT_EQ(csvField(c.text, c.always), c.field) << c.name;
}

}  // namespace
}  // namespace ncservo
