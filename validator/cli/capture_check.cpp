#include "capture_check.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>

#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"
#include "ncservo/rules/coverage.hpp"
#include "ncservo/rules/validator.hpp"
#include "ncservo/wire/frame_clock.hpp"
#include "progress.hpp"

namespace ncservo::cli {

using namespace report;  // the report layer's names

Result<CheckSetup> prepareCheck(const CheckArgs& o) {
  CheckSetup setup;
  Result<LayoutFiles> files = loadLayoutFiles(o.layout);
  if (!files) return fail(files.error());
  setup.files = std::move(*files);
  if (Status built = buildSettings(o, setup.files.config, setup.settings); !built)
    return fail(built.error());
  const Result<TimeWindow> time_window = timeWindowOf(o.window.from, o.window.to, o.window.zone());
  if (!time_window) return fail(time_window.error());
  setup.window = *time_window;
  setup.timestamps = *timestampModeFromName(o.timestamps);
  setup.layout = decoderOptions(setup.files, o.layout);
  if (setup.files.eni) setup.eni_frames = setup.files.eni->frames;
  return setup;
}

namespace {

// The incidents the report's scope keeps; a named axis the capture does not have is an error.
Status keepScope(CaptureReport& report) {
  for (const std::string& name : report.scope.axes) {
    if (std::none_of(report.layout.begin(), report.layout.end(),
                     [&](const AxisInfo& axis) { return axis.name == name; })) {
      std::vector<std::string> names;
      for (const AxisInfo& axis : report.layout) names.push_back(axis.name);
      return fail(fmt::format(
          "--axis {}: no axis of that name (its axes: {})", name,
          names.empty() ? std::string("none") : fmt::format("{}", fmt::join(names, ", "))));
    }
  }
  std::vector<Incident> kept;
  for (Incident& incident : report.incidents) {
    if (report.scope.incidents && report.inScope(incident.axis))
      kept.push_back(std::move(incident));
  }
  report.incidents = std::move(kept);
  return {};
}

}  // namespace

int validateCapture(const std::string& path, const CheckSetup& setup,
                    const report::ReportWriter& writer, const CaptureOutput& output,
                    report::CaptureReport& report, CaptureThreads threads) {
  const RuleSettings& settings = setup.settings;
  const TimeWindow& time_window = setup.window;
  report.path = path;
  if (output.live != nullptr) output.live->beginCapture(report);
  auto opened = CaptureReader::open(path);
  if (!opened) {
    report.error = opened.error().text();
    fmt::print(output.messages, "ncservo: {}\n", *report.error);
    if (output.live != nullptr) output.live->endCapture(report);
    return kExitCapture;
  }
  const std::unique_ptr<CaptureReader> reader = std::move(*opened);
  report.timestamp_digits = reader->timestampDigits();
  CapturePipeline pipeline({setup.layout, settings, time_window, setup.timestamps});
  pipeline.holdEniCycles(setup.eni_frames);
  std::optional<report::TimelineRecorder> timelines;
  if (writer.drawsTimelines()) timelines.emplace(settings);
  const auto start = [&](const DecoderOptions&) {
    report.layout = pipeline.validator()->decoder().axes();  // names for findings as they come
  };
  const auto validate = [&](const PipelineFrame& f) {
    report.first_time_ns = *pipeline.run().first_time_ns;  // findings are written as they come
    report.last_time_ns = f.time_ns;
    if (timelines) timelines->frame(f.number, f.time_ns - report.first_time_ns, *f.judged);
  };
  const auto keepFindings = [&](const std::vector<Finding>& findings) {
    for (const Finding& f : findings) {
      if (!report.scope.findings || !report.inScope(f.axis)) continue;
      const report::BaselineState state = report.tally(f);
      if (output.live == nullptr || writer.keepsFindings()) {
        report.findings.push_back(f);
        if (report.baseline) report.baseline_states.push_back(state);
      }
      if (timelines) timelines->finding(f);
      if (output.live != nullptr) output.live->finding(report, f, state);
    }
  };
  pipeline.setSinks({start, validate, nullptr, keepFindings, nullptr});
  // Progress for one capture at a time only (parallel jobs' messages wait for their turn); the
  // records are counted only then.
  const bool progress_shown = output.messages == stderr && cli::progressWanted();
  std::atomic<std::uint64_t> records{0};
  StreamStop stop{&report::ReportWriter::interrupted(), false, progress_shown ? &records : nullptr};
  const Status status = [&] {
    const cli::Progress progress(path == "-" ? "standard input" : path, records, progress_shown);
    return streamCapture(*reader, pipeline, &stop, threads);
  }();
  const CaptureRun& run = pipeline.run();
  if (stop.stopped) {  // Ctrl-C: not a report, only where it stopped (docs/cli.md#interrupted)
    report.frames = run.records;
    return kExitInterrupted;
  }
  static_cast<CaptureResult&>(report) = pipeline.result();
  if (Status scoped = keepScope(report); !scoped) {
    fmt::print(output.messages, "ncservo: {}: {}\n", path, scoped.error().text());
    if (output.live != nullptr) output.live->endCapture(report);
    return kExitUsage;
  }
  for (const std::string& warning : report.layout_warnings) {
    fmt::print(output.messages, "ncservo: {}: layout does not fit: {}\n", path, warning);
  }
  if (timelines) report.timelines = timelines->finish();
  warnIfTruncated(reader->path(), report.truncation, output.messages);
  if (report.startup_frames_cut > 0) {
    fmt::print(output.messages, "ncservo: {}: layout {}\n", reader->path(),
               report::describeStartupCut(report.startup_frames_cut));
  }
  report.capture_drops = reader->drops();
  if (!status) {
    report.error = status.error().text() + " (the frames before it were analysed)";
    fmt::print(output.messages, "ncservo: {}\n", *report.error);
  }
  if (writer.locatesFrames()) {
    report.frame_spans.clear();
    if (auto located = locateRecords(report.path, findingFrames(report)); located) {
      report.frame_spans = std::move(*located);
    } else {
      fmt::print(output.messages, "ncservo: {}: frames not located in the file: {}\n", path,
                 located.error().text());
    }
  }
  report.closeBaseline();
  if (output.live != nullptr) output.live->endCapture(report);
  return writer.judge().exitStatus(report);
}

}  // namespace ncservo::cli
