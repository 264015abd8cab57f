#include "ncservo/model/dc_clock.hpp"

#include <algorithm>
#include <cmath>

namespace ncservo {

namespace {
using ecat::kRegDcSystemTime;
using ecat::kRegDcSystemTimeDifference;
using ecat::kRegDcSystemTimeOffset;

// The commands with which a master distributes the reference clock's time: the addressed slave's
// is read, the others take it.
constexpr bool distributesTime(std::uint8_t cmd) {
  return cmd == ecat::kFrmw || cmd == ecat::kArmw;
}

// What this module takes of a datagram: a write of the station address (assigned to ring
// positions) or of the system time offset; a read of the DC registers it follows.
constexpr std::uint16_t kEndOfDcRegisters = kRegDcSystemTimeDifference + 4;
bool followed(const Datagram& dg, const FrameAddressing& addressing) {
  if (addressing.takesWrites() && ecat::writesRegisters(dg.command) &&
      (reachesRegisters(dg, ecat::kRegStationAddress, ecat::kRegStationAddress + 2) ||
       registerAt(dg, kRegDcSystemTimeOffset, 4))) {
    return true;
  }
  return addressing.takesRead(dg) && reachesRegisters(dg, kRegDcSystemTime, kEndOfDcRegisters);
}

constexpr double kNsPerPpmSecond = 1000.0;  // 1 ppm of a second
}  // namespace

std::int64_t systemTimeDifferenceNs(std::uint32_t raw) {
  const auto magnitude = static_cast<std::int64_t>(raw & ~ecat::kDcDifferenceSignBit);
  return (raw & ecat::kDcDifferenceSignBit) != 0 ? -magnitude : magnitude;
}

void LineFit::add(double x, double y) {
  n += 1;
  sx += x;
  sy += y;
  sxx += x * x;
  sxy += x * y;
  syy += y * y;
}

void LineFit::merge(const LineFit& other) {
  n += other.n;
  sx += other.sx;
  sy += other.sy;
  sxx += other.sxx;
  sxy += other.sxy;
  syy += other.syy;
}

std::optional<double> LineFit::slopeStandardError() const {
  const std::optional<double> b = slope();
  if (!b || n < 3) return std::nullopt;
  const double spread_x = sxx - sx * sx / n;
  const double spread_xy = sxy - sx * sy / n;
  const double spread_y = syy - sy * sy / n;
  // Rounding may leave a perfect line's residuals a little below zero.
  const double residuals = std::max(spread_y - *b * spread_xy, 0.0);
  return std::sqrt(residuals / (n - 2) / spread_x);
}

std::optional<double> LineFit::slope() const {
  if (n < 2) return std::nullopt;
  const double spread = n * sxx - sx * sx;
  // All x equal (up to rounding): no line.
  if (!(spread > 1e-12 * n * sxx)) return std::nullopt;
  return (n * sxy - sx * sy) / spread;
}

void DriftFit::add(std::int64_t frame_ns, std::uint64_t clock_ns) {
  if (samples_ == 0) {
    first_frame_ns_ = frame_ns;
    first_clock_ns_ = clock_ns;
  }
  ++samples_;
  // A timestamp a little before the first (docs/timing.md#rule-time: they may go back) counts in
  // the first block.
  const std::int64_t since_ns = std::max<std::int64_t>(frame_ns - first_frame_ns_, 0);
  std::size_t block = static_cast<std::size_t>(since_ns / block_ns_);
  while (block >= kBlocks) {
    for (std::size_t i = 0; i < kBlocks / 2; ++i) {
      LineFit merged = blocks_[2 * i];
      merged.merge(blocks_[2 * i + 1]);
      blocks_[i] = merged;
    }
    std::fill(blocks_.begin() + kBlocks / 2, blocks_.end(), LineFit{});
    used_blocks_ = (used_blocks_ + 1) / 2;
    block_ns_ *= 2;
    block = static_cast<std::size_t>(since_ns / block_ns_);
  }
  used_blocks_ = std::max(used_blocks_, block + 1);
  const auto clock_since_ns = static_cast<std::int64_t>(clock_ns - first_clock_ns_);
  // In double: a hostile clock may sit near the int64 range, where the difference overflows.
  const double offset_ns =
      static_cast<double>(clock_since_ns) - static_cast<double>(frame_ns - first_frame_ns_);
  blocks_[block].add(static_cast<double>(frame_ns - first_frame_ns_) / 1e9, offset_ns);
}

std::optional<double> DriftFit::ppmOf(std::size_t from_block, std::size_t to_block) const {
  LineFit fit;
  for (std::size_t i = from_block; i < to_block; ++i) fit.merge(blocks_[i]);
  const std::optional<double> ns_per_s = fit.slope();
  if (!ns_per_s) return std::nullopt;
  return *ns_per_s / kNsPerPpmSecond;
}

std::optional<double> DriftFit::driftPpm() const {
  return ppmOf(0, used_blocks_);
}

std::optional<double> DriftFit::driftUncertaintyPpm() const {
  constexpr double kNinetyFivePercent = 1.96;  // standard errors, for a normal scatter
  LineFit fit;
  for (std::size_t i = 0; i < used_blocks_; ++i) fit.merge(blocks_[i]);
  const std::optional<double> error = fit.slopeStandardError();
  if (!error) return std::nullopt;
  return kNinetyFivePercent * *error / kNsPerPpmSecond;
}

std::optional<double> DriftFit::firstHalfPpm() const {
  if (used_blocks_ < 2) return std::nullopt;
  return ppmOf(0, used_blocks_ / 2);
}

std::optional<double> DriftFit::secondHalfPpm() const {
  if (used_blocks_ < 2) return std::nullopt;
  return ppmOf(used_blocks_ / 2, used_blocks_);
}

void DcClock::DcData::absorb(const DcData& gone) {
  reference = reference || gone.reference;
  if (fit.samples() == 0) {
    fit = gone.fit;
    last_time = gone.last_time;
  }
  if (difference_reads == 0) {
    last_difference_ns = gone.last_difference_ns;
    last_difference_frame = gone.last_difference_frame;
    settled_frame = gone.settled_frame;
  }
  difference_reads += gone.difference_reads;
  max_abs_difference_ns = std::max(max_abs_difference_ns, gone.max_abs_difference_ns);
  if (gone.min_abs_difference_ns) {
    min_abs_difference_ns = std::min(min_abs_difference_ns.value_or(*gone.min_abs_difference_ns),
                                     *gone.min_abs_difference_ns);
  }
}

void DcClock::onSystemTime(DcData& slave, std::uint64_t raw, bool is_64_bit, std::int64_t time_ns) {
  std::uint64_t time = raw;
  if (!is_64_bit && slave.last_time) {
    // A 32-bit read wraps every 4.3 s: it continues the last time read.
    const auto low = static_cast<std::uint32_t>(*slave.last_time);
    time = *slave.last_time + static_cast<std::uint32_t>(static_cast<std::uint32_t>(raw) - low);
  }
  slave.last_time = time;
  slave.fit.add(time_ns, time);
}

void DcClock::onDifference(DcData& slave, std::uint32_t raw, std::uint64_t frame_number) {
  const std::int64_t difference = systemTimeDifferenceNs(raw);
  const std::int64_t magnitude = difference < 0 ? -difference : difference;
  ++slave.difference_reads;
  slave.last_difference_ns = difference;
  slave.last_difference_frame = frame_number;
  slave.max_abs_difference_ns = std::max(slave.max_abs_difference_ns, magnitude);
  slave.min_abs_difference_ns =
      std::min(slave.min_abs_difference_ns.value_or(magnitude), magnitude);
  if (magnitude > settled_ns_) {
    slave.settled_frame.reset();
  } else if (!slave.settled_frame) {
    slave.settled_frame = frame_number;
  }
}

void DcClock::onFrame(const EcatFrame& frame, const ByteReader& bytes, bool returned, bool paired,
                      std::uint64_t frame_number, std::int64_t time_ns) {
  if (frame.status != WalkStatus::Ok && frame.status != WalkStatus::Truncated) return;
  addressing_.beginFrame(frame, returned, paired);
  std::vector<BusEvent> unjudged;
  onFrame(frame, bytes, addressing_, Stamp{frame_number, time_ns}, time_ns, unjudged);
}

void DcClock::onFrame(const EcatFrame& frame, const ByteReader& bytes,
                      const FrameAddressing& addressing, const Stamp& now, std::int64_t time_ns,
                      std::vector<BusEvent>& events) {
  const std::uint64_t frame_number = now.frame;
  // Most frames (the cyclic process data, a master copy of the DC time's read) hold nothing
  // followed here.
  bool any = false;
  for (std::size_t i = 0; i < frame.count && !any; ++i)
    any = followed(frame.datagrams[i], addressing);
  if (!any) return;

  // As the AL tracker takes them: writes from the master's copy (or a returned copy whose master
  // copy was not captured), reads from a returned copy some slave answered.
  const bool take_writes = addressing.takesWrites();
  for (std::size_t i = 0; i < frame.count; ++i) {
    const Datagram& dg = frame.datagrams[i];
    const SlaveAddress address = addressing.addressOf(dg, i);
    if (take_writes && ecat::writesRegisters(dg.command)) {
      directory_.noteStationWrite(dg, bytes, address);
      // A new system time offset moves the slave's system time: its drift is fitted again.
      if (registerAt(dg, kRegDcSystemTimeOffset, 4)) {
        for (auto& slave : directory_.slaves()) {
          const bool addressed =
              address.target == SlaveTarget::All ||
              (address.target == SlaveTarget::Station && slave.station == address.value) ||
              (address.target == SlaveTarget::Position && slave.position == address.value);
          if (addressed) {
            slave.data.fit = DriftFit{};
            slave.data.last_time.reset();
          }
        }
      }
    }
    if (!addressing.takesRead(dg)) continue;
    if (address.target != SlaveTarget::Station && address.target != SlaveTarget::Position) continue;
    const std::optional<std::size_t> time64 = registerAt(dg, kRegDcSystemTime, 8);
    const std::optional<std::size_t> time32 = time64 ? time64 : registerAt(dg, kRegDcSystemTime, 4);
    const std::optional<std::size_t> difference = registerAt(dg, kRegDcSystemTimeDifference, 4);
    if (!time32 && !difference) continue;
    const std::size_t s = directory_.slaveFor(address);
    if (s == directory_.kNone) continue;
    DcData& slave = directory_.slaves()[s].data;
    if (time64) {
      if (auto raw = bytes.le64(*time64)) onSystemTime(slave, *raw, true, time_ns);
    } else if (time32) {
      if (auto raw = bytes.le32(*time32)) onSystemTime(slave, *raw, false, time_ns);
    }
    if (time32 && distributesTime(dg.command)) slave.reference = true;
    if (difference) {
      if (auto raw = bytes.le32(*difference)) {
        DcDifferenceEvent event;
        event.previous_ns = slave.last_difference_ns;
        event.previous_frame = slave.last_difference_frame;
        event.smallest_before_ns = slave.min_abs_difference_ns;
        onDifference(slave, *raw, frame_number);
        event.slave = SlaveRef{directory_.slaves()[s].station, directory_.slaves()[s].position};
        event.difference_ns = *slave.last_difference_ns;
        events.push_back(BusEvent{now, event});
      }
    }
  }
}

void DcClock::startSegment() {
  for (auto& slave : directory_.slaves()) {
    slave.data.fit = DriftFit{};
    slave.data.last_time.reset();
  }
}

std::vector<DcStation> DcClock::stations() const {
  std::vector<DcStation> out;
  for (const auto& slave : directory_.slaves()) {
    const DcData& d = slave.data;
    if (!d.last_time && d.fit.samples() == 0 && d.difference_reads == 0 && !d.reference) continue;
    DcStation station;
    station.slave = SlaveRef{slave.station, slave.position};
    station.reference = d.reference;
    station.time_reads = d.fit.samples();
    station.drift_ppm = d.fit.driftPpm();
    station.drift_uncertainty_ppm = d.fit.driftUncertaintyPpm();
    station.first_half_ppm = d.fit.firstHalfPpm();
    station.second_half_ppm = d.fit.secondHalfPpm();
    station.difference_reads = d.difference_reads;
    station.last_difference_ns = d.last_difference_ns;
    station.max_abs_difference_ns = d.max_abs_difference_ns;
    station.settled_frame = d.settled_frame;
    out.push_back(station);
  }
  return out;
}

}  // namespace ncservo
