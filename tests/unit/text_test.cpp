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

const std::vector<std::string> kLevels{"error", "warning", "info", "never"};
const std::vector<std::string> kFieldish{"fields", "fieldset", "fields-list"};

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
    {"warn", &kLevels, "warning"},  // cut short: the one name it begins
    {"WARN", &kLevels, "warning"},
    {"e", &kLevels, std::nullopt},  // one letter is too little to go on
    {"wa", &kLevels, "warning"},
    {"fields", &kFieldish, std::nullopt},  // begins two names: neither
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

// RFC 3986: a path as a URI reference's path, and an absolute path as a file: URI.
struct UriCase {
  const char* name;
  const char* path;
  const char* uri_path;
  const char* file_uri;  // of the path made absolute under /data
};
const UriCase kUriCases[] = {
    {"plain", "x.pcap", "x.pcap", "file:///data/x.pcap"},
    {"unreserved kept", "a-b_c.d~e/F9.pcapng", "a-b_c.d~e/F9.pcapng",
     "file:///data/a-b_c.d~e/F9.pcapng"},
    {"space", "Pr 1/x.pcap", "Pr%201/x.pcap", "file:///data/Pr%201/x.pcap"},
    {"non-ASCII as UTF-8 bytes", "Pr\u00fcfstand 1/x.pcap", "Pr%C3%BCfstand%201/x.pcap",
     "file:///data/Pr%C3%BCfstand%201/x.pcap"},
    {"colon: no scheme", "c:x.pcap", "c%3Ax.pcap", "file:///data/c%3Ax.pcap"},
    {"reserved and percent", "a#b?c%d[e]@f+g,h;i=j&k!l$m'n(o)p*q",
     "a%23b%3Fc%25d%5Be%5D%40f%2Bg%2Ch%3Bi%3Dj%26k%21l%24m%27n%28o%29p%2Aq",
     "file:///data/a%23b%3Fc%25d%5Be%5D%40f%2Bg%2Ch%3Bi%3Dj%26k%21l%24m%27n%28o%29p%2Aq"},
    {"dot segments stay", "../up/./x.pcap", "../up/./x.pcap", "file:///data/../up/./x.pcap"},
    {"control byte", "a\tb", "a%09b", "file:///data/a%09b"},
};

TEST(Text, UriPath) {
  for (const UriCase& c : kUriCases) {
    EXPECT_EQ(uriPath(c.path), c.uri_path) << c.name;
    EXPECT_EQ(fileUri(std::string("/data/") + c.path), c.file_uri) << c.name;
  }
}

}  // namespace
}  // namespace ncservo
