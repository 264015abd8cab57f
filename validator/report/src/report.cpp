#include "ncservo/report/report.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <iterator>
#include <limits>

#include "ncservo/base/wall_time.hpp"
#include "ncservo/incidents/causes.hpp"

namespace ncservo::report {

namespace {

// Temporary reports are removed if the run is interrupted; the list is fixed while the handler
// may run (between ReportWriter::open and finish).
const std::vector<std::string>* g_temporaries = nullptr;

// docs/cli.md#interrupted: set by the first Ctrl-C once a run asked for it (stopOnInterrupt).
std::atomic<bool> g_interrupted{false};
std::atomic<bool> g_stop_on_interrupt{false};
static_assert(std::atomic<bool>::is_always_lock_free, "set in a signal handler");

// After the first Ctrl-C, system calls restart again: only a read waiting when it came (standard
// input) is cut short, not the reports' writes.
void catchInterrupt(int flags);

extern "C" void removeTemporaries(int signal) {
  if (signal == SIGINT && g_stop_on_interrupt.load() && !g_interrupted.exchange(true)) {
    catchInterrupt(SA_RESTART);
    return;
  }
  if (g_temporaries != nullptr) {
    for (const std::string& path : *g_temporaries) ::unlink(path.c_str());
  }
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

constexpr int kInterrupts[] = {SIGINT, SIGTERM, SIGHUP, SIGPIPE};
// What each was before: a signal the caller ignores (nohup, a background job) stays ignored.
void (*g_previous[std::size(kInterrupts)])(int) = {};
void catchInterrupt(int flags) {
  struct sigaction action {};
  action.sa_handler = removeTemporaries;
  action.sa_flags = flags;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
}
}  // namespace

std::string describeLateLayout(const LateLayout& late) {
  const std::string unjudged = late.unjudged_frames == 0
                                   ? std::string("none")
                                   : fmt::format("{} ({}\u2013{})", late.unjudged_frames,
                                                 late.first_unjudged, late.last_unjudged);
  return fmt::format(
      "layout certain at frame {}, after {} cycles in {} windows of evidence; frames before the "
      "layout was certain, not judged: {}",
      late.certain_at, late.cycles, late.windows, unjudged);
}

std::string describeStartupCut(std::uint64_t frames) {
  return fmt::format(
      "incomplete: the snap length cut {} start-up frame{} short; a servo configured after a cut "
      "is missing from this layout (give the layout with --config or --eni)",
      frames, frames == 1 ? "" : "s");
}

std::string describeTruncation(const Truncation& t) {
  std::string out;
  if (t.snapped > 0) {
    out = fmt::format("{} frame{} cut short by the capture's snap length (first: frame {})",
                      t.snapped, t.snapped == 1 ? "" : "s", t.first_snapped);
  }
  if (t.cut_frames > 0) {
    out += fmt::format("{}PDO words not captured in {} frame{} (first: frame {}) for {}",
                       out.empty() ? "" : "; ", t.cut_frames, t.cut_frames == 1 ? "" : "s",
                       t.first_cut, fmt::join(t.axes, ", "));
  }
  return out;
}

bool CaptureReport::reaches(Severity level) const {
  for (std::size_t s = static_cast<std::size_t>(level); s < counts.size(); ++s) {
    if (counted(static_cast<Severity>(s)) > 0) return true;
  }
  return false;
}

Fingerprint CaptureReport::fingerprintOf(const Finding& f) const {
  return {ruleDef(f.rule).code, f.axis ? std::optional(axisLabel(*this, f.axis)) : std::nullopt,
          f.ordinal};
}

IncidentFingerprint CaptureReport::fingerprintOf(const Incident& i) const {
  std::optional<std::string> where;
  if (i.axis) {
    where = axisLabel(*this, i.axis);
  } else if (i.station) {
    where = fmt::format("0x{:04X}", *i.station);
  }
  return {incidentKindName(i.kind), where, causeDef(i.cause).name, i.ordinal};
}

void CaptureReport::closeBaseline() {
  if (!baseline) return;
  baseline_absent = baseline->absent();
  incident_states.clear();
  for (const Incident& i : incidents) incident_states.push_back(baseline->match(fingerprintOf(i)));
  baseline_absent_incidents = baseline->absentIncidents();
}

std::string describeBaseline(const CaptureReport& r) {
  return fmt::format("{} new, {} unchanged, {} absent", r.newCount(), r.unchanged,
                     r.baseline_absent.size());
}

BaselineState CaptureReport::tally(const Finding& f) {
  ++counts[static_cast<std::size_t>(f.severity)];
  const BaselineState state = baseline ? baseline->match(fingerprintOf(f)) : BaselineState::None;
  const bool added = state == BaselineState::New;
  if (added) ++new_counts[static_cast<std::size_t>(f.severity)];
  if (state == BaselineState::Unchanged) ++unchanged;
  for (FindingGroup& g : groups) {
    if (g.rule == f.rule && g.axis == f.axis) {
      ++g.count;
      g.added += added ? 1 : 0;
      g.last = f.at;
      return state;
    }
  }
  groups.push_back({f.rule, f.severity, f.axis, 1, added ? 1u : 0u, f.at, f.at, f.message});
  return state;
}

std::vector<std::uint64_t> findingFrames(const CaptureReport& report) {
  std::vector<std::uint64_t> frames;
  for (const Finding& f : report.findings) frames.push_back(f.at.frame);
  for (const Incident& i : report.incidents) frames.push_back(i.at.frame);
  std::sort(frames.begin(), frames.end());
  frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  return frames;
}

std::string describeScope(const ReportScope& scope) {
  std::vector<std::string> parts;
  if (!scope.axes.empty()) {
    parts.push_back(fmt::format("ax{} {} and the bus", scope.axes.size() == 1 ? "is" : "es",
                                fmt::join(scope.axes, ", ")));
  }
  if (!scope.findings) parts.emplace_back("incidents only");
  if (!scope.incidents) parts.emplace_back("findings only");
  return fmt::format("{}", fmt::join(parts, "; "));
}

bool CaptureReport::inScope(const std::optional<std::uint16_t>& axis) const {
  if (!axis || scope.axes.empty()) return true;
  return std::find(scope.axes.begin(), scope.axes.end(), axisLabel(*this, axis)) !=
         scope.axes.end();
}

std::string isoUtc(std::int64_t time_ns, int digits) {
  return isoTime(time_ns, digits, TimeZone::Utc);
}

char* writeSeconds(std::int64_t ns, char* out) {
  // Whole microseconds give {:.6f}'s digits wherever ns is not halfway between two: ns / 1e9 is
  // then at least 1e-9 s from a rounding boundary, and below 2^53 ns the double it becomes is
  // less than that from it. Halfway, the double's own rounding decides, so fmt does it.
  constexpr std::int64_t kExactBelow = std::int64_t{1} << 53;
  if (ns >= 0 && ns < kExactBelow && ns % 1000 != 500) {
    const std::int64_t us = (ns + 500) / 1000;
    return fmt::format_to(out, "{}.{:06}", us / 1000000, us % 1000000);
  }
  return fmt::format_to(out, "{:.6f}", static_cast<double>(ns) / 1e9);
}

Result<std::unique_ptr<ReportWriter>> ReportWriter::open(const std::vector<ReportTarget>& targets,
                                                         const ReportOptions& options,
                                                         const Judge& judge) {
  std::unique_ptr<ReportWriter> writer(new ReportWriter(options, judge));
  for (const ReportTarget& target : targets) {
    Output output{target.format, stdout, {}, {}};
    std::error_code ec;
    const auto status = std::filesystem::status(target.path, ec);
    if (!target.path.empty() && target.path != "-" && std::filesystem::exists(status) &&
        !std::filesystem::is_regular_file(status)) {
      // A device or a pipe (/dev/null, a FIFO) is written as it is: renaming a file over it
      // would replace it.
      std::FILE* out = std::fopen(target.path.c_str(), "w");
      if (out == nullptr)
        return fail(fmt::format("{}: cannot write: {}", target.path, std::strerror(errno)));
      output = {target.format, out, target.path, {}};
    } else if (!target.path.empty() && target.path != "-") {
      // Through a link, the file it names is replaced, not the link.
      const std::filesystem::path path =
          std::filesystem::is_symlink(std::filesystem::symlink_status(target.path, ec))
              ? std::filesystem::weakly_canonical(target.path, ec)
              : std::filesystem::path(target.path);
      std::string temporary = (path.parent_path() / ("." + path.filename().string() + ".XXXXXX"))
                                  .lexically_normal()
                                  .string();
      const int fd = ::mkstemp(temporary.data());
      // mkstemp's file is private (0600); the report gets the mode a new file would have.
      const mode_t mask = ::umask(0);
      ::umask(mask);
      if (fd >= 0) ::fchmod(fd, 0666 & ~mask);
      std::FILE* out = fd >= 0 ? ::fdopen(fd, "w") : nullptr;
      if (out == nullptr) {
        if (fd >= 0) {
          ::close(fd);
          ::unlink(temporary.c_str());
        }
        return fail(fmt::format("{}: cannot write: {}", target.path, std::strerror(errno)));
      }
      output = {target.format, out, path.string(), std::move(temporary)};
    }
    writer->outputs_.push_back(std::move(output));
  }
  static std::vector<std::string> temporaries;
  temporaries.clear();
  for (const Output& o : writer->outputs_) {
    if (!o.temporary.empty()) temporaries.push_back(o.temporary);
  }
  g_temporaries = &temporaries;
  for (std::size_t i = 0; i < std::size(kInterrupts); ++i) {
    g_previous[i] = std::signal(kInterrupts[i], removeTemporaries);
    if (g_previous[i] == SIG_IGN) std::signal(kInterrupts[i], SIG_IGN);
  }
  return writer;
}

void ReportWriter::stopOnInterrupt() {
  g_interrupted = false;
  g_stop_on_interrupt = true;
  // Without SA_RESTART, so that a read waiting for standard input returns at the first Ctrl-C; a
  // Ctrl-C the caller ignores stays ignored.
  if (g_previous[0] != SIG_IGN) catchInterrupt(0);
}

const std::atomic<bool>& ReportWriter::interrupted() {
  return g_interrupted;
}

ReportWriter::~ReportWriter() {
  g_stop_on_interrupt = false;
  for (std::size_t i = 0; i < std::size(kInterrupts); ++i) {
    if (g_previous[i] != SIG_ERR) std::signal(kInterrupts[i], g_previous[i]);
  }
  g_temporaries = nullptr;
  for (const Output& o : outputs_) {
    if (o.temporary.empty()) continue;
    std::fclose(o.out);
    ::unlink(o.temporary.c_str());
  }
}

bool ReportWriter::keepsFindings() const {
  return std::any_of(outputs_.begin(), outputs_.end(),
                     [](const Output& o) { return o.format->keeps_findings; });
}

bool ReportWriter::drawsTimelines() const {
  return std::any_of(outputs_.begin(), outputs_.end(),
                     [](const Output& o) { return o.format->draws_timelines; });
}

bool ReportWriter::locatesFrames() const {
  return std::any_of(outputs_.begin(), outputs_.end(),
                     [](const Output& o) { return o.format->locates_frames; });
}

void ReportWriter::beginCapture(const CaptureReport& report) {
  for (const Output& o : outputs_) {
    if (o.format->begin_capture != nullptr)
      o.format->begin_capture({o.out, options_, judge_}, report);
  }
}

void ReportWriter::finding(const CaptureReport& report, const Finding& f, BaselineState state) {
  for (const Output& o : outputs_) {
    if (o.format->finding != nullptr)
      o.format->finding({o.out, options_, judge_}, report, f, state);
  }
}

void ReportWriter::endCapture(const CaptureReport& report) {
  for (const Output& o : outputs_) {
    if (o.format->end_capture != nullptr) o.format->end_capture({o.out, options_, judge_}, report);
  }
}

Status ReportWriter::finish(const std::vector<CaptureReport>& reports) {
  Status status;
  for (Output& o : outputs_) {
    if (o.format->finish != nullptr) o.format->finish({o.out, options_, judge_}, reports);
    if (o.temporary.empty()) {
      const bool written = std::fflush(o.out) == 0;
      const bool closed = o.out == stdout || std::fclose(o.out) == 0;
      if ((!written || !closed) && status)
        status =
            fail(fmt::format("{}: cannot write: {}", o.path.empty() ? "standard output" : o.path,
                             std::strerror(errno)));
      o.out = stdout;
      continue;
    }
    const bool written = std::fflush(o.out) == 0 && ::fsync(fileno(o.out)) == 0;
    const bool closed = std::fclose(o.out) == 0;
    const std::string temporary = std::exchange(o.temporary, {});
    if (!written || !closed || std::rename(temporary.c_str(), o.path.c_str()) != 0) {
      const int error = errno;
      ::unlink(temporary.c_str());
      if (status) status = fail(fmt::format("{}: cannot write: {}", o.path, std::strerror(error)));
    }
  }
  return status;
}

}  // namespace ncservo::report
