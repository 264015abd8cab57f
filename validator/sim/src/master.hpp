// The simulated EtherCAT master (docs/protocol.md §8): its start-up — counts the slaves, assigns
// station addresses, walks every slave INIT -> PRE-OP -> SAFE-OP -> OP with AL status polls,
// configures the sync managers and FMMUs — and its cycle: the process data in the datagrams of
// each frame group (segment.hpp), the first frame with a DC FRMW to 0x0910. Each frame is captured
// twice: the master's copy and the copy the ring returns.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "ncservo/sim/frame_encoder.hpp"
#include "ncservo/sim/models.hpp"
#include "ncservo/sim/options.hpp"
#include "segment.hpp"

namespace ncservo::sim {

// The master's walk of every slave to one AL state, with acknowledgement of refusals.
struct AlWalk {
  std::uint8_t target = 0;
  std::vector<bool> need_request, need_ack, done;
  std::vector<std::uint8_t> ack_value;
  std::vector<std::uint8_t> first_request;  // ESM-001: what the first request asks for
  bool active = false;

  void start(ecat::AlState state, std::size_t slaves, bool request);
  bool finished() const;
};

// A datagram of the master's register access, its data zeroed; numbered when its frame is sent.
RingDatagram registerDatagram(std::uint8_t command, std::uint16_t adp, std::uint16_t ado,
                              std::size_t length);

class Master {
 public:
  explicit Master(Segment& segment);
  // The returned copy this long after its master copy, instead of the ring's own delay.
  void setReturnDelayNs(std::int64_t ns) { return_delay_ns_ = ns; }
  std::int64_t returnDelayNs() const { return return_delay_ns_; }
  // The next cycle's last frame comes back this much later than the ring's delay (COM-007); its
  // returned copy is the cycle's last, so the capture stays in time order.
  void delayNextReturnNs(std::int64_t ns) { next_return_late_ns_ = ns; }

  // The start-up from time `t` in steps of `step_ns`; `t` ends after it. `op_request_slave`: the
  // slave whose first SAFE-OP request asks for OP (ESM-001). False if the sink stopped.
  bool startup(const FrameSink& sink, std::int64_t& t, std::int64_t step_ns,
               std::optional<std::size_t> op_request_slave);
  // One cycle's frames: the NC's outputs per axis in, the inputs that came back per axis out.
  // `lost_before`: no slave sees the frames; `lost_after`: their returned copies are lost.
  bool cycle(const FrameSink& sink, std::int64_t t_ns, std::uint64_t cycle,
             const std::vector<RxPdo>& outputs, bool lost_before, bool lost_after,
             std::vector<std::optional<TxPdo>>& inputs);
  // One step of an AL walk: acknowledgements, requests, or a poll of the AL status.
  bool alFrame(const FrameSink& sink, AlWalk& walk, std::int64_t t_ns);

  // The start-up configures each servo's SM0 and SM1 as its mailbox (docs/simulate.md#diagnosis).
  void configureMailboxes() { mailboxes_ = true; }
  // A bad link: the next `frames` frames reach the slave at ring position `into` corrupted
  // (Segment::pass) and do not come back.
  void corruptFrames(std::size_t into, int frames) {
    corrupt_into_ = into;
    corrupt_frames_left_ = frames;
  }
  // Whether every frame of the last cycle came back.
  bool lastCycleReturned() const { return last_cycle_returned_; }
  // A frame of register datagrams between the cycles (the mailbox, the diagnosis polls); its
  // datagrams then hold what the slaves answered, when `came_back`. False if the sink stopped.
  bool acyclic(const FrameSink& sink, std::vector<RingDatagram>& frame, std::int64_t t_ns,
               bool& came_back) {
    return exchange(sink, frame, t_ns, false, false, &came_back);
  }

  std::uint64_t frames() const { return frames_; }
  // The time of the last frame captured, since the capture's start.
  std::int64_t lastFrameNs() const { return last_frame_ns_; }
  // The number (from 1) of the returned frame the axis's inputs last came in.
  std::uint64_t inputFrame(int axis) const { return input_frames_[static_cast<std::size_t>(axis)]; }

 private:
  bool mailboxFrame(const FrameSink& sink, std::int64_t t_ns);
  bool configFrame(const FrameSink& sink, bool sync_managers, std::int64_t t_ns);
  // Sends a frame round the ring, its datagrams numbered in turn, and captures both copies.
  // `came_back` (when given) says whether the returned copy reached the master.
  bool exchange(const FrameSink& sink, std::vector<RingDatagram>& frame, std::int64_t t_ns,
                bool lost_before = false, bool lost_after = false, bool* came_back = nullptr);
  bool emit(const FrameSink& sink, const std::vector<RingDatagram>& frame, bool returned,
            std::int64_t t_ns);

  Segment& segment_;
  std::int64_t return_delay_ns_;
  std::int64_t next_return_late_ns_ = 0;
  std::int64_t return_late_ns_ = 0;  // this exchange's
  Framing sent_;                     // the master's copy
  Framing returned_;  // the returned copy: the source MAC marked locally administered
  std::uint8_t datagram_index_ = 0;
  std::vector<std::uint8_t> bytes_;
  std::uint64_t frames_ = 0;
  std::int64_t last_frame_ns_ = 0;
  bool mailboxes_ = false;
  std::size_t corrupt_into_ = 0;
  int corrupt_frames_left_ = 0;
  bool last_cycle_returned_ = true;
  std::vector<std::uint64_t> input_frames_;  // per axis
  // Per frame group, reused every cycle: a long run allocates nothing.
  std::vector<std::vector<std::vector<std::uint8_t>>> images_;  // per datagram of each group
  std::vector<std::vector<RingDatagram>> cyclic_frames_;
};

}  // namespace ncservo::sim
