// `ncservo diff --format text|json|html` (docs/baselines.md#diff): two captures side by side.
#include <fmt/format.h>

#include <pugixml.hpp>
#include <sstream>

#include "ncservo/report/baseline.hpp"
#include "report_format.hpp"

namespace ncservo::report {

using detail::Json;

namespace {

// A quantile in microseconds, "-" where the side has none.
std::string us(const std::optional<double>& v) {
  return v ? fmt::format("{:.3f}", *v) : std::string("-");
}

std::string ppm(const std::optional<double>& v) {
  return v ? fmt::format("{:.3f}", *v) : std::string("-");
}

std::string axisText(const std::optional<std::string>& axis) {
  return axis ? *axis : std::string("bus");
}

// The rows of the timing table: what, BASE's value, NEW's.
struct TimingRow {
  std::string what;
  std::optional<double> base, next;
};
std::vector<TimingRow> timingRows(const CaptureDiff& d) {
  std::vector<TimingRow> rows;
  for (const auto& [name, base, next] : {std::tuple{"cycle", &d.base.cycle, &d.next.cycle},
                                         std::tuple{"latency", &d.base.latency, &d.next.latency}}) {
    rows.push_back({fmt::format("{} p50 (us)", name), base->p50, next->p50});
    rows.push_back({fmt::format("{} p99 (us)", name), base->p99, next->p99});
    rows.push_back({fmt::format("{} p99.9 (us)", name), base->p999, next->p999});
    rows.push_back({fmt::format("{} max (us)", name), base->max, next->max});
  }
  return rows;
}

// DC drift per station, in the order first seen (BASE, then NEW).
struct DcRow {
  std::string station;
  std::optional<double> base, next;
};
std::vector<DcRow> dcRows(const CaptureDiff& d) {
  std::vector<DcRow> rows;
  auto row = [&](const std::string& station) -> DcRow& {
    for (DcRow& r : rows) {
      if (r.station == station) return r;
    }
    rows.push_back({station, std::nullopt, std::nullopt});
    return rows.back();
  };
  for (const ReportedDc& s : d.base.dc) row(s.station).base = s.drift_ppm;
  for (const ReportedDc& s : d.next.dc) row(s.station).next = s.drift_ppm;
  return rows;
}

std::string findingLine(const ReportedFinding& f) {
  return fmt::format("{:<7} {} frame {} ({:.6f} s): {}", severityName(f.severity),
                     fingerprintText(f.fingerprint), f.frame, f.time, f.message);
}

std::string incidentLine(const ReportedIncident& i) {
  return fmt::format("{} frame {}{}", fingerprintText(i.fingerprint), i.frame,
                     i.text.empty() ? "" : ": " + i.text);
}

std::string summaryLine(const CaptureDiff& d) {
  return fmt::format(
      "findings: {} new, {} unchanged, {} absent; incidents: {} new, {} unchanged, "
      "{} absent",
      d.added.size(), d.unchanged, d.absent.size(), d.incidents_added.size(), d.incidents_unchanged,
      d.incidents_absent.size());
}

void writeDiffText(std::FILE* out, const CaptureDiff& d) {
  fmt::print(out, "base: {} ({}, {})\nnew:  {} ({}, {})\n", d.base_source, d.base.path,
             d.base.verdict, d.next_source, d.next.path, d.next.verdict);
  fmt::print(out, "{}\n", summaryLine(d));
  if (!d.groups.empty()) {
    fmt::print(out, "{:<8} {:<12} {:>6} {:>6} {:>6} {:>8} {:>10}\n", "rule", "axis", "base", "new",
               "added", "absent", "unchanged");
    for (const DiffGroup& g : d.groups) {
      fmt::print(out, "{:<8} {:<12} {:>6} {:>6} {:>6} {:>8} {:>10}\n", g.rule, axisText(g.axis),
                 g.base, g.next, g.added, g.absent, g.unchanged);
    }
  }
  for (const ReportedFinding& f : d.added) fmt::print(out, "new     {}\n", findingLine(f));
  for (const ReportedFinding& f : d.absent) fmt::print(out, "absent  {}\n", findingLine(f));
  for (const ReportedIncident& i : d.incidents_added)
    fmt::print(out, "new incident     {}\n", incidentLine(i));
  for (const ReportedIncident& i : d.incidents_absent)
    fmt::print(out, "absent incident  {}\n", incidentLine(i));
  fmt::print(out, "{:<20} {:>12} {:>12}\n", "timing", "base", "new");
  for (const TimingRow& r : timingRows(d)) {
    fmt::print(out, "{:<20} {:>12} {:>12}\n", r.what, us(r.base), us(r.next));
  }
  for (const DcRow& r : dcRows(d)) {
    fmt::print(out, "{:<20} {:>12} {:>12}\n", "dc drift " + r.station + " (ppm)", ppm(r.base),
               ppm(r.next));
  }
}

Json number(const std::optional<double>& v) {
  return v ? Json(*v) : Json(nullptr);
}

Json sideJson(const std::string& source, const ReportedCapture& c) {
  return {{"source", source},
          {"path", c.path},
          {"verdict", c.verdict},
          {"findings", c.findings.size()},
          {"incidents", c.incidents.size()}};
}

Json incidentJson(const ReportedIncident& i) {
  const IncidentFingerprint& f = i.fingerprint;
  return {{"kind", f.kind},
          {"axis_name", f.axis ? Json(*f.axis) : Json(nullptr)},
          {"cause", f.cause.empty() ? Json(nullptr) : Json(f.cause)},
          {"fingerprint", fingerprintText(f)},
          {"frame", i.frame},
          {"text", i.text}};
}

void writeDiffJson(std::FILE* out, const CaptureDiff& d) {
  Json groups = Json::array();
  for (const DiffGroup& g : d.groups) {
    groups.push_back({{"rule", g.rule},
                      {"axis_name", g.axis ? Json(*g.axis) : Json(nullptr)},
                      {"base", g.base},
                      {"new", g.next},
                      {"added", g.added},
                      {"absent", g.absent},
                      {"unchanged", g.unchanged}});
  }
  Json added = Json::array();
  for (const ReportedFinding& f : d.added) added.push_back(detail::reportedFindingJson(f, "new"));
  Json absent = Json::array();
  for (const ReportedFinding& f : d.absent)
    absent.push_back(detail::reportedFindingJson(f, "absent"));
  Json incidents_added = Json::array();
  for (const ReportedIncident& i : d.incidents_added) incidents_added.push_back(incidentJson(i));
  Json incidents_absent = Json::array();
  for (const ReportedIncident& i : d.incidents_absent) incidents_absent.push_back(incidentJson(i));
  auto series = [](const ReportedSeries& s) {
    return Json{{"count", s.count},
                {"p50", number(s.p50)},
                {"p99", number(s.p99)},
                {"p999", number(s.p999)},
                {"max", number(s.max)}};
  };
  Json dc = Json::array();
  for (const DcRow& r : dcRows(d)) {
    dc.push_back({{"station", r.station},
                  {"base_drift_ppm", number(r.base)},
                  {"new_drift_ppm", number(r.next)}});
  }
  const Json j{
      {"tool", {{"name", "ncservo"}, {"version", NCSERVO_VERSION}}},
      {"base", sideJson(d.base_source, d.base)},
      {"compared", sideJson(d.next_source, d.next)},
      {"summary",
       {{"new", d.added.size()}, {"unchanged", d.unchanged}, {"absent", d.absent.size()}}},
      {"by_rule", std::move(groups)},
      {"new", std::move(added)},
      {"absent", std::move(absent)},
      {"incidents",
       {{"new", std::move(incidents_added)},
        {"absent", std::move(incidents_absent)},
        {"unchanged", d.incidents_unchanged}}},
      {"timing",
       {{"cycle_us", {{"base", series(d.base.cycle)}, {"new", series(d.next.cycle)}}},
        {"latency_us", {{"base", series(d.base.latency)}, {"new", series(d.next.latency)}}},
        {"dc", std::move(dc)}}}};
  std::fputs((j.dump(2) + "\n").c_str(), out);
}

// A table of `head` and `rows`, each cell text (pugixml escapes it).
void table(pugi::xml_node parent, const std::vector<std::string>& head,
           const std::vector<std::vector<std::string>>& rows, const char* css = nullptr) {
  pugi::xml_node t = parent.append_child("table");
  if (css != nullptr) t.append_attribute("class") = css;
  pugi::xml_node tr = t.append_child("tr");
  for (const std::string& h : head) tr.append_child("th").text() = h.c_str();
  for (const std::vector<std::string>& row : rows) {
    pugi::xml_node r = t.append_child("tr");
    for (const std::string& cell : row) r.append_child("td").text() = cell.c_str();
  }
}

std::vector<std::string> findingRow(const char* state, const ReportedFinding& f) {
  return {state,
          severityName(f.severity),
          f.fingerprint.rule,
          axisText(f.fingerprint.axis),
          fmt::format("#{}", f.fingerprint.ordinal),
          fmt::format("{}", f.frame),
          fmt::format("{:.6f}", f.time),
          f.message};
}

// One self-contained page, styled as the report's (html_report.cpp); nothing runs in it.
void writeDiffHtml(std::FILE* out, const CaptureDiff& d) {
  pugi::xml_document doc;
  pugi::xml_node body = doc.append_child("body");
  body.append_child("h1").text() = "ncservo diff";
  table(body, {"", "file", "capture", "verdict", "findings", "incidents"},
        {{"base", d.base_source, d.base.path, d.base.verdict,
          fmt::format("{}", d.base.findings.size()), fmt::format("{}", d.base.incidents.size())},
         {"new", d.next_source, d.next.path, d.next.verdict,
          fmt::format("{}", d.next.findings.size()), fmt::format("{}", d.next.incidents.size())}});
  pugi::xml_node summary = body.append_child("p");
  summary.append_attribute("id") = "summary";
  summary.text() = summaryLine(d).c_str();
  body.append_child("h2").text() = "Findings by rule and axis";
  std::vector<std::vector<std::string>> groups;
  for (const DiffGroup& g : d.groups) {
    groups.push_back({g.rule, axisText(g.axis), fmt::format("{}", g.base),
                      fmt::format("{}", g.next), fmt::format("{}", g.added),
                      fmt::format("{}", g.absent), fmt::format("{}", g.unchanged)});
  }
  table(body, {"rule", "axis", "base", "new", "added", "absent", "unchanged"}, groups);
  body.append_child("h2").text() = "New and absent findings";
  std::vector<std::vector<std::string>> findings;
  for (const ReportedFinding& f : d.added) findings.push_back(findingRow("new", f));
  for (const ReportedFinding& f : d.absent) findings.push_back(findingRow("absent", f));
  table(body, {"", "severity", "rule", "axis", "ordinal", "frame", "time (s)", "message"}, findings,
        "findings");
  body.append_child("h2").text() = "Incidents";
  std::vector<std::vector<std::string>> incidents;
  for (const auto& [state, list] :
       {std::pair{"new", &d.incidents_added}, std::pair{"absent", &d.incidents_absent}}) {
    for (const ReportedIncident& i : *list) {
      const IncidentFingerprint& f = i.fingerprint;
      incidents.push_back({state, f.kind, axisText(f.axis), f.cause.empty() ? "-" : f.cause,
                           fmt::format("{}", i.frame), i.text});
    }
  }
  table(body, {"", "kind", "axis", "cause", "frame", "what"}, incidents);
  body.append_child("h2").text() = "Timing";
  std::vector<std::vector<std::string>> timing;
  for (const TimingRow& r : timingRows(d)) timing.push_back({r.what, us(r.base), us(r.next)});
  for (const DcRow& r : dcRows(d))
    timing.push_back({"dc drift " + r.station + " (ppm)", ppm(r.base), ppm(r.next)});
  table(body, {"", "base", "new"}, timing);
  std::ostringstream text;
  body.print(text, "", pugi::format_raw);
  fmt::print(out,
             "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
             "<title>ncservo diff: {} new, {} absent</title>\n<style>{}</style>\n</head>\n{}\n"
             "</html>\n",
             d.added.size(), d.absent.size(), detail::htmlStyle(), text.str());
}

struct DiffFormat {
  const char* name;
  void (*write)(std::FILE* out, const CaptureDiff& diff);
};
const DiffFormat kDiffFormats[] = {
    {"text", writeDiffText},
    {"json", writeDiffJson},
    {"html", writeDiffHtml},
};

}  // namespace

std::vector<std::string> diffFormatNames() {
  std::vector<std::string> names;
  for (const DiffFormat& f : kDiffFormats) names.emplace_back(f.name);
  return names;
}

void writeDiff(std::FILE* out, std::string_view format, const CaptureDiff& diff) {
  for (const DiffFormat& f : kDiffFormats) {
    if (format == f.name) f.write(out, diff);
  }
}

}  // namespace ncservo::report
