#include "ncservo/session.hpp"

namespace ncservo {

const FrameView& Session::onFrame(const EcatFrame& frame, const ByteReader& bytes) {
  decoder_.decode(frame, bytes, decode_);
  view_.copy = decode_.copy;
  view_.paired = decode_.paired;
  view_.axis_count = decode_.axis_count;
  for (std::size_t i = 0; i < decode_.axis_count; ++i) {
    AxisFrameView& axis = view_.axes[i];
    axis.placement = decode_.axes[i];
    readFrameValues(axis.placement, bytes, axis.values);
    axis.state.reset();
    if (!track_states_) continue;
    const std::size_t index = axis.placement.axis;
    if (index >= latest_.size()) latest_.resize(index + 1);
    PdoValues& latest = latest_[index];
    for (const WordDef& word : kWords) {
      if (axis.values.has(word.word)) {
        latest.raw[static_cast<std::size_t>(word.word)] = axis.values.word(word.word);
      }
    }
    latest.has_rx = latest.has_rx || axis.values.has_rx;
    latest.has_tx = latest.has_tx || axis.values.has_tx;
    axis.state = driveState(latest);
  }
  return view_;
}

}  // namespace ncservo
