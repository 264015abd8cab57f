// What `simulate --diagnosis` adds to a run (docs/simulate.md#diagnosis): each drive's mailbox
// and its NC's reads of it, the master's polls of the mailboxes, error counters and system time
// differences between the cycles, the bad links and the diagnosis faults of the rules' recipes,
// and the truth of everything said.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "drive_mailbox.hpp"
#include "fault_plan.hpp"
#include "master.hpp"
#include "ncservo/sim/diagnosis_truth.hpp"
#include "ncservo/sim/models.hpp"
#include "ncservo/sim/options.hpp"
#include "segment.hpp"

namespace ncservo::sim {

class DiagnosisPolls {
 public:
  DiagnosisPolls(const SimOptions& options, Segment& segment, Master& master, FaultPlan& faults);

  // From `at_ns` on, the next `frames` frames reach ring position `into` corrupted.
  void corruptFrames(std::int64_t at_ns, std::size_t into, int frames);
  // Before a cycle's frames: the diagnosis faults and bad links due.
  void beforeCycle(std::int64_t slot);
  // After the axis's drive stepped: its mailbox (the emergencies, the answers to requests).
  void stepDrive(int axis, std::uint32_t sew, Esc& esc) {
    drive_mailboxes_[static_cast<std::size_t>(axis)].step(sew, esc);
  }
  // After a cycle: the NC reads a drive's diagnosis objects after each fault its inputs show.
  void watchInputs(const std::vector<std::optional<TxPdo>>& inputs);
  // Between two cycles, from `t_ns` until the next cycle may be sent (`deadline_ns`): the polls
  // due queued, and as many queued frames sent as fit. False if the sink stopped.
  bool between(const FrameSink& sink, std::uint64_t cycle, std::int64_t slot, std::int64_t t_ns,
               std::int64_t deadline_ns);

  const DiagnosisTruth& truth() const { return said_; }

 private:
  enum class Poll : std::uint8_t { Mailbox, Counters };
  struct PendingFrame {
    Poll poll;
    std::vector<RingDatagram> datagrams;
  };
  struct LinkBurst {
    std::int64_t at_ns;
    std::size_t into;  // the ring position whose port 0 receives the corrupted frames
    int frames;
    bool done = false;
  };

  // The datagrams in as few frames as they fit in, queued.
  void queue(Poll poll, std::vector<RingDatagram>& datagrams);
  bool queued(Poll poll) const;
  void queueMailboxPoll();
  void queueCounterPoll(std::uint64_t cycle, std::int64_t slot);
  void mailboxReturned(const std::vector<RingDatagram>& frame);
  void countersReturned(const std::vector<RingDatagram>& frame);
  // What the counters a read covers rose by since the slave's last read of them.
  void countersRead(Esc& esc, bool watchdogs, std::uint64_t frame);
  std::int32_t timeDifference(std::size_t slave, std::uint64_t cycle, std::int64_t slot) const;

  const SimOptions& o_;
  std::int64_t cycle_ns_;
  Segment& segment_;
  Master& master_;
  FaultPlan& faults_;
  std::vector<DriveMailbox> drive_mailboxes_;                // per axis
  std::vector<NcMailbox> nc_mailboxes_;                      // per axis
  std::vector<bool> nc_saw_error_;                           // per axis
  std::vector<std::optional<std::uint64_t>> request_frame_;  // per axis: the open request's
  std::vector<std::array<bool, 2>> baseline_;  // per slave: each block's first read was seen
  std::vector<LinkBurst> bursts_;
  std::deque<PendingFrame> pending_;  // at most one poll of each kind
  DiagnosisTruth said_;
};

}  // namespace ncservo::sim
