// `monitor --metrics` (docs/field.md#metrics): the live monitor's counters and gauges, named from
// the tables they count (the rule table, the drive states, the cause rows, the clock rows), kept
// by the capture thread and handed to the scrapes as a snapshot, so that a scrape never waits
// for a frame and a frame never waits for a scrape.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/incidents/incident.hpp"
#include "ncservo/model/capture_clock.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"
#include "ncservo/protocol/drive_state.hpp"
#include "ncservo/rules/finding.hpp"
#include "ncservo/rules/rules.hpp"

namespace ncservo {

// Every metric's name starts so (INTERFACES.md "Live telemetry").
inline constexpr const char* kMetricPrefix = "ncservo_";

// The cycle-time histogram's buckets: for each common nominal cycle of 125 µs to 10 ms, the
// bounds 0.9 and 1.1 of it (a cycle on time lies between them) and 1.5 of it (beyond, COM-002
// judges a gap). Seconds, ascending.
inline constexpr std::array<int, 9> kCycleNominalsUs{125,  250,  500,  1000, 2000,
                                                     4000, 5000, 8000, 10000};
inline constexpr std::array<int, 3> kCycleBucketTenths{9, 11, 15};  // of the nominal cycle
inline constexpr std::size_t kCycleBucketCount =
    kCycleNominalsUs.size() * kCycleBucketTenths.size();
// The return-latency histogram's buckets: 1, 2 and 5 of each decade from 1 µs to 10 ms.
inline constexpr std::size_t kLatencyBucketCount = 13;
extern const std::array<double, kCycleBucketCount> kCycleBuckets;
extern const std::array<double, kLatencyBucketCount> kLatencyBuckets;

// A histogram over fixed bounds, one count per bucket (not cumulative) and one past the last.
template <std::size_t N>
struct FixedHistogram {
  const std::array<double, N>* bounds;
  std::array<std::uint64_t, N + 1> counts{};
  double sum = 0;
  void observe(double seconds);
};

// A slave's system time difference (0x092C), the last read.
struct DcDifference {
  std::uint16_t station = 0;
  double seconds = 0;
};
// The rises of one ESC error counter of one port of a slave (docs/drive-messages.md).
struct EscErrorCount {
  std::uint16_t station = 0;
  std::uint8_t port = 0;
  std::string counter;  // the counter's name, from the ESC register table
  std::uint64_t count = 0;
};

// Everything one scrape shows: plain values, copied whole.
struct MetricsSnapshot {
  std::uint64_t frames = 0;
  std::uint64_t capture_dropped = 0;
  std::uint64_t lost_cycles = 0;
  std::uint64_t wkc_errors = 0;
  std::optional<ClockSource> clock;
  FixedHistogram<kCycleBucketCount> cycle{&kCycleBuckets};
  FixedHistogram<kLatencyBucketCount> latency{&kLatencyBuckets};
  struct Axis {
    std::string name;
    std::optional<DriveState> state;
    std::uint32_t telegram_failures = 0;
    std::array<std::uint64_t, kRuleCount> findings{};
    std::array<std::uint64_t, kCauseCount> incidents{};
  };
  std::vector<Axis> axes;  // by axis index
  // Findings and incidents of no axis (the bus, a slave that is no axis).
  std::array<std::uint64_t, kRuleCount> bus_findings{};
  std::array<std::uint64_t, kCauseCount> bus_incidents{};
  std::array<bool, kRuleCount> enabled{};
  std::array<Severity, kRuleCount> severity{};
  std::vector<DcDifference> dc;
  std::vector<EscErrorCount> esc;  // the ESC counters' rises (docs/drive-messages.md)
  std::uint64_t mqtt_dropped = 0;  // monitor --mqtt: messages the full queue dropped
};

// The snapshot in Prometheus' text format: every family, its series bounded by the tables (rules
// × axes, states × axes, causes × axes), never by the frames.
std::string exposeMetrics(const MetricsSnapshot& snapshot);

// The capture thread's side: counts what it judges, frame by frame.
class LiveMetrics {
 public:
  explicit LiveMetrics(const RuleSettings& settings);
  // A frame the pipeline delivered, after the validator judged it: its cycle interval and
  // return latency.
  void onFrame(const Validator& validator);
  void onFindings(const std::vector<Finding>& findings);
  // The gauges and running totals as they are now (axis states, telegram failures, the clock,
  // lost cycles, incidents so far, DC): before each publish, not each frame.
  void refresh(const CapturePipeline& pipeline, std::uint64_t frames,
               std::uint64_t capture_dropped);
  void setMqttDropped(std::uint64_t dropped) { snapshot_.mqtt_dropped = dropped; }
  const MetricsSnapshot& snapshot() const { return snapshot_; }

 private:
  MetricsSnapshot::Axis& axis(std::uint16_t index);
  MetricsSnapshot snapshot_;
  std::size_t incidents_counted_ = 0;
};

// The snapshot the scrapes read, handed over under a short lock.
class MetricsBoard {
 public:
  // The capture thread's: never waits; false when a scrape held the lock (try again later).
  bool tryPublish(const MetricsSnapshot& snapshot);
  // Waits for the lock: at the end of the capture.
  void publish(const MetricsSnapshot& snapshot);
  // A scrape's: the last snapshot, formatted outside the lock.
  std::string scrape() const;

 private:
  mutable std::mutex mutex_;
  MetricsSnapshot published_;
};

}  // namespace ncservo
