// The learning window of docs/protocol.md §9.4: with no configuration or ENI, the first frames of a
// capture are held back (their bytes copied, bounded) while the layout is inferred from them; once
// it is decided — or the start-up shows the layout, or the window ends — the held frames are
// replayed to whoever validates or decodes, so no finding in the window is lost, and the capture
// goes on streaming. When the first window cannot decide, the window keeps looking: the evidence
// is gathered again over each following stretch of the capture, and only the latest frames are
// held (two generations of half the limits each); the older ones are forgotten, not judged, and
// counted. With an explicit layout, or inference off, nothing is held.
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
  // When the first window cannot decide, keep looking over the rest of the capture.
  bool keep_looking = true;
};

// What keeping looking cost: the frames forgotten before the layout was certain, never judged.
struct LateLayout {
  std::uint64_t unjudged_frames = 0;  // walked frames forgotten
  std::uint64_t first_unjudged = 0;   // their first and last frame numbers (0: none)
  std::uint64_t last_unjudged = 0;
  std::uint64_t certain_at = 0;  // the frame where the layout became certain (0: first window)
  std::uint32_t windows = 1;     // windows of evidence looked at
  std::uint64_t cycles = 0;      // cycles of evidence over all of them
  bool any() const { return certain_at > 0 || windows > 1; }
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
  // Whether, and how long, the window went on looking after the first window.
  const LateLayout& late() const { return late_; }

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
  // Frames held, with copies of their bytes.
  struct Generation {
    std::vector<Held> held;
    std::vector<std::uint8_t> bytes;
  };
  bool firstWindowFull(std::int64_t time_ns) const;
  void keep(std::uint64_t frame_number, std::int64_t time_ns, LinkType link,
            const ByteReader& bytes, bool judged);
  void forgetOlder();
  void endOfWindow(std::uint64_t frame_number, bool capture_ended);
  void adopt(InferenceResult result);

  DecoderOptions options_;
  WindowLimits limits_;
  bool learning_ = false;
  std::unique_ptr<Decoder> probe_;  // copies and the start-up, as the validator will see them
  std::unique_ptr<FrameDecode> decode_;
  std::unique_ptr<LayoutInference> inference_;
  std::optional<InferenceResult> result_;
  bool looking_further_ = false;  // the first window could not decide
  std::optional<InferenceResult> last_refusal_;
  std::optional<InferenceResult> best_partial_;  // axes found, some status words unexplained
  std::uint32_t windows_without_new_axes_ = 0;
  std::uint64_t last_number_ = 0;
  LateLayout late_;
  Generation older_;
  Generation newer_;
  std::optional<std::int64_t> first_time_ns_;
};

}  // namespace ncservo
