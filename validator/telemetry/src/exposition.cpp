#include "ncservo/telemetry/exposition.hpp"

#include <fmt/format.h>

#include <cmath>

namespace ncservo {

namespace {

const char* typeName(MetricType type) {
  switch (type) {
    case MetricType::Counter:
      return "counter";
    case MetricType::Gauge:
      return "gauge";
    case MetricType::Histogram:
      return "histogram";
  }
  return "untyped";
}

// HELP text escapes backslash and line feed only (the format's rule).
std::string escapeHelp(std::string_view help) {
  std::string out;
  for (const char c : help) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace

std::string escapeLabelValue(std::string_view value) {
  std::string out;
  out.reserve(value.size());
  for (const char c : value) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '"') {
      out += "\\\"";
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out += c;
    }
  }
  return out;
}

std::string exposedNumber(double value) {
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "+Inf" : "-Inf";
  return fmt::format("{}", value);
}

void Exposition::family(std::string_view name, MetricType type, std::string_view help) {
  name_ = name;
  text_ +=
      fmt::format("# HELP {} {}\n# TYPE {} {}\n", name, escapeHelp(help), name, typeName(type));
}

void Exposition::series(std::string_view suffix, std::initializer_list<MetricLabel> labels,
                        const MetricLabel* extra) {
  text_ += name_;
  text_ += suffix;
  if (labels.size() == 0 && extra == nullptr) {
    text_ += ' ';
    return;
  }
  char separator = '{';
  for (const MetricLabel& label : labels) {
    text_ += fmt::format("{}{}=\"{}\"", separator, label.name, escapeLabelValue(label.value));
    separator = ',';
  }
  if (extra != nullptr) {
    text_ += fmt::format("{}{}=\"{}\"", separator, extra->name, escapeLabelValue(extra->value));
  }
  text_ += "} ";
}

void Exposition::sample(std::initializer_list<MetricLabel> labels, double value) {
  series("", labels, nullptr);
  text_ += exposedNumber(value);
  text_ += '\n';
}

void Exposition::sample(std::initializer_list<MetricLabel> labels, std::uint64_t value) {
  series("", labels, nullptr);
  text_ += fmt::format("{}\n", value);
}

void Exposition::histogram(std::initializer_list<MetricLabel> labels,
                           const HistogramCounts& histogram) {
  std::uint64_t cumulative = 0;
  for (std::size_t i = 0; i <= histogram.bounds.size(); ++i) {
    cumulative += i < histogram.counts.size() ? histogram.counts[i] : 0;
    const std::string le =
        i < histogram.bounds.size() ? exposedNumber(histogram.bounds[i]) : std::string("+Inf");
    const MetricLabel bucket{"le", le};
    series("_bucket", labels, &bucket);
    text_ += fmt::format("{}\n", cumulative);
  }
  series("_sum", labels, nullptr);
  text_ += exposedNumber(histogram.sum);
  text_ += '\n';
  series("_count", labels, nullptr);
  text_ += fmt::format("{}\n", cumulative);
}

}  // namespace ncservo
