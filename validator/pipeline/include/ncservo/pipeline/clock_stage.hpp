// The first step every walked frame takes in the pipeline (docs/timing.md#the-clock): duplicate
// records dropped, and each frame timed on the clock that judges the capture.
//
// The first cycles are held (their bytes copied, bounded) while the capture's stamps are judged
// (model/capture_clock.hpp); then they and every later frame go on in capture order:
// - on the capture's or the probe's clock, with the time they came with;
// - on the bus's clock, each cycle at the reference clock's system time its returned copy read:
//   a frame is held until the read that follows it; the master copies that asked for it take
//   the read's time (spread evenly when several came before one read), the frames between them
//   keep their stamps' offsets, never past the next; the returned copies have no latency of
//   their own;
// - counted in cycles, each cyclic frame's master copy one nominal cycle after the last.
// A duplicate is an exact copy of a record within one cycle (a mirror port, two capture points
// merged): the copy of the cyclic frame's last master copy before its returned copy came, of its
// last returned copy before the next master copy, or of another record since the cycle began.
// The capture is judged to have them when a tenth of its first cycles' copies do; then they are
// dropped before anything judges them, and counted.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/model/capture_clock.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "ncservo/wire/frame_clock.hpp"

namespace ncservo {

// What the capture held twice.
struct CaptureDuplicates {
  std::uint64_t count = 0;
  std::uint64_t first_frame = 0;  // 0: none
};

class ClockStage {
 public:
  // Which copy of the cyclic frame a frame is (None: not told apart, or none seen yet).
  enum class Copy : std::uint8_t { None, Master, Returned };
  // A frame on its way, timed.
  using Sink = std::function<void(std::uint64_t number, std::int64_t time_ns, LinkType link,
                                  const ByteReader& bytes, const EcatFrame& frame, bool judged)>;
  // A record dropped as a duplicate.
  using DropSink = std::function<void(std::uint64_t number)>;

  // Held while judging the stamps: at most this many frames, or bytes.
  static constexpr std::size_t kMaxHeldFrames = 16384;
  static constexpr std::size_t kMaxHeldBytes = 8u << 20;
  // On the bus's clock, frames held waiting for a read: more say the reads stopped, and the
  // oldest go on timed from the last read by their stamps.
  static constexpr std::size_t kMaxPending = 1024;

  explicit ClockStage(Sink sink, DropSink dropped = nullptr)
      : sink_(std::move(sink)), dropped_(std::move(dropped)) {}

  // One walked frame (status Ok, Truncated), at its capture (or probe) time. `probe_timed`: the
  // frame clock took the probe's timestamps.
  void onFrame(std::uint64_t number, std::int64_t time_ns, LinkType link, const ByteReader& bytes,
               const EcatFrame& frame, bool judged, bool probe_timed);
  // The capture ended: whatever is held goes on.
  void finish();

  // The first cycles are still held while the stamps are judged.
  bool assessing() const { return !choice_.has_value(); }
  // The clock chosen; a capture's before it was chosen.
  const ClockChoice& choice() const;
  const CaptureDuplicates& duplicates() const { return duplicates_; }
  // Frames the bus's clock could not time (its reads stopped), timed by their stamps instead.
  std::uint64_t untimed() const { return untimed_; }

 private:
  struct Held {
    std::uint64_t number;
    std::int64_t capture_ns;
    LinkType link;
    bool judged;
    bool duplicate;
    bool clock_master;                    // a master copy of the frame that reads the bus's clock
    std::optional<std::uint64_t> bus_ns;  // the read, unwrapped, of a returned copy
    std::vector<std::uint8_t> bytes;
  };
  // The datagram list that names a cyclic frame (command, address, length of each).
  struct FrameKey {
    std::vector<Datagram> datagrams;
    bool matches(const EcatFrame& frame) const;
  };

  bool isDuplicate(const EcatFrame& frame, const ByteReader& bytes);
  void hold(std::uint64_t number, std::int64_t time_ns, LinkType link, const ByteReader& bytes,
            const EcatFrame& frame, bool judged, bool duplicate);
  void decide();
  void pass(const Held& held, std::int64_t time_ns);
  void drop(std::uint64_t number);
  // On the bus's clock: the held frames up to a read at `time_ns`, or (none) by their stamps.
  void releasePending(std::optional<std::int64_t> read_time_ns, std::size_t count);
  // On the bus's clock: the frame just held, released with those before it when it read the time.
  void onBusHeld();
  std::int64_t cycleTime(std::int64_t capture_ns, const EcatFrame& frame);
  std::vector<std::uint8_t> spareBuffer();

  Sink sink_;
  DropSink dropped_;
  std::optional<ClockChoice> choice_;
  mutable std::optional<ClockChoice> capture_choice_;  // what choice() says before the choice

  // Judging the stamps: the first frame that may carry process data names the cyclic frame
  // whose master copies time the stamps; the first read of a system time names the reference
  // clock, whose reads time them better.
  std::optional<FrameKey> cyclic_key_;
  std::optional<SystemTimeRead> reference_;
  StampAssessor cyclic_stamps_, returned_stamps_;
  std::optional<std::uint64_t> read_for_master_, read_for_returned_;  // since the last sample
  SystemTimeUnwrapper unwrap_;
  std::deque<Held> held_;
  std::size_t held_bytes_ = 0;
  std::uint64_t copies_ = 0, duplicate_copies_ = 0;  // of the cyclic frame, in the first cycles
  bool drop_duplicates_ = true;                      // while judging: flagged, not dropped yet
  bool probe_timed_ = false;

  // Duplicates: the cyclic frame's last copy, and the other records since the cycle began.
  Copy last_copy_ = Copy::None;
  std::vector<std::uint8_t> last_copy_bytes_;
  std::vector<std::vector<std::uint8_t>> since_cycle_;
  std::size_t since_cycle_used_ = 0;
  CaptureDuplicates duplicates_;

  // The bus's clock: the first read anchors it to that frame's stamp.
  std::optional<std::uint64_t> bus_anchor_;
  std::int64_t time_anchor_ns_ = 0;
  std::int64_t last_read_time_ns_ = 0;     // the last read's time
  std::int64_t last_read_capture_ns_ = 0;  // ... and its frame's stamp
  bool read_seen_ = false;
  std::int64_t last_passed_ns_ = 0;  // frames go on in non-decreasing time
  std::uint64_t untimed_ = 0;

  // Cycles: the cycles since the cyclic frame's first copy, which anchors them to its stamp.
  std::uint64_t cycles_ = 0;
  std::int64_t cycles_anchor_ns_ = 0;
  Copy last_cycle_copy_ = Copy::None;

  std::vector<std::vector<std::uint8_t>> spare_;
};

}  // namespace ncservo
