// Distributed clocks as the capture shows them (docs/timing.md "Distributed clocks"). Numbers
// only; the reports present them.
//
// - Reads of a slave's system time (0x0910, 64 bits or 32) against the frame's timestamp: the
//   drift of that clock against the capture's clock, by a least-squares fit of
//   (system time − frame time) over frame time. The reference clock is the slave whose system
//   time the master reads with FRMW/ARMW (and writes into the others). The trend is the drift
//   of the first and of the second half of the fit's time span.
// - Reads of a slave's system time difference (0x092C): the last, the largest magnitude, and the
//   frame from which every later read stayed within a bound (`dc_settled_ns`).
//
// Only returned copies of physical reads (FPRD, APRD, FRMW, ARMW, and FPRW/APRW) some slave
// answered (WKC > 0) count; a broadcast read is the OR of every slave's and names none. Slaves
// are named as the AL tracker names them (slave_directory.hpp). Bounded memory: at most
// SlaveDirectory::kMaxSlaves slaves, each with a fixed number of fit blocks.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/model/bus_events.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "ncservo/wire/slave_directory.hpp"

namespace ncservo {

// 0x092C's sign and magnitude as a signed difference: the local copy of the system time minus
// the system time received (negative when bit 31 is set).
std::int64_t systemTimeDifferenceNs(std::uint32_t raw);

// Running sums of a least-squares line fit y = a + b·x; sums of two fits add.
struct LineFit {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  void add(double x, double y);
  void merge(const LineFit& other);
  // The slope b; none for fewer than two distinct x.
  std::optional<double> slope() const;
  // The slope's standard error, from the scatter of the points about the line; none for fewer
  // than three points at distinct x.
  std::optional<double> slopeStandardError() const;
};

// A clock's drift against the frame timestamps, from samples (frame time, clock time). The
// samples' span is cut into kBlocks blocks of equal duration, which double (merging pairs) when
// a sample lies beyond the last, so that both halves of the span have a fit of their own.
class DriftFit {
 public:
  static constexpr std::size_t kBlocks = 8;
  static constexpr std::int64_t kFirstBlockNs = 10'000'000;  // 10 ms, doubled as needed

  void add(std::int64_t frame_ns, std::uint64_t clock_ns);
  std::uint64_t samples() const { return samples_; }
  // Positive when the clock runs faster than the frame timestamps; none for fewer than two
  // samples at distinct times (or a half with fewer).
  std::optional<double> driftPpm() const;
  // Half the width of the drift's 95 % confidence interval (1.96 standard errors of the whole
  // fit's slope): how far the stamps' jitter leaves the drift open (docs/timing.md#drift).
  std::optional<double> driftUncertaintyPpm() const;
  std::optional<double> firstHalfPpm() const;
  std::optional<double> secondHalfPpm() const;

 private:
  std::optional<double> ppmOf(std::size_t from_block, std::size_t to_block) const;

  std::uint64_t samples_ = 0;
  std::int64_t first_frame_ns_ = 0;
  std::uint64_t first_clock_ns_ = 0;
  std::int64_t block_ns_ = kFirstBlockNs;
  std::size_t used_blocks_ = 0;  // blocks up to the last with a sample
  std::array<LineFit, kBlocks> blocks_{};
};

// What the capture showed of one slave's distributed clock.
struct DcStation {
  SlaveRef slave;
  bool reference = false;        // its system time was read with FRMW/ARMW
  std::uint64_t time_reads = 0;  // system time reads in the current fit
  std::optional<double> drift_ppm, first_half_ppm, second_half_ppm;
  std::optional<double> drift_uncertainty_ppm;  // ± at 95 %
  std::uint64_t difference_reads = 0;           // 0x092C reads
  std::optional<std::int64_t> last_difference_ns;
  std::int64_t max_abs_difference_ns = 0;
  // The first of the reads from which every later one stayed within the bound.
  std::optional<std::uint64_t> settled_frame;
};

class DcClock {
 public:
  explicit DcClock(std::int64_t settled_ns) : settled_ns_(settled_ns) {}

  // Every EtherCAT frame, in capture order, with its frame number and timestamp. `paired` as
  // AlTracker::onFrame takes it.
  void onFrame(const EcatFrame& frame, const ByteReader& bytes, bool returned, bool paired,
               std::uint64_t frame_number, std::int64_t time_ns);
  // The same, with the frame's addressing worked out once for every tracker (Ok or Truncated
  // frames only, `addressing.beginFrame` called for each of them); each 0x092C read appends a
  // DcDifferenceEvent (DC-001) to `events`.
  void onFrame(const EcatFrame& frame, const ByteReader& bytes, const FrameAddressing& addressing,
               const Stamp& now, std::int64_t time_ns, std::vector<BusEvent>& events);
  // A capture segment starts (capture_segments.hpp): the drift fits start again; the system
  // time differences, which need no clock of the capture, carry on.
  void startSegment();

  std::int64_t settledNs() const { return settled_ns_; }
  // The slaves with a system time or a system time difference read, in the order first seen.
  std::vector<DcStation> stations() const;

 private:
  struct DcData {
    bool reference = false;
    DriftFit fit;
    std::optional<std::uint64_t> last_time;  // the last system time read (32-bit reads unwrap)
    std::uint64_t difference_reads = 0;
    std::optional<std::int64_t> last_difference_ns;
    std::uint64_t last_difference_frame = 0;
    std::int64_t max_abs_difference_ns = 0;
    std::optional<std::int64_t> min_abs_difference_ns;
    std::optional<std::uint64_t> settled_frame;
    void absorb(const DcData& other);
  };

  void onSystemTime(DcData& slave, std::uint64_t raw, bool is_64_bit, std::int64_t time_ns);
  void onDifference(DcData& slave, std::uint32_t raw, std::uint64_t frame_number);

  std::int64_t settled_ns_;
  SlaveDirectory<DcData> directory_;
  FrameAddressing addressing_;  // for frames given with `returned` and `paired`
};

}  // namespace ncservo
