// ncservo: the command-line face of the library. It parses arguments and presents; the protocol
// knowledge lives in the library's tables.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/capture_reader.hpp"
#include "ncservo/capture_writer.hpp"
#include "ncservo/config.hpp"
#include "ncservo/eni.hpp"
#include "ncservo/ethercat.hpp"
#include "ncservo/fields.hpp"
#include "ncservo/frame_clock.hpp"
#include "ncservo/pdo.hpp"
#include "ncservo/session.hpp"
#include "ncservo/simulator.hpp"
#include "ncservo/validator.hpp"
#include "report.hpp"

namespace {

using namespace ncservo;

enum ExitCode {
  kExitOk = 0,
  kExitFindings = 1,
  kExitUsage = 2,
  kExitCapture = 3,
  kExitNoServo = 4
};

std::string shortName(const char* filter) {
  std::string name(filter);
  return name.substr(std::string("ncservo.").size());
}

// A PDO region the capture cut short or that straddles its datagram's end (the frame is still
// analysed; the region is not read).
void warnIfMalformed(const std::string& capture, std::uint64_t frame, const AxisPlacement& p) {
  if (!p.rx_malformed && !p.tx_malformed) return;
  fmt::print(stderr,
             "ncservo: {}: frame {}: axis {}: {} region cut short or outside its datagram\n",
             capture, frame, p.axis, p.rx_malformed ? "RxPDO" : "TxPDO");
}

class RowWriter {
 public:
  RowWriter(std::FILE* out, bool csv, const Decoder& decoder)
      : out_(out), csv_(csv), decoder_(decoder) {}

  void header() {
    if (!csv_) return;
    std::string line = "frame,time,axis,name";
    for (const FieldDef& f : kFields) line += "," + shortName(f.filter);
    line += ",state,message\n";
    std::fputs(line.c_str(), out_);
  }

  void write(const CycleRow& row, double time) {
    const std::string& name = decoder_.axes().at(row.axis).name;
    char message[128] = "";
    if (row.values.has_tx)
      formatMessage(message, sizeof message, row.values.msgCode(), row.values.msgData());
    const char* state = row.state ? driveStateName(*row.state) : "";
    if (csv_) {
      std::string line = fmt::format("{},{:.9f},{},{}", row.frame, time, row.axis, name);
      for (const FieldDef& f : kFields) line += "," + cell(f, row.values);
      line += fmt::format(",{},\"{}\"\n", state, message);
      std::fputs(line.c_str(), out_);
      return;
    }
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
    if (row.state) j["state"] = state;
    if (row.values.has_tx) j["message"] = message;
    std::fputs((j.dump() + "\n").c_str(), out_);
  }

 private:
  static std::string cell(const FieldDef& f, const PdoValues& values) {
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

  std::FILE* out_;
  bool csv_;
  const Decoder& decoder_;
};

// PROTOCOL.md §9: the configuration's axes, else the ENI's, else (in the decoder) the start-up's,
// else the default layout.
DecoderOptions decoderOptions(const std::optional<Config>& config,
                              const std::optional<EniResult>& eni, bool no_default_layout) {
  const bool default_layout = !no_default_layout && (!config || config->default_layout);
  return layoutOptions(config ? &config->axes : nullptr, eni ? &eni->axes : nullptr,
                       default_layout);
}

// `decode --layout`: the layout as a configuration file, then every slave the start-up showed.
void printLayout(const Decoder& decoder) {
  std::vector<AxisConfig> axes;
  for (const AxisInfo& info : decoder.axes()) axes.push_back(axisConfigOf(info));
  fmt::print("# layout source: {}, {} ax{}{}\n", layoutSourceName(decoder.source()), axes.size(),
             axes.size() == 1 ? "is" : "es",
             axes.empty() ? " (" + decoder.noServoReason() + ")" : std::string());
  for (const SlaveLayout& slave : decoder.learner().slaves()) {
    fmt::print("# slave {}\n", describeSlaveLayout(slave));
  }
  if (!axes.empty()) fmt::print("{}", writeConfig(axes, std::nullopt));
}

int runDecode(const std::string& path, const std::optional<Config>& config,
              const std::optional<EniResult>& eni, bool no_default_layout,
              const std::string& format, bool layout_only, TimestampMode timestamps) {
  auto opened = CaptureReader::open(path);
  if (!opened) {
    fmt::print(stderr, "ncservo: {}\n", opened.error().text());
    return kExitCapture;
  }
  const std::unique_ptr<CaptureReader> reader = std::move(*opened);
  Session session(decoderOptions(config, eni, no_default_layout));
  RowWriter writer(stdout, format == "csv", session.decoder());
  FrameClock clock(timestamps);
  if (!layout_only) writer.header();
  CycleRows cycles;
  std::vector<CycleRow> rows;
  EcatFrame frame;
  CaptureRecord record;
  std::optional<std::int64_t> first_time;
  auto write = [&] {
    for (const CycleRow& row : rows) {
      writer.write(row, static_cast<double>(row.time_ns - *first_time) / 1e9);
    }
    rows.clear();
  };
  Result<bool> status;
  while ((status = reader->next(record)) && *status) {
    if (!first_time) first_time = record.time_ns;
    const ByteReader bytes(record.data, record.captured);
    walkPacket(reader->link(), bytes, frame);
    if (frame.status == WalkStatus::NotEtherCat) continue;
    const std::int64_t time_ns = clock.time(record.frame, record.time_ns, frame.probe);
    if (frame.status == WalkStatus::NotDatagrams || frame.status == WalkStatus::BusFault) continue;
    const FrameView& view = session.onFrame(frame, bytes);
    if (layout_only) continue;
    for (std::size_t i = 0; i < view.axis_count; ++i) {
      warnIfMalformed(reader->path(), record.frame, view.axes[i].placement);
    }
    cycles.onFrame(record.frame, time_ns, view, rows);
    write();
  }
  cycles.finish(rows);
  write();
  std::fflush(stdout);
  if (!status) {
    fmt::print(stderr, "ncservo: {} (the frames before it were decoded)\n", status.error().text());
    return kExitCapture;
  }
  if (layout_only) printLayout(session.decoder());
  if (clock.source() == TimestampSource::Probe || !clock.note().empty()) {
    fmt::print(stderr, "ncservo: {}: timestamps: {}{}{}\n", reader->path(),
               timestampSourceName(clock.source()), clock.note().empty() ? "" : "; ", clock.note());
  }
  if (session.decoder().axes().empty()) {
    fmt::print(stderr, "ncservo: {}: {}\n", reader->path(), session.decoder().noServoReason());
  }
  return kExitOk;
}

void printFields(const std::string& format) {
  if (format == "markdown") {
    fmt::print("| filter name | label | word | bits | values | meaning | spec |\n");
    fmt::print("|---|---|---|---|---|---|---|\n");
  }
  for (const FieldDef& f : kFields) {
    std::string values;
    for (std::size_t i = 0; i < f.value_count; ++i) {
      values += fmt::format("{}{}={}{}", i ? "; " : "", f.values[i].value, f.values[i].name,
                            f.values[i].unit ? fmt::format(" [{}]", f.values[i].unit) : "");
    }
    const std::string mask = f.mask ? fmt::format("0x{:X}", f.mask) : "all";
    if (format == "markdown") {
      fmt::print("| `{}` | {} | {} | {} | {} | {} | {} |\n", f.filter, f.label,
                 wordDef(f.word).name, mask, values, f.blurb, f.clause);
    } else {
      fmt::print("{}\t{}\t{}\t{}\t{}\n", f.filter, f.label, wordDef(f.word).name, mask, f.blurb);
    }
  }
  for (const DerivedFieldDef& f : kDerivedFields) {
    if (format == "markdown") {
      fmt::print("| `{}` | {} | (derived) | | | {} | INTERFACES.md |\n", f.filter, f.label,
                 f.blurb);
    } else {
      fmt::print("{}\t{}\t(derived)\t\t{}\n", f.filter, f.label, f.blurb);
    }
  }
}

struct ValidateOptions {
  std::vector<std::string> captures;
  std::string format = "text";
  std::string output;
  std::string fail_on = "error";
  std::vector<std::string> disable;
  std::vector<std::string> severities;
  std::vector<std::string> timeouts;
  std::optional<int> servo_ready_mode;
  bool no_default_layout = false;
  std::string timestamps = "auto";
  bool allow_empty = false;
};

// The settings from RULES.md's defaults, the config file, then the command line.
std::optional<std::string> buildSettings(const ValidateOptions& o,
                                         const std::optional<Config>& config,
                                         RuleSettings& settings) {
  if (config) {
    if (auto error = settings.apply(*config)) return fmt::format("{}: {}", config->path, *error);
  }
  for (const std::string& id : o.disable) {
    if (auto error = settings.disable(id)) return "--disable: " + *error;
  }
  for (const std::string& pair : o.severities) {
    const auto eq = pair.find('=');
    if (eq == std::string::npos) return "--severity " + pair + ": expected ID=LEVEL";
    if (auto error = settings.setSeverity(pair.substr(0, eq), pair.substr(eq + 1)))
      return "--severity: " + *error;
  }
  for (const std::string& pair : o.timeouts) {
    const auto eq = pair.find('=');
    if (eq == std::string::npos) return "--timeout " + pair + ": expected NAME=MS";
    std::int64_t ms = -1;
    try {
      std::size_t used = 0;
      ms = std::stoll(pair.substr(eq + 1), &used);
      if (used != pair.size() - eq - 1) ms = -1;
    } catch (const std::exception&) {
      ms = -1;
    }
    if (ms < 0) return "--timeout " + pair + ": expected a number of milliseconds";
    if (auto error = settings.setTimeout(pair.substr(0, eq), ms)) return "--timeout: " + *error;
  }
  if (o.servo_ready_mode) settings.servo_ready_mode = o.servo_ready_mode;
  return std::nullopt;
}

// Runs one capture through the validator. Returns the capture's exit status (0, 1, 3 or 4).
int validateCapture(const std::string& path, const DecoderOptions& decoder_options,
                    const RuleSettings& settings, TimestampMode timestamps,
                    cli::ReportWriter& writer, cli::CaptureReport& report) {
  report.path = path;
  writer.beginCapture(report);
  auto opened = CaptureReader::open(path);
  if (!opened) {
    report.error = opened.error().text();
    fmt::print(stderr, "ncservo: {}\n", *report.error);
    writer.endCapture(report);
    return kExitCapture;
  }
  const std::unique_ptr<CaptureReader> reader = std::move(*opened);
  Validator validator(decoder_options, settings);
  FrameClock clock(timestamps);
  EcatFrame frame;
  CaptureRecord record;
  bool first = true;
  Result<bool> status;
  while ((status = reader->next(record)) && *status) {
    if (first) report.first_time_ns = record.time_ns;
    first = false;
    report.frames = record.frame;
    const ByteReader bytes(record.data, record.captured);
    walkPacket(reader->link(), bytes, frame);
    if (frame.status == WalkStatus::NotEtherCat) continue;
    const std::int64_t time_ns = clock.time(record.frame, record.time_ns, frame.probe);
    if (frame.status == WalkStatus::NotDatagrams || frame.status == WalkStatus::BusFault) continue;
    const FrameDecode& decode = validator.onFrame(record.frame, time_ns, frame, bytes).decode;
    for (std::size_t i = 0; decode.any_malformed && i < decode.axis_count; ++i) {
      warnIfMalformed(reader->path(), record.frame, decode.axes[i]);
    }
    for (const Finding& f : validator.findings()) {
      ++report.counts[static_cast<std::size_t>(f.severity)];
      if (writer.keepsFindings()) report.findings.push_back(f);
      writer.finding(report, f);
    }
  }
  cli::summarise(validator, report);
  report.coverage = coverageOf(validator);
  report.timestamps = clock.source();
  report.probe = clock.counts();
  report.probe_note = clock.note();
  if (!status) {
    report.error = status.error().text() + " (the frames before it were analysed)";
    fmt::print(stderr, "ncservo: {}\n", *report.error);
  }
  writer.endCapture(report);
  switch (writer.verdict(report)) {
    case cli::Verdict::Unreadable:
      return kExitCapture;
    case cli::Verdict::Fail:
      return kExitFindings;
    case cli::Verdict::NoServo:
      return kExitNoServo;
    case cli::Verdict::Pass:
      break;
  }
  return kExitOk;
}

// INTERFACES.md: with several captures the status is the most serious, in the order 2, 3, 1, 4, 0.
int combine(int a, int b) {
  constexpr int kOrder[] = {kExitUsage, kExitCapture, kExitFindings, kExitNoServo, kExitOk};
  auto rank = [&](int rc) { return std::find(std::begin(kOrder), std::end(kOrder), rc) - kOrder; };
  return rank(a) <= rank(b) ? a : b;
}

int runValidate(const ValidateOptions& o, const std::optional<Config>& config,
                const std::optional<EniResult>& eni) {
  RuleSettings settings;
  if (auto error = buildSettings(o, config, settings)) {
    fmt::print(stderr, "ncservo: {}\n", *error);
    return kExitUsage;
  }
  const bool never = o.fail_on == "never";
  const Severity fail_on = never ? Severity::Error : *severityFromName(o.fail_on);
  cli::Format format = cli::Format::Text;
  if (o.format == "json") format = cli::Format::Json;
  if (o.format == "jsonl") format = cli::Format::Jsonl;
  if (o.format == "junit") format = cli::Format::Junit;
  if (o.format == "sarif") format = cli::Format::Sarif;
  std::FILE* out = stdout;
  if (!o.output.empty() && o.output != "-") {
    out = std::fopen(o.output.c_str(), "w");
    if (out == nullptr) {
      fmt::print(stderr, "ncservo: {}: cannot write: {}\n", o.output, std::strerror(errno));
      return kExitUsage;
    }
  }
  cli::ReportWriter writer(out, format, fail_on, never, o.allow_empty);
  const TimestampMode timestamps = *timestampModeFromName(o.timestamps);
  std::vector<cli::CaptureReport> reports;
  int rc = kExitOk;
  for (const std::string& path : o.captures) {
    reports.emplace_back();
    rc = combine(rc, validateCapture(path, decoderOptions(config, eni, o.no_default_layout),
                                     settings, timestamps, writer, reports.back()));
  }
  writer.finish(reports);
  if (out != stdout) std::fclose(out);
  return rc;
}

void printRules(const std::string& format) {
  if (format == "markdown") {
    fmt::print("| ID | slug | severity | party | timeout | clause | summary |\n");
    fmt::print("|---|---|---|---|---|---|---|\n");
  }
  for (const RuleDef& rule : kRules) {
    const char* timeout =
        rule.timeout ? kTimeouts[static_cast<std::size_t>(*rule.timeout)].name : "";
    if (format == "markdown") {
      fmt::print("| {} | `{}` | {} | {} | {} | {} | {} |\n", rule.code, rule.slug,
                 severityName(rule.severity), partyName(rule.party), timeout, rule.clause,
                 rule.summary);
    } else {
      fmt::print("{:<8} {:<27} {:<8} {:<6} {}\n", rule.code, rule.slug, severityName(rule.severity),
                 partyName(rule.party), rule.summary);
    }
  }
}

struct SimulateArgs {
  sim::SimOptions options;
  std::string scenario = "commissioning";
  std::string layout = "default";
  std::string output;
  std::string format;  // pcap, pcapng; default from the file name
  std::vector<std::string> faults;
  std::string layout_config;
  std::string eni;
  bool no_startup = false;
  bool list_faults = false;
};

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
  o.layout = args.layout == "interleaved" ? sim::LayoutKind::Interleaved : sim::LayoutKind::Default;
  o.startup = !args.no_startup;
  for (const std::string& text : args.faults) {
    std::string error;
    auto fault = sim::parseFault(text, error);
    if (!fault) {
      fmt::print(stderr, "ncservo simulate: {}\n", error);
      return kExitUsage;
    }
    o.faults.push_back(std::move(*fault));
  }
  if (std::string error = sim::resolveOptions(o); !error.empty()) {
    fmt::print(stderr, "ncservo simulate: {}\n", error);
    return kExitUsage;
  }
  const bool pcapng = args.format.empty()
                          ? args.output.size() >= 7 &&
                                args.output.compare(args.output.size() - 7, 7, ".pcapng") == 0
                          : args.format == "pcapng";
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
  std::string error;
  auto writer =
      CaptureWriter::open(args.output, pcapng ? CaptureFormat::Pcapng : CaptureFormat::Pcap, error);
  if (!writer) {
    fmt::print(stderr, "ncservo simulate: {}\n", error);
    return kExitCapture;
  }
  const auto frames = simulator.run([&](const sim::SimFrame& frame) {
    return writer->write(frame.time_ns, frame.data, frame.size);
  });
  if (!writer->close(error) || !frames) {
    fmt::print(stderr, "ncservo simulate: {}\n",
               error.empty() ? args.output + ": write failed" : error);
    return kExitCapture;
  }
  if (args.output != "-") {
    fmt::print(stderr, "ncservo simulate: wrote {} frames to {}\n", *frames, args.output);
  }
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"ncservo: decode and check NC <-> servo EtherCAT process data"};
  app.set_version_flag("--version", std::string("ncservo ") + NCSERVO_VERSION);
  app.require_subcommand(1);

  std::string capture;
  std::string config_path;
  std::string format = "csv";
  bool no_default_layout = false;
  auto* decode =
      app.add_subcommand("decode", "print the decoded process data, one row per axis and cycle");
  decode->add_option("CAPTURE", capture, "pcap or pcapng capture, - for standard input")
      ->required();
  decode->add_option("--config", config_path, "TOML configuration file (layout)");
  decode->add_option("--format", format, "csv or jsonl")->check(CLI::IsMember({"csv", "jsonl"}));
  decode->add_flag("--no-default-layout", no_default_layout,
                   "never assume the default layout (PROTOCOL.md §9.4)");
  std::string decode_timestamps = "auto";
  decode
      ->add_option("--timestamps", decode_timestamps,
                   "capture, probe or auto (auto: an ESL probe's when the first EtherCAT frame "
                   "has one)")
      ->check(CLI::IsMember({"capture", "probe", "auto"}));
  std::string eni_path;
  bool layout_only = false;
  decode->add_option("--eni", eni_path, "ENI file (EtherCATConfig.xml) giving the layout");
  decode->add_flag("--layout", layout_only,
                   "print the layout found (as a configuration file) and the slaves the start-up "
                   "configured, instead of the process data");

  ValidateOptions vo;
  std::string validate_config;
  auto* validate = app.add_subcommand("validate", "check captures against the rules (RULES.md)");
  validate->add_option("CAPTURE", vo.captures, "pcap or pcapng captures, - for standard input")
      ->required();
  validate->add_option("--config", validate_config, "TOML configuration file");
  validate->add_option("--format", vo.format, "text, json, jsonl, junit or sarif")
      ->check(CLI::IsMember({"text", "json", "jsonl", "junit", "sarif"}));
  validate->add_option("-o,--output", vo.output,
                       "write the report here (default: standard output)");
  validate
      ->add_option("--fail-on", vo.fail_on,
                   "exit 1 on findings at or above: error, warning, info, never")
      ->check(CLI::IsMember({"error", "warning", "info", "never"}));
  validate->add_option("--disable", vo.disable, "rule IDs to skip, comma-separated")
      ->delimiter(',');
  validate->add_option("--severity", vo.severities, "ID=LEVEL: change a rule's severity")
      ->delimiter(',');
  validate->add_option("--timeout", vo.timeouts, "NAME=MS: change a timeout of RULES.md")
      ->delimiter(',');
  validate
      ->add_option("--servo-ready-mode", vo.servo_ready_mode,
                   "Servo_Ready_Mode of the drives (0 or 1)")
      ->check(CLI::Range(0, 1));
  validate->add_flag("--no-default-layout", vo.no_default_layout,
                     "never assume the default layout (PROTOCOL.md §9.4)");
  validate
      ->add_option("--timestamps", vo.timestamps,
                   "capture, probe or auto (auto: an ESL probe's when the first EtherCAT frame "
                   "has one)")
      ->check(CLI::IsMember({"capture", "probe", "auto"}));
  validate->add_flag("--allow-empty", vo.allow_empty,
                     "exit 0, not 4, where no servo (or not every configured axis) was decoded");
  std::string validate_eni;
  validate->add_option("--eni", validate_eni,
                       "ENI file (EtherCATConfig.xml) giving the layout when no --config does");

  std::string rules_format = "text";
  auto* rules = app.add_subcommand("rules", "list the rules: ID, slug, severity, party, summary");
  rules->add_option("--format", rules_format, "text or markdown")
      ->check(CLI::IsMember({"text", "markdown"}));

  std::string fields_format = "tsv";
  auto* fields =
      app.add_subcommand("fields", "list every decoded field (generated from the field table)");
  fields->add_option("--format", fields_format, "tsv or markdown")
      ->check(CLI::IsMember({"tsv", "markdown"}));

  SimulateArgs sa;
  auto* simulate = app.add_subcommand(
      "simulate", "write a capture of simulated NC and drives (scenarios, faults)");
  simulate->add_option("-o,--output", sa.output, "capture to write, - for standard output");
  simulate->add_option("--scenario", sa.scenario, "commissioning, faults or soak")
      ->check(CLI::IsMember({"commissioning", "faults", "soak"}));
  simulate->add_option("--axes", sa.options.axes, "servo axes, 1 to 32 (default 4)");
  simulate->add_option("--io-slaves", sa.options.io_slaves,
                       "8-bit digital output/input terminals sharing the LRW (default 0)");
  simulate->add_option("--cycle-us", sa.options.cycle_us,
                       "cycle time, 125 to 10000 (default 1000)");
  simulate->add_option("--duration", sa.options.duration_s,
                       "seconds (default: commissioning 3, faults 4.3, soak 60)");
  simulate->add_option("--seed", sa.options.seed, "the same seed and options give the same bytes");
  simulate->add_option("--layout", sa.layout, "default (PROTOCOL.md §9.4) or interleaved")
      ->check(CLI::IsMember({"default", "interleaved"}));
  simulate->add_flag("--no-startup", sa.no_startup,
                     "begin with the slaves already in OP (no start-up traffic)");
  simulate->add_option("--format", sa.format, "pcap or pcapng (default: from the file name)")
      ->check(CLI::IsMember({"pcap", "pcapng"}));
  simulate->add_option(
      "--fault", sa.faults,
      "RULE[@SECONDS][:AXIS]: make that rule fire (repeatable; see --list-faults)");
  simulate->add_option("--ready-mode", sa.options.ready_mode,
                       "the drives' Servo_Ready_Mode, 0 or 1");
  simulate->add_option("--jitter-us", sa.options.jitter_us, "master send jitter, microseconds");
  simulate->add_option("--loss", sa.options.loss,
                       "probability that a returned frame is lost (COM-004 findings)");
  simulate->add_option("--layout-config", sa.layout_config,
                       "also write the layout as a configuration file for validate --config");
  simulate->add_option(
      "--eni", sa.eni,
      "also write the set-up as an ENI file (EtherCATConfig.xml) for validate --eni");
  simulate->add_flag("--list-faults", sa.list_faults, "list what --fault does for each rule");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? kExitOk : kExitUsage;
  }

  if (simulate->parsed()) return runSimulate(sa);
  if (fields->parsed()) {
    printFields(fields_format);
    return kExitOk;
  }
  if (rules->parsed()) {
    printRules(rules_format);
    return kExitOk;
  }
  if (validate->parsed()) config_path = validate_config;
  std::optional<Config> config;
  if (!config_path.empty()) {
    ConfigResult loaded = loadConfig(config_path);
    if (!loaded.ok()) {
      fmt::print(stderr, "ncservo: {}\n", loaded.error->text());
      return kExitUsage;
    }
    config = std::move(loaded.config);
  }
  if (validate->parsed()) eni_path = validate_eni;
  std::optional<EniResult> eni;
  if (!eni_path.empty()) {
    eni = loadEni(eni_path);
    if (!eni->ok()) {
      fmt::print(stderr, "ncservo: {}\n", eni->error->text());
      return kExitUsage;
    }
    if (eni->axes.empty()) {
      fmt::print(stderr,
                 "ncservo: {}: no servo of this protocol (10-byte outputs, 40-byte inputs) among "
                 "its {} slaves\n",
                 eni_path, eni->slaves);
      return kExitUsage;
    }
  }
  if (validate->parsed()) return runValidate(vo, config, eni);
  return runDecode(capture, config, eni, no_default_layout, format, layout_only,
                   *timestampModeFromName(decode_timestamps));
}
