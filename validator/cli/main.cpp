// ncservo: the command-line face of the library. It parses arguments and presents; the protocol
// knowledge lives in the library's tables. Every subcommand (kSubcommands) and every output format
// (kRowFormats, kFieldListFormats, kRuleListFormats, kCaptureFormats, report.hpp's ReportFormat)
// is a row: the options, their choices and help, and the dispatch are derived from the rows.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "commands.hpp"
#include "ncservo/base/error.hpp"
#include "ncservo/base/number.hpp"
#include "ncservo/base/ordered_jobs.hpp"
#include "ncservo/base/text.hpp"
#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/capture/capture_stream.hpp"
#include "ncservo/capture/capture_writer.hpp"
#include "ncservo/capture/compressed_output.hpp"
#include "ncservo/config/config.hpp"
#include "ncservo/layout/eni.hpp"
#include "ncservo/layout/session.hpp"
#include "ncservo/model/timing_text.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"
#include "ncservo/protocol/fields.hpp"
#include "ncservo/protocol/pdo.hpp"
#include "ncservo/report/axis_selection.hpp"
#include "ncservo/report/report.hpp"
#include "ncservo/report/waveform.hpp"
#include "ncservo/rules/validator.hpp"
#include "ncservo/sim/simulator.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "ncservo/wire/frame_clock.hpp"

namespace {

using namespace ncservo;
using cli::addLayoutOptions;
using cli::addTimestampsOption;
using cli::buildSettings;
using cli::decoderOptions;
using cli::LayoutArgs;
using cli::LayoutFiles;
using cli::loadLayoutFiles;
using cli::refuseInputAsOutput;

using cli::kExitCapture;
using cli::kExitFindings;
using cli::kExitInterrupted;
using cli::kExitNoServo;
using cli::kExitOk;
using cli::kExitUsage;

// ---- Format tables and the --format option derived from them ----

template <typename Row, std::size_t N>
std::vector<std::string> namesOf(const Row (&rows)[N]) {
  std::vector<std::string> names;
  for (const Row& row : rows) names.emplace_back(row.name);
  return names;
}

// The row `--format` chose; its check admits only the table's names.
template <typename Row, std::size_t N>
const Row& rowNamed(const Row (&rows)[N], const std::string& name) {
  for (const Row& row : rows) {
    if (name == row.name) return row;
  }
  return rows[0];
}

// "a, b or c".
std::string choiceList(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i) {
    text += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  }
  return text;
}

// --format, one of `names`; its help lists them, then `note`.
void addFormatOption(CLI::App& command, std::string& format, const std::vector<std::string>& names,
                     const std::string& note = "") {
  command.add_option("--format", format, choiceList(names) + note)->check(cli::oneOf(names));
}

// ---- decode ----

std::string shortName(const char* filter) {
  std::string name(filter);
  return name.substr(std::string("ncservo.").size());
}

std::string messageOf(const PdoValues& values) {
  char message[128] = "";
  if (values.has_tx) formatMessage(message, sizeof message, values.msgCode(), values.msgData());
  return message;
}

const char* stateOf(const CycleRow& row) {
  return row.state ? driveStateName(*row.state) : "";
}

std::string csvCell(const FieldDef& f, const PdoValues& values) {
  if (!fieldApplies(f, values)) return "";
  const FieldValue v = fieldValue(f, values);
  switch (v.kind) {
    case FieldValue::Kind::Float:
      return fmt::format("{:.9g}", v.f);
    case FieldValue::Kind::Signed:
      return fmt::format("{}", v.i);
    case FieldValue::Kind::Unsigned:
      return f.kind == FieldKind::Word ? fmt::format("0x{:08x}", v.u) : fmt::format("{}", v.u);
  }
  return "";
}

void writeCsvHeader(std::FILE* out) {
  std::string line = "frame,time,axis,name";
  for (const FieldDef& f : kFields) line += "," + shortName(f.filter);
  line += ",state,message\n";
  std::fputs(line.c_str(), out);
}

void writeCsvRow(std::FILE* out, const CycleRow& row, const std::string& name, double time) {
  std::string line = fmt::format("{},{:.9f},{},{}", row.frame, time, row.axis, csvField(name));
  for (const FieldDef& f : kFields) line += "," + csvCell(f, row.values);
  line += fmt::format(",{},{}\n", stateOf(row), csvField(messageOf(row.values), true));
  std::fputs(line.c_str(), out);
}

void writeJsonRow(std::FILE* out, const CycleRow& row, const std::string& name, double time) {
  nlohmann::ordered_json j;
  j["frame"] = row.frame;
  j["time"] = time;
  j["axis"] = row.axis;
  j["name"] = name;
  for (const FieldDef& f : kFields) {
    if (!fieldApplies(f, row.values)) continue;
    const FieldValue v = fieldValue(f, row.values);
    auto& slot = j[shortName(f.filter)];
    if (v.kind == FieldValue::Kind::Float) {
      slot = v.f;
    } else if (v.kind == FieldValue::Kind::Signed) {
      slot = v.i;
    } else {
      slot = v.u;
    }
  }
  if (row.state) j["state"] = stateOf(row);
  if (row.values.has_tx) j["message"] = messageOf(row.values);
  std::fputs((j.dump() + "\n").c_str(), out);
}

struct DecodeArgs;
struct DecodeInput;
int decodeRows(const DecodeArgs& args, DecodeInput& input);
int decodeWaveforms(const DecodeArgs& args, DecodeInput& input);

// `decode`'s formats (docs/cli.md): one line per axis and cycle after an optional header, or
// the waveforms of every copy with the findings (waveform.hpp).
struct DecodeFormat {
  const char* name;
  int (*decode)(const DecodeArgs& args, DecodeInput& input);
  void (*header)(std::FILE* out);
  void (*row)(std::FILE* out, const CycleRow& row, const std::string& name, double time);
};
const DecodeFormat kDecodeFormats[] = {
    {.name = "csv", .decode = decodeRows, .header = writeCsvHeader, .row = writeCsvRow},
    {.name = "jsonl", .decode = decodeRows, .header = nullptr, .row = writeJsonRow},
    {.name = "vcd", .decode = decodeWaveforms, .header = nullptr, .row = nullptr},
};

// --from/--to (docs/cli.md), seconds since the capture's first frame.
struct WindowArgs {
  std::optional<double> from_s, to_s;
};
void addWindowOptions(CLI::App& command, WindowArgs& window) {
  command.add_option("--from", window.from_s,
                     "only frames at or after SECONDS since the capture's first frame");
  command.add_option("--to", window.to_s,
                     "only frames at or before SECONDS since the capture's first frame");
}

// What a snap length cut, on one line (never one per frame).
void warnIfTruncated(const std::string& capture, const Truncation& truncation,
                     std::FILE* messages = stderr) {
  if (truncation.any()) {
    fmt::print(messages, "ncservo: {}: {}\n", capture, cli::describeTruncation(truncation));
  }
}

// No frame of the capture in the window is said as such.
// Every line of `text` as a TOML comment.
std::string commented(std::string_view text) {
  while (!text.empty() && text.back() == '\n') text.remove_suffix(1);
  std::string out = "# ";
  for (const char c : text) out += c == '\n' ? std::string("\n# ") : std::string(1, c);
  return out + "\n";
}

// `decode --layout`: the layout as a configuration file, then every slave the start-up showed;
// with no layout, the placements the inference found, commented out. Always valid TOML.
void printLayout(const Decoder& decoder, const std::optional<InferenceResult>& inference) {
  std::vector<AxisConfig> axes;
  for (const AxisInfo& info : decoder.axes()) axes.push_back(axisConfigOf(info));
  fmt::print("{}", commented(fmt::format(
                       "layout source: {}, {} ax{}{}", layoutSourceName(decoder.source()),
                       axes.size(), axes.size() == 1 ? "is" : "es",
                       axes.empty() ? " (" + decoder.noServoReason() + ")" : std::string())));
  if (inference && !inference->axes.empty()) {
    fmt::print("# inferred from {} cycles of cyclic traffic (docs/layout.md)\n", inference->cycles);
    for (const InferredAxis& axis : inference->axes) {
      fmt::print("# {}: {}\n", axis.config.name, describeEvidence(axis));
    }
  }
  for (const SlaveLayout& slave : decoder.learner().slaves()) {
    fmt::print("# slave {}\n", describeSlaveLayout(slave));
  }
  if (!axes.empty()) fmt::print("{}", writeConfig(axes, std::nullopt));
  if (!axes.empty() || !inference || inference->candidates.empty()) return;
  fmt::print("# candidates found, not certain enough to decode (uncomment to use):\n");
  for (const InferredAxis& axis : inference->candidates) {
    fmt::print("# {}: {}\n", axis.config.name, describeEvidence(axis));
    fmt::print("{}", commented(writeConfig({axis.config}, std::nullopt)));
  }
}

struct DecodeArgs {
  std::string capture;
  LayoutArgs layout;
  std::string format = kDecodeFormats[0].name;
  std::string output;
  std::vector<std::string> axes;
  bool layout_only = false;
  std::string timestamps = "auto";
  WindowArgs window;
  bool timing = false;  // the timing block on standard error at the end
  std::string read_thread = cli::kReadThreadDefault;
};

// What every decode format reads and writes.
struct DecodeInput {
  LayoutFiles files;
  std::unique_ptr<CaptureReader> reader;
  std::FILE* out = stdout;
  TimeWindow window;  // --from/--to
};

// The notes after a decode: which clock timed the frames, and why no axis was found.
void noteDecoded(const CaptureReader& reader, const FrameClock& clock, const Decoder& decoder) {
  if (clock.source() == TimestampSource::Probe || !clock.note().empty()) {
    fmt::print(stderr, "ncservo: {}: timestamps: {}{}{}\n", reader.path(),
               timestampSourceName(clock.source()), clock.note().empty() ? "" : "; ", clock.note());
  }
  if (decoder.axes().empty()) {
    fmt::print(stderr, "ncservo: {}: {}\n", reader.path(), decoder.noServoReason());
  }
}

int decodeRows(const DecodeArgs& args, DecodeInput& input) {
  CaptureReader* reader = input.reader.get();
  std::FILE* out = input.out;
  // --timing: the validator's bus model times the cycles as `validate` does (docs/timing.md).
  PipelineOptions options{decoderOptions(input.files, args.layout), std::nullopt, input.window,
                          *timestampModeFromName(args.timestamps)};
  if (args.timing && !args.layout_only) options.rules = RuleSettings{};
  CapturePipeline pipeline(std::move(options));
  std::optional<Session> session;
  const DecodeFormat& format = rowNamed(kDecodeFormats, args.format);
  // The header comes with the first rows, once the layout can tell whether --axis names its axes:
  // an --axis it does not have is a usage error with nothing written (docs/cli.md#exit-status).
  bool header_due = !args.layout_only && format.header != nullptr;
  Status selected;
  bool checked = args.axes.empty();
  CycleRows cycles;
  std::vector<CycleRow> rows;
  CutRegions cut;
  auto write = [&] {
    if (!checked && !rows.empty()) {
      selected = cli::checkAxisSelection(args.axes, session->decoder().axes());
      checked = true;
    }
    if (!selected) {
      rows.clear();
      return;
    }
    if (header_due && !rows.empty()) {
      format.header(out);
      header_due = false;
    }
    for (const CycleRow& row : rows) {
      const AxisInfo& axis = session->decoder().axes().at(row.axis);
      if (!cli::axisSelected(args.axes, axis)) continue;
      const std::int64_t since_first_ns = row.time_ns - *pipeline.run().first_time_ns;
      format.row(out, row, axis.name, static_cast<double>(since_first_ns) / 1e9);
    }
    rows.clear();
  };
  const auto decode = [&](const PipelineFrame& f) {
    const FrameView& view = session->onFrame(f.frame, f.bytes);
    if (args.layout_only) return;
    for (std::size_t i = 0; i < view.axis_count; ++i) cut.add(f.number, view.axes[i].placement);
    cycles.onFrame(f.number, f.time_ns, view, rows);
    write();
  };
  const auto start = [&](const DecoderOptions& layout) { session.emplace(layout); };
  const auto layout_only = [&](const PipelineFrame& f) {
    session->onLayoutOnlyFrame(f.frame, f.bytes);
  };
  pipeline.setSinks({start, decode, layout_only, nullptr});
  const Status status =
      streamCapture(*reader, pipeline, nullptr, cli::captureThreads(args.read_thread, 1));
  const CaptureRun& run = pipeline.run();
  const FrameClock& clock = pipeline.clock();
  cycles.finish(rows);
  write();
  if (selected) selected = cli::checkAxisSelection(args.axes, session->decoder().axes());
  if (header_due && selected) format.header(out);  // no rows: the header alone
  std::fflush(out);
  warnIfTruncated(reader->path(),
                  truncationOf(run.snapped, run.first_snapped, cut, session->decoder().axes()));
  if (const std::string empty = emptyWindowReason(input.window, run); !empty.empty()) {
    fmt::print(stderr, "ncservo: {}: {}\n", reader->path(), empty);
    return kExitNoServo;
  }
  if (!status) {
    fmt::print(stderr, "ncservo: {} (the frames before it were decoded)\n", status.error().text());
    return kExitCapture;
  }
  if (args.layout_only) printLayout(session->decoder(), pipeline.inference());
  noteDecoded(*reader, clock, session->decoder());
  if (pipeline.lateLayout().certain_at > 0) {
    fmt::print(stderr, "ncservo: {}: {}\n", reader->path(),
               cli::describeLateLayout(pipeline.lateLayout()));
  }
  if (const Validator* timing = pipeline.validator()) {
    fmt::print(stderr, "ncservo: {}: {}", reader->path(),
               timingText(timing->bus().timing().summary(), timestampSourceName(clock.source()),
                          timestampResolutionNs(clock.source(), reader->timestampDigits())));
    std::fputs(dcText(timing->dc().stations(), timing->dc().settledNs()).c_str(), stderr);
  }
  if (!selected) {
    fmt::print(stderr, "ncservo: {}\n", selected.error().text());
    return kExitUsage;
  }
  // No servo decoded (noteDecoded said why), as validate has it (docs/cli.md#exit-status).
  if (session->decoder().axes().empty()) return kExitNoServo;
  return kExitOk;
}

// The waveforms need the findings, so the capture goes through the validator, with the
// configuration's rule settings.
int decodeWaveforms(const DecodeArgs& args, DecodeInput& input) {
  CaptureReader& reader = *input.reader;
  RuleSettings settings;
  if (input.files.config) {
    if (Status s = applyConfig(*input.files.config, settings); !s) {
      fmt::print(stderr, "ncservo: {}\n", s.error().text());
      return kExitUsage;
    }
  }
  CapturePipeline pipeline({decoderOptions(input.files, args.layout), settings, input.window,
                            *timestampModeFromName(args.timestamps)});
  const bool to_stdout = input.out == stdout;
  cli::WaveformWriter waveforms(input.out, to_stdout ? "standard output" : args.output, args.axes);
  Status written;
  std::int64_t end_ns = 0;
  std::int64_t frame_ns = 0;  // the last frame's, where its findings and the capture's last show
  const auto decode = [&](const PipelineFrame& f) {
    if (!written) return;  // a failed write ends the work: the rest is read, not written
    frame_ns = f.time_ns - *pipeline.run().first_time_ns;
    end_ns = std::max(end_ns, frame_ns);
    written = waveforms.frame(frame_ns, *f.judged, pipeline.validator()->decoder());
  };
  const auto findings = [&](const std::vector<Finding>& found) {
    if (written) written = waveforms.findings(frame_ns, found);
  };
  pipeline.setSinks({nullptr, decode, nullptr, findings});
  // The VCD's text writer keeps a second thread busy already.
  const Status status =
      streamCapture(reader, pipeline, nullptr, cli::captureThreads(args.read_thread, 1, 2));
  const Validator& validator = *pipeline.validator();
  const CaptureRun& run = pipeline.run();
  if (written) written = waveforms.finish(end_ns, validator.decoder());
  std::fflush(input.out);
  warnIfTruncated(reader.path(), truncationOf(run.snapped, run.first_snapped,
                                              validator.cutRegions(), validator.decoder().axes()));
  if (const std::string empty = emptyWindowReason(input.window, run); !empty.empty()) {
    fmt::print(stderr, "ncservo: {}: {}\n", reader.path(), empty);
    return kExitNoServo;
  }
  if (!written) {
    fmt::print(stderr, "ncservo: {}\n", written.error().text());
    return kExitUsage;
  }
  if (!status) {
    fmt::print(stderr, "ncservo: {} (the frames before it were decoded)\n", status.error().text());
    return kExitCapture;
  }
  noteDecoded(reader, pipeline.clock(), validator.decoder());
  if (!to_stdout) {
    const std::string save = cli::gtkwPathFor(args.output);
    std::FILE* file = std::fopen(save.c_str(), "w");
    if (file == nullptr) {
      fmt::print(stderr, "ncservo: {}: cannot write: {}\n", save, std::strerror(errno));
      return kExitUsage;
    }
    cli::writeGtkwSave(file, std::filesystem::absolute(args.output).string(),
                       std::filesystem::absolute(save).string(), waveforms.scopes());
    std::fclose(file);
  }
  // No servo decoded (noteDecoded said why), as validate has it (docs/cli.md#exit-status).
  if (validator.decoder().axes().empty()) return kExitNoServo;
  return kExitOk;
}

// `-o FILE`, or standard output for none or "-".
Result<std::FILE*> openOutput(const std::string& output, const std::vector<std::string>& captures) {
  if (output.empty() || output == "-") return stdout;
  if (Status refused = refuseInputAsOutput("--output", output, captures); !refused)
    return fail(refused.error());
  std::FILE* out = std::fopen(output.c_str(), "w");
  if (out == nullptr)
    return fail(fmt::format("{}: cannot write: {}", output, std::strerror(errno)));
  return out;
}

int runDecode(const DecodeArgs& args) {
  DecodeInput input;
  const Result<TimeWindow> window = timeWindowOf(args.window.from_s, args.window.to_s);
  if (!window) {
    fmt::print(stderr, "ncservo: {}\n", window.error().text());
    return kExitUsage;
  }
  input.window = *window;
  Result<LayoutFiles> files = loadLayoutFiles(args.layout);
  if (!files) {
    fmt::print(stderr, "ncservo: {}\n", files.error().text());
    return kExitUsage;
  }
  input.files = std::move(*files);
  auto opened = CaptureReader::open(args.capture);
  if (!opened) {
    fmt::print(stderr, "ncservo: {}\n", opened.error().text());
    return kExitCapture;
  }
  input.reader = std::move(*opened);
  Result<std::FILE*> out = openOutput(args.output, {args.capture});
  if (!out) {
    fmt::print(stderr, "ncservo: {}\n", out.error().text());
    return kExitUsage;
  }
  input.out = *out;
  const auto decode = args.layout_only ? decodeRows : rowNamed(kDecodeFormats, args.format).decode;
  const int rc = decode(args, input);
  if (input.out != stdout) std::fclose(input.out);
  return rc;
}

// ---- validate ----

// What judges a capture, for validate and diff alike: the layout, the rules, the clock, the window.
struct CheckArgs : cli::RuleArgs {
  LayoutArgs layout;
  std::string timestamps = "auto";
  WindowArgs window;
  std::string read_thread = cli::kReadThreadDefault;
};

struct ValidateArgs : CheckArgs {
  std::vector<std::string> captures;
  std::string format = cli::reportFormatNames().front();
  std::string output;
  std::string fail_on = "error";
  bool allow_empty = false;
  bool verbose = false;
  std::optional<unsigned> jobs;      // default: the cores
  std::vector<std::string> reports;  // FORMAT:FILE
  std::string baseline;              // a JSON report (docs/baselines.md)
};

// CheckArgs made ready: the files loaded, the settings built, the window checked.
struct CheckSetup {
  LayoutFiles files;
  RuleSettings settings;
  TimeWindow window;
  TimestampMode timestamps = TimestampMode::Auto;
  DecoderOptions layout;
  // The ENI's tasks, whose cycle times the capture is held against
  // (docs/layout.md#eni-cycle-times).
  std::vector<EniCyclicFrame> eni_frames;
};

// A usage error (exit 2) when a file or an option is wrong.
Result<CheckSetup> prepareCheck(const CheckArgs& o) {
  CheckSetup setup;
  Result<LayoutFiles> files = loadLayoutFiles(o.layout);
  if (!files) return fail(files.error());
  setup.files = std::move(*files);
  if (Status built = buildSettings(o, setup.files.config, setup.settings); !built)
    return fail(built.error());
  const Result<TimeWindow> time_window = timeWindowOf(o.window.from_s, o.window.to_s);
  if (!time_window) return fail(time_window.error());
  setup.window = *time_window;
  setup.timestamps = *timestampModeFromName(o.timestamps);
  setup.layout = decoderOptions(setup.files, o.layout);
  if (setup.files.eni) setup.eni_frames = setup.files.eni->frames;
  return setup;
}

// Where one capture's report goes while it is made: to the writer as it comes (one capture at
// a time), or, with `live` null, kept whole with its messages for the writer (captures in
// parallel, written in argument order by presentCapture).
struct CaptureOutput {
  cli::ReportWriter* live;
  std::FILE* messages;  // standard error, or the capture's own buffer
};

// Runs one capture through the validator. Returns the capture's exit status (0, 1, 3 or 4), or
// 130 when Ctrl-C stopped it (its report unfinished, `frames` the frames read).
int validateCapture(const std::string& path, const CheckSetup& setup,
                    const cli::ReportWriter& writer, const CaptureOutput& output,
                    cli::CaptureReport& report, CaptureThreads threads) {
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
  std::optional<cli::TimelineRecorder> timelines;
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
      const cli::BaselineState state = report.tally(f);
      if (output.live == nullptr || writer.keepsFindings()) {
        report.findings.push_back(f);
        if (report.baseline) report.baseline_states.push_back(state);
      }
      if (timelines) timelines->finding(f);
      if (output.live != nullptr) output.live->finding(report, f, state);
    }
  };
  pipeline.setSinks({start, validate, nullptr, keepFindings});
  StreamStop stop{&cli::ReportWriter::interrupted()};
  const Status status = streamCapture(*reader, pipeline, &stop, threads);
  const CaptureRun& run = pipeline.run();
  if (stop.stopped) {  // Ctrl-C: not a report, only where it stopped (docs/cli.md#interrupted)
    report.frames = run.records;
    return kExitInterrupted;
  }
  static_cast<CaptureResult&>(report) = pipeline.result();
  for (const std::string& warning : report.layout_warnings) {
    fmt::print(output.messages, "ncservo: {}: layout does not fit: {}\n", path, warning);
  }
  if (timelines) report.timelines = timelines->finish();
  warnIfTruncated(reader->path(), report.truncation, output.messages);
  if (report.startup_frames_cut > 0) {
    fmt::print(output.messages, "ncservo: {}: layout {}\n", reader->path(),
               cli::describeStartupCut(report.startup_frames_cut));
  }
  report.capture_drops = reader->drops();
  if (!status) {
    report.error = status.error().text() + " (the frames before it were analysed)";
    fmt::print(output.messages, "ncservo: {}\n", *report.error);
  }
  if (writer.locatesFrames()) {
    if (Status located = cli::locateFindings(report); !located) {
      fmt::print(output.messages, "ncservo: {}: frames not located in the file: {}\n", path,
                 located.error().text());
    }
  }
  report.closeBaseline();
  if (output.live != nullptr) output.live->endCapture(report);
  return writer.exitStatus(report);
}

// A capture validated apart (CaptureOutput without `live`) given to the writer as if it had
// been written as it came: its messages, its findings one by one, its end.
void presentCapture(cli::ReportWriter& writer, const std::string& messages,
                    cli::CaptureReport& report) {
  std::fputs(messages.c_str(), stderr);
  writer.beginCapture(report);
  for (std::size_t i = 0; i < report.findings.size(); ++i) {
    writer.finding(report, report.findings[i],
                   report.baseline ? report.baseline_states[i] : cli::BaselineState::None);
  }
  writer.endCapture(report);
  if (!writer.keepsFindings()) {
    std::vector<Finding>().swap(report.findings);
    std::vector<cli::BaselineState>().swap(report.baseline_states);
  }
}

// docs/cli.md: with several captures the status is the most serious, in the order 2, 3, 1, 4, 0.
int combine(int a, int b) {
  return cli::moreSerious(a, b);
}

// Whether two paths name one file, however spelt (links, "./"), whether or not it exists yet.
bool sameFile(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (std::filesystem::equivalent(a, b, ec)) return true;
  const auto canonical_a = std::filesystem::weakly_canonical(a, ec);
  if (ec) return false;
  const auto canonical_b = std::filesystem::weakly_canonical(b, ec);
  return !ec && canonical_a == canonical_b;
}

// The reports of a run: --format to --output (standard output by default), then each
// --report FORMAT:FILE. docs/cli.md: a report file that is one of the inputs, however named,
// is a usage error, and so are two reports to one file; checked before anything is written.
Result<std::vector<cli::ReportTarget>> reportTargets(const ValidateArgs& o) {
  std::vector<cli::ReportTarget> targets{{cli::findReportFormat(o.format), o.output}};
  std::vector<std::string> options{"--output"};
  for (const std::string& spec : o.reports) {
    const auto colon = spec.find(':');
    const cli::ReportFormat* format =
        colon == std::string::npos ? nullptr : cli::findReportFormat(spec.substr(0, colon));
    if (format == nullptr || colon + 1 == spec.size()) {
      return fail(fmt::format("--report {}: expected FORMAT:FILE, FORMAT one of {}", spec,
                              choiceList(cli::reportFormatNames())));
    }
    const std::string path = spec.substr(colon + 1);
    if (path == "-") {
      return fail(
          fmt::format("--report {}: standard output has the --format report; give a file", spec));
    }
    targets.push_back({format, path});
    options.push_back("--report " + spec.substr(0, colon) + ":");
  }
  for (std::size_t t = 0; t < targets.size(); ++t) {
    const std::string& path = targets[t].path;
    if (path.empty() || path == "-") continue;
    if (Status refused = refuseInputAsOutput(options[t], path, o.captures); !refused)
      return fail(refused.error());
    for (std::size_t u = 0; u < t; ++u) {
      const std::string& other = targets[u].path;
      if (!other.empty() && other != "-" && sameFile(path, other)) {
        return fail(fmt::format("{} {} and {} {} are one file: give each report its own",
                                options[u], other, options[t], path));
      }
    }
  }
  return targets;
}

int runValidate(const ValidateArgs& o) {
  if (std::count(o.captures.begin(), o.captures.end(), "-") > 1) {
    fmt::print(stderr, "ncservo: standard input (-) can be read only once\n");
    return kExitUsage;
  }
  const Result<CheckSetup> setup = prepareCheck(o);
  if (!setup) {
    fmt::print(stderr, "ncservo: {}\n", setup.error().text());
    return kExitUsage;
  }
  // docs/baselines.md: a baseline that cannot be read is a usage error, as a bad --config is.
  std::optional<cli::ReportFile> baseline;
  if (!o.baseline.empty()) {
    Result<cli::ReportFile> loaded = cli::loadReportFile(o.baseline);
    if (!loaded) {
      fmt::print(stderr, "ncservo: --baseline {}\n", loaded.error().text());
      return kExitUsage;
    }
    baseline = std::move(*loaded);
  }
  const Result<std::vector<cli::ReportTarget>> targets = reportTargets(o);
  if (!targets) {
    fmt::print(stderr, "ncservo: {}\n", targets.error().text());
    return kExitUsage;
  }
  cli::ReportPolicy policy;
  cli::setFailOn(o.fail_on, policy);
  policy.allow_empty = o.allow_empty;
  policy.verbose = o.verbose;
  policy.enabled = setup->settings.enabled;
  auto writer = cli::ReportWriter::open(*targets, policy);
  if (!writer) {
    fmt::print(stderr, "ncservo: {}\n", writer.error().text());
    return kExitUsage;
  }
  std::vector<cli::CaptureReport> reports(o.captures.size());
  if (baseline) {
    for (std::size_t i = 0; i < o.captures.size(); ++i) {
      const cli::ReportedCapture* matched =
          cli::baselineCaptureFor(*baseline, o.captures[i], o.captures.size());
      if (matched == nullptr) {
        fmt::print(stderr,
                   "ncservo: {}: no capture of this file name in the baseline {}: each of its "
                   "findings is new\n",
                   o.captures[i], o.baseline);
      }
      reports[i].baseline.emplace(matched);
      reports[i].baseline_path = o.baseline;
    }
  }
  // docs/cli.md#interrupted: each capture's status; kExitInterrupted for one Ctrl-C stopped or kept
  // from starting (`reports[i].frames` then says how far it got).
  std::vector<int> statuses(o.captures.size(), kExitInterrupted);
  (*writer)->stopOnInterrupt();
  const std::atomic<bool>& interrupted = cli::ReportWriter::interrupted();
  int rc = kExitOk;
  const unsigned jobs = o.jobs.value_or(std::max(1u, std::thread::hardware_concurrency()));
  const bool one_at_a_time = jobs <= 1 || o.captures.size() <= 1;
  // docs/cli.md#two-threads: the reading threads and --jobs share the cores.
  const CaptureThreads threads = cli::captureThreads(
      o.read_thread,
      one_at_a_time ? 1u : static_cast<unsigned>(std::min<std::size_t>(jobs, o.captures.size())));
  if (one_at_a_time) {
    for (std::size_t i = 0; i < o.captures.size() && !interrupted; ++i) {
      statuses[i] = validateCapture(o.captures[i], *setup, **writer, {writer->get(), stderr},
                                    reports[i], threads);
    }
  } else {
    struct Validated {
      int rc;
      std::string messages;
    };
    const std::function<Validated(std::size_t)> validate = [&](std::size_t i) {
      if (interrupted) return Validated{kExitInterrupted, {}};
      char* buffer = nullptr;
      std::size_t size = 0;
      std::FILE* messages = open_memstream(&buffer, &size);
      const int status = validateCapture(o.captures[i], *setup, **writer, {nullptr, messages},
                                         reports[i], threads);
      std::fclose(messages);
      Validated validated{status, std::string(buffer, size)};
      std::free(buffer);
      return validated;
    };
    const std::function<void(std::size_t, Validated&)> present = [&](std::size_t i,
                                                                     Validated& validated) {
      statuses[i] = validated.rc;
      if (validated.rc == kExitInterrupted) {
        std::fputs(validated.messages.c_str(), stderr);
        return;
      }
      presentCapture(**writer, validated.messages, reports[i]);
    };
    cli::runInOrder(o.captures.size(), jobs, validate, present);
  }
  // Only finished captures are reported; where Ctrl-C stopped the others is said on stderr.
  std::vector<cli::CaptureReport> finished;
  std::vector<std::string> unstarted;
  for (std::size_t i = 0; i < o.captures.size(); ++i) {
    if (statuses[i] != kExitInterrupted) {
      rc = combine(rc, statuses[i]);
      finished.push_back(std::move(reports[i]));
    } else if (reports[i].path.empty()) {
      unstarted.push_back(o.captures[i]);
    } else {
      fmt::print(stderr, "ncservo: interrupted at {}, frame {}\n",
                 o.captures[i] == "-" ? std::string("standard input") : o.captures[i],
                 reports[i].frames);
      rc = kExitInterrupted;
    }
  }
  if (interrupted) rc = kExitInterrupted;  // before the reports were written, as the text says
  if (!unstarted.empty()) {
    fmt::print(stderr, "ncservo: interrupted before {}\n", fmt::join(unstarted, ", "));
  }
  if (Status written = (*writer)->finish(finished); !written) {
    fmt::print(stderr, "ncservo: {}\n", written.error().text());
    return kExitUsage;
  }
  return rc;
}

// ---- diff ----

struct DiffArgs {
  std::string base, next;
  std::string format = cli::diffFormatNames().front();
  std::string output;
  std::string fail_on = "error";
  CheckArgs check;
};

// One side of a diff: a JSON report of validate (its one capture), or a capture validated as
// validate does. Exit status 3 when it cannot be read, 2 when a report holds several captures.
struct DiffSide {
  int rc = kExitOk;
  cli::ReportedCapture capture;
};
DiffSide diffSide(const std::string& path, const CheckSetup& setup, const cli::ReportWriter& writer,
                  const cli::ReportPolicy& policy, CaptureThreads threads) {
  if (cli::looksLikeJsonReport(path)) {
    Result<cli::ReportFile> report = cli::loadReportFile(path);
    if (!report) {
      fmt::print(stderr, "ncservo diff: {}\n", report.error().text());
      return {kExitCapture, {}};
    }
    if (report->captures.size() != 1) {
      fmt::print(stderr, "ncservo diff: {}: holds {} captures; diff compares one with one\n", path,
                 report->captures.size());
      return {kExitUsage, {}};
    }
    return {kExitOk, std::move(report->captures.front())};
  }
  cli::CaptureReport report;
  const int rc = validateCapture(path, setup, writer, {nullptr, stderr}, report, threads);
  if (rc == kExitCapture) return {rc, {}};
  return {kExitOk, cli::reportedCaptureOf(report, cli::verdictOf(policy, report))};
}

int runDiff(const DiffArgs& o) {
  if (o.base == "-" && o.next == "-") {
    fmt::print(stderr, "ncservo diff: standard input (-) can be read only once\n");
    return kExitUsage;
  }
  const Result<CheckSetup> setup = prepareCheck(o.check);
  if (!setup) {
    fmt::print(stderr, "ncservo diff: {}\n", setup.error().text());
    return kExitUsage;
  }
  cli::ReportPolicy policy;
  cli::setFailOn(o.fail_on, policy);
  policy.enabled = setup->settings.enabled;
  Result<std::FILE*> out = openOutput(o.output, {o.base, o.next});
  if (!out) {
    fmt::print(stderr, "ncservo diff: {}\n", out.error().text());
    return kExitUsage;
  }
  // No report is written: the captures' findings are kept for the comparison.
  auto writer = cli::ReportWriter::open({}, policy);
  const CaptureThreads threads = cli::captureThreads(o.check.read_thread, 1);
  DiffSide base = diffSide(o.base, *setup, **writer, policy, threads);
  DiffSide next =
      base.rc == kExitOk ? diffSide(o.next, *setup, **writer, policy, threads) : DiffSide{};
  int rc = base.rc != kExitOk ? base.rc : next.rc;
  if (rc == kExitOk) {
    cli::CaptureDiff diff = cli::diffCaptures(std::move(base.capture), std::move(next.capture));
    diff.base_source = o.base;
    diff.next_source = o.next;
    cli::writeDiff(*out, o.format, diff);
    rc = cli::diffFails(diff, policy.fail_on, policy.never) ? kExitFindings : kExitOk;
  }
  const bool written = std::fflush(*out) == 0;
  if (*out != stdout) std::fclose(*out);
  if (!written) {
    fmt::print(stderr, "ncservo diff: {}: cannot write\n",
               o.output.empty() ? "standard output" : o.output);
    return kExitUsage;
  }
  return rc;
}

// ---- rules and fields: the library's tables as text ----

void printRuleText(const RuleDef& rule) {
  fmt::print("{:<8} {:<27} {:<8} {:<6} {}{}\n", rule.code, rule.slug, severityName(rule.severity),
             partyName(rule.party), rule.summary,
             rule.by_default == ByDefault::Off ? " (off by default)" : "");
}

const TimeoutDef& timeoutDef(Timeout timeout) {
  return kTimeouts[static_cast<std::size_t>(timeout)];
}

// "drive_response (20 ms)", or "" for a rule without a timeout.
std::string timeoutText(const RuleDef& rule) {
  if (!rule.timeout) return "";
  const TimeoutDef& t = timeoutDef(*rule.timeout);
  return fmt::format("{} ({} ms)", t.name, t.default_ms);
}

const char* byDefaultName(ByDefault by_default) {
  return by_default == ByDefault::On ? "on" : "off";
}

void printRuleMarkdown(const RuleDef& rule) {
  // An anchor per rule: SARIF's helpUri (report.cpp) links each rule here.
  fmt::print("| <a id=\"{}\"></a>{} | `{}` | {} | {} | {} | {} | {} | {} | {} | {} |\n",
             cli::ruleAnchor(rule), rule.code, rule.slug, severityName(rule.severity),
             byDefaultName(rule.by_default), partyName(rule.party), ruleKindName(rule.kind),
             describeReads(rule.reads), timeoutText(rule), rule.clause, rule.summary);
}

// The timeouts with their defaults and the rules that use them.
void printTimeoutsMarkdown() {
  fmt::print(
      "\n| timeout | default (ms) | used by |\n"
      "|---|---|---|\n");
  for (const TimeoutDef& t : kTimeouts) {
    std::vector<std::string> users;
    for (const RuleDef& rule : kRules) {
      if (rule.timeout == t.id) users.emplace_back(rule.code);
    }
    fmt::print("| `{}` | {} | {} |\n", t.name, t.default_ms,
               users.empty() ? std::string("capture segments (a longer pause starts one)")
                             : fmt::format("{}", fmt::join(users, ", ")));
  }
}

// The timeouts, then the limits of the rules that are off by default.
void printRuleSettingsMarkdown() {
  printTimeoutsMarkdown();
  fmt::print(
      "\n| limit | default | range | used by |\n"
      "|---|---|---|---|\n");
  for (const LimitDef& l : kLimits) {
    std::vector<std::string> users;
    for (const RuleDef& rule : kRules) {
      if (rule.limit == l.id) users.emplace_back(rule.code);
    }
    fmt::print("| `{}` | {} | {} to {} ({}) | {} |\n", l.name, l.default_value, l.min, l.max,
               l.unit, fmt::join(users, ", "));
  }
}

// `rules`'s formats: a header, then one line per rule, then an optional footer.
struct RuleListFormat {
  const char* name;
  const char* header;
  void (*rule)(const RuleDef& rule);
  void (*footer)();
};
const RuleListFormat kRuleListFormats[] = {
    {.name = "text", .header = "", .rule = printRuleText, .footer = nullptr},
    {.name = "markdown",
     .header =
         "| ID | slug | severity | by default | party | judged on | reads | timeout (default) "
         "| clause | summary |\n"
         "|---|---|---|---|---|---|---|---|---|---|\n",
     .rule = printRuleMarkdown,
     .footer = printRuleSettingsMarkdown},
};

// `rules --explain ID`: one rule in full, from its row of the rule table.
void explainRule(const RuleDef& rule) {
  fmt::print("{} {}\n", rule.code, rule.slug);
  fmt::print("  fires when:  {}\n", rule.summary);
  fmt::print("  severity:    {} (change it with --severity {}=LEVEL)\n",
             severityName(rule.severity), rule.code);
  if (rule.by_default == ByDefault::Off) {
    fmt::print("  by default:  off (run it with --enable {} or [rules] enable)\n", rule.code);
  }
  if (rule.limit) {
    const LimitDef& l = kLimits[static_cast<std::size_t>(*rule.limit)];
    fmt::print(
        "  limit:       {}, default {} ({}) (--limit {}=VALUE, or {} in the configuration)\n",
        l.name, l.default_value, l.unit, l.name, l.name);
  }
  fmt::print("  party:       {}\n", partyName(rule.party));
  fmt::print("  judged on:   {}\n", ruleKindName(rule.kind));
  if (rule.timeout) {
    const TimeoutDef& t = timeoutDef(*rule.timeout);
    fmt::print("  timeout:     {}, default {} ms (--timeout {}=MS, [timeouts] {})\n", t.name,
               t.default_ms, t.name, t.name);
  }
  fmt::print("  reported:    {}\n",
             rule.delayed()                ? "once the condition has held longer than the timeout"
             : rule.reported != nullptr    ? rule.reported
             : rule.kind == RuleKind::Axis ? "on the frame where the condition begins"
                                           : "on the frame of the event");
  fmt::print("  reads:       {}\n", describeReads(rule.reads));
  fmt::print("  clause:      {}\n", rule.clause);
  fmt::print("  filter:      {}\n", ruleFilterName(rule));
  fmt::print("  docs:        docs/rules.md\n");
}

std::string maskText(const FieldDef& f) {
  return f.mask ? fmt::format("0x{:X}", f.mask) : "all";
}

void printFieldTsv(const FieldDef& f) {
  fmt::print("{}\t{}\t{}\t{}\t{}\n", f.filter, f.label, wordDef(f.word).name, maskText(f), f.blurb);
}

void printDerivedTsv(const DerivedFieldDef& f) {
  fmt::print("{}\t{}\t(derived)\t\t{}\n", f.filter, f.label, f.blurb);
}

void printFieldMarkdown(const FieldDef& f) {
  std::string values;
  for (std::size_t i = 0; i < f.value_count; ++i) {
    values += fmt::format("{}{}={}{}", i ? "; " : "", f.values[i].value, f.values[i].name,
                          f.values[i].unit ? fmt::format(" [{}]", f.values[i].unit) : "");
  }
  fmt::print("| `{}` | {} | {} | {} | {} | {} | {} |\n", f.filter, f.label, wordDef(f.word).name,
             maskText(f), values, f.blurb, f.clause);
}

void printDerivedMarkdown(const DerivedFieldDef& f) {
  fmt::print("| `{}` | {} | (derived) | | | {} | docs/plugin.md |\n", f.filter, f.label, f.blurb);
}

// `fields`'s formats: a header, then one line per field of the field table, then per derived field.
struct FieldListFormat {
  const char* name;
  const char* header;
  void (*field)(const FieldDef& f);
  void (*derived)(const DerivedFieldDef& f);
};
const FieldListFormat kFieldListFormats[] = {
    {.name = "tsv", .header = "", .field = printFieldTsv, .derived = printDerivedTsv},
    {.name = "markdown",
     .header = "| filter name | label | word | bits | values | meaning | spec |\n"
               "|---|---|---|---|---|---|---|\n",
     .field = printFieldMarkdown,
     .derived = printDerivedMarkdown},
};

// ---- simulate ----

// `simulate`'s capture formats; without --format the output file's extension chooses, else the
// first row.
struct CaptureFormatRow {
  const char* name;
  CaptureFormat format;
  const char* extension;
};
const CaptureFormatRow kCaptureFormats[] = {
    {"pcap", CaptureFormat::Pcap, ".pcap"},
    {"pcapng", CaptureFormat::Pcapng, ".pcapng"},
};

// The format by the name under a compression extension ("x.pcapng.zst" is a pcapng).
CaptureFormat captureFormatFor(const std::string& format, const std::string& output) {
  if (!format.empty()) return rowNamed(kCaptureFormats, format).format;
  const std::string_view name = withoutCompressionExtension(output);
  for (const CaptureFormatRow& row : kCaptureFormats) {
    const std::size_t length = std::strlen(row.extension);
    if (name.size() >= length && name.substr(name.size() - length) == row.extension)
      return row.format;
  }
  return kCaptureFormats[0].format;
}

// `simulate --compress`; without it the output file's extension chooses (.gz, .zst).
struct CompressionRow {
  const char* name;
  Compression compression;
};
const CompressionRow kCompressions[] = {
    {"none", Compression::None},
    {"gzip", Compression::Gzip},
    {"zstd", Compression::Zstd},
};

// `simulate --probe`.
struct ProbeRow {
  const char* name;
  sim::Probe probe;
};
const ProbeRow kProbes[] = {
    {"none", sim::Probe::None},
    {"esl", sim::Probe::Esl},
};

struct SimulateArgs {
  sim::SimOptions options;
  std::string scenario = "commissioning";
  std::string image;   // empty: soem
  std::string layout;  // the older name of --image
  std::string probe = "none";
  std::string output;
  std::string format;    // empty: from the file name
  std::string compress;  // empty: from the file name
  std::vector<std::string> faults;
  std::vector<std::string> late_cycles;
  std::vector<std::string> lost_cycles;
  std::string layout_config;
  std::string eni;
  std::string incidents_truth;
  std::string io_inputs = "slow";
  std::string idle;      // SECONDS or all; empty: none
  std::string start_in;  // empty: the capture starts with the session
  bool no_startup = false;
  bool list_faults = false;
};

// --idle SECONDS|all into the options; false (with the message printed) when malformed.
bool parseIdle(const std::string& text, sim::SimOptions& o) {
  if (text.empty()) return true;
  if (text == "all") {
    o.idle_all = true;
    return true;
  }
  const Result<double> seconds = parseNumber<double>(text);
  if (seconds && *seconds > 0) {
    o.idle_s = *seconds;
    return true;
  }
  fmt::print(stderr, "ncservo simulate: --idle {}: seconds above 0, or all\n", text);
  return false;
}

void printFaults() {
  fmt::print("{:<8} {:<11} {}\n", "rule", "companions", "what the simulator does");
  for (const RuleDef& rule : kRules) {
    std::string companions;
    for (RuleId c : sim::companionsOf(rule.id)) {
      companions += (companions.empty() ? "" : ",") + std::string(ruleDef(c).code);
    }
    fmt::print("{:<8} {:<11} {}\n", rule.code, companions.empty() ? "-" : companions,
               sim::faultDescription(rule.id));
  }
}

int runSimulate(SimulateArgs& args) {
  if (args.list_faults) {
    printFaults();
    return kExitOk;
  }
  if (args.output.empty()) {
    fmt::print(
        stderr,
        "ncservo simulate: give the capture to write with -o FILE (- for standard output)\n");
    return kExitUsage;
  }
  sim::SimOptions& o = args.options;
  o.scenario = *sim::scenarioFromName(args.scenario);
  const std::string& style = !args.image.empty() ? args.image : args.layout;
  o.image = style.empty() ? sim::ImageStyle::Soem : *sim::imageStyleFromName(style);
  o.probe = rowNamed(kProbes, args.probe).probe;
  o.startup = !args.no_startup;
  o.terminal_inputs = rowNamed(sim::kTerminalInputs, args.io_inputs).inputs;
  if (!args.start_in.empty()) o.mid_start = *sim::midStartFromName(args.start_in);
  if (!parseIdle(args.idle, o)) return kExitUsage;
  for (const std::string& text : args.faults) {
    Result<sim::FaultRequest> fault = sim::parseFault(text);
    if (!fault) {
      fmt::print(stderr, "ncservo simulate: {}\n", fault.error().text());
      return kExitUsage;
    }
    o.faults.push_back(std::move(*fault));
  }
  for (auto [option, texts, into] :
       {std::tuple{"--late-cycle", &args.late_cycles, &o.late_cycles},
        std::tuple{"--lost-cycles", &args.lost_cycles, &o.lost_cycles}}) {
    for (const std::string& text : *texts) {
      Result<sim::CycleDisturbance> parsed = sim::parseCycleDisturbance(option, text);
      if (!parsed) {
        fmt::print(stderr, "ncservo simulate: {}\n", parsed.error().text());
        return kExitUsage;
      }
      into->push_back(std::move(*parsed));
    }
  }
  if (!args.incidents_truth.empty() && o.scenario != sim::Scenario::Incidents) {
    fmt::print(stderr, "ncservo simulate: --incidents-truth needs --scenario incidents\n");
    return kExitUsage;
  }
  if (Status resolved = sim::resolveOptions(o); !resolved) {
    fmt::print(stderr, "ncservo simulate: {}\n", resolved.error().text());
    return kExitUsage;
  }
  sim::Simulator simulator(o);
  if (!args.layout_config.empty()) {
    std::ofstream out(args.layout_config);
    out << simulator.layoutConfig();
    if (!out.flush()) {
      fmt::print(stderr, "ncservo simulate: {}: cannot write the layout\n", args.layout_config);
      return kExitUsage;
    }
  }
  if (!args.eni.empty()) {
    std::ofstream out(args.eni);
    out << simulator.eni();
    if (!out.flush()) {
      fmt::print(stderr, "ncservo simulate: {}: cannot write the ENI file\n", args.eni);
      return kExitUsage;
    }
  }
  const Compression compression = args.compress.empty()
                                      ? compressionForName(args.output)
                                      : rowNamed(kCompressions, args.compress).compression;
  Result<std::unique_ptr<CaptureWriter>> writer =
      CaptureWriter::open(args.output, captureFormatFor(args.format, args.output), compression);
  // An output that cannot be written is a usage error, as for every command (docs/cli.md).
  if (!writer) {
    fmt::print(stderr, "ncservo simulate: {}\n", writer.error().text());
    return kExitUsage;
  }
  const auto frames = simulator.run([&](const sim::SimFrame& frame) {
    return (*writer)->write(frame.time_ns, frame.data, frame.size);
  });
  const Status closed = (*writer)->close();
  if (!closed || !frames) {
    fmt::print(stderr, "ncservo simulate: {}\n",
               closed ? args.output + ": write failed" : closed.error().text());
    return kExitUsage;
  }
  if (args.output != "-") {
    fmt::print(stderr, "ncservo simulate: wrote {} frames to {}\n", *frames, args.output);
  }
  if (args.options.capture_loss > 0) {
    fmt::print(stderr, "ncservo simulate: {} master copies left out of the capture\n",
               simulator.masterCopiesDropped());
  }
  if (!args.incidents_truth.empty()) {
    const Result<std::vector<sim::IncidentTruth>> incidents = simulator.incidents();
    if (!incidents) {
      fmt::print(stderr, "ncservo simulate: {}\n", incidents.error().text());
      return kExitCapture;
    }
    std::ofstream out(args.incidents_truth);
    out << sim::incidentsJson(*incidents);
    if (!out.flush()) {
      fmt::print(stderr, "ncservo simulate: {}: cannot write the incidents\n",
                 args.incidents_truth);
      return kExitUsage;
    }
  }
  return kExitOk;
}

// ---- The subcommands ----

using cli::Handler;

Handler decodeCommand(CLI::App& command) {
  auto args = std::make_shared<DecodeArgs>();
  command.add_option("CAPTURE", args->capture, "pcap or pcapng capture, - for standard input")
      ->required();
  addLayoutOptions(command, args->layout);
  addFormatOption(command, args->format, namesOf(kDecodeFormats),
                  " (vcd: waveforms for GTKWave, and beside -o OUT.vcd the save file OUT.gtkw)");
  command.add_option("-o,--output", args->output, "write here (default: standard output)");
  command
      .add_option("--axis", args->axes,
                  "only these axes, by name or index (comma-separated, repeatable)")
      ->delimiter(',')
      ->allow_extra_args(false);
  command.add_flag("--timing", args->timing,
                   "at the end, the timing statistics of validate's text report on standard "
                   "error (docs/timing.md)");
  command.add_flag("--layout", args->layout_only,
                   "print the layout found (as a configuration file) and the slaves the start-up "
                   "configured, instead of the process data");
  addTimestampsOption(command, args->timestamps);
  addWindowOptions(command, args->window);
  cli::addReadThreadOption(command, args->read_thread);
  return [args] { return runDecode(*args); };
}

Handler validateCommand(CLI::App& command) {
  auto args = std::make_shared<ValidateArgs>();
  command.add_option("CAPTURE", args->captures, "pcap or pcapng captures, - for standard input")
      ->required();
  addLayoutOptions(command, args->layout);
  addFormatOption(command, args->format, cli::reportFormatNames());
  command.add_option("-o,--output", args->output,
                     "write the report here (default: standard output)");
  command
      .add_option("--report", args->reports,
                  "FORMAT:FILE: also write that report to that file (repeatable)")
      ->allow_extra_args(false);
  command.add_flag("-v,--verbose", args->verbose,
                   "text: every finding, not one line per rule and axis");
  cli::addFailOnOption(command, args->fail_on);
  command.add_option("--baseline", args->baseline,
                     "REPORT.json: a JSON report of an earlier run; each finding is new or "
                     "unchanged against it, and --fail-on counts the new ones (docs/baselines.md)");
  cli::addRuleOptions(command, *args);
  addTimestampsOption(command, args->timestamps);
  addWindowOptions(command, args->window);
  command.add_flag("--allow-empty", args->allow_empty,
                   "exit 0, not 4, where no servo (or not every configured axis) was decoded");
  command
      .add_option("-j,--jobs", args->jobs,
                  "validate this many captures at once (default: the cores); the output is "
                  "in argument order, as with 1")
      ->check(CLI::Range(1u, 1024u));
  cli::addReadThreadOption(command, args->read_thread);
  return [args] { return runValidate(*args); };
}

Handler diffCommand(CLI::App& command) {
  auto args = std::make_shared<DiffArgs>();
  command.add_option("BASE", args->base, "the capture or JSON report compared against")->required();
  command.add_option("NEW", args->next, "the capture or JSON report compared")->required();
  addFormatOption(command, args->format, cli::diffFormatNames());
  command.add_option("-o,--output", args->output, "write here (default: standard output)");
  cli::addFailOnOption(command, args->fail_on);
  // A capture is validated as `validate` would, with the same options.
  addLayoutOptions(command, args->check.layout);
  cli::addRuleOptions(command, args->check);
  addTimestampsOption(command, args->check.timestamps);
  addWindowOptions(command, args->check.window);
  cli::addReadThreadOption(command, args->check.read_thread);
  return [args] { return runDiff(*args); };
}

Handler rulesCommand(CLI::App& command) {
  struct RulesArgs {
    std::string format = kRuleListFormats[0].name;
    std::string explain;
  };
  auto args = std::make_shared<RulesArgs>();
  addFormatOption(command, args->format, namesOf(kRuleListFormats));
  command.add_option("--explain", args->explain,
                     "print one rule in full: what fires it, its timeout and default, what it "
                     "reads (ID in any case)");
  return [args] {
    if (!args->explain.empty()) {
      const Result<const RuleDef*> rule = findRule(args->explain);
      if (!rule) {
        fmt::print(stderr, "ncservo rules: {}\n", rule.error().text());
        return kExitUsage;
      }
      explainRule(**rule);
      return kExitOk;
    }
    const RuleListFormat& list = rowNamed(kRuleListFormats, args->format);
    fmt::print("{}", list.header);
    for (const RuleDef& rule : kRules) list.rule(rule);
    if (list.footer != nullptr) list.footer();
    return kExitOk;
  };
}

Handler fieldsCommand(CLI::App& command) {
  auto format = std::make_shared<std::string>(kFieldListFormats[0].name);
  addFormatOption(command, *format, namesOf(kFieldListFormats));
  return [format] {
    const FieldListFormat& list = rowNamed(kFieldListFormats, *format);
    fmt::print("{}", list.header);
    for (const FieldDef& f : kFields) list.field(f);
    for (const DerivedFieldDef& f : kDerivedFields) list.derived(f);
    return kExitOk;
  };
}

Handler simulateCommand(CLI::App& command) {
  auto args = std::make_shared<SimulateArgs>();
  SimulateArgs& sa = *args;
  command.add_option("-o,--output", sa.output, "capture to write, - for standard output");
  command.add_option("--scenario", sa.scenario, "commissioning, faults, soak or incidents")
      ->check(cli::oneOf({"commissioning", "faults", "soak", "incidents"}));
  command.add_option("--axes", sa.options.axes, "servo axes, 1 to 32 (default 4)");
  command.add_option("--io-slaves", sa.options.io_slaves,
                     "other slaves sharing the process image, 0 to 32 (default: soem and "
                     "etherlab 0, 8-bit digital terminals; mixed 8 and twincat 4, terminals and "
                     "drives of other sizes)");
  command.add_option("--cycle-us", sa.options.cycle_us, "cycle time, 125 to 10000 (default 1000)");
  command.add_option("--duration", sa.options.duration_s,
                     "seconds (default: commissioning 3, faults 4.3, soak 60, incidents 20)");
  command.add_option("--seed", sa.options.seed, "the same seed and options give the same bytes");
  std::vector<std::string> styles, aliases;
  std::string style_help = "the master's process image (docs/simulate.md; default soem):";
  for (const sim::ImageStyleName& row : sim::kImageStyles) {
    styles.emplace_back(row.name);
    style_help += fmt::format(" {} ({}),", row.name, row.summary);
    if (row.layout_alias != nullptr) aliases.emplace_back(row.layout_alias);
  }
  style_help.back() = '.';
  CLI::Option* image =
      command.add_option("--image", sa.image, style_help)->check(cli::oneOf(styles));
  command.add_option("--layout", sa.layout, "older names: default = soem, interleaved = etherlab")
      ->check(cli::oneOf(aliases))
      ->excludes(image);
  command
      .add_option("--probe", sa.probe,
                  "none, or esl: an ET2000 probe's capture (each frame behind an ESL header "
                  "with the exact time; the capture's own timestamps late by up to 300 us)")
      ->check(cli::oneOf(namesOf(kProbes)));
  command.add_flag("--no-startup", sa.no_startup,
                   "begin with the slaves already in OP (no start-up traffic)");
  addFormatOption(command, sa.format, namesOf(kCaptureFormats),
                  " (default: from the file name, under .gz or .zst)");
  command
      .add_option("--compress", sa.compress,
                  "none, gzip or zstd (default: from the file name: .gz gzip, .zst zstd)")
      ->check(cli::oneOf(namesOf(kCompressions)));
  command.add_option("--fault", sa.faults,
                     "RULE[@SECONDS][:AXIS]: make that rule fire (repeatable; see --list-faults)");
  command.add_option("--ready-mode", sa.options.ready_mode, "the drives' Servo_Ready_Mode, 0 or 1");
  command.add_option("--jitter-us", sa.options.jitter_us, "master send jitter, microseconds");
  command.add_option("--latency-us", sa.options.latency_us,
                     "returned copies this long after their master copy, microseconds (default: "
                     "the ring's own few microseconds)");
  command.add_option(
      "--late-cycle", sa.late_cycles,
      "SECONDS:US: the first cycle at or after SECONDS is sent US late (repeatable)");
  command.add_option("--lost-cycles", sa.lost_cycles,
                     "SECONDS:N: N cycles from the first at or after SECONDS are not sent "
                     "(repeatable)");
  command.add_option("--loss", sa.options.loss,
                     "probability that a returned frame is lost (COM-004 findings)");
  command.add_option("--capture-loss", sa.options.capture_loss,
                     "probability that the capture misses a cycle's master copies, keeping "
                     "their returned copies (not the bus: no COM-002)");
  std::string inputs_help = "how often the terminals' inputs change (default slow):";
  for (const sim::TerminalInputsName& row : sim::kTerminalInputs) {
    inputs_help += fmt::format(" {} ({}),", row.name, row.summary);
  }
  inputs_help.back() = '.';
  command.add_option("--io-inputs", sa.io_inputs, inputs_help)
      ->check(cli::oneOf(namesOf(sim::kTerminalInputs)));
  command.add_option("--cia402", sa.options.cia402_drives,
                     "CiA 402 drives with a servo's 10/40-byte PDOs beside the servos, 0 to 32");
  command.add_option("--idle", sa.idle,
                     "SECONDS or all: the drives ready and nothing enabled for that long after "
                     "the start-up, or for the whole capture");
  std::string start_help = "the capture begins in the middle of the commissioning session:";
  for (const sim::MidStartName& row : sim::kMidStarts) {
    start_help += fmt::format(" {} ({}),", row.name, row.summary);
  }
  start_help.back() = '.';
  command.add_option("--start-in", sa.start_in, start_help)
      ->check(cli::oneOf(namesOf(sim::kMidStarts)));
  command.add_option("--io-task-us", sa.options.io_task_us,
                     "a second task: the terminals in a frame of their own at this cycle time, a "
                     "multiple of --cycle-us");
  command.add_option("--layout-config", sa.layout_config,
                     "also write the layout as a configuration file for validate --config");
  command.add_option(
      "--eni", sa.eni,
      "also write the set-up as an ENI file (EtherCATConfig.xml) for validate --eni");
  command.add_option("--incidents-truth", sa.incidents_truth,
                     "with --scenario incidents: also write the incidents `validate` must list, "
                     "as JSON (kind, axis, frame, cause)");
  command.add_flag("--list-faults", sa.list_faults, "list what --fault does for each rule");
  return [args] { return runSimulate(*args); };
}

// ninja's tool table: name, help, and the options' setup, which returns the handler.
struct Subcommand {
  const char* name;
  const char* help;
  Handler (*setup)(CLI::App& command);
};
const Subcommand kSubcommands[] = {
    {"decode", "print the decoded process data, one row per axis and cycle", decodeCommand},
    {"validate", "check captures against the rules (docs/rules.md)", validateCommand},
    {"diff",
     "compare two captures or JSON reports: findings, incidents, timing (docs/baselines.md)",
     diffCommand},
    {"rules", "list the rules: ID, slug, severity, party, summary", rulesCommand},
    {"fields", "list every decoded field (generated from the field table)", fieldsCommand},
    {"simulate", "write a capture of simulated NC and drives (scenarios, faults)", simulateCommand},
    {"annotate", "copy a capture with each finding as a packet comment on its frame",
     cli::annotateCommand},
    {"monitor", "capture live, report findings as they happen, keep a flight record",
     cli::monitorCommand},
};

}  // namespace

// A first word that names no subcommand, with the closest one; "" when it names one or is an
// option (--help, --version).
std::string unknownCommandMessage(int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return "";
  const std::string word = argv[1];
  const std::vector<std::string> names = namesOf(kSubcommands);
  if (std::find(names.begin(), names.end(), word) != names.end()) return "";
  return fmt::format("ncservo: unknown command '{}'{} (commands: {})", word,
                     didYouMean(word, names), choiceList(names));
}

// The first --option of the subcommand's words that it does not take, with the closest one; ""
// when it takes them all.
std::string unknownOptionMessage(const CLI::App& app, int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return "";
  const CLI::App* command = app.get_subcommand(argv[1]);
  std::vector<std::string> options;
  for (const CLI::Option* option : command->get_options()) {
    for (const std::string& name : option->get_lnames()) options.push_back("--" + name);
  }
  for (int i = 2; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "--") break;
    if (word.rfind("--", 0) != 0) continue;
    const std::string name = word.substr(0, word.find('='));
    if (std::find(options.begin(), options.end(), name) != options.end()) continue;
    return fmt::format("ncservo {}: unknown option '{}'{}", argv[1], name,
                       didYouMean(name, options));
  }
  return "";
}

int main(int argc, char** argv) {
  CLI::App app{"ncservo: decode and check NC <-> servo EtherCAT process data"};
  const std::string version = std::string("ncservo ") + NCSERVO_VERSION;
  app.set_version_flag("--version", version);
  app.require_subcommand(1);
  std::vector<std::pair<CLI::App*, Handler>> commands;
  for (const Subcommand& s : kSubcommands) {
    CLI::App* command = app.add_subcommand(s.name, s.help);
    command->set_version_flag("--version", version);
    commands.emplace_back(command, s.setup(*command));
  }
  if (const std::string unknown = unknownCommandMessage(argc, argv); !unknown.empty()) {
    fmt::print(stderr, "{}\n", unknown);
    return kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (app.exit(e) == 0) return kExitOk;
    if (const std::string unknown = unknownOptionMessage(app, argc, argv); !unknown.empty()) {
      fmt::print(stderr, "{}\n", unknown);
    }
    return kExitUsage;
  }
  for (const auto& [command, handler] : commands) {
    if (command->parsed()) return handler();
  }
  return kExitUsage;
}
