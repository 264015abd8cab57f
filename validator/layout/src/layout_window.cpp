#include "ncservo/layout/layout_window.hpp"

#include <fmt/format.h>

#include <utility>

namespace ncservo {

LayoutWindow::LayoutWindow(DecoderOptions options, WindowLimits limits)
    : options_(std::move(options)), limits_(limits) {
  learning_ = options_.axes.empty() && options_.default_layout;
  if (!learning_) return;
  probe_ = std::make_unique<Decoder>(DecoderOptions{});
  decode_ = std::make_unique<FrameDecode>();
  inference_ = std::make_unique<LayoutInference>(limits_.inference);
}

LayoutWindow::~LayoutWindow() = default;

void LayoutWindow::hold(std::uint64_t frame_number, std::int64_t time_ns, LinkType link,
                        const ByteReader& bytes, const EcatFrame& frame, bool judged) {
  if (!learning_) return;
  if (!first_time_ns_) first_time_ns_ = time_ns;
  last_number_ = frame_number;
  keep(frame_number, time_ns, link, bytes, judged);
  probe_->placeAxes(frame, bytes, *decode_);
  // docs/protocol.md §9.3 before §9.4: a captured start-up gives the layout (or shows no servo).
  if (probe_->learner().sawConfiguration()) {
    learning_ = false;
    probe_.reset();
    inference_.reset();
    return;
  }
  inference_->onFrame(frame, bytes, decode_->copy == CopyKind::Returned);
  if (inference_->settled() || (!looking_further_ && firstWindowFull(time_ns))) {
    endOfWindow(frame_number, false);
  }
}

bool LayoutWindow::firstWindowFull(std::int64_t time_ns) const {
  return newer_.held.size() >= limits_.max_frames || newer_.bytes.size() >= limits_.max_bytes ||
         time_ns - *first_time_ns_ >= limits_.max_ns;
}

// While looking further, the newer generation holds at most half the limits; when it is full,
// the older one is forgotten and it takes its place.
void LayoutWindow::keep(std::uint64_t frame_number, std::int64_t time_ns, LinkType link,
                        const ByteReader& bytes, bool judged) {
  if (looking_further_ && (newer_.held.size() >= limits_.max_frames / 2 ||
                           newer_.bytes.size() >= limits_.max_bytes / 2)) {
    forgetOlder();
    older_ = std::exchange(newer_, Generation{});
  }
  newer_.held.push_back(
      Held{frame_number, time_ns, link, newer_.bytes.size(), bytes.size(), judged});
  newer_.bytes.insert(newer_.bytes.end(), bytes.data(), bytes.data() + bytes.size());
}

void LayoutWindow::forgetOlder() {
  for (const Held& h : older_.held) {
    if (!h.judged) continue;
    ++late_.unjudged_frames;
    if (late_.first_unjudged == 0) late_.first_unjudged = h.number;
    late_.last_unjudged = h.number;
  }
  older_ = Generation{};
}

void LayoutWindow::finish() {
  if (learning_) endOfWindow(last_number_, true);
}

namespace {
// After the first window, a layout that leaves servo-like status words unexplained is taken once
// this many windows found no more axes (an axis that never enables); axes enabled one after
// another, seconds apart, are all found first.
constexpr std::uint32_t kWindowsWithoutNewAxes = 4;
}  // namespace

// A window of evidence ended: its layout is taken, or, refused, the next window begins (the
// frames held so far become the older generation), unless the capture ended.
void LayoutWindow::endOfWindow(std::uint64_t frame_number, bool capture_ended) {
  InferenceResult result = inference_->decide();
  late_.cycles += result.cycles;
  const std::size_t best = best_partial_ ? best_partial_->axes.size() : 0;
  if (!result.axes.empty() || best > 0) {
    const bool complete = !result.axes.empty() && result.unexplained == 0;
    windows_without_new_axes_ = result.axes.size() > best ? 0 : windows_without_new_axes_ + 1;
    if (!looking_further_ || complete || capture_ended ||
        windows_without_new_axes_ >= kWindowsWithoutNewAxes) {
      if (looking_further_) late_.certain_at = frame_number;
      adopt(result.axes.size() >= best ? std::move(result) : std::move(*best_partial_));
      return;
    }
    if (result.axes.size() >= best) best_partial_ = std::move(result);
  } else if (capture_ended || !limits_.keep_looking) {
    if (looking_further_) {
      // A last window cut short by the end of the capture says less than a whole one.
      if (last_refusal_ && result.cycles < last_refusal_->cycles) result = *last_refusal_;
      result.refusal = fmt::format(
          "the layout never became certain over the whole capture ({} cycles in {} windows of "
          "evidence); the last window: {}",
          late_.cycles, late_.windows, result.refusal);
    }
    adopt(std::move(result));
    return;
  } else {
    last_refusal_ = std::move(result);
  }
  if (!looking_further_) {
    looking_further_ = true;
    older_ = std::exchange(newer_, Generation{});
  }
  ++late_.windows;
  inference_ = std::make_unique<LayoutInference>(limits_.inference);
}

void LayoutWindow::adopt(InferenceResult result) {
  learning_ = false;
  if (result.axes.empty()) {
    options_.inference_refusal = result.refusal;
  } else {
    options_.explicit_source = LayoutSource::Inferred;
    for (const InferredAxis& axis : result.axes) options_.axes.push_back(axis.config);
  }
  result_ = std::move(result);
  last_refusal_.reset();
  best_partial_.reset();
  probe_.reset();
  inference_.reset();
}

void LayoutWindow::replay(const Sink& sink, const Sink& outside) {
  EcatFrame frame;
  for (Generation* generation : {&older_, &newer_}) {
    for (const Held& h : generation->held) {
      const ByteReader bytes(generation->bytes.data() + h.offset, h.size);
      walkPacket(h.link, bytes, frame);
      if (h.judged) {
        sink(h.number, h.time_ns, frame, bytes);
      } else if (outside) {
        outside(h.number, h.time_ns, frame, bytes);
      }
    }
    *generation = Generation{};
  }
}

}  // namespace ncservo
