// A capture read frame by frame as `validate` and `decode` need it: walked (PROTOCOL.md §8),
// timed by the frame clock (the probe's or the PC's), held in the learning window until the layout
// is known (§9.4), then delivered in capture order — the window's frames first. Frames that are
// not EtherCAT, carry no datagrams or are a probe's bus faults are timed but not delivered.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>

#include "ncservo/capture_reader.hpp"
#include "ncservo/decoder.hpp"
#include "ncservo/error.hpp"
#include "ncservo/frame_clock.hpp"
#include "ncservo/layout_window.hpp"

namespace ncservo {

struct CaptureStream {
  // Called once, with the layout to decode with, before the first frame is delivered.
  std::function<void(const DecoderOptions& layout)> start;
  LayoutWindow::Sink frame;
};

struct CaptureRun {
  std::uint64_t records = 0;                  // read, of any kind
  std::optional<std::int64_t> first_time_ns;  // of the first record
};

// Reads to the end, or to the reader's error (everything before it is delivered); `start` is
// called even for a capture with no frame.
Status streamCapture(CaptureReader& reader, FrameClock& clock, LayoutWindow& window,
                     const CaptureStream& stream, CaptureRun& run);

}  // namespace ncservo
