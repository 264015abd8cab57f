// What fails a run (cli/verdict.hpp): a capture's verdict and exit status under --fail-on,
// --fail-on-incident and --allow-empty, the order of the statuses, the incident gate's words.
#include "verdict.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "row_name.hpp"

namespace ncservo::cli {
namespace {

using report::BaselineState;
using report::CaptureReport;
using report::Verdict;

// docs/cli.md#verdicts: the words describe the capture, --fail-on only the exit status.
struct VerdictRow {
  const char* name;
  std::array<std::size_t, 3> counts;  // info, warning, error
  bool servo;                         // every axis checked
  bool unreadable;
  const char* fail_on;  // error, warning, info or never
  bool allow_empty;
  Verdict verdict;
  int exit_status;
};

class Verdicts : public ::testing::TestWithParam<VerdictRow> {};

TEST_P(Verdicts, DescribeTheCaptureWhateverTheGate) {
  const VerdictRow& row = GetParam();
  CaptureReport report;
  report.counts = row.counts;
  report.coverage.any_axis = row.servo;
  report.frames = 10;
  if (row.unreadable) report.error = "cut short";
  VerdictPolicy policy;
  policy.never = std::string(row.fail_on) == "never";
  if (!policy.never) policy.fail_on = *severityFromName(row.fail_on);
  policy.allow_empty = row.allow_empty;
  const CaptureVerdict judged = judgeCapture(policy, report);
  EXPECT_EQ(judged.verdict, row.verdict);
  EXPECT_EQ(judged.exit_status, row.exit_status);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, Verdicts,
    ::testing::Values(
        VerdictRow{"clean", {0, 0, 0}, true, false, "error", false, Verdict::Pass, 0},
        VerdictRow{"info_only", {3, 0, 0}, true, false, "error", false, Verdict::Pass, 0},
        VerdictRow{"warnings", {0, 2, 0}, true, false, "error", false, Verdict::Warn, 0},
        VerdictRow{
            "warnings_fail_on_warning", {0, 2, 0}, true, false, "warning", false, Verdict::Fail, 1},
        VerdictRow{"info_fail_on_info", {1, 0, 0}, true, false, "info", false, Verdict::Fail, 1},
        VerdictRow{"errors", {0, 0, 5}, true, false, "error", false, Verdict::Fail, 1},
        VerdictRow{"errors_never", {0, 5, 5}, true, false, "never", false, Verdict::Fail, 0},
        VerdictRow{"warnings_never", {0, 5, 0}, true, false, "never", false, Verdict::Warn, 0},
        VerdictRow{"no_servo", {0, 0, 0}, false, false, "error", false, Verdict::NoServo, 4},
        VerdictRow{"no_servo_allowed", {0, 0, 0}, false, false, "error", true, Verdict::NoServo, 0},
        VerdictRow{"no_servo_bus_error", {0, 0, 1}, false, false, "error", false, Verdict::Fail, 1},
        VerdictRow{
            "no_servo_bus_error_never", {0, 0, 1}, false, false, "never", false, Verdict::Fail, 4},
        VerdictRow{"unreadable", {0, 0, 2}, true, true, "error", false, Verdict::Unreadable, 3}),
    test::rowName<VerdictRow>);

// docs/cli.md#exit-status: incidents of the kinds --fail-on-incident names fail the run (with a
// baseline, only new ones), and the capture's verdict says FAIL.
struct IncidentVerdictRow {
  const char* name;
  std::vector<IncidentKind> kinds;
  std::vector<BaselineState> states;  // beside kinds; empty: no baseline
  const char* gate;
  std::size_t warnings;
  Verdict verdict;
  int exit_status;
};

class IncidentVerdicts : public ::testing::TestWithParam<IncidentVerdictRow> {};

TEST_P(IncidentVerdicts, GateTheKindsNamed) {
  const IncidentVerdictRow& row = GetParam();
  CaptureReport report;
  report.counts = {0, row.warnings, 0};
  report.coverage.any_axis = true;
  report.frames = 10;
  for (const IncidentKind kind : row.kinds) {
    Incident incident;
    incident.kind = kind;
    report.incidents.push_back(incident);
  }
  report.incident_states = row.states;
  VerdictPolicy policy;
  const Result<IncidentGate> gate = parseIncidentGate(row.gate);
  ASSERT_TRUE(gate) << gate.error().text();
  policy.incidents = *gate;
  const CaptureVerdict judged = judgeCapture(policy, report);
  EXPECT_EQ(judged.verdict, row.verdict);
  EXPECT_EQ(judged.exit_status, row.exit_status);
}

using enum IncidentKind;
constexpr BaselineState kNew = BaselineState::New;
constexpr BaselineState kSame = BaselineState::Unchanged;
INSTANTIATE_TEST_SUITE_P(
    Rows, IncidentVerdicts,
    ::testing::Values(
        IncidentVerdictRow{"none", {}, {}, "any", 0, Verdict::Pass, 0},
        IncidentVerdictRow{"drive_fault_any", {DriveFault}, {}, "any", 0, Verdict::Fail, 1},
        IncidentVerdictRow{"drive_fault_never", {DriveFault}, {}, "never", 1, Verdict::Warn, 0},
        IncidentVerdictRow{
            "outage_not_named", {BusOutage}, {}, "drive-fault,esm", 0, Verdict::Pass, 0},
        IncidentVerdictRow{"esm_named", {DriveFault, Esm}, {}, "esm", 0, Verdict::Fail, 1},
        IncidentVerdictRow{
            "unchanged_against_baseline", {DriveFault}, {kSame}, "any", 0, Verdict::Pass, 0},
        IncidentVerdictRow{"new_against_baseline",
                           {DriveFault, DriveFault},
                           {kSame, kNew},
                           "drive-fault",
                           0,
                           Verdict::Fail,
                           1}),
    test::rowName<IncidentVerdictRow>);

struct GateTextRow {
  const char* name;
  const char* text;
  const char* parsed;  // incidentGateText of it; "" when refused
};

class IncidentGates : public ::testing::TestWithParam<GateTextRow> {};

TEST_P(IncidentGates, ParseAndSayTheKinds) {
  const GateTextRow& row = GetParam();
  const Result<IncidentGate> gate = parseIncidentGate(row.text);
  EXPECT_EQ(gate ? incidentGateText(*gate) : std::string(), row.parsed);
  if (!gate) {
    EXPECT_NE(gate.error().text().find("is no kind of incident"), std::string::npos);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Rows, IncidentGates,
    ::testing::Values(GateTextRow{"any", "any", "any"}, GateTextRow{"never", "never", "never"},
                      GateTextRow{"one", "bus-outage", "bus-outage"},
                      GateTextRow{"two", "esm,drive-fault", "drive-fault,esm"},
                      GateTextRow{"all_three", "drive-fault,bus-outage,esm", "any"},
                      GateTextRow{"typo", "drive-faults", ""},
                      GateTextRow{"empty_word", "esm,", ""}),
    test::rowName<GateTextRow>);

TEST(Verdicts, TheMostSeriousStatusWins) {
  EXPECT_EQ(moreSerious(0, 4), 4);
  EXPECT_EQ(moreSerious(4, 1), 1);
  EXPECT_EQ(moreSerious(1, 3), 3);
  EXPECT_EQ(moreSerious(3, 2), 2);
  EXPECT_EQ(moreSerious(2, 130), 130);
}

}  // namespace
}  // namespace ncservo::cli
