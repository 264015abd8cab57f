// The texts the dissector gives its items besides their values: an axis's name, drive state and
// layer label, the drive's message, the SEW's active error codes, edges and transitions. The
// plugin's are made here (item_texts.cpp); the benchmark's item floor
// (tests/bench/item_floor_texts.cpp) links constant texts in their place, so that what it
// measures is what Wireshark itself spends on the items.
#pragma once

#include <epan/proto.h>

#include <cstddef>
#include <cstdint>
#include <optional>

#include "ncservo/model/axis_model.hpp"
#include "ncservo/protocol/drive_state.hpp"
#include "ncservo/protocol/pdo.hpp"

namespace ncservo::plugin {

struct AxisTexts {
  const char* name;   // the axis's name: its item and the Info column
  const char* state;  // its drive state; nullptr when not known
  const char* label;  // its layer's label
};

// At the start of each capture: forgets the texts made for the previous one.
void resetItemTexts();
// `name` is the axis's name in the layout. The texts stay valid until resetItemTexts().
AxisTexts axisTexts(guint16 axis, const char* name, std::optional<DriveState> state);
// The drive's message in the inputs `values` carry.
void messageText(const PdoValues& values, char* out, std::size_t size);
// The active error causes of a SEW value, "E09 / 0x8611, E01 / 0x7305"; "" when none.
void sewCausesText(std::uint32_t sew, char* out, std::size_t size);
void edgeText(const FieldEdge& edge, char* out, std::size_t size);
void transitionText(const StateChange& change, char* out, std::size_t size);

}  // namespace ncservo::plugin
