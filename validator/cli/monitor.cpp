// `ncservo monitor -i IFACE` (docs/field.md): a live capture through libpcap, validated as the
// frames arrive; findings printed as they happen, a status line per axis on a terminal, the
// usual report and exit status at the end (--duration, Ctrl-C), and a flight recorder that
// writes an annotated pcapng of the seconds around each finding.
#include <fmt/format.h>
#include <pcap/pcap.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "ncservo/capture/capture_annotation.hpp"
#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/capture/capture_writer.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"
#include "ncservo/protocol/drive_state.hpp"
#include "ncservo/report/report.hpp"
#include "ncservo/rules/coverage.hpp"
#include "ncservo/rules/validator.hpp"
#include "ncservo/telemetry/live_telemetry.hpp"
#include "ncservo/wire/ecat_wire.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "ncservo/wire/frame_clock.hpp"

namespace ncservo::cli {

using namespace report;  // the report layer's names
namespace {

constexpr int kSnapLength = 262144;
// The kernel's ring (docs/field.md#how-fast), mapped into the process and so part of its memory:
// no immediate mode, so that libpcap takes TPACKET_V3, whose blocks hold the frames packed (in
// immediate mode, TPACKET_V2 gives every frame a slot of the snap length, and 64 MiB held 255
// frames); the kernel hands a block over when it is full or kReadTimeoutMs after its first frame.
constexpr int kKernelBuffer = 16 << 20;  // bytes: 0.55 s of a 32-axis bus at 8 kHz
constexpr int kReadTimeoutMs = 100;      // the longest a finding waits, and the quiet link's poll
constexpr auto kStatusPeriod = std::chrono::milliseconds(250);
constexpr std::size_t kRecorderMemory = 256u << 20;  // bytes of frames the recorder keeps at most
// How often the metrics' snapshot is handed to the scrapes and ended incidents are published.
constexpr auto kTelemetryPeriod = std::chrono::milliseconds(100);

struct MonitorArgs : RuleArgs {
  std::string interface;
  LayoutArgs layout;
  std::string format = "text";
  FailOnArgs fail_on;
  std::string timestamps = "auto";
  std::optional<double> duration_s;
  std::string record_dir;
  double record_window_s = 5;
  std::string record_severity = "warning";
  double record_limit_mb = 1024;
  std::string metrics;  // [ADDR:]PORT
  std::string mqtt;     // mqtt[s]://HOST[:PORT]/PREFIX
  std::string mqtt_ca, mqtt_cert, mqtt_key, mqtt_client_id;
  std::size_t mqtt_queue = 10000;
  double mqtt_flush_s = 5;
};

// ---- The live capture ----

struct PcapCloser {
  void operator()(pcap_t* handle) const { pcap_close(handle); }
};
using LiveHandle = std::unique_ptr<pcap_t, PcapCloser>;

// The interface opened for EtherCAT (the kernel's ring, the capture filter); an error says what
// to do.
Result<LiveHandle> openLive(const std::string& interface) {
  char errbuf[PCAP_ERRBUF_SIZE] = {};
  LiveHandle handle(pcap_create(interface.c_str(), errbuf));
  if (!handle) return fail(fmt::format("{}: cannot capture: {}", interface, errbuf));
  // These fail only on a handle already activated (newer libpcap insists they are checked).
  for (const int status :
       {pcap_set_snaplen(handle.get(), kSnapLength), pcap_set_promisc(handle.get(), 1),
        pcap_set_buffer_size(handle.get(), kKernelBuffer),
        pcap_set_timeout(handle.get(), kReadTimeoutMs)}) {
    if (status != 0) {
      return fail(fmt::format("{}: cannot capture: {}", interface, pcap_statustostr(status)));
    }
  }
  // A device without nanosecond time stamps keeps microseconds: the loop asks which it got.
  const int nanoseconds = pcap_set_tstamp_precision(handle.get(), PCAP_TSTAMP_PRECISION_NANO);
  static_cast<void>(nanoseconds);
  const int activated = pcap_activate(handle.get());
  if (activated == PCAP_ERROR_PERM_DENIED || activated == PCAP_ERROR_PROMISC_PERM_DENIED) {
    return fail(fmt::format(
        "{}: no permission to capture: it needs CAP_NET_RAW (run as root, or give the program "
        "the capability: sudo setcap cap_net_raw,cap_net_admin=eip $(command -v ncservo))",
        interface));
  }
  if (activated == PCAP_ERROR_NO_SUCH_DEVICE) {
    return fail(fmt::format("{}: no such interface (ip link lists them)", interface));
  }
  if (activated < 0) {
    return fail(fmt::format("{}: cannot capture: {}", interface, pcap_geterr(handle.get())));
  }
  if (activated > 0) {
    fmt::print(stderr, "ncservo monitor: {}: {}\n", interface, pcap_statustostr(activated));
  }
  if (linkTypeFromDlt(pcap_datalink(handle.get())) == LinkType::Unsupported) {
    return fail(fmt::format("{}: link type {} is neither Ethernet nor Linux cooked", interface,
                            pcap_datalink(handle.get())));
  }
  bpf_program program{};
  if (pcap_compile(handle.get(), &program, ecat::kCaptureFilter, 1, PCAP_NETMASK_UNKNOWN) != 0 ||
      pcap_setfilter(handle.get(), &program) != 0) {
    fmt::print(stderr, "ncservo monitor: {}: capture filter not set ({}): every frame is read\n",
               interface, pcap_geterr(handle.get()));
  }
  pcap_freecode(&program);
  return handle;
}

// Ctrl-C and SIGTERM end the capture; the report is then written as usual.
std::atomic<pcap_t*> g_live{nullptr};
volatile std::sig_atomic_t g_stop = 0;
extern "C" void stopMonitor(int) {
  g_stop = 1;
  if (pcap_t* live = g_live.load()) pcap_breakloop(live);
}

// ---- The flight recorder ----

// UTC as a file name part: 20240501T120000.123456Z.
std::string fileTime(std::int64_t time_ns) {
  const std::time_t seconds = static_cast<std::time_t>(time_ns / 1'000'000'000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y%m%dT%H%M%S", &utc);
  return fmt::format("{}.{:06}Z", text, time_ns % 1'000'000'000 / 1000);
}

// The last `window` of frames in memory (bounded by time and by kRecorderMemory) and, for each
// finding it is given, an annotated pcapng of ±window around it; windows that overlap are one
// recording, named by the time and rule of its first finding. --record-limit bounds the bytes
// of recordings on disk: the oldest of this run are removed first.
class FlightRecorder {
 public:
  FlightRecorder(std::string dir, std::int64_t window_ns, std::uint64_t limit_bytes, int dlt,
                 std::function<void(const std::string&)> say)
      : dir_(std::move(dir)),
        window_ns_(window_ns),
        limit_bytes_(limit_bytes),
        dlt_(dlt),
        say_(std::move(say)) {}

  // Every captured record, in order. `settled`: the layout is known, so no finding can still
  // come for a frame older than the window (the learning window delivers frames late).
  void onRecord(const CaptureRecord& record, bool settled) {
    frames_.push_back({record.frame, record.time_ns, record.original,
                       std::vector<std::uint8_t>(record.data, record.data + record.captured)});
    bytes_ += record.captured;
    if (pending_ && record.time_ns > pending_->end_ns) flush();
    if (pending_ && bytes_ > kRecorderMemory) flush();  // a finding storm: write what is kept
    while (!frames_.empty() && (bytes_ > kRecorderMemory ||
                                (settled && frames_.front().time_ns < record.time_ns - window_ns_ &&
                                 (!pending_ || frames_.front().time_ns < pending_->start_ns)))) {
      bytes_ -= frames_.front().data.size();
      frames_.pop_front();
    }
  }

  void onFinding(const Finding& finding, const std::string& comment) {
    // The time of the finding's frame as captured (the validator's may be a probe's clock).
    std::int64_t t = frames_.empty() ? finding.at.time_ns : frames_.back().time_ns;
    const auto at =
        std::lower_bound(frames_.begin(), frames_.end(), finding.at.frame,
                         [](const Kept& kept, std::uint64_t frame) { return kept.frame < frame; });
    if (at != frames_.end() && at->frame == finding.at.frame) t = at->time_ns;
    if (pending_ && t - window_ns_ > pending_->end_ns) flush();
    if (!pending_) {
      pending_ = Pending{t - window_ns_, t + window_ns_, t, ruleDef(finding.rule).code, {}};
    }
    pending_->end_ns = std::max(pending_->end_ns, t + window_ns_);
    pending_->comments[finding.at.frame].push_back(comment);
  }

  // The capture ended: what is pending is written with the frames there are.
  void finish() {
    if (pending_) flush();
  }

 private:
  struct Kept {
    std::uint64_t frame;
    std::int64_t time_ns;
    std::size_t original;
    std::vector<std::uint8_t> data;
  };
  struct Pending {
    std::int64_t start_ns, end_ns;
    std::int64_t first_ns;  // the first finding's
    std::string rule;
    FrameComments comments;
  };

  void flush() {
    const Pending pending = std::move(*pending_);
    pending_.reset();
    std::string name = fmt::format("ncservo-{}-{}", fileTime(pending.first_ns), pending.rule);
    std::filesystem::path path = std::filesystem::path(dir_) / (name + ".pcapng");
    for (int n = 2; std::filesystem::exists(path); ++n) {
      path = std::filesystem::path(dir_) / fmt::format("{}-{}.pcapng", name, n);
    }
    const std::filesystem::path partial =
        path.parent_path() / ("." + path.filename().string() + ".partial");
    auto writer = CaptureWriter::openPcapng(partial.string(), {dlt_, 9});
    if (!writer) {
      say_(fmt::format("--record: {}", writer.error().text()));
      return;
    }
    std::size_t written = 0;
    for (const Kept& kept : frames_) {
      if (kept.time_ns < pending.start_ns || kept.time_ns > pending.end_ns) continue;
      const auto found = pending.comments.find(kept.frame);
      (*writer)->write(PacketRecord{kept.time_ns, kept.data.data(), kept.data.size(), kept.original,
                                    found == pending.comments.end() ? nullptr : &found->second});
      ++written;
    }
    if (Status closed = (*writer)->close(); !closed) {
      say_(fmt::format("--record: {}", closed.error().text()));
      std::filesystem::remove(partial);
      return;
    }
    std::error_code ec;
    std::filesystem::rename(partial, path, ec);
    const std::uint64_t size = std::filesystem::file_size(path, ec);
    recordings_.push_back({path, size});
    on_disk_ += size;
    say_(fmt::format("recorded {} ({} frames, {} finding frame{})", path.string(), written,
                     pending.comments.size(), pending.comments.size() == 1 ? "" : "s"));
    while (on_disk_ > limit_bytes_ && !recordings_.empty()) {
      const auto& [oldest, bytes] = recordings_.front();
      std::filesystem::remove(oldest, ec);
      on_disk_ -= bytes;
      say_(fmt::format("--record-limit: removed {}", oldest.string()));
      recordings_.pop_front();
    }
  }

  std::string dir_;
  std::int64_t window_ns_;
  std::uint64_t limit_bytes_;
  int dlt_;
  std::function<void(const std::string&)> say_;
  std::deque<Kept> frames_;
  std::size_t bytes_ = 0;
  std::optional<Pending> pending_;
  std::deque<std::pair<std::filesystem::path, std::uint64_t>> recordings_;
  std::uint64_t on_disk_ = 0;
};

// ---- The status lines ----

// One line per axis on a terminal (standard error), redrawn in place; cleared before anything
// else is printed so the findings scroll above it.
class StatusBoard {
 public:
  explicit StatusBoard(bool on) : on_(on) {}
  bool on() const { return on_; }
  void clear() {
    if (lines_ > 0) fmt::print(stderr, "\033[{}A\033[J", lines_);
    lines_ = 0;
  }
  void draw(const Validator* validator, const std::map<std::uint16_t, std::string>& last,
            std::uint64_t frames) {
    if (!on_) return;
    std::fflush(stdout);
    clear();
    std::vector<std::string> lines;
    if (validator == nullptr || validator->decoder().axes().empty()) {
      lines.push_back(fmt::format("{} frames, learning the layout", frames));
    } else {
      for (const AxisInfo& axis : validator->decoder().axes()) {
        const AxisModel* model = validator->axis(axis.index);
        const auto state = model != nullptr ? model->state() : std::nullopt;
        const auto found = last.find(axis.index);
        lines.push_back(fmt::format("{:<12} {:<28} failures {:<6} last: {}", axis.name,
                                    state ? driveStateName(*state) : "-",
                                    model != nullptr ? model->totalFailures() : 0,
                                    found != last.end() ? found->second : "-"));
      }
    }
    for (const std::string& line : lines) fmt::print(stderr, "{}\n", line);
    lines_ = static_cast<int>(lines.size());
  }

 private:
  bool on_;
  int lines_ = 0;
};

// ---- monitor ----

// The numbers and the directory the options give, checked before capturing.
Status checkMonitorArgs(const MonitorArgs& args) {
  if (!(args.record_window_s > 0) || !(args.record_limit_mb > 0) ||
      (args.duration_s && !(*args.duration_s > 0))) {
    return fail("--duration, --record-window and --record-limit take a number above 0");
  }
  if (!args.record_dir.empty() && !std::filesystem::is_directory(args.record_dir)) {
    return fail(fmt::format("--record {}: not a directory", args.record_dir));
  }
  return {};
}

// The text report of findings as they happen, or jsonl.
Result<std::unique_ptr<ReportWriter>> openMonitorReport(const MonitorArgs& args,
                                                        const RuleSettings& settings,
                                                        const PolicyJudge& judge) {
  report::ReportOptions options;
  options.verbose = true;  // text: every finding as it happens
  options.enabled = settings.enabled;
  return ReportWriter::open({{findReportFormat(args.format), ""}}, options, judge);
}

// Ctrl-C and SIGTERM end the capture of `handle` (null: as before).
void stopOnSignals(pcap_t* handle) {
  g_live = handle;
  if (handle == nullptr) {
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
    return;
  }
  struct sigaction action {};
  action.sa_handler = stopMonitor;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

// What the kernel and the interface dropped so far.
std::uint64_t droppedSoFar(pcap_t* handle) {
  pcap_stat stats{};
  if (pcap_stats(handle, &stats) != 0) return 0;
  return std::uint64_t{stats.ps_drop} + stats.ps_ifdrop;
}

// What the monitor shows besides the report: the status lines, the messages above them, the
// flight recorder, each axis's last finding, the metrics and MQTT (--metrics, --mqtt).
struct MonitorOutput {
  StatusBoard board{isatty(STDERR_FILENO) == 1};
  std::optional<FlightRecorder> recorder;
  std::optional<Severity> record_at;
  std::map<std::uint16_t, std::string> last_finding;  // by axis, for the status lines
  std::unique_ptr<LiveTelemetry> telemetry;
  const CaptureReport* report = nullptr;
  void say(const std::string& text) {
    std::fflush(stdout);
    board.clear();
    fmt::print(stderr, "ncservo monitor: {}\n", text);
  }
  // Every kTelemetryPeriod: the metrics handed over, ended incidents published, notes said.
  void tick(const CapturePipeline& pipeline, pcap_t* handle, std::uint64_t frames) {
    if (!telemetry) return;
    telemetry->update(pipeline, *report, frames, droppedSoFar(handle));
    for (const std::string& note : telemetry->notes()) say(note);
  }
};

// Each finding to the report as it happens, to the status lines and to the flight recorder.
void reportFindings(const std::vector<Finding>& findings, const CapturePipeline& pipeline,
                    ReportWriter& writer, CaptureReport& report, MonitorOutput& output) {
  for (const Finding& f : findings) {
    const BaselineState state = report.tally(f);
    output.board.clear();
    writer.finding(report, f, state);  // flushed when the kernel's buffer is drained
    if (f.axis && output.board.on()) {
      output.last_finding[*f.axis] =
          fmt::format("{} at {:.3f} s", ruleDef(f.rule).code,
                      (f.at.time_ns - *pipeline.run().first_time_ns) / 1e9);
    }
    if (output.recorder && f.severity >= *output.record_at) {
      output.recorder->onFinding(f, findingComment(f, pipeline.validator()->decoder().axes()));
    }
  }
}

struct LiveCapture {
  std::uint64_t frames = 0;
  std::optional<std::string> error;
};

// Reads the interface into the pipeline until --duration, Ctrl-C or a capture error.
LiveCapture captureLive(const MonitorArgs& args, pcap_t* handle, CapturePipeline& pipeline,
                        MonitorOutput& output) {
  const int digits = pcap_get_tstamp_precision(handle) == PCAP_TSTAMP_PRECISION_NANO ? 9 : 6;
  const int link_type = pcap_datalink(handle);
  const LinkType link = linkTypeFromDlt(link_type);
  using Clock = std::chrono::steady_clock;
  const auto began = Clock::now();
  std::optional<Clock::time_point> deadline;
  if (args.duration_s) {
    deadline = began + std::chrono::duration_cast<Clock::duration>(
                           std::chrono::duration<double>(*args.duration_s));
  }
  auto next_status = began;
  // Without --metrics and --mqtt there is nothing to tick: never a reason to wake.
  auto next_tick = output.telemetry ? began : Clock::time_point::max();
  // A blocking read can wait for ever on a quiet link (libpcap's TPACKET_V3 reader hands over
  // nothing until a frame comes, whatever its timeout): the handle reads without blocking and
  // the loop itself waits for the next frame, the status line or the deadline, whichever is
  // first (docs/field.md#monitor).
  char errbuf[PCAP_ERRBUF_SIZE] = {};
  int selectable = pcap_get_selectable_fd(handle);
  if (selectable >= 0 && pcap_setnonblock(handle, 1, errbuf) != 0) selectable = -1;
  LiveCapture live;
  while (g_stop == 0) {
    if (deadline && Clock::now() >= *deadline) break;
    pcap_pkthdr* header = nullptr;
    const u_char* data = nullptr;
    const int got = pcap_next_ex(handle, &header, &data);
    // The findings of what the kernel had handed over, written at once rather than one write
    // each: a storm of them (a replay's gaps are lost cycles to the rules) must not slow the
    // capture down.
    if (got == 0) std::fflush(stdout);
    if (got == 0 && selectable >= 0) {
      auto wake = std::min(
          {next_status, next_tick, Clock::now() + std::chrono::milliseconds(kReadTimeoutMs)});
      if (deadline) wake = std::min(wake, *deadline);
      const auto wait_ms =
          std::chrono::ceil<std::chrono::milliseconds>(wake - Clock::now()).count();
      pollfd readable{selectable, POLLIN, 0};
      // Ctrl-C interrupts the wait (EINTR), and g_stop ends the loop.
      static_cast<void>(poll(&readable, 1, static_cast<int>(std::max<long long>(wait_ms, 0))));
    } else if (got == 1) {
      CaptureRecord record;
      record.frame = ++live.frames;
      record.time_ns = static_cast<std::int64_t>(header->ts.tv_sec) * 1'000'000'000 +
                       static_cast<std::int64_t>(header->ts.tv_usec) * (digits == 9 ? 1 : 1000);
      record.data = data;
      record.captured = header->caplen;
      record.original = header->len;
      record.link_type = link_type;
      record.link = link;
      pipeline.onRecord(record);
      if (output.recorder) output.recorder->onRecord(record, !pipeline.learning());
    } else if (got == PCAP_ERROR_BREAK) {
      break;
    } else if (got < 0) {
      live.error = pcap_geterr(handle);
      break;
    }
    if (Clock::now() >= next_status) {
      output.board.draw(pipeline.validator(), output.last_finding, live.frames);
      next_status = Clock::now() + kStatusPeriod;
    }
    if (output.telemetry && Clock::now() >= next_tick) {
      output.tick(pipeline, handle, live.frames);
      next_tick = Clock::now() + kTelemetryPeriod;
    }
  }
  return live;
}

// What the kernel and the interface dropped: the capture's losses, not the bus's.
void printDrops(const std::string& interface, pcap_t* handle, std::uint64_t frames) {
  pcap_stat stats{};
  if (pcap_stats(handle, &stats) != 0) return;
  fmt::print(stderr,
             "ncservo monitor: {}: {} frames captured; dropped: {} by the kernel, {} by the "
             "interface{}\n",
             interface, frames, stats.ps_drop, stats.ps_ifdrop,
             stats.ps_drop + stats.ps_ifdrop > 0
                 ? " (the capture lost them, not necessarily the bus: COM findings around "
                   "them may be the capture's)"
                 : "");
}

// The report's end, as `validate` writes it, and the exit status.
int endReport(const std::string& interface, const LiveCapture& live, ReportWriter& writer,
              CaptureReport& report) {
  if (live.error) {
    report.error = *live.error + " (the frames before it were analysed)";
    fmt::print(stderr, "ncservo monitor: {}: {}\n", interface, *report.error);
  }
  writer.endCapture(report);
  std::vector<CaptureReport> reports{report};
  if (Status written = writer.finish(reports); !written) {
    fmt::print(stderr, "ncservo monitor: {}\n", written.error().text());
    return kExitUsage;
  }
  return writer.judge().exitStatus(report);
}

// --metrics and --mqtt with their options, checked before capturing.
Result<TelemetryOptions> telemetryOptions(const MonitorArgs& args) {
  TelemetryOptions options;
  if (!args.metrics.empty()) {
    Result<ListenAddress> address = parseListenAddress(args.metrics);
    if (!address) return fail(address.error());
    options.metrics = *address;
  }
  if (args.mqtt.empty()) {
    if (!args.mqtt_ca.empty() || !args.mqtt_cert.empty() || !args.mqtt_key.empty()) {
      return fail("--mqtt-ca, --mqtt-cert and --mqtt-key go with --mqtt mqtts://…");
    }
    return options;
  }
  Result<MqttTarget> target = parseMqttUrl(args.mqtt);
  if (!target) return fail(target.error());
  if (!target->tls &&
      (!args.mqtt_ca.empty() || !args.mqtt_cert.empty() || !args.mqtt_key.empty())) {
    return fail("--mqtt-ca, --mqtt-cert and --mqtt-key need mqtts://");
  }
  if (args.mqtt_cert.empty() != args.mqtt_key.empty()) {
    return fail("--mqtt-cert and --mqtt-key go together");
  }
  for (const std::string* file : {&args.mqtt_ca, &args.mqtt_cert, &args.mqtt_key}) {
    if (!file->empty() && !std::filesystem::is_regular_file(*file)) {
      return fail(fmt::format("{}: no such file", *file));
    }
  }
  if (args.mqtt_queue == 0 || !(args.mqtt_flush_s >= 0)) {
    return fail("--mqtt-queue takes a number above 0, --mqtt-flush one of 0 or more");
  }
  options.mqtt = MqttOptions{*target,        args.mqtt_client_id, args.mqtt_ca,
                             args.mqtt_cert, args.mqtt_key,       args.mqtt_queue};
  options.mqtt_flush = std::chrono::milliseconds(std::llround(args.mqtt_flush_s * 1000));
  return options;
}

int runMonitor(const MonitorArgs& args) {
  const Result<LayoutFiles> files = loadLayoutFiles(args.layout);
  RuleSettings settings;
  Status built = files ? buildSettings(args, files->config, settings) : fail(files.error());
  if (built) built = checkMonitorArgs(args);
  Result<TelemetryOptions> telemetry_options = telemetryOptions(args);
  if (built && !telemetry_options) built = fail(telemetry_options.error());
  if (!built) {
    fmt::print(stderr, "ncservo monitor: {}\n", built.error().text());
    return kExitUsage;
  }
  Result<LiveHandle> live = openLive(args.interface);
  if (!live) {
    fmt::print(stderr, "ncservo monitor: {}\n", live.error().text());
    return kExitCapture;
  }
  pcap_t* handle = live->get();
  VerdictPolicy policy;
  setFailOn(args.fail_on, false, policy);
  const PolicyJudge judge(policy);
  auto writer = openMonitorReport(args, settings, judge);
  if (!writer) {
    fmt::print(stderr, "ncservo monitor: {}\n", writer.error().text());
    return kExitUsage;
  }
  auto telemetry = LiveTelemetry::start(*telemetry_options, settings);
  if (!telemetry) {
    fmt::print(stderr, "ncservo monitor: {}\n", telemetry.error().text());
    return kExitUsage;
  }
  stopOnSignals(handle);
  MonitorOutput output;
  output.telemetry = std::move(*telemetry);
  if (output.telemetry && output.telemetry->metricsPort()) {
    output.say(fmt::format("metrics at http://{}:{}/metrics", telemetry_options->metrics->host,
                           *output.telemetry->metricsPort()));
  }
  output.record_at = severityFromName(args.record_severity);
  if (!args.record_dir.empty()) {
    output.recorder.emplace(args.record_dir, std::llround(args.record_window_s * 1e9),
                            static_cast<std::uint64_t>(args.record_limit_mb * 1024 * 1024),
                            pcap_datalink(handle),
                            [&output](const std::string& text) { output.say(text); });
  }
  CaptureReport report;
  output.report = &report;
  report.path = args.interface;
  report.timestamp_digits = pcap_get_tstamp_precision(handle) == PCAP_TSTAMP_PRECISION_NANO ? 9 : 6;
  (*writer)->beginCapture(report);
  CapturePipeline pipeline({decoderOptions(*files, args.layout), settings, TimeWindow{},
                            *timestampModeFromName(args.timestamps)});
  const auto start = [&](const DecoderOptions&) {
    report.layout = pipeline.validator()->decoder().axes();
  };
  const auto frame = [&](const PipelineFrame&) {
    report.first_time_ns = *pipeline.run().first_time_ns;
    if (output.telemetry) output.telemetry->onFrame(*pipeline.validator(), report);
  };
  const auto findings = [&](const std::vector<Finding>& found) {
    reportFindings(found, pipeline, **writer, report, output);
    if (output.telemetry) output.telemetry->onFindings(found, report);
  };
  pipeline.setSinks({start, frame, nullptr, findings, nullptr});
  const LiveCapture captured = captureLive(args, handle, pipeline, output);
  std::fflush(stdout);
  output.board.clear();
  pipeline.finish();  // what only the frames that did not come could tell (COM-002)
  if (output.recorder) output.recorder->finish();
  stopOnSignals(nullptr);
  printDrops(args.interface, handle, captured.frames);
  static_cast<CaptureResult&>(report) = pipeline.result();
  if (output.telemetry) {
    for (const std::string& line :
         output.telemetry->finish(pipeline, report, captured.frames, droppedSoFar(handle))) {
      output.say(line);
    }
    for (const std::string& note : output.telemetry->notes()) output.say(note);
    if (output.telemetry->metricsPort()) {
      output.say(fmt::format(
          "--metrics: {} scrapes, {:.3f} ms formatting each", output.telemetry->scrapes(),
          output.telemetry->scrapes() == 0 ? 0.0
                                           : output.telemetry->scrapeSeconds() * 1e3 /
                                                 static_cast<double>(output.telemetry->scrapes())));
    }
  }
  return endReport(args.interface, captured, **writer, report);
}

}  // namespace

Handler monitorCommand(CLI::App& command) {
  auto args = std::make_shared<MonitorArgs>();
  command.add_option("-i,--interface", args->interface, "the network interface to capture on")
      ->required();
  command.add_option("--format", args->format, "text or jsonl: findings as they happen")
      ->check(oneOf({"text", "jsonl"}));
  command.add_option("--duration", args->duration_s,
                     "stop after SECONDS (default: at Ctrl-C), then report");
  addFailOnOption(command, args->fail_on);
  command.add_option("--record", args->record_dir,
                     "flight recorder: write an annotated pcapng around each finding into DIR");
  command.add_option("--record-window", args->record_window_s,
                     "seconds kept before and after each finding (default 5)");
  command
      .add_option("--record-severity", args->record_severity,
                  "record findings at or above: error, warning or info (default warning)")
      ->check(oneOf({"error", "warning", "info"}));
  command.add_option("--record-limit", args->record_limit_mb,
                     "MiB of recordings kept on disk, the oldest removed first (default 1024)");
  command.add_option("--metrics", args->metrics,
                     "[ADDR:]PORT: serve Prometheus metrics at /metrics (docs/field.md#metrics)");
  command.add_option("--mqtt", args->mqtt,
                     "mqtt://HOST[:PORT]/PREFIX or mqtts://…: publish findings and incidents, QoS "
                     "1 (docs/field.md#mqtt)");
  command.add_option("--mqtt-ca", args->mqtt_ca, "mqtts: the broker's CA certificate (PEM)");
  command.add_option("--mqtt-cert", args->mqtt_cert, "mqtts: a client certificate (PEM)");
  command.add_option("--mqtt-key", args->mqtt_key, "mqtts: the client certificate's key (PEM)");
  command.add_option("--mqtt-client-id", args->mqtt_client_id,
                     "the MQTT client id (default ncservo-HOSTNAME-PID)");
  command.add_option("--mqtt-queue", args->mqtt_queue,
                     "messages kept while the broker is away, the oldest dropped first (default "
                     "10000)");
  command.add_option("--mqtt-flush", args->mqtt_flush_s,
                     "seconds the end waits for the broker to acknowledge the queue (default 5)");
  addLayoutOptions(command, args->layout);
  addRuleOptions(command, *args);
  addTimestampsOption(command, args->timestamps);
  return [args] { return runMonitor(*args); };
}

}  // namespace ncservo::cli
