// `validate --format sarif`: SARIF 2.1.0, one run, a result per finding, a notification per
// capture not read to its end or not fully checked and per axis whose layout does not fit.
#include <fmt/format.h>

#include <filesystem>
#include <system_error>

#include "ncservo/base/text.hpp"
#include "report_format.hpp"

namespace ncservo::cli::detail {

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
         {"level", exitStatusOf(sink.policy, r) == kExitNoServo ? "error" : "note"},
         {"message", {{"text", fmt::format("{}: NO SERVO: {}", r.path, r.coverage.reason)}}},
         {"locations", where}});
  }
}

// A finding's place: the capture, the region of the file that stores its frame where that is
// known (a pcap has no lines), and the frame as a logical location (an element of the capture).
Json sarifLocation(const CaptureReport& r, std::size_t artifact, const Finding& f) {
  Json location = artifactLocation(r.path);
  location["index"] = artifact;
  Json physical{{"artifactLocation", std::move(location)}};
  const auto stored = std::lower_bound(r.frame_spans.begin(), r.frame_spans.end(), f.at.frame,
                                       [](const std::pair<std::uint64_t, RecordSpan>& s,
                                          std::uint64_t frame) { return s.first < frame; });
  if (stored != r.frame_spans.end() && stored->first == f.at.frame) {
    physical["region"] = {{"byteOffset", stored->second.offset},
                          {"byteLength", stored->second.length}};
  }
  const std::string frame = fmt::format("frame {}", f.at.frame);
  return {{"physicalLocation", std::move(physical)},
          {"logicalLocations",
           {{{"name", frame},
             {"fullyQualifiedName", fmt::format("{}/{}", r.path, frame)},
             {"kind", "element"}}}}};
}

}  // namespace

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
      results.push_back(
          {{"ruleId", rule.code},
           {"ruleIndex", static_cast<std::size_t>(&rule - kRules.data())},
           {"level", sarifLevel(f.severity)},
           {"message", {{"text", fmt::format("{} frame {}: {}", axis, f.at.frame, f.message)}}},
           {"locations", {sarifLocation(r, c, f)}},
           {"partialFingerprints",
            {{"ncservoFinding/v1", fmt::format("{}:{}:{}", rule.code, axis, f.since.frame)}}},
           {"properties",
            {{"frame", f.at.frame},
             {"since_frame", f.since.frame},
             {"time", seconds(r, f.at)},
             {"time_utc", utcOf(r, f.at)},
             {"axis", f.axis ? Json(*f.axis) : Json(nullptr)},
             {"axis_name", f.axis ? Json(axis) : Json(nullptr)},
             {"fingerprint", fingerprintText(r.fingerprintOf(f))}}}});
      // SARIF 2.1.0 §3.27.24 (docs/baselines.md).
      if (i < r.baseline_states.size() && r.baseline_states[i] != BaselineState::None)
        results.back()["baselineState"] = baselineStateName(r.baseline_states[i]);
    }
    // The baseline's findings not seen again: results whose baselineState is "absent", of level
    // "none" (no longer a problem), with the capture as their place.
    for (const ReportedFinding& f : r.baseline_absent) {
      const Result<const RuleDef*> rule = findRule(f.fingerprint.rule);
      Json result{{"ruleId", f.fingerprint.rule}};
      if (rule) result["ruleIndex"] = static_cast<std::size_t>(*rule - kRules.data());
      result["kind"] = "pass";
      result["level"] = "none";
      result["message"] = {
          {"text", fmt::format("{} baseline frame {}: {}", f.fingerprint.axis.value_or("bus"),
                               f.frame, f.message)}};
      result["locations"] = {
          {{"physicalLocation", {{"artifactLocation", {{"uri", r.path}, {"index", c}}}}}}};
      result["baselineState"] = "absent";
      result["properties"] = {{"baseline_frame", f.frame},
                              {"baseline_severity", severityName(f.severity)},
                              {"fingerprint", fingerprintText(f.fingerprint)}};
      results.push_back(std::move(result));
    }
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

}  // namespace ncservo::cli::detail
