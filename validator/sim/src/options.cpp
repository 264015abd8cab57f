// `ncservo simulate`'s options: scenarios, the --fault text, and the checks and defaults that
// make a set of options one the simulator runs.
#include "ncservo/sim/options.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <string>

#include "incident_plan.hpp"
#include "ncservo/base/number.hpp"
#include "ncservo/sim/faults.hpp"

namespace ncservo::sim {

std::optional<Scenario> scenarioFromName(std::string_view name) {
  if (name == "commissioning") return Scenario::Commissioning;
  if (name == "faults") return Scenario::Faults;
  if (name == "soak") return Scenario::Soak;
  if (name == "incidents") return Scenario::Incidents;
  return std::nullopt;
}
const char* scenarioName(Scenario scenario) {
  switch (scenario) {
    case Scenario::Commissioning:
      return "commissioning";
    case Scenario::Faults:
      return "faults";
    case Scenario::Soak:
      return "soak";
    case Scenario::Incidents:
      return "incidents";
  }
  return "?";
}
std::optional<ImageStyle> imageStyleFromName(std::string_view name) {
  for (const ImageStyleName& row : kImageStyles) {
    if (name == row.name || (row.layout_alias != nullptr && name == row.layout_alias)) {
      return row.style;
    }
  }
  return std::nullopt;
}
const ImageStyleName& imageStyleRow(ImageStyle style) {
  for (const ImageStyleName& row : kImageStyles) {
    if (row.style == style) return row;
  }
  return kImageStyles[0];
}
std::optional<MidStart> midStartFromName(std::string_view name) {
  for (const MidStartName& row : kMidStarts) {
    if (name == row.name) return row.start;
  }
  return std::nullopt;
}
const MidStartName& midStartRow(MidStart start) {
  for (const MidStartName& row : kMidStarts) {
    if (row.start == start) return row;
  }
  return kMidStarts[0];
}

std::string standingFaultRules() {
  std::string codes;
  for (const FaultRecipe& recipe : faultRecipes()) {
    if (recipe.standing_ns > 0) {
      codes += (codes.empty() ? "" : ", ") + std::string(ruleDef(recipe.rule).code);
    }
  }
  return codes;
}

Result<MidStartRequest> parseMidStart(std::string_view text) {
  if (const std::optional<MidStart> start = midStartFromName(text)) {
    return MidStartRequest{*start, std::nullopt};
  }
  constexpr std::string_view kInFault = "fault:";
  if (!text.starts_with(kInFault)) {
    std::string names;
    for (const MidStartName& row : kMidStarts) names += std::string(row.name) + ", ";
    return fail(fmt::format("--start-in {}: one of {}or fault:RULE with RULE one of {}", text,
                            names, standingFaultRules()));
  }
  std::string code(text.substr(kInFault.size()));
  for (char& c : code) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  const RuleDef* rule = ruleByCode(code);
  if (rule == nullptr) {
    return fail(fmt::format("--start-in {}: no rule '{}' (see `ncservo rules`)", text, code));
  }
  const FaultRecipe* recipe = faultRecipe(rule->id);
  if (recipe == nullptr || recipe->standing_ns <= 0) {
    return fail(fmt::format(
        "--start-in {}: {}'s fault has no standing condition to begin inside; one of {}", text,
        code, standingFaultRules()));
  }
  return MidStartRequest{MidStart::InFault, rule->id};
}

int defaultIoSlaves(ImageStyle style) {
  switch (style) {
    case ImageStyle::Mixed:
      return 8;
    case ImageStyle::TwinCat:
      return 4;
    case ImageStyle::Soem:
    case ImageStyle::EtherLab:
      break;
  }
  return 0;
}

double defaultDuration(Scenario scenario) {
  switch (scenario) {
    case Scenario::Commissioning:
      return 3.0;
    case Scenario::Faults:
      return 4.3;
    case Scenario::Soak:
      return 60.0;
    case Scenario::Incidents:
      return 20.0;
  }
  return 3.0;
}

Result<FaultRequest> parseFault(std::string_view text) {
  FaultRequest fault;
  fault.text = std::string(text);
  std::string_view rest = text;
  std::string_view axis_text;
  std::string_view time_text;
  if (auto colon = rest.find(':'); colon != std::string_view::npos) {
    axis_text = rest.substr(colon + 1);
    rest = rest.substr(0, colon);
  }
  if (auto at = rest.find('@'); at != std::string_view::npos) {
    time_text = rest.substr(at + 1);
    rest = rest.substr(0, at);
  }
  std::string code(rest);
  for (char& c : code) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  const RuleDef* rule = ruleByCode(code);
  if (rule == nullptr) {
    return fail(fmt::format("--fault {}: no rule '{}' (see `ncservo rules`)", text, code));
  }
  fault.rule = rule->id;
  const bool has_time = text.find('@') != std::string_view::npos;
  const bool has_axis = text.find(':') != std::string_view::npos;
  auto malformed = [&] {
    return fail(fmt::format("--fault {}: expected RULE[@SECONDS][:AXIS], e.g. SE-001@1.2:0", text));
  };
  if (has_time) {
    const Result<double> at_s = parseNumber<double>(time_text);
    if (!at_s || !(*at_s >= 0)) return malformed();
    fault.at_s = *at_s;
  }
  if (has_axis) {
    const Result<int> axis = parseNumber<int>(axis_text);
    if (!axis || *axis < 0) return malformed();
    fault.axis = *axis;
  }
  return fault;
}

Result<CycleDisturbance> parseCycleDisturbance(std::string_view option, std::string_view text) {
  const std::size_t colon = text.find(':');
  CycleDisturbance d;
  d.text = std::string(text);
  const bool late = option == "--late-cycle";
  auto malformed = [&] {
    return fail(fmt::format("{} {}: expected SECONDS:{}, e.g. 1.5:{}", option, text,
                            late ? "US" : "N", late ? "400" : "3"));
  };
  if (colon == std::string_view::npos) return malformed();
  const Result<double> at_s = parseNumber<double>(text.substr(0, colon));
  if (!at_s || !(*at_s >= 0)) return malformed();
  d.at_s = *at_s;
  const Result<int> amount = parseNumber<int>(text.substr(colon + 1));
  if (!amount || *amount < 1) return malformed();
  d.amount = *amount;
  return d;
}

namespace {
// A station address as the user writes it: decimal, or hexadecimal after 0x.
std::optional<std::uint16_t> stationNumber(std::string_view text) {
  const Result<std::uint64_t> number = text.starts_with("0x") || text.starts_with("0X")
                                           ? parseNumber<std::uint64_t>(text.substr(2), 16)
                                           : parseNumber<std::uint64_t>(text);
  if (!number || *number > 0xFFFF) return std::nullopt;
  return static_cast<std::uint16_t>(*number);
}
}  // namespace

Result<SlaveAt> parseSyncError(std::string_view text) {
  const std::size_t at = text.find('@');
  const std::optional<std::uint16_t> station =
      at == std::string_view::npos ? std::nullopt : stationNumber(text.substr(0, at));
  const Result<double> seconds =
      at == std::string_view::npos ? fail("no @") : parseNumber<double>(text.substr(at + 1));
  if (!station || !seconds) {
    return fail(fmt::format("--sync-error {}: expected STATION@SECONDS (e.g. 0x3EA@1.6)", text));
  }
  return SlaveAt{*station, *seconds, std::string(text)};
}

Result<BadLink> parseBadLink(std::string_view text) {
  BadLink link;
  link.text = std::string(text);
  auto malformed = [&] {
    return fail(fmt::format(
        "--bad-link {}: expected STATION:PORT@SECONDS[xFRAMES] (e.g. 0x3EB:0@1.2 or 1004:1@2x6)",
        text));
  };
  const std::size_t at = text.find('@');
  const std::size_t colon = text.find(':');
  if (at == std::string_view::npos || colon == std::string_view::npos || colon > at) {
    return malformed();
  }
  const std::string_view station = text.substr(0, colon);
  const std::string_view port = text.substr(colon + 1, at - colon - 1);
  std::string_view when = text.substr(at + 1);
  std::string_view frames;
  if (const std::size_t x = when.find('x'); x != std::string_view::npos) {
    frames = when.substr(x + 1);
    when = when.substr(0, x);
  }
  const std::optional<std::uint16_t> number = stationNumber(station);
  const Result<int> port_number = parseNumber<int>(port);
  const Result<double> seconds = parseNumber<double>(when);
  if (!number || !port_number || !seconds) return malformed();
  link.station = *number;
  link.port = static_cast<std::uint8_t>(std::clamp(*port_number, 0, 255));
  link.at_s = *seconds;
  if (*port_number != 0 && *port_number != 1) {
    return fail(
        fmt::format("--bad-link {}: port 0 (the cable from the slave before) or 1 (the "
                    "cable to the slave after)",
                    text));
  }
  if (!frames.empty()) {
    const Result<int> count = parseNumber<int>(frames);
    if (!count || *count < 1 || *count > 1000) {
      return fail(fmt::format("--bad-link {}: FRAMES from 1 to 1000", text));
    }
    link.frames = *count;
  }
  return link;
}

namespace {

// The bad links' and sync errors' slaves and times (docs/simulate.md#diagnosis); each turns
// --diagnosis on, whose polls read what they do.
Status checkSlaveFaults(SimOptions& o) {
  const int slaves = o.axes + *o.io_slaves + o.cia402_drives;
  const double earliest = (o.startup ? kStartupSeconds : 0.0) + 0.45;
  auto check = [&](const char* option, const std::string& text, std::uint16_t station,
                   double at_s) -> Status {
    const int position = station - kFirstStation;
    if (position < 0 || position >= slaves) {
      return fail(fmt::format("{} {}: station {} is not in the ring (0x{:04X} to 0x{:04X})", option,
                              text, station, kFirstStation, kFirstStation + slaves - 1));
    }
    if (at_s < earliest || at_s > *o.duration_s - 0.4) {
      return fail(fmt::format("{} {}: {} s is outside the quiet part of the run ({:g} s to {:g} s)",
                              option, text, at_s, earliest, *o.duration_s - 0.4));
    }
    if (o.mid_start != MidStart::None || o.scenario == Scenario::Incidents) {
      return fail(fmt::format(
          "{} {}: not with --start-in or --scenario incidents (which has its own with --diagnosis)",
          option, text));
    }
    o.diagnosis = true;
    return {};
  };
  for (const BadLink& link : o.bad_links) {
    if (Status placed = check("--bad-link", link.text, link.station, link.at_s); !placed) {
      return placed;
    }
    if (link.port == 1 && link.station - kFirstStation == slaves - 1) {
      return fail(fmt::format("--bad-link {}: the last slave's port 1 has no cable", link.text));
    }
  }
  for (const SlaveAt& sync : o.sync_errors) {
    if (Status placed = check("--sync-error", sync.text, sync.station, sync.at_s); !placed) {
      return placed;
    }
  }
  return {};
}

// The shapes of a machine's bus (docs/simulate.md#shapes), each within its range.
Status checkShapeOptions(const SimOptions& o) {
  if (o.cia402_drives < 0 || o.cia402_drives > 32) {
    return fail(fmt::format("--cia402 {}: from 0 to 32", o.cia402_drives));
  }
  if (o.io_task_us != 0) {
    if (o.io_task_us <= o.cycle_us || o.io_task_us % o.cycle_us != 0 || o.io_task_us > 100000) {
      return fail(
          fmt::format("--io-task-us {}: a multiple of the cycle ({} us) above it, at most 100000",
                      o.io_task_us, o.cycle_us));
    }
    if (*o.io_slaves == 0) return fail("--io-task-us needs terminals: give --io-slaves");
  }
  if (!(o.idle_s >= 0)) return fail(fmt::format("--idle {}: seconds, or all", o.idle_s));
  const bool idle = o.idle_all || o.idle_s > 0;
  if (idle && o.scenario == Scenario::Faults) return fail("--idle: not with --scenario faults");
  if (idle && o.scenario == Scenario::Incidents) {
    return fail("--idle: not with --scenario incidents");
  }
  if (o.idle_all && !o.faults.empty()) {
    return fail("--idle all: nothing is enabled, so no --fault can happen");
  }
  if (o.mid_start != MidStart::None && (o.scenario != Scenario::Commissioning || idle)) {
    return fail("--start-in: a commissioning run only, without --idle");
  }
  if (o.mid_start == MidStart::InFault && !o.mid_start_fault) {
    return fail("--start-in fault:RULE: no rule given");
  }
  return {};
}

// What the capturing PC does to the recording (docs/simulate.md#the-capturing-pc).
Status checkCaptureOptions(const SimOptions& o) {
  if (o.second_interface && !o.writes_pcapng) {
    return fail(
        "--second-interface: a pcap holds one interface; write a pcapng (--format pcapng or a "
        ".pcapng file)");
  }
  return {};
}

// The bus's numbers and its disturbances, each within its range.
Status checkBusOptions(SimOptions& o) {
  if (o.axes < 1 || o.axes > 32) return fail(fmt::format("--axes {}: from 1 to 32", o.axes));
  if (!o.io_slaves) o.io_slaves = defaultIoSlaves(o.image);
  if (*o.io_slaves < 0 || *o.io_slaves > 32) {
    return fail(fmt::format("--io-slaves {}: from 0 to 32", *o.io_slaves));
  }
  if (o.cycle_us < 125 || o.cycle_us > 10000) {
    return fail(fmt::format("--cycle-us {}: from 125 to 10000", o.cycle_us));
  }
  if (o.ready_mode != 0 && o.ready_mode != 1) {
    return fail(fmt::format("--ready-mode {}: 0 or 1", o.ready_mode));
  }
  // A fifth of a cycle either way keeps every interval under 1.5 cycles (COM-002).
  if (o.jitter_us < 0 || o.jitter_us > o.cycle_us / 5) {
    return fail(fmt::format("--jitter-us {}: from 0 to a fifth of the cycle ({})", o.jitter_us,
                            o.cycle_us / 5));
  }
  if (!(o.dc_drift_ppm >= -1000 && o.dc_drift_ppm <= 1000)) {
    return fail(fmt::format("--dc-drift {}: from -1000 to 1000 ppm", o.dc_drift_ppm));
  }
  if (!(o.loss >= 0 && o.loss <= 0.5)) return fail(fmt::format("--loss {}: from 0 to 0.5", o.loss));
  if (!(o.capture_loss >= 0 && o.capture_loss <= 0.5))
    return fail(fmt::format("--capture-loss {}: from 0 to 0.5", o.capture_loss));
  // The returned copy comes back before the next cycle's master copy, jitter and all.
  if (o.latency_us < 0 || o.latency_us > o.cycle_us / 2) {
    return fail(fmt::format("--latency-us {}: from 0 to half the cycle ({})", o.latency_us,
                            o.cycle_us / 2));
  }
  // Late, not lost: sent before the next cycle's earliest send, whatever the jitter.
  const int most_late_us = o.cycle_us - 2 * o.jitter_us - 1;
  for (const CycleDisturbance& late : o.late_cycles) {
    if (late.amount > most_late_us) {
      return fail(
          fmt::format("--late-cycle {}: at most {} us late (the cycle less twice the "
                      "jitter, less 1)",
                      late.text, most_late_us));
    }
  }
  if (Status shapes = checkShapeOptions(o); !shapes) return shapes;
  return checkCaptureOptions(o);
}

// The run's length (the scenario's when not given), and what the faults scenario needs.
Status checkDuration(SimOptions& o) {
  if (!o.duration_s) o.duration_s = defaultDuration(o.scenario);
  const double duration = *o.duration_s;
  if (!(duration >= 1.0 && duration <= 24 * 3600.0)) {
    return fail(fmt::format("--duration {}: from 1 s to 24 h", duration));
  }
  if (o.scenario == Scenario::Faults) {
    if (o.axes < 4) return fail("--scenario faults needs at least 4 axes");
    if (!o.startup)
      return fail("--scenario faults needs the start-up (its ESM faults happen there)");
    if (duration < defaultDuration(Scenario::Faults)) {
      return fail(fmt::format("--scenario faults needs --duration {} or more",
                              defaultDuration(Scenario::Faults)));
    }
  }
  if (o.scenario == Scenario::Incidents) {
    if (o.axes < 4) return fail("--scenario incidents needs at least 4 axes");
    if (duration < kIncidentsMinDuration) {
      return fail(
          fmt::format("--scenario incidents needs --duration {:g} or more", kIncidentsMinDuration));
    }
    // Its truth (--incidents-truth) lists the scenario's own incidents: nothing may add or hide
    // one.
    if (!o.faults.empty() || o.loss > 0 || o.capture_loss > 0 || !o.lost_cycles.empty()) {
      return fail(
          "--scenario incidents takes no --fault, --loss, --capture-loss or --lost-cycles "
          "(its truth lists its own incidents only)");
    }
  }
  return {};
}

// One --fault's time and axis, defaulted where not given, checked against the run and its recipe.
// `after_s`: the moment a --start-in capture begins, which a fault must come after.
Status placeFault(FaultRequest& f, const SimOptions& o, std::optional<double> after_s) {
  const double duration = *o.duration_s;
  const double start = o.startup ? kStartupSeconds : 0.0;
  const char* code = ruleDef(f.rule).code;
  const FaultRecipe* recipe = faultRecipe(f.rule);
  if (recipe == nullptr || !recipe->injectable()) {
    return fail(fmt::format("--fault {}: {}", f.text, faultDescription(f.rule)));
  }
  const FaultRecipe& r = *recipe;
  if (r.phase == FaultPhase::Startup) {
    if (o.mid_start != MidStart::None) {
      return fail(fmt::format("--fault {}: {} happens in the start-up, which --start-in cuts away",
                              f.text, code));
    }
    if (!o.startup)
      return fail(fmt::format("--fault {}: {} happens in the start-up", f.text, code));
    if (f.at_s) {
      return fail(
          fmt::format("--fault {}: {} happens in the start-up; give no @time", f.text, code));
    }
  } else {
    // After the start-up and the enables; in a commissioning run before the emergency stop
    // and the disables that end it (at 53 % and 85 % of the run), else before the end.
    double earliest = start + o.idle_s + 0.45;
    if (after_s) earliest = std::max(earliest, *after_s + 0.1);
    const double latest = o.scenario == Scenario::Commissioning
                              ? o.idle_s + 0.53 * (duration - o.idle_s) - 0.25
                              : duration - 0.4;
    if (latest < earliest) {
      return fail(fmt::format("--fault {}: the run is too short for a fault; use --duration {:g}",
                              f.text, o.scenario == Scenario::Commissioning ? 2.5 : 1.5));
    }
    if (!f.at_s) f.at_s = std::clamp(0.43 * duration, earliest, latest);
    if (*f.at_s < earliest || *f.at_s > latest) {
      return fail(
          fmt::format("--fault {}: {} s is outside the quiet part of the run ({:g} s to {:g} s)",
                      f.text, *f.at_s, earliest, latest));
    }
  }
  if (r.need == AxisNeed::None) {
    if (f.axis)
      return fail(fmt::format("--fault {}: {} concerns the whole bus; no :axis", f.text, code));
    return {};
  }
  if (!f.axis) {
    int axis = 2 % o.axes;
    if (r.need == AxisNeed::Incremental && !isIncrementalAxis(axis)) axis = o.axes > 1 ? 1 : -1;
    if (r.need == AxisNeed::Absolute && isIncrementalAxis(axis)) axis = 0;
    if (axis < 0) {
      return fail(fmt::format("--fault {}: {} needs an incremental axis (odd index): use --axes 2",
                              f.text, code));
    }
    f.axis = axis;
  }
  if (*f.axis >= o.axes) {
    return fail(
        fmt::format("--fault {}: axis {} does not exist (--axes {})", f.text, *f.axis, o.axes));
  }
  if (r.need == AxisNeed::Incremental && !isIncrementalAxis(*f.axis)) {
    return fail(fmt::format("--fault {}: {} needs an incremental axis (odd index)", f.text, code));
  }
  if (r.need == AxisNeed::Absolute && isIncrementalAxis(*f.axis)) {
    return fail(fmt::format("--fault {}: {} needs an absolute axis (even index)", f.text, code));
  }
  return {};
}

// --start-in fault:RULE: the fault it begins inside, placed before the others (added with the
// rule's defaults when no --fault names the rule), and its time, which the others come after.
Result<std::optional<double>> placeStartFault(SimOptions& o) {
  if (o.mid_start != MidStart::InFault) {
    if (o.mid_start == MidStart::None) return std::nullopt;
    const double start = o.startup ? kStartupSeconds : 0.0;
    return std::optional<double>(start + midStartRow(o.mid_start).after_plan_s);
  }
  auto inside = std::find_if(o.faults.begin(), o.faults.end(),
                             [&](const FaultRequest& f) { return f.rule == *o.mid_start_fault; });
  if (inside == o.faults.end()) {
    FaultRequest added;
    added.rule = *o.mid_start_fault;
    added.text = ruleDef(added.rule).code;
    inside = o.faults.insert(o.faults.begin(), std::move(added));
  }
  std::rotate(o.faults.begin(), inside, inside + 1);
  if (Status placed = placeFault(o.faults.front(), o, std::nullopt); !placed)
    return fail(placed.error());
  return o.faults.front().at_s;
}

}  // namespace

Status resolveOptions(SimOptions& o) {
  if (Status bus = checkBusOptions(o); !bus) return bus;
  if (Status duration = checkDuration(o); !duration) return duration;
  const Result<std::optional<double>> begins_s = placeStartFault(o);
  if (!begins_s) return fail(begins_s.error());
  if (Status slaves = checkSlaveFaults(o); !slaves) return slaves;
  const std::size_t placed_already = o.mid_start == MidStart::InFault ? 1 : 0;
  for (std::size_t i = placed_already; i < o.faults.size(); ++i) {
    if (Status placed = placeFault(o.faults[i], o, *begins_s); !placed) return placed;
  }
  for (const FaultRequest& f : o.faults) {
    if (faultRecipe(f.rule)->diagnosis) o.diagnosis = true;
  }
  // The polls go between the cycles: a returned copy must come back well inside one.
  if (o.diagnosis && o.latency_us > o.cycle_us / 4 - 2) {
    return fail(
        fmt::format("--latency-us {}: at most a quarter cycle less 2 ({}) with --diagnosis, "
                    "whose polls go between the cycles",
                    o.latency_us, o.cycle_us / 4 - 2));
  }
  return {};
}

}  // namespace ncservo::sim
