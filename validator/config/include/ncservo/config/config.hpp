// The TOML configuration file (docs/configuration.md). Errors are values naming file, line and key.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/layout/axis_config.hpp"
#include "ncservo/layout/decoder.hpp"
#include "ncservo/rules/rules.hpp"

namespace ncservo {

struct Config {
  std::string path;  // where it came from, for messages
  std::optional<int> servo_ready_mode;
  std::uint32_t telegram_failure_limit = 3;
  std::uint32_t dc_settled_ns = 100;  // docs/timing.md "Distributed clocks"
  bool default_layout = true;
  std::map<std::string, std::uint32_t> timeouts_ms;  // only the ones the file sets
  std::map<std::string, std::uint32_t> limits;       // of kLimits, only the ones the file sets
  std::vector<AxisConfig> axes;
  std::vector<std::string> disabled_rules;
  std::vector<std::string> enabled_rules;
  std::map<std::string, std::string> severity_overrides;
};

// The keys of the file's top level, in the order docs/configuration.md lists them.
const std::vector<std::string>& topLevelConfigKeys();

// An error names the file, the line and the key: "FILE:LINE: key 'K': MESSAGE".
Result<Config> parseConfig(std::string_view text, const std::string& path);
// The axes (and a Servo_Ready_Mode) as a configuration file that parseConfig reads back,
// addresses in hexadecimal.
std::string writeConfig(const std::vector<AxisConfig>& axes, std::optional<int> servo_ready_mode);
Result<Config> loadConfig(const std::string& path);
// The file's settings over the defaults (the parser checked all but the rule IDs); an error
// names the file.
Status applyConfig(const Config& config, RuleSettings& settings);

// Where the decoder takes its layout from: the file's axes, else the ENI's, else inference (or
// the default layout, when allowed and the file does not turn it off).
DecoderOptions layoutOptions(const Config* config, const std::vector<AxisConfig>* eni_axes,
                             bool allow_default_layout);

}  // namespace ncservo
