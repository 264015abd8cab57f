#include "ncservo/incidents/causes.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "incident_tracks.hpp"
#include "ncservo/model/al_tracker.hpp"
#include "ncservo/model/esc_errors.hpp"
#include "ncservo/protocol/fields.hpp"
#include "ncservo/wire/diagnosis_texts.hpp"

namespace ncservo {

namespace {

constexpr std::uint32_t kEcatBits =
    mask32("ncservo.sew.ecat_watchdog") | mask32("ncservo.sew.ecat_timeout");
constexpr std::uint32_t kI2t = mask32("ncservo.sew.i2t_endat");
constexpr std::uint32_t kFollowing = mask32("ncservo.sew.following");
constexpr std::uint32_t kCurrentBits =
    mask32("ncservo.sew.current") | mask32("ncservo.sew.current_offset") |
    mask32("ncservo.sew.current_symmetry") | mask32("ncservo.sew.overload");
constexpr std::uint32_t kBusVoltage = mask32("ncservo.sew.bus_voltage");
constexpr std::uint32_t kEncoderBits = mask32("ncservo.sew.encoder") | mask32("ncservo.sew.hall") |
                                       mask32("ncservo.sew.hall_sequence");
constexpr std::uint32_t kOverspeed = mask32("ncservo.sew.overspeed");
constexpr std::uint32_t kConfigurationBits =
    mask32("ncservo.sew.ecat_config") | mask32("ncservo.sew.param_checksum") |
    mask32("ncservo.sew.program_checksum") | mask32("ncservo.sew.flash");
constexpr std::uint32_t kTempWarning = mask32("ncservo.ssw.temp_warning");

constexpr std::int64_t kMinuteNs = 60'000 * kMsNs;

// "FollowerErr (E09), OverLoad (E20)": the labels of the SEW bits in `bits`, in bit order.
std::string sewLabels(std::uint32_t bits) {
  std::string out;
  for (const FieldDef& f : kFields) {
    if (f.word != Word::Sew || f.view != FieldView::Cause || (bits & f.mask) == 0) continue;
    out += fmt::format("{}{}", out.empty() ? "" : ", ", f.label);
  }
  return out;
}

// "300 ms", "2.5 s".
std::string duration(std::int64_t ns) {
  if (ns < 1000 * kMsNs) return fmt::format("{} ms", (ns + kMsNs / 2) / kMsNs);
  return fmt::format("{:.1f} s", static_cast<double>(ns) / 1e9);
}

void evidence(CauseMatch& m, const Mark& at, std::string what) {
  m.evidence.push_back(IncidentEvidence{at.stamp(), std::move(what)});
}

// The drive's last message of `code` before the incident, with where it came: message codes take
// turns, so a value may be several cycles old (docs/incidents.md#before).
struct Said {
  double value;
  Mark at;
};
std::optional<Said> said(const MessageHistory* messages, std::int32_t code) {
  if (messages == nullptr) return std::nullopt;
  for (std::size_t i = 0; i < kBefore.size(); ++i) {
    if (kBefore[i].message_code == code && messages->before[i]) {
      return Said{*messages->before[i], messages->before_at[i]};
    }
  }
  return std::nullopt;
}

// The SEW bits of `bits` set at the incident, with the message value before it, where seen.
bool bitsWithValue(const CauseContext& c, CauseMatch& m, std::uint32_t bits, std::int32_t code) {
  if ((c.sew & bits) == 0) return false;
  m.text = sewLabels(c.sew & bits);
  if (const std::optional<Said> last = said(c.messages, code)) {
    const ValueName* meaning = valueName(kMessageCodeField, static_cast<std::uint64_t>(code));
    m.text +=
        fmt::format(", {} {:.1f} {} {} before (frame {})", meaning->name, last->value,
                    meaning->unit, duration(c.at.clock_ns - last->at.clock_ns), last->at.frame);
  }
  return true;
}

}  // namespace

std::string lostCyclesText(const AxisTrack& axis, const Mark& at, std::int64_t window_ns,
                           std::vector<IncidentEvidence>* evidence) {
  // The runs newest first: the frames named are the oldest run's first and the newest's last.
  std::uint64_t lost = 0, failed = 0, first = 0, last = 0;
  bool between = true;
  for (std::size_t i = 0; i < axis.failures.size(); ++i) {
    const FailureRun& run = axis.failures[i];
    if (!within(run.last, at, window_ns)) continue;
    lost += run.lost;
    failed += run.failed;
    first = run.first_frame.frame;
    if (last == 0) last = run.last_frame.frame;
    between = between && run.between;
    if (evidence == nullptr) continue;
    evidence->push_back(IncidentEvidence{
        run.first_frame,
        run.lost > 0
            ? fmt::format("{} cycle{} lost", run.lost, run.lost == 1 ? "" : "s")
            : fmt::format("{} cycle{} with a wrong WKC", run.failed, run.failed == 1 ? "" : "s")});
  }
  if (lost + failed == 0) return "";
  std::string text;
  if (lost > 0) text = fmt::format("{} cycle{} lost", lost, lost == 1 ? "" : "s");
  if (failed > 0) {
    text += fmt::format("{}{} cycle{} with a wrong WKC", text.empty() ? "" : ", ", failed,
                        failed == 1 ? "" : "s");
  }
  text += between         ? fmt::format(" (between frames {} and {})", first, last)
          : first == last ? fmt::format(" (frame {})", first)
                          : fmt::format(" (frames {}-{})", first, last);
  return text;
}

std::uint64_t firstFailedFrame(const AxisTrack& axis, const Mark& at, std::int64_t window_ns) {
  std::uint64_t first = 0;
  for (std::size_t i = 0; i < axis.failures.size(); ++i) {
    const FailureRun& run = axis.failures[i];
    if (within(run.last, at, window_ns)) first = run.first_frame.frame;  // newest first
  }
  return first;
}

std::string linkRiseText(const LinkMark& link) {
  const LinkErrorEvent& e = link.event;
  const std::string counted =
      e.lost ? fmt::format("{} lost link{}", e.link.errors, e.link.errors == 1 ? "" : "s")
             : fmt::format("{} RX error{}", e.link.errors, e.link.errors == 1 ? "" : "s");
  const std::string since = e.previous_read_frame == 0
                                ? std::string("since the counters were cleared")
                                : fmt::format("since frame {}", e.previous_read_frame);
  return fmt::format("{}: {} at the read of frame {} ({})", linkFaultText(e.link), counted,
                     link.at.frame, since);
}

IncidentEvidence linkRiseEvidence(const LinkMark& link) {
  const LinkErrorEvent& e = link.event;
  return IncidentEvidence{
      link.at.stamp(),
      fmt::format("{} {} at {} port {}", e.link.errors, e.lost ? "lost links" : "RX errors",
                  slaveName(e.link.reported), e.link.reported_port)};
}

namespace {

bool communicationLoss(const CauseContext& c, CauseMatch& m) {
  std::string text;
  if (c.axis != nullptr) text = lostCyclesText(*c.axis, c.at, kShortWindowNs, &m.evidence);
  if ((c.sew & kEcatBits) != 0) {
    text += fmt::format("{}{}", text.empty() ? "" : ", then ", sewLabels(c.sew & kEcatBits));
  }
  if (text.empty()) return false;
  m.text = c.kind == IncidentKind::BusOutage ? "every axis failing: " + text : text;
  return true;
}

// A link's counters rose over the axis's failures, read before the incident (after it: the
// detector's pending links, kLinkReadWaitNs). The text is communication-loss's after the link's,
// as a revision to link-fault writes it.
bool linkFault(const CauseContext& c, CauseMatch& m) {
  if (c.axis == nullptr || c.bus == nullptr || c.bus->links.size() == 0) return false;
  const std::uint64_t first = firstFailedFrame(*c.axis, c.at, kShortWindowNs);
  if (first == 0) return false;
  for (std::size_t i = 0; i < c.bus->links.size(); ++i) {
    const LinkMark& link = c.bus->links[i];
    if (!link.covers(first) || link.at.clock_ns > c.at.clock_ns) continue;
    communicationLoss(c, m);
    m.text = fmt::format("{}; {}", linkRiseText(link), m.text);
    m.evidence.push_back(linkRiseEvidence(link));
    return true;
  }
  return false;
}

// The drive's ESC lost its synchronisation: its AL status code says so (diag::kAlStatusCodes).
bool syncError(const CauseContext& c, CauseMatch& m) {
  if (!c.al_code || !within(c.al_code->at, c.at, kShortWindowNs)) return false;
  const diag::AlCodeDef* code = diag::alStatusCode(c.al_code->code);
  if (code == nullptr || !code->sync) return false;
  m.text = fmt::format("AL status code 0x{:04X} {} (frame {})", code->code, code->text,
                       c.al_code->at.frame);
  evidence(m, c.al_code->at, fmt::format("AL status code 0x{:04X}", code->code));
  return true;
}

// The motor temperature's rise in the minute before `at` (docs/incidents.md#overtemperature):
// from where it last left its steady level to the last reading, with how fast; "" when the last
// reading is not kTemperatureRiseC above the minute's lowest.
std::string temperatureRise(const MessageHistory& t, const Mark& at, CauseMatch& m) {
  if (!t.temperature_last_at || !within(*t.temperature_last_at, at, kMinuteNs)) return "";
  const std::int64_t second = t.temperature_last_at->clock_ns / 1'000'000'000;
  std::vector<const TemperatureBucket*> minute;
  for (const TemperatureBucket& b : t.temperature) {
    if (b.second < second - kTemperatureWindowS || b.second > second) continue;
    if (within(b.steady_at, at, kMinuteNs)) minute.push_back(&b);
  }
  if (minute.empty()) return "";
  const double lowest = (*std::min_element(minute.begin(), minute.end(), [](auto* x, auto* y) {
                          return x->lowest < y->lowest;
                        }))->lowest;
  if (t.temperature_last - lowest < kTemperatureRiseC) return "";
  // The latest second still at the minute's level: the rise left it there.
  const TemperatureBucket* left = nullptr;
  for (const TemperatureBucket* b : minute) {
    if (b->lowest <= lowest + kSteadyBandC &&
        (left == nullptr || b->steady_at.clock_ns > left->steady_at.clock_ns)) {
      left = b;
    }
  }
  const std::int64_t took = t.temperature_last_at->clock_ns - left->steady_at.clock_ns;
  evidence(m, left->steady_at, fmt::format("motor temperature {:.1f} \u00b0C", left->steady));
  evidence(m, *t.temperature_last_at,
           fmt::format("motor temperature {:.1f} \u00b0C", t.temperature_last));
  const double rate = took > 0 ? (t.temperature_last - left->steady) * 1e9 / took : 0;
  return fmt::format(
      "motor temperature {:.0f} \u2192 {:.0f} \u00b0C over {} from frame {} ({:.0f} "
      "\u00b0C/s)",
      left->steady, t.temperature_last, duration(took), left->steady_at.frame, rate);
}

bool overtemperature(const CauseContext& c, CauseMatch& m) {
  std::string text;
  if ((c.sew & kI2t) != 0) text = sewLabels(kI2t);
  const AxisMeasurements* a = c.signals;
  if (a != nullptr) {
    if (a->tempWarningRose() && within(*a->tempWarningRose(), c.at, kMinuteNs)) {
      text += fmt::format("{}SSW.TempWarning from frame {}", text.empty() ? "" : ", ",
                          a->tempWarningRose()->frame);
      evidence(m, *a->tempWarningRose(), "SSW.TempWarning \u2191");
    } else if (a->inputsKnown() && (a->ssw() & kTempWarning) != 0) {
      text += fmt::format("{}SSW.TempWarning set", text.empty() ? "" : ", ");
    }
    const std::string rise = temperatureRise(*c.messages, c.at, m);
    if (!rise.empty()) text += fmt::format("{}{}", text.empty() ? "" : ", ", rise);
  }
  if (text.empty()) return false;
  m.text = text;
  return true;
}

// Where FollowerErr rose for this incident: where the detector saw it rise, else at the incident.
Mark followingRose(const CauseContext& c) {
  if (c.signals != nullptr && c.signals->followingRose() &&
      within(*c.signals->followingRose(), c.at, kMinuteNs))
    return *c.signals->followingRose();
  return c.at;
}

bool followingErrorAfterStep(const CauseContext& c, CauseMatch& m) {
  if ((c.sew & kFollowing) == 0 || c.signals == nullptr) return false;
  const Mark rose = followingRose(c);
  const Step* step = nullptr;
  const std::optional<Step>& candidate = c.signals->stepCandidate();
  if (candidate && within(candidate->at, rose, kShortWindowNs)) step = &*candidate;
  const Ring<Step, 4>& steps = c.signals->steps();
  for (std::size_t i = 0; step == nullptr && i < steps.size(); ++i) {
    if (within(steps[i].at, rose, kShortWindowNs)) step = &steps[i];
  }
  if (step == nullptr) return false;
  m.text = fmt::format(
      "{} {} after an SSP step {} \u2192 {} at frame {} (the {} cycles before changed by at "
      "most {})",
      sewLabels(kFollowing), duration(rose.clock_ns - step->at.clock_ns), step->from, step->to,
      step->at.frame, kStepHistory, step->before_max);
  evidence(m, step->at, fmt::format("SSP step {} \u2192 {}", step->from, step->to));
  if (rose.frame != c.at.frame) evidence(m, rose, "SEW.FollowerErr \u2191");
  return true;
}

bool followingError(const CauseContext& c, CauseMatch& m) {
  if ((c.sew & kFollowing) == 0) return false;
  m.text = fmt::format("{}, no set-point step in the 100 ms before", sewLabels(kFollowing));
  const Mark rose = followingRose(c);
  if (rose.frame != c.at.frame) evidence(m, rose, "SEW.FollowerErr \u2191");
  return true;
}

bool overcurrent(const CauseContext& c, CauseMatch& m) {
  return bitsWithValue(c, m, kCurrentBits, 1);
}

bool busVoltage(const CauseContext& c, CauseMatch& m) {
  return bitsWithValue(c, m, kBusVoltage, 3);
}

bool encoder(const CauseContext& c, CauseMatch& m) {
  std::string text = sewLabels(c.sew & kEncoderBits);
  const std::optional<Mark> rose = c.signals != nullptr ? c.signals->noEncoderRose() : std::nullopt;
  if (rose && within(*rose, c.at, kShortWindowNs)) {
    text += fmt::format("{}SSW.NoEncoder from frame {}", text.empty() ? "" : ", ", rose->frame);
    evidence(m, *rose, "SSW.NoEncoder \u2191");
  }
  if (text.empty()) return false;
  m.text = text;
  return true;
}

bool overspeed(const CauseContext& c, CauseMatch& m) {
  return bitsWithValue(c, m, kOverspeed, 0);
}

bool configuration(const CauseContext& c, CauseMatch& m) {
  if ((c.sew & kConfigurationBits) == 0) return false;
  m.text = sewLabels(c.sew & kConfigurationBits);
  return true;
}

bool ncCommand(const CauseContext& c, CauseMatch& m) {
  if (c.axis == nullptr) return false;
  for (std::size_t i = 0; i < c.axis->findings.size(); ++i) {
    const FindingMark& f = c.axis->findings[i];
    const RuleDef& rule = ruleDef(f.rule);
    if (rule.party != Party::Nc || !within(f.at, c.at, kShortWindowNs)) continue;
    m.text = fmt::format("{} {} at frame {}, {} before", rule.code, rule.slug, f.at.frame,
                         duration(c.at.clock_ns - f.at.clock_ns));
    evidence(m, f.at, f.what);
    return true;
  }
  return false;
}

bool unknown(const CauseContext& c, CauseMatch& m) {
  const std::uint32_t causes = c.sew & kSewCauseMask;
  const std::string seen = causes != 0       ? sewLabels(causes)
                           : !c.what.empty() ? c.what
                                             : std::string("no cause bit set");
  m.text = fmt::format("{}; no cause row's evidence in the windows before", seen);
  return true;
}

}  // namespace

// docs/incidents.md#causes; INTERFACES.md "Incidents" fixes the ids and their order.
const std::array<CauseDef, kCauseCount> kCauses{{
    {CauseId::LinkFault, "link-fault",
     "cycles lost or failing on the axis within 100 ms before, and a link's RX or lost-link "
     "counters risen at their next read, up to 10 s after the fault",
     kShortWindowNs, linkFault},
    {CauseId::CommunicationLoss, "communication-loss",
     "ECatWatchDog or ECatTErr set at the fault, or cycles lost or returned with a wrong WKC on "
     "the axis within 100 ms before",
     kShortWindowNs, communicationLoss},
    {CauseId::SyncError, "sync-error",
     "the slave's AL status code, read at the fault or within 100 ms before, is a "
     "synchronization, sync-manager watchdog or PLL error",
     kShortWindowNs, syncError},
    {CauseId::Overtemperature, "overtemperature",
     "I2t_Endat set at the fault, or SSW.TempWarning rising (or set), or the motor temperature "
     "(message code 4) rising by 10 °C or more, in the minute before",
     kMinuteNs, overtemperature},
    {CauseId::FollowingErrorAfterStep, "following-error-after-step",
     "FollowerErr set, having risen within 100 ms after a set-point step", kShortWindowNs,
     followingErrorAfterStep},
    {CauseId::FollowingError, "following-error", "FollowerErr set otherwise", 0, followingError},
    {CauseId::Overcurrent, "overcurrent", "CurrErr, CURROErr, CurrDiffErr or OverLoad set", 0,
     overcurrent},
    {CauseId::BusVoltage, "bus-voltage", "BVErr set", 0, busVoltage},
    {CauseId::Encoder, "encoder",
     "EncoderErr, HallErr or HallSErr set, or SSW.NoEncoder rising within 100 ms before",
     kShortWindowNs, encoder},
    {CauseId::Overspeed, "overspeed", "OverSpeed set", 0, overspeed},
    {CauseId::Configuration, "configuration",
     "ECatConfigError, PTBLCHKSErr, PRGCHKSErr or SFlashErr set", 0, configuration},
    {CauseId::NcCommand, "nc-command", "a rule of party NC fired on the axis within 100 ms before",
     kShortWindowNs, ncCommand},
    {CauseId::Unknown, "unknown", "none of the rows above", 0, unknown},
}};

const CauseDef& causeDef(CauseId id) {
  return kCauses[static_cast<std::size_t>(id)];
}

std::optional<CauseId> findCause(std::string_view name) {
  for (const CauseDef& cause : kCauses) {
    if (name == cause.name) return cause.id;
  }
  return std::nullopt;
}

}  // namespace ncservo
