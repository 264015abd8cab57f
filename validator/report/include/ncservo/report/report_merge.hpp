// `ncservo merge REPORT.json…` (docs/field.md#a-fleets-recordings): one report over the JSON
// reports of many captures, as a batch engine leaves them (one per capture or per batch): verdict
// counts, findings by rule and severity, incidents by cause and kind, the bus's counts, and the
// timing series merged exactly where the numbers allow (counts, extremes, mean and standard
// deviation always; the histograms where the captures' bins line up). Presentation only.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ncservo/base/error.hpp"

namespace ncservo::report {

// A timing series over many captures, in microseconds.
struct MergedSeries {
  std::uint64_t count = 0;
  double min = 0, max = 0;
  double sum = 0, sum_squares = 0;  // of the samples, from each capture's mean and stddev
  // Bins on one axis (each capture's bins shifted by its histogram_zero), in ns: from -> (to,
  // count). Exact while no two captures' bins overlap partially.
  std::map<std::int64_t, std::pair<std::int64_t, std::uint64_t>> bins;
  std::uint64_t under = 0, over = 0;       // beyond each capture's histogram
  std::optional<std::string> not_aligned;  // the first capture whose bins did not line up
  double mean() const;
  double stddev() const;  // population
  // The bin the nearest-rank quantile lies in ([from, to) µs); none when the bins did not line
  // up or it lies beyond them.
  std::optional<std::pair<double, double>> quantileBin(double q) const;
};

struct MergedReport {
  std::vector<std::string> reports;  // the files, in the order given
  std::uint64_t captures = 0;
  std::map<std::string, std::uint64_t> verdicts;  // "fail", "warn", "pass", "no servo", ...
  std::uint64_t frames = 0, cycles = 0;
  // Counts a report written before they existed lacks: none once one capture lacks them.
  std::optional<std::uint64_t> lost_cycles = 0, wkc_errors = 0;
  std::map<std::string, std::uint64_t> severities;        // findings by severity
  std::map<std::string, std::uint64_t> findings_by_rule;  // "SE-001"
  std::map<std::string, std::uint64_t> incidents_by_cause, incidents_by_kind;
  std::optional<MergedSeries> cycle, latency;
};

// Adds one JSON report of `validate` (every capture in it). Fails naming the file and what is
// wrong: missing, not JSON, not such a report; `merged` is then unchanged.
Status mergeReportFile(const std::string& path, MergedReport& merged);
Status mergeReportText(const std::string& text, const std::string& path, MergedReport& merged);

// The merged report as JSON (docs/field.md says its keys) and as text.
std::string mergedJson(const MergedReport& merged);
std::string mergedText(const MergedReport& merged);

}  // namespace ncservo::report
