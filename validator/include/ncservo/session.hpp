// One capture's process data, frame by frame: layout and copy (Decoder), the PDO values in each
// frame, and each axis's latest values and drive state. Shared by the CLI and the plugin.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "ncservo/decoder.hpp"
#include "ncservo/drive_state.hpp"
#include "ncservo/pdo.hpp"

namespace ncservo {

struct AxisFrameView {
  AxisPlacement placement;
  PdoValues values;                 // only what this frame carries
  std::optional<DriveState> state;  // from this frame's values and the axis's latest ones
};

// The values one frame carries for one axis at its placement; the words of a PDO the frame does
// not carry (or that is cut short) are zero and marked absent.
inline void readFrameValues(const AxisPlacement& placement, const ByteReader& bytes,
                            PdoValues& out) {
  if (!placement.has_rx || !readPdoOf<Pdo::Rx>(bytes, placement.rx_offset, out)) {
    clearPdoOf<Pdo::Rx>(out);
  }
  if (!placement.has_tx || !readPdoOf<Pdo::Tx>(bytes, placement.tx_offset, out)) {
    clearPdoOf<Pdo::Tx>(out);
  }
}

struct FrameView {
  CopyKind copy = CopyKind::Master;
  bool paired = false;  // a returned copy whose master's copy was the frame just before
  std::size_t axis_count = 0;
  std::array<AxisFrameView, kMaxAxesPerFrame> axes{};
};

class Session {
 public:
  explicit Session(DecoderOptions options) : decoder_(std::move(options)) {}

  // The frame must have been walked over `bytes`. The returned view lives until the next call.
  const FrameView& onFrame(const EcatFrame& frame, const ByteReader& bytes);

  const Decoder& decoder() const { return decoder_; }
  // A caller with its own model of each axis (the validator) keeps the states itself.
  void trackStates(bool on) { track_states_ = on; }
  void setState(std::size_t i, std::optional<DriveState> state) { view_.axes[i].state = state; }

 private:
  Decoder decoder_;
  FrameDecode decode_;
  FrameView view_;
  std::vector<PdoValues> latest_;  // per axis index
  bool track_states_ = true;
};

}  // namespace ncservo
