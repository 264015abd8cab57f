// What `monitor` hands to a plant's own systems while it captures (docs/field.md#metrics,
// #mqtt): the metrics a Prometheus server scrapes, and the findings and incidents published over
// MQTT. Driven by the capture thread; neither face ever makes it wait.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"
#include "ncservo/report/report.hpp"
#include "ncservo/telemetry/live_metrics.hpp"
#include "ncservo/telemetry/metrics_server.hpp"
#include "ncservo/telemetry/mqtt_publisher.hpp"

namespace ncservo {

struct TelemetryOptions {
  std::optional<ListenAddress> metrics;
  std::optional<MqttOptions> mqtt;
  // How long the end of the capture waits for the broker to acknowledge what is queued.
  std::chrono::milliseconds mqtt_flush{5000};
};

class LiveTelemetry {
 public:
  // Nothing to do (no --metrics, no --mqtt): null. Fails when the port cannot be bound or the
  // MQTT options are wrong; a broker not there yet is no error (it is tried again).
  static Result<std::unique_ptr<LiveTelemetry>> start(const TelemetryOptions& options,
                                                      const RuleSettings& settings);

  // A frame delivered and judged: the metrics, and what the drives and ESCs said in it to MQTT
  // (docs/drive-messages.md), as JSON Lines objects of `report`'s capture.
  void onFrame(const Validator& validator, const report::CaptureReport& report);
  // The findings of a frame, as `report` names them.
  void onFindings(const std::vector<Finding>& findings, const report::CaptureReport& report);
  // Now and then (every 100 ms of the capture loop): the gauges and totals refreshed and handed
  // to the scrapes, the incidents that ended published. `report` lends its names and clock.
  void update(const CapturePipeline& pipeline, const report::CaptureReport& report,
              std::uint64_t frames, std::uint64_t capture_dropped);
  // The capture ended and `report` holds its result: the incidents not yet published, the last
  // snapshot, the queue given time to drain. Returns what to say (messages left, dropped).
  std::vector<std::string> finish(const CapturePipeline& pipeline,
                                  const report::CaptureReport& report, std::uint64_t frames,
                                  std::uint64_t capture_dropped);
  // Lines to print (the broker connected or lost, the queue dropping), since the last call.
  std::vector<std::string> notes();
  // The port --metrics listens on (the system's pick for 0); none without --metrics.
  std::optional<int> metricsPort() const;
  // Scrapes answered and the time spent formatting them.
  std::uint64_t scrapes() const;
  double scrapeSeconds() const;

 private:
  LiveTelemetry(const RuleSettings& settings, std::chrono::milliseconds mqtt_flush);
  // `detector`: whose causes are final (null with `all`: every one is).
  void publishIncidents(const std::vector<Incident>& incidents, const report::CaptureReport& report,
                        bool all, const IncidentDetector* detector);

  LiveMetrics metrics_;
  MetricsBoard board_;
  std::unique_ptr<MetricsServer> server_;
  std::unique_ptr<MqttPublisher> mqtt_;
  std::chrono::milliseconds mqtt_flush_;
  std::vector<bool> incident_published_;  // by index in the detector's incidents
};

}  // namespace ncservo
