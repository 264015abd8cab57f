// The item floor of tests/bench/plugin_ratio.sh: linked into the plugin's dissector in place of
// plugin/item_texts.cpp, it gives every item a constant text, so that the same first pass and
// the same items cost only what Wireshark itself spends on them.
#include <cstdio>

#include "item_texts.hpp"

namespace ncservo::plugin {

void resetItemTexts() {}

AxisTexts axisTexts(guint16, const char*, std::optional<DriveState> state) {
  return {"axis", state ? "state" : nullptr, "Axis"};
}

void messageText(const PdoValues&, char* out, std::size_t size) {
  std::snprintf(out, size, "message");
}

void sewCausesText(std::uint32_t, char* out, std::size_t size) {
  std::snprintf(out, size, "causes");
}

void edgeText(const FieldEdge&, char* out, std::size_t size) {
  std::snprintf(out, size, "edge");
}

void transitionText(const StateChange&, char* out, std::size_t size) {
  std::snprintf(out, size, "transition");
}

}  // namespace ncservo::plugin
