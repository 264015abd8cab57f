// One capture's process data, frame by frame, for a caller that shows values rather than judges
// them (`decode`): layout and copy (Decoder), the PDO values in each frame, and each axis's latest
// values and drive state. The validator places and reads the frames itself (validator.hpp).
#pragma once

#include <array>
#include <map>
#include <optional>
#include <vector>

#include "ncservo/layout/decoder.hpp"
#include "ncservo/protocol/drive_state.hpp"
#include "ncservo/protocol/pdo.hpp"

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

// One axis in one cycle, as `decode` lists it: the outputs of the master's copy and the inputs of
// its returned copy (docs/protocol.md §8), at the frame that completed it.
struct CycleRow {
  std::uint64_t frame = 0;
  std::int64_t time_ns = 0;
  std::uint16_t axis = 0;
  PdoValues values;
  std::optional<DriveState> state;
};

// Pairs each axis's outputs in a master's copy with its inputs in the returned copy. A master's
// copy whose return was not captured, or a returned copy without a master's copy, is a row of
// its own. Holds at most one row per axis.
class CycleRows {
 public:
  // One frame's view; appends the rows it completes to `out`.
  void onFrame(std::uint64_t frame, std::int64_t time_ns, const FrameView& view,
               std::vector<CycleRow>& out);
  // The rows still waiting for a returned copy, at the end of a capture.
  void finish(std::vector<CycleRow>& out);

 private:
  std::map<std::uint16_t, CycleRow> pending_;  // outputs of a master's copy, by axis
};

class Session {
 public:
  explicit Session(DecoderOptions options) : decoder_(std::move(options)) {}

  // The frame must have been walked over `bytes`. The returned view lives until the next call.
  const FrameView& onFrame(const EcatFrame& frame, const ByteReader& bytes);
  // A frame another decoder placed and read already (the validator's observation): taken as it
  // is, neither placed nor read again; this session's decoder() then learns nothing of it.
  const FrameView& onDecoded(const FrameDecode& decode,
                             const std::array<PdoValues, kMaxAxesPerFrame>& values);

  // A frame outside the time window (capture_stream.hpp): only what it shows of the layout.
  void onLayoutOnlyFrame(const EcatFrame& frame, const ByteReader& bytes) {
    decoder_.placeAxes(frame, bytes, decode_);
  }
  const Decoder& decoder() const { return decoder_; }

 private:
  const FrameView& take(const FrameDecode& decode);

  Decoder decoder_;
  FrameDecode decode_;
  FrameView view_;
  std::vector<PdoValues> latest_;  // per axis index
};

}  // namespace ncservo
