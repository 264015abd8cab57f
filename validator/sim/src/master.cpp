#include "master.hpp"

#include <algorithm>

#include "ncservo/base/little_endian.hpp"
#include "ncservo/protocol/pdo.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo::sim {
namespace {

constexpr MacAddress kBroadcastMac = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
constexpr MacAddress kMasterMac = {0x00, 0x1B, 0x21, 0x4E, 0x43, 0x01};
constexpr int kMaxPolls = 50;
constexpr std::size_t kAlStatusPoll = 6;  // AL status, reserved, AL status code
constexpr std::size_t kDcTimeSize = 8;
// Sync manager control: buffered, write with watchdog (outputs) or read (inputs).
constexpr std::uint8_t kSmOutputs = 0x64, kSmInputs = 0x20;

constexpr auto kInit = ecat::kAlInit;

Framing ethernetFraming(bool returned) {
  Framing framing;
  framing.destination = kBroadcastMac;
  framing.source = kMasterMac;
  if (returned) framing.source[0] |= ecat::kMacLocallyAdministered;
  framing.min_size = ecat::kEthernetMinFrame;
  return framing;
}

}  // namespace

void AlWalk::start(ecat::AlState state, std::size_t slaves, bool request) {
  target = static_cast<std::uint8_t>(state);
  need_request.assign(slaves, request);
  need_ack.assign(slaves, false);
  done.assign(slaves, false);
  ack_value.assign(slaves, 0);
  first_request.assign(slaves, 0);
  active = true;
}
bool AlWalk::finished() const {
  return std::all_of(done.begin(), done.end(), [](bool d) { return d; });
}

Master::Master(Segment& segment)
    : segment_(segment),
      // the ring's round trip: a few microseconds plus a quarter per slave
      return_delay_ns_((2 + static_cast<std::int64_t>(segment.escs.size()) / 4) * kUs),
      sent_(ethernetFraming(false)),
      returned_(ethernetFraming(true)),
      input_frames_(segment.servo_slave.size(), 0),
      images_(segment.groups.size()),
      cyclic_frames_(segment.groups.size()) {
  for (std::size_t g = 0; g < segment.groups.size(); ++g) {
    for (const ImageDatagram& dg : segment.groups[g].datagrams) {
      images_[g].emplace_back(dg.size, 0);
    }
  }
}

// --- frames on the wire ---

RingDatagram registerDatagram(std::uint8_t command, std::uint16_t adp, std::uint16_t ado,
                              std::size_t length) {
  RingDatagram dg;
  dg.command = command;
  dg.adp = adp;
  dg.ado = ado;
  dg.data.assign(length, 0);
  return dg;
}

bool Master::emit(const FrameSink& sink, const std::vector<RingDatagram>& frame, bool returned,
                  std::int64_t t_ns) {
  FrameEncoder encoder(returned ? returned_ : sent_, bytes_);
  DatagramFields fields;
  for (const RingDatagram& dg : frame) {
    fields.command = dg.command;
    fields.index = dg.index;
    fields.address = dg.logical();
    fields.wkc = dg.wkc;
    encoder.add(fields, dg.data.data(), dg.data.size());
  }
  encoder.finish();
  ++frames_;
  last_frame_ns_ = t_ns;
  return sink(SimFrame{kEpochNs + t_ns, bytes_.data(), bytes_.size(), returned});
}

bool Master::exchange(const FrameSink& sink, std::vector<RingDatagram>& frame, std::int64_t t_ns,
                      bool lost_before, bool lost_after, bool* came_back) {
  if (came_back != nullptr) *came_back = false;
  for (RingDatagram& dg : frame) dg.index = datagram_index_++;  // in the order sent
  if (!emit(sink, frame, false, t_ns)) return false;
  if (lost_before) return true;
  std::optional<std::size_t> corrupted;
  if (corrupt_frames_left_ > 0) {
    --corrupt_frames_left_;
    corrupted = corrupt_into_;
  }
  if (!segment_.pass(frame, kEpochNs + t_ns, corrupted) || lost_after) return true;
  if (came_back != nullptr) *came_back = true;
  return emit(sink, frame, true, t_ns + return_delay_ns_ + return_late_ns_);
}

// --- the start-up ---

bool Master::alFrame(const FrameSink& sink, AlWalk& walk, std::int64_t t_ns) {
  std::vector<RingDatagram> frame;
  const std::size_t n = segment_.escs.size();
  const bool acks =
      std::find(walk.need_ack.begin(), walk.need_ack.end(), true) != walk.need_ack.end();
  const bool requests = std::find(walk.need_request.begin(), walk.need_request.end(), true) !=
                        walk.need_request.end();
  for (std::size_t s = 0; s < n; ++s) {
    const auto station = static_cast<std::uint16_t>(kFirstStation + s);
    if (acks) {
      if (!walk.need_ack[s]) continue;
      RingDatagram dg = registerDatagram(ecat::kFpwr, station, ecat::kRegAlControl, 2);
      storeLe(dg.data.data(), walk.ack_value[s], 2);
      frame.push_back(std::move(dg));
      walk.need_ack[s] = false;
      walk.need_request[s] = true;
    } else if (requests) {
      if (!walk.need_request[s]) continue;
      RingDatagram dg = registerDatagram(ecat::kFpwr, station, ecat::kRegAlControl, 2);
      const std::uint8_t value = walk.first_request[s] != 0 ? walk.first_request[s] : walk.target;
      walk.first_request[s] = 0;
      storeLe(dg.data.data(), value, 2);
      frame.push_back(std::move(dg));
      walk.need_request[s] = false;
    } else if (!walk.done[s]) {
      frame.push_back(registerDatagram(ecat::kFprd, station, ecat::kRegAlStatus, kAlStatusPoll));
    }
  }
  const bool poll = !acks && !requests;
  if (!exchange(sink, frame, t_ns)) return false;
  if (poll) {
    for (const RingDatagram& dg : frame) {
      if (dg.wkc == 0) continue;
      const std::size_t s = static_cast<std::size_t>(dg.adp - kFirstStation);
      const std::uint8_t status = dg.data[0];
      if (status & ecat::kAlErrorBit) {
        walk.need_ack[s] = true;
        walk.ack_value[s] =
            static_cast<std::uint8_t>((status & ecat::kAlStateMask) | ecat::kAlErrorBit);
      } else if ((status & ecat::kAlStateMask) == walk.target) {
        walk.done[s] = true;
      }
    }
    if (walk.finished()) walk.active = false;
  }
  return true;
}

bool Master::mailboxFrame(const FrameSink& sink, std::int64_t t_ns) {
  std::vector<RingDatagram> frame;
  for (std::size_t s = 0; s < segment_.escs.size(); ++s) {
    if (!segment_.escs[s].servo()) continue;
    RingDatagram dg = registerDatagram(ecat::kFpwr, static_cast<std::uint16_t>(kFirstStation + s),
                                       ecat::kRegSyncManager0, kMailboxSyncManagers);
    writeMailboxSyncManagers(dg.data.data());
    frame.push_back(std::move(dg));
  }
  return frame.empty() || exchange(sink, frame, t_ns);
}

bool Master::configFrame(const FrameSink& sink, bool sync_managers, std::int64_t t_ns) {
  std::vector<RingDatagram> frame;
  for (std::size_t s = 0; s < segment_.escs.size(); ++s) {
    const Esc& esc = segment_.escs[s];
    const auto station = static_cast<std::uint16_t>(kFirstStation + s);
    struct Entry {
      std::uint8_t sm;
      std::uint16_t phys;
      std::size_t length;
      std::uint32_t logical;
      bool outputs;
    };
    std::vector<Entry> entries;
    if (esc.outputBytes() > 0) {
      entries.push_back({esc.model->output_sm, esc.outputsPhysical(), esc.outputBytes(),
                         esc.outputs_logical, true});
    }
    if (esc.inputBytes() > 0) {
      entries.push_back(
          {esc.model->input_sm, esc.inputsPhysical(), esc.inputBytes(), esc.inputs_logical, false});
    }
    if (entries.empty()) continue;
    if (sync_managers) {
      // One write over the sync managers the slave uses (SM2 and SM3 of a servo, SM0 of a
      // digital terminal).
      const std::uint8_t first = std::min(entries.front().sm, entries.back().sm);
      const std::uint8_t last = std::max(entries.front().sm, entries.back().sm);
      const auto slots = static_cast<std::size_t>(last - first + 1);
      RingDatagram dg = registerDatagram(
          ecat::kFpwr, station,
          static_cast<std::uint16_t>(ecat::kRegSyncManager0 + first * ecat::kSyncManagerStride),
          slots * ecat::kSyncManagerStride);
      for (std::size_t e = 0; e < entries.size(); ++e) {
        std::uint8_t* sm = &dg.data[(entries[e].sm - first) * ecat::kSyncManagerStride];
        storeLe(sm + ecat::kSmStartAt, entries[e].phys, 2);
        storeLe(sm + ecat::kSmLengthAt, entries[e].length, 2);
        sm[ecat::kSmControlAt] = entries[e].outputs ? kSmOutputs : kSmInputs;
        sm[ecat::kSmActivateAt] = 0x01;
      }
      frame.push_back(std::move(dg));
    } else {
      RingDatagram dg = registerDatagram(ecat::kFpwr, station, ecat::kRegFmmu0,
                                         entries.size() * ecat::kFmmuStride);
      for (std::size_t e = 0; e < entries.size(); ++e) {
        std::uint8_t* fmmu = &dg.data[e * ecat::kFmmuStride];
        storeLe(fmmu + ecat::kFmmuLogicalAt, entries[e].logical, 4);
        storeLe(fmmu + ecat::kFmmuLengthAt, entries[e].length, 2);
        fmmu[ecat::kFmmuStartBitAt] = 0;
        fmmu[ecat::kFmmuStopBitAt] = 7;
        storeLe(fmmu + ecat::kFmmuPhysicalAt, entries[e].phys, 2);
        fmmu[ecat::kFmmuPhysicalStartBitAt] = 0;
        fmmu[ecat::kFmmuTypeAt] = entries[e].outputs ? ecat::kFmmuWrite : ecat::kFmmuRead;
        fmmu[ecat::kFmmuActivateAt] = 1;
      }
      frame.push_back(std::move(dg));
    }
  }
  return exchange(sink, frame, t_ns);
}

bool Master::startup(const FrameSink& sink, std::int64_t& t, std::int64_t step_ns,
                     std::optional<std::size_t> op_request_slave) {
  const std::size_t n = segment_.escs.size();
  auto next = [&] { t += step_ns; };
  // 1. count the slaves
  std::vector<RingDatagram> frame{registerDatagram(ecat::kBrd, 0, ecat::kRegType, 2)};
  if (!exchange(sink, frame, t)) return false;
  next();
  // 2. station addresses by ring position
  frame.clear();
  for (std::size_t s = 0; s < n; ++s) {
    RingDatagram dg = registerDatagram(
        ecat::kApwr, static_cast<std::uint16_t>(-static_cast<int>(s)), ecat::kRegStationAddress, 2);
    storeLe(dg.data.data(), kFirstStation + s, 2);
    frame.push_back(std::move(dg));
  }
  if (!exchange(sink, frame, t)) return false;
  next();
  // 3. read each slave's state, 4. INIT with error acknowledge to all, then wait for INIT
  AlWalk walk;
  walk.start(ecat::kAlInit, n, false);
  if (!alFrame(sink, walk, t)) return false;
  next();
  frame.clear();
  RingDatagram reset = registerDatagram(ecat::kBwr, 0, ecat::kRegAlControl, 2);
  storeLe(reset.data.data(), kInit | ecat::kAlErrorBit, 2);
  frame.push_back(std::move(reset));
  if (!exchange(sink, frame, t)) return false;
  next();
  walk.start(ecat::kAlInit, n, false);
  for (int polls = 0; walk.active && polls < kMaxPolls; ++polls, next()) {
    if (!alFrame(sink, walk, t)) return false;
  }
  // the mailboxes, in INIT (a slave answers its mailbox from PRE-OP on)
  if (mailboxes_) {
    if (!mailboxFrame(sink, t)) return false;
    next();
  }
  // 5. PRE-OP, 6. sync managers and FMMUs, 7. SAFE-OP
  walk.start(ecat::kAlPreOp, n, true);
  for (int polls = 0; walk.active && polls < kMaxPolls; ++polls, next()) {
    if (!alFrame(sink, walk, t)) return false;
  }
  if (!configFrame(sink, true, t)) return false;
  next();
  if (!configFrame(sink, false, t)) return false;
  next();
  walk.start(ecat::kAlSafeOp, n, true);
  if (op_request_slave) walk.first_request[*op_request_slave] = ecat::kAlOp;
  for (int polls = 0; walk.active && polls < kMaxPolls; ++polls, next()) {
    if (!alFrame(sink, walk, t)) return false;
  }
  return true;
}

// --- the cycle ---

bool Master::cycle(const FrameSink& sink, std::int64_t t_ns, std::uint64_t cycle,
                   const std::vector<RxPdo>& outputs, bool lost_before, bool lost_after,
                   std::vector<std::optional<TxPdo>>& inputs) {
  last_cycle_returned_ = true;
  std::size_t last_sent = 0;  // the cycle's last frame (a slower task's frame is not in every one)
  for (std::size_t g = 0; g < segment_.groups.size(); ++g) {
    if (cycle % segment_.groups[g].every_cycles == 0) last_sent = g;
  }
  for (std::size_t g = 0; g < segment_.groups.size(); ++g) {
    const FrameGroup& fg = segment_.groups[g];
    if (cycle % fg.every_cycles != 0) continue;
    std::vector<std::vector<std::uint8_t>>& images = images_[g];  // per datagram
    // the NC's outputs, and the terminals', into the master's image
    for (int pos : fg.slaves) {
      const Esc& esc = segment_.escs[static_cast<std::size_t>(pos)];
      if (esc.outputBytes() == 0) continue;
      const std::optional<ImagePlace> at = fg.place(esc.outputs_logical);
      if (!at) continue;
      std::uint8_t* out = &images[at->datagram][at->offset];
      if (esc.servo()) {
        encodeRx(outputs[static_cast<std::size_t>(esc.axis)], out);
      } else {
        writeTerminalOutputs(*esc.model, cycle, out);
      }
    }
    // The same datagrams every cycle, refilled in place; the first frame also carries the DC
    // time (and, in the TwinCAT style, the AL status of all slaves).
    std::vector<RingDatagram>& frame = cyclic_frames_[g];
    const std::size_t extra = g == 0 ? (segment_.status_poll ? 2 : 1) : 0;
    frame.resize(fg.datagrams.size() + extra);
    for (std::size_t d = 0; d < fg.datagrams.size(); ++d) {
      RingDatagram& dg = frame[d];
      dg.command = fg.datagrams[d].command;
      dg.adp = static_cast<std::uint16_t>(fg.datagrams[d].logical & 0xFFFF);
      dg.ado = static_cast<std::uint16_t>(fg.datagrams[d].logical >> 16);
      dg.data.assign(images[d].begin(), images[d].end());
      dg.wkc = 0;
    }
    if (g == 0) {
      RingDatagram& dc = frame[fg.datagrams.size()];
      dc.command = ecat::kFrmw;
      dc.adp = kFirstStation;
      dc.ado = ecat::kRegDcSystemTime;
      dc.data.assign(kDcTimeSize, 0);
      dc.wkc = 0;
      if (segment_.status_poll) {
        RingDatagram& status = frame[fg.datagrams.size() + 1];
        status.command = ecat::kBrd;
        status.adp = 0;
        status.ado = ecat::kRegAlStatus;
        status.data.assign(2, 0);
        status.wkc = 0;
      }
    }
    const std::int64_t at_ns = t_ns + static_cast<std::int64_t>(g) * 2 * return_delay_ns_;
    bool came_back = false;
    if (g == last_sent) return_late_ns_ = std::exchange(next_return_late_ns_, 0);
    const bool exchanged = exchange(sink, frame, at_ns, lost_before, lost_after, &came_back);
    return_late_ns_ = 0;
    if (!exchanged) return false;
    if (!came_back) {
      last_cycle_returned_ = false;
      continue;
    }
    for (std::size_t d = 0; d < fg.datagrams.size(); ++d) {
      // the inputs the slaves wrote
      if (frame[d].wkc > 0) images[d].assign(frame[d].data.begin(), frame[d].data.end());
    }
    for (int pos : fg.slaves) {
      const Esc& esc = segment_.escs[static_cast<std::size_t>(pos)];
      if (!esc.servo()) continue;
      const std::optional<ImagePlace> at = fg.place(esc.inputs_logical);
      if (!at || frame[at->datagram].wkc == 0) continue;
      const std::vector<std::uint8_t>& image = images[at->datagram];
      PdoValues values;
      readPdoOf<Pdo::Tx>(ByteReader(image.data(), image.size()), at->offset, values);
      inputs[static_cast<std::size_t>(esc.axis)] = txPdoOf(values);
      input_frames_[static_cast<std::size_t>(esc.axis)] = frames_;
    }
  }
  return true;
}

}  // namespace ncservo::sim
