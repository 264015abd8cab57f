// libFuzzer target: the TOML configuration parser, then what the CLI does with a configuration it
// accepted (rule settings, a decoder with its layout). Input: the file's text.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "ncservo/config/config.hpp"
#include "ncservo/layout/decoder.hpp"
#include "ncservo/rules/rules.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace ncservo;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const Result<Config> result = parseConfig(text, "fuzz.toml");
  if (!result) {
    // Errors name the file: "fuzz.toml:LINE: key 'K': MESSAGE".
    if (result.error().text().rfind("fuzz.toml", 0) != 0) std::abort();
    return 0;
  }
  RuleSettings settings;
  (void)applyConfig(*result, settings);
  DecoderOptions options;
  options.axes = result->axes;
  options.default_layout = result->default_layout;
  Decoder decoder(options);
  (void)decoder.noServoReason();
  return 0;
}
