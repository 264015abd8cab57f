// The validator's fast path (an axis whose read bits did not change is not observed again) is
// derived from what the axis model and the rules declare they read (rules.hpp Reads). If a check
// read something it does not declare, the fast path would skip frames where its condition changes;
// this test runs every bundled capture and a table of simulated ones with the fast path on and
// off and requires the same findings, states, timelines, error histories and counters.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/layout/layout_window.hpp"
#include "ncservo/rules/validator.hpp"
#include "ncservo/sim/faults.hpp"
#include "ncservo/sim/simulator.hpp"
#include "row_name.hpp"
#include "status_text.hpp"

namespace ncservo {
namespace {

// Everything a run shows of the rules and the models, as text: a difference reads as a diff.
class Transcript {
 public:
  explicit Transcript(FastPath fast_path) : fast_path_(fast_path) {}

  // As the CLI does: the learning window's frames are validated once the layout is known.
  void frame(std::uint64_t number, std::int64_t time_ns, const std::uint8_t* data, std::size_t size,
             LinkType link) {
    const ByteReader bytes(data, size);
    EcatFrame walked;
    walkPacket(link, bytes, walked);
    if (window_.learning()) {
      window_.hold(number, time_ns, link, bytes, walked);
      if (!window_.learning()) decided();
      return;
    }
    validate(number, time_ns, walked, bytes);
  }
  void end() {
    if (!window_.learning()) return;
    window_.finish();
    decided();
  }

 private:
  void decided() {
    validator_.emplace(window_.options(), RuleSettings{}, fast_path_);
    window_.replay([this](std::uint64_t n, std::int64_t t, const EcatFrame& f,
                          const ByteReader& b) { validate(n, t, f, b); });
  }
  void validate(std::uint64_t number, std::int64_t time_ns, const EcatFrame& walked,
                const ByteReader& bytes) {
    const Observation& v = validator_->onFrame(number, time_ns, walked, bytes);
    for (const Finding& f : validator_->findings()) {
      lines_.push_back(std::to_string(number) + " " + ruleDef(f.rule).code + " axis " +
                       (f.axis ? std::to_string(*f.axis) : "-") + " since " +
                       std::to_string(f.since.frame) + ": " + f.message);
    }
    for (std::size_t i = 0; i < v.decode.axis_count; ++i) {
      const auto& state = v.states[i];
      states_ += std::to_string(state ? static_cast<int>(*state) : -1);
    }
    states_ += ';';
  }

 public:
  std::string finish() {
    end();
    std::string out;
    for (const std::string& line : lines_) out += line + "\n";
    out += "states " + std::to_string(std::hash<std::string>{}(states_)) + "\n";
    for (std::size_t a = 0; validator_ && a < validator_->axisCount(); ++a) {
      const AxisModel* m = validator_->axis(a);
      if (m == nullptr) continue;
      out += "axis " + std::to_string(a) + " state " +
             std::to_string(m->state() ? static_cast<int>(*m->state()) : -1) + " failures " +
             std::to_string(m->totalFailures()) + "/" + std::to_string(m->consecutiveFailed()) +
             " omitted " + std::to_string(m->timelineOmitted()) + "\n";
      for (const StateChange& c : m->timeline()) {
        out += "  " + std::string(driveStateName(c.state)) + " " +
               (c.transition ? c.transition : "-") + " " + std::to_string(c.at.frame) + "\n";
      }
      for (const ErrorHistoryEntry& e : m->errorHistory()) {
        out +=
            "  history " + std::string(e.cause->display) + " " + std::to_string(e.at.frame) + "\n";
      }
    }
    return out;
  }
  std::size_t findingCount() const { return lines_.size(); }

 private:
  FastPath fast_path_;
  LayoutWindow window_{DecoderOptions{}};
  std::optional<Validator> validator_;
  std::vector<std::string> lines_;
  std::string states_;
};

struct Both {
  Transcript on{FastPath::On};
  Transcript off{FastPath::Off};
  void frame(std::uint64_t n, std::int64_t t, const std::uint8_t* d, std::size_t s, LinkType l) {
    on.frame(n, t, d, s, l);
    off.frame(n, t, d, s, l);
  }
};

// --- the bundled captures ---------------------------------------------------------------------

struct CaptureRow {
  std::string name;  // file name
  std::string path;
};

void PrintTo(const CaptureRow& row, std::ostream* os) {
  *os << row.name;
}

std::vector<CaptureRow> bundledCaptures() {
  std::vector<CaptureRow> out;
  for (const auto& entry : std::filesystem::directory_iterator(NCSERVO_CAPTURES_DIR)) {
    const std::string ext = entry.path().extension().string();
    if (ext == ".pcap" || ext == ".pcapng") {
      out.push_back({entry.path().filename().string(), entry.path().string()});
    }
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  return out;
}

class FastPathOnBundled : public ::testing::TestWithParam<CaptureRow> {};

TEST_P(FastPathOnBundled, ChangesNothing) {
  auto reader = CaptureReader::open(GetParam().path);
  ASSERT_TRUE(reader) << reader.error().text();
  Both both;
  CaptureRecord record;
  Result<bool> more;
  while ((more = (*reader)->next(record)) && *more) {
    both.frame(record.frame, record.time_ns, record.data, record.captured, record.link);
  }
  EXPECT_EQ(both.on.finish(), both.off.finish());
}

INSTANTIATE_TEST_SUITE_P(Captures, FastPathOnBundled, ::testing::ValuesIn(bundledCaptures()),
                         test::rowName<CaptureRow>);

// --- simulated captures -----------------------------------------------------------------------

struct SimRow {
  const char* name;
  sim::SimOptions options;
  bool expect_findings;
};

void PrintTo(const SimRow& row, std::ostream* os) {
  *os << row.name;
}

sim::SimOptions opts(sim::Scenario scenario, int axes, double duration_s) {
  sim::SimOptions o;
  o.scenario = scenario;
  o.axes = axes;
  o.duration_s = duration_s;
  return o;
}

// A fault of each axis rule `wanted` accepts, the first at `first_s`, then one every `every_s`.
std::vector<sim::FaultRequest> faultsOneAfterAnother(double first_s, double every_s,
                                                     bool (*wanted)(const RuleDef&)) {
  std::vector<sim::FaultRequest> faults;
  for (const RuleDef& rule : kRules) {
    // only the axis rules the simulator injects (not MBX-001, MBX-002, ERH-002: no mailbox)
    const sim::FaultRecipe* recipe = sim::faultRecipe(rule.id);
    if (rule.kind != RuleKind::Axis || !wanted(rule) || recipe == nullptr ||
        !recipe->injectable()) {
      continue;
    }
    sim::FaultRequest fault;
    fault.rule = rule.id;
    fault.at_s = first_s + every_s * static_cast<double>(faults.size());
    fault.text = rule.code;
    faults.push_back(fault);
  }
  return faults;
}

std::vector<SimRow> simRows() {
  using sim::Scenario;
  std::vector<SimRow> rows;
  rows.push_back({"commissioning", opts(Scenario::Commissioning, 4, 3), false});
  rows.push_back({"faults", opts(Scenario::Faults, 4, 4.3), true});
  {
    SimRow r{"faults_interleaved_io", opts(Scenario::Faults, 5, 4.3), true};
    r.options.image = sim::ImageStyle::EtherLab;
    r.options.io_slaves = 3;
    r.options.seed = 3;
    rows.push_back(r);
  }
  {
    SimRow r{"faults_ready_mode_1_fast_cycle", opts(Scenario::Faults, 4, 4.3), true};
    r.options.ready_mode = 1;
    r.options.cycle_us = 250;
    r.options.seed = 8;
    rows.push_back(r);
  }
  {
    SimRow r{"soak_lossy_jitter", opts(Scenario::Soak, 6, 3), true};
    r.options.loss = 0.02;
    r.options.jitter_us = 40;
    r.options.seed = 9;
    rows.push_back(r);
  }
  {
    SimRow r{"soak_no_startup", opts(Scenario::Soak, 3, 3), false};
    r.options.startup = false;
    rows.push_back(r);
  }
  {
    SimRow r{"commissioning_no_startup_8_axes", opts(Scenario::Commissioning, 8, 3), false};
    r.options.startup = false;
    r.options.seed = 2;
    rows.push_back(r);
  }
  {
    // Communication lost again and again: drives fault (E15) and are cleared, delayed rules'
    // timers run most of the time, and the fast path skips an axis until the first can run out.
    SimRow r{"soak_lost_cycles_drives_faulting", opts(Scenario::Soak, 8, 4), true};
    r.options.seed = 4;
    for (int k = 1; k < 150; ++k) {
      r.options.lost_cycles.push_back({0.5 + 0.02 * k, 3, "lost"});
    }
    // and the delayed rules' conditions held past their timeouts meanwhile
    r.options.faults =
        faultsOneAfterAnother(0.7, 0.2, [](const RuleDef& rule) { return rule.delayed(); });
    rows.push_back(r);
  }
  {
    // Without a start-up no AL state is known, so the fast path runs throughout: every fault the
    // simulator can inject there, one after another.
    SimRow r{"soak_no_startup_every_axis_fault", opts(Scenario::Soak, 8, 20), true};
    r.options.startup = false;
    r.options.faults = faultsOneAfterAnother(
        1.0, 0.5, [](const RuleDef& rule) { return rule.id != RuleId::Esm002; });
    rows.push_back(r);
  }
  return rows;
}

class FastPathOnSimulated : public ::testing::TestWithParam<SimRow> {};

TEST_P(FastPathOnSimulated, ChangesNothing) {
  sim::SimOptions options = GetParam().options;
  ASSERT_EQ(test::statusText(sim::resolveOptions(options)), "");
  sim::Simulator simulator(options);
  Both both;
  std::uint64_t frame = 0;
  simulator.run([&](const sim::SimFrame& f) {
    both.frame(++frame, f.time_ns, f.data, f.size, LinkType::Ethernet);
    return true;
  });
  ASSERT_GT(frame, 1000u);
  EXPECT_EQ(both.on.finish(), both.off.finish());
  if (GetParam().expect_findings) {
    EXPECT_GT(both.on.findingCount(), 0u);
  }
}

INSTANTIATE_TEST_SUITE_P(Scenarios, FastPathOnSimulated, ::testing::ValuesIn(simRows()),
                         test::rowName<SimRow>);

}  // namespace
}  // namespace ncservo
