#include "item_texts.hpp"

#include <fmt/format.h>

#include <string>
#include <vector>

namespace ncservo::plugin {

namespace {

// Each axis's layer label ("NC-Servo axis 3 (x): control active") per drive state, formatted
// once per capture: formatting it on every frame cost more than creating the item it names.
constexpr std::size_t kStateSlots = 9;  // the eight drive states, then "no state"
struct AxisLabel {
  std::string name;             // the axis name and
  const char* state = nullptr;  // the state name it was made with
  std::string text;
};
std::vector<AxisLabel> g_axis_labels;  // [axis * kStateSlots + slot]

const char* axisLabel(guint16 axis, std::optional<DriveState> known_state, const char* name,
                      const char* state) {
  const std::size_t slot =
      known_state ? static_cast<std::size_t>(*known_state) % (kStateSlots - 1) : kStateSlots - 1;
  const std::size_t index = std::size_t{axis} * kStateSlots + slot;
  if (index >= g_axis_labels.size()) g_axis_labels.resize(index + kStateSlots);
  AxisLabel& label = g_axis_labels[index];
  if (label.text.empty() || label.state != state || label.name != name) {
    label.name = name;
    label.state = state;
    label.text =
        fmt::format("NC-Servo axis {} ({}){}{}", axis, name, state ? ": " : "", state ? state : "");
  }
  return label.text.c_str();
}

void copyTo(const std::string& text, char* out, std::size_t size) {
  if (size == 0) return;
  const std::size_t n = std::min(text.size(), size - 1);
  text.copy(out, n);
  out[n] = '\0';
}

}  // namespace

void resetItemTexts() {
  g_axis_labels.clear();
}

AxisTexts axisTexts(guint16 axis, const char* name, std::optional<DriveState> state) {
  const char* state_name = state ? driveStateName(*state) : nullptr;
  return {name, state_name, axisLabel(axis, state, name, state_name)};
}

void messageText(const PdoValues& values, char* out, std::size_t size) {
  formatMessage(out, size, values.msgCode(), values.msgData());
}

void sewCausesText(std::uint32_t sew, char* out, std::size_t size) {
  std::string text;
  for (const SewCause& cause : kSewCauses) {
    if (!(sew & cause.mask)) continue;
    fmt::format_to(std::back_inserter(text), "{}{} / {:#06x}", text.empty() ? "" : ", ",
                   cause.display, cause.canopen);
  }
  copyTo(text, out, size);
}

void edgeText(const FieldEdge& edge, char* out, std::size_t size) {
  copyTo(ncservo::edgeText(edge), out, size);
}

void transitionText(const StateChange& change, char* out, std::size_t size) {
  copyTo(ncservo::transitionText(change), out, size);
}

}  // namespace ncservo::plugin
