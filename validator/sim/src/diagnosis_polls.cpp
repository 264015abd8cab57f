#include "diagnosis_polls.hpp"

#include <algorithm>
#include <cmath>
#include <string_view>

#include "ncservo/wire/diagnosis_texts.hpp"
#include "ncservo/wire/ecat_wire.hpp"

namespace ncservo::sim {
namespace {

// The master reads the servos' mailboxes, and every slave's error counters and system time
// difference, this often (docs/simulate.md#diagnosis).
constexpr std::int64_t kMailboxPollNs = 2 * kMs;
constexpr std::int64_t kCountersPollNs = 100 * kMs;
// A frame of register datagrams holds at most this much (datagram headers and WKC included).
constexpr std::size_t kAcyclicFrameBytes = 1400;
constexpr std::size_t kDatagramOverhead = 12;

}  // namespace

DiagnosisPolls::DiagnosisPolls(const SimOptions& options, Segment& segment, Master& master,
                               FaultPlan& faults)
    : o_(options),
      cycle_ns_(static_cast<std::int64_t>(options.cycle_us) * kUs),
      segment_(segment),
      master_(master),
      faults_(faults),
      drive_mailboxes_(static_cast<std::size_t>(options.axes)),
      nc_mailboxes_(static_cast<std::size_t>(options.axes)),
      nc_saw_error_(static_cast<std::size_t>(options.axes), false),
      request_frame_(static_cast<std::size_t>(options.axes)),
      baseline_(segment.escs.size(), {false, false}) {
  master.configureMailboxes();
  segment.watchdogs = true;
  for (const BadLink& link : options.bad_links) {
    const auto position = static_cast<std::size_t>(link.station - kFirstStation);
    corruptFrames(static_cast<std::int64_t>(std::llround(link.at_s * 1e9)),
                  position + (link.port == 1 ? 1u : 0u), link.frames);
  }
}

void DiagnosisPolls::corruptFrames(std::int64_t at_ns, std::size_t into, int frames) {
  bursts_.push_back({at_ns, into, frames});
}

void DiagnosisPolls::beforeCycle(std::int64_t slot) {
  for (FaultPlan::TimedDiagnosis& d : faults_.diagnosisFaults()) {
    if (d.done || slot < d.at_ns) continue;
    const auto axis = static_cast<std::size_t>(d.axis);
    const auto position = static_cast<std::size_t>(segment_.servo_slave[axis]);
    switch (d.fault.kind) {
      case DiagnosisFault::Kind::Mailbox:
        drive_mailboxes_[axis].quirk(d.fault.quirk);
        break;
      case DiagnosisFault::Kind::NcRead:
        nc_mailboxes_[axis].upload(d.fault.index, d.fault.subindex);
        break;
      case DiagnosisFault::Kind::CorruptFrames:
        corruptFrames(slot, position, d.fault.amount);
        break;
      case DiagnosisFault::Kind::LinkDown:
        segment_.escs[position].countError(diag::EscCounter::LostLink, 0);
        if (position > 0) segment_.escs[position - 1].countError(diag::EscCounter::LostLink, 1);
        break;
      case DiagnosisFault::Kind::TimeDifference:
        continue;  // read by timeDifference while it stands
    }
    d.done = true;
  }
  for (LinkBurst& burst : bursts_) {
    if (burst.done || slot < burst.at_ns) continue;
    master_.corruptFrames(burst.into, burst.frames);
    burst.done = true;
  }
}

void DiagnosisPolls::watchInputs(const std::vector<std::optional<TxPdo>>& inputs) {
  for (std::size_t a = 0; a < inputs.size(); ++a) {
    if (!inputs[a]) continue;
    const bool error = (inputs[a]->sew & bits::kServoErrors) != 0;
    if (error && !nc_saw_error_[a]) nc_mailboxes_[a].faultSeen();
    nc_saw_error_[a] = error;
  }
}

bool DiagnosisPolls::between(const FrameSink& sink, std::uint64_t cycle, std::int64_t slot,
                             std::int64_t t_ns, std::int64_t deadline_ns) {
  auto every = [&](std::int64_t period_ns) {
    return static_cast<std::uint64_t>(std::max<std::int64_t>(1, period_ns / cycle_ns_));
  };
  // A poll not yet sent in full is not queued again: the queue stays bounded on any bus.
  if (cycle % every(kMailboxPollNs) == 0 && !queued(Poll::Mailbox)) queueMailboxPoll();
  const std::uint64_t counters = every(kCountersPollNs);
  if (cycle % counters == counters / 2 && !queued(Poll::Counters)) queueCounterPoll(cycle, slot);
  // Each frame only when its returned copy comes before the next cycle may be sent.
  while (!pending_.empty() && t_ns + master_.returnDelayNs() + kUs <= deadline_ns) {
    PendingFrame frame = std::move(pending_.front());
    pending_.pop_front();
    bool came_back = false;
    if (!master_.acyclic(sink, frame.datagrams, t_ns, came_back)) return false;
    t_ns = master_.lastFrameNs() + kUs;
    if (!came_back) continue;
    if (frame.poll == Poll::Mailbox) {
      mailboxReturned(frame.datagrams);
    } else {
      countersReturned(frame.datagrams);
    }
  }
  return true;
}

void DiagnosisPolls::queue(Poll poll, std::vector<RingDatagram>& datagrams) {
  std::size_t bytes = kAcyclicFrameBytes;  // a new frame for the first datagram
  for (RingDatagram& dg : datagrams) {
    if (bytes + dg.data.size() + kDatagramOverhead > kAcyclicFrameBytes) {
      pending_.push_back({poll, {}});
      bytes = 0;
    }
    bytes += dg.data.size() + kDatagramOverhead;
    pending_.back().datagrams.push_back(std::move(dg));
  }
}

bool DiagnosisPolls::queued(Poll poll) const {
  return std::any_of(pending_.begin(), pending_.end(),
                     [&](const PendingFrame& f) { return f.poll == poll; });
}

// The NC's requests written into the servos' SM0, every SM1 read.
void DiagnosisPolls::queueMailboxPoll() {
  std::vector<RingDatagram> datagrams;
  for (int a = 0; a < o_.axes; ++a) {
    const std::uint16_t station = segment_.servo(a).station();
    if (std::optional<std::vector<std::uint8_t>> request =
            nc_mailboxes_[static_cast<std::size_t>(a)].takeRequest()) {
      RingDatagram dg = registerDatagram(ecat::kFpwr, station, kMailboxOutPhys, kMailboxBytes);
      dg.data = std::move(*request);
      datagrams.push_back(std::move(dg));
    }
    datagrams.push_back(registerDatagram(ecat::kFprd, station, kMailboxInPhys, kMailboxBytes));
  }
  queue(Poll::Mailbox, datagrams);
}

// What came back of a mailbox poll is the truth of what the drives said.
void DiagnosisPolls::mailboxReturned(const std::vector<RingDatagram>& frame) {
  for (const RingDatagram& dg : frame) {
    if (dg.command != ecat::kFpwr || dg.wkc == 0) continue;
    // the request's frame is the master's copy, the one before the returned copy
    const auto s = static_cast<std::size_t>(dg.adp - kFirstStation);
    request_frame_[static_cast<std::size_t>(segment_.escs[s].axis)] = master_.frames() - 1;
  }
  for (int a = 0; a < o_.axes; ++a) {
    const auto axis = static_cast<std::size_t>(a);
    Esc& esc = segment_.servo(a);
    for (Esc::MailboxAnswer& taken : esc.mailbox_taken) {
      taken.said.frame = master_.frames();
      if (std::string_view(taken.said.kind) != "emergency") {
        taken.said.request_frame = request_frame_[axis];
      }
      nc_mailboxes_[axis].answered(taken.bytes);
      said_.drive_messages.push_back(taken.said);
    }
    esc.mailbox_taken.clear();
  }
}

// Every slave's error counters and system time difference.
void DiagnosisPolls::queueCounterPoll(std::uint64_t cycle, std::int64_t slot) {
  std::vector<RingDatagram> datagrams;
  for (std::size_t s = 0; s < segment_.escs.size(); ++s) {
    Esc& esc = segment_.escs[s];
    esc.setTimeDifference(timeDifference(s, cycle, slot));
    datagrams.push_back(registerDatagram(ecat::kFprd, esc.station(), ecat::kRegErrorCounters,
                                         ecat::kErrorCountersSize));
    datagrams.push_back(registerDatagram(ecat::kFprd, esc.station(), ecat::kRegSmWatchdogCounter,
                                         ecat::kWatchdogCountersSize));
    datagrams.push_back(
        registerDatagram(ecat::kFprd, esc.station(), ecat::kRegDcSystemTimeDifference, 4));
  }
  queue(Poll::Counters, datagrams);
}

// The rises each read shows since the slave's last read (its first is the baseline), and the
// links they name, are the truth.
void DiagnosisPolls::countersReturned(const std::vector<RingDatagram>& frame) {
  for (const RingDatagram& dg : frame) {
    const bool watchdogs = dg.ado == ecat::kRegSmWatchdogCounter;
    if ((dg.ado != ecat::kRegErrorCounters && !watchdogs) || dg.wkc == 0) continue;
    const auto s = static_cast<std::size_t>(dg.adp - kFirstStation);
    countersRead(segment_.escs[s], watchdogs, master_.frames());
  }
}

void DiagnosisPolls::countersRead(Esc& esc, bool watchdogs, std::uint64_t frame) {
  using diag::EscCounter;
  const auto s = static_cast<std::size_t>(esc.station() - kFirstStation);
  const bool baseline = !baseline_[s][watchdogs ? 1 : 0];
  baseline_[s][watchdogs ? 1 : 0] = true;
  for (std::size_t c = 0; c < esc.counted.size(); ++c) {
    const auto counter = static_cast<EscCounter>(c);
    const bool watchdog = counter == EscCounter::SmWatchdog || counter == EscCounter::PdiWatchdog;
    if (watchdog != watchdogs) continue;
    for (std::uint8_t port = 0; port < ecat::kEscPorts; ++port) {
      if (!baseline && esc.counted[c][port] > 0) {
        said_.esc_errors.push_back(
            {frame, esc.station(), port, diag::escCounterName(counter), esc.counted[c][port]});
      }
    }
    esc.counted[c].fill(0);
  }
  if (watchdogs) return;
  // The link is the cable the simulator corrupted the frames on, into this slave's port 0.
  if (!baseline && esc.corrupted_frames > 0) {
    said_.link_faults.push_back({frame, esc.station(), 0, esc.corrupted_frames});
  }
  esc.corrupted_frames = 0;
}

// A slave's system time difference at a read: within a few tens of ns of the reference, but
// where a fault (DC-001) puts it.
std::int32_t DiagnosisPolls::timeDifference(std::size_t slave, std::uint64_t cycle,
                                            std::int64_t slot) const {
  for (const FaultPlan::TimedDiagnosis& d : faults_.diagnosisFaults()) {
    if (d.fault.kind == DiagnosisFault::Kind::TimeDifference &&
        static_cast<std::size_t>(segment_.servo_slave[static_cast<std::size_t>(d.axis)]) == slave &&
        slot >= d.at_ns && slot < d.at_ns + d.fault.for_ns) {
      return d.fault.amount;
    }
  }
  const std::uint64_t x = (cycle * 0x9E3779B97F4A7C15ULL) ^ (slave * 0xBF58476D1CE4E5B9ULL);
  return static_cast<std::int32_t>((x >> 33) % 61) - 30;
}

}  // namespace ncservo::sim
