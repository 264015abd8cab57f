// The rule table (docs/rules.md) and the conditions of the axis rules. Each check reads the axis
// model's state only; the validator owns timing and the once-per-episode discipline.
#include "ncservo/rules/rules.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

#include "ncservo/base/text.hpp"
#include "ncservo/model/al_tracker.hpp"
#include "ncservo/model/axis_model.hpp"
#include "ncservo/model/esc_errors.hpp"
#include "ncservo/protocol/fields.hpp"
#include "ncservo/protocol/word_bits.hpp"
#include "ncservo/wire/diagnosis_texts.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo {

namespace {
using namespace bits;

double heldMs(std::int64_t held_ns) {
  return static_cast<double>(held_ns) / 1e6;
}
bool longerThan(const AxisModel& a, const Stamp& since, std::int64_t ns) {
  return a.now().time_ns - since.time_ns > ns;
}

std::uint32_t commandedTable(const AxisModel& a) {
  return parameterTable(Word::Scw, a.latest().scw());
}
std::uint32_t activeTable(const AxisModel& a) {
  return parameterTable(Word::Ssw, a.latest().ssw());
}

bool driveReady(const AxisModel& a) {
  if (!a.readyMode()) return false;
  return *a.readyMode() == 0 ? a.servoRdy().on() : a.servoErrors().off();
}

// --- Servo enable (docs/protocol.md §2) ---
bool se001(const AxisModel& a, const RuleContext&) {
  return a.illegalEnableEdge();
}
std::string se001Text(const AxisModel& a, const RuleContext&, std::int64_t) {
  return fmt::format("SCW.SE went 0x{:X} -> 0x2; an enable is legal only from 0x1", a.previousSe());
}

// A valid enable now, or one that ended within the row's timeout.
bool recentlyEnabled(const AxisModel& a, const RuleContext& c) {
  if (a.validEnable()) return true;
  const auto& ended = a.validEnableEnded();
  return ended && !longerThan(a, *ended, c.timeoutNs());
}
bool se002(const AxisModel& a, const RuleContext& c) {
  return a.servoEn().rose && !recentlyEnabled(a, c);
}
std::string se002Text(const AxisModel& a, const RuleContext& c, std::int64_t) {
  return fmt::format(
      "SSW.ServoEn rose with no valid enable within {} ms (SCW.SE is 0x{:X}); the drive may "
      "enable only after SE goes 0x1 -> 0x2",
      c.timeoutMs(), a.se().value);
}

bool se003(const AxisModel& a, const RuleContext&) {
  return a.servoEn().on() && !a.validEnable();
}
std::string se003Text(const AxisModel& a, const RuleContext& c, std::int64_t held) {
  return fmt::format("SSW.ServoEn still 1 {:.3f} ms {} (SCW.SE is 0x{:X}); expected 0 within {} ms",
                     heldMs(held),
                     a.validEnableEnded() ? "after the enable ended" : "with no valid enable",
                     a.se().value, c.timeoutMs());
}

bool se004(const AxisModel& a, const RuleContext&) {
  return a.validEnable() && driveReady(a) && a.emgon().on() && a.brake().on() && a.servoEn().off();
}
std::string se004Text(const AxisModel&, const RuleContext& c, std::int64_t held) {
  return fmt::format(
      "valid enable held {:.3f} ms with the drive ready, EMGON 1 and Brake 1, but SSW.ServoEn "
      "stays 0; expected it within {} ms",
      heldMs(held), c.timeoutMs());
}

// --- Zero-pulse search ---
bool zp001(const AxisModel& a, const RuleContext&) {
  return a.zpulseRequest().off() && a.zpulseAck().on();
}
std::string zp001Text(const AxisModel&, const RuleContext& c, std::int64_t held) {
  return fmt::format(
      "SSW.ZPulseAck still 1 {:.3f} ms after SCW.ZPulseRequest fell; expected 0 within {} ms",
      heldMs(held), c.timeoutMs());
}

bool zp002(const AxisModel& a, const RuleContext& c) {
  return a.zpulseAck().rose && a.zpulseRequest().off() &&
         longerThan(a, a.zpulseRequest().since, c.timeoutNs());
}
std::string zp002Text(const AxisModel& a, const RuleContext&, std::int64_t) {
  return fmt::format(
      "SSW.ZPulseAck rose while SCW.ZPulseRequest had been 0 for {:.3f} ms (since frame {}); "
      "an acknowledge answers a request",
      heldMs(a.now().time_ns - a.zpulseRequest().since.time_ns), a.zpulseRequest().since.frame);
}

bool zp003(const AxisModel& a, const RuleContext&) {
  if (!a.zpulseRequest().on() || !a.knowsInputs()) return false;
  const std::uint32_t ssw = a.latest().ssw();
  return !(ssw & kIncremental) || (ssw & kNoEncoder);
}
std::string zp003Text(const AxisModel& a, const RuleContext&, std::int64_t) {
  return fmt::format(
      "SCW.ZPulseRequest is 1 but SSW says {}; a zero-pulse search needs an "
      "incremental encoder",
      (a.latest().ssw() & kNoEncoder) ? "no encoder" : "absolute encoder");
}

// --- Error clear ---
bool ec001(const AxisModel& a, const RuleContext& c) {
  return a.errClearAck().rose && a.errorClear().off() &&
         longerThan(a, a.errorClear().since, c.timeoutNs());
}
std::string ec001Text(const AxisModel& a, const RuleContext&, std::int64_t) {
  return fmt::format(
      "SSW.ErrClearAck rose while SCW.ErrorClear had been 0 for {:.3f} ms (since frame {}); "
      "an acknowledge answers a request",
      heldMs(a.now().time_ns - a.errorClear().since.time_ns), a.errorClear().since.frame);
}

bool ec002(const AxisModel& a, const RuleContext&) {
  return a.errorClear().on() && a.clearAcknowledged();
}
std::string ec002Text(const AxisModel&, const RuleContext& c, std::int64_t held) {
  return fmt::format(
      "SCW.ErrorClear still 1 {:.3f} ms after SSW.ErrClearAck rose; the NC must drop it within "
      "{} ms",
      heldMs(held), c.timeoutMs());
}

bool ec003(const AxisModel& a, const RuleContext&) {
  return a.errClearAck().on() && a.errorClear().off();
}
std::string ec003Text(const AxisModel&, const RuleContext& c, std::int64_t held) {
  return fmt::format(
      "SSW.ErrClearAck still 1 {:.3f} ms after SCW.ErrorClear fell; expected 0 within {} ms",
      heldMs(held), c.timeoutMs());
}

bool ec004(const AxisModel& a, const RuleContext&) {
  return a.errorClear().on() && a.servoErrors().on() && !a.clearAcknowledged();
}
std::string ec004Text(const AxisModel& a, const RuleContext& c, std::int64_t held) {
  return fmt::format(
      "SCW.ErrorClear held {:.3f} ms with SEW 0x{:08X} and no SSW.ErrClearAck; expected the "
      "acknowledge within {} ms",
      heldMs(held), a.latest().sew(), c.timeoutMs());
}

// --- Status and error words ---
bool sew001(const AxisModel& a, const RuleContext&) {
  const std::uint32_t sew = a.latest().sew();
  return a.knowsInputs() && (sew & kSewCauseMask) && !(sew & kServoErrors);
}
std::string sew001Text(const AxisModel& a, const RuleContext&, std::int64_t) {
  return fmt::format("SEW 0x{:08X} has cause bits set but not the summary bit 0", a.latest().sew());
}

bool sew002(const AxisModel& a, const RuleContext&) {
  const std::uint32_t sew = a.latest().sew();
  return a.knowsInputs() && (sew & kServoErrors) && !(sew & kSewCauseMask);
}
std::string sew002Text(const AxisModel& a, const RuleContext& c, std::int64_t held) {
  return fmt::format("SEW 0x{:08X}: summary bit set with no cause bit for {:.3f} ms (limit {} ms)",
                     a.latest().sew(), heldMs(held), c.timeoutMs());
}

bool sew003(const AxisModel& a, const RuleContext&) {
  return a.knowsInputs() && (a.latest().sew() & kSewReserved);
}
std::string sew003Text(const AxisModel& a, const RuleContext&, std::int64_t) {
  return fmt::format("SEW 0x{:08X} sets reserved bits 0x{:08X}; they must be 0", a.latest().sew(),
                     a.latest().sew() & kSewReserved);
}

bool ssw001(const AxisModel& a, const RuleContext&) {
  return a.knowsInputs() && (a.latest().ssw() & kSswReserved);
}
std::string ssw001Text(const AxisModel& a, const RuleContext&, std::int64_t) {
  return fmt::format("SSW 0x{:08X} sets reserved bits 0x{:08X}; they must be 0", a.latest().ssw(),
                     a.latest().ssw() & kSswReserved);
}

bool scw001(const AxisModel& a, const RuleContext&) {
  return a.knowsOutputs() && (a.latest().scw() & kScwReserved);
}
std::string scw001Text(const AxisModel& a, const RuleContext&, std::int64_t) {
  return fmt::format("SCW 0x{:08X} sets reserved bits 0x{:08X}; they must be 0", a.latest().scw(),
                     a.latest().scw() & kScwReserved);
}

bool rdy001(const AxisModel& a, const RuleContext&) {
  const std::optional<bool> expected = a.expectedReady();
  return expected && a.servoRdy().on() != *expected;
}
std::string rdy001Text(const AxisModel& a, const RuleContext& c, std::int64_t held) {
  return fmt::format(
      "SSW.ServoRDY is {} for {:.3f} ms with ServoEn {} and ServoErrors {}; Servo_Ready_Mode {} "
      "({}) requires {} (limit {} ms)",
      a.servoRdy().on() ? 1 : 0, heldMs(held), a.servoEn().on() ? 1 : 0,
      a.servoErrors().on() ? 1 : 0, a.readyMode().value_or(-1),
      a.readyModeConfigured() ? "configured" : "inferred",
      a.expectedReady().value_or(false) ? 1 : 0, c.timeoutMs());
}

bool flt001(const AxisModel& a, const RuleContext&) {
  return a.servoEn().on() && a.servoErrors().on();
}
std::string flt001Text(const AxisModel& a, const RuleContext& c, std::int64_t held) {
  return fmt::format(
      "drive still enabled {:.3f} ms after reporting an error (SEW 0x{:08X}); expected ServoEn 0 "
      "within {} ms",
      heldMs(held), a.latest().sew(), c.timeoutMs());
}

bool pt001(const AxisModel& a, const RuleContext&) {
  return a.knowsOutputs() && a.knowsInputs() && commandedTable(a) != activeTable(a);
}
std::string pt001Text(const AxisModel& a, const RuleContext& c, std::int64_t held) {
  return fmt::format(
      "active parameter table {} differs from the commanded table {} for {:.3f} ms (limit {} ms)",
      activeTable(a), commandedTable(a), heldMs(held), c.timeoutMs());
}

bool definedMessageCode(std::uint64_t raw) {
  return messageCodeDefined(static_cast<std::int32_t>(raw));
}
bool msg001(const AxisModel& a, const RuleContext&) {
  const std::int32_t code = a.latest().msgCode();
  return a.knowsInputs() && !messageCodeDefined(code);
}
std::string msg001Text(const AxisModel& a, const RuleContext&, std::int64_t) {
  const std::int32_t code = a.latest().msgCode();
  const bool listed = code >= 0 && static_cast<std::uint32_t>(code) <= kLastListedMessageCode;
  return fmt::format("message code {} is {}; defined codes are 0-{}", code,
                     listed ? "listed without a meaning" : "undefined", kLastDefinedMessageCode);
}
// MSG-001's summary names the ranges of fields.hpp.
static_assert(kLastDefinedMessageCode == 5 && kLastListedMessageCode == 9);

// --- Bus, per axis ---
// Judged only on inputs the capture gave: ECatTErr may have risen in inputs it cut off.
bool com003(const AxisModel& a, const RuleContext&) {
  return a.unansweredOutageCycles() >= kEcatTimeoutCycles && a.knowsInputs();
}
// COM-003's summary names the count.
static_assert(kEcatTimeoutCycles == 3);
std::string com003Text(const AxisModel& a, const RuleContext& c, std::int64_t) {
  return fmt::format(
      "{} consecutive cycles failed, but SEW.ECatTErr did not rise within {} ms after traffic "
      "resumed",
      a.unansweredOutageCycles(), c.timeoutMs());
}

bool com005(const AxisModel& a, const RuleContext& c) {
  return a.consecutiveFailed() > c.settings.telegram_failure_limit;
}
std::string com005Text(const AxisModel& a, const RuleContext& c, std::int64_t) {
  return fmt::format("{} consecutive telegram failures exceed the limit of {} (total {})",
                     a.consecutiveFailed(), c.settings.telegram_failure_limit, a.totalFailures());
}

// --- EtherCAT state machine, per axis (docs/protocol.md §8) ---
using ecat::kAlOp;
bool esm002(const AxisModel& a, const RuleContext&) {
  if (!a.alState()) return false;
  const std::uint8_t state = *a.alState();
  const bool enabling = a.knowsOutputs() && a.se().value != 0 && state != kAlOp;
  const bool inputs = a.inputsInAlState() && !ecat::exchangesInputs(state);
  return enabling || inputs;
}
std::string esm002Text(const AxisModel& a, const RuleContext&, std::int64_t) {
  const std::uint8_t state = a.alState().value_or(0);
  if (a.knowsOutputs() && a.se().value != 0 && state != kAlOp) {
    return fmt::format("SCW.SE is 0x{:X} while the slave's AL state is {:#x}; enable only in OP",
                       a.se().value, state);
  }
  return fmt::format("inputs exchanged while the slave's AL state is {:#x}; expected SAFE-OP or OP",
                     state);
}

// --- Bus (docs/protocol.md §8; docs/rules.md#com-001, COM-002, COM-004) ---
bool com001(const WorkingCounterEvent& e, const RuleContext&) {
  return e.wkc != e.expected;
}
std::string com001Text(const WorkingCounterEvent& e, const Stamp&, const RuleContext&) {
  return fmt::format("{} at 0x{:08X} ({} bytes) returned with WKC {}, expected {}{}",
                     ecat::commandName(e.command), e.address, e.length, e.wkc, e.expected,
                     e.wkc == 0 ? " (no slave processed it)" : "; inputs may be stale");
}

bool com002(const CycleGapEvent&, const RuleContext&) {
  return true;  // the bus model reports an interval only when it is a gap
}
std::string com002Text(const CycleGapEvent& e, const Stamp&, const RuleContext&) {
  using Verdict = CycleGapEvent::Verdict;
  // One buffer: a failing bus reports a gap every few cycles.
  fmt::memory_buffer text;
  auto out = std::back_inserter(text);
  const bool late = e.verdict == Verdict::Late;
  if (late) {
    fmt::format_to(out, "late cycle: ");
  } else {
    fmt::format_to(out, "{} cycle{} lost: ", e.missing, e.missing == 1 ? "" : "s");
  }
  fmt::format_to(out, "{:.3f} ms from frame {} to frame {}",
                 static_cast<double>(e.interval_ns) / 1e6, e.previous_frame, e.next_frame);
  if (e.next_interval_ns) {
    fmt::format_to(out, ", then {:.3f} ms", static_cast<double>(*e.next_interval_ns) / 1e6);
  }
  if (late) fmt::format_to(out, "; nothing missing");
  fmt::format_to(out, " ({:.3f} ms nominal)", static_cast<double>(e.nominal_ns) / 1e6);
  if (e.verdict == Verdict::CaptureEnds) {
    fmt::format_to(out, "; the capture ends before the next cycle: late or lost cannot be told");
  } else if (e.verdict == Verdict::SegmentEnds) {
    fmt::format_to(out,
                   "; a capture segment starts before the next cycle: late or lost cannot be told");
  }
  return fmt::to_string(text);
}

// COM-006: one finding per run of deviating cycles. A gap deviates too but is COM-002's: it
// starts a run without a finding, so a late cycle's short interval after it is not reported.
bool com006(const CycleIntervalEvent& e, const RuleContext& c, bool& in_run) {
  const std::int64_t deviation =
      e.interval_ns > e.nominal_ns ? e.interval_ns - e.nominal_ns : e.nominal_ns - e.interval_ns;
  const bool deviates = deviation * 100 > e.nominal_ns * std::int64_t{c.limit()};
  const bool begins = deviates && !e.gap && !in_run;
  in_run = deviates;
  return begins;
}
std::string com006Text(const CycleIntervalEvent& e, const Stamp&, const RuleContext& c) {
  const double deviation = static_cast<double>(e.interval_ns - e.nominal_ns) / 1e3;
  return fmt::format(
      "cycle of {:.3f} ms since frame {} deviates {:+.1f} us from the {:.3f} ms nominal, more "
      "than cycle_jitter_percent = {}",
      static_cast<double>(e.interval_ns) / 1e6, e.previous_frame, deviation,
      static_cast<double>(e.nominal_ns) / 1e6, c.limit());
}

// COM-007: one finding per run of late returns.
bool com007(const ReturnLatencyEvent& e, const RuleContext& c, bool& in_run) {
  const bool late = e.latency_ns > std::int64_t{c.limit()} * 1000;
  const bool begins = late && !in_run;
  in_run = late;
  return begins;
}
std::string com007Text(const ReturnLatencyEvent& e, const Stamp&, const RuleContext& c) {
  return fmt::format(
      "returned {:.1f} us after its master copy (frame {}), more than "
      "return_latency_us = {}",
      static_cast<double>(e.latency_ns) / 1e3, e.master_frame, c.limit());
}

bool com004(const NotReturnedEvent&, const RuleContext&) {
  return true;
}
std::string com004Text(const NotReturnedEvent& e, const Stamp&, const RuleContext&) {
  // One buffer: a lossy ring reports this every few cycles.
  fmt::memory_buffer text;
  auto out = std::back_inserter(text);
  fmt::format_to(out, "the master frame {} (", e.master_frame);
  if (e.axes) {
    fmt::format_to(out, "axes {}-{}", e.axes->first, e.axes->last);
  } else {
    fmt::format_to(out, "{} at 0x{:08X}, {} byte{}", ecat::commandName(e.command), e.address,
                   e.length, e.length == 1 ? "" : "s");
    const int more = e.datagrams - 1;
    if (more > 0) {
      fmt::format_to(out, ", and {} more datagram{}", more, more == 1 ? "" : "s");
    }
  }
  fmt::format_to(out, ") was not returned before the next cycle's master frame");
  return fmt::to_string(text);
}

// --- EtherCAT state machine, per slave (docs/protocol.md §8) ---
std::string allowedFrom(std::uint8_t from) {
  std::string out;
  for (std::uint8_t to : ecat::kAlStates) {
    if (!alTransitionAllowed(from, to)) continue;
    if (!out.empty()) out += ", ";
    out += alStateName(to);
  }
  return out;
}

bool esm001(const AlControlEvent& e, const RuleContext&) {
  return !alTransitionAllowed(e.known_state, e.requested);
}
std::string esm001Text(const AlControlEvent& e, const Stamp&, const RuleContext&) {
  return fmt::format("{}: AL control 0x{:04X} requests {} from known state {}; allowed: {}",
                     slaveName(e.slave), e.raw, alStateName(e.requested),
                     alStateName(e.known_state), allowedFrom(e.known_state));
}

// docs/rules.md#esm-003, #esm-004: judged on the requested state, or with none the previous one.
bool errorAboveInit(const AlErrorEvent& e) {
  const std::optional<std::uint8_t> reference = e.requested ? e.requested : e.previous;
  return reference && alStateAboveInit(*reference);
}
bool esm003(const AlErrorEvent& e, const RuleContext&) {
  return errorAboveInit(e);
}
bool esm004(const AlErrorEvent& e, const RuleContext&) {
  return !errorAboveInit(e);
}
std::string alErrorText(const AlErrorEvent& e, const Stamp& at, const RuleContext&) {
  std::string context;
  if (e.requested) {
    context = fmt::format("while {} requested", alStateName(*e.requested));
  } else if (e.previous) {
    context = fmt::format("with no request seen, previous state {}", alStateName(*e.previous));
  } else {
    context = "with no request seen and no previous state";
  }
  std::string code = "; AL status code not read";
  if (e.status_code) {
    const diag::AlCodeDef* known = diag::alStatusCode(*e.status_code);
    code = fmt::format("; AL status code 0x{:04X} ({}{})", *e.status_code,
                       known != nullptr ? known->text : "a code ETG.1000.6 does not list",
                       e.status_code_frame != at.frame
                           ? fmt::format(", read in frame {}", e.status_code_frame)
                           : std::string{});
  }
  return fmt::format("{}: AL status 0x{:04X} ({} + error) {}{}", slaveName(e.slave), e.raw,
                     alStateName(e.raw & 0x0F), context, code);
}

// --- What the drives and the ESCs say themselves (docs/drive-messages.md) ---
bool mbx003(const SdoAbortEvent& e, const RuleContext&) {
  return !e.expected;
}
std::string mbx003Text(const SdoAbortEvent& e, const Stamp&, const RuleContext&) {
  const char* object = diag::objectName(e.index);
  const char* why = diag::abortText(e.code);
  return fmt::format(
      "{}: SDO {:04X}h:{:02X}{} aborted with 0x{:08X} ({}){}", slaveName(e.slave), e.index,
      e.subindex, object ? fmt::format(" ({})", object) : std::string{}, e.code,
      why ? why : "a code CiA 301 does not list",
      e.request_frame ? fmt::format(", the request in frame {}", *e.request_frame) : std::string{});
}

// --- The drive's own words against its SEW (docs/drive-messages.md#the-rules) ---
std::string codeText(std::uint16_t code) {
  const char* text = diag::errorCodeText(code);
  return fmt::format("0x{:04X} ({})", code,
                     text != nullptr ? text : "a code CiA 301 does not list");
}
// "E09 FollowerErr (0x8611)", for each SEW cause bit in `causes`.
std::string causesText(std::uint32_t causes) {
  std::string out;
  for (const SewCause& cause : kSewCauses) {
    if (!(causes & cause.mask)) continue;
    out +=
        fmt::format("{}{} (0x{:04X})", out.empty() ? "" : ", ", sewCauseText(cause), cause.canopen);
  }
  return out;
}
// ", the nearest 25.000 ms before it (frame 12)": where the nearest answers came, if any.
std::string nearestText(const Answered& e, const char* what) {
  std::string out;
  if (e.before) {
    out += fmt::format("; the last {} {:.3f} ms before it (frame {})", what,
                       heldMs(e.at->time_ns - e.before->time_ns), e.before->frame);
  }
  if (e.after) {
    out += fmt::format("; the next {} {:.3f} ms after it (frame {})", what,
                       heldMs(e.after->time_ns - e.at->time_ns), e.after->frame);
  }
  return out;
}

bool mbx001(const AxisModel& a, const RuleContext& c) {
  return a.emergencies().at && !a.emergencies().within(c.timeoutNs());
}
std::optional<Stamp> mbx001Began(const AxisModel& a) {
  return a.emergencies().at;
}
std::string mbx001Text(const AxisModel& a, const RuleContext& c, std::int64_t) {
  return fmt::format(
      "the drive sent emergency {}, but no SEW cause bit rose within {} ms before "
      "or after it{}",
      codeText(a.emergencyCode()), c.timeoutMs(), nearestText(a.emergencies(), "rose"));
}

// A drive that reports faults with emergencies: it sent one before this fault.
bool mbx002(const AxisModel& a, const RuleContext& c) {
  const Answered& f = a.faults();
  const std::optional<Stamp>& first = a.firstEmergency();
  return f.at && first && first->frame < f.at->frame && !f.within(c.timeoutNs());
}
std::optional<Stamp> mbx002Began(const AxisModel& a) {
  return a.faults().at;
}
std::string mbx002Text(const AxisModel& a, const RuleContext& c, std::int64_t) {
  return fmt::format(
      "SEW {} rose, but the drive, which sent an emergency in frame {}, sent none within {} ms "
      "before or after it{}",
      causesText(a.faultCauses()), a.firstEmergency().value_or(Stamp{}).frame, c.timeoutMs(),
      nearestText(a.faults(), "came"));
}

// docs/protocol.md §7: the code this project maps the fault's cause bits to.
bool faultRaised(const AxisModel& a, std::uint16_t code) {
  for (const SewCause& cause : kSewCauses) {
    if ((a.faultCauses() & cause.mask) && cause.canopen == code) return true;
  }
  return false;
}
bool erh002(const AxisModel& a, const RuleContext&) {
  const std::optional<HistoryRead>& read = a.historyRead();
  return read && !faultRaised(a, diag::errorFieldEntry(read->value).code);
}
std::optional<Stamp> erh002Began(const AxisModel& a) {
  const std::optional<HistoryRead>& read = a.historyRead();
  return read ? std::optional<Stamp>{read->at} : std::nullopt;
}
std::string erh002Text(const AxisModel& a, const RuleContext&, std::int64_t) {
  const HistoryRead read = a.historyRead().value_or(HistoryRead{});
  return fmt::format(
      "1003h:01 read 0x{:08X}, code {}, after the fault in frame {} raised SEW {} "
      "(docs/protocol.md §7's codes)",
      read.value, codeText(diag::errorFieldEntry(read.value).code),
      a.faults().at.value_or(Stamp{}).frame, causesText(a.faultCauses()));
}

bool erh001(const ErrorHistoryShrunkEvent&, const RuleContext&) {
  return true;
}
std::string erh001Text(const ErrorHistoryShrunkEvent& e, const Stamp&, const RuleContext&) {
  return fmt::format(
      "{}: error history 1003h:00 read {}, {} in frame {}, and no write of 0 cleared it between",
      slaveName(e.slave), e.now, e.before, e.before_frame);
}

bool lnk001(const LinkErrorEvent& e, const RuleContext&) {
  return !e.lost;
}
bool lnk002(const LinkErrorEvent& e, const RuleContext&) {
  return e.lost;
}
std::string sinceRead(std::uint64_t previous_read_frame) {
  return previous_read_frame != 0 ? fmt::format("since the read in frame {}", previous_read_frame)
                                  : std::string{"since they were cleared"};
}
std::string lnk001Text(const LinkErrorEvent& e, const Stamp&, const RuleContext&) {
  const std::uint32_t n = e.link.errors;
  return fmt::format(
      "{}: {} RX or invalid-frame error{} at port {} {}, none forwarded from "
      "upstream: {}",
      slaveName(e.link.reported), n, n == 1 ? "" : "s", e.link.reported_port,
      sinceRead(e.previous_read_frame), linkFaultText(e.link));
}
std::string lnk002Text(const LinkErrorEvent& e, const Stamp&, const RuleContext&) {
  const std::uint32_t n = e.link.errors;
  return fmt::format("{}: the link at port {} went down {} time{} {}: {}",
                     slaveName(e.link.reported), e.link.reported_port, n, n == 1 ? "" : "s",
                     sinceRead(e.previous_read_frame), linkFaultText(e.link));
}

// DC-001: one finding per run of reads beyond the limit; the run ends at a read within it. A
// slave is judged once a read of it was within the limit: before, its clock is converging.
bool beyondDcLimit(std::int64_t difference_ns, const RuleContext& c) {
  return (difference_ns < 0 ? -difference_ns : difference_ns) > std::int64_t{c.limit()};
}
bool dc001(const DcDifferenceEvent& e, const RuleContext& c) {
  const bool synchronised = e.smallest_before_ns && !beyondDcLimit(*e.smallest_before_ns, c);
  return synchronised && beyondDcLimit(e.difference_ns, c) &&
         !(e.previous_ns && beyondDcLimit(*e.previous_ns, c));
}
std::string dc001Text(const DcDifferenceEvent& e, const Stamp&, const RuleContext& c) {
  return fmt::format("{}: system time difference (0x092C) {:+} ns, beyond dc_sync_limit_ns = {}{}",
                     slaveName(e.slave), e.difference_ns, c.limit(),
                     e.previous_ns ? fmt::format(" (the read before, frame {}: {:+} ns)",
                                                 e.previous_frame, *e.previous_ns)
                                   : std::string{});
}

// The table's uniform check signature over the axis model or one kind of event.
template <bool (*F)(const AxisModel&, const RuleContext&)>
bool onAxis(const RuleSubject& s, const RuleContext& context) {
  return F(*s.axis, context);
}
template <std::string (*F)(const AxisModel&, const RuleContext&, std::int64_t)>
std::string describeAxis(const RuleSubject& s, const RuleContext& context, std::int64_t held) {
  return F(*s.axis, context, held);
}
template <std::optional<Stamp> (*F)(const AxisModel&)>
std::optional<Stamp> beganOnAxis(const RuleSubject& s) {
  return F(*s.axis);
}
template <class Event, bool (*F)(const Event&, const RuleContext&)>
bool onEvent(const RuleSubject& s, const RuleContext& context) {
  const Event* e = std::get_if<Event>(&s.event->data);
  return e != nullptr && F(*e, context);
}
// A measurement continues its cyclic frame's run for the judging rule.
template <class Event, bool (*F)(const Event&, const RuleContext&, bool& in_run)>
bool onMeasurement(const RuleSubject& s, const RuleContext& context) {
  const Event* e = std::get_if<Event>(&s.event->data);
  return e != nullptr && F(*e, context, s.runs->inRun(context.rule.id, e->cyclic_frame));
}
template <class Event, std::string (*F)(const Event&, const Stamp&, const RuleContext&)>
std::string describeEvent(const RuleSubject& s, const RuleContext& context, std::int64_t) {
  return F(std::get<Event>(s.event->data), s.event->since, context);
}

}  // namespace

#define NCSERVO_AXIS(name) .check = onAxis<name>, .describe = describeAxis<name##Text>
#define NCSERVO_AXIS_EVENT(name) NCSERVO_AXIS(name), .began = beganOnAxis<name##Began>
#define NCSERVO_EVENT(type, name, text) \
  .event = eventIndex<type>(), .check = onEvent<type, name>, .describe = describeEvent<type, text>
#define NCSERVO_MEASUREMENT(type, name, text)                      \
  .event = eventIndex<type>(), .check = onMeasurement<type, name>, \
  .describe = describeEvent<type, text>
const std::array<RuleDef, kRuleCount> kRules{{
    {.id = RuleId::Se001,
     .code = "SE-001",
     .slug = "illegal-enable-edge",
     .severity = Severity::Error,
     .party = Party::Nc,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §2 SE",
     .reads = readsOf({"ncservo.scw.se"}),
     NCSERVO_AXIS(se001),
     .summary = "SCW.SE becomes 0x2 from a value other than 0x1"},
    {.id = RuleId::Se002,
     .code = "SE-002",
     .slug = "enable-without-edge",
     .severity = Severity::Error,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §2 SE",
     .timeout = Timeout::DriveResponse,
     .timeout_use = TimeoutUse::LookBack,
     .reads = readsOf({"ncservo.scw.se", "ncservo.ssw.servo_en"}),
     NCSERVO_AXIS(se002),
     .summary = "SSW.ServoEn rises with no valid enable"},
    {.id = RuleId::Se003,
     .code = "SE-003",
     .slug = "not-disabled",
     .severity = Severity::Error,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §2 SE",
     .timeout = Timeout::DriveResponse,
     .timeout_use = TimeoutUse::Delay,
     .reads = readsOf({"ncservo.scw.se", "ncservo.ssw.servo_en"}),
     NCSERVO_AXIS(se003),
     .summary = "SSW.ServoEn stays 1 after the valid enable ended, or without one"},
    {.id = RuleId::Se004,
     .code = "SE-004",
     .slug = "enable-not-honoured",
     .severity = Severity::Warning,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §2 SE, §5",
     .timeout = Timeout::EnableResponse,
     .timeout_use = TimeoutUse::Delay,
     .reads =
         readsOf({"ncservo.scw.se", "ncservo.scw.emgon", "ncservo.scw.brake",
                  "ncservo.ssw.servo_en", "ncservo.ssw.servo_rdy", "ncservo.sew.servo_errors"}),
     NCSERVO_AXIS(se004),
     .summary = "a valid enable to a ready drive is not answered with ServoEn"},
    {.id = RuleId::Zp001,
     .code = "ZP-001",
     .slug = "zpulse-ack-not-cleared",
     .severity = Severity::Error,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §2 ZPulseRequest, §3 ZPulseAck",
     .timeout = Timeout::DriveResponse,
     .timeout_use = TimeoutUse::Delay,
     .reads = readsOf({"ncservo.scw.zpulse_request", "ncservo.ssw.zpulse_ack"}),
     NCSERVO_AXIS(zp001),
     .summary = "ZPulseAck stays 1 after ZPulseRequest fell"},
    {.id = RuleId::Zp002,
     .code = "ZP-002",
     .slug = "zpulse-ack-without-request",
     .severity = Severity::Error,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §3 ZPulseAck",
     .timeout = Timeout::DriveResponse,
     .timeout_use = TimeoutUse::LookBack,
     .reads = readsOf({"ncservo.scw.zpulse_request", "ncservo.ssw.zpulse_ack"}),
     NCSERVO_AXIS(zp002),
     .summary = "ZPulseAck rises with no ZPulseRequest"},
    {.id = RuleId::Zp003,
     .code = "ZP-003",
     .slug = "zpulse-absolute-encoder",
     .severity = Severity::Warning,
     .party = Party::Nc,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §1, §2 ZPulseRequest",
     .reads = readsOf(
         {"ncservo.scw.zpulse_request", "ncservo.ssw.incremental", "ncservo.ssw.no_encoder"}),
     NCSERVO_AXIS(zp003),
     .summary = "ZPulseRequest on an axis with an absolute encoder or none"},
    {.id = RuleId::Ec001,
     .code = "EC-001",
     .slug = "clear-ack-without-request",
     .severity = Severity::Error,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §3 ErrClearAck",
     .timeout = Timeout::DriveResponse,
     .timeout_use = TimeoutUse::LookBack,
     .reads = readsOf({"ncservo.scw.error_clear", "ncservo.ssw.err_clear_ack"}),
     NCSERVO_AXIS(ec001),
     .summary = "ErrClearAck rises with no ErrorClear"},
    {.id = RuleId::Ec002,
     .code = "EC-002",
     .slug = "clear-request-held",
     .severity = Severity::Warning,
     .party = Party::Nc,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §2 ErrorClear",
     .timeout = Timeout::NcRelease,
     .timeout_use = TimeoutUse::Delay,
     .reads = readsOf({"ncservo.scw.error_clear", "ncservo.ssw.err_clear_ack"}),
     NCSERVO_AXIS(ec002),
     .summary = "ErrorClear held after ErrClearAck rose"},
    {.id = RuleId::Ec003,
     .code = "EC-003",
     .slug = "clear-ack-not-cleared",
     .severity = Severity::Error,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §3 ErrClearAck",
     .timeout = Timeout::DriveResponse,
     .timeout_use = TimeoutUse::Delay,
     .reads = readsOf({"ncservo.scw.error_clear", "ncservo.ssw.err_clear_ack"}),
     NCSERVO_AXIS(ec003),
     .summary = "ErrClearAck stays 1 after ErrorClear fell"},
    {.id = RuleId::Ec004,
     .code = "EC-004",
     .slug = "clear-not-acknowledged",
     .severity = Severity::Warning,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §2 ErrorClear, §3 ErrClearAck",
     .timeout = Timeout::ClearResponse,
     .timeout_use = TimeoutUse::Delay,
     .reads = readsOf({"ncservo.scw.error_clear", "ncservo.ssw.err_clear_ack", "ncservo.sew"}),
     NCSERVO_AXIS(ec004),
     .summary = "ErrorClear on a drive in error is not acknowledged"},
    {.id = RuleId::Sew001,
     .code = "SEW-001",
     .slug = "cause-without-summary",
     .severity = Severity::Error,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §4",
     .reads = readsOf({"ncservo.sew"}),
     NCSERVO_AXIS(sew001),
     .summary = "a SEW cause bit without the summary bit 0"},
    {.id = RuleId::Sew002,
     .code = "SEW-002",
     .slug = "summary-without-cause",
     .severity = Severity::Warning,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §4",
     .timeout = Timeout::DriveResponse,
     .timeout_use = TimeoutUse::Delay,
     .reads = readsOf({"ncservo.sew"}),
     NCSERVO_AXIS(sew002),
     .summary = "SEW summary bit 0 with no cause bit"},
    {.id = RuleId::Sew003,
     .code = "SEW-003",
     .slug = "reserved-error-bits",
     .severity = Severity::Warning,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §4",
     .reads = readsOf({"ncservo.sew"}),
     NCSERVO_AXIS(sew003),
     .summary = "reserved SEW bits set"},
    {.id = RuleId::Ssw001,
     .code = "SSW-001",
     .slug = "reserved-status-bits",
     .severity = Severity::Warning,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §3",
     .reads = readsOf({"ncservo.ssw.reserved"}),
     NCSERVO_AXIS(ssw001),
     .summary = "reserved SSW bits set"},
    {.id = RuleId::Scw001,
     .code = "SCW-001",
     .slug = "reserved-control-bits",
     .severity = Severity::Warning,
     .party = Party::Nc,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §2",
     .reads = readsOf({"ncservo.scw.reserved"}),
     NCSERVO_AXIS(scw001),
     .summary = "reserved SCW bits set"},
    {.id = RuleId::Rdy001,
     .code = "RDY-001",
     .slug = "ready-mismatch",
     .severity = Severity::Error,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §5",
     .timeout = Timeout::DriveResponse,
     .timeout_use = TimeoutUse::Delay,
     .reads =
         readsOf({"ncservo.ssw.servo_rdy", "ncservo.ssw.servo_en", "ncservo.sew.servo_errors"}),
     NCSERVO_AXIS(rdy001),
     .summary = "ServoRDY differs from the Servo_Ready_Mode table"},
    {.id = RuleId::Flt001,
     .code = "FLT-001",
     .slug = "enabled-with-error",
     .severity = Severity::Error,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §4, §6",
     .timeout = Timeout::FaultReaction,
     .timeout_use = TimeoutUse::Delay,
     .reads = readsOf({"ncservo.ssw.servo_en", "ncservo.sew"}),
     NCSERVO_AXIS(flt001),
     .summary = "the drive stays enabled while reporting an error"},
    {.id = RuleId::Pt001,
     .code = "PT-001",
     .slug = "param-table-not-followed",
     .severity = Severity::Warning,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §2 PRMTBL, §3 PRMTBL",
     .timeout = Timeout::ParamTable,
     .timeout_use = TimeoutUse::Delay,
     .reads = readsOf({"ncservo.scw.prmtbl", "ncservo.scw.ext_prmtbl", "ncservo.ssw.prmtbl",
                       "ncservo.ssw.ext_prmtbl"}),
     NCSERVO_AXIS(pt001),
     .summary = "the active parameter table differs from the commanded one"},
    {.id = RuleId::Msg001,
     .code = "MSG-001",
     .slug = "undefined-message-code",
     .severity = Severity::Warning,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §5",
     .reads = readsThrough("ncservo.msg_code", definedMessageCode),
     NCSERVO_AXIS(msg001),
     .summary = "a message code outside 0-5 (6-9 are listed without a meaning)"},
    {.id = RuleId::Com001,
     .code = "COM-001",
     .slug = "working-counter",
     .severity = Severity::Error,
     .party = Party::Bus,
     .kind = RuleKind::Bus,
     .clause = "docs/protocol.md §8 WKC",
     NCSERVO_EVENT(WorkingCounterEvent, com001, com001Text),
     .summary = "a returned cyclic process-data datagram has an unexpected WKC"},
    {.id = RuleId::Com002,
     .code = "COM-002",
     .slug = "cycle-gap",
     .severity = Severity::Warning,
     .party = Party::Bus,
     .kind = RuleKind::Bus,
     .clause = "docs/protocol.md §8; docs/rules.md timeouts",
     // docs/rules.md: the interval after a gap tells a late cycle from lost ones.
     .reported = "at the next master copy after the gap, one cycle after it (since: the master "
                 "copy before the gap); at a segment's or the capture's end when none follows",
     NCSERVO_EVENT(CycleGapEvent, com002, com002Text),
     .summary = "cycles late or missing between two master frames"},
    {.id = RuleId::Com003,
     .code = "COM-003",
     .slug = "timeout-not-reported",
     .severity = Severity::Info,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §4 ECatTErr",
     .timeout = Timeout::DriveResponse,
     .timeout_use = TimeoutUse::Delay,
     .reads = readsOf({"ncservo.sew.ecat_timeout"}),
     NCSERVO_AXIS(com003),
     .summary = "3 or more failed cycles without SEW.ECatTErr"},
    {.id = RuleId::Com004,
     .code = "COM-004",
     .slug = "frame-not-returned",
     .severity = Severity::Warning,
     .party = Party::Bus,
     .kind = RuleKind::Bus,
     .clause = "docs/protocol.md §8",
     NCSERVO_EVENT(NotReturnedEvent, com004, com004Text),
     .summary = "a cyclic master frame was not returned"},
    {.id = RuleId::Com005,
     .code = "COM-005",
     .slug = "telegram-failure-limit",
     .severity = Severity::Error,
     .party = Party::Bus,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §8",
     NCSERVO_AXIS(com005),
     .summary = "consecutive failed cycles of an axis exceed the limit"},
    {.id = RuleId::Com006,
     .code = "COM-006",
     .slug = "cycle-jitter",
     .severity = Severity::Warning,
     .party = Party::Bus,
     .kind = RuleKind::Bus,
     .clause = "docs/timing.md; docs/rules.md limits",
     .limit = Limit::CycleJitterPercent,
     .by_default = ByDefault::Off,
     NCSERVO_MEASUREMENT(CycleIntervalEvent, com006, com006Text),
     .summary = "a master copy's interval deviates from the nominal cycle by more than "
                "cycle_jitter_percent"},
    {.id = RuleId::Com007,
     .code = "COM-007",
     .slug = "late-return",
     .severity = Severity::Warning,
     .party = Party::Bus,
     .kind = RuleKind::Bus,
     .clause = "docs/timing.md; docs/rules.md limits",
     .limit = Limit::ReturnLatencyUs,
     .by_default = ByDefault::Off,
     NCSERVO_MEASUREMENT(ReturnLatencyEvent, com007, com007Text),
     .summary = "a returned copy arrives more than return_latency_us after its master copy"},
    {.id = RuleId::Esm001,
     .code = "ESM-001",
     .slug = "invalid-al-transition",
     .severity = Severity::Error,
     .party = Party::Nc,
     .kind = RuleKind::Slave,
     .clause = "docs/protocol.md §8 AL control",
     NCSERVO_EVENT(AlControlEvent, esm001, esm001Text),
     .summary = "an AL control write requests a transition the state machine does not allow"},
    {.id = RuleId::Esm002,
     .code = "ESM-002",
     .slug = "pdo-outside-op",
     .severity = Severity::Warning,
     .party = Party::Nc,
     .kind = RuleKind::Axis,
     .clause = "docs/protocol.md §8 AL states",
     .reads = readsOf({"ncservo.scw.se"}, true),
     NCSERVO_AXIS(esm002),
     .summary = "process data exchanged with an axis outside OP/SAFE-OP"},
    {.id = RuleId::Esm003,
     .code = "ESM-003",
     .slug = "al-error",
     .severity = Severity::Error,
     .party = Party::Drive,
     .kind = RuleKind::Slave,
     .clause = "docs/protocol.md §8 AL status",
     NCSERVO_EVENT(AlErrorEvent, esm003, alErrorText),
     .summary = "AL status shows the error indicator above INIT"},
    {.id = RuleId::Esm004,
     .code = "ESM-004",
     .slug = "al-error-at-init",
     .severity = Severity::Info,
     .party = Party::Drive,
     .kind = RuleKind::Slave,
     .clause = "docs/protocol.md §8 AL status",
     NCSERVO_EVENT(AlErrorEvent, esm004, alErrorText),
     .summary = "AL status shows the error indicator at INIT"},
    {.id = RuleId::Mbx001,
     .code = "MBX-001",
     .slug = "emergency-without-fault",
     .severity = Severity::Warning,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/drive-messages.md emergencies; docs/protocol.md §4",
     .timeout = Timeout::DriveResponse,
     .timeout_use = TimeoutUse::Around,
     .reads = readsWithMailbox({"ncservo.sew"}),
     NCSERVO_AXIS_EVENT(mbx001),
     .summary = "an emergency (not an error reset) with no SEW cause bit rising around it"},
    {.id = RuleId::Mbx002,
     .code = "MBX-002",
     .slug = "fault-without-emergency",
     .severity = Severity::Info,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/drive-messages.md emergencies; docs/protocol.md §4",
     .timeout = Timeout::DriveResponse,
     .timeout_use = TimeoutUse::Around,
     .reads = readsWithMailbox({"ncservo.sew"}),
     NCSERVO_AXIS_EVENT(mbx002),
     .summary = "a drive that sent emergencies faults and sends none around it"},
    {.id = RuleId::Mbx003,
     .code = "MBX-003",
     .slug = "sdo-abort",
     .severity = Severity::Info,
     .party = Party::Drive,
     .kind = RuleKind::Slave,
     .clause = "docs/drive-messages.md SDO; CiA 301 abort codes",
     NCSERVO_EVENT(SdoAbortEvent, mbx003, mbx003Text),
     .summary = "an SDO request was aborted (not 0x08000024 on an empty 1003h)"},
    {.id = RuleId::Erh001,
     .code = "ERH-001",
     .slug = "error-history-shrunk",
     .severity = Severity::Warning,
     .party = Party::Drive,
     .kind = RuleKind::Slave,
     .clause = "docs/drive-messages.md error history 1003h",
     NCSERVO_EVENT(ErrorHistoryShrunkEvent, erh001, erh001Text),
     .summary = "1003h:00 read lower than before with no write of 0 between"},
    {.id = RuleId::Erh002,
     .code = "ERH-002",
     .slug = "error-history-disagrees",
     .severity = Severity::Info,
     .party = Party::Drive,
     .kind = RuleKind::Axis,
     .clause = "docs/drive-messages.md error history 1003h; docs/protocol.md §7",
     .reported = "on the frame that reads 1003h:01, the first read of it since the fault",
     .reads = readsWithMailbox({"ncservo.sew"}),
     NCSERVO_AXIS_EVENT(erh002),
     .summary = "the newest 1003h entry read after a fault lacks the code of its SEW cause"},
    {.id = RuleId::Lnk001,
     .code = "LNK-001",
     .slug = "link-rx-errors",
     .severity = Severity::Warning,
     .party = Party::Bus,
     .kind = RuleKind::Slave,
     .clause = "docs/drive-messages.md ESC error counters",
     NCSERVO_EVENT(LinkErrorEvent, lnk001, lnk001Text),
     .summary = "a slave's RX or invalid-frame counter at a port rose, not forwarded: a bad link"},
    {.id = RuleId::Lnk002,
     .code = "LNK-002",
     .slug = "link-lost",
     .severity = Severity::Error,
     .party = Party::Bus,
     .kind = RuleKind::Slave,
     .clause = "docs/drive-messages.md ESC error counters",
     NCSERVO_EVENT(LinkErrorEvent, lnk002, lnk002Text),
     .summary = "a slave's lost-link counter at a port rose"},
    {.id = RuleId::Dc001,
     .code = "DC-001",
     .slug = "dc-out-of-sync",
     .severity = Severity::Warning,
     .party = Party::Bus,
     .kind = RuleKind::Slave,
     .clause = "docs/timing.md distributed clocks",
     .limit = Limit::DcSyncLimitNs,
     NCSERVO_EVENT(DcDifferenceEvent, dc001, dc001Text),
     .summary = "a slave's system time difference (0x092C) exceeds dc_sync_limit_ns"},
}};
#undef NCSERVO_AXIS
#undef NCSERVO_AXIS_EVENT
#undef NCSERVO_EVENT
#undef NCSERVO_MEASUREMENT

const char* severityName(Severity severity) {
  switch (severity) {
    case Severity::Info:
      return "info";
    case Severity::Warning:
      return "warning";
    case Severity::Error:
      return "error";
  }
  return "error";
}

std::optional<Severity> severityFromName(std::string_view name) {
  for (Severity s : {Severity::Info, Severity::Warning, Severity::Error}) {
    if (name == severityName(s)) return s;
  }
  return std::nullopt;
}

const char* partyName(Party party) {
  switch (party) {
    case Party::Nc:
      return "NC";
    case Party::Drive:
      return "drive";
    case Party::Bus:
      return "bus";
  }
  return "bus";
}

std::optional<Timeout> timeoutFromName(std::string_view name) {
  for (const TimeoutDef& t : kTimeouts) {
    if (name == t.name) return t.id;
  }
  return std::nullopt;
}

std::string unknownTimeoutMessage(std::string_view name) {
  std::vector<std::string> names;
  for (const TimeoutDef& t : kTimeouts) names.emplace_back(t.name);
  return fmt::format("unknown timeout '{}' (known: {}){}", name, timeoutNameList(),
                     didYouMean(name, names));
}

std::string timeoutNameList() {
  std::string known;
  for (const TimeoutDef& t : kTimeouts)
    known += fmt::format("{}{}", known.empty() ? "" : ", ", t.name);
  return known;
}

const RuleDef& ruleDef(RuleId id) {
  return kRules[static_cast<std::size_t>(id)];
}

const RuleDef* ruleByCode(std::string_view code) {
  for (const RuleDef& rule : kRules) {
    if (equalsIgnoringCase(code, rule.code)) return &rule;
  }
  return nullptr;
}

Result<const RuleDef*> findRule(std::string_view code) {
  if (const RuleDef* rule = ruleByCode(code)) return rule;
  std::vector<std::string> codes;
  for (const RuleDef& rule : kRules) codes.emplace_back(rule.code);
  return fail(
      fmt::format("unknown rule ID '{}' (see `ncservo rules`){}", code, didYouMean(code, codes)));
}

std::vector<FieldRead> fieldsRead(const Reads& reads) {
  std::vector<FieldRead> out;
  for (const FieldDef& f : kFields) {
    const std::size_t w = static_cast<std::size_t>(f.word);
    const std::uint64_t bits = reads.bits[w];
    const bool whole = bits == wordMask(f.word);
    if (f.kind == FieldKind::Word) {
      if (whole) out.push_back({&f, false});
      if (reads.classes[w] != nullptr) out.push_back({&f, true});
    } else if ((f.kind == FieldKind::Flag || f.kind == FieldKind::BitRange) && !whole &&
               (bits & f.mask) == f.mask) {
      out.push_back({&f, false});
    }
  }
  return out;
}

std::string describeReads(const Reads& reads) {
  std::string out;
  auto add = [&out](std::string_view filter, const char* suffix) {
    out += fmt::format("{}{}{}", out.empty() ? "" : ", ", filter.substr(8), suffix);
  };
  for (const FieldRead& read : fieldsRead(reads)) {
    add(read.field->filter, read.through_class ? " (its class)" : "");
  }
  if (reads.al_state) add("ncservo.al_state", "");
  if (reads.mailbox) add("ncservo.mailbox", "");
  return out.empty() ? "-" : out;
}

const char* ruleKindName(RuleKind kind) {
  switch (kind) {
    case RuleKind::Axis:
      return "axis";
    case RuleKind::Bus:
      return "bus";
    case RuleKind::Slave:
      return "slave";
  }
  return "axis";
}

bool& MeasurementRuns::inRun(RuleId rule, CyclicFrameId frame) {
  Slot& slot = slots_[frame.slot];
  if (slot.serial != frame.serial) slot = Slot{frame.serial, {}};
  return slot.in_run[static_cast<std::size_t>(rule)];
}

namespace {
// The slave an event is about; none for the bus model's.
SlaveRef slaveOf(const BusEvent& event) {
  return std::visit(
      [](const auto& e) -> SlaveRef {
        using Event = std::decay_t<decltype(e)>;
        if constexpr (std::is_same_v<Event, LinkErrorEvent>) {
          return e.link.reported;
        } else if constexpr (requires { e.slave; }) {
          return e.slave;
        } else {
          return SlaveRef{};
        }
      },
      event.data);
}
}  // namespace

void judgeEvent(const BusEvent& event, const RuleSettings& settings, MeasurementRuns& runs,
                std::vector<EventFinding>& out) {
  const RuleSubject subject{nullptr, &event, &runs};
  for (const RuleDef& rule : kRules) {
    if (rule.event != event.data.index() || !settings.isEnabled(rule.id)) continue;
    const RuleContext context{rule, settings};
    if (!rule.check(subject, context)) continue;
    out.push_back(EventFinding{rule.id, slaveOf(event), rule.describe(subject, context, 0)});
  }
}

std::optional<AllowedWindow> allowedWindow(const RuleDef& rule, const RuleSettings& settings) {
  if (!rule.timeout) return std::nullopt;
  const std::int64_t timeout = settings.timeoutNs(*rule.timeout);
  switch (rule.timeout_use) {
    case TimeoutUse::Delay:
      return AllowedWindow{0, timeout};
    case TimeoutUse::LookBack:
      return AllowedWindow{-timeout, 0};
    case TimeoutUse::Around:
      return AllowedWindow{-timeout, timeout};
    case TimeoutUse::None:
      break;
  }
  return std::nullopt;
}

std::string ruleFilterName(const RuleDef& rule) {
  std::string slug = rule.slug;
  std::replace(slug.begin(), slug.end(), '-', '_');
  return "ncservo.rule." + slug;
}

RuleSettings::RuleSettings() {
  for (const RuleDef& rule : kRules) {
    enabled[static_cast<std::size_t>(rule.id)] = rule.by_default == ByDefault::On;
    severity[static_cast<std::size_t>(rule.id)] = rule.severity;
  }
  for (const TimeoutDef& t : kTimeouts) {
    timeout_ns[static_cast<std::size_t>(t.id)] = std::int64_t{t.default_ms} * 1'000'000;
  }
  for (const LimitDef& l : kLimits) limit[static_cast<std::size_t>(l.id)] = l.default_value;
}

const LimitDef* limitByName(std::string_view name) {
  for (const LimitDef& l : kLimits) {
    if (name == l.name) return &l;
  }
  return nullptr;
}

std::optional<int> RuleSettings::readyModeFor(std::size_t axis) const {
  if (axis < axis_ready_mode.size() && axis_ready_mode[axis]) return axis_ready_mode[axis];
  return servo_ready_mode;
}

Status RuleSettings::disable(std::string_view code) {
  const Result<const RuleDef*> rule = findRule(code);
  if (!rule) return fail(rule.error());
  enabled[static_cast<std::size_t>((*rule)->id)] = false;
  return {};
}

Status RuleSettings::enable(std::string_view code) {
  const Result<const RuleDef*> rule = findRule(code);
  if (!rule) return fail(rule.error());
  enabled[static_cast<std::size_t>((*rule)->id)] = true;
  return {};
}

Status RuleSettings::setLimit(std::string_view name, std::int64_t value) {
  const LimitDef* l = limitByName(name);
  if (l == nullptr) {
    std::vector<std::string> names;
    for (const LimitDef& known : kLimits) names.emplace_back(known.name);
    return fail(fmt::format("unknown limit '{}' (known: {}){}", name, fmt::join(names, ", "),
                            didYouMean(name, names)));
  }
  if (value < l->min || value > l->max) {
    return fail(
        fmt::format("{} = {}: expected {} to {} ({})", name, value, l->min, l->max, l->unit));
  }
  limit[static_cast<std::size_t>(l->id)] = static_cast<std::uint32_t>(value);
  return {};
}

Status RuleSettings::setSeverity(std::string_view code, std::string_view level) {
  const Result<const RuleDef*> rule = findRule(code);
  if (!rule) return fail(rule.error());
  const std::optional<Severity> s = severityFromName(level);
  if (!s) {
    return fail(
        fmt::format("severity '{}' for {}: expected error, warning or info", level, (*rule)->code));
  }
  severity[static_cast<std::size_t>((*rule)->id)] = *s;
  return {};
}

Status RuleSettings::setTimeout(std::string_view name, std::int64_t ms) {
  const std::optional<Timeout> t = timeoutFromName(name);
  if (!t) return fail(unknownTimeoutMessage(name));
  if (ms < 0 || ms > kMaxTimeoutMs) {
    return fail(fmt::format("timeout {} = {} ms: expected 0 to {}", name, ms, kMaxTimeoutMs));
  }
  timeout_ns[static_cast<std::size_t>(*t)] = ms * 1'000'000;
  return {};
}

}  // namespace ncservo
