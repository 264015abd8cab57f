// `ncservo simulate`: an EtherCAT master, its slaves and the NC/drive models (models.hpp)
// producing a capture whose truth is known. The output is a pure function of the options.
//
// The master does what real masters do (docs/protocol.md §8): counts the slaves, assigns station
// addresses, walks every slave INIT -> PRE-OP -> SAFE-OP -> OP with AL status polls, configures
// SM2/SM3 and FMMUs, then exchanges process data once per cycle in the datagrams of its image
// style (ImageStyle) with a DC FRMW to 0x0910. Each frame is captured twice: the master's copy and
// the copy the ring returns. The slaves are small ESC models with register memory: FMMUs, sync
// managers and AL control work from what the master wrote, so the capture is consistent by
// construction. Each rule's fault is a row of faults.hpp. With --diagnosis the servos also have
// mailboxes, the drives report their faults there, the NC reads their error history and the
// master polls the ESCs' error counters between the cycles (docs/simulate.md#diagnosis).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/config/config.hpp"
#include "ncservo/sim/diagnosis_truth.hpp"
#include "ncservo/sim/options.hpp"

namespace ncservo::sim {

// An incident of the `incidents` scenario as `validate` must list it (docs/simulate.md#incidents):
// the frame is the one the simulator wrote, counted from 1 in the capture.
struct IncidentTruth {
  std::string kind;         // drive-fault, bus-outage or esm
  std::optional<int> axis;  // none for a bus outage
  std::uint64_t frame = 0;
  std::string cause;  // the cause id
};
// `{"incidents": [{"kind", "axis", "frame", "cause"}, ...]}`, for --incidents-truth.
std::string incidentsJson(const std::vector<IncidentTruth>& incidents);

// A finding a planned fault must produce, from the plan alone: the rule, its axis (none for a
// bus rule) and the frames it may be reported on, from the fault's time to kFaultReportedWithinNs
// after it (a start-up fault: from the first frame to the slaves' reaching OP).
struct FaultTruth {
  std::string rule;
  std::optional<int> axis;
  std::uint64_t first_frame = 0;
  std::uint64_t last_frame = 0;
};
// Every recipe's condition and timeout are over this long after its fault's time (the longest,
// FLT-001's drive enabled 200 ms beside its error; docs/simulate.md).
inline constexpr std::int64_t kFaultReportedWithinNs = 300'000'000;
// gen_capture.py --findings' form, which check_findings.py reads: `{"expected": [{"rule", "axis",
// "first_frame", "last_frame"}, ...], "companions": {RULE: [RULE, ...]}}`, for --faults-truth.
std::string faultsJson(const std::vector<FaultTruth>& faults);

class Simulator {
 public:
  // The options must have passed resolveOptions.
  explicit Simulator(const SimOptions& options);
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  // Where each axis's PDOs are, as a configuration file gives them: name, logical addresses and
  // station, in axis order.
  const std::vector<AxisConfig>& layout() const;
  // The layout as a TOML configuration file that `ncservo validate --config` reads.
  std::string layoutConfig() const;
  // The set-up as an ENI file (ETG.2100 EtherCATConfig.xml), for `ncservo validate --eni`.
  std::string eni() const;
  // Runs the whole simulation; the number of frames written, or nothing if the sink stopped.
  std::optional<std::uint64_t> run(const FrameSink& sink);
  // The master copies --capture-loss left out of the capture: its truth.
  std::uint64_t masterCopiesDropped() const;
  // After run, in the `incidents` scenario: every incident it wrote, in capture order; an error
  // when an incident happened that its plan did not say, or one it planned did not happen.
  Result<std::vector<IncidentTruth>> incidents() const;
  // After run: the findings of every fault it planned (--fault, the faults scenario); an error
  // when the capture's records are not the bus's frames (a capture shape, --start-in,
  // --capture-loss).
  Result<std::vector<FaultTruth>> faults() const;
  // After run, with --diagnosis: what the drives and the ESCs said; an error when the capture's
  // records are not the bus's frames.
  Result<DiagnosisTruth> diagnosis() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ncservo::sim
