// The rules (docs/rules.md) as the Validator reports them (validator.hpp), on default-layout cycles
// built byte by byte (validator_driver.hpp): per rule a row where it fires — rule, axis, the frame
// it is reported on and the frame the condition began, exactly — a row where it must not, and for
// every timed rule the two rows at its limit (held exactly T: nothing; one cycle more: reported).
#include "ncservo/rules/validator.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <cstdint>
#include <iterator>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/layout/session.hpp"
#include "ncservo/model/axis_model.hpp"
#include "ncservo/protocol/fields.hpp"
#include "row_name.hpp"
#include "validator_driver.hpp"

namespace ncservo {
namespace {

using test::At;
using test::Bytes;
using test::Dg;
using test::FrameBuilder;
using test::kClear;
using test::kClearAck;
using test::kEcatTErr;
using test::kEncoderErr;
using test::kEnd;
using test::kEpochNs;
using test::kIncremental;
using test::kMs;
using test::kNoEncoder;
using test::kScwArmed;
using test::kScwOff;
using test::kScwRunning;
using test::kScwSe3;
using test::kSswNone;
using test::kSswReady;
using test::kSswRunning;
using test::kSummary;
using test::kUs;
using test::kZAck;
using test::kZRequest;
using test::M;
using test::physical;
using test::R;
using test::Script;
using test::ValidatorDriver;

RuleSettings readyMode(int mode) {
  RuleSettings s;
  s.servo_ready_mode = mode;
  return s;
}
RuleSettings timeoutMs(const char* name, std::int64_t ms) {
  RuleSettings s;
  EXPECT_TRUE(s.setTimeout(name, ms));
  return s;
}
// An off-by-default timing rule enabled with its limit (docs/rules.md#com-006, COM-007).
RuleSettings timingRule(const char* code, const char* limit, std::int64_t value) {
  RuleSettings s;
  EXPECT_TRUE(s.enable(code));
  EXPECT_TRUE(s.setLimit(limit, value));
  return s;
}
RuleSettings failureLimit(std::uint32_t limit) {
  RuleSettings s;
  s.telegram_failure_limit = limit;
  return s;
}

// Each rule's severity as docs/rules.md gives it, written out (rules_test.cpp holds the table to
// the catalogue): the expectation does not come from the table under test.
Severity catalogueSeverity(RuleId rule) {
  const std::string errors =
      " SE-001 SE-002 SE-003 ZP-001 ZP-002 EC-001 EC-003 SEW-001 RDY-001 "
      "FLT-001 COM-001 COM-005 ESM-001 ESM-003 ";
  const std::string warnings =
      " SE-004 ZP-003 EC-002 EC-004 SEW-002 SEW-003 SSW-001 SCW-001 "
      "PT-001 MSG-001 COM-002 COM-004 COM-006 COM-007 ESM-002 ";
  const std::string infos = " COM-003 ESM-004 ";
  const std::string code = " " + std::string(ruleDef(rule).code) + " ";
  if (errors.find(code) != std::string::npos) return Severity::Error;
  if (warnings.find(code) != std::string::npos) return Severity::Warning;
  EXPECT_NE(infos.find(code), std::string::npos) << code << "has no severity written here";
  return Severity::Info;
}

// One expected finding: where it is reported and where its condition began.
struct Expect {
  RuleId rule;
  std::optional<std::uint16_t> axis;
  At at;
  At since;
};
Expect on(RuleId rule, At at, At since, std::uint16_t axis = 0) {
  return Expect{rule, axis, at, since};
}
Expect now(RuleId rule, At at, std::uint16_t axis = 0) {
  return Expect{rule, axis, at, at};
}
Expect bus(RuleId rule, At at, At since) {
  return Expect{rule, std::nullopt, at, since};
}

struct RuleCase {
  std::string name;
  std::vector<RuleId> rules;  // the findings compared are those of these rules
  Script script;
  std::vector<Expect> expected;
  std::string message{};  // a text every expected finding's message contains
};

std::unique_ptr<ValidatorDriver> runScript(const Script& script,
                                           std::optional<RuleSettings> settings = {}) {
  auto driver = std::make_unique<ValidatorDriver>(settings.value_or(script.ruleSettings()));
  driver->run(script);
  return driver;
}

bool watched(const RuleCase& c, RuleId rule) {
  for (RuleId r : c.rules) {
    if (r == rule) return true;
  }
  return false;
}

// clang-format off
std::vector<RuleCase> ruleCases() {
  using Id = RuleId;
  const Id SE1 = Id::Se001, SE2 = Id::Se002, SE3 = Id::Se003, SE4 = Id::Se004;
  const Id ZP1 = Id::Zp001, ZP2 = Id::Zp002, ZP3 = Id::Zp003;
  const Id EC1 = Id::Ec001, EC2 = Id::Ec002, EC3 = Id::Ec003, EC4 = Id::Ec004;
  const Id SEW1 = Id::Sew001, SEW2 = Id::Sew002, SEW3 = Id::Sew003;
  const Id SSW1 = Id::Ssw001, SCW1 = Id::Scw001, RDY1 = Id::Rdy001, FLT1 = Id::Flt001;
  const Id PT1 = Id::Pt001, MSG1 = Id::Msg001;
  const Id COM1 = Id::Com001, COM2 = Id::Com002, COM3 = Id::Com003, COM4 = Id::Com004;
  const Id COM5 = Id::Com005, COM6 = Id::Com006, COM7 = Id::Com007;
  const std::uint32_t incr = kSswRunning | kIncremental;  // enabled, incremental encoder
  return {
    // ---- SE-001: SE becomes 0x2 from anything but 0x1 (immediate) ----
    {"SE001 0x0 to 0x2", {SE1}, Script().base(kScwOff, kSswReady).scw(5, kEnd, kScwRunning),
     {now(SE1, M(5))}, "0x0 -> 0x2"},
    {"SE001 0x3 to 0x2", {SE1},
     Script().base(kScwOff, kSswReady).scw(5, 6, kScwSe3).scw(6, kEnd, kScwRunning),
     {now(SE1, M(6))}, "0x3 -> 0x2"},
    {"SE001 not for 0x0 0x1 0x2", {SE1},
     Script().base(kScwOff, kSswReady).scw(5, 6, kScwArmed).scw(6, kEnd, kScwRunning), {}},
    {"SE001 again after SE left 0x2", {SE1},
     Script().base(kScwOff, kSswReady).scw(5, 10, kScwRunning).scw(20, kEnd, kScwRunning),
     {now(SE1, M(5)), now(SE1, M(20))}},
    {"SE001 on axis 1 of 2", {SE1},
     Script().axes(2).base(kScwOff, kSswReady).scw(5, kEnd, kScwRunning, 1),
     {now(SE1, M(5), 1)}},

    // ---- SE-002: ServoEn rises with no valid enable within drive_response (immediate) ----
    {"SE002 rise with SE 0", {SE2}, Script().base(kScwOff, kSswReady).ssw(10, kEnd, kSswRunning),
     {now(SE2, R(10))}},
    {"SE002 rise after an illegal enable", {SE2},
     Script().base(kScwOff, kSswReady).scw(5, kEnd, kScwRunning).ssw(6, kEnd, kSswRunning),
     {now(SE2, R(6))}},
    {"SE002 not after a legal enable", {SE2},
     Script().base(kScwOff, kSswReady).scw(4, 5, kScwArmed).scw(5, kEnd, kScwRunning)
         .ssw(6, kEnd, kSswRunning), {}},
    {"SE002 not exactly drive_response after the enable ended", {SE2},
     Script().base(kScwArmed, kSswReady).scw(5, 10, kScwRunning).scw(10, kEnd, kScwOff)
         .ssw(30, kEnd, kSswRunning), {}},
    {"SE002 one cycle after drive_response after the enable ended", {SE2},
     Script().base(kScwArmed, kSswReady).scw(5, 10, kScwRunning).scw(10, kEnd, kScwOff)
         .ssw(31, kEnd, kSswRunning), {now(SE2, R(31))}},

    // ---- SE-003: ServoEn stays 1 longer than drive_response without a valid enable ----
    {"SE003 enable ended", {SE3}, Script().scw(10, kEnd, kScwOff), {on(SE3, M(31), M(10))},
     "after the enable ended"},
    {"SE003 held exactly drive_response", {SE3},
     Script().scw(10, kEnd, kScwOff).ssw(30, kEnd, kSswReady), {}},
    {"SE003 drive disables at once", {SE3},
     Script().scw(10, kEnd, kScwOff).ssw(10, kEnd, kSswReady), {}},
    {"SE003 with no valid enable", {SE3},
     Script().base(kScwOff, kSswReady).ssw(10, kEnd, kSswRunning), {on(SE3, M(31), R(10))},
     "with no valid enable"},
    {"SE003 reported on the returned copy when it is the first frame past T", {SE3},
     Script().delay(400 * kUs).scw(10, kEnd, kScwOff), {on(SE3, R(30), M(10))}},
    {"SE003 after an illegal enable", {SE3},
     Script().base(kScwOff, kSswReady).scw(5, kEnd, kScwRunning).ssw(6, kEnd, kSswRunning),
     {on(SE3, M(27), R(6))}},
    {"SE003 drive_response override moves the report", {SE3},
     Script().scw(10, kEnd, kScwOff).settings(timeoutMs("drive_response", 5)),
     {on(SE3, M(16), M(10))}, "within 5 ms"},
    {"SE003 once per episode, again after it ended", {SE3},
     Script(120).scw(10, kEnd, kScwOff).ssw(40, 60, kSswReady),
     {on(SE3, M(31), M(10)), on(SE3, M(81), R(60))}},

    // ---- SE-004: a valid enable to a ready drive held longer than enable_response ----
    {"SE004 mode 0 inferred", {SE4},
     Script(120).base(kScwArmed, kSswReady).scw(5, kEnd, kScwRunning), {on(SE4, M(106), M(5))}},
    {"SE004 held exactly enable_response", {SE4},
     Script(120).base(kScwArmed, kSswReady).scw(5, kEnd, kScwRunning).ssw(105, kEnd, kSswRunning),
     {}},
    {"SE004 mode 1 inferred, no error means ready", {SE4},
     Script(120).base(kScwArmed, kSswNone).scw(5, kEnd, kScwRunning), {on(SE4, M(106), M(5))}},
    {"SE004 not with EMGON 0", {SE4},
     Script(120).base(0x401, kSswReady).scw(5, kEnd, 0x402), {}},
    {"SE004 not with Brake 0", {SE4},
     Script(120).base(0x005, kSswReady).scw(5, kEnd, 0x006), {}},
    {"SE004 not when mode 0 and RDY 0", {SE4},
     Script(120).base(kScwArmed, kSswNone).scw(5, kEnd, kScwRunning).settings(readyMode(0)), {}},
    {"SE004 not when mode 1 and in error", {SE4},
     Script(120).base(kScwArmed, kSswNone, kSummary | kEncoderErr).scw(5, kEnd, kScwRunning)
         .settings(readyMode(1)), {}},
    {"SE004 not while the ready mode is unknown", {SE4},
     Script(120).base(kScwArmed, kSswNone, kSummary | kEncoderErr).scw(5, kEnd, kScwRunning), {}},

    // ---- ZP-001: ZPulseAck stays 1 longer than drive_response after the request fell ----
    {"ZP001 ack held", {ZP1},
     Script().base(kScwRunning, incr).scw(5, 10, kScwRunning | kZRequest).ssw(6, kEnd, incr | kZAck),
     {on(ZP1, M(31), M(10))}},
    {"ZP001 held exactly drive_response", {ZP1},
     Script().base(kScwRunning, incr).scw(5, 10, kScwRunning | kZRequest).ssw(6, 30, incr | kZAck),
     {}},
    {"ZP001 ack cleared at once", {ZP1},
     Script().base(kScwRunning, incr).scw(5, 10, kScwRunning | kZRequest).ssw(6, 11, incr | kZAck),
     {}},
    {"ZP001 starts at the later cause, the ack's rise", {ZP1},
     Script().base(kScwRunning, incr).scw(5, 10, kScwRunning | kZRequest).ssw(15, kEnd, incr | kZAck),
     {on(ZP1, M(36), R(15))}},

    // ---- ZP-002: ZPulseAck rises while the request has been 0 longer than drive_response ----
    {"ZP002 ack with no request", {ZP2}, Script().base(kScwRunning, incr).ssw(30, kEnd, incr | kZAck),
     {now(ZP2, R(30))}},
    {"ZP002 not exactly drive_response after the request fell", {ZP2},
     Script().base(kScwRunning, incr).scw(5, 10, kScwRunning | kZRequest).ssw(30, kEnd, incr | kZAck),
     {}},
    {"ZP002 one cycle after drive_response after the request fell", {ZP2},
     Script().base(kScwRunning, incr).scw(5, 10, kScwRunning | kZRequest).ssw(31, kEnd, incr | kZAck),
     {now(ZP2, R(31))}},
    {"ZP002 not for an answered request", {ZP2},
     Script().base(kScwRunning, incr).scw(5, kEnd, kScwRunning | kZRequest).ssw(7, kEnd, incr | kZAck),
     {}},
    {"ZP002 first observation has no edge", {ZP2}, Script().base(kScwRunning, incr | kZAck), {}},

    // ---- ZP-003: a zero-pulse request to an absolute encoder or none (immediate) ----
    {"ZP003 absolute encoder", {ZP3}, Script().scw(5, kEnd, kScwRunning | kZRequest),
     {now(ZP3, M(5))}, "absolute encoder"},
    {"ZP003 no encoder", {ZP3},
     Script().base(kScwRunning, incr | kNoEncoder).scw(5, kEnd, kScwRunning | kZRequest),
     {now(ZP3, M(5))}, "no encoder"},
    {"ZP003 not for an incremental encoder", {ZP3},
     Script().base(kScwRunning, incr).scw(5, kEnd, kScwRunning | kZRequest), {}},

    // ---- EC-001: ErrClearAck rises while ErrorClear has been 0 longer than drive_response ----
    {"EC001 ack with no request", {EC1}, Script().ssw(30, kEnd, kSswRunning | kClearAck),
     {now(EC1, R(30))}},
    {"EC001 not exactly drive_response after the request fell", {EC1},
     Script().scw(5, 10, kScwRunning | kClear).ssw(30, kEnd, kSswRunning | kClearAck), {}},
    {"EC001 one cycle after drive_response after the request fell", {EC1},
     Script().scw(5, 10, kScwRunning | kClear).ssw(31, kEnd, kSswRunning | kClearAck),
     {now(EC1, R(31))}},
    {"EC001 not for an answered request", {EC1},
     Script().scw(5, 8, kScwRunning | kClear).ssw(6, 9, kSswRunning | kClearAck), {}},
    {"EC001 first observation has no edge", {EC1}, Script().base(kScwRunning, kSswRunning | kClearAck),
     {}},

    // ---- EC-002: ErrorClear held longer than nc_release after ErrClearAck rose ----
    {"EC002 request held", {EC2},
     Script().scw(5, kEnd, kScwRunning | kClear).ssw(6, kEnd, kSswRunning | kClearAck),
     {on(EC2, M(57), R(6))}},
    {"EC002 held exactly nc_release", {EC2},
     Script().scw(5, 56, kScwRunning | kClear).ssw(6, kEnd, kSswRunning | kClearAck), {}},
    {"EC002 request dropped at once", {EC2},
     Script().scw(5, 7, kScwRunning | kClear).ssw(6, 8, kSswRunning | kClearAck), {}},

    // ---- EC-003: ErrClearAck stays 1 longer than drive_response after ErrorClear fell ----
    {"EC003 ack held", {EC3},
     Script().scw(5, 10, kScwRunning | kClear).ssw(6, kEnd, kSswRunning | kClearAck),
     {on(EC3, M(31), M(10))}},
    {"EC003 held exactly drive_response", {EC3},
     Script().scw(5, 10, kScwRunning | kClear).ssw(6, 30, kSswRunning | kClearAck), {}},
    {"EC003 ack cleared at once", {EC3},
     Script().scw(5, 10, kScwRunning | kClear).ssw(6, 10, kSswRunning | kClearAck), {}},

    // ---- EC-004: ErrorClear on a drive in error not acknowledged within clear_response ----
    {"EC004 no acknowledge", {EC4},
     Script(120).base(kScwOff, kSswNone, kSummary | kEncoderErr).scw(5, kEnd, kScwOff | kClear),
     {on(EC4, M(106), M(5))}},
    {"EC004 acknowledged exactly at clear_response", {EC4},
     Script(120).base(kScwOff, kSswNone, kSummary | kEncoderErr).scw(5, kEnd, kScwOff | kClear)
         .ssw(105, kEnd, kClearAck), {}},
    {"EC004 acknowledged at once", {EC4},
     Script(120).base(kScwOff, kSswNone, kSummary | kEncoderErr).scw(5, kEnd, kScwOff | kClear)
         .ssw(6, kEnd, kClearAck).sew(6, kEnd, 0), {}},
    {"EC004 not without an error", {EC4},
     Script(120).base(kScwOff, kSswReady).scw(5, kEnd, kScwOff | kClear), {}},

    // ---- SEW-001: a cause bit without the summary bit (immediate) ----
    {"SEW001 EncoderErr alone", {SEW1}, Script().sew(5, kEnd, kEncoderErr), {now(SEW1, R(5))}},
    {"SEW001 CurrDiffErr (bit 24) alone", {SEW1}, Script().sew(5, kEnd, 1u << 24),
     {now(SEW1, R(5))}},
    {"SEW001 not with the summary", {SEW1}, Script().sew(5, kEnd, kSummary | kEncoderErr), {}},
    {"SEW001 not for reserved bit 4", {SEW1}, Script().sew(5, kEnd, 0x10), {}},

    // ---- SEW-002: the summary bit with no cause longer than drive_response ----
    {"SEW002 summary alone", {SEW2}, Script().base(kScwOff, kSswNone).sew(5, kEnd, kSummary),
     {on(SEW2, M(26), R(5))}},
    {"SEW002 held exactly drive_response", {SEW2},
     Script().base(kScwOff, kSswNone).sew(5, 25, kSummary), {}},
    {"SEW002 cause follows exactly at drive_response", {SEW2},
     Script().base(kScwOff, kSswNone).sew(5, 25, kSummary).sew(25, kEnd, kSummary | kEncoderErr),
     {}},
    {"SEW002 once per episode, again after it ended", {SEW2},
     Script(100).base(kScwOff, kSswNone).sew(5, 40, kSummary).sew(50, kEnd, kSummary),
     {on(SEW2, M(26), R(5)), on(SEW2, M(71), R(50))}},

    // ---- SEW-003: reserved SEW bits (immediate) ----
    {"SEW003 bit 4", {SEW3}, Script().sew(5, kEnd, 0x10), {now(SEW3, R(5))}},
    {"SEW003 bit 25", {SEW3}, Script().sew(5, kEnd, kSummary | (1u << 25)), {now(SEW3, R(5))}},
    {"SEW003 bit 31", {SEW3}, Script().sew(5, kEnd, 0x80000000u), {now(SEW3, R(5))}},
    {"SEW003 not for every defined bit", {SEW3}, Script().sew(5, kEnd, 0x01FFFFEFu), {}},

    // ---- SSW-001 and SCW-001: reserved bits (immediate) ----
    {"SSW001 bit 13", {SSW1}, Script().ssw(5, kEnd, kSswRunning | 0x2000), {now(SSW1, R(5))}},
    {"SSW001 bit 31", {SSW1}, Script().ssw(5, kEnd, kSswRunning | 0x80000000u), {now(SSW1, R(5))}},
    {"SSW001 not for bits 0 to 12", {SSW1}, Script().ssw(5, kEnd, 0x1FFF), {}},
    {"SCW001 bit 13", {SCW1}, Script().scw(5, kEnd, kScwRunning | 0x2000), {now(SCW1, M(5))}},
    {"SCW001 bit 30", {SCW1}, Script().scw(5, kEnd, kScwRunning | 0x40000000u), {now(SCW1, M(5))}},
    {"SCW001 not for PRGDWN (bit 31)", {SCW1}, Script().scw(5, kEnd, kScwRunning | 0x80000000u),
     {}},
    {"SCW001 once per episode, again after it ended", {SCW1},
     Script().scw(5, 15, kScwRunning | 0x2000).scw(20, 25, kScwRunning | 0x2000),
     {now(SCW1, M(5)), now(SCW1, M(20))}},
    {"SCW001 on axis 1 of 2", {SCW1}, Script().axes(2).scw(5, kEnd, kScwRunning | 0x2000, 1),
     {now(SCW1, M(5), 1)}},

    // ---- RDY-001: ServoRDY against the Servo_Ready_Mode table, longer than drive_response ----
    {"RDY001 mode 0 inferred, RDY drops", {RDY1},
     Script().base(kScwOff, kSswReady).ssw(10, kEnd, kSswNone), {on(RDY1, M(31), R(10))},
     "inferred"},
    {"RDY001 held exactly drive_response", {RDY1},
     Script().base(kScwOff, kSswReady).ssw(10, 30, kSswNone), {}},
    {"RDY001 mode 1 inferred, RDY while disabled", {RDY1},
     Script().base(kScwOff, kSswNone).ssw(10, kEnd, kSswReady), {on(RDY1, M(31), R(10))}},
    {"RDY001 mode 1 configured", {RDY1},
     Script().base(kScwOff, kSswReady).settings(readyMode(1)), {on(RDY1, M(21), R(0))},
     "configured"},
    {"RDY001 mode 0, RDY stays 1 in error", {RDY1},
     Script().base(kScwOff, kSswReady).sew(10, kEnd, kSummary | kEncoderErr),
     {on(RDY1, M(31), R(10))}},
    {"RDY001 mode 0, RDY follows the error", {RDY1},
     Script().base(kScwOff, kSswReady).sew(10, kEnd, kSummary | kEncoderErr).ssw(10, kEnd, kSswNone),
     {}},
    {"RDY001 waits while the mode is unknown", {RDY1}, Script().base(kScwRunning, 0x81), {}},
    {"RDY001 per-axis mode", {RDY1},
     Script().axes(2).base(kScwOff, kSswReady).settings([] {
       RuleSettings s = readyMode(0);
       s.axis_ready_mode = {std::nullopt, 1};
       return s;
     }()), {on(RDY1, M(21), R(0), 1)}},

    // ---- FLT-001: enabled while in error longer than fault_reaction ----
    {"FLT001 drive stays enabled", {FLT1}, Script(120).sew(5, kEnd, kSummary | kEncoderErr),
     {on(FLT1, M(106), R(5))}},
    {"FLT001 disabled exactly at fault_reaction", {FLT1},
     Script(120).sew(5, kEnd, kSummary | kEncoderErr).ssw(105, kEnd, kSswNone), {}},
    {"FLT001 disabled at once", {FLT1},
     Script(120).sew(5, kEnd, kSummary | kEncoderErr).ssw(5, kEnd, kSswNone), {}},

    // ---- PT-001: active parameter table differs from the commanded one ----
    {"PT001 table 2 commanded, 1 active", {PT1}, Script().scw(5, kEnd, kScwRunning | 0x10),
     {on(PT1, M(56), M(5))}, "active parameter table 1 differs from the commanded table 2"},
    {"PT001 followed exactly at param_table", {PT1},
     Script().scw(5, kEnd, kScwRunning | 0x10).ssw(55, kEnd, kSswRunning | 0x100), {}},
    {"PT001 ExtPRMTBL: table 5 commanded", {PT1}, Script().scw(5, kEnd, kScwRunning | 0x1000),
     {on(PT1, M(56), M(5))}, "commanded table 5"},
    {"PT001 table 8 followed within the cycle", {PT1},
     Script().scw(5, kEnd, kScwRunning | 0x1030).ssw(5, kEnd, kSswRunning | 0x1300), {}},

    // ---- MSG-001: message code outside 0-5 (immediate) ----
    {"MSG001 code 6", {MSG1}, Script().msg(5, kEnd, 6), {now(MSG1, R(5))}, "message code 6"},
    {"MSG001 code 9", {MSG1}, Script().msg(5, kEnd, 9), {now(MSG1, R(5))}},
    {"MSG001 code -1", {MSG1}, Script().msg(5, kEnd, -1), {now(MSG1, R(5))}},
    {"MSG001 not for codes 0 to 5", {MSG1},
     Script().msg(1, 2, 1).msg(2, 3, 2).msg(3, 4, 3).msg(4, 5, 4).msg(5, kEnd, 5), {}},

    // ---- COM-001: a returned WKC other than 3n (immediate, bus) ----
    {"COM001 WKC 2", {COM1}, Script().wkc(10, 11, 2), {bus(COM1, R(10), R(10))},
     "returned with WKC 2, expected 3"},
    {"COM001 WKC 0", {COM1}, Script().wkc(10, 11, 0), {bus(COM1, R(10), R(10))},
     "(no slave processed it)"},
    {"COM001 once per episode, again after it ended", {COM1},
     Script().wkc(10, 15, 2).wkc(20, 21, 4), {bus(COM1, R(10), R(10)), bus(COM1, R(20), R(20))}},
    {"COM001 two axes expect 6", {COM1}, Script().axes(2).wkc(10, 11, 3),
     {bus(COM1, R(10), R(10))}, "expected 6"},
    {"COM001 not for the expected WKC", {COM1}, Script().axes(2), {}},

    // ---- COM-002: interval between master copies more than 1.5 x the median, judged late or
    // lost at the next master copy ----
    {"COM002 two cycles lost", {COM2}, Script().missing(20, 22), {bus(COM2, M(23), M(19))},
     "2 cycles lost: 3.000 ms from frame 39 to frame 41, then 1.000 ms (1.000 ms nominal)"},
    {"COM002 one outage, one finding; a second outage, another", {COM2},
     Script().missing(20, 21).missing(40, 43),
     {bus(COM2, M(22), M(19)), bus(COM2, M(44), M(39))}},
    {"COM002 the 9th interval is judged", {COM2}, Script().missing(9, 10),
     {bus(COM2, M(11), M(8))}, "1 cycle lost"},
    {"COM002 late: a long interval, then a short one", {COM2},
     Script().time(M(20), kEpochNs + 20 * kMs + 600 * kUs)
         .time(R(20), kEpochNs + 20 * kMs + 610 * kUs),
     {bus(COM2, M(21), M(19))},
     "late cycle: 1.600 ms from frame 39 to frame 41, then 0.400 ms; nothing missing"},
    {"COM002 at the capture's end: late or lost cannot be told", {COM2},
     Script(30).missing(27, 29), {bus(COM2, R(29), M(26))},
     "2 cycles lost: 3.000 ms from frame 53 to frame 55 (1.000 ms nominal); the capture ends "
     "before the next cycle: late or lost cannot be told"},
    {"COM002 before a new segment: late or lost cannot be told", {COM2},
     Script().missing(20, 22).shift(23, 5000 * kMs), {bus(COM2, M(23), M(19))},
     "a capture segment starts before the next cycle: late or lost cannot be told"},
    {"COM002 not before 8 intervals", {COM2}, Script().missing(8, 9), {}},
    {"COM002 not for exactly 1.5 cycles", {COM2},
     Script().time(M(20), kEpochNs + 20 * kMs + 500 * kUs)
         .time(R(20), kEpochNs + 20 * kMs + 500 * kUs), {}},
    {"COM002 just over 1.5 cycles", {COM2},
     Script().time(M(20), kEpochNs + 20 * kMs + 500 * kUs + 1)
         .time(R(20), kEpochNs + 20 * kMs + 500 * kUs + 1),
     {bus(COM2, M(21), M(19))}, "late cycle"},
    {"COM002 on returned copies when no master copy is captured", {COM2},
     Script().noMaster(0, kEnd).missing(20, 23), {bus(COM2, R(24), R(19))}, "3 cycles lost"},
    {"COM002 not for returned copies missing", {COM2}, Script().noReturned(20, 23), {}},

    // ---- COM-006: a master copy's interval deviates more than cycle_jitter_percent ----
    {"COM006 one finding per run of deviating cycles", {COM6},
     Script()
         .time(M(20), kEpochNs + 20 * kMs + 200 * kUs)
         .time(R(20), kEpochNs + 20 * kMs + 210 * kUs)
         .time(M(40), kEpochNs + 40 * kMs - 300 * kUs)
         .time(R(40), kEpochNs + 40 * kMs - 290 * kUs)
         .settings(timingRule("COM-006", "cycle_jitter_percent", 10)),
     {bus(COM6, M(20), M(19)), bus(COM6, M(40), M(39))}, "more than cycle_jitter_percent = 10"},
    {"COM006 off by default", {COM6},
     Script().time(M(20), kEpochNs + 20 * kMs + 200 * kUs)
         .time(R(20), kEpochNs + 20 * kMs + 210 * kUs), {}},
    {"COM006 not for exactly the limit", {COM6},
     Script()
         .time(M(20), kEpochNs + 20 * kMs + 100 * kUs)
         .time(R(20), kEpochNs + 20 * kMs + 110 * kUs)
         .settings(timingRule("COM-006", "cycle_jitter_percent", 10)), {}},
    {"COM006 a gap is COM-002's", {COM6},
     Script().missing(20, 22).settings(timingRule("COM-006", "cycle_jitter_percent", 10)), {}},
    {"COM006 a late cycle is COM-002's, its short interval too", {COM6},
     Script()
         .time(M(20), kEpochNs + 20 * kMs + 600 * kUs)
         .time(R(20), kEpochNs + 20 * kMs + 610 * kUs)
         .settings(timingRule("COM-006", "cycle_jitter_percent", 10)), {}},

    // ---- COM-007: a returned copy later than return_latency_us after its master copy ----
    {"COM007 one finding per run of late returns", {COM7},
     Script()
         .time(R(20), kEpochNs + 20 * kMs + 600 * kUs)
         .time(R(21), kEpochNs + 21 * kMs + 700 * kUs)
         .time(R(30), kEpochNs + 30 * kMs + 501 * kUs)
         .settings(timingRule("COM-007", "return_latency_us", 500)),
     {bus(COM7, R(20), M(20)), bus(COM7, R(30), M(30))}, "more than return_latency_us = 500"},
    {"COM007 off by default", {COM7},
     Script().time(R(20), kEpochNs + 20 * kMs + 600 * kUs), {}},
    {"COM007 not for exactly the limit", {COM7},
     Script().time(R(20), kEpochNs + 20 * kMs + 500 * kUs)
         .settings(timingRule("COM-007", "return_latency_us", 500)), {}},

    // ---- COM-003: 3 or more lost cycles and ECatTErr not raised within drive_response ----
    {"COM003 three returned with WKC 0", {COM3}, Script().wkc(10, 13, 0), {on(COM3, M(34), R(13))},
     "3 consecutive cycles failed"},
    {"COM003 ECatTErr exactly drive_response after traffic resumed", {COM3},
     Script().wkc(10, 13, 0).sew(33, kEnd, kSummary | kEcatTErr), {}},
    {"COM003 ECatTErr one cycle too late", {COM3},
     Script().wkc(10, 13, 0).sew(34, kEnd, kSummary | kEcatTErr), {on(COM3, M(34), R(13))}},
    {"COM003 ECatTErr at once", {COM3},
     Script().wkc(10, 13, 0).sew(13, kEnd, kSummary | kEcatTErr), {}},
    {"COM003 not for two lost cycles", {COM3}, Script().wkc(10, 12, 0), {}},
    {"COM003 not for wrong but non-zero WKCs", {COM3}, Script().wkc(10, 14, 2), {}},
    {"COM003 three not returned", {COM3}, Script().noReturned(10, 13), {on(COM3, M(34), R(13))}},
    {"COM003 three missing from the capture", {COM3}, Script().missing(10, 13),
     {on(COM3, M(34), R(13))}},
    {"COM003 per axis", {COM3}, Script().axes(2).wkc(10, 13, 0).sew(14, kEnd, kSummary | kEcatTErr, 0),
     {on(COM3, M(34), R(13), 1)}},

    // ---- COM-004: a master copy not returned before the next master copy ----
    {"COM004 one not returned", {COM4}, Script().noReturned(10, 11), {bus(COM4, M(11), M(10))},
     "master frame 21"},
    {"COM004 once per episode, again after it ended", {COM4},
     Script().noReturned(10, 13).noReturned(20, 21),
     {bus(COM4, M(11), M(10)), bus(COM4, M(21), M(20))}},
    {"COM004 not in a capture with no returned copies", {COM4}, Script().noReturned(0, kEnd), {}},
    {"COM004 not for the last frame of the capture", {COM4}, Script(60).noReturned(59, 60), {}},

    // ---- COM-005: consecutive failed cycles exceed telegram_failure_limit ----
    {"COM005 four wrong WKCs", {COM5}, Script().wkc(10, 14, 2), {now(COM5, R(13))},
     "4 consecutive telegram failures exceed the limit of 3"},
    {"COM005 not for exactly the limit", {COM5}, Script().wkc(10, 13, 2), {}},
    {"COM005 four lost", {COM5}, Script().wkc(10, 14, 0), {now(COM5, R(13))}},
    {"COM005 once per episode", {COM5}, Script().wkc(10, 20, 2), {now(COM5, R(13))}},
    {"COM005 four not returned", {COM5}, Script().noReturned(10, 14), {now(COM5, M(14))}},
    {"COM005 four missing: the first frame after the gap", {COM5}, Script().missing(20, 24),
     {now(COM5, M(24))}},
    {"COM005 not for three missing", {COM5}, Script().missing(20, 23), {}},
    // docs/rules.md#com-002: from 2.5 cycles on no next interval can make a gap late, so its
    // cycles count at once, on the first frame after it, before any later frame and segment.
    {"COM005 limit 1: two missing, the first frame after the gap", {COM5},
     Script().missing(20, 22).settings(failureLimit(1)), {now(COM5, M(22))}},
    {"COM005 limit 1: two missing, then a new segment", {COM5},
     Script().missing(20, 22).shift(23, 5000 * kMs).settings(failureLimit(1)),
     {now(COM5, M(22))}},
    {"COM005 mixed failures count together", {COM5},
     Script().wkc(10, 11, 2).wkc(11, 12, 0).noReturned(12, 13).wkc(13, 14, 2), {now(COM5, R(13))}},
    {"COM005 limit 5: five failures", {COM5}, Script().wkc(10, 15, 2).settings(failureLimit(5)), {}},
    {"COM005 limit 5: six failures", {COM5}, Script().wkc(10, 16, 2).settings(failureLimit(5)),
     {now(COM5, R(15))}, "limit of 5"},
    {"COM005 every axis of the frame", {COM5}, Script().axes(2).wkc(10, 14, 1),
     {now(COM5, R(13), 0), now(COM5, R(13), 1)}},

    // ---- "Time": first observation, first seen with SE 0x2, timestamps going backwards ----
    {"first seen with SE 0x2 and ServoEn 1 is validly enabled", {SE1, SE2, SE3}, Script(), {}},
    {"first seen with SE 0x2 and ServoEn 0 is a valid enable", {SE1, SE3, SE4},
     Script(120).base(kScwRunning, kSswReady), {on(SE4, M(101), R(0))}},
    {"first seen with ServoEn 1 and SE 0: no edge, but no enable", {SE2, SE3},
     Script().base(kScwOff, kSswRunning), {on(SE3, M(21), R(0))}},
    {"a returned copy's timestamp going backwards within a cycle changes nothing", {SE3, COM2},
     Script().scw(10, kEnd, kScwOff).time(R(15), kEpochNs + 15 * kMs - 500 * kUs),
     {on(SE3, M(31), M(10))}},
    {"a condition beginning on a backwards timestamp starts at the latest time", {SE3},
     Script().scw(10, kEnd, kScwOff).time(M(10), kEpochNs + 9 * kMs - 500 * kUs)
         .time(R(10), kEpochNs + 9 * kMs - 500 * kUs),
     {on(SE3, M(30), M(10))}},

    // ---- "Time": capture discontinuities start a segment, whose timers restart ----
    {"a jump back by more than a cycle: the condition restarts with the segment", {SE3},
     Script(80).scw(10, kEnd, kScwOff).shift(20, -60 * kMs), {on(SE3, M(41), R(20))}},
    {"a jump back: no gap, no failure, the same finding as a capture starting there",
     {SE3, COM2, COM3, COM4, COM5}, Script(80).base(kScwOff, kSswRunning).shift(20, -60 * kMs),
     {on(SE3, M(41), R(20))}},
    {"a pause longer than capture_pause: no gap, no lost cycles", {COM2, COM3, COM4, COM5},
     Script().shift(20, 3'600'000 * kMs), {}},
    {"a pause of capture_pause exactly is a gap", {COM2},
     Script().shift(20, 999 * kMs), {bus(COM2, M(21), M(19))}},
    {"capture_pause 100 ms: a pause of 500 ms starts a segment", {COM2, COM3, COM5},
     Script().shift(20, 500 * kMs).settings(timeoutMs("capture_pause", 100)), {}},
  };
}
// clang-format on

class ValidatorRules : public testing::TestWithParam<RuleCase> {};

TEST_P(ValidatorRules, ReportsExactlyTheExpectedFindings) {
  const RuleCase& c = GetParam();
  const auto driver = runScript(c.script);
  std::vector<std::string> expected, actual;
  for (const Expect& e : c.expected) {
    expected.push_back(
        test::describe(e.rule, e.axis, driver->frameOf(e.at), driver->frameOf(e.since)));
  }
  for (const Finding& f : driver->findings()) {
    if (watched(c, f.rule)) actual.push_back(test::describe(f));
  }
  EXPECT_EQ(actual, expected);
  if (actual != expected) return;
  std::size_t i = 0;
  for (const Finding& f : driver->findings()) {
    if (!watched(c, f.rule)) continue;
    const Expect& e = c.expected[i++];
    SCOPED_TRACE(test::describe(f) + ": " + f.message);
    EXPECT_EQ(f.severity, catalogueSeverity(f.rule));
    EXPECT_EQ(f.at.time_ns, c.script.timeOf(e.at)) << "reported with its frame's own timestamp";
    EXPECT_FALSE(f.message.empty());
    EXPECT_NE(f.message.find(c.message), std::string::npos);
  }
}

INSTANTIATE_TEST_SUITE_P(Validator, ValidatorRules, testing::ValuesIn(ruleCases()),
                         test::rowName<RuleCase>);

// The rows where something is reported, again: disabled, and with another severity.
std::vector<RuleCase> reportingCases() {
  std::vector<RuleCase> out;
  for (RuleCase& c : ruleCases()) {
    if (!c.expected.empty()) out.push_back(std::move(c));
  }
  return out;
}
class ValidatorRuleSettings : public testing::TestWithParam<RuleCase> {};

TEST_P(ValidatorRuleSettings, ADisabledRuleIsNeverReported) {
  const RuleCase& c = GetParam();
  RuleSettings settings = c.script.ruleSettings();
  for (RuleId rule : c.rules) ASSERT_TRUE(settings.disable(ruleDef(rule).code));
  const auto driver = runScript(c.script, settings);
  for (const Finding& f : driver->findings()) {
    EXPECT_FALSE(watched(c, f.rule)) << test::describe(f);
  }
}

TEST_P(ValidatorRuleSettings, ASeverityOverrideChangesTheFindings) {
  const RuleCase& c = GetParam();
  RuleSettings settings = c.script.ruleSettings();
  for (RuleId rule : c.rules) {
    const char* level = catalogueSeverity(rule) == Severity::Info ? "error" : "info";
    ASSERT_TRUE(settings.setSeverity(ruleDef(rule).code, level));
  }
  const auto driver = runScript(c.script, settings);
  std::size_t seen = 0;
  for (const Finding& f : driver->findings()) {
    if (!watched(c, f.rule)) continue;
    ++seen;
    EXPECT_EQ(f.severity,
              catalogueSeverity(f.rule) == Severity::Info ? Severity::Error : Severity::Info);
  }
  EXPECT_EQ(seen, c.expected.size());
}

INSTANTIATE_TEST_SUITE_P(Validator, ValidatorRuleSettings, testing::ValuesIn(reportingCases()),
                         test::rowName<RuleCase>);

// Every rule the default layout can show has a positive and a negative row above.
TEST(ValidatorRuleCoverage, EveryAxisAndBusRuleHasAPositiveAndANegativeRow) {
  std::vector<bool> positive(kRuleCount), negative(kRuleCount);
  for (const RuleCase& c : ruleCases()) {
    for (RuleId rule : c.rules) {
      bool fires = false;
      for (const Expect& e : c.expected) fires = fires || e.rule == rule;
      (fires ? positive : negative)[static_cast<std::size_t>(rule)] = true;
    }
  }
  for (const RuleDef& rule : kRules) {
    // ValidatorEsm below and al_tracker_test; the rules on what slaves say in
    // drive_said_rules_test.
    if (rule.id >= RuleId::Esm001) continue;
    EXPECT_TRUE(positive[static_cast<std::size_t>(rule.id)]) << rule.code;
    EXPECT_TRUE(negative[static_cast<std::size_t>(rule.id)]) << rule.code;
  }
}

// ---- Conforming captures raise nothing ----

// Not a finding (docs/protocol.md §4): a drive fault reported correctly — cause and summary set,
// drive off in 2 ms, errors cleared by the ErrorClear/ErrClearAck handshake — then a legal enable.
Script faultAndRecovery() {
  return Script(200)
      .sew(50, 100, kSummary | kEncoderErr)
      .ssw(50, 52, kSswRunning)
      .ssw(52, 100, kSswNone)
      .scw(50, 100, kScwOff)
      .scw(95, 100, kScwOff | kClear)
      .ssw(97, 100, kClearAck)
      .scw(100, 110, kScwOff)
      .ssw(100, 120, kSswNone)
      .scw(110, 120, kScwArmed)
      .scw(120, kEnd, kScwRunning | 0x10)
      .ssw(120, kEnd, kSswRunning | 0x100);
}

TEST(ValidatorNominal, ConformingCyclesRaiseNoFinding) {
  struct Case {
    const char* name;
    Script script;
  };
  const Case cases[] = {
      {"one axis running", Script(200)},
      {"two axes running", Script(200).axes(2)},
      {"one axis disabled and ready", Script(200).base(kScwOff, kSswReady)},
      {"returned 300 us after the master", Script(200).axes(2).delay(300 * kUs)},
      {"a legal enable, answered", Script(200)
                                       .base(kScwOff, kSswReady)
                                       .scw(10, 20, kScwArmed)
                                       .scw(20, kEnd, kScwRunning)
                                       .ssw(25, kEnd, kSswRunning)},
      {"a fault reported correctly and cleared", faultAndRecovery()},
      {"a constant datagram index", Script(200).axes(2).constantIndex()},
      {"a zero-pulse search, answered", Script(200)
                                            .base(kScwRunning, kSswRunning | kIncremental)
                                            .scw(10, 30, kScwRunning | kZRequest)
                                            .ssw(20, 32, kSswRunning | kIncremental | kZAck)},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const auto driver = runScript(c.script);
    for (const Finding& f : driver->findings())
      ADD_FAILURE() << test::describe(f) << ": " << f.message;
    EXPECT_EQ(driver->validator().cycles(), 200u);
  }
}

TEST(ValidatorNominal, AReportedFaultGoesIntoTheHistoryAndTheTimeline) {
  const auto driver = runScript(faultAndRecovery());
  EXPECT_TRUE(driver->findings().empty());
  const AxisModel* axis = driver->validator().axis(0);
  ASSERT_NE(axis, nullptr);
  ASSERT_EQ(axis->errorHistory().size(), 1u);
  EXPECT_STREQ(axis->errorHistory()[0].cause->display, "E01");
  EXPECT_EQ(axis->errorHistory()[0].cause->canopen, 0x7305);
  EXPECT_EQ(axis->errorHistory()[0].at.frame, driver->frameOf(R(50)));
  struct Change {
    DriveState state;
    std::string transition;
    std::uint64_t frame;
  };
  const std::vector<Change> expected = {
      {DriveState::ControlActive, "", driver->frameOf(R(0))},
      {DriveState::FaultReactionActive, "FAULT REACTION ACTIVE", driver->frameOf(R(50))},
      {DriveState::Error, "FAULT", driver->frameOf(R(52))},
      {DriveState::NotReadyToSwitchOn, "FAULT RESET", driver->frameOf(R(100))},
      {DriveState::ControlActive, "ENABLE OPERATION", driver->frameOf(R(120))},
  };
  ASSERT_EQ(axis->timeline().size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    SCOPED_TRACE(i);
    const StateChange& got = axis->timeline()[i];
    EXPECT_EQ(got.state, expected[i].state);
    EXPECT_EQ(got.transition ? got.transition : "", expected[i].transition);
    EXPECT_EQ(got.at.frame, expected[i].frame);
  }
  EXPECT_EQ(axis->totalFailures(), 0u);
}

// ---- Rule time: timestamps going backwards are not an error ----

// docs/timing.md#rule-time: a timestamp that goes back is no error and moves no timer back (the
// timers keep the latest time). Here every cycle is captured and one master copy carries a
// timestamp 8 ms in the past. The validator puts that master copy at the latest time seen (R(14),
// 14 ms) for its cycle clock, so the next master copy (16 ms) is 2 ms after it: COM-002 reports
// "1 cycle missing" on M(16) and counts a lost cycle for the axis, though no cycle is missing.
// BUG (validator.cpp, Validator::tick): a backwards timestamp turns into a gap finding.
TEST(ValidatorTime, AMasterCopyGoingBackwardsIsNotAGap) {
  const Script script = Script().time(M(15), kEpochNs + 7 * kMs).time(R(15), kEpochNs + 7 * kMs);
  const auto driver = runScript(script);
  for (const Finding& f : driver->findings())
    ADD_FAILURE() << test::describe(f) << ": " << f.message;
}

TEST(ValidatorTime, FindingsCarryTheirFramesOwnTimestamps) {
  // SE-003 begins at M(10) and is reported on M(31): each with its frame's timestamp.
  const Script script = Script().scw(10, kEnd, kScwOff);
  const auto driver = runScript(script);
  ASSERT_EQ(driver->findings().size(), 1u);
  const Finding& f = driver->findings()[0];
  EXPECT_EQ(f.rule, RuleId::Se003);
  EXPECT_EQ(f.at.time_ns, kEpochNs + 31 * kMs);
  EXPECT_EQ(f.since.time_ns, kEpochNs + 10 * kMs);
  EXPECT_EQ(f.since.frame, driver->frameOf(M(10)));
  EXPECT_NE(f.message.find("21.000 ms"), std::string::npos) << f.message;
}

// docs/rules.md#com-002: a late cycle loses nothing; lost cycles count as failures of every axis.
TEST(ValidatorCom002, TheVerdictDecidesTheFailureCount) {
  struct Row {
    const char* name;
    Script script;
    std::uint32_t failures;
  };
  const std::vector<Row> rows = {
      {"late",
       Script()
           .time(M(20), kEpochNs + 20 * kMs + 900 * kUs)
           .time(R(20), kEpochNs + 20 * kMs + 910 * kUs),
       0},
      {"two lost", Script().missing(20, 22), 2},
      {"two lost at the capture's end", Script(30).missing(27, 29), 2},
      {"two lost, then a new segment", Script().missing(20, 22).shift(23, 5000 * kMs), 2},
  };
  for (const Row& row : rows) {
    const auto driver = runScript(row.script);
    const AxisModel* axis = driver->validator().axis(0);
    ASSERT_NE(axis, nullptr) << row.name;
    EXPECT_EQ(axis->totalFailures(), row.failures) << row.name;
  }
}

// ---- COM-002's statistics and COM-003 after mixed outages ----

TEST(ValidatorCycleTime, MedianP99AndMaxOfTheMasterIntervals) {
  const auto driver = runScript(Script(101).missing(50, 52));
  const CycleTimeSummary summary = driver->validator().cycleTime();
  ASSERT_TRUE(summary.median_us && summary.p99_us && summary.max_us);
  EXPECT_DOUBLE_EQ(*summary.median_us, 1000.0);
  EXPECT_DOUBLE_EQ(*summary.max_us, 3000.0);
  EXPECT_EQ(driver->validator().cycles(), 99u);
}

// docs/rules.md#com-003 counts 3 or more failed cycles in a row: missing from the capture, not
// returned, or returned with WKC 0. Below, two lost cycles, then one returned with WKC 2 (a
// wrong WKC, but the drive took its outputs: traffic went through, docs/protocol.md §8), then one
// lost cycle: no 3 consecutive lost cycles, so the drive had no reason to raise ECatTErr.
// BUG (axis_model.cpp, AxisModel::cycleFailed): a failed-but-not-lost cycle does not end the run
// of lost cycles (consecutive_lost_ is only reset by cycleOk), so 2 + 1 lost cycles separated by
// a WKC-2 cycle count as 3 consecutive and COM-003 is reported at M(35).
TEST(ValidatorCom003, LostCyclesSeparatedByAWrongWkcAreNotConsecutive) {
  const auto driver = runScript(Script().wkc(10, 12, 0).wkc(12, 13, 2).wkc(13, 14, 0));
  for (const Finding& f : driver->findings()) {
    EXPECT_NE(f.rule, RuleId::Com003) << test::describe(f) << ": " << f.message;
  }
}

// ---- ESM-002: station-addressed axes (FPWR/FPRD exchange) and AL status reads ----

using test::kStation;
using test::stationAxis;
using test::stationFrame;

struct EsmStep {
  std::int64_t from;  // cycles [from, next step's from)
  std::uint32_t scw;
  std::uint32_t ssw;
  std::optional<std::uint16_t> al;  // AL status read in the cycle, if any
};
struct EsmCase {
  const char* name;
  std::vector<EsmStep> steps;
  std::vector<Expect> expected;  // ESM-002 findings, axis 0
};

std::vector<EsmCase> esmCases() {
  const RuleId E = RuleId::Esm002;
  return {
      {"OP, enabled", {{0, kScwRunning, kSswRunning, 8}}, {}},
      {"SAFE-OP, SE 0x2", {{0, kScwRunning, kSswRunning, 4}}, {now(E, R(0))}},
      {"SAFE-OP, SE 0x1", {{0, kScwArmed, kSswReady, 4}}, {now(E, R(0))}},
      {"SAFE-OP, SE 0, inputs exchanged", {{0, kScwOff, kSswReady, 4}}, {}},
      {"AL state unknown", {{0, kScwRunning, kSswRunning, std::nullopt}}, {}},
      {"start-up: SAFE-OP with SE 0, then OP, then enabled",
       {{0, kScwOff, kSswReady, 4},
        {10, kScwOff, kSswReady, 8},
        {12, kScwArmed, kSswReady, 8},
        {13, kScwRunning, kSswRunning, 8}},
       {}},
      {"falls out of OP while enabled",
       {{0, kScwRunning, kSswRunning, 8}, {20, kScwRunning, kSswRunning, 4}},
       {now(E, R(20))}},
      {"the state stays known between AL status reads",
       {{0, kScwOff, kSswReady, 4},
        {5, kScwOff, kSswReady, std::nullopt},
        {10, kScwRunning, kSswReady, std::nullopt}},
       {now(E, M(10))}},
  };
}

std::unique_ptr<ValidatorDriver> runEsm(const EsmCase& c, std::vector<std::uint64_t>& masters,
                                        std::vector<std::uint64_t>& returns) {
  auto driver = std::make_unique<ValidatorDriver>(RuleSettings{}, stationAxis());
  for (std::int64_t k = 0; k < 40; ++k) {
    const EsmStep* step = &c.steps.front();
    for (const EsmStep& s : c.steps) {
      if (s.from <= k) step = &s;
    }
    for (bool returned : {false, true}) {
      driver->feed(stationFrame(step->scw, step->ssw, step->al, returned), kEpochNs + k * kMs);
      (returned ? returns : masters).push_back(driver->frames());
    }
  }
  return driver;
}

TEST(ValidatorEsm, Esm002PdoOutsideOp) {
  for (const EsmCase& c : esmCases()) {
    SCOPED_TRACE(c.name);
    std::vector<std::uint64_t> masters, returns;
    const auto driver = runEsm(c, masters, returns);
    auto frame = [&](At at) {
      return (at.copy == test::Copy::Master ? masters
                                            : returns)[static_cast<std::size_t>(at.cycle)];
    };
    std::vector<std::string> expected, actual;
    for (const Expect& e : c.expected) {
      expected.push_back(test::describe(e.rule, e.axis, frame(e.at), frame(e.since)));
    }
    for (const Finding& f : driver->findings()) {
      if (f.rule == RuleId::Esm002) actual.push_back(test::describe(f));
      // The cyclic exchange itself is sound: FPWR and FPRD of one slave expect WKC 1.
      EXPECT_NE(f.rule, RuleId::Com001) << f.message;
    }
    EXPECT_EQ(actual, expected);
  }
}

// docs/rules.md#esm-002: inputs exchanged with an axis before SAFE-OP. An axis in PRE-OP whose
// inputs are exchanged every cycle is one lasting condition, reported once
// (docs/timing.md#rule-time). The check (rules.cpp, esm002) looks at whether *this frame* carries
// inputs, so the condition is false on every master copy and true again on every returned copy: the
// episode ends and restarts each cycle and ESM-002 is reported on every returned copy (40 times
// in 40 cycles here), where COM-001's WKC episodes, for instance, last across master copies.
// BUG (rules.cpp esm002 with validator.cpp evaluateAxis): reported once per cycle, not once.
TEST(ValidatorEsm, InputsExchangedInPreOpAreReported) {
  const EsmCase c{"PRE-OP, inputs exchanged", {{0, kScwOff, kSswReady, 2}}, {}};
  std::vector<std::uint64_t> masters, returns;
  const auto driver = runEsm(c, masters, returns);
  ASSERT_FALSE(driver->findings().empty());
  const Finding& f = driver->findings().front();
  EXPECT_EQ(test::describe(f), test::describe(RuleId::Esm002, 0, returns[0], returns[0]));
  EXPECT_NE(f.message.find("expected SAFE-OP or OP"), std::string::npos) << f.message;
}

TEST(ValidatorEsm, InputsExchangedInPreOpAreReportedOnce) {
  const EsmCase c{"PRE-OP, inputs exchanged", {{0, kScwOff, kSswReady, 2}}, {}};
  std::vector<std::uint64_t> masters, returns;
  const auto driver = runEsm(c, masters, returns);
  std::size_t reported = 0;
  for (const Finding& f : driver->findings()) reported += f.rule == RuleId::Esm002 ? 1 : 0;
  EXPECT_EQ(reported, 1u);
}

TEST(ValidatorEsm, AlErrorIsAttributedToTheAxisOfItsStation) {
  ValidatorDriver driver(RuleSettings{}, stationAxis());
  for (std::int64_t k = 0; k < 3; ++k) {
    const std::uint16_t al = k < 2 ? 8 : 0x14;  // OP, then SAFE-OP + error indicator
    driver.feed(stationFrame(kScwOff, kSswReady, al, false), kEpochNs + k * kMs);
    driver.feed(stationFrame(kScwOff, kSswReady, al, true), kEpochNs + k * kMs);
  }
  std::vector<std::string> actual;
  for (const Finding& f : driver.findings()) actual.push_back(test::describe(f));
  EXPECT_EQ(actual, std::vector<std::string>{test::describe(RuleId::Esm003, 0, 6, 6)});
}

// docs/cli.md `telegram_failures`: an axis's total failure counter resets when its slave enters OP,
// whether the AL status read that shows OP shares the cyclic frame or has a frame of its own
// (a master polls AL status in frames of their own, as the simulator's does).
struct OpEntryRow {
  const char* name;
  bool own_frame;  // the OP read in a frame of its own, not in the cyclic frame
  bool enter_op;   // the slave goes SAFE-OP -> OP at all
};

using test::alStatusFrame;

TEST(ValidatorEsm, TotalFailuresResetWhenTheSlaveEntersOp) {
  const OpEntryRow rows[] = {
      {"OP read in the cyclic frame", false, true},
      {"OP read in a frame of its own", true, true},
      {"stays in SAFE-OP: the failures stay counted", true, false},
  };
  for (const OpEntryRow& row : rows) {
    SCOPED_TRACE(row.name);
    ValidatorDriver driver(RuleSettings{}, stationAxis());
    std::int64_t t = kEpochNs;
    // SAFE-OP, outputs off; three cycles not returned (a master copy with no returned copy;
    // docs/protocol.md §8 takes a master copy after one with the same datagrams as its returned
    // copy with WKC 0, so this counts fewer than three failures, but some).
    for (std::int64_t k = 0; k < 10; ++k, t += kMs) {
      driver.feed(stationFrame(kScwOff, kSswReady, 4, false), t);
      if (k < 3 || k > 5) driver.feed(stationFrame(kScwOff, kSswReady, 4, true), t + 20 * kUs);
    }
    const AxisModel* axis = driver.validator().axis(0);
    ASSERT_NE(axis, nullptr);
    const std::uint32_t failures = axis->totalFailures();
    ASSERT_GT(failures, 0u);
    const std::uint16_t next = row.enter_op ? 8 : 4;
    if (row.own_frame) {
      driver.feed(alStatusFrame(next, false), t);
      driver.feed(alStatusFrame(next, true), t + 10 * kUs);
      t += kMs;
    }
    for (std::int64_t k = 0; k < 5; ++k, t += kMs) {
      std::optional<std::uint16_t> al;  // the AL status read in the cyclic frame
      if (!row.own_frame) al = next;
      driver.feed(stationFrame(kScwOff, kSswReady, al, false), t);
      driver.feed(stationFrame(kScwOff, kSswReady, al, true), t + 20 * kUs);
    }
    EXPECT_EQ(driver.validator().axis(0)->totalFailures(), row.enter_op ? 0u : failures);
  }
}

// The validator reads each frame's placements and values itself, in one pass with its judging:
// its view must be what a Session gives for the same frames (placements, values, copy), and each
// axis's state its model's. One row per frame, fed in order to both.
struct ViewRow {
  const char* name;
  std::vector<Dg> datagrams;
  std::size_t cut = 0;  // bytes cut off the end of the captured frame
};

std::vector<ViewRow> viewRows() {
  using test::concat;
  using test::rxPdo;
  using test::txPdo;
  const auto lrw = [](std::uint32_t scw, std::optional<std::uint32_t> ssw, std::uint16_t wkc) {
    Bytes data = concat({rxPdo(100, scw), rxPdo(101, scw)});
    for (std::int64_t k = 0; k < 2; ++k) {
      data = concat({data, ssw ? txPdo({1000 + k, *ssw}) : Bytes(40, 0)});
    }
    return Dg{ecat::kLrw, 0x80, 0x00010000, data, wkc};
  };
  const Dg dc{ecat::kFrmw, 1, physical(0x1001, 0x0910), Bytes(8, 0), 0};
  const Dg dc_back{ecat::kFrmw, 1, physical(0x1001, 0x0910), Bytes(8, 0), 1};
  const Dg lwr{ecat::kLwr, 2, 0x00020000, concat({rxPdo(7, 0x1), rxPdo(8, 0x1), rxPdo(9, 0x1)}), 0};
  const Dg lrd{ecat::kLrd, 3, 0x00030000, Bytes(120, 0), 0};
  Dg lwr_back = lwr;
  lwr_back.wkc = 3;
  Bytes inputs;
  for (std::int64_t k = 0; k < 3; ++k) inputs = concat({inputs, txPdo({k, 0x2})});
  const Dg lrd_back{ecat::kLrd, 3, 0x00030000, inputs, 3};
  return {
      {"master, 2 axes", {lrw(kScwRunning, std::nullopt, 0), dc}},
      {"returned, 2 axes", {lrw(kScwRunning, kSswRunning, 6), dc_back}},
      {"master again: cached placements", {lrw(kScwRunning, std::nullopt, 0), dc}},
      {"returned, words unchanged", {lrw(kScwRunning, kSswRunning, 6), dc_back}},
      {"master, SCW changed", {lrw(0x402, std::nullopt, 0), dc}},
      {"returned, SSW changed", {lrw(0x402, 0x2, 6), dc_back}},
      {"returned with WKC 0: outputs only", {lrw(0x402, std::nullopt, 0), dc_back}},
      {"returned, cut inside the second TxPDO", {lrw(0x402, 0x2, 6)}, 18},
      {"returned, cut inside the first RxPDO", {lrw(0x402, 0x2, 6)}, 98},
      {"master, LWR and LRD of 3 more axes", {lwr, lrd}},
      {"returned, LWR and LRD", {lwr_back, lrd_back}},
      {"no servo: the DC time alone", {dc_back}},
      {"returned, 2 axes again", {lrw(kScwRunning, kSswRunning, 6), dc_back}},
  };
}

TEST(ValidatorView, SameAsSessionFrameByFrame) {
  // The rows' outputs-first layouts: 2 axes in the LRW, 3 in the LWR and LRD.
  DecoderOptions layout = test::inferredDefault(2);
  test::appendDefaultAxes(layout, 3, 0x00020000, 0x00030000);
  Validator validator(layout, RuleSettings{});
  Session session(layout);
  std::uint64_t frame = 0;
  std::size_t axes_seen = 0;
  for (const ViewRow& row : viewRows()) {
    SCOPED_TRACE(row.name);
    FrameBuilder builder;
    for (const Dg& dg : row.datagrams) builder.add(dg);
    const Bytes bytes = builder.bytes();
    ASSERT_LT(row.cut, bytes.size());
    const test::Walked w = test::walk(bytes, bytes.size() - row.cut);
    ++frame;
    const Observation& got = validator.onFrame(
        frame, kEpochNs + static_cast<std::int64_t>(frame) * kMs, *w.frame, w.reader());
    const FrameView& want = session.onFrame(*w.frame, w.reader());
    EXPECT_EQ(got.decode.copy, want.copy);
    EXPECT_EQ(got.decode.paired, want.paired);
    ASSERT_EQ(got.decode.axis_count, want.axis_count);
    axes_seen += got.decode.axis_count;
    bool any_malformed = false;
    for (std::size_t i = 0; i < got.decode.axis_count; ++i) {
      SCOPED_TRACE("axis slot " + std::to_string(i));
      const AxisPlacement& g = got.decode.axes[i];
      const AxisPlacement& e = want.axes[i].placement;
      EXPECT_EQ(g.axis, e.axis);
      EXPECT_EQ(g.rx_placed, e.rx_placed);
      EXPECT_EQ(g.tx_placed, e.tx_placed);
      EXPECT_EQ(g.has_rx, e.has_rx);
      EXPECT_EQ(g.has_tx, e.has_tx);
      EXPECT_EQ(g.rx_malformed, e.rx_malformed);
      EXPECT_EQ(g.tx_malformed, e.tx_malformed);
      EXPECT_EQ(g.rx_datagram, e.rx_datagram);
      EXPECT_EQ(g.tx_datagram, e.tx_datagram);
      EXPECT_EQ(g.rx_offset, e.rx_offset);
      EXPECT_EQ(g.tx_offset, e.tx_offset);
      any_malformed = any_malformed || g.rx_malformed || g.tx_malformed;
      // The values at the validator's placements are the session's.
      PdoValues values;
      readFrameValues(g, w.reader(), values);
      EXPECT_EQ(values.has_rx, want.axes[i].values.has_rx);
      EXPECT_EQ(values.has_tx, want.axes[i].values.has_tx);
      EXPECT_EQ(values.raw, want.axes[i].values.raw);
      const AxisModel* model = validator.axis(g.axis);
      ASSERT_NE(model, nullptr);
      EXPECT_EQ(got.states[i], model->state());
    }
    EXPECT_EQ(got.decode.any_malformed, any_malformed);
  }
  EXPECT_GT(axes_seen, 20u) << "the rows must place axes";
}

}  // namespace
}  // namespace ncservo
