// The ESCs' own error counters as the master reads them (PROTOCOL.md §11, docs/drive-messages.md):
// every read of 0x0300-0x0313 of one slave gives, per port, how much each counter rose since
// its last read (invalid frames, RX errors, forwarded RX errors, lost links; processing-unit and
// PDI errors per slave), and a read of 0x0442-0x0443 how often its watchdogs expired. The first
// read of a slave is its baseline (what it counted before the capture has no time); a counter lower
// than before was cleared (a write, or the slave's reset) and rose by its new value; a write to the
// registers clears them. A BRD gives the sum over every slave and names none: its deltas are kept
// apart (`broadcast`).
//
// Localisation (Beckhoff's interpretation of the counters): an RX or invalid-frame error at a port
// that no upstream slave forwarded (the forwarded counter did not rise as much) is a fault of the
// physical link arriving at that port (the slaves downstream count its errors as forwarded): for
// port 0 the cable from the slave before it in the ring (its port 1), for port 1 the cable to the
// one after it (its port 0). Each such port of the slaves a frame read names its link, in
// processing order (ring position, else the order read). Bounded: kMaxListed deltas and faults
// listed, the rest counted.
#pragma once

#include <array>
#include <bitset>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/model/bus_events.hpp"
#include "ncservo/wire/diagnosis_texts.hpp"
#include "ncservo/wire/ecat_wire.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "ncservo/wire/slave_directory.hpp"

namespace ncservo {

// One counter's rise (JSON `esc_errors`).
struct EscErrorDelta {
  SlaveRef slave;
  bool broadcast = false;  // a BRD: the sum over all slaves
  std::uint8_t port = 0;   // 0 for the per-slave counters (processing, PDI)
  diag::EscCounter counter = diag::EscCounter::Rx;
  std::uint32_t delta = 0;
  std::uint64_t frame = 0;
};

// "the link between station 0x03EA port 1 and station 0x03EB port 0"
std::string linkFaultText(const LinkFault& fault);

class EscErrorTracker {
 public:
  static constexpr std::size_t kMaxListed = 10'000;

  // Every walked frame (Ok or Truncated) in capture order, `addressing.beginFrame` called for it.
  // LNK-001/LNK-002 events are appended to `out`.
  void onFrame(const EcatFrame& frame, const ByteReader& bytes, const FrameAddressing& addressing,
               const Stamp& now, std::vector<BusEvent>& out);

  // A frame with no register command: no counter read in it.
  void quietFrame() {
    if (!frame_deltas_.empty()) frame_deltas_.clear();
    if (!frame_faults_.empty()) frame_faults_.clear();
    if (!frame_events_.empty()) frame_events_.clear();
  }

  const std::vector<EscErrorDelta>& deltas() const { return deltas_; }
  const std::vector<LinkFault>& linkFaults() const { return faults_; }
  std::uint64_t omitted() const { return omitted_; }
  // The last frame's (the plugin's fields).
  const std::vector<EscErrorDelta>& frameDeltas() const { return frame_deltas_; }
  const std::vector<LinkFault>& frameLinkFaults() const { return frame_faults_; }
  // The last frame's rises of RX and lost-link counters, as LNK-001/LNK-002 judge them (the
  // incident cause link-fault, docs/incidents.md#link-fault).
  const std::vector<LinkErrorEvent>& frameLinkEvents() const { return frame_events_; }
  std::uint64_t reads() const { return reads_; }
  std::uint64_t broadcastReads() const { return broadcast_reads_; }

 private:
  // 0x0300-0x0313, then 0x0442-0x0443
  static constexpr std::size_t kCounters = ecat::kErrorCountersSize + ecat::kWatchdogCountersSize;
  struct Counters {
    std::array<std::uint8_t, kCounters> value{};
    std::bitset<kCounters> known;
    Stamp last_read;
    void absorb(const Counters& other);
  };
  struct Read {  // one slave's rises in this frame
    std::size_t slave = 0;
    std::uint32_t order = 0;  // processing order: ring position, else the order read
    std::array<std::uint32_t, kCounters> delta{};
    Stamp since;
  };
  // Rises of the counters the datagram read, into `read`; whether any was known before.
  bool take(Counters& counters, const Datagram& dg, const ByteReader& bytes, Read& read);
  void clear(Counters& counters, const Datagram& dg);
  // This frame's reads: the links their unforwarded RX errors name.
  void localise(const Stamp& now, std::vector<BusEvent>& out);
  void list(const EscErrorDelta& delta);
  SlaveRef refOf(std::size_t slave) const;
  // The link at a slave's port, its neighbour named where the ring order says who it is.
  LinkFault linkAt(std::size_t slave, std::uint8_t port) const;

  SlaveDirectory<Counters> directory_;
  Counters broadcast_;
  std::vector<Read> reads_this_frame_;
  std::vector<EscErrorDelta> deltas_, frame_deltas_;
  std::vector<LinkFault> faults_, frame_faults_;
  std::vector<LinkErrorEvent> frame_events_;
  std::uint64_t omitted_ = 0;
  std::uint64_t reads_ = 0;
  std::uint64_t broadcast_reads_ = 0;
};

}  // namespace ncservo
