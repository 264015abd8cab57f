// What a capturing PC does to a recording (docs/simulate.md#the-capturing-pc): its clock stamps
// each record late, in steps, or at the end of the NIC's interrupt burst; a mirroring switch port
// hands it every record twice; its office port records beside the bus's. None of it is the bus:
// the frames, their bytes and the distributed clock's system time stay the bus's.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/sim/models.hpp"

namespace ncservo::sim {

// How the capturing PC's clock stamps a record (--capture-stamps SHAPE:LENGTH).
enum class StampShape : std::uint8_t {
  Exact,      // when the frame passed (no --capture-stamps)
  Bunched,    // the NIC coalesces interrupts: each record at the end of its burst window
  Quantised,  // a coarse clock: each stamp floored to a multiple of the quantum
  Late,       // interrupt moderation and scheduling: each stamp late by up to the length
};
struct StampShapeRow {
  const char* name;
  StampShape shape;
  const char* length_is;  // what the length is, for messages
  std::int64_t least_ns;  // the length's range
  std::int64_t most_ns;
  const char* summary;
};
inline constexpr StampShapeRow kStampShapes[] = {
    {.name = "bunched",
     .shape = StampShape::Bunched,
     .length_is = "a burst window",
     .least_ns = 100 * kUs,
     .most_ns = 100 * kMs,
     .summary = "each record stamped at the end of its burst window, a burst's records 2 us apart"},
    {.name = "quantised",
     .shape = StampShape::Quantised,
     .length_is = "a quantum",
     .least_ns = 1 * kUs,
     .most_ns = 100 * kMs,
     .summary = "each stamp floored to a multiple of the quantum"},
    {.name = "late",
     .shape = StampShape::Late,
     .length_is = "the most a stamp is late",
     .least_ns = 1 * kUs,
     .most_ns = 10 * kMs,
     .summary = "each stamp late by a random 0 to LENGTH, never before the one before it"},
};

// --capture-stamps as given: the shape and its length.
struct StampShaping {
  StampShape shape = StampShape::Exact;
  std::int64_t length_ns = 0;  // the burst window, the quantum or the most a stamp is late
  std::string text;            // as given, for messages
};
// "bunched:4ms", "quantised:1ms", "late:400us"; an error says what is wrong with the text.
Result<StampShaping> parseCaptureStamps(std::string_view text);

// A burst's records are this far apart in capture order, as a NIC's coalesced interrupt hands
// them over one after the other.
inline constexpr std::int64_t kBurstSpacingNs = 2 * kUs;
// A mirrored copy reaches the PC this long after its original (docs/simulate.md).
inline constexpr std::int64_t kDuplicateLagNs = 1 * kUs;

// The capturing PC's clock: the stamp of each record in capture order, a pure function of the
// records' times so far and the seed. Its stamps never go back, as a PC's do not.
class CaptureClock {
 public:
  CaptureClock(const StampShaping& stamps, std::uint64_t seed);
  // The stamp of the next record, which passed the capture point at `passed_ns`.
  std::int64_t stamp(std::int64_t passed_ns);
  // The stamp of the mirrored copy of the record just stamped `original_ns`: 1 us later, or the
  // same when the clock is too coarse to tell them apart (quantised).
  std::int64_t duplicate(std::int64_t original_ns);

 private:
  std::int64_t shaped(std::int64_t passed_ns);
  std::int64_t kept(std::int64_t stamp_ns);

  StampShaping stamps_;
  Rng late_;
  std::int64_t burst_ = -1;    // the burst window of the last record (Bunched)
  std::int64_t in_burst_ = 0;  // records stamped in it so far
  std::int64_t last_ns_ = 0;   // the last stamp given
};

// The office port of the capturing PC (--second-interface): ARP and UDP of the PC and its
// neighbours on the office network, as Linux cooked (SLL) records, a few hundred a second, each
// a pure function of the seed.
class OfficePort {
 public:
  explicit OfficePort(std::uint64_t seed);
  // The port's first record comes after `from_ns` (the bus capture's first record).
  void start(std::int64_t from_ns);
  bool started() const { return started_; }
  // The next record: its time and its bytes (SLL header, then ARP or IPv4/UDP).
  std::int64_t nextAt() const { return next_ns_; }
  const std::vector<std::uint8_t>& nextBytes() const { return bytes_; }
  // Draws the record after it.
  void advance();

 private:
  void arp();
  void udp();
  void cooked(std::uint16_t packet_type, const std::uint8_t* source_mac, std::uint16_t protocol);

  Rng rng_;
  bool started_ = false;
  std::int64_t next_ns_ = 0;
  std::uint16_t ip_id_ = 0;
  std::vector<std::uint8_t> bytes_;
};

}  // namespace ncservo::sim
