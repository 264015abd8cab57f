// Baselines (baseline.hpp, docs/baselines.md): the matching of fingerprints, a JSON report read
// back, which baseline capture a capture is held against, and the ordinals the validator gives
// findings in each capture segment, through the simulator's recordings.
#include "ncservo/report/baseline.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "ncservo/pipeline/capture_pipeline.hpp"
#include "ncservo/report/report.hpp"
#include "ncservo/sim/simulator.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "row_name.hpp"
#include "status_text.hpp"
#include "verdict.hpp"

namespace ncservo::report {
namespace {

// "SE-001 axis0 2": a rule, an axis ("bus": none) and an ordinal.
Fingerprint parsed(const std::string& text) {
  const auto first = text.find(' ');
  const auto second = text.find(' ', first + 1);
  const std::string axis = text.substr(first + 1, second - first - 1);
  return {text.substr(0, first), axis == "bus" ? std::nullopt : std::optional(axis),
          static_cast<std::uint32_t>(std::stoul(text.substr(second + 1)))};
}

ReportedCapture captureOf(const std::vector<const char*>& fingerprints) {
  ReportedCapture capture;
  capture.path = "base.pcap";
  for (const char* f : fingerprints) {
    ReportedFinding finding;
    finding.fingerprint = parsed(f);
    capture.findings.push_back(finding);
  }
  return capture;
}

struct MatchRow {
  const char* name;
  std::vector<const char*> baseline;
  std::vector<const char*> next;  // in capture order
  const char* states;             // per finding of `next`: N new, U unchanged
  std::vector<const char*> absent;
  bool no_baseline_capture = false;
};

class Matching : public ::testing::TestWithParam<MatchRow> {};

TEST_P(Matching, EachFindingNewOrUnchangedAndTheRestAbsent) {
  const MatchRow& row = GetParam();
  const ReportedCapture baseline = captureOf(row.baseline);
  BaselineMatcher matcher(row.no_baseline_capture ? nullptr : &baseline);
  std::string states;
  for (const char* f : row.next) {
    states += matcher.match(parsed(f)) == BaselineState::New ? 'N' : 'U';
  }
  EXPECT_EQ(states, row.states);
  std::vector<std::string> absent, expected;
  for (const ReportedFinding& f : matcher.absent())
    absent.push_back(fingerprintText(f.fingerprint));
  for (const char* f : row.absent) expected.push_back(fingerprintText(parsed(f)));
  EXPECT_EQ(absent, expected);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, Matching,
    ::testing::Values(
        MatchRow{"same recording",
                 {"SE-001 axis0 1", "SE-001 axis0 2", "COM-002 bus 1"},
                 {"SE-001 axis0 1", "SE-001 axis0 2", "COM-002 bus 1"},
                 "UUU",
                 {}},
        // Ordinals restart in each segment: a clean recording in front changes none.
        MatchRow{"behind a clean recording",
                 {"SE-001 axis0 1", "COM-002 bus 1"},
                 {"SE-001 axis0 1", "COM-002 bus 1"},
                 "UU",
                 {}},
        // docs/baselines.md#fingerprints: a segment in front with findings of its own takes the
        // fingerprints first; the count of new ones is right, the later one is marked new.
        MatchRow{"behind a recording with a finding of the same rule",
                 {"SE-001 axis0 1"},
                 {"SE-001 axis0 1", "SE-001 axis0 1"},
                 "UN",
                 {}},
        MatchRow{"behind a recording with another rule's finding",
                 {"SE-001 axis0 1"},
                 {"EC-001 axis2 1", "SE-001 axis0 1"},
                 "NU",
                 {}},
        MatchRow{"one more violation on another rule",
                 {"SE-001 axis0 1", "EC-001 axis2 1"},
                 {"SE-001 axis0 1", "SEW-001 axis1 1", "EC-001 axis2 1"},
                 "UNU",
                 {}},
        MatchRow{"one fewer",
                 {"SE-001 axis0 1", "EC-001 axis2 1", "COM-002 bus 1"},
                 {"SE-001 axis0 1", "COM-002 bus 1"},
                 "UU",
                 {"EC-001 axis2 1"}},
        // One more of a rule on an axis before the others shifts their ordinals: the last is new.
        MatchRow{"ordinal shifts",
                 {"SE-001 axis0 1", "SE-001 axis0 2"},
                 {"SE-001 axis0 1", "SE-001 axis0 2", "SE-001 axis0 3"},
                 "UUN",
                 {}},
        MatchRow{"ordinal shifts down",
                 {"SE-001 axis0 1", "SE-001 axis0 2", "SE-001 axis0 3"},
                 {"SE-001 axis0 1", "SE-001 axis0 2"},
                 "UU",
                 {"SE-001 axis0 3"}},
        MatchRow{"another axis is another fingerprint",
                 {"SE-001 axis0 1"},
                 {"SE-001 axis1 1"},
                 "N",
                 {"SE-001 axis0 1"}},
        MatchRow{"the bus is not an axis",
                 {"COM-002 bus 1"},
                 {"COM-002 axis0 1"},
                 "N",
                 {"COM-002 bus 1"}},
        MatchRow{
            "no baseline capture: all new", {"SE-001 axis0 1"}, {"SE-001 axis0 1"}, "N", {}, true}),
    test::rowName<MatchRow>);

struct ParseRow {
  const char* name;
  const char* text;
  const char* error;  // a part of the message; "" when it reads
  std::size_t findings = 0;
};

class ReportFileParse : public ::testing::TestWithParam<ParseRow> {};

TEST_P(ReportFileParse, ReadsAReportOrSaysWhatIsWrong) {
  const ParseRow& row = GetParam();
  const Result<ReportFile> file = parseReportFile(row.text, "base.json");
  if (*row.error == '\0') {
    ASSERT_TRUE(file.has_value()) << file.error().text();
    ASSERT_EQ(file->captures.size(), 1u);
    EXPECT_EQ(file->captures[0].findings.size(), row.findings);
    return;
  }
  ASSERT_FALSE(file.has_value());
  EXPECT_NE(file.error().text().find("base.json: "), std::string::npos) << file.error().text();
  EXPECT_NE(file.error().text().find(row.error), std::string::npos) << file.error().text();
}

#define FINDING(fingerprint)                                                                 \
  R"({"rule": "SE-001", "severity": "error", "axis": 0, "axis_name": "axis0", "frame": 9, )" \
  R"("fingerprint": )" fingerprint "}"

INSTANTIATE_TEST_SUITE_P(
    Rows, ReportFileParse,
    ::testing::Values(
        ParseRow{"good",
                 R"({"captures": [{"path": "a.pcap", "findings": [)" FINDING(
                     R"("SE-001 axis0 #2")") "]}]}",
                 "", 1},
        ParseRow{"no findings", R"({"captures": [{"path": "a.pcap", "findings": []}]})", "", 0},
        ParseRow{"not json", "== a.pcap\n", "not JSON"},
        ParseRow{"not a report", R"({"runs": []})", "no 'captures' list"},
        ParseRow{"no path", R"({"captures": [{"findings": []}]})", "capture 1: no 'path'"},
        ParseRow{"older report",
                 R"({"captures": [{"path": "a", "findings": [{"rule": "SE-001", "severity": )"
                 R"("error", "axis_name": null}]}]})",
                 "capture 1, finding 1: no 'fingerprint'"},
        ParseRow{"fingerprint without ordinal",
                 R"({"captures": [{"path": "a", "findings": [)" FINDING(R"("SE-001 axis0")") "]}]}",
                 "does not end in #N"},
        ParseRow{"bad severity",
                 R"({"captures": [{"path": "a", "findings": [{"rule": "SE-001", "severity": )"
                 R"("fatal", "axis_name": null, "fingerprint": "SE-001 bus #1"}]}]})",
                 "'severity'"}),
    test::rowName<ParseRow>);

struct CaptureForRow {
  const char* name;
  std::vector<const char*> baseline;  // its captures' paths
  const char* capture;
  std::size_t run_captures;
  int expected;  // index into `baseline`, -1: none
};

class BaselineCaptureFor : public ::testing::TestWithParam<CaptureForRow> {};

TEST_P(BaselineCaptureFor, ByFileNameOrTheOneOfEach) {
  const CaptureForRow& row = GetParam();
  ReportFile file{"base.json", {}};
  for (const char* path : row.baseline) {
    file.captures.emplace_back();
    file.captures.back().path = path;
  }
  const ReportedCapture* found = baselineCaptureFor(file, row.capture, row.run_captures);
  EXPECT_EQ(found == nullptr ? -1 : static_cast<int>(found - file.captures.data()), row.expected);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, BaselineCaptureFor,
    ::testing::Values(
        CaptureForRow{
            "same name elsewhere", {"/ci/1/a.pcap", "/ci/1/b.pcap"}, "/ci/2/b.pcap", 2, 1},
        CaptureForRow{"one of each, another name", {"old.pcap"}, "new.pcap", 1, 0},
        CaptureForRow{"several, no such name", {"a.pcap", "b.pcap"}, "c.pcap", 1, -1},
        CaptureForRow{"one in the baseline, several run", {"a.pcap"}, "c.pcap", 2, -1},
        CaptureForRow{"two of that name", {"x/a.pcap", "y/a.pcap"}, "a.pcap", 1, -1}),
    test::rowName<CaptureForRow>);

// ---- diff: findings by rule and axis, incidents, the exit status ----

// "drive-fault axis1 communication-loss 2": kind, axis ("bus": none), cause, ordinal (1 if none).
ReportedIncident incident(const std::string& text) {
  std::istringstream words(text);
  std::string kind, axis, cause;
  std::uint32_t ordinal = 1;
  words >> kind >> axis >> cause >> ordinal;
  ReportedIncident i;
  i.fingerprint.kind = kind;
  if (axis != "bus") i.fingerprint.axis = axis;
  i.fingerprint.cause = cause;
  i.fingerprint.ordinal = ordinal;
  return i;
}

struct DiffRow {
  const char* name;
  std::vector<const char*> base, next;  // findings' fingerprints; those with "warn" are warnings
  std::vector<const char*> base_incidents, next_incidents;
  std::size_t added, absent, unchanged;
  std::size_t incidents_added, incidents_absent, incidents_unchanged;
  bool fails;  // at --fail-on error
  // The kinds --fail-on-incident gates, and whether NEW's incidents then fail the diff.
  const char* incident_gate = "never";
  bool incident_fails = false;
};

class Diff : public ::testing::TestWithParam<DiffRow> {};

TEST_P(Diff, CountsAndTheExitStatus) {
  const DiffRow& row = GetParam();
  auto side = [](const std::vector<const char*>& findings,
                 const std::vector<const char*>& incidents) {
    ReportedCapture c = captureOf(findings);
    for (std::size_t k = 0; k < findings.size(); ++k) {
      c.findings[k].severity =
          c.findings[k].fingerprint.rule == "COM-002" ? Severity::Warning : Severity::Error;
    }
    for (const char* i : incidents) c.incidents.push_back(incident(i));
    return c;
  };
  const CaptureDiff d =
      diffCaptures(side(row.base, row.base_incidents), side(row.next, row.next_incidents));
  EXPECT_EQ(d.added.size(), row.added);
  EXPECT_EQ(d.absent.size(), row.absent);
  EXPECT_EQ(d.unchanged, row.unchanged);
  EXPECT_EQ(d.incidents_added.size(), row.incidents_added);
  EXPECT_EQ(d.incidents_absent.size(), row.incidents_absent);
  EXPECT_EQ(d.incidents_unchanged, row.incidents_unchanged);
  std::size_t by_group = 0;
  for (const DiffGroup& g : d.groups) {
    EXPECT_EQ(g.next, g.added + g.unchanged) << g.rule;
    EXPECT_EQ(g.base, g.absent + g.unchanged) << g.rule;
    by_group += g.added;
  }
  EXPECT_EQ(by_group, row.added);
  const cli::IncidentGate none = *cli::parseIncidentGate("never");
  EXPECT_EQ(cli::diffFails(d, Severity::Error, false, none), row.fails);
  EXPECT_FALSE(cli::diffFails(d, Severity::Error, true, none));  // --fail-on never
  const cli::IncidentGate gate = *cli::parseIncidentGate(row.incident_gate);
  EXPECT_EQ(cli::diffFails(d, Severity::Error, true, gate), row.incident_fails);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, Diff,
    ::testing::Values(
        DiffRow{"same", {"SE-001 axis0 1"}, {"SE-001 axis0 1"}, {}, {}, 0, 0, 1, 0, 0, 0, false},
        DiffRow{"one more error",
                {"SE-001 axis0 1"},
                {"SE-001 axis0 1", "SEW-001 axis1 1"},
                {},
                {},
                1,
                0,
                1,
                0,
                0,
                0,
                true},
        DiffRow{"one more warning", {}, {"COM-002 bus 1"}, {}, {}, 1, 0, 0, 0, 0, 0, false},
        DiffRow{"one fewer",
                {"SE-001 axis0 1", "SEW-001 axis1 1"},
                {"SE-001 axis0 1"},
                {},
                {},
                0,
                1,
                1,
                0,
                0,
                0,
                false},
        DiffRow{"incidents by kind, axis and cause",
                {},
                {},
                {"drive-fault axis1 communication-loss", "bus-outage bus -"},
                {"drive-fault axis1 overtemperature", "bus-outage bus -",
                 "drive-fault axis1 communication-loss"},
                0,
                0,
                0,
                1,
                0,
                2,
                false,
                "drive-fault",
                true},
        DiffRow{"a second fault of one cause",
                {},
                {},
                {"drive-fault axis1 encoder"},
                {"drive-fault axis1 encoder", "drive-fault axis1 encoder 2"},
                0,
                0,
                0,
                1,
                0,
                1,
                false,
                "any",
                true},
        DiffRow{"a new outage, drive faults gated",
                {},
                {},
                {},
                {"bus-outage bus communication-loss"},
                0,
                0,
                0,
                1,
                0,
                0,
                false,
                "drive-fault,esm",
                false},
        DiffRow{"a new slave fall, esm gated",
                {},
                {},
                {},
                {"esm 0x1002 unknown"},
                0,
                0,
                0,
                1,
                0,
                0,
                false,
                "esm",
                true},
        DiffRow{"an incident gone",
                {},
                {},
                {"esm axis2 -", "drive-fault axis0 encoder"},
                {"drive-fault axis0 encoder"},
                0,
                0,
                0,
                0,
                1,
                1,
                false,
                "any",
                false}),
    test::rowName<DiffRow>);

// ---- The ordinals the validator gives, through simulated recordings ----

struct Frame {
  std::int64_t time_ns;
  std::vector<std::uint8_t> bytes;
};

std::vector<Frame> simulate(std::uint64_t seed, const std::vector<const char*>& faults) {
  sim::SimOptions o;
  o.seed = seed;
  o.axes = 4;
  for (const char* text : faults) o.faults.push_back(*sim::parseFault(text));
  EXPECT_EQ(test::statusText(sim::resolveOptions(o)), "");
  std::vector<Frame> frames;
  sim::Simulator simulator(o);
  EXPECT_TRUE(simulator.run([&](const sim::SimFrame& f) {
    frames.push_back({f.time_ns, {f.data, f.data + f.size}});
    return true;
  }));
  return frames;
}

// The recordings one after the other, as `mergecap -a` joins them (each keeps its timestamps, so
// each after the first starts a segment), through the pipeline as `validate` runs it.
CaptureReport judge(const std::vector<const std::vector<Frame>*>& recordings,
                    const ReportedCapture* baseline) {
  CaptureReport report;
  report.path = "capture.pcap";
  if (baseline != nullptr) report.baseline.emplace(baseline);
  CapturePipeline pipeline(
      {DecoderOptions{}, RuleSettings{}, TimeWindow{}, TimestampMode::Capture});
  pipeline.setSinks(
      {[&](const DecoderOptions&) { report.layout = pipeline.validator()->decoder().axes(); },
       nullptr, nullptr,
       [&](const std::vector<Finding>& findings) {
         for (const Finding& f : findings) {
           report.baseline_states.push_back(report.tally(f));
           report.findings.push_back(f);
         }
       },
       nullptr});
  std::uint64_t number = 0;
  EcatFrame frame;
  for (const std::vector<Frame>* recording : recordings) {
    for (const Frame& f : *recording) {
      const ByteReader bytes(f.bytes.data(), f.bytes.size());
      walkPacket(LinkType::Ethernet, bytes, frame);
      pipeline.onWalkedFrame(++number, f.time_ns, LinkType::Ethernet, bytes, frame);
    }
  }
  pipeline.finish();
  report.segment_count = pipeline.validator()->segments().count();
  report.closeBaseline();
  return report;
}

struct SegmentRow {
  const char* name;
  bool clean_in_front;
  std::vector<const char*> extra_faults;  // beyond the baseline's
  std::size_t segments;
  std::size_t added, unchanged, absent;
};

class SegmentOrdinals : public ::testing::TestWithParam<SegmentRow> {};

const std::vector<const char*> kFaults = {"SE-002@0.7:0", "COM-002@0.9", "EC-001@1.0:2"};

TEST_P(SegmentOrdinals, TheSameRecordingMatchesWhereverItIs) {
  const SegmentRow& row = GetParam();
  static const std::vector<Frame> base = simulate(3, kFaults);
  static const std::vector<Frame> clean = simulate(9, {});
  const CaptureReport base_report = judge({&base}, nullptr);
  ASSERT_EQ(base_report.findings.size(), 3u);
  // The baseline is what its JSON report holds.
  const ReportedCapture baseline = reportedCaptureOf(base_report, Verdict::Fail);
  std::vector<const char*> faults = kFaults;
  faults.insert(faults.end(), row.extra_faults.begin(), row.extra_faults.end());
  const std::vector<Frame> next = row.extra_faults.empty() ? base : simulate(3, faults);
  std::vector<const std::vector<Frame>*> recordings{&next};
  if (row.clean_in_front) recordings.insert(recordings.begin(), &clean);
  const CaptureReport report = judge(recordings, &baseline);
  EXPECT_EQ(report.segment_count, row.segments);
  EXPECT_EQ(report.newCount(), row.added);
  EXPECT_EQ(report.unchanged, row.unchanged);
  EXPECT_EQ(report.baseline_absent.size(), row.absent);
  EXPECT_EQ(describeBaseline(report),
            fmt::format("{} new, {} unchanged, {} absent", row.added, row.unchanged, row.absent));
}

// The recording twice over in one file: the second copy is a segment of its own, whose findings
// have the first copy's fingerprints (docs/baselines.md#fingerprints).
TEST(SegmentOrdinalsRestart, TheSecondCopyHasTheFirstsFingerprints) {
  const std::vector<Frame> base = simulate(3, kFaults);
  const CaptureReport report = judge({&base, &base}, nullptr);
  EXPECT_EQ(report.segment_count, 2u);
  ASSERT_EQ(report.findings.size(), 6u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(report.findings[i].ordinal, 1u);
    EXPECT_EQ(fingerprintText(report.fingerprintOf(report.findings[i])),
              fingerprintText(report.fingerprintOf(report.findings[i + 3])));
  }
}

INSTANTIATE_TEST_SUITE_P(
    Rows, SegmentOrdinals,
    ::testing::Values(SegmentRow{"same recording", false, {}, 1, 0, 3, 0},
                      SegmentRow{"behind another recording", true, {}, 2, 0, 3, 0},
                      SegmentRow{"one more violation", false, {"SEW-001@1.2:1"}, 1, 1, 3, 0},
                      SegmentRow{"one more, behind another", true, {"SEW-001@1.2:1"}, 2, 1, 3, 0}),
    test::rowName<SegmentRow>);

}  // namespace
}  // namespace ncservo::report
