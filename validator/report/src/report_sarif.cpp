// `validate --format sarif`: SARIF 2.1.0, one run, a result per finding, a notification per
// capture not read to its end or not fully checked and per axis whose layout does not fit.
#include <fmt/format.h>

#include <filesystem>
#include <system_error>

#include "ncservo/base/text.hpp"
#include "ncservo/incidents/causes.hpp"
#include "report_format.hpp"

namespace ncservo::report::detail {

namespace {

// The base a capture named by a relative path is relative to: the directory validate ran in, which
// the run's originalUriBaseIds gives as an absolute file: URI (SARIF 2.1.0 §3.4.4, §3.14.14).
constexpr const char* kCaptureBase = "SRCROOT";

// Where a capture is, as SARIF's artifactLocation has it: a URI reference (RFC 3986), percent-
// encoded; relative to kCaptureBase when the capture was named by a relative path, a file: URI
// when by an absolute one, and only a description for standard input.
Json artifactLocation(const std::string& path) {
  if (path == "-") return {{"description", {{"text", "standard input"}}}};
  if (!path.empty() && path.front() == '/') return {{"uri", fileUri(path)}};
  return {{"uri", uriPath(path)}, {"uriBaseId", kCaptureBase}};
}

// The absolute URI of kCaptureBase, ending in "/" as §3.14.14 asks.
Json originalUriBaseIds() {
  std::error_code ec;
  std::string directory = std::filesystem::current_path(ec).string();
  if (ec) return nullptr;
  if (directory.empty() || directory.back() != '/') directory += '/';
  return {{kCaptureBase, {{"uri", fileUri(directory)}}}};
}

const char* sarifLevel(Severity s) {
  switch (s) {
    case Severity::Error:
      return "error";
    case Severity::Warning:
      return "warning";
    case Severity::Info:
      return "note";
  }
  return "note";
}

// A capture is a notification, not a result (SARIF 2.1.0 §3.58), where it could not be read to its
// end, not every axis was checked or an axis's layout does not fit: nothing there was found, nor
// shown to be right.
void addNotifications(const ReportSink& sink, const CaptureReport& r, std::size_t artifact,
                      Json& notifications) {
  Json location = artifactLocation(r.path);
  location["index"] = artifact;
  const Json where = {{{"physicalLocation", {{"artifactLocation", std::move(location)}}}}};
  if (r.error) {
    notifications.push_back({{"descriptor", {{"id", "UNREADABLE"}}},
                             {"level", "error"},
                             {"message", {{"text", fmt::format("{}: {}", r.path, *r.error)}}},
                             {"locations", where}});
  }
  // A configured or ENI layout that does not fit (docs/layout.md#a-layout-that-does-not-fit):
  // not a rule's finding, but what makes the axis's findings untrustworthy.
  for (const std::string& warning : r.layout_warnings) {
    notifications.push_back(
        {{"descriptor", {{"id", "LAYOUT-FIT"}}},
         {"level", "warning"},
         {"message", {{"text", fmt::format("{}: layout does not fit: {}", r.path, warning)}}},
         {"locations", where}});
  }
  if (!r.unopened() && !r.coverage.complete()) {
    notifications.push_back(
        {{"descriptor", {{"id", "NO-SERVO"}}},
         {"level", sink.judge.failsUnchecked(r) ? "error" : "note"},
         {"message", {{"text", fmt::format("{}: NO SERVO: {}", r.path, r.coverage.reason)}}},
         {"locations", where}});
  }
}

// Where a result is: the capture, at line 1 (GitHub's code scanning takes no location without a
// startLine, and a capture has no lines), the frame as a logical location (an element of the
// capture), and, where known, the frame's record in the file as a related location's binary
// region (docs/cli.md#sarif).
Json sarifPlace(const CaptureReport& r, std::size_t artifact, std::uint64_t frame_number,
                Json& result) {
  Json location = artifactLocation(r.path);
  location["index"] = artifact;
  const std::string frame = fmt::format("frame {}", frame_number);
  const auto stored = std::lower_bound(r.frame_spans.begin(), r.frame_spans.end(), frame_number,
                                       [](const std::pair<std::uint64_t, RecordSpan>& s,
                                          std::uint64_t wanted) { return s.first < wanted; });
  if (stored != r.frame_spans.end() && stored->first == frame_number) {
    result["relatedLocations"] = {
        {{"id", 1},
         {"physicalLocation",
          {{"artifactLocation", location},
           {"region",
            {{"byteOffset", stored->second.offset}, {"byteLength", stored->second.length}}}}},
         {"message", {{"text", fmt::format("the record of {} in the file", frame)}}}}};
  }
  return {{{"physicalLocation",
            {{"artifactLocation", std::move(location)}, {"region", {{"startLine", 1}}}}},
           {"logicalLocations",
            {{{"name", frame},
              {"fullyQualifiedName", fmt::format("{}/{}", r.path, frame)},
              {"kind", "element"}}}}}};
}

// The rules of the incidents' causes (docs/incidents.md#causes), after the catalogue's rules.
void addIncidentRules(Json& rules) {
  for (const CauseDef& cause : kCauses) {
    rules.push_back(
        {{"id", incidentRuleId(cause.id)},
         {"name", fmt::format("incident-{}", cause.name)},
         {"shortDescription", {{"text", cause.when}}},
         {"helpUri", fmt::format("{}/blob/main/docs/incidents.md#causes", kRepositoryUri)},
         {"defaultConfiguration", {{"level", "error"}}}});
  }
}

std::size_t incidentRuleIndex(CauseId cause) {
  return kRules.size() + static_cast<std::size_t>(cause);
}

// Each incident a result of its cause's rule: level error when --fail-on-incident gates it.
void addIncidentResults(const ReportSink& sink, const CaptureReport& r, std::size_t artifact,
                        Json& results) {
  for (std::size_t i = 0; i < r.incidents.size(); ++i) {
    const Incident& incident = r.incidents[i];
    const std::string fingerprint = fingerprintText(r.fingerprintOf(incident));
    Json result{{"ruleId", incidentRuleId(incident.cause)},
                {"ruleIndex", incidentRuleIndex(incident.cause)},
                {"level", sink.judge.failsIncident(r, i) ? "error" : "warning"},
                {"message", {{"text", incidentSummary(r, incident)}}}};
    result["locations"] = sarifPlace(r, artifact, incident.at.frame, result);
    result["partialFingerprints"] = {{"ncservoIncident/v1", fingerprint}};
    result["properties"] = {
        {"kind", incidentKindName(incident.kind)},
        {"frame", incident.at.frame},
        {"time", seconds(r, incident.at)},
        {"time_utc", utcOf(r, incident.at)},
        {"axis", incident.axis ? Json(*incident.axis) : Json(nullptr)},
        {"axis_name", incident.axis ? Json(axisLabel(r, incident.axis)) : Json(nullptr)},
        {"cause", causeDef(incident.cause).name},
        {"fingerprint", fingerprint}};
    if (i < r.incident_states.size())
      result["baselineState"] = baselineStateName(r.incident_states[i]);
    results.push_back(std::move(result));
  }
}

// The baseline's results not seen again: baselineState "absent", of level "none" (no longer a
// problem), with the capture as their place.
Json absentResult(const CaptureReport& r, std::size_t artifact, const std::string& rule_id,
                  std::optional<std::size_t> rule_index, const std::string& text) {
  Json result{{"ruleId", rule_id}};
  if (rule_index) result["ruleIndex"] = *rule_index;
  result["kind"] = "pass";
  result["level"] = "none";
  result["message"] = {{"text", text}};
  result["locations"] = {{{"physicalLocation",
                           {{"artifactLocation", {{"uri", r.path}, {"index", artifact}}},
                            {"region", {{"startLine", 1}}}}}}};
  result["baselineState"] = "absent";
  return result;
}

void addAbsentResults(const CaptureReport& r, std::size_t artifact, Json& results) {
  for (const ReportedFinding& f : r.baseline_absent) {
    const Result<const RuleDef*> rule = findRule(f.fingerprint.rule);
    Json result = absentResult(
        r, artifact, f.fingerprint.rule,
        rule ? std::optional(static_cast<std::size_t>(*rule - kRules.data())) : std::nullopt,
        fmt::format("{} baseline frame {}: {}", f.fingerprint.axis.value_or("bus"), f.frame,
                    f.message));
    result["properties"] = {{"baseline_frame", f.frame},
                            {"baseline_severity", severityName(f.severity)},
                            {"fingerprint", fingerprintText(f.fingerprint)}};
    results.push_back(std::move(result));
  }
  for (const ReportedIncident& i : r.baseline_absent_incidents) {
    const std::optional<CauseId> cause = findCause(i.fingerprint.cause);
    Json result = absentResult(
        r, artifact, "INC-" + i.fingerprint.cause,
        cause ? std::optional(incidentRuleIndex(*cause)) : std::nullopt,
        fmt::format("{} baseline frame {}: {}", fingerprintText(i.fingerprint), i.frame, i.text));
    result["properties"] = {{"baseline_frame", i.frame},
                            {"fingerprint", fingerprintText(i.fingerprint)}};
    results.push_back(std::move(result));
  }
}

}  // namespace

std::string incidentRuleId(CauseId cause) {
  return fmt::format("INC-{}", causeDef(cause).name);
}

void writeSarif(const ReportSink& sink, const std::vector<CaptureReport>& reports) {
  Json rules = Json::array();
  for (const RuleDef& rule : kRules) {
    rules.push_back({{"id", rule.code},
                     {"name", rule.slug},
                     {"shortDescription", {{"text", rule.summary}}},
                     {"helpUri", ruleHelpUri(rule)},
                     {"defaultConfiguration", {{"level", sarifLevel(rule.severity)}}},
                     {"properties", {{"party", partyName(rule.party)}, {"clause", rule.clause}}}});
  }
  addIncidentRules(rules);
  Json results = Json::array();
  Json artifacts = Json::array();
  Json notifications = Json::array();
  bool all_read = true;
  bool relative = false;  // a capture named by a relative path
  for (std::size_t c = 0; c < reports.size(); ++c) {
    const CaptureReport& r = reports[c];
    artifacts.push_back({{"location", artifactLocation(r.path)}});
    relative = relative || artifacts.back()["location"].contains("uriBaseId");
    addNotifications(sink, r, c, notifications);
    all_read = all_read && !r.error;
    for (std::size_t i = 0; i < r.findings.size(); ++i) {
      const Finding& f = r.findings[i];
      const RuleDef& rule = ruleDef(f.rule);
      const std::string axis = axisLabel(r, f.axis);
      Json result{
          {"ruleId", rule.code},
          {"ruleIndex", static_cast<std::size_t>(&rule - kRules.data())},
          {"level", sarifLevel(f.severity)},
          {"message", {{"text", fmt::format("{} frame {}: {}", axis, f.at.frame, f.message)}}}};
      result["locations"] = sarifPlace(r, c, f.at.frame, result);
      result["partialFingerprints"] = {
          {"ncservoFinding/v1", fmt::format("{}:{}:{}", rule.code, axis, f.since.frame)}};
      result["properties"] = {{"frame", f.at.frame},
                              {"since_frame", f.since.frame},
                              {"time", seconds(r, f.at)},
                              {"time_utc", utcOf(r, f.at)},
                              {"axis", f.axis ? Json(*f.axis) : Json(nullptr)},
                              {"axis_name", f.axis ? Json(axis) : Json(nullptr)},
                              {"fingerprint", fingerprintText(r.fingerprintOf(f))}};
      // SARIF 2.1.0 §3.27.24 (docs/baselines.md).
      if (i < r.baseline_states.size() && r.baseline_states[i] != BaselineState::None)
        result["baselineState"] = baselineStateName(r.baseline_states[i]);
      results.push_back(std::move(result));
    }
    addIncidentResults(sink, r, c, results);
    addAbsentResults(r, c, results);
  }
  // executionSuccessful (§3.20.14): false where a capture could not be read (exit status 3).
  Json invocation{{"executionSuccessful", all_read}};
  if (!notifications.empty()) invocation["toolExecutionNotifications"] = std::move(notifications);
  Json run{{"tool",
            {{"driver",
              {{"name", "ncservo"},
               {"version", NCSERVO_VERSION},
               {"informationUri", kRepositoryUri},
               {"rules", std::move(rules)}}}}},
           {"invocations", {std::move(invocation)}}};
  if (Json bases = originalUriBaseIds(); relative && !bases.is_null()) {
    run["originalUriBaseIds"] = std::move(bases);
  }
  run["artifacts"] = std::move(artifacts);
  run["results"] = std::move(results);
  Json sarif{{"$schema", "https://json.schemastore.org/sarif-2.1.0.json"},
             {"version", "2.1.0"},
             {"runs", {std::move(run)}}};
  std::fputs((sarif.dump(2) + "\n").c_str(), sink.out);
}

}  // namespace ncservo::report::detail
