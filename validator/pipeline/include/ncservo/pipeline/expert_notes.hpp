// The plugin's expert items besides its one per rule (ncservo.rule.<slug>, from the rule table):
// what it says of a frame that is no finding (docs/plugin.md). The plugin registers them from
// this table, and `ncservo fields` lists them (docs/fields.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <iterator>

#include "ncservo/layout/layout_inference.hpp"

namespace ncservo {

enum class ExpertNote : std::uint8_t {
  Malformed,
  ClockJudging,
  LayoutLearning,
  StructureOnly,
  LayoutMisfit,
  PreferenceError,
  DriveEmergency,
  SdoAborted,
  LinkFaultNamed,
};

// Wireshark's expert groups and severities the notes use (the plugin maps them to PI_*).
enum class NoteGroup : std::uint8_t { Malformed, Undecoded, Assumption, Protocol };
enum class NoteLevel : std::uint8_t { Chat, Note, Warn, Error };

struct ExpertNoteDef {
  ExpertNote note;
  const char* filter;
  NoteGroup group;
  NoteLevel level;
  const char* summary;
};

inline constexpr ExpertNoteDef kExpertNotes[] = {
    {ExpertNote::Malformed, "ncservo.malformed", NoteGroup::Malformed, NoteLevel::Error,
     "A PDO region is cut short or lies partly outside its datagram"},
    {ExpertNote::ClockJudging, "ncservo.clock_judging", NoteGroup::Undecoded, NoteLevel::Chat,
     "capture's clock being judged (docs/timing.md#the-clock): `tshark -2` or the GUI decodes "
     "this frame"},
    {ExpertNote::LayoutLearning, "ncservo.layout_learning", NoteGroup::Undecoded, NoteLevel::Chat,
     "layout being learned: `tshark -2` or the GUI decodes this frame"},
    {ExpertNote::StructureOnly, "ncservo.structure_only", NoteGroup::Assumption, NoteLevel::Note,
     kStructureOnlyNote},
    // On the first decoded frame, in a later pass: the layout's data does not look like this
    // protocol's, as the CLI warns (docs/layout.md#a-layout-that-does-not-fit).
    {ExpertNote::LayoutMisfit, "ncservo.layout_misfit", NoteGroup::Protocol, NoteLevel::Warn,
     "layout does not fit"},
    // On the first decoded frame: a preference (a configuration or ENI file, the ready mode)
    // could not be used, so the layout and rules come from elsewhere (docs/plugin.md).
    {ExpertNote::PreferenceError, "ncservo.preference_error", NoteGroup::Protocol, NoteLevel::Error,
     "NCSERVO preference not used"},
    // What the drives and ESCs said (docs/drive-messages.md), on the frame that carried it.
    {ExpertNote::DriveEmergency, "ncservo.emcy.expert", NoteGroup::Protocol, NoteLevel::Warn,
     "a drive sent a CoE emergency"},
    {ExpertNote::SdoAborted, "ncservo.sdo.abort.expert", NoteGroup::Protocol, NoteLevel::Note,
     "an SDO request was aborted"},
    {ExpertNote::LinkFaultNamed, "ncservo.link_fault.expert", NoteGroup::Protocol, NoteLevel::Warn,
     "the ESC error counters name a faulty link"},
};
inline constexpr std::size_t kExpertNoteCount = std::size(kExpertNotes);

constexpr bool notesInEnumOrder() {
  for (std::size_t i = 0; i < kExpertNoteCount; ++i) {
    if (static_cast<std::size_t>(kExpertNotes[i].note) != i) return false;
  }
  return true;
}
static_assert(notesInEnumOrder(), "kExpertNotes lists ExpertNote values in order");

constexpr const ExpertNoteDef& noteDef(ExpertNote note) {
  return kExpertNotes[static_cast<std::size_t>(note)];
}

}  // namespace ncservo
