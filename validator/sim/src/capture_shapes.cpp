// The capturing PC's clock and office port (capture_shapes.hpp, docs/simulate.md#the-capturing-pc).
#include "ncservo/sim/capture_shapes.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "ncservo/base/number.hpp"
#include "ncservo/wire/ecat_wire.hpp"

namespace ncservo::sim {
namespace {

constexpr std::uint64_t kLateSeedSalt = 0x1A7E5EEDULL;
constexpr std::uint64_t kOfficeSeedSalt = 0x0FF1CEULL;

std::string lengthText(std::int64_t ns) {
  return ns % kMs == 0 ? fmt::format("{} ms", ns / kMs) : fmt::format("{} us", ns / kUs);
}

// "400us", "4ms", "0.5ms": a whole number of microseconds, in ns.
std::optional<std::int64_t> parseLength(std::string_view text) {
  std::int64_t unit_ns = 0;
  if (text.ends_with("us")) unit_ns = kUs;
  if (text.ends_with("ms")) unit_ns = kMs;
  if (unit_ns == 0) return std::nullopt;
  const Result<double> value = parseNumber<double>(text.substr(0, text.size() - 2));
  if (!value || !(*value >= 0) || *value > 1e9) return std::nullopt;
  const double ns = *value * static_cast<double>(unit_ns);
  const auto whole_us = static_cast<std::int64_t>(std::llround(ns / kUs));
  if (std::abs(ns - static_cast<double>(whole_us * kUs)) > 0.5) return std::nullopt;
  return whole_us * kUs;
}

// --- the office network (docs/simulate.md#the-capturing-pc) ---

// Linux cooked capture v1 (LINKTYPE_LINUX_SLL): packet type, ARPHRD type, address length, the
// sender's address in 8 bytes, protocol; all big-endian.
constexpr std::uint16_t kSllToUs = 0, kSllBroadcast = 1, kSllOutgoing = 4;
constexpr std::uint16_t kArphrdEther = 1;
constexpr std::uint16_t kEtherTypeArp = 0x0806;
constexpr std::size_t kMacSize = 6;
// The PC (an Intel NIC's OUI) and its neighbours, 192.168.10.0/24.
constexpr std::array<std::uint8_t, kMacSize> kPcMac{0x00, 0x1B, 0x21, 0x3A, 0x4C, 0x10};
constexpr std::array<std::uint8_t, 4> kOfficeNet{192, 168, 10, 0};
constexpr std::uint8_t kPcHost = 10;
constexpr int kNeighbours = 6;
// A few hundred records a second: each 0.5 to 7 ms after the one before.
constexpr std::int64_t kLeastGapUs = 500, kMostGapUs = 7000;
// UDP between the PC and its neighbours on ports no stock dissector claims.
constexpr std::uint16_t kLeastPort = 40000, kMostPort = 40099;

void appendBe(std::vector<std::uint8_t>& out, std::uint64_t value, std::size_t count) {
  for (std::size_t i = count; i-- > 0;) out.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
}
std::array<std::uint8_t, kMacSize> neighbourMac(int host) {
  return {0x00, 0x0C, 0x29, 0x00, 0x10, static_cast<std::uint8_t>(host)};
}
std::array<std::uint8_t, 4> hostIp(int host) {
  return {kOfficeNet[0], kOfficeNet[1], kOfficeNet[2], static_cast<std::uint8_t>(host)};
}
// The IPv4 header checksum (RFC 791): the ones' complement of the ones' complement sum.
std::uint16_t ipv4Checksum(const std::uint8_t* header, std::size_t size) {
  std::uint32_t sum = 0;
  for (std::size_t i = 0; i + 1 < size; i += 2) sum += (header[i] << 8) | header[i + 1];
  while (sum > 0xFFFF) sum = (sum & 0xFFFF) + (sum >> 16);
  return static_cast<std::uint16_t>(~sum);
}

}  // namespace

Result<StampShaping> parseCaptureStamps(std::string_view text) {
  auto malformed = [&] {
    return fail(fmt::format(
        "--capture-stamps {}: expected SHAPE:LENGTH, SHAPE bunched, quantised or late and LENGTH "
        "in us or ms, e.g. bunched:4ms",
        text));
  };
  const std::size_t colon = text.find(':');
  if (colon == std::string_view::npos) return malformed();
  const std::string_view name = text.substr(0, colon);
  const auto row = std::find_if(std::begin(kStampShapes), std::end(kStampShapes),
                                [&](const StampShapeRow& r) { return name == r.name; });
  if (row == std::end(kStampShapes)) {
    return fail(
        fmt::format("--capture-stamps {}: no shape '{}' (bunched, quantised or late)", text, name));
  }
  const std::optional<std::int64_t> length = parseLength(text.substr(colon + 1));
  if (!length) return malformed();
  if (*length < row->least_ns || *length > row->most_ns) {
    return fail(fmt::format("--capture-stamps {}: {} from {} to {}", text, row->length_is,
                            lengthText(row->least_ns), lengthText(row->most_ns)));
  }
  return StampShaping{row->shape, *length, std::string(text)};
}

// --- the clock ---

CaptureClock::CaptureClock(const StampShaping& stamps, std::uint64_t seed)
    : stamps_(stamps), late_(seed ^ kLateSeedSalt) {}

std::int64_t CaptureClock::shaped(std::int64_t passed_ns) {
  const std::int64_t length = stamps_.length_ns;
  switch (stamps_.shape) {
    case StampShape::Exact:
      return passed_ns;
    case StampShape::Bunched: {
      const std::int64_t burst = passed_ns / length;  // capture times are after the epoch
      if (burst != burst_) {
        burst_ = burst;
        in_burst_ = 0;
      }
      return (burst + 1) * length + kBurstSpacingNs * in_burst_++;
    }
    case StampShape::Quantised:
      return passed_ns / length * length;
    case StampShape::Late:  // in whole microseconds, so a pcap keeps every stamp as drawn
      return passed_ns + late_.between(0, length / kUs) * kUs;
  }
  return passed_ns;
}

std::int64_t CaptureClock::kept(std::int64_t stamp_ns) {
  last_ns_ = std::max(last_ns_, stamp_ns);
  return last_ns_;
}

std::int64_t CaptureClock::stamp(std::int64_t passed_ns) {
  return kept(shaped(passed_ns));
}

std::int64_t CaptureClock::duplicate(std::int64_t original_ns) {
  return kept(stamps_.shape == StampShape::Quantised ? original_ns : original_ns + kDuplicateLagNs);
}

// --- the office port ---

OfficePort::OfficePort(std::uint64_t seed) : rng_(seed ^ kOfficeSeedSalt) {}

void OfficePort::start(std::int64_t from_ns) {
  started_ = true;
  next_ns_ = from_ns / kUs * kUs;
  advance();
}

void OfficePort::advance() {
  next_ns_ += rng_.between(kLeastGapUs, kMostGapUs) * kUs;
  if (rng_.uniform() < 0.25) {
    arp();
  } else {
    udp();
  }
}

void OfficePort::cooked(std::uint16_t packet_type, const std::uint8_t* source_mac,
                        std::uint16_t protocol) {
  bytes_.clear();
  appendBe(bytes_, packet_type, 2);
  appendBe(bytes_, kArphrdEther, 2);
  appendBe(bytes_, kMacSize, 2);
  bytes_.insert(bytes_.end(), source_mac, source_mac + kMacSize);
  bytes_.resize(bytes_.size() + 2, 0);  // the address field's 8 bytes
  appendBe(bytes_, protocol, 2);
}

// A neighbour asks, by broadcast, who has another address (RFC 826).
void OfficePort::arp() {
  const int sender = static_cast<int>(rng_.between(1, kNeighbours));
  const int target = static_cast<int>(rng_.between(1, kNeighbours + 1));
  const auto mac = neighbourMac(sender);
  cooked(kSllBroadcast, mac.data(), kEtherTypeArp);
  appendBe(bytes_, kArphrdEther, 2);
  appendBe(bytes_, ecat::kEtherTypeIpv4, 2);
  bytes_.push_back(kMacSize);
  bytes_.push_back(4);
  appendBe(bytes_, 1, 2);  // request
  bytes_.insert(bytes_.end(), mac.begin(), mac.end());
  const auto sender_ip = hostIp(sender);
  bytes_.insert(bytes_.end(), sender_ip.begin(), sender_ip.end());
  bytes_.resize(bytes_.size() + kMacSize, 0);
  const auto target_ip = hostIp(target == kNeighbours + 1 ? kPcHost : target);
  bytes_.insert(bytes_.end(), target_ip.begin(), target_ip.end());
}

// A UDP datagram the PC sends a neighbour, a neighbour sends the PC, or a neighbour broadcasts.
void OfficePort::udp() {
  const int neighbour = static_cast<int>(rng_.between(1, kNeighbours));
  const auto mac = neighbourMac(neighbour);
  const int direction = static_cast<int>(rng_.between(0, 2));
  const std::uint16_t packet_type = direction == 0   ? kSllOutgoing
                                    : direction == 1 ? kSllToUs
                                                     : kSllBroadcast;
  cooked(packet_type, direction == 0 ? kPcMac.data() : mac.data(), ecat::kEtherTypeIpv4);
  const std::array<std::uint8_t, 4> source = hostIp(direction == 0 ? kPcHost : neighbour);
  const std::array<std::uint8_t, 4> destination =
      direction == 0 ? hostIp(neighbour)
      : direction == 1
          ? hostIp(kPcHost)
          : std::array<std::uint8_t, 4>{kOfficeNet[0], kOfficeNet[1], kOfficeNet[2], 255};
  const auto payload = static_cast<std::size_t>(rng_.between(16, 300));
  const std::size_t ip_at = bytes_.size();
  const std::size_t total = ecat::kIpv4MinHeaderSize + ecat::kUdpHeaderSize + payload;
  bytes_.push_back(0x45);  // IPv4, 5 words of header
  bytes_.push_back(0);
  appendBe(bytes_, total, 2);
  appendBe(bytes_, ++ip_id_, 2);
  appendBe(bytes_, 0x4000, 2);                  // don't fragment
  bytes_.push_back(direction == 0 ? 128 : 64);  // TTL: the PC's Windows, the neighbours' Linux
  bytes_.push_back(ecat::kIpProtoUdp);
  appendBe(bytes_, 0, 2);  // the checksum, below
  bytes_.insert(bytes_.end(), source.begin(), source.end());
  bytes_.insert(bytes_.end(), destination.begin(), destination.end());
  const std::uint16_t checksum = ipv4Checksum(&bytes_[ip_at], ecat::kIpv4MinHeaderSize);
  bytes_[ip_at + 10] = static_cast<std::uint8_t>(checksum >> 8);
  bytes_[ip_at + 11] = static_cast<std::uint8_t>(checksum);
  appendBe(bytes_, static_cast<std::uint64_t>(rng_.between(kLeastPort, kMostPort)), 2);
  appendBe(bytes_, static_cast<std::uint64_t>(rng_.between(kLeastPort, kMostPort)), 2);
  appendBe(bytes_, ecat::kUdpHeaderSize + payload, 2);
  appendBe(bytes_, 0, 2);  // no checksum (RFC 768 allows it over IPv4)
  for (std::size_t i = 0; i < payload; ++i)
    bytes_.push_back(static_cast<std::uint8_t>(rng_.next()));
}

}  // namespace ncservo::sim
