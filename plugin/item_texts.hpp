// The texts the dissector gives its items besides their values: an axis's name, drive state and
// subtree label, the drive's message, and the copy kind. The plugin's are made here
// (item_texts.cpp); the benchmark's item floor (tests/bench/item_floor_texts.cpp) links constant
// texts in their place, so that what it measures is what Wireshark itself spends on the items.
#pragma once

#include <epan/proto.h>

#include <cstddef>
#include <optional>

#include "ncservo/decoder.hpp"
#include "ncservo/drive_state.hpp"
#include "ncservo/pdo.hpp"

namespace ncservo::plugin {

struct AxisTexts {
  const char* name;   // the axis's name: its item and the Info column
  const char* state;  // its drive state; nullptr when not known
  const char* label;  // its subtree's label
};

// At the start of each capture: forgets the texts made for the previous one.
void resetItemTexts();
// `name` is the axis's name in the layout. The texts stay valid until resetItemTexts().
AxisTexts axisTexts(guint16 axis, const char* name, std::optional<DriveState> state);
// The drive's message in the inputs `values` carry.
void messageText(const PdoValues& values, char* out, std::size_t size);
// The copy kind's text, after adding it and the axis count to the protocol's item `root`.
const char* describeCopy(proto_item* root, CopyKind copy, unsigned axis_count);

}  // namespace ncservo::plugin
