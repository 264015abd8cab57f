// The simulated segment in time (simulator.hpp): the scenarios' plans for the NCs, the cycle
// that steps the NCs, the master, the slaves and the drives, and the faults due in it. The parts
// are segment.hpp (the slaves' ESCs), master.hpp (start-up and cycle), frame_encoder.hpp and
// fault_plan.hpp.
#include "ncservo/sim/simulator.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "capture_shaper.hpp"
#include "diagnosis_polls.hpp"
#include "esl_probe.hpp"
#include "fault_plan.hpp"
#include "incident_plan.hpp"
#include "master.hpp"
#include "ncservo/config/config.hpp"
#include "ncservo/sim/eni_writer.hpp"
#include "ncservo/sim/models.hpp"
#include "segment.hpp"

namespace ncservo::sim {

namespace {
constexpr std::int64_t kSoakPeriodNs = 10 * kSecond;
// The incidents scenario's master reads every slave's AL status this often (docs/simulate.md).
constexpr std::int64_t kStatusPollNs = 10 * kMs;
// An incident the plan says must happen, matched with what the capture shows.
struct PlannedIncident {
  IncidentKind kind;
  int axis;  // -1: the bus
  const char* cause;
  std::int64_t at_ns;
  bool seen = false;
};
// A planned incident is seen this long after its time at the latest (a drift trips around it).
constexpr std::int64_t kIncidentSlackNs = 250 * kMs;
}  // namespace

std::string faultsJson(const std::vector<FaultTruth>& faults) {
  nlohmann::ordered_json expected = nlohmann::ordered_json::array();
  nlohmann::ordered_json companions = nlohmann::ordered_json::object();
  for (const FaultTruth& f : faults) {
    expected.push_back(
        {{"rule", f.rule},
         {"axis", f.axis ? nlohmann::ordered_json(*f.axis) : nlohmann::ordered_json()},
         {"first_frame", f.first_frame},
         {"last_frame", f.last_frame}});
    const FaultRecipe* recipe = faultRecipe(ruleByCode(f.rule)->id);
    nlohmann::ordered_json others = nlohmann::ordered_json::array();
    for (RuleId other : recipe->companions) others.push_back(ruleDef(other).code);
    companions[f.rule] = others;
  }
  return nlohmann::ordered_json{{"expected", expected}, {"companions", companions}}.dump(1) + "\n";
}

std::string incidentsJson(const std::vector<IncidentTruth>& incidents) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const IncidentTruth& i : incidents) {
    list.push_back({{"kind", i.kind},
                    {"axis", i.axis ? nlohmann::ordered_json(*i.axis) : nlohmann::ordered_json()},
                    {"frame", i.frame},
                    {"cause", i.cause}});
  }
  return nlohmann::ordered_json{{"incidents", list}}.dump(1) + "\n";
}

struct Simulator::Impl {
  SimOptions o;
  std::int64_t cycle_ns;
  std::int64_t duration_ns;
  std::int64_t plan_start_ns;  // since the capture's start
  Rng rng;
  Segment segment;
  std::vector<AxisConfig> axis_layout;
  std::vector<DriveModel> drives;
  std::vector<NcAxis> ncs;
  FaultPlan faults;
  Master master;
  std::vector<RxPdo> outputs;                       // per axis, from the NC this cycle
  std::vector<std::optional<TxPdo>> latest_inputs;  // per axis, from this cycle's returned frame
  std::int64_t soak_planned_until_ns = 0;
  // --capture-loss draws from its own generator: without it the capture is the same as before.
  Rng capture_loss_rng{o.seed ^ 0xC0FFEE5EEDULL};
  std::uint64_t master_copies_dropped = 0;
  std::uint64_t frames_cut = 0;  // before --start-in's moment
  CaptureShaper shaper{o};       // what the capturing PC does to the recording
  // The incidents scenario: its plan, what the capture shows of it, the slaves' falls from OP
  // and the master's AL status checks.
  struct Fall {  // a slave's, by ring position
    std::int64_t at_ns;
    int slave;
    std::uint16_t code;
    bool done = false;
  };
  // Where each planned fault's findings may be reported, in bus frames (faults()).
  struct FaultWindow {
    FaultPlan::Placed fault;
    std::uint64_t first = 0;
    std::uint64_t last = 0;
  };
  std::vector<FaultWindow> fault_windows;
  std::vector<PlannedIncident> planned;
  std::vector<IncidentTruth> seen;
  std::vector<std::string> unplanned;
  std::vector<bool> sew_error;  // per axis, in the last inputs returned
  std::vector<Fall> falls;
  std::vector<int> fallen_axes;  // out of OP until the status check's walk ends
  AlWalk status_check;
  int failed_cycles = 0;  // consecutive cycles every axis failed
  bool outage_due = false;
  // --diagnosis (docs/simulate.md#diagnosis): the mailboxes, the polls, the bad links.
  std::optional<DiagnosisPolls> polls;

  explicit Impl(const SimOptions& options)
      : o(options),
        cycle_ns(static_cast<std::int64_t>(options.cycle_us) * kUs),
        duration_ns(static_cast<std::int64_t>(std::llround(*options.duration_s * 1e9))),
        plan_start_ns((options.startup ? static_cast<std::int64_t>(kStartupSeconds * 1e9) : 0) +
                      at(options.idle_s)),
        rng(options.seed),
        segment(options, rng),
        axis_layout(segment.axisLayout()),
        faults(segment, drives, ncs),
        master(segment) {
    if (o.latency_us > 0) master.setReturnDelayNs(o.latency_us * kUs);
    for (int a = 0; a < o.axes; ++a) {
      DriveSetup setup;
      setup.axis = a;
      setup.incremental = isIncrementalAxis(a);
      setup.ready_mode = o.ready_mode;
      setup.seed = o.seed;
      drives.emplace_back(setup);
      ncs.emplace_back(setup.incremental);
    }
    latest_inputs.assign(static_cast<std::size_t>(o.axes), std::nullopt);
    outputs.assign(static_cast<std::size_t>(o.axes), RxPdo{});
    if (o.diagnosis) polls.emplace(o, segment, master, faults);
    for (const SlaveAt& sync : o.sync_errors) {
      falls.push_back({at(sync.at_s), sync.station - kFirstStation, ecat::kAlCodeSyncError});
    }
    planScenario();
    for (const FaultRequest& f : o.faults) {
      faults.inject(f.rule, f.at_s.value_or(-1), f.axis.value_or(-1));
    }
    if (o.scenario == Scenario::Faults) faults.injectScenario(o.diagnosis);
    for (const FaultPlan::Placed& fault : faults.placed()) fault_windows.push_back({fault});
  }

  Status recordsAreBusFrames(const char* truth) const;

  // The capture ends: the windows still open end with it.
  void closeFaultWindows() {
    for (FaultWindow& w : fault_windows) {
      if (w.last == 0) w.last = master.frames();
    }
  }
  // Before a cycle's frames: the windows that open or close at its slot (FaultTruth).
  void markFaultWindows(std::int64_t slot, bool operational) {
    for (FaultWindow& w : fault_windows) {
      if (w.first == 0 && (w.fault.startup || slot >= w.fault.at_ns)) {
        w.first = w.fault.startup ? 1 : master.frames() + 1;
      }
      const bool over =
          w.fault.startup ? operational : slot >= w.fault.at_ns + kFaultReportedWithinNs;
      if (w.last == 0 && over) w.last = master.frames();
    }
  }

  // --- scenarios ---

  static std::int64_t at(double seconds) {
    return static_cast<std::int64_t>(std::llround(seconds * 1e9));
  }

  void planScenario() {
    const double base = static_cast<double>(plan_start_ns) * 1e-9;
    // The run's later steps fall at fractions of what the idle time leaves.
    const double idle = o.idle_s;
    auto late = [&](double fraction) { return at(idle + fraction * (*o.duration_s - idle)); };
    if (o.idle_all) return;                    // drives ready, nothing enabled
    if (o.scenario == Scenario::Soak) return;  // planned period by period (planSoak)
    for (int a = 0; a < o.axes; ++a) {
      NcAxis& nc = ncs[static_cast<std::size_t>(a)];
      const double rpm = (a % 2 ? -1.0 : 1.0) * (600 + 300 * (a % 4));
      nc.schedule({at(base + 0.05 + 0.01 * (a % 8)), NcAction::Enable});
      nc.schedule({at(base + 0.15), NcAction::Speed, rpm});
      if (o.scenario == Scenario::Faults || o.scenario == Scenario::Incidents) continue;
      if (isIncrementalAxis(a)) nc.schedule({at(base + 0.30), NcAction::ZeroPulse});
      nc.schedule({at(base + 0.55), NcAction::Table, static_cast<double>(a % 3 + 2)});
      nc.schedule({late(0.53), NcAction::Emergency, 150});
      nc.schedule({late(0.62), NcAction::Table, 1});
      nc.schedule({late(0.78), NcAction::Speed, 0});
      nc.schedule({late(0.85), NcAction::Disable});
    }
    if (o.scenario == Scenario::Commissioning) {
      faults.scheduleDriveFault(at(base + 0.8), 1 % o.axes, bits::kFollowing);
    }
    if (o.scenario == Scenario::Incidents) planIncidents();
  }

  // The incidents scenario: each row's chain at its time (a cycle slot, so that an offset of a
  // nanosecond is the next cycle), and the incidents it must give.
  class Chain final : public IncidentActions {
   public:
    Chain(Impl& impl, std::int64_t at_ns, int axis) : impl_(impl), at_ns_(at_ns), axis_(axis) {}
    void nc(std::int64_t offset_ns, NcAction action, double value) override {
      impl_.ncs[index()].schedule({at_ns_ + offset_ns, action, value});
    }
    void driveFault(std::int64_t offset_ns, std::uint32_t cause) override {
      impl_.faults.scheduleDriveFault(at_ns_ + offset_ns, axis_, cause);
    }
    void drift(std::int64_t offset_ns, Drift drift) override {
      drift.from_ns = at_ns_ + offset_ns;
      impl_.drives[index()].drift(drift);
    }
    void bus(std::int64_t offset_ns, BusFault fault) override {
      impl_.faults.scheduleBusFault(at_ns_ + offset_ns, axis_, fault);
    }
    void fallFromOp(std::int64_t offset_ns, std::uint16_t code) override {
      impl_.falls.push_back({at_ns_ + offset_ns, impl_.segment.servo_slave[index()], code});
    }
    void badLink(std::int64_t offset_ns, int frames) override {
      const auto into = static_cast<std::size_t>(impl_.segment.servo_slave[index()]);
      impl_.polls->corruptFrames(at_ns_ + offset_ns, into, frames);
      // the drives behind the link miss the frames too: each an incident of this cause
      for (int a = 0; a < impl_.o.axes; ++a) {
        if (a != axis_ && static_cast<std::size_t>(
                              impl_.segment.servo_slave[static_cast<std::size_t>(a)]) >= into) {
          impl_.planned.push_back({IncidentKind::DriveFault, a, "link-fault", at_ns_ + offset_ns});
        }
      }
    }

   private:
    std::size_t index() const { return static_cast<std::size_t>(axis_); }
    Impl& impl_;
    std::int64_t at_ns_;
    int axis_;
  };

  void planIncidents() {
    const std::vector<IncidentRow>& rows = incidentRows(o.diagnosis);
    for (std::size_t r = 0; r < rows.size(); ++r) {
      const IncidentRow& row = rows[r];
      const std::int64_t t = at(incidentTime(r, rows.size(), *o.duration_s));
      const std::int64_t slot = (t + cycle_ns - 1) / cycle_ns * cycle_ns;
      Chain chain(*this, slot, row.axis);
      row.apply(chain);
      planned.push_back({row.kind, row.axis, row.cause, slot});
      if (row.kind == IncidentKind::BusOutage) {  // and every drive's ECatTErr
        for (int a = 0; a < o.axes; ++a) {
          planned.push_back({IncidentKind::DriveFault, a, "communication-loss", slot});
        }
      }
    }
    sew_error.assign(static_cast<std::size_t>(o.axes), false);
  }

  // An incident the capture shows at `frame`, now: the cause its plan gave it.
  void incident(IncidentKind kind, int axis, std::uint64_t frame, std::int64_t now_ns) {
    for (PlannedIncident& p : planned) {
      if (p.seen || p.kind != kind || p.axis != axis || p.at_ns > now_ns ||
          now_ns > p.at_ns + kIncidentSlackNs) {
        continue;
      }
      p.seen = true;
      shaper.track(frame);
      seen.push_back({incidentKindName(kind), axis < 0 ? std::nullopt : std::optional<int>(axis),
                      frame, p.cause});
      return;
    }
    unplanned.push_back(
        fmt::format("{} on axis {} at frame {}", incidentKindName(kind), axis, frame));
  }

  // After a cycle's exchange: the drive faults its returned copies show first (SEW.ServoErrors
  // rising: the axis enters "fault reaction active", or "error" when the drive was already off;
  // docs/protocol.md §6).
  void watchDriveFaults(std::int64_t slot) {
    for (int a = 0; a < o.axes; ++a) {
      const auto& in = latest_inputs[static_cast<std::size_t>(a)];
      if (!in) continue;
      const bool error = (in->sew & bits::kServoErrors) != 0;
      if (error && !sew_error[static_cast<std::size_t>(a)]) {
        incident(IncidentKind::DriveFault, a, master.inputFrame(a), slot);
      }
      sew_error[static_cast<std::size_t>(a)] = error;
    }
  }

  // The master reads every slave's AL status every kStatusPollNs (between two cycles, as its
  // start-up's walk does); a slave out of OP is acknowledged and walked back, and its axis's NC
  // sends neutral outputs until then.
  bool checkAlStatus(const FrameSink& sink, std::uint64_t cycle, std::int64_t slot,
                     std::int64_t at_ns) {
    if (status_check.active) {
      if (!master.alFrame(sink, status_check, at_ns)) return false;
      if (!status_check.active) {
        for (int a : fallen_axes) ncs[static_cast<std::size_t>(a)].setOperational(true);
        fallen_axes.clear();
      }
      return true;
    }
    const auto every =
        static_cast<std::uint64_t>(std::max<std::int64_t>(1, kStatusPollNs / cycle_ns));
    if (cycle % every != 0) return true;
    status_check.start(ecat::kAlOp, segment.escs.size(), false);
    if (!master.alFrame(sink, status_check, at_ns)) return false;
    for (std::size_t s = 0; s < segment.escs.size(); ++s) {
      const int axis = segment.escs[s].axis;
      if (!status_check.need_ack[s] || axis < 0) continue;
      incident(IncidentKind::Esm, axis, master.frames(), slot);
      ncs[static_cast<std::size_t>(axis)].fellFromOp();
      fallen_axes.push_back(axis);
    }
    return true;
  }

  // --- between two cycles ---

  // After a cycle: the NC's reads of what faulted, and (in a cycle whose frames came back, in
  // OP) the master's AL status check and its diagnosis polls, each frame only when its returned
  // copy comes before the next cycle may be sent. False if the sink stopped.
  bool betweenCycles(const FrameSink& sink, std::uint64_t cycle, std::int64_t slot, bool in_op) {
    if (polls) polls->watchInputs(latest_inputs);
    if (!in_op || (o.scenario != Scenario::Incidents && !polls)) return true;
    const std::int64_t t_ns = std::max(slot + cycle_ns / 2, master.lastFrameNs() + kUs);
    const std::int64_t deadline_ns = slot + cycle_ns - cycle_ns / 4;
    if (t_ns + master.returnDelayNs() + kUs > deadline_ns) return true;
    if (!checkAlStatus(sink, cycle, slot, t_ns)) return false;
    return !polls || polls->between(sink, cycle, slot, master.lastFrameNs() + kUs, deadline_ns);
  }

  // Soak: a 10 s pattern repeated, planned a period ahead (constant memory).
  void planSoak(std::int64_t now_ns) {
    if (o.idle_all) return;
    while (soak_planned_until_ns <= now_ns + kSoakPeriodNs) {
      const std::int64_t p = soak_planned_until_ns == 0 ? plan_start_ns : soak_planned_until_ns;
      const std::int64_t k = (p - plan_start_ns) / kSoakPeriodNs;
      for (int a = 0; a < o.axes; ++a) {
        NcAxis& nc = ncs[static_cast<std::size_t>(a)];
        const auto ka = k + a;
        if (k == 0) nc.schedule({p + 50 * kMs + 10 * kMs * (a % 8), NcAction::Enable});
        nc.schedule({p + 500 * kMs, NcAction::Speed,
                     (ka % 2 ? -1.0 : 1.0) * static_cast<double>(500 + 150 * (ka % 5))});
        if (isIncrementalAxis(a)) nc.schedule({p + 2 * kSecond, NcAction::ZeroPulse});
        nc.schedule({p + 4 * kSecond, NcAction::Table, static_cast<double>(ka % 4 + 1)});
        if (k % 3 == 2) nc.schedule({p + 6 * kSecond, NcAction::Emergency, 100});
        nc.schedule({p + 9 * kSecond, NcAction::Speed, 0});
      }
      if (k % 6 == 5) {
        faults.scheduleDriveFault(p + 7500 * kMs, static_cast<int>(k / 6 % o.axes),
                                  bits::kOverload);
      }
      soak_planned_until_ns = p + kSoakPeriodNs;
    }
    faults.dropRaisedDriveFaults();
  }

  // --- the cycle ---

  // The drives take the outputs their slave received and write their inputs into its RAM.
  void stepDrives(std::int64_t now_ns) {
    faults.raiseDriveFaults(now_ns);
    for (int a = 0; a < o.axes; ++a) {
      Esc& esc = segment.servo(a);
      if (!esc.processData()) continue;
      DriveModel& drive = drives[static_cast<std::size_t>(a)];
      drive.setOperational(esc.state == ecat::kAlOp);
      if (esc.outputs_taken) {
        const RxPdo rx = decodeRx(&esc.mem[esc.outputsPhysical()]);
        drive.step(&rx, now_ns);
      } else {
        drive.step(nullptr, now_ns);
      }
      encodeTx(drive.inputs(), &esc.mem[esc.inputsPhysical()]);
      if (polls) polls->stepDrive(a, drive.inputs().sew, esc);
    }
    for (Esc& esc : segment.escs) {
      if (!esc.servo()) esc.updateTerminalInputs(now_ns);
    }
  }

  // Before a cycle's frames: the NCs' outputs from the inputs the last cycle returned, and the
  // slaves' falls from OP now due.
  void stepNcs(std::int64_t slot) {
    for (int a = 0; a < o.axes; ++a) {
      const auto& in = latest_inputs[static_cast<std::size_t>(a)];
      outputs[static_cast<std::size_t>(a)] =
          ncs[static_cast<std::size_t>(a)].step(in ? &*in : nullptr, slot);
    }
    for (Esc& esc : segment.escs) esc.outputs_taken = false;
    std::fill(latest_inputs.begin(), latest_inputs.end(), std::nullopt);
    for (Fall& f : falls) {
      if (f.done || slot < f.at_ns) continue;
      segment.escs[static_cast<std::size_t>(f.slave)].fallFromOp(f.code);
      f.done = true;
    }
  }

  // --start-in: the capture keeps nothing before the moment (half a cycle early, so that each
  // cycle keeps both its copies). Inside a fault (fault:RULE) the moment is the cycle after the
  // fault's first, whose returned copy shows the drive's answer to it.
  std::int64_t midStartNs() const {
    if (o.mid_start != MidStart::InFault) {
      return plan_start_ns + at(midStartRow(o.mid_start).after_plan_s);
    }
    for (const FaultRequest& f : o.faults) {
      if (f.rule == *o.mid_start_fault) return firstSlotAt(*f.at_s) + cycle_ns;
    }
    return 0;  // resolveOptions added the fault
  }
  FrameSink midStartSink(const FrameSink& captured) {
    const std::int64_t from_ns = kEpochNs + midStartNs() - cycle_ns / 2;
    return [this, captured, from_ns](const SimFrame& frame) {
      if (frame.time_ns >= from_ns) return captured(frame);
      ++frames_cut;
      return true;
    };
  }

  // The cycle slot at or after a capture time; SimFrame times count from the capture's start.
  std::int64_t firstSlotAt(double at_s) const {
    const auto at = static_cast<std::int64_t>(std::llround(at_s * 1e9));
    return (at + cycle_ns - 1) / cycle_ns * cycle_ns;
  }
  // How late (µs) the cycle of this slot is sent (--late-cycle).
  std::int64_t disturbance(const std::vector<CycleDisturbance>& late, std::int64_t slot) const {
    std::int64_t us = 0;
    for (const CycleDisturbance& d : late) {
      if (slot == firstSlotAt(d.at_s)) us += d.amount;
    }
    return us;
  }

  std::optional<std::uint64_t> run(const FrameSink& captured) {
    const FrameSink shaped = shaper.active() ? shaper.sink(captured) : captured;
    const FrameSink kept = o.mid_start == MidStart::None ? shaped : midStartSink(shaped);
    const FrameSink sink = o.probe == Probe::Esl ? eslProbeSink(kept, o.seed) : kept;
    std::int64_t t = 0;
    const std::int64_t step_ns = std::min<std::int64_t>(cycle_ns, kMs);
    if (o.startup) {
      if (!master.startup(sink, t, step_ns, faults.opRequestSlave())) return std::nullopt;
      stepDrives(t);  // the drives' first inputs, for the first cycle
      t = (t / cycle_ns + 1) * cycle_ns;
    } else {
      for (std::size_t s = 0; s < segment.escs.size(); ++s) {
        segment.escs[s].startInOp(static_cast<std::uint16_t>(kFirstStation + s));
        if (o.diagnosis && segment.escs[s].servo()) segment.escs[s].startWithMailbox();
      }
      stepDrives(0);
    }
    // Cyclic exchange: SAFE-OP first, then the master walks every slave to OP.
    AlWalk walk;
    const std::uint64_t safe_op_cycles =
        static_cast<std::uint64_t>(std::max<std::int64_t>(10, 20 * kMs / cycle_ns));
    const std::int64_t first_cycle = t;
    bool operational = !o.startup;
    for (NcAxis& nc : ncs) nc.setOperational(operational);
    for (std::uint64_t cycle = 0;; ++cycle) {
      const std::int64_t slot = first_cycle + static_cast<std::int64_t>(cycle) * cycle_ns;
      if (slot >= duration_ns) break;
      if (o.scenario == Scenario::Soak) planSoak(slot);
      markFaultWindows(slot, operational);
      faults.startBusFaults(slot);
      std::int64_t send = slot;
      if (o.jitter_us > 0) send += rng.between(-o.jitter_us, o.jitter_us) * kUs;
      send += disturbance(o.late_cycles, slot) * kUs;
      send +=
          static_cast<std::int64_t>(faults.takeSendDelayCycles() * static_cast<double>(cycle_ns));
      master.delayNextReturnNs(static_cast<std::int64_t>(faults.takeReturnDelayCycles() *
                                                         static_cast<double>(cycle_ns)));
      const bool lost = std::any_of(o.lost_cycles.begin(), o.lost_cycles.end(), [&](const auto& d) {
        const std::int64_t from = firstSlotAt(d.at_s);
        return slot >= from && slot < from + d.amount * cycle_ns;
      });
      stepNcs(slot);
      bool failed = true;  // every axis: the cycle's frames lost or not sent
      if (polls) polls->beforeCycle(slot);
      if (!faults.takeSkippedCycle() && !lost) {
        const bool lost_before = faults.takeLossBeforeSlaves();
        const bool lost_after =
            faults.takeLossAfterSlaves() || (o.loss > 0 && rng.uniform() < o.loss);
        failed = lost_before || lost_after;
        if (outage_due) {  // the limit was exceeded: this cycle's master copy shows it
          incident(IncidentKind::BusOutage, -1, master.frames() + 1, slot);
          outage_due = false;
        }
        // The capture, not the bus, misses the master copies of a cycle whose returned copies
        // it holds (docs/simulate.md); never the first cycle's, which starts each frame's clock.
        const bool drop_master = o.capture_loss > 0 && cycle > 0 && !lost_before && !lost_after &&
                                 capture_loss_rng.uniform() < o.capture_loss;
        const FrameSink dropping = [&](const SimFrame& frame) {
          if (frame.returned) return sink(frame);
          ++master_copies_dropped;
          return true;
        };
        if (!master.cycle(drop_master ? dropping : sink, std::max(send, slot - cycle_ns / 4), cycle,
                          outputs, lost_before, lost_after, latest_inputs)) {
          return std::nullopt;
        }
        failed = failed || !master.lastCycleReturned();
      }
      stepDrives(slot);
      if (o.scenario == Scenario::Incidents) {
        watchDriveFaults(slot);
        failed_cycles = failed ? failed_cycles + 1 : 0;
        if (failed_cycles == kTelegramFailureLimit + 1) outage_due = true;
      }
      if (!betweenCycles(sink, cycle, slot, operational && !failed)) return std::nullopt;
      if (!operational) {
        if (!walk.active && cycle + 1 == safe_op_cycles) {
          walk.start(ecat::kAlOp, segment.escs.size(), true);
        } else if (walk.active) {
          if (!master.alFrame(sink, walk, slot + cycle_ns / 2)) return std::nullopt;
          if (!walk.active) {
            operational = true;
            for (NcAxis& nc : ncs) nc.setOperational(true);
          }
        }
      }
    }
    closeFaultWindows();
    if (shaper.active()) return shaper.records();
    return master.frames() - master_copies_dropped - frames_cut;
  }
};

Simulator::Simulator(const SimOptions& options) : impl_(std::make_unique<Impl>(options)) {}
Simulator::~Simulator() = default;

std::uint64_t Simulator::masterCopiesDropped() const {
  return impl_->master_copies_dropped;
}

// A truth counted in the bus's frames holds only where the capture's records are those frames.
Status Simulator::Impl::recordsAreBusFrames(const char* truth) const {
  if (shaper.active() || o.mid_start != MidStart::None || o.capture_loss > 0) {
    return fail(fmt::format(
        "the capture's records are not the bus's frames (a capture shape, --start-in or "
        "--capture-loss): no {}",
        truth));
  }
  return {};
}

Result<std::vector<FaultTruth>> Simulator::faults() const {
  const Impl& impl = *impl_;
  if (Status frames = impl.recordsAreBusFrames("fault truth"); !frames) return fail(frames.error());
  std::vector<FaultTruth> out;
  for (const Impl::FaultWindow& w : impl.fault_windows) {
    const RuleDef& rule = ruleDef(w.fault.rule);
    std::vector<std::optional<int>> axes;  // a bus rule names none; the whole bus, every axis
    if (rule.kind == RuleKind::Bus) {
      axes.push_back(std::nullopt);
    } else if (w.fault.axis < 0) {
      for (int a = 0; a < impl.o.axes; ++a) axes.push_back(a);
    } else {
      axes.push_back(w.fault.axis);
      axes.insert(axes.end(), w.fault.also.begin(), w.fault.also.end());
    }
    for (const std::optional<int>& axis : axes) {
      out.push_back({rule.code, axis, w.first, w.last});
    }
  }
  return out;
}

Result<DiagnosisTruth> Simulator::diagnosis() const {
  const Impl& impl = *impl_;
  if (Status frames = impl.recordsAreBusFrames("diagnosis truth"); !frames) {
    return fail(frames.error());
  }
  return impl.polls ? impl.polls->truth() : DiagnosisTruth{};
}

Result<std::vector<IncidentTruth>> Simulator::incidents() const {
  const Impl& impl = *impl_;
  if (!impl.unplanned.empty()) {
    return fail("incidents the plan did not say: " +
                fmt::format("{}", fmt::join(impl.unplanned, "; ")));
  }
  for (const PlannedIncident& p : impl.planned) {
    if (!p.seen) {
      return fail(fmt::format("a planned {} on axis {} ({}) did not happen",
                              incidentKindName(p.kind), p.axis, p.cause));
    }
  }
  // The bus's frame numbers as the capture's records (copies and office records between them).
  std::vector<IncidentTruth> incidents = impl.seen;
  for (IncidentTruth& incident : incidents) {
    const std::optional<std::uint64_t> record = impl.shaper.recordOf(incident.frame);
    if (!record) return fail(fmt::format("no record known for frame {}", incident.frame));
    incident.frame = *record;
  }
  return incidents;
}

const std::vector<AxisConfig>& Simulator::layout() const {
  return impl_->axis_layout;
}

std::string Simulator::layoutConfig() const {
  return fmt::format(
             "# The layout of `ncservo simulate` ({} axes, {}, {} terminals), for\n"
             "# `ncservo validate --config` or the Wireshark preference ncservo.config.\n",
             impl_->o.axes, impl_->segment.describe(), *impl_->o.io_slaves) +
         writeConfig(impl_->axis_layout, impl_->o.ready_mode);
}

std::string Simulator::eni() const {
  const Segment& segment = impl_->segment;
  std::vector<EniSlave> slaves;
  for (std::size_t pos = 0; pos < segment.escs.size(); ++pos) {
    const Esc& esc = segment.escs[pos];
    EniSlave e;
    e.name = esc.servo() ? fmt::format("axis{}", esc.axis)
                         : fmt::format("Term {} ({})", pos, esc.model->name);
    e.station = static_cast<std::uint16_t>(kFirstStation + pos);
    e.position = static_cast<std::uint16_t>(pos);
    e.outputs = esc.outputs_logical;
    e.output_bytes = static_cast<std::uint16_t>(esc.outputBytes());
    e.inputs = esc.inputs_logical;
    e.input_bytes = static_cast<std::uint16_t>(esc.inputBytes());
    if (impl_->o.diagnosis && esc.servo()) {
      e.mailbox_out = kMailboxOutPhys;
      e.mailbox_in = kMailboxInPhys;
      e.mailbox_bytes = kMailboxBytes;
    }
    slaves.push_back(std::move(e));
  }
  std::vector<EniCyclicCommand> commands;
  for (std::size_t g = 0; g < segment.groups.size(); ++g) {
    for (const ImageDatagram& dg : segment.groups[g].datagrams) {
      commands.push_back(
          {dg.command, dg.logical, static_cast<std::uint16_t>(dg.size), segment.expectedWkc(dg), g,
           static_cast<std::uint32_t>(impl_->o.cycle_us * segment.groups[g].every_cycles)});
    }
  }
  return writeEni(slaves, commands);
}

std::optional<std::uint64_t> Simulator::run(const FrameSink& sink) {
  return impl_->run(sink);
}

}  // namespace ncservo::sim
