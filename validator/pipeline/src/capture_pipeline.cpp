#include "ncservo/pipeline/capture_pipeline.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <tuple>
#include <utility>

#include "ncservo/base/number.hpp"

namespace ncservo {

Result<TimeWindow> timeWindowOf(const std::optional<std::string>& from,
                                const std::optional<std::string>& to, TimeZone zone) {
  constexpr double kLimitS = 1e9;  // about 30 years either way: the nanoseconds fit
  TimeWindow window;
  for (auto [option, text, ns, absolute] :
       {std::tuple{"--from", &from, &window.from_ns, &window.from_absolute},
        std::tuple{"--to", &to, &window.to_ns, &window.to_absolute}}) {
    if (!*text) continue;
    if (const Result<double> seconds = parseNumber<double>(**text); seconds) {
      if (!std::isfinite(*seconds) || std::fabs(*seconds) > kLimitS) {
        return fail(
            fmt::format("{} {}: expected seconds since the capture's first frame", option, **text));
      }
      *ns = std::llround(*seconds * 1e9);
    } else if (const std::optional<std::int64_t> time = parseIsoTime(**text, zone); time) {
      *ns = *time;
      *absolute = true;
    } else {
      return fail(
          fmt::format("{} {}: expected seconds since the capture's first frame or an ISO 8601 time "
                      "(2024-05-01T10:41:00, with Z or +01:00 for its zone)",
                      option, **text));
    }
  }
  if (window.from_ns && window.to_ns && window.from_absolute == window.to_absolute &&
      *window.to_ns < *window.from_ns) {
    return fail(fmt::format("--to {} is before --from {}", *to, *from));
  }
  return window;
}

std::string describeTimeWindow(const TimeWindow& window) {
  std::string out;
  auto add = [&out](const char* option, const std::optional<std::int64_t>& ns, bool absolute) {
    if (!ns) return;
    out += fmt::format("{}{} {}", out.empty() ? "" : " ", option,
                       absolute ? isoTime(*ns, 6, TimeZone::Utc) : fmt::format("{:g}", *ns / 1e9));
  };
  add("--from", window.from_ns, window.from_absolute);
  add("--to", window.to_ns, window.to_absolute);
  return out;
}

CapturePipeline::CapturePipeline(PipelineOptions options, WindowLimits limits)
    : rules_(std::move(options.rules)),
      time_window_(options.window),
      clock_(options.timestamps),
      clock_stage_([this](std::uint64_t number, std::int64_t time_ns, LinkType link,
                          const ByteReader& bytes, const EcatFrame& frame,
                          bool judged) { route(number, time_ns, link, bytes, frame, judged); },
                   [this](std::uint64_t number) {
                     if (sinks_.duplicate) sinks_.duplicate(number);
                   }),
      window_(std::move(options.layout), limits) {
  if (!window_.learning() && rules_) {
    validator_.emplace(window_.options(), *rules_);
    incidents_.emplace(*rules_);
  }
  const LayoutSource source = window_.options().explicit_source;
  if (validator_ && !window_.options().axes.empty() &&
      (source == LayoutSource::Config || source == LayoutSource::Eni)) {
    fit_.emplace();
  }
}

void CapturePipeline::started() {
  if (started_) return;
  started_ = true;
  if (sinks_.start) sinks_.start(window_.options());
}

// The window decided the layout: the validator starts with it, then the held frames follow.
void CapturePipeline::decided() {
  if (rules_) {
    validator_.emplace(window_.options(), *rules_);
    incidents_.emplace(*rules_);
    clock_told_ = false;
  }
  started();
  window_.replay(
      [this](std::uint64_t number, std::int64_t time_ns, const EcatFrame& frame,
             const ByteReader& bytes) { deliver(number, time_ns, frame, bytes); },
      [this](std::uint64_t number, std::int64_t time_ns, const EcatFrame& frame,
             const ByteReader& bytes) { deliverLayoutOnly(number, time_ns, frame, bytes); });
}

void CapturePipeline::deliver(std::uint64_t number, std::int64_t time_ns, const EcatFrame& frame,
                              const ByteReader& bytes) {
  started();
  if (validator_ && !clock_told_) {
    // On the bus's clock or in cycles, a returned copy has no time of its own to measure.
    const ClockSource source = clock_stage_.choice().source;
    validator_->measureLatencies(source == ClockSource::Capture || source == ClockSource::Probe);
    clock_told_ = true;
  }
  const Observation* judged =
      validator_ ? &validator_->onFrame(number, time_ns, frame, bytes) : nullptr;
  if (fit_ && judged != nullptr) fit_->onFrame(judged->decode, bytes);
  if (incidents_ && judged != nullptr) incidents_->onFrame(*validator_, *judged, number, time_ns);
  if (sinks_.frame) sinks_.frame(PipelineFrame{number, time_ns, frame, bytes, judged});
  if (validator_ && sinks_.findings && !validator_->findings().empty()) {
    sinks_.findings(validator_->findings());
  }
}

void CapturePipeline::deliverLayoutOnly(std::uint64_t number, std::int64_t time_ns,
                                        const EcatFrame& frame, const ByteReader& bytes) {
  started();
  if (validator_) validator_->onLayoutOnlyFrame(frame, bytes);
  if (sinks_.layout_only) sinks_.layout_only(PipelineFrame{number, time_ns, frame, bytes, nullptr});
}

void CapturePipeline::onRecord(const CaptureRecord& record) {
  if (const std::optional<WalkedRecord> walked = walk(record, frame_)) {
    const ByteReader bytes(record.data, record.captured);
    onWalkedFrame(record.frame, walked->time_ns, record.link, bytes, frame_, walked->judged,
                  walked->probe_timed);
  }
}

CaptureInterface* CapturePipeline::interfaceOf(const CaptureRecord& record) {
  for (CaptureInterface& i : interfaces_) {
    if (i.id == record.interface) return last_interface_ = &i;
  }
  if (interfaces_.size() >= kMaxInterfaces) return nullptr;
  // Room for all at once: the pointer to the last one stays valid.
  if (interfaces_.empty()) interfaces_.reserve(kMaxInterfaces);
  interfaces_.push_back({.id = record.interface, .link_type = record.link_type});
  return last_interface_ = &interfaces_.back();
}

std::optional<WalkedRecord> CapturePipeline::walk(const CaptureRecord& record, EcatFrame& frame) {
  if (!run_.first_time_ns) run_.first_time_ns = record.time_ns;
  // Records merged by time may come out of frame order (record_merge.hpp).
  run_.records = std::max(run_.records, record.frame);
  if (record.captured < record.original &&
      (run_.snapped++ == 0 || record.frame < run_.first_snapped)) {
    run_.first_snapped = record.frame;
  }
  // A capture of one interface finds it at once.
  CaptureInterface* counted =
      last_interface_ != nullptr && last_interface_->id == record.interface ? last_interface_
                                                                            : interfaceOf(record);
  if (counted != nullptr) {
    ++counted->frames;
  } else {
    ++interface_records_omitted_;
  }
  const ByteReader bytes(record.data, record.captured);
  walkPacket(record.link, bytes, frame);
  if (frame.status == WalkStatus::NotEtherCat) return std::nullopt;
  if (counted != nullptr) counted->ethercat = true;
  ++run_.ethercat;
  const std::int64_t time_ns = clock_.time(record.frame, record.time_ns, frame.probe);
  const bool judged = time_window_.contains(time_ns - *run_.first_time_ns, *run_.first_time_ns);
  run_.in_window += judged ? 1 : 0;
  if (frame.status == WalkStatus::NotDatagrams || frame.status == WalkStatus::BusFault) {
    return std::nullopt;
  }
  return WalkedRecord{time_ns, judged, clock_.source() == TimestampSource::Probe};
}

void CapturePipeline::onWalkedFrame(std::uint64_t number, std::int64_t time_ns, LinkType link,
                                    const ByteReader& bytes, const EcatFrame& frame, bool judged,
                                    bool probe_timed) {
  clock_stage_.onFrame(number, time_ns, link, bytes, frame, judged, probe_timed);
  if (judge_held_ && rules_ && learning()) {
    if (!held_judge_) held_judge_.emplace(window_.options(), *rules_);
    held_judge_->onFrame(number, time_ns, frame, bytes);
  } else {
    held_judge_.reset();
  }
}

void CapturePipeline::route(std::uint64_t number, std::int64_t time_ns, LinkType link,
                            const ByteReader& bytes, const EcatFrame& frame, bool judged) {
  if (window_.learning()) {
    window_.hold(number, time_ns, link, bytes, frame, judged);
    if (!window_.learning()) decided();
  } else if (judged) {
    deliver(number, time_ns, frame, bytes);
  } else {
    deliverLayoutOnly(number, time_ns, frame, bytes);
  }
}

void CapturePipeline::endLearning() {
  held_judge_.reset();
  clock_stage_.finish();
  if (!window_.learning()) return;
  window_.finish();
  decided();
}

std::string emptyWindowReason(const TimeWindow& window, const CaptureRun& run) {
  if (!window.limited() || run.in_window > 0) return "";
  return fmt::format("no EtherCAT frame in the time window ({})", describeTimeWindow(window));
}

std::string noEtherCatReason(const CaptureRun& run) {
  if (run.ethercat > 0) return "";
  if (run.records == 0) return "no EtherCAT frame in the capture: it holds no frame";
  return fmt::format("no EtherCAT frame in the capture: its {} frame{} {} other traffic",
                     run.records, run.records == 1 ? "" : "s", run.records == 1 ? "is" : "are");
}

std::vector<std::string> eniCycleWarnings(const std::vector<EniCyclicFrame>& eni,
                                          const std::vector<CyclicFrameSummary>& seen) {
  std::vector<std::string> warnings;
  for (const EniCyclicFrame& frame : eni) {
    if (!frame.cycle_us || frame.commands.empty()) continue;
    const EniCommand& first = frame.commands.front();
    const auto carries = [&](const CyclicFrameSummary& s) {
      return std::any_of(s.datagrams.begin(), s.datagrams.end(), [&](const CyclicDatagram& d) {
        return std::any_of(frame.commands.begin(), frame.commands.end(), [&](const EniCommand& c) {
          return c.command == d.command && c.address == d.address && c.length == d.length;
        });
      });
    };
    const auto shown = std::find_if(seen.begin(), seen.end(), carries);
    if (shown == seen.end() || !shown->cycle_ns) continue;
    const std::int64_t eni_ns = std::int64_t{*frame.cycle_us} * 1000;
    if (std::abs(*shown->cycle_ns - eni_ns) * 10 <= eni_ns) continue;
    warnings.push_back(fmt::format(
        "the ENI's cyclic frame of {} {:#010x} ({} bytes) has the cycle time {} us of its task; "
        "the capture shows it every {:.1f} us (docs/layout.md#eni-cycle-times)",
        ecat::commandName(first.command), first.address, first.length, *frame.cycle_us,
        static_cast<double>(*shown->cycle_ns) / 1000.0));
  }
  return warnings;
}

namespace {

// Why nothing could be checked when no record came on a link type the walker reads (a pcapng
// opens whatever its interfaces are: docs/cli.md#interfaces); empty when some did.
std::string unreadLinkTypes(const CaptureResult& r) {
  std::vector<int> types;
  for (const CaptureInterface& i : r.interfaces) {
    if (linkTypeFromDlt(i.link_type) != LinkType::Unsupported) return {};
    if (std::find(types.begin(), types.end(), i.link_type) == types.end()) {
      types.push_back(i.link_type);
    }
  }
  if (types.empty()) return {};
  return fmt::format(
      "no frame of a link type ncservo reads (Ethernet, Linux cooked SLL and SLL2): the "
      "capture's link type{} {}",
      types.size() == 1 ? " is" : "s are", fmt::join(types, ", "));
}

}  // namespace

bool CapturePipeline::structureOnly(std::uint16_t axis) const {
  const std::optional<InferenceResult>& inferred = window_.inference();
  const bool layout_inferred =
      validator_ ? validator_->decoder().source() == LayoutSource::Inferred
                 : layout().explicit_source == LayoutSource::Inferred && !layout().axes.empty();
  return layout_inferred && inferred && axis < inferred->axes.size() &&
         inferred->axes[axis].evidence.structure_only;
}

CaptureResult CapturePipeline::result() const {
  CaptureResult r;
  r.frames = run_.records;
  r.first_time_ns = run_.first_time_ns.value_or(0);
  r.timestamps = clock_.source();
  r.probe = clock_.counts();
  r.probe_note = clock_.note();
  r.clock = clock_stage_.choice();
  r.duplicates = clock_stage_.duplicates();
  r.untimed_frames = clock_stage_.untimed();
  r.late_layout = lateLayout();
  r.layout_warnings = layout_warnings_;
  r.interfaces = interfaces_;
  std::sort(r.interfaces.begin(), r.interfaces.end(),
            [](const CaptureInterface& a, const CaptureInterface& b) { return a.id < b.id; });
  r.interface_records_omitted = interface_records_omitted_;
  if (!validator_) return r;
  const Validator& validator = *validator_;
  takeValidator(validator, r);
  if (incidents_) {
    r.incidents = incidents_->incidents();
    r.incidents_omitted = incidents_->omitted();
  }
  if (inference() && r.layout_source == LayoutSource::Inferred) {
    for (const InferredAxis& axis : inference()->axes) r.inferred.push_back(axis.evidence);
  }
  r.coverage = coverageOf(validator);
  if (std::string empty = emptyWindowReason(time_window_, run_); !empty.empty()) {
    r.coverage.reason = std::move(empty);
    r.coverage.wants_layout = false;
  }
  if (std::string none = noEtherCatReason(run_); !none.empty()) {
    r.coverage.reason = std::move(none);
    r.coverage.wants_layout = false;
  }
  r.truncation = truncationOf(run_.snapped, run_.first_snapped, validator.cutRegions(),
                              validator.decoder().axes());
  if (std::string unread = unreadLinkTypes(r); !r.coverage.complete() && !unread.empty()) {
    r.coverage.reason = std::move(unread);
    r.coverage.wants_layout = false;
  }
  return r;
}

std::vector<std::string> CapturePipeline::layoutMisfitsSoFar() const {
  if (!fit_ || !validator_) return {};
  return fit_->warnings(validator_->decoder().axes());
}

void CapturePipeline::finish() {
  endLearning();
  started();
  if (!validator_) return;
  if (fit_) layout_warnings_ = fit_->warnings(validator_->decoder().axes());
  for (std::string& warning : eniCycleWarnings(eni_frames_, validator_->bus().cyclicFrames())) {
    layout_warnings_.push_back(std::move(warning));
  }
  validator_->finish();
  if (incidents_) incidents_->finish();
  if (sinks_.findings && !validator_->findings().empty()) sinks_.findings(validator_->findings());
}

}  // namespace ncservo
