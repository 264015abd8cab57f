#include "ncservo/layout/session.hpp"

namespace ncservo {

const FrameView& Session::onFrame(const EcatFrame& frame, const ByteReader& bytes) {
  decoder_.placeAxes(frame, bytes, decode_);
  for (std::size_t i = 0; i < decode_.axis_count; ++i) {
    readFrameValues(decode_.axes[i], bytes, view_.axes[i].values);
  }
  return take(decode_);
}

const FrameView& Session::onDecoded(const FrameDecode& decode,
                                    const std::array<PdoValues, kMaxAxesPerFrame>& values) {
  for (std::size_t i = 0; i < decode.axis_count; ++i) view_.axes[i].values = values[i];
  return take(decode);
}

// The frame's values are in the view: its placements, each axis's latest values and state.
const FrameView& Session::take(const FrameDecode& decode) {
  view_.copy = decode.copy;
  view_.paired = decode.paired;
  view_.axis_count = decode.axis_count;
  for (std::size_t i = 0; i < decode.axis_count; ++i) {
    AxisFrameView& axis = view_.axes[i];
    axis.placement = decode.axes[i];
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

void CycleRows::onFrame(std::uint64_t frame, std::int64_t time_ns, const FrameView& view,
                        std::vector<CycleRow>& out) {
  for (std::size_t i = 0; i < view.axis_count; ++i) {
    const AxisFrameView& axis = view.axes[i];
    const std::uint16_t index = axis.placement.axis;
    CycleRow row{frame, time_ns, index, axis.values, axis.state};
    auto it = pending_.find(index);
    if (view.copy == CopyKind::Master) {
      if (it != pending_.end()) {
        out.push_back(it->second);  // its returned copy was not captured
        it->second = row;
      } else {
        pending_.emplace(index, row);
      }
      continue;
    }
    if (it != pending_.end() && it->second.values.has_rx) {
      // The master's outputs are what the NC sent; the returned copy adds the inputs.
      for (const WordDef& word : kWords) {
        if (word.pdo == Pdo::Rx) {
          row.values.raw[static_cast<std::size_t>(word.word)] = it->second.values.word(word.word);
        }
      }
      row.values.has_rx = true;
      pending_.erase(it);
    }
    out.push_back(row);
  }
}

void CycleRows::finish(std::vector<CycleRow>& out) {
  for (const auto& [axis, row] : pending_) out.push_back(row);
  pending_.clear();
}

}  // namespace ncservo
