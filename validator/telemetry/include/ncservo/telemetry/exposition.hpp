// Prometheus' text exposition format (version 0.0.4), as `monitor --metrics` serves it: metric
// families with their HELP and TYPE lines, then their samples. Only the writing; what the metrics
// are is live_metrics.hpp's.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>

namespace ncservo {

// The content type of the format, for the HTTP response.
inline constexpr const char* kExpositionContentType = "text/plain; version=0.0.4; charset=utf-8";

struct MetricLabel {
  std::string_view name;
  std::string_view value;
};

enum class MetricType : std::uint8_t { Counter, Gauge, Histogram };

// A histogram's buckets as Prometheus counts them: `bounds` ascending (seconds), `counts` one per
// bound and one more past the last (+Inf), each not cumulative.
struct HistogramCounts {
  std::span<const double> bounds;
  std::span<const std::uint64_t> counts;
  double sum = 0;
};

class Exposition {
 public:
  // A family's HELP and TYPE lines; its samples follow until the next family. `name` is the
  // family's full name (prefix included).
  void family(std::string_view name, MetricType type, std::string_view help);
  // One sample of the current family (a counter's, a gauge's).
  void sample(std::initializer_list<MetricLabel> labels, double value);
  void sample(std::initializer_list<MetricLabel> labels, std::uint64_t value);
  // A histogram's samples: `_bucket` (cumulative, with `le`), `_sum` and `_count`.
  void histogram(std::initializer_list<MetricLabel> labels, const HistogramCounts& histogram);
  const std::string& text() const { return text_; }

 private:
  void series(std::string_view suffix, std::initializer_list<MetricLabel> labels,
              const MetricLabel* extra);
  std::string text_;
  std::string name_;
};

// A label value as the format writes it between quotes: backslash, quote and line feed escaped.
std::string escapeLabelValue(std::string_view value);
// A number as the format writes it: "+Inf", "-Inf", "NaN", or the shortest text that reads back.
std::string exposedNumber(double value);

}  // namespace ncservo
