#include "ncservo/report/report_merge.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>

namespace ncservo::report {

namespace {

using Json = nlohmann::ordered_json;

std::int64_t ns(double us) {
  return std::llround(us * 1000.0);
}

// One capture's series into the merged one; its bins shifted onto one axis by histogram_zero
// (the median in reports written before it was given).
void mergeSeries(const Json& s, const std::string& where, std::optional<MergedSeries>& into) {
  if (!s.is_object() || s.value("count", 0ull) == 0) return;
  if (!into) {
    into.emplace();
    into->min = s.at("min").get<double>();
    into->max = s.at("max").get<double>();
  }
  MergedSeries& m = *into;
  const auto n = s.at("count").get<std::uint64_t>();
  const double mean = s.at("mean").get<double>();
  const double stddev = s.at("stddev").get<double>();
  m.count += n;
  m.min = std::min(m.min, s.at("min").get<double>());
  m.max = std::max(m.max, s.at("max").get<double>());
  m.sum += mean * static_cast<double>(n);
  m.sum_squares += (stddev * stddev + mean * mean) * static_cast<double>(n);
  m.under += s.value("under", 0ull);
  m.over += s.value("over", 0ull);
  const double zero = s.contains("histogram_zero") ? s.at("histogram_zero").get<double>()
                                                   : s.at("median").get<double>();
  for (const Json& bin : s.at("histogram")) {
    const std::int64_t from = ns(zero + bin.at("from_us").get<double>());
    const std::int64_t to = ns(zero + bin.at("to_us").get<double>());
    const auto count = bin.at("count").get<std::uint64_t>();
    auto at = m.bins.lower_bound(from);
    bool aligned = true;
    if (at != m.bins.end() && at->first == from) {
      aligned = at->second.first == to;
    } else {
      aligned = (at == m.bins.end() || at->first >= to) &&
                (at == m.bins.begin() || std::prev(at)->second.first <= from);
    }
    if (!aligned) {
      if (!m.not_aligned) m.not_aligned = where;
      continue;
    }
    if (at != m.bins.end() && at->first == from) {
      at->second.second += count;
    } else {
      m.bins.emplace(from, std::make_pair(to, count));
    }
  }
}

void add(std::map<std::string, std::uint64_t>& counts, const std::string& key,
         std::uint64_t n = 1) {
  counts[key] += n;
}

// A count of the bus a report written before it existed lacks: then none.
void addOptional(std::optional<std::uint64_t>& total, const Json& timing, const char* key) {
  if (total && timing.is_object() && timing.contains(key)) {
    *total += timing.at(key).get<std::uint64_t>();
  } else {
    total.reset();
  }
}

}  // namespace

double MergedSeries::mean() const {
  return count == 0 ? 0 : sum / static_cast<double>(count);
}

double MergedSeries::stddev() const {
  if (count == 0) return 0;
  const double m = mean();
  return std::sqrt(std::max(0.0, sum_squares / static_cast<double>(count) - m * m));
}

std::optional<std::pair<double, double>> MergedSeries::quantileBin(double q) const {
  if (not_aligned || count == 0) return std::nullopt;
  const auto rank = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count)));
  std::uint64_t seen = under;
  if (seen >= std::max<std::uint64_t>(rank, 1)) return std::nullopt;
  for (const auto& [from, bin] : bins) {
    seen += bin.second;
    if (seen >= rank) return std::make_pair(from / 1000.0, bin.first / 1000.0);
  }
  return std::nullopt;
}

Status mergeReportText(const std::string& text, const std::string& path, MergedReport& merged) {
  Json report;
  try {
    report = Json::parse(text);
  } catch (const Json::parse_error& e) {
    // Not e.what(): it quotes what it read, the bytes of a capture given by mistake.
    return fail(Error{path, 0, 0, {}, fmt::format("not JSON (at byte {})", e.byte)});
  }
  const auto not_report = [&path](const std::string& why) {
    return fail(
        Error{path, 0, 0, {}, "not a JSON report of ncservo validate (--format json): " + why});
  };
  if (!report.is_object() || !report.contains("captures") || !report["captures"].is_array()) {
    return not_report("no 'captures' list");
  }
  MergedReport next = merged;
  try {
    for (const Json& capture : report["captures"]) {
      const std::string where = fmt::format("{}: {}", path, capture.value("path", "?"));
      ++next.captures;
      add(next.verdicts, capture.at("verdict").get<std::string>());
      next.frames += capture.value("frames", 0ull);
      next.cycles += capture.value("cycles", 0ull);
      const Json timing = capture.value("timing", Json());
      addOptional(next.lost_cycles, timing, "lost_cycles");
      addOptional(next.wkc_errors, timing, "wkc_errors");
      for (const Json& f : capture.value("findings", Json::array())) {
        add(next.findings_by_rule, f.at("rule").get<std::string>());
        add(next.severities, f.at("severity").get<std::string>());
      }
      for (const Json& i : capture.value("incidents", Json::array())) {
        add(next.incidents_by_cause, i.at("cause").at("id").get<std::string>());
        add(next.incidents_by_kind, i.at("kind").get<std::string>());
      }
      if (timing.is_object()) {
        mergeSeries(timing.value("cycle_us", Json()), where, next.cycle);
        mergeSeries(timing.value("latency_us", Json()), where, next.latency);
      }
    }
  } catch (const Json::exception& e) {
    return not_report(e.what());
  }
  next.reports.push_back(path);
  merged = std::move(next);
  return {};
}

Status mergeReportFile(const std::string& path, MergedReport& merged) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return fail(Error{path, 0, 0, {}, "cannot read it"});
  std::ostringstream text;
  text << in.rdbuf();
  return mergeReportText(text.str(), path, merged);
}

namespace {

Json seriesJson(const std::optional<MergedSeries>& series) {
  if (!series) return nullptr;
  const MergedSeries& s = *series;
  auto us = [](double v) { return std::round(v * 1000.0) / 1000.0; };
  Json j{{"count", s.count},
         {"min", us(s.min)},
         {"max", us(s.max)},
         {"mean", us(s.mean())},
         {"stddev", us(s.stddev())}};
  if (s.not_aligned) {
    j["histogram"] = nullptr;
    j["histogram_not_merged"] =
        *s.not_aligned +
        ": its bins do not line up with those before (medians a fraction of a "
        "bin apart): no histogram or quantile over all";
    return j;
  }
  Json bins = Json::array();
  for (const auto& [from, bin] : s.bins) {
    bins.push_back(
        {{"from_us", from / 1000.0}, {"to_us", bin.first / 1000.0}, {"count", bin.second}});
  }
  j["histogram"] = std::move(bins);
  j["under"] = s.under;
  j["over"] = s.over;
  for (const auto& [name, q] :
       {std::pair{"p50_bin", 0.5}, {"p99_bin", 0.99}, {"p999_bin", 0.999}}) {
    const auto bin = s.quantileBin(q);
    j[name] = bin ? Json::array({bin->first, bin->second}) : Json(nullptr);
  }
  return j;
}

Json optionalJson(const std::optional<std::uint64_t>& value) {
  return value ? Json(*value) : Json(nullptr);
}

}  // namespace

std::string mergedJson(const MergedReport& m) {
  const Json j{
      {"tool", {{"name", "ncservo"}, {"version", NCSERVO_VERSION}}},
      {"reports", m.reports},
      {"captures", m.captures},
      {"verdicts", m.verdicts},
      {"frames", m.frames},
      {"cycles", m.cycles},
      {"lost_cycles", optionalJson(m.lost_cycles)},
      {"wkc_errors", optionalJson(m.wkc_errors)},
      {"findings", {{"by_severity", m.severities}, {"by_rule", m.findings_by_rule}}},
      {"incidents", {{"by_cause", m.incidents_by_cause}, {"by_kind", m.incidents_by_kind}}},
      {"timing", {{"cycle_us", seriesJson(m.cycle)}, {"latency_us", seriesJson(m.latency)}}}};
  return j.dump(2) + "\n";
}

namespace {

std::string countsText(const std::map<std::string, std::uint64_t>& counts) {
  std::vector<std::string> parts;
  for (const auto& [name, n] : counts) parts.push_back(fmt::format("{} {}", n, name));
  return parts.empty() ? "none" : fmt::format("{}", fmt::join(parts, ", "));
}

std::string seriesText(const char* name, const std::optional<MergedSeries>& s) {
  if (!s) return fmt::format("{}: none\n", name);
  std::string text =
      fmt::format("{}: {} samples, mean {:.3f} µs, stddev {:.3f} µs, min {:.3f} µs, max {:.3f} µs",
                  name, s->count, s->mean(), s->stddev(), s->min, s->max);
  if (const auto p99 = s->quantileBin(0.99)) {
    text += fmt::format("; p99 in [{:.3f}, {:.3f}) µs", p99->first, p99->second);
  } else if (s->not_aligned) {
    text += fmt::format("; no quantile over all ({}: bins not lined up)", *s->not_aligned);
  }
  return text + "\n";
}

}  // namespace

std::string mergedText(const MergedReport& m) {
  std::string text = fmt::format("{} reports, {} captures: {}\n", m.reports.size(), m.captures,
                                 countsText(m.verdicts));
  text += fmt::format("frames {}, cycles {}, lost cycles {}, wrong WKCs {}\n", m.frames, m.cycles,
                      m.lost_cycles ? fmt::format("{}", *m.lost_cycles) : "not in every report",
                      m.wkc_errors ? fmt::format("{}", *m.wkc_errors) : "not in every report");
  text += fmt::format("findings: {}\n", countsText(m.severities));
  for (const auto& [rule, n] : m.findings_by_rule) text += fmt::format("  {:<8} {}\n", rule, n);
  text += fmt::format("incidents: {}\n", countsText(m.incidents_by_kind));
  for (const auto& [cause, n] : m.incidents_by_cause)
    text += fmt::format("  {:<28} {}\n", cause, n);
  text += seriesText("cycle time", m.cycle);
  text += seriesText("return latency", m.latency);
  return text;
}

}  // namespace ncservo::report
