// The layout inferred from the cyclic traffic itself (docs/protocol.md §9.4): every 10-byte window
// of the data a master writes and every 40-byte window of the data slaves return, in every cyclic
// logical or FPRD/FPWR datagram, is a candidate RxPDO or TxPDO. The signature of §1–5 rules
// candidates out (reserved bits, SEW summary, message code and its datum, finite floats, a smooth
// or standing ActPos, a steady SE); the bytes the slaves changed against the master's copy are no
// RxPDO's. Behaviour pairs them (SSW.ServoEn follows SCW.SE, ErrClearAck follows ErrorClear,
// ZPulseAck follows ZPulseRequest). Without any handshake the structure alone decides when exactly
// one tiling fits: RxPDO k with TxPDO k in process-image order, the SSW's parameter tables among
// the SCW's, ServoRDY per the ready table. Evidence is gathered over a bounded number of cycles;
// memory is bounded.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/layout/axis_config.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo {

// What the evidence says about one inferred axis (`decode --layout` prints it).
struct AxisEvidence {
  std::uint32_t cycles = 0;            // cycles in which the TxPDO was seen
  std::uint32_t violations = 0;        // of the TxPDO's signature checks (stale or faulty data)
  std::uint32_t rx_violations = 0;     // of the RxPDO's (SCW reserved bits)
  std::uint32_t actpos_moves = 0;      // cycles in which ActPos changed, smoothly
  std::uint32_t status_cycles = 0;     // cycles with a status bit of SSW set
  std::uint32_t enabled_agree = 0;     // cycles with SCW.SE 0x2 and SSW.ServoEn 1
  std::uint32_t enabled_disagree = 0;  // cycles with ServoEn 1 long after SE left 0x2
  std::uint32_t clear_agree = 0;       // cycles with ErrorClear and ErrClearAck both 1
  std::uint32_t zpulse_agree = 0;      // cycles with ZPulseRequest and ZPulseAck both 1
  std::uint32_t ready_mismatches = 0;  // cycles with ServoRDY against the ready table
  // Cycles of the three handshakes above (ServoEn with SE, ErrClearAck, ZPulseAck): 0 when the
  // layout came from the structure alone.
  std::uint32_t handshakes_seen = 0;
  double confidence = 0;  // 0..1: how far the next best candidate is behind
  // No data the slaves wrote was captured (master copies only, or frames cut before the
  // inputs): the outputs-first layout of §9.4 is taken from the outputs alone.
  bool outputs_only = false;
  // No handshake decided this axis: the structure singled out one tiling (docs/layout.md).
  bool structure_only = false;
  // RxPDO k was paired with TxPDO k in process-image order, not by a handshake.
  bool paired_by_order = false;
};

struct InferredAxis {
  AxisConfig config;  // logical addresses, or station and SM addresses
  AxisEvidence evidence;
};

struct InferenceResult {
  std::vector<InferredAxis> axes;  // in process-image order; empty when refused
  // When refused: the placements that were found, with their evidence (not certain enough).
  std::vector<InferredAxis> candidates;
  std::uint32_t cycles = 0;  // cycles observed
  // TxPDOs that look like a servo's but that no control word explains (yet): the window goes on.
  std::uint32_t unexplained = 0;
  // Axes whose handshakes are all over a ServoEn already set when the window began, beside a SE
  // that read 0x2: a neighbour's steady input explains that as well, so the window goes on until
  // one is seen happen or it is full (docs/layout.md).
  std::uint32_t unconfirmed = 0;
  // Why nothing was inferred, the candidates and how to write a configuration (empty when axes
  // were inferred).
  std::string refusal;
};

// What a view of an axis found from the structure alone says beside its decoded data (the
// plugin's expert note; docs/layout.md).
inline constexpr const char* kStructureOnlyNote =
    "layout inferred from the PDO structure alone; no handshake confirmed it (docs/layout.md)";

// One line per check for an inferred axis, for `decode --layout`.
std::string describeEvidence(const InferredAxis& axis);
// How an inferred axis was found and how sure, in a few words (the reports).
std::string describeInference(const AxisEvidence& evidence);

struct InferenceLimits {
  std::uint32_t max_cycles = 4096;   // cycles of evidence, at most
  std::uint32_t min_cycles = 128;    // before an early decision
  std::size_t max_streams = 16;      // cyclic datagrams followed
  std::size_t max_bytes = 4u << 20;  // memory for the evidence
};

class LayoutInference {
 public:
  explicit LayoutInference(InferenceLimits limits = {});
  ~LayoutInference();
  LayoutInference(const LayoutInference&) = delete;
  LayoutInference& operator=(const LayoutInference&) = delete;

  // Every walked frame in capture order; only returned copies (`returned`) with a working
  // counter above zero carry evidence.
  void onFrame(const EcatFrame& frame, const ByteReader& bytes, bool returned);
  std::uint32_t cycles() const;
  // Enough evidence has been gathered, or the limits are reached: decide() will not change.
  bool settled() const;
  InferenceResult decide() const;

 private:
  struct State;
  bool outputsFirst(InferenceResult& result) const;
  bool fromStructure(InferenceResult& result, std::string& why) const;
  std::unique_ptr<State> state_;
};

}  // namespace ncservo
