// A capture read frame by frame as `validate` and `decode` need it: walked (docs/protocol.md §8),
// timed by the frame clock (the probe's or the PC's), held in the learning window until the layout
// is known (§9.4), then delivered in capture order — the window's frames first. Frames that are
// not EtherCAT, carry no datagrams or are a probe's bus faults are timed but not delivered.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "ncservo/base/error.hpp"
#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/layout/decoder.hpp"
#include "ncservo/layout/layout_window.hpp"
#include "ncservo/wire/frame_clock.hpp"

namespace ncservo {

// docs/cli.md `--from SECONDS --to SECONDS`: the frames whose time, in the capture's own
// seconds (since its first record, as Wireshark's frame.time_relative), lies in [from, to]. The
// frames outside are neither decoded for their values nor judged: the capture seen starts
// mid-operation at `from`. They still show the layout (a start-up before the window, the
// learning window's cyclic traffic): the stream gives them to `CaptureStream::layout_only`.
struct TimeWindow {
  std::optional<std::int64_t> from_ns, to_ns;
  bool contains(std::int64_t relative_ns) const {
    return (!from_ns || relative_ns >= *from_ns) && (!to_ns || relative_ns <= *to_ns);
  }
  bool limited() const { return from_ns || to_ns; }
};
// The window of `--from`/`--to` in seconds; fails when `to` is before `from` or either is not a
// finite number.
Result<TimeWindow> timeWindowOf(std::optional<double> from_s, std::optional<double> to_s);
// "--from 1.5 --to 2", "--from 1.5", for messages.
std::string describeTimeWindow(const TimeWindow& window);

struct CaptureStream {
  // Called once, with the layout to decode with, before the first frame is delivered.
  std::function<void(const DecoderOptions& layout)> start;
  LayoutWindow::Sink frame;
  TimeWindow window;
  LayoutWindow::Sink layout_only;  // frames outside the window (may be null)
};

struct CaptureRun {
  std::uint64_t records = 0;                  // read, of any kind
  std::optional<std::int64_t> first_time_ns;  // of the first record
  std::uint64_t in_window = 0;                // EtherCAT frames inside the time window
  std::uint64_t snapped = 0;                  // records cut by the capture's snap length
  std::uint64_t first_snapped = 0;            // the first of them (0: none)
};

// Records given one at a time, as a live capture delivers them: each walked, timed, held in the
// learning window or delivered. `streamCapture` feeds it a capture file.
class RecordStream {
 public:
  // `start` is called here already when the window is not learning.
  RecordStream(FrameClock& clock, LayoutWindow& window, const CaptureStream& stream,
               CaptureRun& run);
  void onRecord(LinkType link, const CaptureRecord& record);
  // The capture ended: a window still learning decides and delivers what it held; `start` is
  // called even for a capture with no frame.
  void finish();

 private:
  void decided();
  FrameClock& clock_;
  LayoutWindow& window_;
  const CaptureStream& stream_;
  CaptureRun& run_;
  EcatFrame frame_;
};

// Reads to the end, or to the reader's error (everything before it is delivered); `start` is
// called even for a capture with no frame.
Status streamCapture(CaptureReader& reader, FrameClock& clock, LayoutWindow& window,
                     const CaptureStream& stream, CaptureRun& run);

}  // namespace ncservo
