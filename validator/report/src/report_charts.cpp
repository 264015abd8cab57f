#include "ncservo/report/report_charts.hpp"

#include <algorithm>

namespace ncservo::report {

namespace {
// A field's value in a word: its bits shifted down (a whole word's row: the word).
std::uint64_t fieldValue(const FieldDef& field, std::uint64_t raw) {
  if (field.mask == 0) return raw;
  std::uint64_t mask = field.mask;
  while ((mask & 1) == 0) {
    mask >>= 1;
    raw >>= 1;
  }
  return raw & mask;
}
}  // namespace

TimelineRecorder::AxisRing& TimelineRecorder::ring(std::uint16_t axis) {
  if (axis >= axes_.size()) axes_.resize(axis + 1u);
  AxisRing& r = axes_[axis];
  if (r.samples.empty()) r.samples.resize(kRingFrames);
  return r;
}

void TimelineRecorder::frame(std::uint64_t number, std::int64_t time_ns, const Observation& frame) {
  const FrameDecode& decode = frame.decode;
  for (std::size_t i = 0; i < decode.axis_count; ++i) {
    const AxisPlacement& placement = decode.axes[i];
    if (!placement.has_rx && !placement.has_tx) continue;
    AxisRing& r = ring(placement.axis);
    const PdoValues& values = frame.values[i];
    // docs/protocol.md §8: outputs from either copy, inputs from the returned copy.
    for (std::size_t w = 0; w < kWordCount; ++w) {
      if (values.has(kWords[w].word)) r.current[w] = values.raw[w];
    }
    Sample& sample = r.samples[r.next];
    sample.frame = number;
    sample.time_ns = time_ns;
    sample.raw = r.current;
    r.next = (r.next + 1) % kRingFrames;
    r.size = std::min(r.size + 1, kRingFrames);
    if (r.pending.empty()) continue;
    for (Pending& p : r.pending) {
      if (number > p.at.frame) ++p.after;
    }
    auto done = [](const Pending& p) { return p.after >= kFramesAround; };
    for (const Pending& p : r.pending) {
      if (done(p)) cut(r, p);
    }
    r.pending.erase(std::remove_if(r.pending.begin(), r.pending.end(), done), r.pending.end());
  }
}

void TimelineRecorder::finding(const Finding& f) {
  const std::size_t index = findings_++;
  const RuleDef& rule = ruleDef(f.rule);
  if (!f.axis || rule.kind != RuleKind::Axis) return;
  // A rule that reads no field-table row (COM-005 counts failed cycles) has nothing to draw: no
  // timeline, and the page links none (docs/html-report.md).
  if (fieldsRead(rule.reads).empty()) return;
  AxisRing& r = ring(*f.axis);
  std::size_t& drawn = r.drawn[static_cast<std::size_t>(f.rule)];
  if (drawn >= kPerRuleAndAxis || out_.drawn.size() + pendingCount() >= kMaxTimelines) {
    ++out_.omitted;
    return;
  }
  ++drawn;
  r.pending.push_back({index, f.rule, f.at, f.since});
}

std::size_t TimelineRecorder::pendingCount() const {
  std::size_t count = 0;
  for (const AxisRing& r : axes_) count += r.pending.size();
  return count;
}

void TimelineRecorder::cut(AxisRing& r, const Pending& p) {
  // The ring's samples, oldest first.
  const std::size_t oldest = (r.next + kRingFrames - r.size) % kRingFrames;
  auto at = [&](std::size_t k) -> const Sample& { return r.samples[(oldest + k) % kRingFrames]; };
  std::size_t finding_k = r.size;
  std::size_t since_k = r.size;
  for (std::size_t k = 0; k < r.size; ++k) {
    if (since_k == r.size && at(k).frame >= p.since.frame) since_k = k;
    if (at(k).frame <= p.at.frame) finding_k = k;
  }
  if (finding_k == r.size) return;  // the axis carried nothing up to the finding
  const bool clipped = since_k == r.size || at(since_k).frame > p.since.frame;
  if (since_k == r.size) since_k = 0;
  const std::size_t first = since_k > kFramesAround ? since_k - kFramesAround : 0;
  const std::size_t last = std::min(r.size - 1, finding_k + kFramesAround);
  const std::int64_t origin = at(finding_k).time_ns;

  FindingTimeline timeline;
  timeline.finding = p.finding;
  timeline.start_ns = at(first).time_ns - origin;
  timeline.end_ns = at(last).time_ns - origin;
  timeline.clipped = clipped;
  if (!clipped) {
    timeline.since_ns = at(since_k).time_ns - origin;
    if (const std::optional<AllowedWindow> w = allowedWindow(ruleDef(p.rule), settings_)) {
      timeline.allowed_ns = {*timeline.since_ns + w->from_ns, *timeline.since_ns + w->to_ns};
    }
  }
  const Reads& reads = ruleDef(p.rule).reads;
  for (const FieldRead& read : fieldsRead(reads)) {
    BitTrace trace{read.field, read.through_class, {}};
    const std::size_t w = static_cast<std::size_t>(read.field->word);
    const WordClass word_class = reads.classes[w];
    for (std::size_t k = first; k <= last; ++k) {
      const std::uint64_t raw = at(k).raw[w];
      const std::uint64_t value =
          read.through_class ? (word_class(raw) ? 1 : 0) : fieldValue(*read.field, raw);
      if (trace.changes.empty() || trace.changes.back().second != value) {
        trace.changes.emplace_back(at(k).time_ns - origin, value);
      }
    }
    timeline.traces.push_back(std::move(trace));
  }
  out_.drawn.push_back(std::move(timeline));
}

FindingTimelines TimelineRecorder::finish() {
  for (AxisRing& r : axes_) {
    for (const Pending& p : r.pending) cut(r, p);
    r.pending.clear();
  }
  std::sort(
      out_.drawn.begin(), out_.drawn.end(),
      [](const FindingTimeline& a, const FindingTimeline& b) { return a.finding < b.finding; });
  return std::move(out_);
}

}  // namespace ncservo::report
