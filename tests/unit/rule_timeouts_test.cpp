// Each timed rule's row is the whole rule (rules.hpp): the timeout its row names, as the settings
// give it, moves its check, the milliseconds its message names and the window its HTML timeline
// draws; and a check or text given another row takes that row's timeout, never a class of its own.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "ncservo/rules/rules.hpp"
#include "row_name.hpp"
#include "timeline_run.hpp"

namespace ncservo {
namespace {

using test::At;
using test::kEnd;
using test::kMs;
using test::M;
using test::R;
using test::Script;

// Every timeout the row does not name: far from any the tests set, so that a check, a text or a
// window taken from another class shows.
constexpr std::int64_t kOtherTimeoutsMs = 40;
// A look-back rule's answer ends this long before its edge (`since`).
constexpr std::int64_t kAnsweredBeforeMs = 13;

struct TimedRow {
  const char* name;  // the rule's ID
  Script script;     // its condition begins at `since` and holds to the end
  At since;
  const char* timeout_text;  // how its message names the timeout, "{}" the ms; null: it does not
};

void PrintTo(const TimedRow& row, std::ostream* os) {
  *os << row.name;
}

const RuleDef& ruleOf(const TimedRow& row) {
  return **findRule(row.name);
}

// The row's timeout at `ms`, every other one at kOtherTimeoutsMs.
RuleSettings timeoutAt(const RuleDef& rule, std::int64_t ms) {
  RuleSettings s;
  for (const TimeoutDef& t : kTimeouts) {
    EXPECT_TRUE(s.setTimeout(t.name, t.id == *rule.timeout ? ms : kOtherTimeoutsMs));
  }
  return s;
}

std::vector<Finding> findingsOf(const std::vector<Finding>& all, RuleId rule) {
  std::vector<Finding> out;
  std::copy_if(all.begin(), all.end(), std::back_inserter(out),
               [&](const Finding& f) { return f.rule == rule; });
  return out;
}

class TimedRules : public ::testing::TestWithParam<TimedRow> {};

// Set through RuleSettings::setTimeout, the API of --timeout NAME=MS and [timeouts].
TEST_P(TimedRules, CheckTextAndWindowMoveWithTheRowsTimeout) {
  const TimedRow& row = GetParam();
  const RuleDef& rule = ruleOf(row);
  ASSERT_TRUE(rule.timeout.has_value());
  // An event answered around it (MBX-001, MBX-002) is reported as a delay is.
  const bool around = rule.timeout_use == TimeoutUse::Around;
  const bool delayed = rule.timeout_use == TimeoutUse::Delay || around;
  ASSERT_TRUE(delayed || rule.timeout_use == TimeoutUse::LookBack);
  // A delayed rule at two timeouts; a look-back rule just under and at how long ago its answer
  // ended: it fires, then it does not.
  const std::vector<std::int64_t> timeouts =
      delayed ? std::vector<std::int64_t>{7, 13}
              : std::vector<std::int64_t>{kAnsweredBeforeMs - 1, kAnsweredBeforeMs};
  for (const std::int64_t timeout_ms : timeouts) {
    SCOPED_TRACE(fmt::format("{} = {} ms", kTimeouts[static_cast<std::size_t>(*rule.timeout)].name,
                             timeout_ms));
    Script script = row.script;
    script.settings(timeoutAt(rule, timeout_ms));
    const test::Recorded r = test::record(script);
    const std::vector<Finding> found = findingsOf(r.findings, rule.id);
    if (!delayed && timeout_ms >= kAnsweredBeforeMs) {
      EXPECT_TRUE(found.empty()) << found.front().message;
      continue;
    }
    ASSERT_EQ(found.size(), 1u);
    const Finding& f = found.front();
    // The check: a delayed rule reports on the first frame past the timeout, a look-back rule on
    // its edge.
    const At at = delayed ? M(row.since.cycle + timeout_ms + 1) : row.since;
    EXPECT_EQ(f.at.frame, test::recordedFrame(at));
    EXPECT_EQ(f.since.frame, test::recordedFrame(row.since));
    // The text.
    if (row.timeout_text != nullptr) {
      const std::string named = fmt::format(fmt::runtime(row.timeout_text), timeout_ms);
      EXPECT_NE(f.message.find(named), std::string::npos) << f.message;
    }
    // The window, in ns from the finding's frame: after `since` for a delay, before it for a
    // look-back, both for an event answered around it.
    const auto drawn = std::find_if(
        r.timelines.drawn.begin(), r.timelines.drawn.end(),
        [&](const report::FindingTimeline& t) { return r.findings[t.finding].rule == rule.id; });
    ASSERT_NE(drawn, r.timelines.drawn.end());
    const std::int64_t since_ns = delayed ? -(timeout_ms + 1) * kMs : 0;
    EXPECT_EQ(drawn->since_ns, since_ns);
    const std::pair<std::int64_t, std::int64_t> window =
        around    ? std::pair{since_ns - timeout_ms * kMs, since_ns + timeout_ms * kMs}
        : delayed ? std::pair{since_ns, since_ns + timeout_ms * kMs}
                  : std::pair{since_ns - timeout_ms * kMs, since_ns};
    EXPECT_EQ(drawn->allowed_ns, window);
  }
}

// A row's timeout moved to another class: the check and the text follow the row they are given.
// On the frame of the finding, judged again with a copy of the row naming another class.
TEST_P(TimedRules, CheckAndTextReadTheRowTheyAreGiven) {
  const TimedRow& row = GetParam();
  const RuleDef& rule = ruleOf(row);
  ASSERT_TRUE(rule.timeout.has_value());
  const bool delayed =
      rule.timeout_use == TimeoutUse::Delay || rule.timeout_use == TimeoutUse::Around;
  RuleDef moved = rule;
  moved.timeout =
      *rule.timeout == Timeout::DriveResponse ? Timeout::NcRelease : Timeout::DriveResponse;
  const char* own = kTimeouts[static_cast<std::size_t>(*rule.timeout)].name;
  const char* other = kTimeouts[static_cast<std::size_t>(*moved.timeout)].name;
  // Each class at `own_ms` and `other_ms`.
  auto settings = [&](std::int64_t own_ms, std::int64_t other_ms) {
    RuleSettings s;
    EXPECT_TRUE(s.setTimeout(own, own_ms));
    EXPECT_TRUE(s.setTimeout(other, other_ms));
    return s;
  };
  Script script = row.script;
  script.settings(timeoutAt(rule, kAnsweredBeforeMs - 1));
  bool judged = false;
  test::record(script, [&](const Validator& validator) {
    const bool reported = std::any_of(validator.findings().begin(), validator.findings().end(),
                                      [&](const Finding& f) { return f.rule == rule.id; });
    if (!reported) return;
    judged = true;
    const RuleSubject subject{validator.axis(0)};
    if (delayed) {
      // Its condition holds whatever the timeout; the text names the moved row's.
      const RuleSettings s = settings(7, 29);
      EXPECT_TRUE(rule.check(subject, RuleContext{moved, s}));
      if (row.timeout_text != nullptr) {
        const std::string text = rule.describe(subject, RuleContext{moved, s}, 0);
        EXPECT_NE(text.find(fmt::format(fmt::runtime(row.timeout_text), 29)), std::string::npos)
            << text;
        EXPECT_EQ(text.find(fmt::format(fmt::runtime(row.timeout_text), 7)), std::string::npos)
            << text;
      }
      return;
    }
    // The answer ended kAnsweredBeforeMs ago: a timeout under that fires, one of it does not.
    const RuleSettings own_fires = settings(kAnsweredBeforeMs - 1, kAnsweredBeforeMs);
    const RuleSettings other_fires = settings(kAnsweredBeforeMs, kAnsweredBeforeMs - 1);
    EXPECT_TRUE(rule.check(subject, RuleContext{rule, own_fires}));
    EXPECT_FALSE(rule.check(subject, RuleContext{rule, other_fires}));
    EXPECT_FALSE(rule.check(subject, RuleContext{moved, own_fires}));
    EXPECT_TRUE(rule.check(subject, RuleContext{moved, other_fires}));
    if (row.timeout_text != nullptr) {
      const std::string text = rule.describe(subject, RuleContext{moved, other_fires}, 0);
      EXPECT_NE(text.find(fmt::format(fmt::runtime(row.timeout_text), kAnsweredBeforeMs - 1)),
                std::string::npos)
          << text;
    }
  });
  EXPECT_TRUE(judged) << "no finding to judge again";
}

// clang-format off
const std::uint32_t kIncr = test::kSswRunning | test::kIncremental;
const TimedRow kTimedRows[] = {
    // Look-back: the answer (a valid enable, the request) ends at cycle 10, the edge at 23.
    {"SE-002",
     Script().base(test::kScwArmed, test::kSswReady).scw(5, 10, test::kScwRunning)
         .scw(10, kEnd, test::kScwOff).ssw(23, kEnd, test::kSswRunning),
     R(23), "no valid enable within {} ms"},
    {"ZP-002",
     Script().base(test::kScwRunning, kIncr).scw(5, 10, test::kScwRunning | test::kZRequest)
         .ssw(23, kEnd, kIncr | test::kZAck),
     R(23), nullptr},
    {"EC-001",
     Script().scw(5, 10, test::kScwRunning | test::kClear)
         .ssw(23, kEnd, test::kSswRunning | test::kClearAck),
     R(23), nullptr},
    // Delayed.
    {"SE-003", Script().scw(10, kEnd, test::kScwOff), M(10), "expected 0 within {} ms"},
    {"SE-004",
     Script().base(test::kScwArmed, test::kSswReady).scw(5, kEnd, test::kScwRunning), M(5),
     "expected it within {} ms"},
    {"ZP-001",
     Script().base(test::kScwRunning, kIncr).scw(5, 10, test::kScwRunning | test::kZRequest)
         .ssw(6, kEnd, kIncr | test::kZAck),
     M(10), "expected 0 within {} ms"},
    {"EC-002",
     Script().scw(5, kEnd, test::kScwRunning | test::kClear)
         .ssw(6, kEnd, test::kSswRunning | test::kClearAck),
     R(6), "must drop it within {} ms"},
    {"EC-003",
     Script().scw(5, 10, test::kScwRunning | test::kClear)
         .ssw(6, kEnd, test::kSswRunning | test::kClearAck),
     M(10), "expected 0 within {} ms"},
    {"EC-004",
     Script().base(test::kScwOff, test::kSswNone, test::kSummary | test::kEncoderErr)
         .scw(5, kEnd, test::kScwOff | test::kClear),
     M(5), "acknowledge within {} ms"},
    {"SEW-002", Script().base(test::kScwOff, test::kSswNone).sew(5, kEnd, test::kSummary), R(5),
     "(limit {} ms)"},
    {"RDY-001", Script().base(test::kScwOff, test::kSswReady).ssw(10, kEnd, test::kSswNone), R(10),
     "(limit {} ms)"},
    {"FLT-001", Script().sew(5, kEnd, test::kSummary | test::kEncoderErr), R(5),
     "expected ServoEn 0 within {} ms"},
    {"PT-001", Script().scw(5, kEnd, test::kScwRunning | 0x10), M(5), "(limit {} ms)"},
    {"COM-003", Script().wkc(10, 13, 0), R(13), "did not rise within {} ms"},
    // Around: an emergency no SEW cause bit answers; a fault of a drive that sent an emergency
    // 37 ms before it (more than any timeout set here), answered by none.
    {"MBX-001", Script().stations(0x1001).emergency(10, 0x8611), R(10),
     "no SEW cause bit rose within {} ms"},
    {"MBX-002",
     Script().stations(0x1001).emergency(3, 0x8611).sew(3, 6, test::kSummary | test::kEncoderErr)
         .sew(40, kEnd, test::kSummary | test::kEncoderErr),
     R(40), "sent none within {} ms"},
};
// clang-format on

INSTANTIATE_TEST_SUITE_P(Rows, TimedRules, ::testing::ValuesIn(kTimedRows),
                         test::rowName<TimedRow>);

TEST(TimedRuleRows, EveryRowWithATimeoutIsARow) {
  std::set<std::string> listed;
  for (const TimedRow& row : kTimedRows) listed.insert(row.name);
  for (const RuleDef& rule : kRules) {
    EXPECT_EQ(listed.count(rule.code) == 1, rule.timeout.has_value()) << rule.code;
  }
}

}  // namespace
}  // namespace ncservo
