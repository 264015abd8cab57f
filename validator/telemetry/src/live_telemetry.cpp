#include "ncservo/telemetry/live_telemetry.hpp"

#include <fmt/format.h>

namespace ncservo {

LiveTelemetry::LiveTelemetry(const RuleSettings& settings, std::chrono::milliseconds mqtt_flush)
    : metrics_(settings), mqtt_flush_(mqtt_flush) {}

Result<std::unique_ptr<LiveTelemetry>> LiveTelemetry::start(const TelemetryOptions& options,
                                                            const RuleSettings& settings) {
  if (!options.metrics && !options.mqtt) return nullptr;
  std::unique_ptr<LiveTelemetry> telemetry(new LiveTelemetry(settings, options.mqtt_flush));
  // The first scrape already has every family (zeros until the layout is known).
  telemetry->board_.publish(telemetry->metrics_.snapshot());
  if (options.metrics) {
    auto server = MetricsServer::start(*options.metrics, telemetry->board_);
    if (!server) return fail(server.error());
    telemetry->server_ = std::move(*server);
  }
  if (options.mqtt) {
    auto publisher = MqttPublisher::start(*options.mqtt);
    if (!publisher) return fail(publisher.error());
    telemetry->mqtt_ = std::move(*publisher);
  }
  return telemetry;
}

void LiveTelemetry::onFrame(const Validator& validator, const report::CaptureReport& report) {
  if (server_) metrics_.onFrame(validator);
  if (!mqtt_) return;
  for (const DriveMessage& m : validator.mailbox().frameMessages()) {
    mqtt_->publish(MqttTopic::DriveMessage, report::driveMessageJsonLine(report, m));
  }
  for (const LinkFault& f : validator.escErrors().frameLinkFaults()) {
    mqtt_->publish(MqttTopic::LinkFault, report::linkFaultJsonLine(report, f));
  }
}

void LiveTelemetry::onFindings(const std::vector<Finding>& findings,
                               const report::CaptureReport& report) {
  metrics_.onFindings(findings);
  if (!mqtt_) return;
  for (const Finding& f : findings) {
    mqtt_->publish(MqttTopic::Finding,
                   report::findingJsonLine(report, f, report::BaselineState::None));
  }
}

// An incident's object is final once it ended (its recovery known) and its cause is (a read of
// the links' counters can still make it link-fault); the rest wait for the end.
void LiveTelemetry::publishIncidents(const std::vector<Incident>& incidents,
                                     const report::CaptureReport& report, bool all,
                                     const IncidentDetector* detector) {
  if (!mqtt_) return;
  if (incident_published_.size() < incidents.size()) incident_published_.resize(incidents.size());
  report::CaptureReport lent;  // incidentJsonLine reads a report's incidents: this one's copy
  for (std::size_t i = 0; i < incidents.size(); ++i) {
    if (incident_published_[i]) continue;
    if (!all && !(incidents[i].ended && detector->causeFinal(i))) continue;
    if (lent.incidents.empty()) {
      lent.path = report.path;
      lent.timestamp_digits = report.timestamp_digits;
      lent.first_time_ns = report.first_time_ns;
      lent.layout = report.layout;
      lent.incidents = incidents;
    }
    mqtt_->publish(MqttTopic::Incident, report::incidentJsonLine(lent, i));
    incident_published_[i] = true;
  }
}

void LiveTelemetry::update(const CapturePipeline& pipeline, const report::CaptureReport& report,
                           std::uint64_t frames, std::uint64_t capture_dropped) {
  if (const IncidentDetector* detector = pipeline.incidents()) {
    publishIncidents(detector->incidents(), report, false, detector);
  }
  if (!server_) return;
  metrics_.refresh(pipeline, frames, capture_dropped);
  if (mqtt_) metrics_.setMqttDropped(mqtt_->dropped());
  // A scrape holding the board: this snapshot is skipped, the next update's goes.
  static_cast<void>(board_.tryPublish(metrics_.snapshot()));
}

std::vector<std::string> LiveTelemetry::finish(const CapturePipeline& pipeline,
                                               const report::CaptureReport& report,
                                               std::uint64_t frames,
                                               std::uint64_t capture_dropped) {
  std::vector<std::string> said;
  publishIncidents(report.incidents, report, true, nullptr);
  if (mqtt_) {
    const std::size_t left = mqtt_->finish(mqtt_flush_);
    if (left > 0) {
      said.push_back(
          fmt::format("--mqtt: {} messages not acknowledged by the broker at the end", left));
    }
    if (const std::uint64_t dropped = mqtt_->dropped(); dropped > 0) {
      said.push_back(
          fmt::format("--mqtt: {} messages dropped, the oldest first (queue full)", dropped));
    }
  }
  if (server_) {
    metrics_.refresh(pipeline, frames, capture_dropped);
    if (mqtt_) metrics_.setMqttDropped(mqtt_->dropped());
    board_.publish(metrics_.snapshot());
  }
  return said;
}

std::vector<std::string> LiveTelemetry::notes() {
  return mqtt_ ? mqtt_->notes() : std::vector<std::string>{};
}

std::optional<int> LiveTelemetry::metricsPort() const {
  return server_ ? std::optional<int>(server_->port()) : std::nullopt;
}
std::uint64_t LiveTelemetry::scrapes() const {
  return server_ ? server_->scrapes() : 0;
}
double LiveTelemetry::scrapeSeconds() const {
  return server_ ? server_->scrapeSeconds() : 0;
}

}  // namespace ncservo
