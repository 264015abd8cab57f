// The TOML configuration file (config.hpp, docs/configuration.md).
#include "ncservo/config/config.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/rules/rules.hpp"

namespace ncservo {
namespace {

// A full example, with a comment after the values as users write them.
constexpr const char* kInterfacesExample =
    R"(servo_ready_mode = 0          # optional; inferred when absent
telegram_failure_limit = 3    # COM-005
default_layout = true         # docs/protocol.md §9.4

[timeouts]                    # milliseconds, defaults when absent
drive_response = 20

[[axis]]                      # optional; without axes the layout comes from docs/protocol.md §9
name = "X"
outputs = 0x00010000          # logical address of the 10-byte RxPDO
inputs  = 0x00010028          # logical address of the 40-byte TxPDO
servo_ready_mode = 1          # optional, per axis

[[axis]]                      # an axis exchanged with FPRD/FPWR instead of logical commands
name = "Y"
station = 0x03EA              # configured station address
sm_outputs = 0x1100           # physical address of SM2 (RxPDO)
sm_inputs  = 0x1180           # physical address of SM3 (TxPDO)

[rules]
disable = ["MSG-001"]
severity = { "EC-002" = "error" }
)";

TEST(Config, InterfacesExampleParses) {
  const Result<Config> result = parseConfig(kInterfacesExample, "example.toml");
  ASSERT_TRUE(result.has_value()) << result.error().text();
  const Config& c = *result;
  EXPECT_EQ(c.path, "example.toml");
  EXPECT_EQ(c.servo_ready_mode, 0);
  EXPECT_EQ(c.telegram_failure_limit, 3u);
  EXPECT_TRUE(c.default_layout);
  EXPECT_EQ(c.timeouts_ms, (std::map<std::string, std::uint32_t>{{"drive_response", 20}}));
  ASSERT_EQ(c.axes.size(), 2u);

  const AxisConfig& x = c.axes[0];
  EXPECT_EQ(x.name, "X");
  EXPECT_EQ(x.outputs, 0x00010000u);
  EXPECT_EQ(x.inputs, 0x00010028u);
  EXPECT_EQ(x.servo_ready_mode, 1);
  EXPECT_FALSE(x.station.has_value());
  EXPECT_FALSE(x.sm_outputs.has_value());
  EXPECT_FALSE(x.sm_inputs.has_value());

  const AxisConfig& y = c.axes[1];
  EXPECT_EQ(y.name, "Y");
  EXPECT_EQ(y.station, 0x03EA);
  EXPECT_EQ(y.sm_outputs, 0x1100);
  EXPECT_EQ(y.sm_inputs, 0x1180);
  EXPECT_FALSE(y.outputs.has_value());
  EXPECT_FALSE(y.inputs.has_value());
  EXPECT_FALSE(y.servo_ready_mode.has_value());

  EXPECT_EQ(c.disabled_rules, std::vector<std::string>{"MSG-001"});
  EXPECT_EQ(c.severity_overrides, (std::map<std::string, std::string>{{"EC-002", "error"}}));
}

TEST(Config, EmptyFileGivesDefaults) {
  const Result<Config> result = parseConfig("", "empty.toml");
  ASSERT_TRUE(result.has_value());
  const Config& c = *result;
  EXPECT_FALSE(c.servo_ready_mode.has_value());
  EXPECT_EQ(c.telegram_failure_limit, 3u);
  EXPECT_TRUE(c.default_layout);
  EXPECT_TRUE(c.timeouts_ms.empty());
  EXPECT_TRUE(c.axes.empty());
  EXPECT_TRUE(c.disabled_rules.empty());
  EXPECT_TRUE(c.severity_overrides.empty());
}

TEST(Config, EveryTimeoutNameIsAccepted) {
  std::string text = "[timeouts]\n";
  std::uint32_t ms = 1;
  for (const TimeoutDef& timeout : kTimeouts)
    text += std::string(timeout.name) + " = " + std::to_string(ms++) + "\n";
  const Result<Config> result = parseConfig(text, "t.toml");
  ASSERT_TRUE(result.has_value()) << result.error().text();
  ASSERT_EQ(result->timeouts_ms.size(), kTimeouts.size());
  ms = 1;
  for (const TimeoutDef& timeout : kTimeouts) {
    EXPECT_EQ(result->timeouts_ms.at(timeout.name), ms++) << timeout.name;
  }
}

struct GoodCase {
  const char* name;
  const char* text;
  void (*check)(const Config&);
};
const GoodCase kGoodCases[] = {
    {"default layout off", "default_layout = false\n",
     [](const Config& c) { EXPECT_FALSE(c.default_layout); }},
    {"ready mode 1, limit 10", "servo_ready_mode = 1\ntelegram_failure_limit = 10\n",
     [](const Config& c) {
       EXPECT_EQ(c.servo_ready_mode, 1);
       EXPECT_EQ(c.telegram_failure_limit, 10u);
     }},
    {"dc_settled_ns 250", "dc_settled_ns = 250\n",
     [](const Config& c) { EXPECT_EQ(c.dc_settled_ns, 250u); }},
    {"dc_settled_ns default", "", [](const Config& c) { EXPECT_EQ(c.dc_settled_ns, 100u); }},
    {"unnamed axes get index names",
     "[[axis]]\noutputs = 0\ninputs = 20\n[[axis]]\noutputs = 10\ninputs = 60\n",
     [](const Config& c) {
       ASSERT_EQ(c.axes.size(), 2u);
       EXPECT_EQ(c.axes[0].name, "axis0");
       EXPECT_EQ(c.axes[1].name, "axis1");
       EXPECT_EQ(c.axes[1].inputs, 60u);
       EXPECT_EQ(c.axes[1].outputs, 10u);
     }},
    {"logical axis naming its station (ESM-002)",
     "[[axis]]\nname = \"L\"\noutputs = 0x10000\ninputs = 0x10028\nstation = 0x3E9\n",
     [](const Config& c) {
       ASSERT_EQ(c.axes.size(), 1u);
       EXPECT_EQ(c.axes[0].station, 0x3E9);
       EXPECT_EQ(c.axes[0].outputs, 0x10000u);
       EXPECT_FALSE(c.axes[0].physical());
     }},
    {"station axis",
     "[[axis]]\nname = \"S\"\nstation = 1001\nsm_outputs = 0x1100\nsm_inputs = 0x1180\n",
     [](const Config& c) {
       ASSERT_EQ(c.axes.size(), 1u);
       EXPECT_EQ(c.axes[0].station, 1001);
       EXPECT_EQ(c.axes[0].sm_outputs, 0x1100);
       EXPECT_TRUE(c.axes[0].physical());
     }},
    {"adjacent axes do not overlap",
     "[[axis]]\noutputs = 0x10000\ninputs = 0x10100\n[[axis]]\noutputs = 0x1000A\ninputs = "
     "0x10128\n",
     [](const Config& c) { EXPECT_EQ(c.axes.size(), 2u); }},
    {"outputs of one axis at another's inputs (one LRW image)",
     "[[axis]]\noutputs = 0x10000\ninputs = 0x10100\n[[axis]]\noutputs = 0x10100\ninputs = "
     "0x10000\n",
     [](const Config& c) { EXPECT_EQ(c.axes.size(), 2u); }},
    {"the same SM addresses on two stations",
     "[[axis]]\nstation = 1001\nsm_outputs = 0x1100\nsm_inputs = 0x1180\n[[axis]]\nstation = "
     "1002\nsm_outputs = 0x1100\nsm_inputs = 0x1180\n",
     [](const Config& c) { EXPECT_EQ(c.axes.size(), 2u); }},
    {"largest logical address", "[[axis]]\noutputs = 0xFFFFFFFF\ninputs = 0\n",
     [](const Config& c) { EXPECT_EQ(c.axes[0].outputs, 0xFFFFFFFFu); }},
    {"several rules",
     "[rules]\ndisable = [\"MSG-001\", \"COM-002\"]\n"
     "severity = { \"SE-001\" = \"warning\", \"ZP-003\" = \"info\" }\n",
     [](const Config& c) {
       EXPECT_EQ(c.disabled_rules, (std::vector<std::string>{"MSG-001", "COM-002"}));
       EXPECT_EQ(c.severity_overrides.at("SE-001"), "warning");
       EXPECT_EQ(c.severity_overrides.at("ZP-003"), "info");
     }},
    {"timing rules enabled with their limits",
     "cycle_jitter_percent = 25\nreturn_latency_us = 300\n[rules]\nenable = [\"com-006\", "
     "\"COM-007\"]\n",
     [](const Config& c) {
       EXPECT_EQ(c.limits.at("cycle_jitter_percent"), 25u);
       EXPECT_EQ(c.limits.at("return_latency_us"), 300u);
       EXPECT_EQ(c.enabled_rules, (std::vector<std::string>{"COM-006", "COM-007"}));
     }},
    {"rule IDs in any case, kept as the catalogue spells them",
     "[rules]\ndisable = [\"msg-001\", \"Com-002\"]\nseverity = { \"se-001\" = \"warning\" }\n",
     [](const Config& c) {
       EXPECT_EQ(c.disabled_rules, (std::vector<std::string>{"MSG-001", "COM-002"}));
       EXPECT_EQ(c.severity_overrides.at("SE-001"), "warning");
     }},
};

TEST(Config, GoodFiles) {
  for (const GoodCase& c : kGoodCases) {
    SCOPED_TRACE(c.name);
    const Result<Config> result = parseConfig(c.text, "good.toml");
    ASSERT_TRUE(result.has_value()) << result.error().text();
    c.check(*result);
  }
}

// One bad file per row: where the error must point, and a word of its message.
struct BadCase {
  const char* name;
  const char* text;
  std::uint32_t line;
  const char* key;
  const char* message;  // a part of the message
};
const BadCase kBadCases[] = {
    {"unknown top-level key", "servo_ready_mode = 0\nbogus = 1\n", 2, "bogus", "unknown key"},
    {"unknown axis key", "[[axis]]\nname = \"X\"\noutputs = 1\ncolour = \"red\"\n", 4,
     "axis[0].colour", "unknown key"},
    {"unknown key in the second axis",
     "[[axis]]\nname = \"X\"\noutputs = 1\ninputs = 11\n\n[[axis]]\nname = \"Y\"\nstatoin = 3\n", 8,
     "axis[1].statoin", "unknown key"},
    {"servo_ready_mode 2", "servo_ready_mode = 2\n", 1, "servo_ready_mode", "out of range"},
    {"servo_ready_mode -1", "\nservo_ready_mode = -1\n", 2, "servo_ready_mode", "out of range"},
    {"servo_ready_mode as a string", "servo_ready_mode = \"0\"\n", 1, "servo_ready_mode",
     "expected an integer"},
    {"axis servo_ready_mode 2", "[[axis]]\noutputs = 0\nservo_ready_mode = 2\n", 3,
     "axis[0].servo_ready_mode", "out of range"},
    {"outputs as a string", "[[axis]]\nname = \"X\"\noutputs = \"x\"\n", 3, "axis[0].outputs",
     "expected an integer"},
    {"outputs as a float", "[[axis]]\noutputs = 1.5\n", 2, "axis[0].outputs",
     "expected an integer"},
    {"station as a float beyond 64 bits (fuzz_config)", "[[axis]]\nstation=3E80\n", 2,
     "axis[0].station", "expected an integer"},
    {"outputs above 32 bits", "[[axis]]\noutputs = 0x100000000\n", 2, "axis[0].outputs",
     "out of range"},
    {"station above 16 bits", "[[axis]]\nstation = 0x10000\nsm_outputs = 0x1100\n", 2,
     "axis[0].station", "out of range"},
    {"axis name not a string", "[[axis]]\nname = 3\noutputs = 0\n", 2, "axis[0].name",
     "expected a string"},
    {"outputs and station in one axis",
     "[[axis]]\nname = \"X\"\noutputs = 0x10000\nstation = 0x3EA\nsm_outputs = 0x1100\n", 1,
     "axis[0]", "not both"},
    {"station alone", "[[axis]]\nname = \"Y\"\nstation = 0x3EA\n", 1, "axis[0]",
     "a station alone places no PDO"},
    {"sm_* without station", "[[axis]]\nname = \"Y\"\nsm_outputs = 0x1100\n", 1, "axis[0]",
     "station axis needs"},
    {"axis without addresses", "[[axis]]\nname = \"Z\"\n", 1, "axis[0]", "needs"},
    {"duplicate axis names",
     "[[axis]]\nname = \"X\"\noutputs = 0\ninputs = 20\n\n[[axis]]\nname = \"X\"\noutputs = "
     "50\ninputs = 70\n",
     6, "axis[1].name", "used twice"},
    {"axis without inputs", "\n[[axis]]\nname = \"X\"\noutputs = 0x10000\n", 2, "axis[0].inputs",
     "missing"},
    {"axis without outputs", "[[axis]]\nname = \"X\"\ninputs = 0x10028\n", 1, "axis[0].outputs",
     "missing"},
    {"second axis without inputs",
     "[[axis]]\noutputs = 0\ninputs = 10\n\n[[axis]]\nname = \"Y\"\noutputs = 50\n", 5,
     "axis[1].inputs", "missing"},
    // Two axes on the same bytes would each decode the other's data (docs/configuration.md).
    {"outputs inside another axis's",
     "[[axis]]\nname = \"X\"\noutputs = 0x10000\ninputs = 0x10100\n\n[[axis]]\nname = "
     "\"Y\"\noutputs = 0x10004\ninputs = 0x10100\n",
     8, "axis[1].outputs", "overlaps axis 'X'"},
    {"inputs at another axis's",
     "[[axis]]\nname = \"X\"\noutputs = 0x10000\ninputs = 0x10100\n\n[[axis]]\nname = "
     "\"Y\"\ninputs = 0x10127\noutputs = 0x1000A\n",
     8, "axis[1].inputs", "overlaps axis 'X'"},
    {"station axes on the same sync manager",
     "[[axis]]\nstation = 1001\nsm_outputs = 0x1100\nsm_inputs = 0x1180\n\n[[axis]]\nstation = "
     "1001\nsm_outputs = 0x1104\nsm_inputs = 0x1400\n",
     8, "axis[1].sm_outputs", "overlaps axis 'axis0'"},
    {"station axis without sm_inputs", "[[axis]]\nstation = 1001\nsm_outputs = 0x1100\n", 1,
     "axis[0].sm_inputs", "missing"},
    {"station axis without sm_outputs", "[[axis]]\nstation = 1001\nsm_inputs = 0x1180\n", 1,
     "axis[0].sm_outputs", "missing"},
    {"mistyped top-level key", "telegram_failure_limt = 3\n", 1, "telegram_failure_limt",
     "unknown key; did you mean 'telegram_failure_limit'?"},
    {"mistyped axis key", "[[axis]]\noutputs = 0\ninput = 40\n", 3, "axis[0].input",
     "unknown key; did you mean 'inputs'?"},
    {"mistyped rules key", "[rules]\ndisabel = []\n", 2, "rules.disabel",
     "unknown key; did you mean 'disable'?"},
    {"mistyped rule ID", "[rules]\ndisable = [\"MSG-01\"]\n", 2, "rules.disable",
     "did you mean 'MSG-001'?"},
    {"mistyped rule ID in severity", "[rules]\nseverity = { \"ec-02\" = \"error\" }\n", 2,
     "rules.severity.ec-02", "did you mean 'EC-002'?"},
    {"mistyped timeout", "[timeouts]\nfault_reactoin = 50\n", 2, "timeouts.fault_reactoin",
     "did you mean 'fault_reaction'?"},
    {"axis not an array of tables", "axis = 5\n", 1, "axis", "[[axis]]"},
    {"unknown timeout name", "[timeouts]\ndrive_response = 20\ndrive_respons = 20\n", 3,
     "timeouts.drive_respons", "unknown timeout"},
    {"negative timeout", "[timeouts]\nnc_release = -5\n", 2, "timeouts.nc_release", "out of range"},
    {"timeout as a string", "[timeouts]\nnc_release = \"50ms\"\n", 2, "timeouts.nc_release",
     "expected an integer"},
    {"timeouts not a table", "timeouts = 5\n", 1, "timeouts", "expected a table"},
    {"telegram_failure_limit 0", "telegram_failure_limit = 0\n", 1, "telegram_failure_limit",
     "out of range"},
    {"dc_settled_ns negative", "dc_settled_ns = -1\n", 1, "dc_settled_ns", "out of range"},
    {"dc_settled_ns as a string", "dc_settled_ns = \"100ns\"\n", 1, "dc_settled_ns",
     "expected an integer"},
    {"default_layout not a boolean", "default_layout = \"yes\"\n", 1, "default_layout",
     "expected true or false"},
    {"rules.disable with a non-ID", "[rules]\ndisable = [\"MSG-001\", \"msg-1\"]\n", 2,
     "rules.disable", "rule IDs"},
    {"rules.disable with a number", "[rules]\ndisable = [\n  \"MSG-001\",\n  7,\n]\n", 4,
     "rules.disable", "rule IDs"},
    {"rules.disable not an array", "[rules]\ndisable = \"MSG-001\"\n", 2, "rules.disable", "array"},
    {"severity with a bad level", "[rules]\nseverity = { \"EC-002\" = \"fatal\" }\n", 2,
     "rules.severity.EC-002", "\"error\", \"warning\" or \"info\""},
    {"severity with a non-ID", "[rules]\nseverity = { \"EC2\" = \"error\" }\n", 2,
     "rules.severity.EC2", "not a rule ID"},
    {"severity not a table", "[rules]\nseverity = \"error\"\n", 2, "rules.severity", "table"},
    {"unknown rules key", "[rules]\nenabled = []\n", 2, "rules.enabled",
     "unknown key; did you mean 'enable'?"},
    {"rules.enable with a non-ID", "[rules]\nenable = [\"COM-6\"]\n", 2, "rules.enable",
     "did you mean 'COM-006'?"},
    {"cycle_jitter_percent 0", "cycle_jitter_percent = 0\n", 1, "cycle_jitter_percent",
     "out of range [1, 100]"},
    {"return_latency_us as a float", "return_latency_us = 2.5\n", 1, "return_latency_us",
     "expected an integer"},
    {"mistyped limit", "cycle_jitter_percnt = 10\n", 1, "cycle_jitter_percnt",
     "did you mean 'cycle_jitter_percent'?"},
    {"rules not a table", "rules = 1\n", 1, "rules", "expected a table"},
    {"TOML syntax error", "default_layout = true\n\ntelegram_failure_limit = = 3\n", 3, "", ""},
    {"TOML unterminated string", "[[axis]]\nname = \"X\noutputs = 0\n", 2, "", ""},
    {"TOML duplicate key", "servo_ready_mode = 0\nservo_ready_mode = 1\n", 2, "", ""},
};

TEST(Config, BadFilesNameLineAndKey) {
  for (const BadCase& c : kBadCases) {
    SCOPED_TRACE(c.name);
    const Result<Config> result = parseConfig(c.text, "bad.toml");
    ASSERT_FALSE(result.has_value());
    const Error& e = result.error();
    EXPECT_EQ(e.path, "bad.toml");
    EXPECT_EQ(e.line, c.line) << e.text();
    EXPECT_EQ(e.key, c.key) << e.text();
    EXPECT_NE(e.message.find(c.message), std::string::npos) << e.text();
    EXPECT_FALSE(e.message.empty());
    const std::string where = "bad.toml:" + std::to_string(c.line) + ": ";
    EXPECT_EQ(e.text().substr(0, where.size()), where);
  }
}

struct TextCase {
  Error error;
  const char* text;
};
const TextCase kTextCases[] = {
    {{"cfg.toml", 3, 0, "axis[0].outputs", "expected an integer"},
     "cfg.toml:3: key 'axis[0].outputs': expected an integer"},
    {{"/etc/ncservo.toml", 12, 0, "timeouts.x", "unknown timeout"},
     "/etc/ncservo.toml:12: key 'timeouts.x': unknown timeout"},
    {{"cfg.toml", 2, 0, "", "expected '='"}, "cfg.toml:2: expected '='"},
    {{"missing.toml", 0, 0, "", "cannot open the configuration file"},
     "missing.toml: cannot open the configuration file"},
};

TEST(Config, ErrorText) {
  for (const TextCase& c : kTextCases) EXPECT_EQ(c.error.text(), c.text);
  const Result<Config> result = parseConfig("[[axis]]\nname = \"X\"\noutputs = \"x\"\n", "my.toml");
  ASSERT_FALSE(result.has_value());
  EXPECT_EQ(result.error().text(), "my.toml:3: key 'axis[0].outputs': expected an integer");
}

TEST(Config, LoadMissingFileNamesTheFile) {
  const std::string path = ::testing::TempDir() + "ncservo-no-such-config.toml";
  std::remove(path.c_str());
  const Result<Config> result = loadConfig(path);
  ASSERT_FALSE(result.has_value());
  EXPECT_EQ(result.error().path, path);
  EXPECT_NE(result.error().text().find(path), std::string::npos) << result.error().text();
}

// docs/configuration.md explains every key of the top level in its table.
TEST(Config, EveryTopLevelKeyHasADocumentedRow) {
  std::ifstream doc(NCSERVO_DOCS_DIR "/configuration.md");
  ASSERT_TRUE(doc.good());
  const std::string text((std::istreambuf_iterator<char>(doc)), std::istreambuf_iterator<char>());
  for (const std::string& key : topLevelConfigKeys()) {
    const bool table = key == "timeouts" || key == "rules";
    const std::string wanted = key == "axis" ? "## `[[axis]]`"
                               : table       ? "## `[" + key + "]`"
                                             : "\n| `" + key + "` |";
    EXPECT_NE(text.find(wanted), std::string::npos) << "no \"" << wanted << "\" for " << key;
  }
}

TEST(Config, LoadFileFromDisk) {
  const std::string path = ::testing::TempDir() + "ncservo-unit-config.toml";
  std::FILE* file = std::fopen(path.c_str(), "wb");
  ASSERT_NE(file, nullptr);
  std::fputs(kInterfacesExample, file);
  std::fclose(file);
  const Result<Config> good = loadConfig(path);
  ASSERT_TRUE(good.has_value()) << good.error().text();
  EXPECT_EQ(good->path, path);
  EXPECT_EQ(good->axes.size(), 2u);

  file = std::fopen(path.c_str(), "wb");
  ASSERT_NE(file, nullptr);
  std::fputs("\n\nbogus = 1\n", file);
  std::fclose(file);
  const Result<Config> bad = loadConfig(path);
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().text(), path + ":3: key 'bogus': unknown key");
  std::remove(path.c_str());
}

}  // namespace
}  // namespace ncservo
