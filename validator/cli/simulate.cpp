// `ncservo simulate` (docs/simulate.md): a capture of simulated NC and drives, and beside it on
// request the layout, the ENI file and the incidents' truth.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "commands.hpp"
#include "ncservo/base/number.hpp"
#include "ncservo/capture/capture_writer.hpp"
#include "ncservo/capture/compressed_output.hpp"
#include "ncservo/rules/rules.hpp"
#include "ncservo/sim/simulator.hpp"
#include "ncservo/wire/ecat_wire.hpp"

namespace ncservo::cli {

using namespace report;  // the report layer's names
namespace {

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
  std::string faults_truth;
  std::string diagnosis_truth;
  std::vector<std::string> bad_links;
  std::vector<std::string> sync_errors;
  std::string io_inputs = "slow";
  std::string idle;            // SECONDS or all; empty: none
  std::string start_in;        // empty: the capture starts with the session
  std::string capture_stamps;  // empty: the bus's own times
  bool no_startup = false;
  bool list_faults = false;
};

// An option's help: `intro`, then each row's name and summary ("intro: a (x), b (y).").
template <typename Row, std::size_t N>
std::string rowsHelp(std::string intro, const Row (&rows)[N]) {
  for (const Row& row : rows) intro += fmt::format(" {} ({}),", row.name, row.summary);
  intro.back() = '.';
  return intro;
}

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

// Each text of a repeatable option parsed into `into`; false (with the message printed) at the
// first malformed one.
template <typename T, typename Parse>
bool parseEach(const std::vector<std::string>& texts, Parse parse, std::vector<T>& into) {
  for (const std::string& text : texts) {
    Result<T> item = parse(text);
    if (!item) {
      fmt::print(stderr, "ncservo simulate: {}\n", item.error().text());
      return false;
    }
    into.push_back(std::move(*item));
  }
  return true;
}

// The options of the command line into the simulator's; false (with the message printed) when
// one is malformed or they do not go together.
bool simulationOptions(SimulateArgs& args) {
  sim::SimOptions& o = args.options;
  o.scenario = *sim::scenarioFromName(args.scenario);
  const std::string& style = !args.image.empty() ? args.image : args.layout;
  o.image = style.empty() ? sim::ImageStyle::Soem : *sim::imageStyleFromName(style);
  o.probe = rowNamed(kProbes, args.probe).probe;
  o.startup = !args.no_startup;
  o.terminal_inputs = rowNamed(sim::kTerminalInputs, args.io_inputs).inputs;
  if (!args.start_in.empty()) {
    const Result<sim::MidStartRequest> start = sim::parseMidStart(args.start_in);
    if (!start) {
      fmt::print(stderr, "ncservo simulate: {}\n", start.error().text());
      return false;
    }
    o.mid_start = start->start;
    o.mid_start_fault = start->fault;
  }
  if (!args.capture_stamps.empty()) {
    Result<sim::StampShaping> stamps = sim::parseCaptureStamps(args.capture_stamps);
    if (!stamps) {
      fmt::print(stderr, "ncservo simulate: {}\n", stamps.error().text());
      return false;
    }
    o.capture_stamps = std::move(*stamps);
  }
  o.writes_pcapng = captureFormatFor(args.format, args.output) == CaptureFormat::Pcapng;
  if (!parseIdle(args.idle, o)) return false;
  const bool parsed =
      parseEach(args.faults, sim::parseFault, o.faults) &&
      parseEach(
          args.late_cycles,
          [](std::string_view text) { return sim::parseCycleDisturbance("--late-cycle", text); },
          o.late_cycles) &&
      parseEach(
          args.lost_cycles,
          [](std::string_view text) { return sim::parseCycleDisturbance("--lost-cycles", text); },
          o.lost_cycles) &&
      parseEach(args.bad_links, sim::parseBadLink, o.bad_links) &&
      parseEach(args.sync_errors, sim::parseSyncError, o.sync_errors);
  if (!parsed) return false;
  if (!args.incidents_truth.empty() && o.scenario != sim::Scenario::Incidents) {
    fmt::print(stderr, "ncservo simulate: --incidents-truth needs --scenario incidents\n");
    return false;
  }
  if (Status resolved = sim::resolveOptions(o); !resolved) {
    fmt::print(stderr, "ncservo simulate: {}\n", resolved.error().text());
    return false;
  }
  if (!args.diagnosis_truth.empty() && !o.diagnosis) {
    fmt::print(stderr,
               "ncservo simulate: --diagnosis-truth needs --diagnosis (or --bad-link, "
               "--sync-error or a --fault of what the drives and ESCs say)\n");
    return false;
  }
  return true;
}

// A file written beside the capture (--layout-config, --eni, --incidents-truth); false (with the
// message printed) when it cannot be written.
bool writeBesideCapture(const std::string& path, const std::string& text, const char* what) {
  std::ofstream out(path);
  out << text;
  if (!out.flush()) {
    fmt::print(stderr, "ncservo simulate: {}: cannot write the {}\n", path, what);
    return false;
  }
  return true;
}

// The simulation run into the capture file; false (with the message printed) when it cannot be
// written.
bool writeCapture(const SimulateArgs& args, sim::Simulator& simulator) {
  const Compression compression = args.compress.empty()
                                      ? compressionForName(args.output)
                                      : rowNamed(kCompressions, args.compress).compression;
  // --second-interface: the office port beside the bus (docs/simulate.md#the-capturing-pc).
  std::vector<PcapngInterface> interfaces;
  if (args.options.second_interface) {
    interfaces = {{.dlt = ecat::kDltEthernet}, {.dlt = ecat::kDltLinuxSll}};
  }
  Result<std::unique_ptr<CaptureWriter>> writer = CaptureWriter::open(
      args.output, captureFormatFor(args.format, args.output), compression, interfaces);
  // An output that cannot be written is a usage error, as for every command (docs/cli.md).
  if (!writer) {
    fmt::print(stderr, "ncservo simulate: {}\n", writer.error().text());
    return false;
  }
  const auto frames = simulator.run([&](const sim::SimFrame& frame) {
    return (*writer)->write(PacketRecord{.time_ns = frame.time_ns,
                                         .data = frame.data,
                                         .captured = frame.size,
                                         .original = frame.size,
                                         .interface_id = frame.interface_id});
  });
  const Status closed = (*writer)->close();
  if (!closed || !frames) {
    fmt::print(stderr, "ncservo simulate: {}\n",
               closed ? args.output + ": write failed" : closed.error().text());
    return false;
  }
  if (args.output != "-") {
    fmt::print(stderr, "ncservo simulate: wrote {} frames to {}\n", *frames, args.output);
  }
  return true;
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
  if (!simulationOptions(args)) return kExitUsage;
  sim::Simulator simulator(args.options);
  if (!args.layout_config.empty() &&
      !writeBesideCapture(args.layout_config, simulator.layoutConfig(), "layout")) {
    return kExitUsage;
  }
  if (!args.eni.empty() && !writeBesideCapture(args.eni, simulator.eni(), "ENI file")) {
    return kExitUsage;
  }
  if (!writeCapture(args, simulator)) return kExitUsage;
  if (args.options.capture_loss > 0) {
    fmt::print(stderr, "ncservo simulate: {} master copies left out of the capture\n",
               simulator.masterCopiesDropped());
  }
  if (!args.faults_truth.empty()) {
    const Result<std::vector<sim::FaultTruth>> faults = simulator.faults();
    if (!faults) {
      fmt::print(stderr, "ncservo simulate: --faults-truth: {}\n", faults.error().text());
      return kExitUsage;
    }
    if (!writeBesideCapture(args.faults_truth, sim::faultsJson(*faults), "fault truth")) {
      return kExitUsage;
    }
  }
  if (!args.diagnosis_truth.empty()) {
    const Result<sim::DiagnosisTruth> said = simulator.diagnosis();
    if (!said) {
      fmt::print(stderr, "ncservo simulate: --diagnosis-truth: {}\n", said.error().text());
      return kExitUsage;
    }
    if (!writeBesideCapture(args.diagnosis_truth, sim::diagnosisJson(*said), "diagnosis truth")) {
      return kExitUsage;
    }
  }
  if (!args.incidents_truth.empty()) {
    const Result<std::vector<sim::IncidentTruth>> incidents = simulator.incidents();
    if (!incidents) {
      fmt::print(stderr, "ncservo simulate: {}\n", incidents.error().text());
      return kExitCapture;
    }
    if (!writeBesideCapture(args.incidents_truth, sim::incidentsJson(*incidents), "incidents")) {
      return kExitUsage;
    }
  }
  return kExitOk;
}

// What the bus's timing does (jitter, drift, latency, lost and late cycles, loss): the options.
void addBusTimingOptions(CLI::App& command, SimulateArgs& sa) {
  command.add_option("--jitter-us", sa.options.jitter_us, "master send jitter, microseconds");
  command.add_option("--dc-drift", sa.options.dc_drift_ppm,
                     "PPM: the reference clock runs this fast against the master's (and the "
                     "capture's) clock, -1000 to 1000 (docs/simulate.md)");
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
}

}  // namespace

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
  std::vector<std::string> aliases;
  for (const sim::ImageStyleName& row : sim::kImageStyles) {
    if (row.layout_alias != nullptr) aliases.emplace_back(row.layout_alias);
  }
  CLI::Option* image =
      command
          .add_option("--image", sa.image,
                      rowsHelp("the master's process image (docs/simulate.md; default soem):",
                               sim::kImageStyles))
          ->check(cli::oneOf(namesOf(sim::kImageStyles)));
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
  command.add_flag("--diagnosis", sa.options.diagnosis,
                   "the drives' mailboxes: emergencies and error history, the NC's reads of "
                   "1001h and 1003h after a fault, the master's polls of the ESC error counters, "
                   "AL status and DC time differences (docs/simulate.md#diagnosis)");
  command.add_option("--bad-link", sa.bad_links,
                     "STATION:PORT@SECONDS[xFRAMES]: FRAMES frames (default 2) cross the cable "
                     "at that port corrupted from SECONDS on (repeatable; implies --diagnosis)");
  command.add_option("--sync-error", sa.sync_errors,
                     "STATION@SECONDS: the slave falls from OP to SAFE-OP with AL status code "
                     "0x001A (synchronization error) (repeatable; implies --diagnosis)");
  addBusTimingOptions(command, sa);
  command
      .add_option(
          "--io-inputs", sa.io_inputs,
          rowsHelp("how often the terminals' inputs change (default slow):", sim::kTerminalInputs))
      ->check(cli::oneOf(namesOf(sim::kTerminalInputs)));
  command.add_option("--cia402", sa.options.cia402_drives,
                     "CiA 402 drives with a servo's 10/40-byte PDOs beside the servos, 0 to 32");
  command.add_option("--idle", sa.idle,
                     "SECONDS or all: the drives ready and nothing enabled for that long after "
                     "the start-up, or for the whole capture");
  command.add_option(
      "--start-in", sa.start_in,
      rowsHelp("the capture begins in the middle of the commissioning session:", sim::kMidStarts) +
          " Or fault:RULE: inside the standing condition of that rule's --fault, RULE one of " +
          sim::standingFaultRules() + " (docs/simulate.md#shapes).");
  command.add_option("--io-task-us", sa.options.io_task_us,
                     "a second task: the terminals in a frame of their own at this cycle time, a "
                     "multiple of --cycle-us");
  command.add_option("--capture-stamps", sa.capture_stamps,
                     rowsHelp("SHAPE:LENGTH (us or ms): how the capturing PC stamps the records; "
                              "the bus's own times stay in its frames:",
                              sim::kStampShapes));
  command.add_flag("--duplicate-records", sa.options.duplicate_records,
                   "every record twice, the copy right after it, as a switch port mirroring both "
                   "directions gives it");
  command.add_flag("--second-interface", sa.options.second_interface,
                   "pcapng only: the capturing PC's office port (ARP and UDP, Linux cooked) as a "
                   "second interface beside the bus's");
  command.add_option("--layout-config", sa.layout_config,
                     "also write the layout as a configuration file for validate --config");
  command.add_option(
      "--eni", sa.eni,
      "also write the set-up as an ENI file (EtherCATConfig.xml) for validate --eni");
  command.add_option("--incidents-truth", sa.incidents_truth,
                     "with --scenario incidents: also write the incidents `validate` must list, "
                     "as JSON (kind, axis, frame, cause)");
  command.add_option("--faults-truth", sa.faults_truth,
                     "also write the findings the faults must give (rule, axis, frames), as JSON");
  command.add_option("--diagnosis-truth", sa.diagnosis_truth,
                     "with --diagnosis: also write what the drives and ESCs said, by frame, as "
                     "JSON (drive_messages, esc_errors, link_faults)");
  command.add_flag("--list-faults", sa.list_faults, "list what --fault does for each rule");
  return [args] { return runSimulate(*args); };
}

}  // namespace ncservo::cli
