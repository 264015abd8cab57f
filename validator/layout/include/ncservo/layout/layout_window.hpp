// The learning window of docs/protocol.md §9.4: with no configuration or ENI, the first frames of a
// capture are held back (their bytes copied, bounded) while the layout is inferred from them; once
// it is decided — or the start-up shows the layout, or the window ends — the held frames are
// replayed to whoever validates or decodes, so no finding in the window is lost, and the capture
// goes on streaming. With an explicit layout, or inference off, nothing is held.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/layout/decoder.hpp"
#include "ncservo/layout/layout_inference.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo {

struct WindowLimits {
  InferenceLimits inference;
  std::size_t max_frames = 32768;
  std::size_t max_bytes = 8u << 20;  // copies of the held frames
  std::int64_t max_ns = 10'000'000'000;
};

class LayoutWindow {
 public:
  explicit LayoutWindow(DecoderOptions options, WindowLimits limits = {});
  ~LayoutWindow();

  // Frames are still being held back: give the next one to hold().
  bool learning() const { return learning_; }
  // A walked frame (any status but NotEtherCat, NotDatagrams and BusFault) with its 1-based
  // number and capture time; its bytes are copied. `judged`: inside the time window (replayed to
  // the judging sink, else to the layout-only one).
  void hold(std::uint64_t frame_number, std::int64_t time_ns, LinkType link,
            const ByteReader& bytes, const EcatFrame& frame, bool judged = true);
  // The capture ended while learning: decide with what was seen.
  void finish();
  // The layout to decode with, once no longer learning.
  const DecoderOptions& options() const { return options_; }
  // What the inference decided, when it ran.
  const std::optional<InferenceResult>& inference() const { return result_; }

  using Sink = std::function<void(std::uint64_t frame_number, std::int64_t time_ns,
                                  const EcatFrame& frame, const ByteReader& bytes)>;
  // The held frames, walked again, in capture order (those outside the time window to
  // `outside`, when given); then forgets them.
  void replay(const Sink& sink, const Sink& outside = nullptr);

 private:
  struct Held {
    std::uint64_t number;
    std::int64_t time_ns;
    LinkType link;
    std::size_t offset;
    std::size_t size;
    bool judged;
  };
  void decide();

  DecoderOptions options_;
  WindowLimits limits_;
  bool learning_ = false;
  std::unique_ptr<Decoder> probe_;  // copies and the start-up, as the validator will see them
  std::unique_ptr<FrameDecode> decode_;
  std::unique_ptr<LayoutInference> inference_;
  std::optional<InferenceResult> result_;
  std::vector<Held> held_;
  std::vector<std::uint8_t> bytes_;
  std::optional<std::int64_t> first_time_ns_;
};

}  // namespace ncservo
