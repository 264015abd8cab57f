// `ncservo annotate IN OUT.pcapng` (docs/field.md): the capture copied to pcapng with each
// finding as a packet comment on its frame. Two passes over the file: the first judges it (a
// finding is known only once its frame is judged, and the learning window (docs/layout.md)
// delivers its frames late), the second copies it with the comments. So the input must be a
// file that can be read again, not standard input.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "ncservo/capture/capture_annotation.hpp"
#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/capture/capture_stream.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"
#include "ncservo/report/report.hpp"
#include "ncservo/rules/coverage.hpp"
#include "ncservo/rules/validator.hpp"
#include "ncservo/wire/frame_clock.hpp"

namespace ncservo::cli {

using namespace report;  // the report layer's names
namespace {

struct AnnotateArgs : RuleArgs {
  std::string input;
  std::string output;
  LayoutArgs layout;
  std::string timestamps = "auto";
  std::optional<double> snippets_s;
};

struct Judged {
  FrameComments comments;
  Coverage coverage;  // whether every axis was checked (no servo: nothing was)
  std::vector<std::int64_t> finding_times_ns;  // of each finding's frame, in capture order
  std::size_t findings = 0;
  std::size_t incidents = 0;
};

// The first pass: every finding, as a comment on its frame.
Result<Judged> judge(const AnnotateArgs& args, const LayoutFiles& files,
                     const RuleSettings& settings) {
  auto opened = CaptureReader::open(args.input);
  if (!opened) return fail(opened.error());
  CapturePipeline pipeline({decoderOptions(files, args.layout), settings, TimeWindow{},
                            *timestampModeFromName(args.timestamps)});
  Judged judged;
  const auto keep = [&](const std::vector<Finding>& findings) {
    for (const Finding& f : findings) {
      judged.comments[f.at.frame].push_back(
          findingComment(f, pipeline.validator()->decoder().axes()));
      judged.finding_times_ns.push_back(f.at.time_ns);
      ++judged.findings;
    }
  };
  pipeline.setSinks({nullptr, nullptr, nullptr, keep, nullptr});
  if (Status status = streamCapture(**opened, pipeline); !status) return fail(status.error());
  const CaptureResult result = pipeline.result();
  judged.coverage = result.coverage;
  // docs/field.md#annotate: each incident on its frame too, so that a colleague without the
  // plugin sees its cause in any Wireshark.
  CaptureReport report;
  static_cast<CaptureResult&>(report) = result;
  for (const Incident& incident : result.incidents) {
    judged.comments[incident.at.frame].push_back(incidentComment(report, incident));
    judged.finding_times_ns.push_back(incident.at.time_ns);
    ++judged.incidents;
  }
  return judged;
}

// `--snippets S`: the frames within S seconds of a finding, and the findings' own frames.
FrameFilter snippetFilter(const Judged& judged, double seconds) {
  const auto reach = static_cast<std::int64_t>(std::llround(seconds * 1e9));
  std::vector<std::pair<std::int64_t, std::int64_t>> windows;  // merged, in time order
  std::vector<std::int64_t> times = judged.finding_times_ns;
  std::sort(times.begin(), times.end());
  for (const std::int64_t t : times) {
    if (!windows.empty() && t - reach <= windows.back().second) {
      windows.back().second = t + reach;
    } else {
      windows.emplace_back(t - reach, t + reach);
    }
  }
  return [windows, &comments = judged.comments](std::uint64_t frame, std::int64_t time_ns) {
    if (comments.count(frame) != 0) return true;
    const auto after = std::upper_bound(
        windows.begin(), windows.end(), time_ns,
        [](std::int64_t t, const std::pair<std::int64_t, std::int64_t>& w) { return t < w.first; });
    return after != windows.begin() && time_ns <= std::prev(after)->second;
  };
}

int runAnnotate(const AnnotateArgs& args) {
  if (args.input == "-") {
    fmt::print(stderr,
               "ncservo annotate: standard input cannot be annotated: the capture is read twice "
               "(to judge it, then to copy it with the comments); give a file\n");
    return kExitUsage;
  }
  if (Status refused = refuseInputAsOutput("OUT", args.output, {args.input}); !refused) {
    fmt::print(stderr, "ncservo annotate: {}\n", refused.error().text());
    return kExitUsage;
  }
  if (args.snippets_s && !(std::isfinite(*args.snippets_s) && *args.snippets_s >= 0)) {
    fmt::print(stderr, "ncservo annotate: --snippets {}: expected seconds, 0 or more\n",
               *args.snippets_s);
    return kExitUsage;
  }
  const Result<LayoutFiles> files = loadLayoutFiles(args.layout);
  RuleSettings settings;
  Status built = files ? buildSettings(args, files->config, settings) : fail(files.error());
  if (!built) {
    fmt::print(stderr, "ncservo annotate: {}\n", built.error().text());
    return kExitUsage;
  }
  const Result<Judged> judged = judge(args, *files, settings);
  if (!judged) {
    fmt::print(stderr, "ncservo annotate: {}\n", judged.error().text());
    return kExitCapture;
  }
  const FrameFilter keep = args.snippets_s ? snippetFilter(*judged, *args.snippets_s) : nullptr;
  if (Status written = annotateCapture(
          args.input, args.output, judged->comments, keep,
          [](std::string_view c) { return isFindingComment(c) || isIncidentComment(c); });
      !written) {
    fmt::print(stderr, "ncservo annotate: {}\n", written.error().text());
    // docs/cli.md#exit-status: an output that cannot be written is a usage error, as in every
    // command; the input's damage is 3.
    return written.error().path == args.output ? kExitUsage : kExitCapture;
  }
  if (args.output != "-") {
    fmt::print(stderr,
               "ncservo annotate: {} finding{} and {} incident{} as comments on {} frame{} in {}\n",
               judged->findings, judged->findings == 1 ? "" : "s", judged->incidents,
               judged->incidents == 1 ? "" : "s", judged->comments.size(),
               judged->comments.size() == 1 ? "" : "s", args.output);
  }
  // The copy is written all the same; nothing of the protocol was checked in it (as validate).
  if (!judged->coverage.complete()) {
    fmt::print(stderr, "ncservo annotate: {}: NO SERVO: {}\n", args.input, judged->coverage.reason);
    return kExitNoServo;
  }
  return kExitOk;
}

}  // namespace

Handler annotateCommand(CLI::App& command) {
  auto args = std::make_shared<AnnotateArgs>();
  command
      .add_option("IN", args->input,
                  "pcap or pcapng capture (a file: it is read twice; a compressed pcap is fine)")
      ->required();
  command.add_option("OUT", args->output, "the pcapng to write, - for standard output")->required();
  command.add_option("--snippets", args->snippets_s,
                     "write only the frames within SECONDS of a finding");
  addLayoutOptions(command, args->layout);
  addRuleOptions(command, *args);
  addTimestampsOption(command, args->timestamps);
  return [args] { return runAnnotate(*args); };
}

}  // namespace ncservo::cli
