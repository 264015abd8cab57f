// `ncservo decode` (docs/cli.md): the process data, one row per axis and cycle (csv, jsonl), the
// waveforms with the findings (vcd), or the layout found (--layout).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "ncservo/base/text.hpp"
#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/capture/capture_stream.hpp"
#include "ncservo/config/config.hpp"
#include "ncservo/layout/session.hpp"
#include "ncservo/model/timing_text.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"
#include "ncservo/protocol/fields.hpp"
#include "ncservo/protocol/pdo.hpp"
#include "ncservo/report/axis_selection.hpp"
#include "ncservo/report/report.hpp"
#include "ncservo/report/waveform.hpp"
#include "ncservo/rules/validator.hpp"
#include "ncservo/wire/frame_clock.hpp"

namespace ncservo::cli {

using namespace report;  // the report layer's names
namespace {

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

// Whether the frames' own timestamps (the capture's or the probe's) timed them.
bool ownStamps(const CapturePipeline& pipeline) {
  const ClockSource source = pipeline.clockStage().choice().source;
  return source == ClockSource::Capture || source == ClockSource::Probe;
}

// decode --timing's block on standard error, on the clock that timed the frames.
void printTiming(const CaptureReader& reader, const CapturePipeline& pipeline) {
  const Validator& timing = *pipeline.validator();
  const TimestampSource stamps = pipeline.clock().source();
  const bool own = ownStamps(pipeline);
  fmt::print(stderr, "ncservo: {}: {}", reader.path(),
             timingText(timing.bus().timing().summary(),
                        own ? timestampSourceName(stamps)
                            : clockSourceName(pipeline.clockStage().choice().source),
                        own ? timestampResolutionNs(stamps, reader.timestampDigits()) : 1));
  std::fputs(dcText(timing.dc().stations(), timing.dc().settledNs(),
                    clockSourceMeaning(pipeline.clockStage().choice().source))
                 .c_str(),
             stderr);
}

// The notes after a decode: which clock timed the frames (the `time` column, the VCD's times),
// and why no axis was found.
void noteDecoded(const CaptureReader& reader, const CapturePipeline& pipeline,
                 const Decoder& decoder) {
  const FrameClock& clock = pipeline.clock();
  if (clock.source() == TimestampSource::Probe || !clock.note().empty()) {
    fmt::print(stderr, "ncservo: {}: timestamps: {}{}{}\n", reader.path(),
               timestampSourceName(clock.source()), clock.note().empty() ? "" : "; ", clock.note());
  }
  const ClockChoice& choice = pipeline.clockStage().choice();
  if (choice.source == ClockSource::Bus || choice.source == ClockSource::Cycles) {
    fmt::print(stderr, "ncservo: {}: times on the clock {}\n", reader.path(),
               describeClock(choice));
  }
  if (pipeline.clockStage().duplicates().count > 0) {
    fmt::print(stderr, "ncservo: {}: duplicates: {} records ignored (the first: frame {})\n",
               reader.path(), pipeline.clockStage().duplicates().count,
               pipeline.clockStage().duplicates().first_frame);
  }
  if (const std::string none = noEtherCatReason(pipeline.run()); !none.empty()) {
    fmt::print(stderr, "ncservo: {}: {}\n", reader.path(), none);
  } else if (decoder.axes().empty()) {
    fmt::print(stderr, "ncservo: {}: {}\n", reader.path(), decoder.noServoReason());
    if (decoder.noServoWantsLayout()) {
      fmt::print(stderr, "a --config file gives each axis (docs/configuration.md#axis), e.g.:\n{}",
                 kLayoutConfigExample);
    }
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
  // With --timing the validator's decoder places the frames, else the session's.
  const auto decoderInUse = [&]() -> const Decoder& {
    const Validator* validator = pipeline.validator();
    return validator != nullptr ? validator->decoder() : session->decoder();
  };
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
      selected = report::checkAxisSelection(args.axes, decoderInUse().axes());
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
      const AxisInfo& axis = decoderInUse().axes().at(row.axis);
      if (!report::axisSelected(args.axes, axis)) continue;
      const std::int64_t since_first_ns = row.time_ns - *pipeline.run().first_time_ns;
      format.row(out, row, axis.name, static_cast<double>(since_first_ns) / 1e9);
    }
    rows.clear();
  };
  const auto decode = [&](const PipelineFrame& f) {
    // --timing: the validator placed and read the frame already.
    const FrameView& view = f.judged != nullptr
                                ? session->onDecoded(f.judged->decode, f.judged->values)
                                : session->onFrame(f.frame, f.bytes);
    if (args.layout_only) return;
    for (std::size_t i = 0; i < view.axis_count; ++i) cut.add(f.number, view.axes[i].placement);
    cycles.onFrame(f.number, f.time_ns, view, rows);
    write();
  };
  const auto start = [&](const DecoderOptions& layout) { session.emplace(layout); };
  const auto layout_only = [&](const PipelineFrame& f) {
    if (pipeline.validator() == nullptr) session->onLayoutOnlyFrame(f.frame, f.bytes);
  };
  pipeline.setSinks({start, decode, layout_only, nullptr, nullptr});
  const Status status =
      streamCapture(*reader, pipeline, nullptr, cli::captureThreads(args.read_thread, 1));
  const CaptureRun& run = pipeline.run();
  cycles.finish(rows);
  write();
  if (selected) selected = report::checkAxisSelection(args.axes, decoderInUse().axes());
  if (header_due && selected) format.header(out);  // no rows: the header alone
  std::fflush(out);
  warnIfTruncated(reader->path(),
                  truncationOf(run.snapped, run.first_snapped, cut, decoderInUse().axes()));
  if (const std::string empty = emptyWindowReason(input.window, run); !empty.empty()) {
    fmt::print(stderr, "ncservo: {}: {}\n", reader->path(), empty);
    return kExitNoServo;
  }
  if (!status) {
    fmt::print(stderr, "ncservo: {} (the frames before it were decoded)\n", status.error().text());
    return kExitCapture;
  }
  if (args.layout_only) printLayout(decoderInUse(), pipeline.inference());
  noteDecoded(*reader, pipeline, decoderInUse());
  if (pipeline.lateLayout().certain_at > 0) {
    fmt::print(stderr, "ncservo: {}: {}\n", reader->path(),
               report::describeLateLayout(pipeline.lateLayout()));
  }
  if (pipeline.validator() != nullptr) printTiming(*reader, pipeline);
  if (!selected) {
    fmt::print(stderr, "ncservo: {}\n", selected.error().text());
    return kExitUsage;
  }
  // No servo decoded (noteDecoded said why), as validate has it (docs/cli.md#exit-status).
  if (decoderInUse().axes().empty()) return kExitNoServo;
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
  report::WaveformWriter waveforms(input.out, to_stdout ? "standard output" : args.output,
                                   args.axes);
  Status written;
  std::int64_t end_ns = 0;
  std::int64_t frame_ns = 0;  // the last frame's, where its findings and the capture's last show
  bool clock_said = false;
  const auto decode = [&](const PipelineFrame& f) {
    if (!written) return;  // a failed write ends the work: the rest is read, not written
    if (!clock_said) waveforms.timedBy(describeClock(pipeline.clockStage().choice()));
    clock_said = true;
    frame_ns = f.time_ns - *pipeline.run().first_time_ns;
    end_ns = std::max(end_ns, frame_ns);
    written = waveforms.frame(frame_ns, *f.judged, pipeline.validator()->decoder());
  };
  const auto findings = [&](const std::vector<Finding>& found) {
    if (written) written = waveforms.findings(frame_ns, found);
  };
  pipeline.setSinks({nullptr, decode, nullptr, findings, nullptr});
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
  noteDecoded(reader, pipeline, validator.decoder());
  if (!to_stdout) {
    const std::string save = report::gtkwPathFor(args.output);
    std::FILE* file = std::fopen(save.c_str(), "w");
    if (file == nullptr) {
      fmt::print(stderr, "ncservo: {}: cannot write: {}\n", save, std::strerror(errno));
      return kExitUsage;
    }
    report::writeGtkwSave(file, std::filesystem::absolute(args.output).string(),
                          std::filesystem::absolute(save).string(), waveforms.scopes());
    std::fclose(file);
  }
  // No servo decoded (noteDecoded said why), as validate has it (docs/cli.md#exit-status).
  if (validator.decoder().axes().empty()) return kExitNoServo;
  return kExitOk;
}

int runDecode(const DecodeArgs& args) {
  DecodeInput input;
  const Result<TimeWindow> window =
      timeWindowOf(args.window.from, args.window.to, args.window.zone());
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

}  // namespace

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

}  // namespace ncservo::cli
