// Baselines and comparisons (docs/baselines.md): a finding's fingerprint, a JSON report of
// `validate` read back, the matching of a capture's findings against it (`validate --baseline`),
// and `ncservo diff` of two captures or reports. Presentation only: what is compared is what the
// JSON report holds.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/rules/rules.hpp"

namespace ncservo::report {

// What a finding is matched by (docs/baselines.md#fingerprints): its rule, its axis's name (none:
// the bus) and its ordinal among that rule's findings on that axis in its capture segment.
struct Fingerprint {
  std::string rule;                 // "SE-001"
  std::optional<std::string> axis;  // the axis's name; none for the bus
  std::uint32_t ordinal = 0;
  auto operator<=>(const Fingerprint&) const = default;
};
// "SE-001 axis0 #2", "COM-002 bus #1": the JSON report's `fingerprint`.
std::string fingerprintText(const Fingerprint& fingerprint);

// What an incident is matched by (docs/baselines.md#fingerprints): its kind, its axis's name (or
// its slave's station, none for the bus), its cause's id and its ordinal among the incidents of
// those three in its capture segment.
struct IncidentFingerprint {
  std::string kind;                 // "drive-fault"
  std::optional<std::string> axis;  // "axis2", "0x1002"; none for the bus
  std::string cause;                // "encoder"
  std::uint32_t ordinal = 0;
  auto operator<=>(const IncidentFingerprint&) const = default;
};
// "drive-fault axis2 encoder #1": the JSON report's incident `fingerprint`.
std::string fingerprintText(const IncidentFingerprint& fingerprint);

// A finding against a baseline; None without one.
enum class BaselineState : std::uint8_t { None, New, Unchanged };
// "new", "unchanged" (and "" for None), as JSON, JSON Lines and SARIF name them.
const char* baselineStateName(BaselineState state);

// A finding as a JSON report holds it.
struct ReportedFinding {
  Fingerprint fingerprint;
  std::string slug;
  Severity severity = Severity::Info;
  std::optional<std::uint16_t> axis;  // the axis's index
  std::uint64_t frame = 0;
  std::uint64_t since_frame = 0;
  double time = 0;
  std::string message;
};

// One incident as a JSON report holds it (docs/cli.md: `incidents`): what baselines and `diff`
// compare.
struct ReportedIncident {
  IncidentFingerprint fingerprint;
  std::uint64_t frame = 0;
  std::string text;  // cause.text
};

// The quantiles `diff` puts side by side (the JSON report's `timing.cycle_us`, `latency_us`).
struct ReportedSeries {
  std::uint64_t count = 0;
  std::optional<double> p50, p99, p999, max;
};
struct ReportedDc {
  std::string station;
  std::optional<double> drift_ppm;
};

// One capture of a JSON report of `validate`, as far as baselines and `diff` read it.
struct ReportedCapture {
  std::string path;
  std::string verdict;
  std::vector<ReportedFinding> findings;  // in the report's order
  std::vector<ReportedIncident> incidents;
  ReportedSeries cycle, latency;
  std::vector<ReportedDc> dc;
};

// A JSON report of `validate --format json` read back.
struct ReportFile {
  std::string path;
  std::vector<ReportedCapture> captures;
};
// Fails naming the file and what is wrong: missing, not JSON, not such a report, or written
// without fingerprints.
Result<ReportFile> loadReportFile(const std::string& path);
Result<ReportFile> parseReportFile(std::string_view text, const std::string& path);
// Whether a file starts like a JSON document ('{'), not a capture: how `diff` tells them apart.
bool looksLikeJsonReport(const std::string& path);

// The baseline's capture a capture of the run is held against (docs/baselines.md#captures): the
// one of the same file name; else, when the baseline and the run each hold one capture, that one.
// Null when none.
const ReportedCapture* baselineCaptureFor(const ReportFile& baseline, const std::string& path,
                                          std::size_t run_captures);

// Items (findings or incidents) matched against a baseline's, in capture order, as they come:
// an item takes a baseline item of its fingerprint not yet taken, the earliest first; what is
// left at the end is absent.
template <class Reported>
class FingerprintMatcher {
 public:
  using Key = decltype(Reported::fingerprint);
  // `items` null: every item is new. They must outlive the matcher.
  explicit FingerprintMatcher(const std::vector<Reported>* items) : items_(items) {
    if (items_ == nullptr) return;
    taken_.assign(items_->size(), false);
    for (std::size_t i = items_->size(); i-- > 0;) waiting_[(*items_)[i].fingerprint].push_back(i);
  }
  BaselineState match(const Key& fingerprint) {
    const auto it = waiting_.find(fingerprint);
    if (it == waiting_.end() || it->second.empty()) return BaselineState::New;
    taken_[it->second.back()] = true;
    it->second.pop_back();
    return BaselineState::Unchanged;
  }
  // The baseline's items none took, in the baseline's order.
  std::vector<Reported> absent() const {
    std::vector<Reported> left;
    for (std::size_t i = 0; i < taken_.size(); ++i) {
      if (!taken_[i]) left.push_back((*items_)[i]);
    }
    return left;
  }

 private:
  const std::vector<Reported>* items_;
  std::map<Key, std::vector<std::size_t>> waiting_;  // item indices, latest first
  std::vector<bool> taken_;
};

// One capture's findings and incidents matched against a baseline capture's (so JSON Lines can
// say it on each finding's line).
class BaselineMatcher {
 public:
  // `capture` null: everything is new. It must outlive the matcher.
  explicit BaselineMatcher(const ReportedCapture* capture)
      : capture_(capture),
        findings_(capture ? &capture->findings : nullptr),
        incidents_(capture ? &capture->incidents : nullptr) {}
  BaselineState match(const Fingerprint& fingerprint) { return findings_.match(fingerprint); }
  BaselineState match(const IncidentFingerprint& fingerprint) {
    return incidents_.match(fingerprint);
  }
  std::vector<ReportedFinding> absent() const { return findings_.absent(); }
  std::vector<ReportedIncident> absentIncidents() const { return incidents_.absent(); }
  const ReportedCapture* capture() const { return capture_; }

 private:
  const ReportedCapture* capture_;
  FingerprintMatcher<ReportedFinding> findings_;
  FingerprintMatcher<ReportedIncident> incidents_;
};

// `ncservo diff BASE NEW` (docs/baselines.md#diff): one capture against another.
struct DiffGroup {
  std::string rule;
  std::optional<std::string> axis;
  std::size_t base = 0, next = 0;  // findings on either side
  std::size_t added = 0, absent = 0, unchanged = 0;
};
struct CaptureDiff {
  std::string base_source, next_source;  // the files named
  ReportedCapture base, next;
  std::vector<ReportedFinding> added;   // NEW's findings BASE does not have
  std::vector<ReportedFinding> absent;  // BASE's findings NEW does not have
  std::size_t unchanged = 0;
  std::vector<DiffGroup> groups;  // by rule and axis, in the order first seen (BASE, then NEW)
  std::vector<ReportedIncident> incidents_added, incidents_absent;
  std::size_t incidents_unchanged = 0;
};
CaptureDiff diffCaptures(ReportedCapture base, ReportedCapture next);
// `diff --format`: text, json or html.
std::vector<std::string> diffFormatNames();
void writeDiff(std::FILE* out, std::string_view format, const CaptureDiff& diff);

}  // namespace ncservo::report
