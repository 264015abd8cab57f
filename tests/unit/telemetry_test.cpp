// `monitor --metrics` and `--mqtt` (docs/field.md#metrics, #mqtt): the exposition writer, the
// histograms' buckets as docs/field.md lists them, the metrics of a bundled capture against its
// report, the HTTP face, and the addresses the options take.
#include <gtest/gtest.h>
#include <httplib.h>

#include <algorithm>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "ncservo/capture/capture_stream.hpp"
#include "ncservo/config/config.hpp"
#include "ncservo/incidents/causes.hpp"
#include "ncservo/telemetry/exposition.hpp"
#include "ncservo/telemetry/live_metrics.hpp"
#include "ncservo/telemetry/metrics_server.hpp"
#include "ncservo/telemetry/mqtt_publisher.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

TEST(Exposition, CounterWithEscapedLabels) {
  Exposition out;
  out.family("ncservo_x_total", MetricType::Counter, "a \\ help\nline");
  out.sample({{"a", "q\"uote"}, {"b", "back\\slash\nfeed"}}, std::uint64_t{7});
  out.sample({}, 0.25);
  EXPECT_EQ(out.text(),
            "# HELP ncservo_x_total a \\\\ help\\nline\n"
            "# TYPE ncservo_x_total counter\n"
            "ncservo_x_total{a=\"q\\\"uote\",b=\"back\\\\slash\\nfeed\"} 7\n"
            "ncservo_x_total 0.25\n");
}

TEST(Exposition, HistogramIsCumulativeWithInf) {
  const std::array<double, 2> bounds{0.001, 0.002};
  const std::array<std::uint64_t, 3> counts{1, 2, 4};
  Exposition out;
  out.family("h_seconds", MetricType::Histogram, "h");
  out.histogram({{"axis", "x"}}, {bounds, counts, 0.5});
  EXPECT_EQ(out.text(),
            "# HELP h_seconds h\n"
            "# TYPE h_seconds histogram\n"
            "h_seconds_bucket{axis=\"x\",le=\"0.001\"} 1\n"
            "h_seconds_bucket{axis=\"x\",le=\"0.002\"} 3\n"
            "h_seconds_bucket{axis=\"x\",le=\"+Inf\"} 7\n"
            "h_seconds_sum{axis=\"x\"} 0.5\n"
            "h_seconds_count{axis=\"x\"} 7\n");
}

// docs/field.md#metrics lists them: 0.9, 1.1 and 1.5 of 125, 250, 500 µs, 1, 2, 4, 5, 8, 10 ms.
TEST(MetricBuckets, CycleAsDocumented) {
  const std::vector<double> us{112.5, 137.5, 187.5, 225,  275,  375,  450,   550,   750,
                               900,   1100,  1500,  1800, 2200, 3000, 3600,  4400,  4500,
                               5500,  6000,  7200,  7500, 8800, 9000, 11000, 12000, 15000};
  ASSERT_EQ(kCycleBuckets.size(), us.size());
  for (std::size_t i = 0; i < us.size(); ++i) {
    EXPECT_EQ(exposedNumber(kCycleBuckets[i]), exposedNumber(us[i] / 1e6)) << i;
  }
}

TEST(MetricBuckets, LatencyAsDocumented) {
  const std::vector<double> us{1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000};
  ASSERT_EQ(kLatencyBuckets.size(), us.size());
  for (std::size_t i = 0; i < us.size(); ++i) EXPECT_DOUBLE_EQ(kLatencyBuckets[i], us[i] / 1e6);
}

TEST(MetricBuckets, SampleOnABoundCountsInIt) {
  FixedHistogram<kLatencyBucketCount> h{&kLatencyBuckets};
  h.observe(2e-6);    // le="2e-06"
  h.observe(2.5e-6);  // le="5e-06"
  h.observe(0.5);     // +Inf
  EXPECT_EQ(h.counts[1], 1u);
  EXPECT_EQ(h.counts[2], 1u);
  EXPECT_EQ(h.counts[kLatencyBucketCount], 1u);
  EXPECT_DOUBLE_EQ(h.sum, 2e-6 + 2.5e-6 + 0.5);
}

// The samples of one family, by their labels ("{...}" as written), from an exposition.
std::map<std::string, std::string> samples(const std::string& text, const std::string& family) {
  std::map<std::string, std::string> out;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind(family, 0) != 0) continue;
    const std::size_t space = line.rfind(' ');
    const std::string series = line.substr(family.size(), space - family.size());
    if (!series.empty() && series[0] != '{') continue;  // another family sharing the prefix
    out[series] = line.substr(space + 1);
  }
  return out;
}

// The metrics of sim-incidents-4axis (faults, incidents, lost cycles, a wrong WKC) fed as the
// monitor feeds them, against the capture's own result: the same counts.
TEST(LiveMetrics, BundledCaptureAgreesWithItsResult) {
  auto reader =
      CaptureReader::open(std::string(NCSERVO_CAPTURES_DIR) + "/sim-incidents-4axis.pcap");
  ASSERT_TRUE(reader) << reader.error().text();
  const RuleSettings settings;
  CapturePipeline pipeline(
      {layoutOptions(nullptr, nullptr, true), settings, TimeWindow{}, TimestampMode::Auto});
  LiveMetrics metrics(settings);
  std::map<std::pair<std::string, std::string>, std::uint64_t> findings;  // rule, axis index
  CapturePipeline::Sinks sinks;
  sinks.frame = [&](const PipelineFrame&) { metrics.onFrame(*pipeline.validator()); };
  sinks.findings = [&](const std::vector<Finding>& found) {
    metrics.onFindings(found);
    for (const Finding& f : found) {
      ++findings[{ruleDef(f.rule).code, f.axis ? "axis" + std::to_string(*f.axis) : ""}];
    }
  };
  pipeline.setSinks(sinks);
  ASSERT_TRUE(streamCapture(**reader, pipeline));
  const CaptureResult result = pipeline.result();
  metrics.refresh(pipeline, result.frames, 0);
  const std::string text = exposeMetrics(metrics.snapshot());

  EXPECT_EQ(samples(text, "ncservo_frames_total")[""], std::to_string(result.frames));
  ASSERT_TRUE(result.timing.cycle && result.timing.latency);
  EXPECT_EQ(samples(text, "ncservo_cycle_seconds_count")[""],
            std::to_string(result.timing.cycle->count));
  EXPECT_EQ(samples(text, "ncservo_return_latency_seconds_count")[""],
            std::to_string(result.timing.latency->count));
  // The capture's 5 ms cycle lies in (4.5, 5.5] ms every time (its histogram: one bin at 0).
  EXPECT_EQ(samples(text, "ncservo_cycle_seconds_bucket")["{le=\"0.0045\"}"], "0");
  EXPECT_EQ(samples(text, "ncservo_cycle_seconds_bucket")["{le=\"0.0055\"}"],
            std::to_string(result.timing.cycle->count));
  EXPECT_GT(result.lost_cycles, 0u);
  EXPECT_EQ(samples(text, "ncservo_lost_cycles_total")[""], std::to_string(result.lost_cycles));
  EXPECT_GT(result.wkc_errors, 0u);
  EXPECT_EQ(samples(text, "ncservo_wkc_errors_total")[""], std::to_string(result.wkc_errors));

  // Findings by rule and axis; every other series of the family is 0.
  const auto finding_series = samples(text, "ncservo_findings_total");
  std::uint64_t total = 0;
  for (const auto& [key, count] : findings) {
    const RuleDef& rule = *ruleByCode(key.first);
    const std::string series = "{rule=\"" + key.first + "\",severity=\"" +
                               severityName(rule.severity) + "\",axis=\"" + key.second + "\"}";
    EXPECT_EQ(finding_series.count(series) ? finding_series.at(series) : "absent",
              std::to_string(count))
        << series;
    total += count;
  }
  std::uint64_t exposed = 0;
  for (const auto& [series, value] : finding_series) exposed += std::stoull(value);
  EXPECT_EQ(exposed, total);
  EXPECT_GT(total, 0u);

  // Incidents by cause and axis.
  std::map<std::string, std::uint64_t> incidents;
  for (const Incident& incident : result.incidents) {
    ++incidents["{cause=\"" + std::string(causeDef(incident.cause).name) + "\",axis=\"" +
                (incident.axis ? "axis" + std::to_string(*incident.axis) : "") + "\"}"];
  }
  const auto incident_series = samples(text, "ncservo_incidents_total");
  EXPECT_EQ(incident_series.size(), kCauseCount * 5);  // the bus and 4 axes
  for (const auto& [series, value] : incident_series) {
    EXPECT_EQ(value, std::to_string(incidents[series])) << series;
  }

  // Each axis in exactly its state; its telegram failures as the result counts them.
  const auto states = samples(text, "ncservo_axis_state");
  const auto failures = samples(text, "ncservo_telegram_failures");
  for (const AxisSummary& axis : result.axes) {
    ASSERT_TRUE(axis.state);
    int ones = 0;
    for (const auto& [series, value] : states) {
      if (series.find("axis=\"" + axis.name + "\"") == std::string::npos) continue;
      ones += value == "1";
      if (value == "1") {
        EXPECT_NE(series.find(driveStateName(*axis.state)), std::string::npos);
      }
    }
    EXPECT_EQ(ones, 1) << axis.name;
    EXPECT_EQ(failures.at("{axis=\"" + axis.name + "\"}"), std::to_string(axis.telegram_failures));
  }
  EXPECT_EQ(samples(text, "ncservo_clock_source")["{source=\"capture\"}"], "1");
}

// Cardinality follows the tables, not the traffic: a snapshot with many findings has the
// series of one with none.
TEST(LiveMetrics, SeriesBoundedByTheTables) {
  const RuleSettings settings;
  MetricsSnapshot none;
  none.enabled = settings.enabled;
  none.severity = settings.severity;
  none.axes.resize(3);
  for (std::size_t i = 0; i < 3; ++i) none.axes[i].name = "axis" + std::to_string(i);
  MetricsSnapshot many = none;
  for (const RuleDef& rule : kRules) {  // as many findings as each enabled rule can give
    const auto r = static_cast<std::size_t>(rule.id);
    if (!settings.isEnabled(rule.id)) continue;
    if (rule.kind != RuleKind::Bus) {
      for (auto& axis : many.axes) axis.findings[r] = 100000;
    }
    if (rule.kind != RuleKind::Axis) many.bus_findings[r] = 5;
  }
  for (auto& axis : many.axes) axis.incidents.fill(7);
  const auto lines = [](const std::string& text) {
    return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
  };
  EXPECT_EQ(lines(exposeMetrics(none)), lines(exposeMetrics(many)));
  std::size_t axis_states = 0;
  for (const std::string& text : {exposeMetrics(none)}) {
    axis_states = samples(text, "ncservo_axis_state").size();
  }
  EXPECT_EQ(axis_states, 3u * 8u);  // the eight drive states of docs/protocol.md §6
}

// The slaves' series: ESC error counters by station, port and counter; DC differences
// (monitor_metrics.sh feeds the counters from a capture).
TEST(LiveMetrics, SlaveCountersAsFed) {
  MetricsSnapshot snapshot;
  snapshot.esc = {{0x1001, 1, "rx_error", 3}, {0x03E9, 0, "lost_link", 0}};
  snapshot.dc.push_back({0x1001, -2.5e-8});
  const std::string text = exposeMetrics(snapshot);
  const auto esc = samples(text, "ncservo_esc_errors_total");
  EXPECT_EQ(esc.at("{station=\"0x1001\",port=\"1\",counter=\"rx_error\"}"), "3");
  EXPECT_EQ(esc.at("{station=\"0x03E9\",port=\"0\",counter=\"lost_link\"}"), "0");
  EXPECT_EQ(samples(text, "ncservo_dc_system_time_difference_seconds").at("{station=\"0x1001\"}"),
            "-2.5e-08");
  // Without them the families are declared, with no series.
  const std::string bare = exposeMetrics(MetricsSnapshot{});
  EXPECT_NE(bare.find("# TYPE ncservo_esc_errors_total counter\n"), std::string::npos);
  EXPECT_TRUE(samples(bare, "ncservo_esc_errors_total").empty());
}

TEST(MetricsServer, ServesTheBoard) {
  MetricsBoard board;
  MetricsSnapshot snapshot;
  snapshot.frames = 42;
  board.publish(snapshot);
  auto server = MetricsServer::start({"127.0.0.1", 0}, board);
  ASSERT_TRUE(server) << server.error().text();
  httplib::Client client("127.0.0.1", (*server)->port());
  const auto response = client.Get("/metrics");
  ASSERT_TRUE(response);
  EXPECT_EQ(response->status, 200);
  EXPECT_EQ(response->get_header_value("Content-Type"), kExpositionContentType);
  EXPECT_EQ(response->body, board.scrape());
  EXPECT_NE(response->body.find("\nncservo_frames_total 42\n"), std::string::npos);
  EXPECT_EQ(client.Get("/")->status, 404);
  EXPECT_EQ((*server)->scrapes(), 1u);
  // A port taken is an error that names it.
  auto second = MetricsServer::start({"127.0.0.1", (*server)->port()}, board);
  ASSERT_FALSE(second);
  EXPECT_NE(second.error().message.find("cannot listen on 127.0.0.1:"), std::string::npos);
}

struct AddressRow {
  std::string name;
  std::string text;
  std::string host;  // "" with error
  int port;
  std::string error;
};
void PrintTo(const AddressRow& row, std::ostream* os) {
  *os << row.text;
}

class ListenAddressRows : public ::testing::TestWithParam<AddressRow> {};
TEST_P(ListenAddressRows, Parse) {
  const AddressRow& row = GetParam();
  const auto parsed = parseListenAddress(row.text);
  if (!row.error.empty()) {
    ASSERT_FALSE(parsed);
    EXPECT_EQ(parsed.error().message, row.error);
    return;
  }
  ASSERT_TRUE(parsed) << parsed.error().text();
  EXPECT_EQ(parsed->host, row.host);
  EXPECT_EQ(parsed->port, row.port);
}
INSTANTIATE_TEST_SUITE_P(
    Rows, ListenAddressRows,
    ::testing::Values(
        AddressRow{"port", "9100", "0.0.0.0", 9100, ""},
        AddressRow{"host and port", "127.0.0.1:9100", "127.0.0.1", 9100, ""},
        AddressRow{"ipv6", "[::1]:0", "::1", 0, ""},
        AddressRow{"name", "localhost:8080", "localhost", 8080, ""},
        AddressRow{"no host", ":9100", "", 0, "--metrics :9100: no address before ':'"},
        AddressRow{"too big", "70000", "", 0,
                   "--metrics 70000: expected [ADDRESS:]PORT, PORT a number of 0 to 65535"},
        AddressRow{"word", "x:y", "", 0,
                   "--metrics x:y: expected [ADDRESS:]PORT, PORT a number of 0 to 65535"}),
    test::rowName<AddressRow>);

struct UrlRow {
  std::string name;
  std::string url;
  bool tls;
  std::string host;
  int port;
  std::string prefix;
  std::string error;
};
void PrintTo(const UrlRow& row, std::ostream* os) {
  *os << row.url;
}

class MqttUrlRows : public ::testing::TestWithParam<UrlRow> {};
TEST_P(MqttUrlRows, Parse) {
  const UrlRow& row = GetParam();
  const auto parsed = parseMqttUrl(row.url);
  if (!row.error.empty()) {
    ASSERT_FALSE(parsed);
    EXPECT_EQ(parsed.error().message, row.error);
    return;
  }
  ASSERT_TRUE(parsed) << parsed.error().text();
  EXPECT_EQ(parsed->tls, row.tls);
  EXPECT_EQ(parsed->host, row.host);
  EXPECT_EQ(parsed->port, row.port);
  EXPECT_EQ(parsed->prefix, row.prefix);
}
INSTANTIATE_TEST_SUITE_P(
    Rows, MqttUrlRows,
    ::testing::Values(
        UrlRow{"plain", "mqtt://broker/plant/line1", false, "broker", 1883, "plant/line1", ""},
        UrlRow{"port", "mqtt://10.0.0.1:1884/m7/", false, "10.0.0.1", 1884, "m7", ""},
        UrlRow{"tls", "mqtts://broker.example/m", true, "broker.example", 8883, "m", ""},
        UrlRow{"ipv6", "mqtt://[::1]:1883/m", false, "::1", 1883, "m", ""},
        UrlRow{"scheme", "http://broker/m", false, "", 0, "",
               "--mqtt http://broker/m: expected mqtt://HOST[:PORT]/PREFIX or mqtts://…"},
        UrlRow{"no prefix", "mqtt://broker", false, "", 0, "",
               "--mqtt mqtt://broker: no topic prefix after the host"},
        UrlRow{"wildcard", "mqtt://broker/a/#", false, "", 0, "",
               "--mqtt mqtt://broker/a/#: a topic prefix cannot hold the wildcards # or +"},
        UrlRow{"bad port", "mqtt://broker:0/m", false, "", 0, "",
               "--mqtt mqtt://broker:0/m: the port is not a number of 1 to 65535"}),
    test::rowName<UrlRow>);

TEST(MqttTopics, NamesAsDocumented) {
  EXPECT_STREQ(mqttTopicName(MqttTopic::Finding), "finding");
  EXPECT_STREQ(mqttTopicName(MqttTopic::Incident), "incident");
  EXPECT_STREQ(mqttTopicName(MqttTopic::DriveMessage), "drive-message");
  EXPECT_STREQ(mqttTopicName(MqttTopic::LinkFault), "link-fault");
  EXPECT_STREQ(mqttTopicName(MqttTopic::Presence), "status");
}

}  // namespace
}  // namespace ncservo
