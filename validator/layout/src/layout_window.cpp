#include "ncservo/layout/layout_window.hpp"

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
  held_.push_back(Held{frame_number, time_ns, link, bytes_.size(), bytes.size(), judged});
  bytes_.insert(bytes_.end(), bytes.data(), bytes.data() + bytes.size());
  probe_->placeAxes(frame, bytes, *decode_);
  // docs/protocol.md §9.3 before §9.4: a captured start-up gives the layout (or shows no servo).
  if (probe_->learner().sawConfiguration()) {
    learning_ = false;
    probe_.reset();
    inference_.reset();
    return;
  }
  inference_->onFrame(frame, bytes, decode_->copy == CopyKind::Returned);
  if (inference_->settled() || held_.size() >= limits_.max_frames ||
      bytes_.size() >= limits_.max_bytes || time_ns - *first_time_ns_ >= limits_.max_ns) {
    decide();
  }
}

void LayoutWindow::finish() {
  if (learning_) decide();
}

void LayoutWindow::decide() {
  learning_ = false;
  InferenceResult result = inference_->decide();
  if (result.axes.empty()) {
    options_.inference_refusal = result.refusal;
  } else {
    options_.explicit_source = LayoutSource::Inferred;
    for (const InferredAxis& axis : result.axes) options_.axes.push_back(axis.config);
  }
  result_ = std::move(result);
  probe_.reset();
  inference_.reset();
}

void LayoutWindow::replay(const Sink& sink, const Sink& outside) {
  EcatFrame frame;
  for (const Held& h : held_) {
    const ByteReader bytes(bytes_.data() + h.offset, h.size);
    walkPacket(h.link, bytes, frame);
    if (h.judged) {
      sink(h.number, h.time_ns, frame, bytes);
    } else if (outside) {
      outside(h.number, h.time_ns, frame, bytes);
    }
  }
  held_.clear();
  held_.shrink_to_fit();
  bytes_.clear();
  bytes_.shrink_to_fit();
}

}  // namespace ncservo
