// The TOML configuration file of INTERFACES.md. Errors are values that name file, line and key.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/error.hpp"
#include "ncservo/rules.hpp"

namespace ncservo {

struct AxisConfig {
  std::string name;
  // Logical addresses of the 10-byte RxPDO and the 40-byte TxPDO (LRW/LRD/LWR exchange) ...
  std::optional<std::uint32_t> outputs;
  std::optional<std::uint32_t> inputs;
  // ... or a configured station address and SM2/SM3 physical addresses (FPRD/FPWR exchange).
  std::optional<std::uint16_t> station;
  std::optional<std::uint16_t> sm_outputs;
  std::optional<std::uint16_t> sm_inputs;
  std::optional<int> servo_ready_mode;

  // Exchanged with FPRD/FPWR at SM addresses; else logical. A logical axis may still name its
  // station, which ties it to that slave's AL state (ESM-002).
  bool physical() const { return sm_outputs.has_value() || sm_inputs.has_value(); }
};

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
// The file's settings over RULES.md's defaults (the parser checked all but the rule IDs); an error
// names the file.
Status applyConfig(const Config& config, RuleSettings& settings);

}  // namespace ncservo
