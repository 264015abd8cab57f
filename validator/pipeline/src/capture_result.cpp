#include "ncservo/pipeline/capture_result.hpp"

#include <fmt/format.h>

namespace ncservo {

std::string axisNameIn(const std::vector<AxisInfo>& layout, std::uint16_t axis) {
  for (const AxisInfo& info : layout) {
    if (info.index == axis) return info.name;
  }
  return fmt::format("axis{}", axis);
}

Truncation truncationOf(std::uint64_t snapped, std::uint64_t first_snapped, const CutRegions& cut,
                        const std::vector<AxisInfo>& axes) {
  Truncation t{snapped, first_snapped, cut.frames(), cut.firstFrame(), {}};
  for (std::uint16_t axis : cut.axes()) {
    t.axes.push_back(axis < axes.size() ? axes[axis].name : fmt::format("axis{}", axis));
  }
  return t;
}

namespace {

// The bus as the validator's models saw it.
void takeBus(const Validator& validator, CaptureResult& r) {
  const BusModel& bus = validator.bus();
  r.timing = bus.timing().summary();
  r.cyclic_datagrams = bus.cyclicDatagrams();
  r.unfollowed_frames = bus.unfollowedFrames();
  r.cyclic_frames = bus.cyclicFrames();
  r.master_copies_missing = bus.masterCopiesMissing();
  r.returned_copies_missing = bus.returnedCopiesMissing();
  r.lost_cycles = bus.lostCycles();
  r.wkc_errors = bus.wkcErrors();
  r.dc = validator.dc().stations();
  r.dc_settled_ns = validator.dc().settledNs();
  r.cycles = validator.cycles();
  // One source for the cycle time: the timing's series where it has one (its quantiles exact up
  // to kExactSamples), so that `cycle_time_us` and `timing.cycle_us` agree to the digit.
  if (r.timing.cycle) {
    auto us = [](std::int64_t ns) { return static_cast<double>(ns) / 1000.0; };
    r.cycle_time = {us(r.timing.cycle->median_ns), us(r.timing.cycle->p99_ns),
                    us(r.timing.cycle->max_ns)};
  } else {
    r.cycle_time = validator.cycleTime();
  }
  r.segments = validator.segments().segments();
  r.segment_count = validator.segments().count();
  r.drive_messages = validator.mailbox().messages();
  r.drive_messages_omitted = validator.mailbox().omitted();
  r.mailbox_notes = validator.mailbox().notes();
  r.mailbox_counts = validator.mailbox().counts();
  r.esc_errors = validator.escErrors().deltas();
  r.link_faults = validator.escErrors().linkFaults();
  r.esc_errors_omitted = validator.escErrors().omitted();
}

void takeAxes(const Validator& validator, CaptureResult& r) {
  for (std::size_t i = 0; i < validator.axisCount(); ++i) {
    const AxisModel* model = validator.axis(i);
    if (model == nullptr) continue;
    r.axes.push_back(AxisSummary{model->index(), axisNameIn(r.layout, model->index()),
                                 model->state(), model->timeline(), model->timelineOmitted(),
                                 model->errorHistory(), model->totalFailures(),
                                 model->readyMode()});
  }
}

}  // namespace

void takeValidator(const Validator& validator, CaptureResult& r) {
  takeBus(validator, r);
  r.layout_source = validator.decoder().source();
  r.layout = validator.decoder().axes();
  if (r.layout_source == LayoutSource::Startup) {
    r.startup_frames_cut = validator.decoder().learner().configurationFramesCut();
  }
  r.axes.clear();
  takeAxes(validator, r);
}

}  // namespace ncservo
