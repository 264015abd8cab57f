#include "ncservo/config/config.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <set>
#include <sstream>

#include "ncservo/base/text.hpp"
#include "ncservo/protocol/pdo_layout.hpp"
#include "ncservo/rules/rules.hpp"

namespace ncservo {

namespace {

Error configError(const std::string& path, std::uint64_t line, std::string key,
                  std::string message) {
  return Error{path, line, 0, std::move(key), std::move(message)};
}

// Collects the first error; every check below returns false once one is recorded.
class Checker {
 public:
  explicit Checker(std::string path) : path_(std::move(path)) {}

  bool fail(const toml::node& node, std::string key, std::string message) {
    if (!error_) {
      error_ = configError(path_, node.source().begin.line, std::move(key), std::move(message));
    }
    return false;
  }
  bool failed() const { return error_.has_value(); }
  const Error& error() const { return *error_; }

  template <typename T>
  std::optional<T> integer(const toml::node& node, const std::string& key, std::int64_t lo,
                           std::int64_t hi) {
    // Only an integer node is converted: toml++ casts a float to int64 unchecked (UB for 3E80).
    auto value = node.is_integer() ? node.value<std::int64_t>() : std::nullopt;
    if (!value) {
      fail(node, key, "expected an integer");
      return std::nullopt;
    }
    if (*value < lo || *value > hi) {
      fail(node, key, fmt::format("{} is out of range [{}, {}]", *value, lo, hi));
      return std::nullopt;
    }
    return static_cast<T>(*value);
  }

  std::optional<int> readyMode(const toml::node& node, const std::string& key) {
    return integer<int>(node, key, 0, 1);
  }

 private:
  std::string path_;
  std::optional<Error> error_;
};

// A second: a larger system time difference is no distributed clock's.
constexpr std::uint32_t kMaxDcSettledNs = 1'000'000'000;

// The keys each table of the file takes (docs/configuration.md), for "did you mean".
std::vector<std::string> topKeys() {
  std::vector<std::string> keys{"servo_ready_mode",
                                "telegram_failure_limit",
                                "dc_settled_ns",
                                "default_layout",
                                "timeouts",
                                "axis",
                                "rules"};
  for (const LimitDef& l : kLimits) keys.emplace_back(l.name);
  return keys;
}
const std::vector<std::string> kAxisKeys{"name",       "outputs",   "inputs",          "station",
                                         "sm_outputs", "sm_inputs", "servo_ready_mode"};
const std::vector<std::string> kRulesKeys{"disable", "enable", "severity"};

std::string unknownKey(std::string_view key, const std::vector<std::string>& known) {
  return "unknown key" + didYouMean(key, known);
}

// The bytes [at, at + size) of one PDO of two axes overlap.
bool overlaps(std::optional<std::uint32_t> a, std::optional<std::uint32_t> b, std::size_t size) {
  if (!a || !b) return false;
  const std::uint64_t lo = std::max(*a, *b), hi = std::min(*a, *b);
  return lo - hi < size;
}

// The key of `axis` whose PDO lies on bytes an earlier axis already has, and that axis: two
// axes on the same bytes would each decode the other's data (docs/configuration.md#axis). A
// logical axis's outputs may share bytes with another's inputs (one LRW image); two outputs or
// two inputs may not, nor two station axes' sync managers on one station.
std::optional<std::pair<const char*, const AxisConfig*>> overlapOf(
    const std::vector<AxisConfig>& earlier, const AxisConfig& axis) {
  for (const AxisConfig& other : earlier) {
    if (other.physical() != axis.physical()) continue;
    if (axis.physical() && other.station != axis.station) continue;
    if (axis.physical()) {
      if (overlaps(other.sm_outputs, axis.sm_outputs, kRxPdoSize)) {
        return std::pair{"sm_outputs", &other};
      }
      if (overlaps(other.sm_inputs, axis.sm_inputs, kTxPdoSize)) {
        return std::pair{"sm_inputs", &other};
      }
      continue;
    }
    if (overlaps(other.outputs, axis.outputs, kRxPdoSize)) return std::pair{"outputs", &other};
    if (overlaps(other.inputs, axis.inputs, kTxPdoSize)) return std::pair{"inputs", &other};
  }
  return std::nullopt;
}

void readAxis(Checker& check, const toml::table& table, std::size_t index, Config& config) {
  AxisConfig axis;
  const std::string prefix = fmt::format("axis[{}]", index);
  for (const auto& [key_node, node] : table) {
    const std::string key{key_node.str()};
    const std::string name = prefix + "." + key;
    if (key == "name") {
      if (!node.is_string()) {
        check.fail(node, name, "expected a string");
        return;
      }
      axis.name = *node.value<std::string>();
    } else if (key == "outputs") {
      axis.outputs = check.integer<std::uint32_t>(node, name, 0, 0xFFFFFFFF);
    } else if (key == "inputs") {
      axis.inputs = check.integer<std::uint32_t>(node, name, 0, 0xFFFFFFFF);
    } else if (key == "station") {
      axis.station = check.integer<std::uint16_t>(node, name, 0, 0xFFFF);
    } else if (key == "sm_outputs") {
      axis.sm_outputs = check.integer<std::uint16_t>(node, name, 0, 0xFFFF);
    } else if (key == "sm_inputs") {
      axis.sm_inputs = check.integer<std::uint16_t>(node, name, 0, 0xFFFF);
    } else if (key == "servo_ready_mode") {
      axis.servo_ready_mode = check.readyMode(node, name);
    } else {
      check.fail(node, name, unknownKey(key, kAxisKeys));
    }
    if (check.failed()) return;
  }
  const bool logical = axis.outputs || axis.inputs;
  const bool physical = axis.physical();
  if (logical && physical) {
    check.fail(table, prefix,
               "give either logical addresses (outputs/inputs, optionally with station) or a "
               "station with SM addresses (station/sm_outputs/sm_inputs), not both");
    return;
  }
  if (!logical && !physical && axis.station) {
    check.fail(table, prefix,
               "a station alone places no PDO: give outputs/inputs or sm_outputs/sm_inputs too");
    return;
  }
  if (!logical && !physical) {
    check.fail(table, prefix, "needs outputs/inputs or station/sm_outputs/sm_inputs");
    return;
  }
  if (physical && !axis.station) {
    check.fail(table, prefix, "a station axis needs station, sm_outputs and sm_inputs");
    return;
  }
  // Every axis has both PDOs (docs/protocol.md §1): a missing address is a mistake, not an axis
  // whose other half is ignored.
  const auto missing = [&](const char* key, const char* what) {
    check.fail(table, prefix + "." + key, fmt::format("missing: {}", what));
  };
  if (logical && !axis.outputs) return missing("outputs", "the logical address of the RxPDO");
  if (logical && !axis.inputs) return missing("inputs", "the logical address of the TxPDO");
  if (physical && !axis.sm_outputs) return missing("sm_outputs", "the address of SM2 (RxPDO)");
  if (physical && !axis.sm_inputs) return missing("sm_inputs", "the address of SM3 (TxPDO)");
  if (axis.name.empty()) axis.name = fmt::format("axis{}", index);
  for (const AxisConfig& other : config.axes) {
    if (other.name == axis.name) {
      check.fail(table, prefix + ".name", fmt::format("axis name '{}' is used twice", axis.name));
      return;
    }
  }
  if (const auto overlap = overlapOf(config.axes, axis)) {
    const auto& [key, other] = *overlap;
    const toml::node* node = table.get(key);
    check.fail(node != nullptr ? *node : table, prefix + "." + key,
               fmt::format("overlaps axis '{}': two axes on the same PDO bytes", other->name));
    return;
  }
  config.axes.push_back(std::move(axis));
}

void readRules(Checker& check, const toml::table& rules, Config& config) {
  for (const auto& [key_node, node] : rules) {
    const std::string key = "rules." + std::string(key_node.str());
    if (key_node.str() == "disable" || key_node.str() == "enable") {
      std::vector<std::string>& listed =
          key_node.str() == "disable" ? config.disabled_rules : config.enabled_rules;
      const toml::array* ids = node.as_array();
      if (ids == nullptr) {
        check.fail(node, key, "expected an array of rule IDs");
        return;
      }
      for (const toml::node& id : *ids) {
        if (!id.is_string()) {
          check.fail(id, key,
                     "expected rule IDs of the catalogue (`ncservo rules`), such as \"MSG-001\"");
          return;
        }
        const Result<const RuleDef*> rule = findRule(*id.value<std::string>());
        if (!rule) {
          check.fail(id, key, "expected rule IDs of the catalogue: " + rule.error().message);
          return;
        }
        listed.emplace_back((*rule)->code);
      }
    } else if (key_node.str() == "severity") {
      const toml::table* table = node.as_table();
      if (table == nullptr) {
        check.fail(node, key, "expected a table of rule ID = \"error|warning|info\"");
        return;
      }
      for (const auto& [id_node, level] : *table) {
        const std::string id{id_node.str()};
        auto text = level.value<std::string>();
        const Result<const RuleDef*> rule = findRule(id);
        if (!rule) {
          check.fail(level, key + "." + id,
                     "not a rule ID of the catalogue: " + rule.error().message);
          return;
        }
        if (!level.is_string() || (*text != "error" && *text != "warning" && *text != "info")) {
          check.fail(level, key + "." + id, "expected \"error\", \"warning\" or \"info\"");
          return;
        }
        config.severity_overrides[(*rule)->code] = *text;
      }
    } else {
      check.fail(node, key, unknownKey(key_node.str(), kRulesKeys));
      return;
    }
  }
}

}  // namespace

const std::vector<std::string>& topLevelConfigKeys() {
  static const std::vector<std::string> keys = topKeys();
  return keys;
}

Result<Config> parseConfig(std::string_view text, const std::string& path) {
  toml::table root;
  try {
    root = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    return fail(configError(path, e.source().begin.line, {}, std::string(e.description())));
  }
  Config config;
  config.path = path;
  Checker check(path);
  for (const auto& [key_node, node] : root) {
    const std::string key{key_node.str()};
    if (key == "servo_ready_mode") {
      config.servo_ready_mode = check.readyMode(node, key);
    } else if (key == "telegram_failure_limit") {
      if (auto v = check.integer<std::uint32_t>(node, key, 1, 65535)) {
        config.telegram_failure_limit = *v;
      }
    } else if (const LimitDef* limit = limitByName(key)) {
      if (auto v = check.integer<std::uint32_t>(node, key, limit->min, limit->max)) {
        config.limits[key] = *v;
      }
    } else if (key == "dc_settled_ns") {
      if (auto v = check.integer<std::uint32_t>(node, key, 0, kMaxDcSettledNs)) {
        config.dc_settled_ns = *v;
      }
    } else if (key == "default_layout") {
      if (!node.is_boolean()) {
        check.fail(node, key, "expected true or false");
      } else {
        config.default_layout = *node.value<bool>();
      }
    } else if (key == "timeouts") {
      const toml::table* table = node.as_table();
      if (table == nullptr) {
        check.fail(node, key, "expected a table");
      } else {
        for (const auto& [name_node, value] : *table) {
          const std::string name{name_node.str()};
          if (!timeoutFromName(name)) {
            check.fail(value, "timeouts." + name, unknownTimeoutMessage(name));
            break;
          }
          if (auto ms = check.integer<std::uint32_t>(value, "timeouts." + name, 0, kMaxTimeoutMs)) {
            config.timeouts_ms[name] = *ms;
          }
        }
      }
    } else if (key == "axis") {
      const toml::array* axes = node.as_array();
      if (axes == nullptr || !axes->is_array_of_tables()) {
        check.fail(node, key, "expected [[axis]] tables");
      } else {
        std::size_t index = 0;
        for (const toml::node& axis : *axes) {
          readAxis(check, *axis.as_table(), index++, config);
          if (check.failed()) break;
        }
      }
    } else if (key == "rules") {
      if (const toml::table* rules = node.as_table()) {
        readRules(check, *rules, config);
      } else {
        check.fail(node, key, "expected a table");
      }
    } else {
      check.fail(node, key, unknownKey(key, topLevelConfigKeys()));
    }
    if (check.failed()) break;
  }
  if (check.failed()) return fail(check.error());
  return config;
}

Result<Config> loadConfig(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return fail(configError(path, 0, {}, "cannot open the configuration file"));
  std::string text;
  char buffer[4096];
  std::size_t n;
  // A configuration file is small; refuse absurd sizes rather than read them whole.
  constexpr std::size_t kMaxConfigBytes = 4u << 20;
  while ((n = std::fread(buffer, 1, sizeof buffer, file)) > 0) {
    text.append(buffer, n);
    if (text.size() > kMaxConfigBytes) {
      std::fclose(file);
      return fail(configError(path, 0, {}, "the configuration file is larger than 4 MiB"));
    }
  }
  const bool read_error = std::ferror(file) != 0;
  std::fclose(file);
  if (read_error) return fail(configError(path, 0, {}, "cannot read the configuration file"));
  return parseConfig(text, path);
}

std::string writeConfig(const std::vector<AxisConfig>& axes, std::optional<int> servo_ready_mode) {
  toml::table root;
  if (servo_ready_mode) root.insert("servo_ready_mode", *servo_ready_mode);
  auto hex = [](std::int64_t value) {
    toml::value<std::int64_t> v(value);
    v.flags(toml::value_flags::format_as_hexadecimal);
    return v;
  };
  toml::array list;
  for (const AxisConfig& a : axes) {
    toml::table axis;
    axis.insert("name", a.name);
    if (a.outputs) axis.insert("outputs", hex(*a.outputs));
    if (a.inputs) axis.insert("inputs", hex(*a.inputs));
    if (a.station) axis.insert("station", hex(*a.station));
    if (a.sm_outputs) axis.insert("sm_outputs", hex(*a.sm_outputs));
    if (a.sm_inputs) axis.insert("sm_inputs", hex(*a.sm_inputs));
    if (a.servo_ready_mode) axis.insert("servo_ready_mode", *a.servo_ready_mode);
    list.push_back(std::move(axis));
  }
  root.insert("axis", std::move(list));
  std::ostringstream text;
  text << root << "\n";
  return text.str();
}

Status applyConfig(const Config& config, RuleSettings& settings) {
  auto named = [&config](Error error) {
    error.path = config.path;
    return fail(std::move(error));
  };
  if (config.servo_ready_mode) settings.servo_ready_mode = config.servo_ready_mode;
  settings.telegram_failure_limit = config.telegram_failure_limit;
  settings.dc_settled_ns = config.dc_settled_ns;
  for (const auto& [name, value] : config.timeouts_ms) {
    if (Status s = settings.setTimeout(name, value); !s) return named(s.error());
  }
  for (const auto& [name, value] : config.limits) {
    if (Status s = settings.setLimit(name, value); !s) return named(s.error());
  }
  for (const std::string& code : config.enabled_rules) {
    if (Status s = settings.enable(code); !s) return named(s.error());
  }
  for (const std::string& code : config.disabled_rules) {
    if (Status s = settings.disable(code); !s) return named(s.error());
  }
  for (const auto& [code, level] : config.severity_overrides) {
    if (Status s = settings.setSeverity(code, level); !s) return named(s.error());
  }
  settings.axis_ready_mode.clear();
  for (const AxisConfig& axis : config.axes)
    settings.axis_ready_mode.push_back(axis.servo_ready_mode);
  return {};
}

DecoderOptions layoutOptions(const Config* config, const std::vector<AxisConfig>* eni_axes,
                             bool allow_default_layout) {
  DecoderOptions options;
  options.default_layout = allow_default_layout && (config == nullptr || config->default_layout);
  if (config != nullptr && !config->axes.empty()) {
    options.axes = config->axes;
    options.explicit_source = LayoutSource::Config;
  } else if (eni_axes != nullptr && !eni_axes->empty()) {
    options.axes = *eni_axes;
    options.explicit_source = LayoutSource::Eni;
  }
  return options;
}

}  // namespace ncservo
