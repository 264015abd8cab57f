// `ncservo simulate`'s library (simulator.hpp, capture_writer.hpp): options and faults, the
// frame stream (docs/protocol.md §8, §9.4), its layout, and the stream through the validator.
#include "ncservo/sim/simulator.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/capture/capture_writer.hpp"
#include "ncservo/config/config.hpp"
#include "ncservo/layout/eni.hpp"
#include "ncservo/layout/layout_learner.hpp"
#include "ncservo/model/esc_errors.hpp"
#include "ncservo/model/mailbox_tracker.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"
#include "ncservo/rules/rules.hpp"
#include "ncservo/rules/validator.hpp"
#include "ncservo/sim/faults.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "status_text.hpp"

namespace ncservo::sim {
namespace {

using test::Bytes;

struct Frame {
  std::int64_t time_ns;
  Bytes bytes;
};

// Runs a simulation (its options must resolve) and keeps every frame.
std::vector<Frame> simulate(SimOptions options) {
  const std::string error = test::statusText(resolveOptions(options));
  EXPECT_EQ(error, "");
  std::vector<Frame> frames;
  Simulator simulator(options);
  const auto count = simulator.run([&](const SimFrame& f) {
    frames.push_back({f.time_ns, Bytes(f.data, f.data + f.size)});
    return true;
  });
  EXPECT_TRUE(count.has_value());
  if (count) {
    EXPECT_EQ(*count, frames.size());
  }
  return frames;
}

std::uint64_t fnv1a(const std::vector<Frame>& frames) {
  std::uint64_t h = 0xCBF29CE484222325ULL;
  auto mix = [&](std::uint8_t byte) { h = (h ^ byte) * 0x100000001B3ULL; };
  for (const Frame& f : frames) {
    for (int i = 0; i < 8; ++i)
      mix(static_cast<std::uint8_t>(static_cast<std::uint64_t>(f.time_ns) >> (8 * i)));
    for (std::uint8_t b : f.bytes) mix(b);
    mix(0xFF);
  }
  return h;
}

EcatFrame walked(const Bytes& bytes) {
  EcatFrame frame;
  walkPacket(LinkType::Ethernet, ByteReader(bytes.data(), bytes.size()), frame);
  return frame;
}
bool returnedMac(const Bytes& bytes) {
  return (bytes[6] & 0x02) != 0;  // source MAC, locally-administered bit
}

SimOptions options(Scenario scenario, int axes, double duration_s) {
  SimOptions o;
  o.scenario = scenario;
  o.axes = axes;
  o.duration_s = duration_s;
  return o;
}

// --- parseCycleDisturbance ---

TEST(ParseCycleDisturbance, Rows) {
  struct Row {
    const char* option;
    const char* text;
    std::optional<std::pair<double, int>> parsed;  // none: an error
    const char* error;
  };
  const Row rows[] = {
      {"--late-cycle", "1.5:400", std::pair{1.5, 400}, ""},
      {"--lost-cycles", "0:3", std::pair{0.0, 3}, ""},
      {"--late-cycle", "1.5", std::nullopt, "--late-cycle 1.5: expected SECONDS:US, e.g. 1.5:400"},
      {"--lost-cycles", "1:0", std::nullopt, "--lost-cycles 1:0: expected SECONDS:N, e.g. 1.5:3"},
      {"--lost-cycles", "-1:2", std::nullopt, "--lost-cycles -1:2: expected SECONDS:N, e.g. 1.5:3"},
      {"--late-cycle", "1:4x", std::nullopt,
       "--late-cycle 1:4x: expected SECONDS:US, e.g. 1.5:400"},
  };
  for (const Row& row : rows) {
    SCOPED_TRACE(row.text);
    const Result<CycleDisturbance> d = parseCycleDisturbance(row.option, row.text);
    if (!row.parsed) {
      ASSERT_FALSE(d.has_value());
      EXPECT_EQ(d.error().text(), row.error);
      continue;
    }
    ASSERT_TRUE(d.has_value()) << d.error().text();
    EXPECT_EQ(d->at_s, row.parsed->first);
    EXPECT_EQ(d->amount, row.parsed->second);
  }
}

// --- parseFault ---

struct ParseRow {
  const char* text;
  std::optional<RuleId> rule;  // none: an error
  std::optional<double> at_s;
  std::optional<int> axis;
  const char* error;          // the exact message, where the row gives one
  const char* bug = nullptr;  // a known simulator bug: the row is skipped until it is fixed
};
class ParseFault : public ::testing::TestWithParam<ParseRow> {};

TEST_P(ParseFault, Rows) {
  const ParseRow& row = GetParam();
  if (row.bug != nullptr) GTEST_SKIP() << row.bug;
  const Result<FaultRequest> parsed = parseFault(row.text);
  const std::optional<FaultRequest> fault =
      parsed ? std::optional<FaultRequest>(*parsed) : std::nullopt;
  const std::string error = parsed ? std::string() : parsed.error().text();
  if (!row.rule) {
    EXPECT_FALSE(fault.has_value()) << row.text;
    EXPECT_FALSE(error.empty()) << row.text;
    if (row.error != nullptr) {
      EXPECT_EQ(error, row.error);
    }
    return;
  }
  ASSERT_TRUE(fault.has_value()) << row.text << ": " << error;
  EXPECT_EQ(fault->rule, *row.rule);
  EXPECT_EQ(fault->at_s, row.at_s);
  EXPECT_EQ(fault->axis, row.axis);
  EXPECT_EQ(fault->text, row.text);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, ParseFault,
    ::testing::Values(
        ParseRow{"SE-001", RuleId::Se001, std::nullopt, std::nullopt, nullptr},
        ParseRow{"se-001@1.5", RuleId::Se001, 1.5, std::nullopt, nullptr},
        ParseRow{"ZP-001@2:3", RuleId::Zp001, 2.0, 3, nullptr},
        ParseRow{"COM-002@1", RuleId::Com002, 1.0, std::nullopt, nullptr},
        ParseRow{"ESM-004:0", RuleId::Esm004, std::nullopt, 0, nullptr},
        ParseRow{"XX-1", std::nullopt, std::nullopt, std::nullopt,
                 "--fault XX-1: no rule 'XX-1' (see `ncservo rules`)"},
        ParseRow{"SE-001@x", std::nullopt, std::nullopt, std::nullopt,
                 "--fault SE-001@x: expected RULE[@SECONDS][:AXIS], e.g. SE-001@1.2:0"},
        ParseRow{"SE-001:-1", std::nullopt, std::nullopt, std::nullopt, nullptr},
        ParseRow{"SE-001@-2", std::nullopt, std::nullopt, std::nullopt, nullptr},
        ParseRow{"SE-001@1.5s", std::nullopt, std::nullopt, std::nullopt, nullptr},
        ParseRow{"SE-001:1x", std::nullopt, std::nullopt, std::nullopt, nullptr},
        ParseRow{"SE-001@nan", std::nullopt, std::nullopt, std::nullopt, nullptr},
        ParseRow{"", std::nullopt, std::nullopt, std::nullopt, nullptr},
        ParseRow{"SE-001@", std::nullopt, std::nullopt, std::nullopt,
                 "--fault SE-001@: expected RULE[@SECONDS][:AXIS], e.g. SE-001@1.2:0"},
        ParseRow{"SE-001@1:", std::nullopt, std::nullopt, std::nullopt, nullptr}));

// --- resolveOptions ---

struct ResolveRow {
  const char* name;
  std::function<void(SimOptions&)> change;
  const char* error;  // a part of the message; "" = resolves
};
class ResolveOptions : public ::testing::TestWithParam<ResolveRow> {};

FaultRequest fault(const char* text) {
  const Result<FaultRequest> f = parseFault(text);
  EXPECT_TRUE(f.has_value()) << f.error().text();
  return f.value_or(FaultRequest{});
}

TEST_P(ResolveOptions, Rows) {
  const ResolveRow& row = GetParam();
  SimOptions o;
  row.change(o);
  const std::string error = test::statusText(resolveOptions(o));
  if (std::string(row.error).empty()) {
    EXPECT_EQ(error, "") << row.name;
  } else {
    EXPECT_NE(error.find(row.error), std::string::npos) << row.name << ": " << error;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Rows, ResolveOptions,
    ::testing::Values(
        ResolveRow{"defaults", [](SimOptions&) {}, ""},
        ResolveRow{"axes_0", [](SimOptions& o) { o.axes = 0; }, "--axes 0: from 1 to 32"},
        ResolveRow{"axes_33", [](SimOptions& o) { o.axes = 33; }, "--axes 33: from 1 to 32"},
        ResolveRow{"axes_32", [](SimOptions& o) { o.axes = 32; }, ""},
        ResolveRow{"cycle_124", [](SimOptions& o) { o.cycle_us = 124; },
                   "--cycle-us 124: from 125 to 10000"},
        ResolveRow{"cycle_10001", [](SimOptions& o) { o.cycle_us = 10001; }, "--cycle-us 10001"},
        ResolveRow{"cycle_125", [](SimOptions& o) { o.cycle_us = 125; }, ""},
        ResolveRow{"io_slaves_33", [](SimOptions& o) { o.io_slaves = 33; },
                   "--io-slaves 33: from 0 to 32"},
        ResolveRow{"ready_mode_2", [](SimOptions& o) { o.ready_mode = 2; },
                   "--ready-mode 2: 0 or 1"},
        ResolveRow{"loss_too_big", [](SimOptions& o) { o.loss = 0.6; },
                   "--loss 0.6: from 0 to 0.5"},
        ResolveRow{"duration_too_short", [](SimOptions& o) { o.duration_s = 0.5; },
                   "--duration 0.5: from 1 s to 24 h"},
        ResolveRow{"faults_too_short",
                   [](SimOptions& o) {
                     o.scenario = Scenario::Faults;
                     o.duration_s = 4.0;
                   },
                   "--scenario faults needs --duration 4.3 or more"},
        ResolveRow{"jitter_fifth", [](SimOptions& o) { o.jitter_us = 200; }, ""},
        ResolveRow{"jitter_too_big", [](SimOptions& o) { o.jitter_us = 201; },
                   "--jitter-us 201: from 0 to a fifth of the cycle (200)"},
        ResolveRow{"latency_half", [](SimOptions& o) { o.latency_us = 500; }, ""},
        ResolveRow{"latency_too_big", [](SimOptions& o) { o.latency_us = 501; },
                   "--latency-us 501: from 0 to half the cycle (500)"},
        ResolveRow{"late_cycle_latest",
                   [](SimOptions& o) {
                     o.jitter_us = 100;
                     o.late_cycles.push_back({1.0, 799, "1:799"});
                   },
                   ""},
        ResolveRow{"late_cycle_too_late",
                   [](SimOptions& o) {
                     o.jitter_us = 100;
                     o.late_cycles.push_back({1.0, 800, "1:800"});
                   },
                   "--late-cycle 1:800: at most 799 us late"},
        ResolveRow{"faults_3_axes",
                   [](SimOptions& o) {
                     o.scenario = Scenario::Faults;
                     o.axes = 3;
                   },
                   "--scenario faults needs at least 4 axes"},
        ResolveRow{"faults_no_startup",
                   [](SimOptions& o) {
                     o.scenario = Scenario::Faults;
                     o.startup = false;
                   },
                   "--scenario faults needs the start-up"},
        ResolveRow{"esm_with_time", [](SimOptions& o) { o.faults = {fault("ESM-001@1")}; },
                   "--fault ESM-001@1: ESM-001 happens in the start-up; give no @time"},
        ResolveRow{"esm_without_startup",
                   [](SimOptions& o) {
                     o.startup = false;
                     o.faults = {fault("ESM-004")};
                   },
                   "--fault ESM-004: ESM-004 happens in the start-up"},
        ResolveRow{"zp001_even_axis", [](SimOptions& o) { o.faults = {fault("ZP-001:2")}; },
                   "--fault ZP-001:2: ZP-001 needs an incremental axis (odd index)"},
        ResolveRow{"zp001_odd_axis", [](SimOptions& o) { o.faults = {fault("ZP-001:3")}; }, ""},
        ResolveRow{"zp001_one_axis",
                   [](SimOptions& o) {
                     o.axes = 1;
                     o.faults = {fault("ZP-001")};
                   },
                   "needs an incremental axis"},
        ResolveRow{"zp003_odd_axis", [](SimOptions& o) { o.faults = {fault("ZP-003:1")}; },
                   "--fault ZP-003:1: ZP-003 needs an absolute axis (even index)"},
        ResolveRow{"axis_out_of_range", [](SimOptions& o) { o.faults = {fault("SE-001:4")}; },
                   "--fault SE-001:4: axis 4 does not exist (--axes 4)"},
        ResolveRow{"com002_with_axis", [](SimOptions& o) { o.faults = {fault("COM-002:1")}; },
                   "--fault COM-002:1: COM-002 concerns the whole bus; no :axis"},
        ResolveRow{"time_before_quiet", [](SimOptions& o) { o.faults = {fault("SE-001@0.6")}; },
                   "is outside the quiet part of the run (0.65 s to 1.34 s)"},
        ResolveRow{"time_after_quiet", [](SimOptions& o) { o.faults = {fault("SE-001@2.7")}; },
                   "outside the quiet part"},
        ResolveRow{"time_quiet_start", [](SimOptions& o) { o.faults = {fault("SE-001@0.65")}; },
                   ""},
        ResolveRow{"time_quiet_end", [](SimOptions& o) { o.faults = {fault("SE-001@1.34")}; }, ""},
        ResolveRow{"time_after_quiet_end", [](SimOptions& o) { o.faults = {fault("SE-001@1.35")}; },
                   "outside the quiet part"},
        ResolveRow{"time_without_startup",
                   [](SimOptions& o) {
                     o.startup = false;
                     o.faults = {fault("SE-001@0.45")};
                   },
                   ""},
        ResolveRow{"cia402_33", [](SimOptions& o) { o.cia402_drives = 33; },
                   "--cia402 33: from 0 to 32"},
        ResolveRow{"io_task_not_a_multiple",
                   [](SimOptions& o) {
                     o.io_slaves = 2;
                     o.io_task_us = 2500;
                   },
                   "--io-task-us 2500: a multiple of the cycle (1000 us)"},
        ResolveRow{"io_task_without_terminals", [](SimOptions& o) { o.io_task_us = 10000; },
                   "--io-task-us needs terminals"},
        ResolveRow{"io_task_10ms",
                   [](SimOptions& o) {
                     o.io_slaves = 2;
                     o.io_task_us = 10000;
                   },
                   ""},
        ResolveRow{"idle_faults_scenario",
                   [](SimOptions& o) {
                     o.scenario = Scenario::Faults;
                     o.idle_s = 1;
                   },
                   "--idle: not with --scenario faults"},
        ResolveRow{"idle_all_with_fault",
                   [](SimOptions& o) {
                     o.idle_all = true;
                     o.faults = {fault("SE-001")};
                   },
                   "--idle all: nothing is enabled"},
        ResolveRow{"idle_moves_the_quiet_part",
                   [](SimOptions& o) {
                     o.idle_s = 1;
                     o.duration_s = 4;
                     o.faults = {fault("SE-001@1.6")};
                   },
                   "outside the quiet part of the run (1.65 s to 2.34 s)"},
        ResolveRow{"idle_fault_after_it",
                   [](SimOptions& o) {
                     o.idle_s = 1;
                     o.duration_s = 4;
                     o.faults = {fault("SE-001@2.0")};
                   },
                   ""},
        ResolveRow{"start_in_soak",
                   [](SimOptions& o) {
                     o.scenario = Scenario::Soak;
                     o.mid_start = MidStart::Homing;
                   },
                   "--start-in: a commissioning run only"},
        ResolveRow{"start_in_startup_fault",
                   [](SimOptions& o) {
                     o.mid_start = MidStart::Fault;
                     o.faults = {fault("ESM-004")};
                   },
                   "which --start-in cuts away"},
        ResolveRow{"start_in_fault_before_the_moment",
                   [](SimOptions& o) {
                     o.mid_start = MidStart::Fault;
                     o.duration_s = 5;
                     o.faults = {fault("SE-001@1.0")};
                   },
                   "outside the quiet part"},
        ResolveRow{"incidents", [](SimOptions& o) { o.scenario = Scenario::Incidents; }, ""},
        ResolveRow{"incidents_3_axes",
                   [](SimOptions& o) {
                     o.scenario = Scenario::Incidents;
                     o.axes = 3;
                   },
                   "--scenario incidents needs at least 4 axes"},
        ResolveRow{"incidents_too_short",
                   [](SimOptions& o) {
                     o.scenario = Scenario::Incidents;
                     o.duration_s = 5.9;
                   },
                   "--scenario incidents needs --duration 6 or more"},
        ResolveRow{"incidents_with_a_fault",
                   [](SimOptions& o) {
                     o.scenario = Scenario::Incidents;
                     o.faults = {fault("SE-001")};
                   },
                   "takes no --fault"},
        ResolveRow{"incidents_with_loss",
                   [](SimOptions& o) {
                     o.scenario = Scenario::Incidents;
                     o.loss = 0.01;
                   },
                   "takes no --fault, --loss"},
        ResolveRow{"incidents_idle",
                   [](SimOptions& o) {
                     o.scenario = Scenario::Incidents;
                     o.idle_s = 1;
                   },
                   "--idle: not with --scenario incidents"}),
    [](const ::testing::TestParamInfo<ResolveRow>& row) { return std::string(row.param.name); });

bool incrementalAxis(int axis) {
  return axis % 2 == 1;  // the simulator's set-up: odd axes have an incremental encoder
}

struct DefaultRow {
  const char* fault;
  int axes;
  bool startup;
  bool needs_incremental, needs_absolute, bus, in_startup;
};
class ResolveDefaults : public ::testing::TestWithParam<DefaultRow> {};

TEST_P(ResolveDefaults, TimeAndAxisFilledIn) {
  const DefaultRow& row = GetParam();
  SimOptions o;
  o.axes = row.axes;
  o.startup = row.startup;
  o.faults = {fault(row.fault)};
  ASSERT_EQ(test::statusText(resolveOptions(o)), "") << row.fault;
  ASSERT_TRUE(o.duration_s.has_value());
  const FaultRequest& f = o.faults[0];
  if (row.in_startup) {
    EXPECT_FALSE(f.at_s.has_value());
  } else {
    ASSERT_TRUE(f.at_s.has_value());
    const double start = row.startup ? 0.2 : 0.0;  // the start-up's length
    EXPECT_GE(*f.at_s, start + 0.45) << row.fault;
    EXPECT_LE(*f.at_s, *o.duration_s - 0.4) << row.fault;
  }
  if (row.bus) {
    EXPECT_FALSE(f.axis.has_value()) << row.fault;
    return;
  }
  ASSERT_TRUE(f.axis.has_value()) << row.fault;
  EXPECT_GE(*f.axis, 0);
  EXPECT_LT(*f.axis, row.axes);
  if (row.needs_incremental) {
    EXPECT_TRUE(incrementalAxis(*f.axis)) << row.fault;
  }
  if (row.needs_absolute) {
    EXPECT_FALSE(incrementalAxis(*f.axis)) << row.fault;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Rows, ResolveDefaults,
    ::testing::Values(DefaultRow{"SE-001", 4, true, false, false, false, false},
                      DefaultRow{"SE-001", 1, false, false, false, false, false},
                      DefaultRow{"ZP-001", 4, true, true, false, false, false},
                      DefaultRow{"ZP-001", 2, true, true, false, false, false},
                      DefaultRow{"ZP-003", 4, true, false, true, false, false},
                      DefaultRow{"ZP-003", 2, true, false, true, false, false},
                      DefaultRow{"COM-002", 4, true, false, false, true, false},
                      DefaultRow{"COM-005", 4, false, false, false, true, false},
                      DefaultRow{"ESM-001", 4, true, false, false, false, true},
                      DefaultRow{"ESM-004", 3, true, false, false, false, true}));

// --- the fault catalogue ---

std::set<std::string> documentedCompanions(const char* code) {
  const std::map<std::string, std::set<std::string>> table = {{"ESM-001", {"ESM-003"}},
                                                              {"COM-003", {"COM-004"}},
                                                              {"COM-005", {"COM-004"}},
                                                              {"LNK-001", {"COM-004"}}};
  const auto it = table.find(code);
  return it == table.end() ? std::set<std::string>{} : it->second;
}

TEST(FaultCatalogue, EveryRuleHasARecipeRow) {
  std::set<RuleId> rows;
  for (const FaultRecipe& recipe : faultRecipes()) {
    EXPECT_TRUE(rows.insert(recipe.rule).second) << ruleDef(recipe.rule).code << ": two rows";
  }
  for (const RuleDef& rule : kRules) {
    const FaultRecipe* recipe = faultRecipe(rule.id);
    ASSERT_NE(recipe, nullptr) << rule.code << " has no row in the fault recipes (faults.cpp)";
    if (!recipe->injectable()) {
      EXPECT_EQ(std::string(recipe->description).rfind("not injectable: ", 0), 0U)
          << rule.code << ": a row without a recipe says why";
      continue;
    }
    // Where the faults scenario puts it: an axis of its 4 that suits the rule, or the bus.
    const int axis = recipe->scenario.axis;
    if (recipe->need == AxisNeed::None) {
      EXPECT_EQ(axis, -1) << rule.code;
    } else {
      EXPECT_TRUE(axis >= 0 && axis < 4) << rule.code;
      if (recipe->need == AxisNeed::Incremental) {
        EXPECT_TRUE(isIncrementalAxis(axis)) << rule.code;
      }
      if (recipe->need == AxisNeed::Absolute) {
        EXPECT_FALSE(isIncrementalAxis(axis)) << rule.code;
      }
    }
  }
  EXPECT_EQ(rows.size(), kRules.size());
}

TEST(FaultCatalogue, EveryRuleHasADescriptionAndItsCompanions) {
  for (const RuleDef& rule : kRules) {
    const char* description = faultDescription(rule.id);
    ASSERT_NE(description, nullptr) << rule.code;
    EXPECT_GT(std::string(description).size(), 10U) << rule.code;
    std::set<std::string> companions;
    for (RuleId c : companionsOf(rule.id)) companions.insert(ruleDef(c).code);
    EXPECT_EQ(companions, documentedCompanions(rule.code)) << rule.code;
  }
  // Each description is its own (no row copied over another).
  std::set<std::string> texts;
  for (const RuleDef& rule : kRules) texts.insert(faultDescription(rule.id));
  EXPECT_EQ(texts.size(), kRules.size());
}

// --- the frame stream ---

struct StreamRow {
  const char* name;
  SimOptions options;
};
const std::vector<StreamRow>& streamRows() {
  static std::vector<StreamRow> rows;
  if (!rows.empty()) return rows;
  rows.push_back({"commissioning_4", options(Scenario::Commissioning, 4, 1.0)});
  SimOptions io = options(Scenario::Commissioning, 3, 1.0);
  io.io_slaves = 3;
  io.image = ImageStyle::EtherLab;
  rows.push_back({"interleaved_3_io_3", io});
  SimOptions fast = options(Scenario::Soak, 2, 1.0);
  fast.cycle_us = 250;
  fast.jitter_us = 50;
  fast.loss = 0.01;
  rows.push_back({"soak_250us_jitter_loss", fast});
  SimOptions nostart = options(Scenario::Commissioning, 5, 1.0);
  nostart.startup = false;
  rows.push_back({"no_startup_5", nostart});
  rows.push_back({"faults_4", options(Scenario::Faults, 4, 4.3)});
  rows.push_back({"commissioning_32", options(Scenario::Commissioning, 32, 1.0)});
  SimOptions said = options(Scenario::Commissioning, 4, 3.0);
  said.diagnosis = true;
  said.bad_links.push_back({.station = 0x03EB, .port = 0, .at_s = 1.2, .frames = 3, .text = ""});
  rows.push_back({"diagnosis_bad_link", said});
  SimOptions said_32 = options(Scenario::Commissioning, 32, 1.0);
  said_32.diagnosis = true;
  said_32.io_slaves = 8;
  rows.push_back({"diagnosis_32_io_8", said_32});
  // polls that do not fit between two cycles of 125 us go in the next ones, never late
  SimOptions crowded = options(Scenario::Commissioning, 32, 1.0);
  crowded.diagnosis = true;
  crowded.io_slaves = 32;
  crowded.cycle_us = 125;
  rows.push_back({"diagnosis_125us_32_io_32", crowded});
  return rows;
}
class Stream : public ::testing::TestWithParam<std::size_t> {};

TEST_P(Stream, SameOptionsSameBytesAnotherSeedOthers) {
  const StreamRow& row = streamRows()[GetParam()];
  const std::uint64_t first = fnv1a(simulate(row.options));
  EXPECT_EQ(fnv1a(simulate(row.options)), first) << row.name;
  SimOptions other = row.options;
  other.seed = row.options.seed + 1;
  EXPECT_NE(fnv1a(simulate(other)), first) << row.name;
}

TEST_P(Stream, FramesOrderedLongEnoughAndPaired) {
  const StreamRow& row = streamRows()[GetParam()];
  const std::vector<Frame> frames = simulate(row.options);
  ASSERT_GT(frames.size(), 100U);
  if (row.options.startup) {
    const EcatFrame first = walked(frames[0].bytes);
    ASSERT_EQ(first.status, WalkStatus::Ok);
    EXPECT_EQ(first.datagrams[0].command, ecat::kBrd) << row.name << ": slaves counted first";
  }
  std::size_t masters = 0, returned = 0;
  std::optional<EcatFrame> previous;
  bool previous_master = false;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const Frame& f = frames[i];
    if (i > 0) {
      ASSERT_GE(f.time_ns, frames[i - 1].time_ns) << row.name << " frame " << i + 1;
    }
    ASSERT_GE(f.bytes.size(), 60U) << row.name << " frame " << i + 1;
    const EcatFrame frame = walked(f.bytes);
    ASSERT_EQ(frame.status, WalkStatus::Ok) << row.name << " frame " << i + 1;
    if (returnedMac(f.bytes)) {
      ++returned;
      // the returned copy follows its master copy, with the same datagram list (§8)
      ASSERT_TRUE(previous_master) << row.name << " frame " << i + 1;
      EXPECT_TRUE(frame.sameDatagramList(*previous)) << row.name << " frame " << i + 1;
      EXPECT_TRUE(frame.anyWkcAboveZero()) << row.name << " frame " << i + 1;
      previous_master = false;
    } else {
      ++masters;
      EXPECT_FALSE(frame.anyWkcAboveZero()) << row.name << " frame " << i + 1;
      previous_master = true;
    }
    previous = frame;
  }
  // Every master copy returns unless the run loses frames.
  if (row.options.loss == 0 && row.options.scenario != Scenario::Faults) {
    EXPECT_EQ(masters, returned) << row.name;
  } else {
    EXPECT_GT(masters, returned) << row.name;
  }
}

INSTANTIATE_TEST_SUITE_P(Rows, Stream, ::testing::Range<std::size_t>(0, 6),
                         [](const ::testing::TestParamInfo<std::size_t>& row) {
                           return std::string(streamRows()[row.param].name);
                         });

// --- working counters ---

struct WkcRow {
  int axes;
  int io_slaves;
  ImageStyle image;
};
class CyclicWkc : public ::testing::TestWithParam<WkcRow> {};

TEST_P(CyclicWkc, ThreePerServoTwoPerOutputOnePerInputTerminal) {
  const WkcRow& row = GetParam();
  SimOptions o = options(Scenario::Commissioning, row.axes, 1.0);
  o.io_slaves = row.io_slaves;
  o.image = row.image;
  // terminals alternate output, input, ... (8-bit digital terminals)
  const int outputs = (row.io_slaves + 1) / 2, inputs = row.io_slaves / 2;
  const int expected = 3 * row.axes + 2 * outputs + inputs;
  const std::vector<Frame> frames = simulate(o);
  // Per cycle: the returned LRWs' working counters, summed over the cycle's frames.
  std::vector<int> sums;
  std::size_t lrw_per_cycle = 0, in_cycle = 0;
  int sum = 0;
  std::int64_t last_lrw = -1;
  for (const Frame& f : frames) {
    if (!returnedMac(f.bytes)) continue;
    const EcatFrame frame = walked(f.bytes);
    if (frame.datagrams[0].command != ecat::kLrw) continue;
    ASSERT_LE(frame.datagrams[0].length, 1450U);
    if (last_lrw >= 0 && f.time_ns - last_lrw > 100'000) {  // a new cycle
      sums.push_back(sum);
      lrw_per_cycle = std::max(lrw_per_cycle, in_cycle);
      sum = 0;
      in_cycle = 0;
    }
    sum += frame.datagrams[0].wkc;
    ++in_cycle;
    last_lrw = f.time_ns;
  }
  sums.push_back(sum);
  ASSERT_GT(sums.size(), 900U);
  EXPECT_EQ(lrw_per_cycle, row.axes > 29 ? 2U : 1U);
  // After the start-up (the first cycles, in SAFE-OP) every cycle has the full count.
  int full = 0;
  for (std::size_t k = 100; k < sums.size(); ++k) {
    EXPECT_EQ(sums[k], expected) << "cycle " << k;
    full += sums[k] == expected;
  }
  EXPECT_GT(full, 0);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, CyclicWkc,
    ::testing::Values(WkcRow{1, 0, ImageStyle::Soem}, WkcRow{4, 0, ImageStyle::Soem},
                      WkcRow{4, 3, ImageStyle::Soem}, WkcRow{4, 4, ImageStyle::EtherLab},
                      WkcRow{32, 0, ImageStyle::Soem}, WkcRow{30, 5, ImageStyle::EtherLab}));

// --- layout ---

struct LayoutRow {
  int axes;
  int io_slaves;
  ImageStyle image;
};
class Layout : public ::testing::TestWithParam<LayoutRow> {};

// The cyclic LRWs of a run: logical address -> data length.
std::map<std::uint32_t, std::uint16_t> cyclicLrws(const std::vector<Frame>& frames) {
  std::map<std::uint32_t, std::uint16_t> lrws;
  for (const Frame& f : frames) {
    const EcatFrame frame = walked(f.bytes);
    for (std::size_t i = 0; i < frame.count; ++i) {
      if (frame.datagrams[i].command == ecat::kLrw) {
        lrws[frame.datagrams[i].address] = frame.datagrams[i].length;
      }
    }
  }
  return lrws;
}

TEST_P(Layout, AddressesAndStations) {
  const LayoutRow& row = GetParam();
  SimOptions o = options(Scenario::Commissioning, row.axes, 1.0);
  o.io_slaves = row.io_slaves;
  o.image = row.image;
  ASSERT_EQ(test::statusText(resolveOptions(o)), "");
  const Simulator simulator(o);
  const std::vector<AxisConfig>& layout = simulator.layout();
  ASSERT_EQ(layout.size(), static_cast<std::size_t>(row.axes));
  const auto lrws = cyclicLrws(simulate(o));
  ASSERT_FALSE(lrws.empty());
  for (const auto& [address, length] : lrws) {
    EXPECT_LE(length, 1450U);
  }
  EXPECT_EQ(lrws.size(), row.axes > 29 ? 2U : 1U);

  // Every axis's PDOs inside one cyclic LRW; the LRW's axes by frame.
  std::map<std::uint32_t, std::vector<const AxisConfig*>> by_frame;
  for (std::size_t k = 0; k < layout.size(); ++k) {
    const AxisConfig& a = layout[k];
    EXPECT_EQ(a.name, "axis" + std::to_string(k));
    if (k > 0) {
      EXPECT_GT(a.station, layout[k - 1].station) << "stations in ring order";
    }
    const auto lrw = std::find_if(lrws.begin(), lrws.end(), [&](const auto& l) {
      return *a.outputs >= l.first && *a.outputs + 10 <= l.first + l.second;
    });
    ASSERT_NE(lrw, lrws.end()) << "axis " << k;
    EXPECT_GE(*a.inputs, lrw->first);
    EXPECT_LE(*a.inputs + 40, lrw->first + lrw->second) << "axis " << k;
    by_frame[lrw->first].push_back(&a);
  }
  for (const auto& [base, axes] : by_frame) {
    for (std::size_t k = 0; k < axes.size(); ++k) {
      if (row.image == ImageStyle::EtherLab) {
        EXPECT_EQ(*axes[k]->inputs, *axes[k]->outputs + 10) << axes[k]->name;
      } else {
        // §9.4: all outputs first, then all inputs, in axis order
        for (const AxisConfig* other : axes) {
          EXPECT_LE(*other->outputs + 10, *axes[k]->inputs);
        }
        if (row.io_slaves == 0) {
          EXPECT_EQ(*axes[k]->outputs, base + 10 * k);
          EXPECT_EQ(*axes[k]->inputs, base + 10 * axes.size() + 40 * k);
        } else if (k > 0) {
          EXPECT_GT(*axes[k]->outputs, *axes[k - 1]->outputs);
          EXPECT_GT(*axes[k]->inputs, *axes[k - 1]->inputs);
        }
      }
    }
  }
}

TEST_P(Layout, ConfigFileGivesTheSameLayout) {
  const LayoutRow& row = GetParam();
  SimOptions o = options(Scenario::Commissioning, row.axes, 1.0);
  o.io_slaves = row.io_slaves;
  o.image = row.image;
  o.ready_mode = row.axes % 2;
  ASSERT_EQ(test::statusText(resolveOptions(o)), "");
  const Simulator simulator(o);
  const Result<Config> parsed = parseConfig(simulator.layoutConfig(), "sim.toml");
  ASSERT_TRUE(parsed.has_value()) << parsed.error().text() << "\n" << simulator.layoutConfig();
  const Config& config = *parsed;
  EXPECT_EQ(config.servo_ready_mode, o.ready_mode);
  ASSERT_EQ(config.axes.size(), simulator.layout().size());
  for (std::size_t k = 0; k < config.axes.size(); ++k) {
    const AxisConfig& a = simulator.layout()[k];
    EXPECT_EQ(config.axes[k].name, a.name);
    EXPECT_EQ(config.axes[k].outputs, a.outputs);
    EXPECT_EQ(config.axes[k].inputs, a.inputs);
    EXPECT_EQ(config.axes[k].station, a.station);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Rows, Layout,
    ::testing::Values(LayoutRow{1, 0, ImageStyle::Soem}, LayoutRow{4, 0, ImageStyle::Soem},
                      LayoutRow{4, 0, ImageStyle::EtherLab}, LayoutRow{3, 5, ImageStyle::Soem},
                      LayoutRow{3, 5, ImageStyle::EtherLab}, LayoutRow{29, 0, ImageStyle::Soem},
                      LayoutRow{30, 0, ImageStyle::Soem}, LayoutRow{32, 2, ImageStyle::EtherLab}));

// --- through the validator ---

struct Validated {
  std::vector<Finding> findings;
  std::int64_t first_ns = 0;  // the first frame's time
  std::size_t axes = 0;
  std::vector<std::size_t> history;  // error-history entries per axis
};

// The frames through a Validator as `ncservo validate` runs them, with the simulator's layout
// file (or the default layout when `with_config` is false).
Validated validate(const SimOptions& resolved, bool with_config,
                   const RuleSettings& base = RuleSettings{}) {
  const Simulator layout_of(resolved);
  DecoderOptions decoder;
  RuleSettings settings = base;
  if (with_config) {
    const Result<Config> parsed = parseConfig(layout_of.layoutConfig(), "sim.toml");
    EXPECT_TRUE(parsed.has_value());
    if (parsed.has_value()) {
      decoder.axes = parsed->axes;
      EXPECT_TRUE(applyConfig(*parsed, settings));
    }
  }
  // Through the capture pipeline, as the CLI reads a capture.
  CapturePipeline pipeline({decoder, settings, TimeWindow{}, TimestampMode::Capture});
  Validated out;
  pipeline.setSinks({nullptr, nullptr, nullptr,
                     [&out](const std::vector<Finding>& found) {
                       out.findings.insert(out.findings.end(), found.begin(), found.end());
                     },
                     nullptr});
  std::uint64_t number = 0;
  EcatFrame frame;
  for (const Frame& f : simulate(resolved)) {
    if (number == 0) out.first_ns = f.time_ns;
    const ByteReader bytes(f.bytes.data(), f.bytes.size());
    walkPacket(LinkType::Ethernet, bytes, frame);
    pipeline.onWalkedFrame(++number, f.time_ns, LinkType::Ethernet, bytes, frame);
  }
  pipeline.finish();
  const Validator& validator = *pipeline.validator();
  out.axes = validator.axisCount();
  for (std::size_t a = 0; a < validator.axisCount(); ++a) {
    out.history.push_back(validator.axis(a) ? validator.axis(a)->errorHistory().size() : 0);
  }
  return out;
}

std::string findingsText(const std::vector<Finding>& findings) {
  std::string text;
  for (const Finding& f : findings) {
    text += std::string(ruleDef(f.rule).code) + " " + severityName(f.severity) + " axis " +
            (f.axis ? std::to_string(*f.axis) : "-") + " frame " + std::to_string(f.at.frame) +
            ": " + f.message + "\n";
  }
  return text;
}

// --- what the drives and the ESCs said (--diagnosis, docs/simulate.md#diagnosis) ---

struct DiagnosisRow {
  const char* name;
  SimOptions options;
};
std::vector<DiagnosisRow> diagnosisRows() {
  std::vector<DiagnosisRow> rows;
  SimOptions bad_link = options(Scenario::Commissioning, 4, 3.0);
  bad_link.bad_links.push_back(
      {.station = 0x03EB, .port = 0, .at_s = 1.2, .frames = 3, .text = ""});
  bad_link.faults.push_back({.rule = RuleId::Mbx003, .at_s = 0.9, .axis = 0, .text = "MBX-003"});
  bad_link.faults.push_back({.rule = RuleId::Dc001, .at_s = 1.0, .axis = 3, .text = "DC-001"});
  rows.push_back({"commissioning_bad_link", bad_link});
  SimOptions far_port = options(Scenario::Commissioning, 3, 3.0);
  far_port.image = ImageStyle::TwinCat;
  far_port.bad_links.push_back(
      {.station = 0x03EA, .port = 1, .at_s = 1.2, .frames = 6, .text = ""});
  rows.push_back({"twincat_port_1_outage", far_port});
  SimOptions incidents = options(Scenario::Incidents, 4, 6.0);
  incidents.cycle_us = 5000;
  incidents.diagnosis = true;
  rows.push_back({"incidents", incidents});
  SimOptions running = options(Scenario::Commissioning, 4, 3.0);
  running.startup = false;
  running.faults.push_back({.rule = RuleId::Erh002, .at_s = 1.0, .axis = 1, .text = "ERH-002"});
  rows.push_back({"no_startup_history", running});
  SimOptions faults = options(Scenario::Faults, 4, 4.3);
  faults.cycle_us = 2000;
  faults.diagnosis = true;
  rows.push_back({"faults", faults});
  // 150 ms without outputs: every slave's sync manager watchdog expires once (0x0442)
  SimOptions silent = options(Scenario::Commissioning, 4, 3.0);
  silent.diagnosis = true;
  silent.lost_cycles.push_back({.at_s = 1.3, .amount = 150, .text = "1.3:150"});
  rows.push_back({"watchdogs", silent});
  return rows;
}
class DiagnosisRun : public ::testing::TestWithParam<DiagnosisRow> {};

// Every emergency, SDO answer and abort, counter rise and link fault the simulator wrote is what
// the capture pipeline decodes, on the same frame, and nothing else.
TEST_P(DiagnosisRun, TheValidatorDecodesWhatTheSimulatorSaid) {
  SimOptions o = GetParam().options;
  ASSERT_EQ(test::statusText(resolveOptions(o)), "");
  ASSERT_TRUE(o.diagnosis);
  Simulator simulator(o);
  DecoderOptions decoder;
  if (!o.startup) {  // without it, the ENI gives the mailboxes' areas
    const Result<EniLayout> eni = parseEni(simulator.eni(), "sim.xml");
    ASSERT_TRUE(eni.has_value());
    decoder.mailbox_areas = eni->mailboxes;
    EXPECT_EQ(decoder.mailbox_areas.size(), static_cast<std::size_t>(o.axes));
  }
  CapturePipeline pipeline({decoder, RuleSettings{}, TimeWindow{}, TimestampMode::Capture});
  std::uint64_t number = 0;
  EcatFrame frame;
  ASSERT_TRUE(simulator.run([&](const SimFrame& f) {
    const ByteReader bytes(f.data, f.size);
    walkPacket(LinkType::Ethernet, bytes, frame);
    pipeline.onWalkedFrame(++number, f.time_ns, LinkType::Ethernet, bytes, frame);
    return true;
  }));
  pipeline.finish();
  const CaptureResult result = pipeline.result();
  const Result<DiagnosisTruth> truth = simulator.diagnosis();
  ASSERT_TRUE(truth.has_value());

  std::vector<std::string> said, decoded;
  for (const DriveSaid& m : truth->drive_messages) {
    said.push_back(fmt::format("{} {} {} {:04X}:{} v{} rq{} c{:04X} r{:02X} a{:08X}", m.frame,
                               m.station, m.kind, m.index, m.subindex, m.value.value_or(~0ULL),
                               m.request_frame.value_or(0), m.code, m.error_register,
                               m.abort_code));
  }
  for (const DriveMessage& m : result.drive_messages) {
    const bool emergency = m.kind == DriveMessage::Kind::Emergency;
    decoded.push_back(fmt::format("{} {} {} {:04X}:{} v{} rq{} c{:04X} r{:02X} a{:08X}", m.frame,
                                  m.slave.station.value_or(0), driveMessageKindName(m.kind),
                                  m.index, m.subindex, m.value.value_or(~0ULL),
                                  m.request_frame.value_or(0), emergency ? m.emergency.code : 0,
                                  emergency ? m.emergency.error_register : 0, m.abort_code));
  }
  EXPECT_EQ(decoded, said) << GetParam().name;
  EXPECT_FALSE(said.empty()) << GetParam().name;

  std::multiset<std::string> rose, read;
  for (const EscErrorTruth& e : truth->esc_errors) {
    rose.insert(fmt::format("{} {} {} {} {}", e.frame, e.station, e.port, e.counter, e.delta));
  }
  for (const EscErrorDelta& e : result.esc_errors) {
    read.insert(fmt::format("{} {} {} {} {}", e.frame, e.slave.station.value_or(0), e.port,
                            diag::escCounterName(e.counter), e.delta));
  }
  EXPECT_EQ(read, rose) << GetParam().name;
  if (!o.lost_cycles.empty()) {
    EXPECT_EQ(std::count_if(truth->esc_errors.begin(), truth->esc_errors.end(),
                            [](const EscErrorTruth& e) {
                              return std::string_view(e.counter) == "sm-watchdog";
                            }),
              o.axes)
        << "each servo's watchdog expired once";
  }
  std::vector<std::string> links, named;
  for (const LinkFaultTruth& l : truth->link_faults) {
    links.push_back(fmt::format("{} {} {} {}", l.frame, l.station, l.port, l.errors));
  }
  for (const LinkFault& l : result.link_faults) {
    named.push_back(fmt::format("{} {} {} {}", l.frame, l.reported.station.value_or(0),
                                l.reported_port, l.errors));
  }
  EXPECT_EQ(named, links) << GetParam().name;
  EXPECT_TRUE(result.mailbox_notes.empty()) << GetParam().name;
}

INSTANTIATE_TEST_SUITE_P(Rows, DiagnosisRun, ::testing::ValuesIn(diagnosisRows()),
                         [](const auto& row) { return std::string(row.param.name); });

TEST(ParseBadLink, Rows) {
  struct Row {
    const char* text;
    std::optional<std::tuple<std::uint16_t, int, double, int>> parsed;  // none: an error
  };
  const Row rows[] = {
      {"0x3EB:0@1.2", std::tuple{0x03EB, 0, 1.2, 2}},
      {"1004:1@2x6", std::tuple{1004, 1, 2.0, 6}},
      {"0x3EB:2@1", std::nullopt},
      {"0x3EB@1", std::nullopt},
      {"0x3EB:0", std::nullopt},
      {"1004:0@1x0", std::nullopt},
      {"70000:0@1", std::nullopt},
      {"x:0@1", std::nullopt},
  };
  for (const Row& row : rows) {
    const Result<BadLink> link = parseBadLink(row.text);
    ASSERT_EQ(link.has_value(), row.parsed.has_value()) << row.text;
    if (!link) {
      EXPECT_NE(link.error().text().find(row.text), std::string::npos) << link.error().text();
      continue;
    }
    const auto [station, port, at_s, frames] = *row.parsed;
    EXPECT_EQ(link->station, station) << row.text;
    EXPECT_EQ(link->port, port) << row.text;
    EXPECT_DOUBLE_EQ(link->at_s, at_s) << row.text;
    EXPECT_EQ(link->frames, frames) << row.text;
  }
}

TEST(ParseSyncError, Rows) {
  const std::pair<const char*, std::optional<std::pair<std::uint16_t, double>>> rows[] = {
      {"0x3EA@1.6", std::pair{0x03EA, 1.6}},
      {"1001@2", std::pair{1001, 2.0}},
      {"0x3EA", std::nullopt},
      {"@1.6", std::nullopt},
      {"0x3EA@soon", std::nullopt},
      {"0x10000@1", std::nullopt},
  };
  for (const auto& [text, parsed] : rows) {
    const Result<SlaveAt> sync = parseSyncError(text);
    ASSERT_EQ(sync.has_value(), parsed.has_value()) << text;
    if (!sync) {
      EXPECT_NE(sync.error().text().find(text), std::string::npos) << sync.error().text();
      continue;
    }
    EXPECT_EQ(sync->station, parsed->first) << text;
    EXPECT_DOUBLE_EQ(sync->at_s, parsed->second) << text;
  }
  SimOptions o = options(Scenario::Commissioning, 4, 3.0);
  o.sync_errors.push_back(*parseSyncError("0x3F0@1.6"));
  EXPECT_NE(test::statusText(resolveOptions(o)).find("is not in the ring"), std::string::npos);
  SimOptions fine = options(Scenario::Commissioning, 4, 3.0);
  fine.sync_errors.push_back(*parseSyncError("0x3EA@1.6"));
  EXPECT_EQ(test::statusText(resolveOptions(fine)), "");
  EXPECT_TRUE(fine.diagnosis) << "the AL status polls see it";
}

TEST(ResolveBadLink, RefusesWhatTheRingDoesNotHave) {
  const std::pair<const char*, const char*> rows[] = {
      {"0x3E8:0@1.2", "is not in the ring"},
      {"0x3EC:1@1.2", "has no cable"},
      {"0x3EA:0@0.1", "outside the quiet part"},
  };
  for (const auto& [text, error] : rows) {
    SimOptions o = options(Scenario::Commissioning, 4, 3.0);
    o.bad_links.push_back(*parseBadLink(text));
    EXPECT_NE(test::statusText(resolveOptions(o)).find(error), std::string::npos) << text;
  }
  SimOptions fine = options(Scenario::Commissioning, 4, 3.0);
  fine.bad_links.push_back(*parseBadLink("0x3EA:0@1.2"));
  EXPECT_EQ(test::statusText(resolveOptions(fine)), "");
  EXPECT_TRUE(fine.diagnosis) << "a bad link needs the counter polls";
}

// --- process-image styles (docs/protocol.md §9.4) ---

struct StyleRow {
  const char* name;
  ImageStyle image;
  int axes;
  bool startup;
};
class ImageStyleRun : public ::testing::TestWithParam<StyleRow> {};

SimOptions styleOptions(const StyleRow& row, double duration_s) {
  SimOptions o = options(Scenario::Commissioning, row.axes, duration_s);
  o.image = row.image;
  o.startup = row.startup;
  EXPECT_EQ(test::statusText(resolveOptions(o)), "");
  return o;
}

// The cyclic frames' logical datagrams, from one returned copy in OP.
std::vector<Datagram> cyclicLogicalDatagrams(const std::vector<Frame>& frames) {
  std::vector<Datagram> out;
  std::int64_t first_of_cycle = -1;
  for (const Frame& f : frames) {
    if (f.time_ns - frames.front().time_ns < 500'000'000 || !returnedMac(f.bytes)) continue;
    const EcatFrame frame = walked(f.bytes);
    if (frame.count == 0 || !ecat::isLogical(frame.datagrams[0].command)) continue;
    if (first_of_cycle >= 0 && f.time_ns - first_of_cycle > 100'000) break;  // the next cycle
    if (first_of_cycle < 0) first_of_cycle = f.time_ns;
    for (std::size_t i = 0; i < frame.count; ++i) {
      if (ecat::isLogical(frame.datagrams[i].command)) out.push_back(frame.datagrams[i]);
    }
  }
  return out;
}

TEST_P(ImageStyleRun, DatagramsOfTheStyle) {
  const StyleRow& row = GetParam();
  const std::vector<Datagram> dgs = cyclicLogicalDatagrams(simulate(styleOptions(row, 1.0)));
  ASSERT_FALSE(dgs.empty());
  if (row.image != ImageStyle::TwinCat) {
    for (const Datagram& dg : dgs) EXPECT_EQ(dg.command, ecat::kLrw);
    return;
  }
  // Outputs written by LWRs, then inputs read by LRDs, each area contiguous and the two apart.
  std::size_t lwr = 0, lrd = 0;
  for (const Datagram& dg : dgs) {
    ASSERT_TRUE(dg.command == ecat::kLwr || dg.command == ecat::kLrd);
    (dg.command == ecat::kLwr ? lwr : lrd) += 1;
  }
  for (const std::size_t area : {lwr, lrd}) {
    EXPECT_GE(area, 1U);
    EXPECT_LE(area, 2U) << "split in two once two slaves share it";
  }
  EXPECT_EQ(dgs[0].command, ecat::kLwr);
  for (std::size_t i = 1; i < dgs.size(); ++i) {
    if (dgs[i].command == dgs[i - 1].command) {
      EXPECT_EQ(dgs[i].address, dgs[i - 1].address + dgs[i - 1].length) << "one area";
    } else {
      EXPECT_GT(dgs[i].address, dgs[i - 1].address + dgs[i - 1].length + 0x1000) << "apart";
    }
  }
}

// The slaves as the start-up of these options (with a start-up) configures them.
std::vector<SlaveLayout> startUpSlaves(SimOptions o) {
  o.startup = true;
  LayoutLearner learner;
  bool previous_master = false;
  EcatFrame previous;
  for (const Frame& f : simulate(o)) {
    const ByteReader bytes(f.bytes.data(), f.bytes.size());
    EcatFrame frame;
    walkPacket(LinkType::Ethernet, bytes, frame);
    const bool returned = returnedMac(f.bytes);
    learner.onFrame(frame, bytes, returned,
                    returned && previous_master && frame.sameDatagramList(previous));
    previous_master = !returned;
    previous = frame;
  }
  return learner.slaves();
}

// docs/protocol.md §8: each returned logical datagram's WKC is what the FMMUs of the start-up add:
// LRW 2 per slave written and 1 per slave read, LRD and LWR 1 per slave; a capture without the
// start-up has the same set-up.
TEST_P(ImageStyleRun, WorkingCountersFromTheStartUpsFmmus) {
  const StyleRow& row = GetParam();
  const SimOptions o = styleOptions(row, 1.0);
  const std::vector<SlaveLayout> slaves = startUpSlaves(o);
  ASSERT_FALSE(slaves.empty());
  const std::vector<Frame> frames = simulate(o);
  std::size_t checked = 0;
  for (const Frame& f : frames) {
    if (!returnedMac(f.bytes) || f.time_ns - frames.front().time_ns < 500'000'000) continue;
    const EcatFrame frame = walked(f.bytes);
    for (std::size_t i = 0; i < frame.count; ++i) {
      const Datagram& dg = frame.datagrams[i];
      if (!ecat::isLogical(dg.command)) continue;
      int expected = 0;
      for (const SlaveLayout& slave : slaves) {
        bool writes = false, reads = false;
        for (const FmmuView& fmmu : slave.fmmus) {
          const bool overlaps = fmmu.active && fmmu.logical < dg.address + dg.length &&
                                fmmu.logical + fmmu.length > dg.address;
          writes = writes ||
                   (overlaps && fmmu.type == ecat::kFmmuWrite && ecat::writesSlaves(dg.command));
          reads =
              reads || (overlaps && fmmu.type == ecat::kFmmuRead && ecat::readsSlaves(dg.command));
        }
        expected += dg.command == ecat::kLrw ? 2 * writes + reads : (writes || reads);
      }
      ASSERT_EQ(dg.wkc, expected) << ecat::commandName(dg.command) << " at " << dg.address;
      ++checked;
    }
  }
  EXPECT_GT(checked, 400U);
}

// The commissioning scenario through the Validator with the layout file the simulator writes:
// every axis decoded, no finding at all.
TEST_P(ImageStyleRun, ValidatesWithItsLayoutFile) {
  const StyleRow& row = GetParam();
  const Validated v = validate(styleOptions(row, 3.0), true);
  ASSERT_EQ(v.axes, static_cast<std::size_t>(row.axes));
  EXPECT_TRUE(v.findings.empty()) << row.name << ":\n" << findingsText(v.findings);
  EXPECT_GE(v.history[1 % static_cast<std::size_t>(row.axes)], 1U) << "the planned drive fault";
}

std::vector<StyleRow> styleRows() {
  std::vector<StyleRow> rows;
  static std::vector<std::string> names;  // the rows' names outlive the table
  for (const ImageStyleName& style : kImageStyles) {
    for (const bool startup : {true, false}) {
      for (const int axes : {1, 3, 8}) {
        names.push_back(
            fmt::format("{}_{}_axes{}", style.name, axes, startup ? "" : "_no_startup"));
        rows.push_back({nullptr, style.style, axes, startup});
      }
    }
  }
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i].name = names[i].c_str();
  return rows;
}

INSTANTIATE_TEST_SUITE_P(Rows, ImageStyleRun, ::testing::ValuesIn(styleRows()),
                         [](const ::testing::TestParamInfo<StyleRow>& row) {
                           return std::string(row.param.name);
                         });

// --- the ESL probe (docs/protocol.md §8) ---

TEST(EslProbe, EachFrameBehindAHeaderWithTheExactTime) {
  SimOptions plain = options(Scenario::Commissioning, 2, 1.0);
  plain.image = ImageStyle::TwinCat;
  ASSERT_EQ(test::statusText(resolveOptions(plain)), "");
  SimOptions probed = plain;
  probed.probe = Probe::Esl;
  const std::vector<Frame> exact = simulate(plain);
  const std::vector<Frame> captured = simulate(probed);
  ASSERT_EQ(captured.size(), exact.size());
  std::int64_t previous = 0;
  for (std::size_t k = 0; k < exact.size(); ++k) {
    SCOPED_TRACE("frame " + std::to_string(k + 1));
    const Bytes& bytes = captured[k].bytes;
    const EcatFrame frame = walked(bytes);
    ASSERT_TRUE(frame.probe.present);
    EXPECT_TRUE(frame.probe.before);
    EXPECT_TRUE(frame.probe.timestampValid());
    EXPECT_EQ(frame.probe.port(), returnedMac(exact[k].bytes) ? 1 : 0);
    EXPECT_EQ(frame.probe.timestamp_ns, static_cast<std::uint64_t>(exact[k].time_ns));
    ASSERT_EQ(bytes.size(), exact[k].bytes.size() + esl::kHeaderSize);
    EXPECT_TRUE(
        std::equal(exact[k].bytes.begin(), exact[k].bytes.end(), bytes.begin() + esl::kHeaderSize));
    // the PC's stamp: late by a few hundred microseconds at most, never back
    const std::int64_t late = captured[k].time_ns - exact[k].time_ns;
    EXPECT_GE(late, 0);
    EXPECT_LE(late, 400'000);
    EXPECT_GT(captured[k].time_ns, previous);
    previous = captured[k].time_ns;
  }
  EXPECT_EQ(fnv1a(captured), fnv1a(simulate(probed))) << "the noise comes from the seed";
}

// --- shapes of a machine's bus (docs/simulate.md#shapes) ---

// The logical address of each LRW of a frame.
std::vector<std::uint32_t> lrwAddresses(const Bytes& bytes) {
  std::vector<std::uint32_t> addresses;
  const EcatFrame frame = walked(bytes);
  for (std::size_t d = 0; d < frame.count; ++d) {
    if (frame.datagrams[d].command == ecat::kLrw) addresses.push_back(frame.datagrams[d].address);
  }
  return addresses;
}

TEST(Shapes, SecondTaskFrameEveryTenCyclesWithItsOwnLrw) {
  SimOptions o = options(Scenario::Commissioning, 4, 1.0);
  o.startup = false;
  o.io_slaves = 4;
  o.io_task_us = 10000;
  const std::vector<Frame> frames = simulate(o);
  std::map<std::uint32_t, std::size_t> copies;  // per LRW address, both copies
  for (const Frame& f : frames) {
    const std::vector<std::uint32_t> lrws = lrwAddresses(f.bytes);
    ASSERT_EQ(lrws.size(), 1U) << "one LRW per frame";
    ++copies[lrws[0]];
  }
  ASSERT_EQ(copies.size(), 2U);
  EXPECT_EQ(copies.begin()->second, 2U * 1000) << "the servos' frame every 1 ms cycle";
  EXPECT_EQ(std::next(copies.begin())->second, 2U * 100) << "the terminals' frame every 10 ms";
  const Simulator simulator(o);
  for (const AxisConfig& axis : simulator.layout()) {
    EXPECT_LT(axis.inputs, std::next(copies.begin())->first) << "servos in the first frame";
  }
}

TEST(Shapes, MidStartHoldsNothingBeforeItsMoment) {
  for (const MidStartName& row : kMidStarts) {
    SCOPED_TRACE(row.name);
    SimOptions o = options(Scenario::Commissioning, 4, 3.0);
    o.mid_start = row.start;
    const std::vector<Frame> frames = simulate(o);
    ASSERT_FALSE(frames.empty());
    const std::int64_t moment_ns =
        static_cast<std::int64_t>(std::llround((kStartupSeconds + row.after_plan_s) * 1e9));
    SimOptions whole = o;
    whole.mid_start = MidStart::None;
    const std::int64_t first_ns = simulate(whole).front().time_ns;  // the session's start
    EXPECT_GE(frames.front().time_ns - first_ns, moment_ns - kMs / 2);
    EXPECT_LT(frames.front().time_ns - first_ns, moment_ns + kMs);
    for (const Frame& f : frames) ASSERT_EQ(lrwAddresses(f.bytes).size(), 1U) << "no start-up";
  }
}

TEST(Shapes, BusyTerminalInputsChangeEveryCycle) {
  SimOptions o = options(Scenario::Commissioning, 2, 1.0);
  o.startup = false;
  o.io_slaves = 3;
  o.terminal_inputs = TerminalInputs::EveryCycle;
  const std::vector<Frame> frames = simulate(o);
  // SOEM style: servo, terminal (out), servo, terminal (in), terminal (out); the input terminal's
  // byte lies after the servos' 80 input bytes, behind 20 + 2 output bytes.
  std::size_t changes = 0, returned = 0;
  std::optional<std::uint8_t> last;
  for (const Frame& f : frames) {
    if (!returnedMac(f.bytes)) continue;
    const EcatFrame frame = walked(f.bytes);
    const Datagram& lrw = frame.datagrams.front();
    const std::uint8_t input = f.bytes[lrw.data_offset + lrw.length - 1];
    if (last && *last != input) ++changes;
    last = input;
    ++returned;
  }
  EXPECT_GT(changes, returned * 9 / 10) << "the terminal's input byte, cycle after cycle";
}

// With its exact layout, each shape is a clean run: every axis decoded, no finding of any
// severity (idle for the whole run), or none at warning or error.
struct ShapeRow {
  const char* name;
  std::function<void(SimOptions&)> shape;
  bool no_finding_at_all = false;
};
class ShapeRun : public ::testing::TestWithParam<ShapeRow> {};

TEST_P(ShapeRun, CleanWithItsLayout) {
  const ShapeRow& row = GetParam();
  SimOptions o = options(Scenario::Commissioning, 4, 3.0);
  o.startup = false;
  row.shape(o);
  ASSERT_EQ(test::statusText(resolveOptions(o)), "");
  const Validated v = validate(o, true);
  ASSERT_EQ(v.axes, 4U);
  std::vector<Finding> reported;
  for (const Finding& f : v.findings) {
    if (row.no_finding_at_all || f.severity != Severity::Info) reported.push_back(f);
  }
  EXPECT_TRUE(reported.empty()) << row.name << ":\n" << findingsText(reported);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, ShapeRun,
    ::testing::Values(ShapeRow{"busy_io_soem",
                               [](SimOptions& o) {
                                 o.io_slaves = 5;
                                 o.terminal_inputs = TerminalInputs::EveryCycle;
                               }},
                      ShapeRow{"busy_io_mixed",
                               [](SimOptions& o) {
                                 o.image = ImageStyle::Mixed;
                                 o.terminal_inputs = TerminalInputs::EveryCycle;
                               }},
                      ShapeRow{"cia402", [](SimOptions& o) { o.cia402_drives = 2; }},
                      ShapeRow{"cia402_twincat",
                               [](SimOptions& o) {
                                 o.image = ImageStyle::TwinCat;
                                 o.cia402_drives = 3;
                               }},
                      ShapeRow{"idle_then_session",
                               [](SimOptions& o) {
                                 o.idle_s = 1.5;
                                 o.duration_s = 4.0;
                               }},
                      ShapeRow{"idle_all", [](SimOptions& o) { o.idle_all = true; }, true},
                      ShapeRow{"start_in_fault",
                               [](SimOptions& o) {
                                 o.startup = true;
                                 o.mid_start = MidStart::Fault;
                               }},
                      ShapeRow{"start_in_error_clear",
                               [](SimOptions& o) {
                                 o.startup = true;
                                 o.mid_start = MidStart::ErrorClear;
                               }},
                      ShapeRow{"start_in_homing",
                               [](SimOptions& o) {
                                 o.startup = true;
                                 o.mid_start = MidStart::Homing;
                               }}),
    [](const ::testing::TestParamInfo<ShapeRow>& row) { return std::string(row.param.name); });

struct CleanRow {
  const char* name;
  int axes;
  int io_slaves;
  ImageStyle image;
  bool with_config;
  int ready_mode;
  int cycle_us;
  bool startup;
  int jitter_us = 0;
  Scenario scenario = Scenario::Commissioning;
  double duration_s = 3.0;
  const char* bug = nullptr;  // a known simulator bug: the row is skipped until it is fixed
};
class CleanRun : public ::testing::TestWithParam<CleanRow> {};

TEST_P(CleanRun, NoFindingAtWarningOrError) {
  const CleanRow& row = GetParam();
  if (row.bug != nullptr) GTEST_SKIP() << row.bug;
  SimOptions o = options(row.scenario, row.axes, row.duration_s);
  o.io_slaves = row.io_slaves;
  o.image = row.image;
  o.ready_mode = row.ready_mode;
  o.cycle_us = row.cycle_us;
  o.startup = row.startup;
  o.jitter_us = row.jitter_us;
  ASSERT_EQ(test::statusText(resolveOptions(o)), "");
  const Validated v = validate(o, row.with_config);
  ASSERT_EQ(v.axes, static_cast<std::size_t>(row.axes)) << row.name << ": every axis decoded";
  std::vector<Finding> serious;
  for (const Finding& f : v.findings) {
    if (f.severity != Severity::Info) serious.push_back(f);
  }
  EXPECT_TRUE(serious.empty()) << row.name << ":\n" << findingsText(serious);
  // The drive faults of the plan are in the error history, not findings: commissioning has a
  // following error on axis 1, soak an overload on axis 0 in its sixth 10 s period.
  const std::size_t faulty =
      row.scenario == Scenario::Soak ? 0 : 1 % static_cast<std::size_t>(row.axes);
  if (row.scenario == Scenario::Commissioning || row.duration_s > 60.0) {
    EXPECT_GE(v.history[faulty], 1U) << row.name;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Rows, CleanRun,
    ::testing::Values(
        CleanRow{"default_layout_4", 4, 0, ImageStyle::Soem, false, 0, 1000, true},
        CleanRow{"config_4", 4, 0, ImageStyle::Soem, true, 0, 1000, true},
        CleanRow{"ready_mode_1", 4, 0, ImageStyle::Soem, true, 1, 1000, true},
        CleanRow{"interleaved_io", 3, 4, ImageStyle::EtherLab, true, 0, 1000, true},
        CleanRow{"one_axis", 1, 0, ImageStyle::Soem, false, 0, 1000, true},
        CleanRow{"cycle_500us_no_startup", 4, 0, ImageStyle::Soem, false, 0, 500, false},
        CleanRow{"32_axes", 32, 0, ImageStyle::Soem, true, 0, 2000, true},
        CleanRow{"32_axes_default_layout", 32, 0, ImageStyle::Soem, false, 0, 2000, true},
        CleanRow{"cycle_125us", 2, 0, ImageStyle::Soem, false, 0, 125, true},
        CleanRow{"cycle_10ms", 4, 0, ImageStyle::Soem, false, 0, 10000, true},
        CleanRow{"jitter_200us", 4, 0, ImageStyle::Soem, false, 0, 1000, true, 200},
        CleanRow{"soak_12s", 4, 0, ImageStyle::Soem, false, 0, 1000, true, 0, Scenario::Soak, 12.0},
        CleanRow{"soak_62s", 2, 0, ImageStyle::Soem, false, 0, 1000, true, 0, Scenario::Soak,
                 62.0}),
    [](const ::testing::TestParamInfo<CleanRow>& row) { return std::string(row.param.name); });

// Each fault makes its rule fire, with its documented companions, and nothing else; in a few
// set-ups (the fault's default axis and time).
struct FaultSetup {
  const char* name;
  int axes;
  int io_slaves;
  ImageStyle image;
  int cycle_us;
  int ready_mode;
  std::uint64_t seed;
  double at_s = -1;  // the fault's time, < 0: its default
};
const std::vector<FaultSetup>& faultSetups() {
  static const std::vector<FaultSetup> setups = {
      {"4_axes", 4, 0, ImageStyle::Soem, 1000, 0, 1},
      {"2_axes_500us_ready_mode_1", 2, 0, ImageStyle::Soem, 500, 1, 7},
      {"5_axes_io_interleaved", 5, 2, ImageStyle::EtherLab, 1000, 0, 3},
      {"earliest", 4, 0, ImageStyle::Soem, 1000, 0, 4, 0.65},  // start-up 0.2 + 0.45
      {"late", 4, 0, ImageStyle::Soem, 1000, 0, 6, 1.3},
      {"latest", 4, 0, ImageStyle::Soem, 1000, 0, 5, 1.34},  // 0.53 x 3 s - 0.25
  };
  return setups;
}
// The rules the simulator injects, by index in the rule table.
std::vector<std::size_t> injectableRules() {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < kRuleCount; ++i) {
    if (faultRecipe(kRules[i].id)->injectable()) out.push_back(i);
  }
  return out;
}
class FaultRun : public ::testing::TestWithParam<std::tuple<std::size_t, std::size_t>> {};

TEST_P(FaultRun, FiresItsRuleAndCompanionsOnly) {
  const RuleDef& rule = kRules[std::get<0>(GetParam())];
  const FaultSetup& setup = faultSetups()[std::get<1>(GetParam())];
  SimOptions o = options(Scenario::Commissioning, setup.axes, 3.0);
  o.io_slaves = setup.io_slaves;
  o.image = setup.image;
  o.cycle_us = setup.cycle_us;
  o.ready_mode = setup.ready_mode;
  o.seed = setup.seed;
  o.faults = {fault(rule.code)};
  if (setup.at_s >= 0 && std::string(rule.code).rfind("ESM-", 0) != 0) {
    o.faults[0].at_s = setup.at_s;
  }
  ASSERT_EQ(test::statusText(resolveOptions(o)), "") << rule.code;
  std::set<std::string> expected = documentedCompanions(rule.code);
  expected.insert(rule.code);
  // A rule off by default is enabled; COM-007 with a limit the fault's three quarters of a cycle
  // exceed at any cycle time.
  RuleSettings settings;
  if (rule.by_default == ByDefault::Off) {
    ASSERT_TRUE(settings.enable(rule.code));
  }
  if (rule.id == RuleId::Com007) {
    ASSERT_TRUE(settings.setLimit("return_latency_us", o.cycle_us / 2));
  }
  const Validated v = validate(o, true, settings);
  std::set<std::string> fired;
  for (const Finding& f : v.findings) fired.insert(ruleDef(f.rule).code);
  EXPECT_EQ(fired, expected) << rule.code << ":\n" << findingsText(v.findings);
  // The rule fires once (a whole-bus fault: at most once per axis), on the fault's axis, around
  // the fault's time (the start-up's faults within the start-up).
  const FaultRequest& f = o.faults[0];
  int count = 0;
  // A link down is counted at both its ends: the slave before the axis's names its own axis.
  const bool both_ends = rule.id == RuleId::Lnk002 && f.axis && *f.axis > 0;
  for (const Finding& finding : v.findings) {
    if (finding.rule != rule.id) continue;
    ++count;
    if (finding.axis && f.axis && !(both_ends && *finding.axis == *f.axis - 1)) {
      EXPECT_EQ(*finding.axis, *f.axis) << rule.code;
    }
    const double since_s = static_cast<double>(finding.since.time_ns - v.first_ns) * 1e-9;
    if (f.at_s) {
      EXPECT_GE(since_s, *f.at_s - 0.2) << rule.code;
      EXPECT_LE(since_s, *f.at_s + 0.5) << rule.code;
    } else {
      EXPECT_LE(since_s, 0.25) << rule.code;
    }
  }
  EXPECT_GE(count, 1) << rule.code;
  EXPECT_LE(count, both_ends ? 2
                   : f.axis  ? 1
                             : o.axes)
      << rule.code << ":\n"
      << findingsText(v.findings);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, FaultRun,
    ::testing::Combine(::testing::ValuesIn(injectableRules()),
                       ::testing::Range<std::size_t>(0, faultSetups().size())),
    [](const ::testing::TestParamInfo<std::tuple<std::size_t, std::size_t>>& row) {
      std::string name = std::string(kRules[std::get<0>(row.param)].code) + "_" +
                         faultSetups()[std::get<1>(row.param)].name;
      std::replace(name.begin(), name.end(), '-', '_');
      return name;
    });

// Returned frames lost at random: only COM-004 (a frame not returned) is reported at warning or
// error.
struct LossRow {
  double loss;
  std::uint64_t seed;
};
class LossyRun : public ::testing::TestWithParam<LossRow> {};

TEST_P(LossyRun, OnlyFramesNotReturned) {
  SimOptions o = options(Scenario::Commissioning, 4, 2.0);
  o.loss = GetParam().loss;
  o.seed = GetParam().seed;
  ASSERT_EQ(test::statusText(resolveOptions(o)), "");
  const Validated v = validate(o, false);
  std::size_t not_returned = 0;
  for (const Finding& f : v.findings) {
    // three losses in a row are COM-003 at info: the drives had their data, ECatTErr stays 0
    if (f.severity != Severity::Info) {
      EXPECT_EQ(f.rule, RuleId::Com004) << findingsText({f});
    }
    not_returned += f.rule == RuleId::Com004;
  }
  // about loss × cycles of them
  EXPECT_GT(not_returned, static_cast<std::size_t>(o.loss * 2000 * 0.5));
  EXPECT_LT(not_returned, static_cast<std::size_t>(o.loss * 2000 * 1.5));
}

INSTANTIATE_TEST_SUITE_P(Rows, LossyRun, ::testing::Values(LossRow{0.01, 1}, LossRow{0.05, 2}));

TEST(Simulator, StopsWhenTheSinkDoes) {
  SimOptions o = options(Scenario::Commissioning, 2, 1.0);
  ASSERT_EQ(test::statusText(resolveOptions(o)), "");
  for (std::size_t stop_at : {1U, 2U, 500U}) {
    Simulator simulator(o);
    std::size_t seen = 0;
    const auto count = simulator.run([&](const SimFrame&) { return ++seen < stop_at; });
    EXPECT_FALSE(count.has_value()) << stop_at;
    EXPECT_EQ(seen, stop_at);
  }
}

class FaultsScenario : public ::testing::TestWithParam<bool> {};

TEST_P(FaultsScenario, FiresEveryRule) {
  SimOptions o = options(Scenario::Faults, 4, 4.3);
  o.diagnosis = GetParam();
  ASSERT_EQ(test::statusText(resolveOptions(o)), "");
  const Validated v = validate(o, true);
  std::set<std::string> fired, all;
  for (const Finding& f : v.findings) fired.insert(ruleDef(f.rule).code);
  // The rules off by default are not injected there (a plain validate would not report them),
  // nor those the simulator cannot inject (--list-faults says why), nor those of what the drives
  // and ESCs say without --diagnosis.
  for (const RuleDef& rule : kRules) {
    const FaultRecipe& recipe = *faultRecipe(rule.id);
    if (rule.by_default == ByDefault::On && recipe.injectable() &&
        (o.diagnosis || !recipe.diagnosis)) {
      all.insert(rule.code);
    }
  }
  EXPECT_EQ(fired, all) << findingsText(v.findings);
  EXPECT_EQ(all.size(), o.diagnosis ? 37U : 29U);
}

INSTANTIATE_TEST_SUITE_P(WithAndWithoutDiagnosis, FaultsScenario, ::testing::Bool());

// --- the incidents scenario (docs/simulate.md#incidents) ---

// Its truth: one incident per cause row, on the frames the drives' SEW.ServoErrors first reads
// 1 in a returned copy, COM-005's frame for the outage and ESM-003's for the fall from OP.
TEST(IncidentsScenario, TruthOnTheFramesTheCaptureShows) {
  SimOptions o = options(Scenario::Incidents, 4, 6);
  o.cycle_us = 2000;
  ASSERT_EQ(test::statusText(resolveOptions(o)), "");
  Simulator simulator(o);
  std::vector<Frame> frames;
  ASSERT_TRUE(simulator.run([&](const SimFrame& f) {
    frames.push_back({f.time_ns, Bytes(f.data, f.data + f.size)});
    return true;
  }));
  const Result<std::vector<IncidentTruth>> truth = simulator.incidents();
  ASSERT_TRUE(truth.has_value()) << truth.error().text();
  std::multiset<std::string> causes;
  std::uint64_t last = 0;
  for (const IncidentTruth& i : *truth) {
    if (i.kind == "drive-fault") causes.insert(i.cause);
    EXPECT_GE(i.frame, last) << "in capture order";
    EXPECT_LE(i.frame, frames.size());
    last = i.frame;
  }
  // one drive fault per cause row, and the outage's four
  EXPECT_EQ(causes,
            (std::multiset<std::string>{
                "following-error", "following-error-after-step", "overcurrent",
                "communication-loss", "bus-voltage", "encoder", "overspeed", "configuration",
                "nc-command", "unknown", "overtemperature", "communication-loss",
                "communication-loss", "communication-loss", "communication-loss"}));

  const Validated v = validate(o, true);
  auto finding = [&](const char* rule, std::uint64_t frame) {
    return std::count_if(v.findings.begin(), v.findings.end(), [&](const Finding& f) {
      return std::string(ruleDef(f.rule).code) == rule && f.at.frame == frame;
    });
  };
  for (const IncidentTruth& i : *truth) {
    if (i.kind == "bus-outage") {
      EXPECT_FALSE(i.axis.has_value());
      EXPECT_EQ(finding("COM-005", i.frame), 4) << "COM-005 of every axis at frame " << i.frame;
    } else if (i.kind == "esm") {
      EXPECT_EQ(finding("ESM-003", i.frame), 1) << "ESM-003 at frame " << i.frame;
    } else {
      ASSERT_TRUE(i.axis.has_value());
      ASSERT_GE(i.frame, 2u);
      ASSERT_TRUE(returnedMac(frames[i.frame - 1].bytes)) << i.frame << " is a returned copy";
    }
  }
  EXPECT_EQ(incidentsJson({{"bus-outage", std::nullopt, 7, "communication-loss"},
                           {"drive-fault", 2, 9, "overtemperature"}}),
            "{\n \"incidents\": [\n  {\n   \"kind\": \"bus-outage\",\n   \"axis\": null,\n   "
            "\"frame\": 7,\n   \"cause\": \"communication-loss\"\n  },\n  {\n   \"kind\": "
            "\"drive-fault\",\n   \"axis\": 2,\n   \"frame\": 9,\n   \"cause\": "
            "\"overtemperature\"\n  }\n ]\n}\n");
}

// Other scenarios plan no incident truth: the list is empty, not an error.
TEST(IncidentsScenario, NoneInOtherScenarios) {
  SimOptions o = options(Scenario::Commissioning, 2, 3);
  ASSERT_EQ(test::statusText(resolveOptions(o)), "");
  Simulator simulator(o);
  ASSERT_TRUE(simulator.run([](const SimFrame&) { return true; }));
  const Result<std::vector<IncidentTruth>> truth = simulator.incidents();
  ASSERT_TRUE(truth.has_value());
  EXPECT_TRUE(truth->empty());
}

// --- capture writer ---

struct WriterRow {
  const char* name;
  CaptureFormat format;
  std::int64_t resolution_ns;  // what the format keeps of a timestamp
  Compression compression = Compression::None;
};
class WriterRoundTrip : public ::testing::TestWithParam<WriterRow> {};

TEST_P(WriterRoundTrip, ReadsBackWithTheCaptureReader) {
  const WriterRow& row = GetParam();
  SimOptions o = options(Scenario::Commissioning, 2, 1.0);
  o.jitter_us = 100;  // timestamps that are not round numbers
  std::vector<Frame> frames = simulate(o);
  frames.resize(600);
  // a time with nanoseconds in it, and an odd frame size (pcapng pads its blocks)
  frames.push_back({frames.back().time_ns + 123'456'789, Bytes(61, 0xA5)});
  char path[] = "/tmp/ncservo_writer_XXXXXX";
  const int fd = mkstemp(path);
  ASSERT_GE(fd, 0);
  close(fd);
  auto writer = CaptureWriter::open(path, row.format, row.compression);
  ASSERT_TRUE(writer) << writer.error().text();
  for (const Frame& f : frames)
    ASSERT_TRUE((*writer)->write(f.time_ns, f.bytes.data(), f.bytes.size()));
  const Status closed = (*writer)->close();
  ASSERT_TRUE(closed) << closed.error().text();

  auto opened = CaptureReader::open(path);
  ASSERT_TRUE(opened) << opened.error().text();
  CaptureReader& reader = **opened;
  EXPECT_EQ(reader.compression(), row.compression);
  CaptureRecord record;
  std::size_t k = 0;
  Result<bool> next;
  while ((next = reader.next(record)) && *next) {
    ASSERT_LT(k, frames.size());
    const Frame& f = frames[k];
    EXPECT_EQ(record.frame, k + 1);
    EXPECT_EQ(record.time_ns, f.time_ns / row.resolution_ns * row.resolution_ns)
        << "frame " << k + 1;
    EXPECT_EQ(record.original, f.bytes.size());
    EXPECT_EQ(record.link, LinkType::Ethernet);
    ASSERT_EQ(record.captured, f.bytes.size());
    EXPECT_TRUE(std::equal(f.bytes.begin(), f.bytes.end(), record.data)) << "frame " << k + 1;
    ++k;
  }
  ASSERT_TRUE(next) << next.error().text();
  EXPECT_FALSE(*next);
  EXPECT_EQ(k, frames.size());
  std::remove(path);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, WriterRoundTrip,
    ::testing::Values(WriterRow{"pcapng_ns", CaptureFormat::Pcapng, 1},
                      WriterRow{"pcap_us", CaptureFormat::Pcap, 1000},
                      WriterRow{"pcapng_zstd", CaptureFormat::Pcapng, 1, Compression::Zstd},
                      WriterRow{"pcap_gzip", CaptureFormat::Pcap, 1000, Compression::Gzip}),
    [](const ::testing::TestParamInfo<WriterRow>& row) { return std::string(row.param.name); });

TEST(CaptureWriter, UnwritablePathNamesTheFile) {
  auto writer = CaptureWriter::open("/nonexistent-dir/x.pcap", CaptureFormat::Pcap);
  ASSERT_FALSE(writer);
  const std::string error = writer.error().text();
  EXPECT_NE(error.find("/nonexistent-dir/x.pcap"), std::string::npos) << error;
}

}  // namespace
}  // namespace ncservo::sim
