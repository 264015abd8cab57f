// Baselines (docs/baselines.md): fingerprints, a JSON report read back, the matching, and the
// comparison of two captures that `ncservo diff` writes (report_diff.cpp).
#include "ncservo/report/baseline.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "ncservo/base/number.hpp"
#include "ncservo/incidents/incident.hpp"

namespace ncservo::report {

using Json = nlohmann::ordered_json;

std::string fingerprintText(const Fingerprint& f) {
  return fmt::format("{} {} #{}", f.rule, f.axis ? *f.axis : std::string("bus"), f.ordinal);
}

std::string fingerprintText(const IncidentFingerprint& f) {
  return fmt::format("{} {} {} #{}", f.kind, f.axis ? *f.axis : std::string("bus"), f.cause,
                     f.ordinal);
}

const char* baselineStateName(BaselineState state) {
  switch (state) {
    case BaselineState::New:
      return "new";
    case BaselineState::Unchanged:
      return "unchanged";
    case BaselineState::None:
      break;
  }
  return "";
}

namespace {

// nlohmann's checked access throws; a report that is not what `validate` writes is an error
// value naming the place (capture and finding).
struct Bad {
  std::string what;
};

const Json& member(const Json& object, const char* key, const std::string& where) {
  if (!object.is_object() || !object.contains(key))
    throw Bad{fmt::format("{}: no '{}'", where, key)};
  return object[key];
}

std::string text(const Json& object, const char* key, const std::string& where) {
  const Json& v = member(object, key, where);
  if (!v.is_string()) throw Bad{fmt::format("{}: '{}' is not a string", where, key)};
  return v.get<std::string>();
}

std::optional<std::string> optionalText(const Json& object, const char* key) {
  if (!object.is_object() || !object.contains(key) || !object[key].is_string()) return std::nullopt;
  return object[key].get<std::string>();
}

std::optional<double> optionalNumber(const Json& object, const char* key) {
  if (!object.is_object() || !object.contains(key) || !object[key].is_number()) return std::nullopt;
  return object[key].get<double>();
}

std::uint64_t count(const Json& object, const char* key) {
  if (!object.is_object() || !object.contains(key) || !object[key].is_number_unsigned()) return 0;
  return object[key].get<std::uint64_t>();
}

// The ordinal after a fingerprint's last '#' ("SE-001 axis0 #2": 2).
std::uint32_t ordinalOf(const std::string& fingerprint, const std::string& where) {
  const auto hash = fingerprint.rfind('#');
  const auto ordinal =
      hash == std::string::npos
          ? Result<std::uint32_t>(fail(""))
          : parseNumber<std::uint32_t>(std::string_view(fingerprint).substr(hash + 1));
  if (!ordinal || *ordinal == 0) {
    throw Bad{fmt::format("{}: fingerprint '{}' does not end in #N", where, fingerprint)};
  }
  return *ordinal;
}

// An incident as the report holds it; a report written before incidents had fingerprints gives
// none, and its ordinal is taken from the order (numberUnfingerprinted).
ReportedIncident incidentOf(const Json& i, const std::string& where) {
  ReportedIncident incident;
  incident.fingerprint.kind = optionalText(i, "kind").value_or("");
  incident.fingerprint.axis = optionalText(i, "axis_name");
  if (!incident.fingerprint.axis) incident.fingerprint.axis = optionalText(i, "station");
  if (i.contains("cause") && i["cause"].is_object()) {
    incident.fingerprint.cause = optionalText(i["cause"], "id").value_or("");
    incident.text = optionalText(i["cause"], "text").value_or("");
  }
  if (const std::optional<std::string> f = optionalText(i, "fingerprint")) {
    incident.fingerprint.ordinal = ordinalOf(*f, where);
  }
  incident.frame = count(i, "frame");
  return incident;
}

// Ordinals, in report order, for the incidents whose report gave none.
void numberUnfingerprinted(std::vector<ReportedIncident>& incidents) {
  std::map<IncidentFingerprint, std::uint32_t> seen;
  for (ReportedIncident& i : incidents) {
    if (i.fingerprint.ordinal != 0) continue;
    IncidentFingerprint key = i.fingerprint;
    i.fingerprint.ordinal = ++seen[key];
  }
}

ReportedFinding findingOf(const Json& f, const std::string& where) {
  ReportedFinding r;
  r.fingerprint.rule = text(f, "rule", where);
  const Json& axis_name = member(f, "axis_name", where);
  if (!axis_name.is_null() && !axis_name.is_string())
    throw Bad{where + ": 'axis_name' is neither a string nor null"};
  if (axis_name.is_string()) r.fingerprint.axis = axis_name.get<std::string>();
  // docs/baselines.md#fingerprints: "RULE AXIS #N"; the ordinal is what follows the last '#'.
  if (!f.contains("fingerprint")) {
    throw Bad{where +
              ": no 'fingerprint' (a report of an older ncservo: write it again with this one)"};
  }
  r.fingerprint.ordinal = ordinalOf(text(f, "fingerprint", where), where);
  const std::optional<Severity> severity = severityFromName(text(f, "severity", where));
  if (!severity) throw Bad{where + ": 'severity' is not error, warning or info"};
  r.severity = *severity;
  r.slug = optionalText(f, "slug").value_or("");
  if (f.contains("axis") && f["axis"].is_number_unsigned()) r.axis = f["axis"].get<std::uint16_t>();
  r.frame = count(f, "frame");
  r.since_frame = count(f, "since_frame");
  r.time = optionalNumber(f, "time").value_or(0);
  r.message = optionalText(f, "message").value_or("");
  return r;
}

ReportedSeries seriesOf(const Json& timing, const char* key) {
  ReportedSeries s;
  if (!timing.is_object() || !timing.contains(key) || !timing[key].is_object()) return s;
  const Json& series = timing[key];
  s.count = count(series, "count");
  s.p50 = optionalNumber(series, "median");
  s.p99 = optionalNumber(series, "p99");
  s.p999 = optionalNumber(series, "p999");
  s.max = optionalNumber(series, "max");
  return s;
}

ReportedCapture captureOf(const Json& c, const std::string& where) {
  ReportedCapture r;
  r.path = text(c, "path", where);
  r.verdict = optionalText(c, "verdict").value_or("");
  const Json& findings = member(c, "findings", where);
  if (!findings.is_array()) throw Bad{where + ": 'findings' is not a list"};
  for (std::size_t i = 0; i < findings.size(); ++i) {
    r.findings.push_back(findingOf(findings[i], fmt::format("{}, finding {}", where, i + 1)));
  }
  // Incidents (docs/cli.md), where the report has them.
  if (c.contains("incidents") && c["incidents"].is_array()) {
    const Json& incidents = c["incidents"];
    for (std::size_t i = 0; i < incidents.size(); ++i) {
      r.incidents.push_back(incidentOf(incidents[i], fmt::format("{}, incident {}", where, i + 1)));
    }
    numberUnfingerprinted(r.incidents);
  }
  if (c.contains("timing") && c["timing"].is_object()) {
    const Json& timing = c["timing"];
    r.cycle = seriesOf(timing, "cycle_us");
    r.latency = seriesOf(timing, "latency_us");
    if (timing.contains("dc") && timing["dc"].is_array()) {
      for (const Json& d : timing["dc"]) {
        r.dc.push_back({optionalText(d, "station").value_or("?"), optionalNumber(d, "drift_ppm")});
      }
    }
  }
  return r;
}

}  // namespace

Result<ReportFile> parseReportFile(std::string_view text_, const std::string& path) {
  const Json j = Json::parse(text_.begin(), text_.end(), nullptr, false);
  if (j.is_discarded()) return fail(Error{path, 0, 0, {}, "not JSON"});
  try {
    if (!j.is_object() || !j.contains("captures") || !j["captures"].is_array()) {
      throw Bad{"not a report of 'ncservo validate --format json' (no 'captures' list)"};
    }
    ReportFile file{path, {}};
    const Json& captures = j["captures"];
    for (std::size_t i = 0; i < captures.size(); ++i) {
      file.captures.push_back(captureOf(captures[i], fmt::format("capture {}", i + 1)));
    }
    return file;
  } catch (const Bad& bad) {
    return fail(Error{path, 0, 0, {}, bad.what});
  } catch (const Json::exception& e) {
    return fail(Error{path, 0, 0, {}, e.what()});
  }
}

Result<ReportFile> loadReportFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return fail(Error{path, 0, 0, {}, "a directory"});
  std::ifstream in(path, std::ios::binary);
  if (!in) return fail(Error{path, 0, 0, {}, std::strerror(errno)});
  std::ostringstream content;
  content << in.rdbuf();
  return parseReportFile(content.str(), path);
}

bool looksLikeJsonReport(const std::string& path) {
  if (path == "-") return false;
  std::ifstream in(path, std::ios::binary);
  char c = 0;
  while (in.get(c)) {
    if (c != ' ' && c != '\n' && c != '\r' && c != '\t') return c == '{';
  }
  return false;
}

const ReportedCapture* baselineCaptureFor(const ReportFile& baseline, const std::string& path,
                                          std::size_t run_captures) {
  const std::string name = std::filesystem::path(path).filename().string();
  const ReportedCapture* named = nullptr;
  for (const ReportedCapture& c : baseline.captures) {
    if (std::filesystem::path(c.path).filename().string() != name) continue;
    if (named != nullptr) return nullptr;  // two of that name: neither is the one
    named = &c;
  }
  if (named != nullptr) return named;
  if (baseline.captures.size() == 1 && run_captures == 1) return &baseline.captures.front();
  return nullptr;
}

namespace {

DiffGroup& groupOf(std::vector<DiffGroup>& groups, const Fingerprint& f) {
  for (DiffGroup& g : groups) {
    if (g.rule == f.rule && g.axis == f.axis) return g;
  }
  groups.push_back({f.rule, f.axis});
  return groups.back();
}

}  // namespace

CaptureDiff diffCaptures(ReportedCapture base, ReportedCapture next) {
  CaptureDiff diff;
  for (const ReportedFinding& f : base.findings) ++groupOf(diff.groups, f.fingerprint).base;
  BaselineMatcher matcher(&base);
  for (const ReportedFinding& f : next.findings) {
    DiffGroup& g = groupOf(diff.groups, f.fingerprint);
    ++g.next;
    if (matcher.match(f.fingerprint) == BaselineState::New) {
      ++g.added;
      diff.added.push_back(f);
    } else {
      ++g.unchanged;
      ++diff.unchanged;
    }
  }
  diff.absent = matcher.absent();
  for (const ReportedFinding& f : diff.absent) ++groupOf(diff.groups, f.fingerprint).absent;
  // Incidents are matched as findings are, by their fingerprints (docs/baselines.md#ncservo-diff).
  for (const ReportedIncident& i : next.incidents) {
    if (matcher.match(i.fingerprint) == BaselineState::New) {
      diff.incidents_added.push_back(i);
    } else {
      ++diff.incidents_unchanged;
    }
  }
  diff.incidents_absent = matcher.absentIncidents();
  diff.base = std::move(base);
  diff.next = std::move(next);
  return diff;
}

}  // namespace ncservo::report
