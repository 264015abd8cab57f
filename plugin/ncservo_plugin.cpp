// Wireshark 4.0–4.6 plugin: a thin presenter over the ncservo library. The field registration is
// generated from the library's field table; layout, copy detection and drive state come from the
// library's Validator — as are the rules' findings, shown as expert info — computed on the first
// pass and kept per frame, as Wireshark's later passes do not visit frames in order.
//
// Wireshark raises exceptions with longjmp: no object with a destructor may be alive in a frame
// of this file across a tvb_* or proto_tree_add_* call. The dissector therefore works on plain
// structs and raw pointers only.
#define WS_BUILD_DLL
#include <epan/expert.h>
#include <epan/packet.h>
#include <epan/prefs.h>
#include <epan/proto_data.h>
#include <epan/stat_tap_ui.h>
#include <epan/tap.h>
#include <fmt/format.h>
#include <wireshark.h>
#include <wiretap/wtap.h>
#include <wsutil/report_message.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "item_texts.hpp"
#include "ncservo/base/text.hpp"
#include "ncservo/config/config.hpp"
#include "ncservo/incidents/causes.hpp"
#include "ncservo/layout/eni.hpp"
#include "ncservo/layout/layout_inference.hpp"
#include "ncservo/model/esc_errors.hpp"
#include "ncservo/model/mailbox_tracker.hpp"
#include "ncservo/model/timing_text.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"
#include "ncservo/pipeline/expert_notes.hpp"
#include "ncservo/protocol/fields.hpp"
#include "ncservo/protocol/pdo.hpp"
#include "ncservo/rules/rules.hpp"
#include "ncservo/rules/validator.hpp"
#include "ncservo/wire/diagnosis_texts.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "ncservo/wire/frame_clock.hpp"
#include "ws_compat.hpp"

extern "C" {
WS_DLL_PUBLIC const char plugin_version[];
WS_DLL_PUBLIC const int plugin_want_major;
WS_DLL_PUBLIC const int plugin_want_minor;
WS_DLL_PUBLIC void plugin_register(void);
}
const char plugin_version[] = NCSERVO_VERSION;
const int plugin_want_major = WIRESHARK_VERSION_MAJOR;
const int plugin_want_minor = WIRESHARK_VERSION_MINOR;
NCSERVO_WS_DESCRIBE_PLUGIN(WS_PLUGIN_DESC_DISSECTOR)

namespace {

using namespace ncservo;

constexpr std::size_t kDerivedCount = std::size(kDerivedFields);
constexpr std::size_t kMaxChildren = 33;  // at most 32 bit fields per word, NULL-terminated

int proto_ncservo = -1;
int hf_field[kFieldCount];
int hf_derived[kDerivedCount];
// The registrations of the fields, kept at hand-off: whether an item is needed is read from them
// once per item instead of a call to proto_field_is_referenced.
const header_field_info* hfi_field[kFieldCount];
const header_field_info* hfi_derived[kDerivedCount];
const header_field_info* hfi_protocol = nullptr;
protocol_t* protocol_ncservo = nullptr;  // kept at hand-off: whether it is enabled, per frame
int ett_ncservo = -1;
int ett_axis = -1;
int ett_finding = -1;
int ett_clear_causes = -1;
int ett_transition = -1;
int ett_word[kWordCount];
// The protocol's layer, one per axis of a frame; called by the postdissector.
dissector_handle_t layer_handle = nullptr;
// What each PDO word adds, prepared once from the field table so that no frame scans the table.
constexpr std::size_t kMaxParts = 2;
struct WordItems {
  std::size_t row;      // the word's row in kFields; its bit fields and parts follow it
  std::size_t row_end;  // one past the word's last row
  guint offset;         // in its PDO
  gint length;
  int* children[kMaxChildren];           // bit fields drawn by one bitmask call, NULL-terminated
  std::size_t child_rows[kMaxChildren];  // their rows in kFields
  std::size_t parts[kMaxParts];          // rows of byte-aligned parts, each shown when it applies
  std::size_t part_count;
};
WordItems word_items[kWordCount];
expert_field ei_note[kExpertNoteCount];  // the expert items of kExpertNotes, in its order
expert_field ei_rule[kRuleCount];        // one expert item per rule: ncservo.rule.<slug>

expert_field* noteEi(ExpertNote note) {
  return &ei_note[static_cast<std::size_t>(note)];
}

const char* pref_config_path = "";
const char* pref_eni_path = "";
ws::PrefBool pref_default_layout = true;
// A string preference, checked in applyPreferences: Wireshark 4.0 keeps an enum preference as it
// was, silently, when `-o` names none of its values (epan/prefs.c, PREF_ENUM), and a mistyped
// mode must be reported. The descriptions are what 4.0's enum preference wrote to preference
// files, still read.
const char* pref_servo_ready_mode = "auto";
struct ReadyModeName {
  const char* name;
  const char* description;
  std::optional<int> mode;  // none: inferred per axis
};
const ReadyModeName kReadyModes[] = {{"auto", "Inferred from the capture", std::nullopt},
                                     {"0", "Servo_Ready_Mode 0", 0},
                                     {"1", "Servo_Ready_Mode 1", 1}};

// The mode the preference names, or an error saying what it takes.
Result<std::optional<int>> readyModeOf(const char* text) {
  const std::string_view value = text != nullptr ? text : "";
  if (value.empty()) return std::nullopt;
  for (const ReadyModeName& row : kReadyModes) {
    if (equalsIgnoringCase(value, row.name) || equalsIgnoringCase(value, row.description)) {
      return row.mode;
    }
  }
  return fail(
      fmt::format("ncservo.servo_ready_mode: '{}' is not auto, 0 or 1; auto is used", value));
}

// Options from the preferences, and the state of the capture being dissected: the capture
// pipeline (its learning window, docs/layout.md, then the validator once the layout is known),
// and what it found in each frame by frame number (the window's frames are validated when it
// ends, not in their turn).
DecoderOptions* g_options = nullptr;
RuleSettings* g_settings = nullptr;
CapturePipeline* g_pipeline = nullptr;
bool g_capture_open = false;
// What each capture's first decoded frame says as expert info, besides a dialog or standard
// error (report_failure): the preferences that could not be used, and in a later pass the
// misfits of a configured or ENI layout (docs/plugin.md#preferences).
std::vector<std::string> g_preference_errors;
std::vector<std::string> g_layout_misfits;
bool g_misfits_taken = false;  // in this capture's later pass
guint32 g_first_frame = 0;     // the first frame with a record; 0: none yet
// While the learning window holds the frames, a single pass shows each before the layout is
// known, with the findings the pipeline's judge of held frames reported on it. The window's
// replay then keeps each frame's record anew for later passes.
const char* g_held_info = nullptr;  // the Info text of a held frame without findings

// What the first pass found in a frame, kept in file scope for later passes.
enum AxisFlags : guint8 {
  kHasRx = 1,
  kHasTx = 2,
  kRxMalformed = 4,
  kTxMalformed = 8,
  kHasState = 16,
  // The axis's layout came from the PDO structure alone, no handshake confirming it.
  kStructureOnly = 32,
};
struct AxisRecord {
  guint16 axis;
  guint8 flags;
  guint8 state;
  guint8 edge_count;
  guint32 rx_offset;
  guint32 tx_offset;
  const FieldEdge* edges;     // edge_count entries, in file scope
  const StateChange* change;  // the drive-state change in this frame, or null; in file scope
};
constexpr guint16 kBusAxis = 0xFFFF;
struct FindingRecord {
  guint8 rule;       // RuleId
  guint16 axis;      // kBusAxis for a finding about the bus
  guint32 since;     // frame where the condition began
  const char* text;  // "SE-001 illegal-enable-edge: axis0: ...", in file scope
};
// An incident beginning in a frame (docs/incidents.md), as the first pass found it.
struct IncidentRecord {
  guint16 axis;  // kBusAxis for the bus or a slave that is no axis
  guint16 evidence_count;
  const char* text;         // "communication-loss: 12 cycles lost ...", in file scope
  const guint32* evidence;  // evidence_count frame numbers, in file scope
};
// What a drive or an ESC said in a frame (docs/drive-messages.md), as the first pass read it.
enum class SaidKind : guint8 { Emergency, SdoUpload, SdoDownload, SdoAbort, EscRise, LinkFault };
// Who said it: a station address, a ring position, or every slave (a BRD's sum of counters).
enum SaidSlave : guint8 { kByStation, kByPosition, kAllSlaves };
struct SaidRecord {
  SaidKind kind;
  guint8 addressed;  // SaidSlave: what `slave` is
  bool has_value;    // an SDO's value (at most 8 bytes)
  bool history;      // the value is an error history entry (errorHistoryEntry)
  guint8 subindex;
  guint16 slave;          // the station address of the slave that said it
  guint16 index;          // SDO
  guint16 code;           // emergency: its error code; ESC: the counter (diag::EscCounter)
  guint8 error_register;  // emergency; ESC: the port
  guint8 data[5];         // emergency
  guint32 number;         // SDO abort: its code; ESC: the rise
  guint32 request_frame;  // SDO: 0 when the capture did not hold it
  guint64 value;          // SDO
  const char* text;       // link fault: the link named, in file scope
};
// Why the first pass saw a frame held: the capture's clock was being judged, or the layout learned.
enum HeldFor : guint8 {
  kNotHeld = 0,
  kHeldForLayout = 1,
  kHeldForClock = 2,
};
// Which timing values a frame has (FrameTiming).
enum TimingFlags : guint8 {
  kHasInterval = 1,
  kHasDeviation = 2,
  kHasLatency = 4,
};
struct FrameRecord {
  const AxisRecord* axes;  // axis_count entries, in file scope; frames alike share one array
  const FindingRecord* findings;
  const IncidentRecord* incidents;
  const SaidRecord* said;  // said_count entries in file scope, grouped by slave
  const char* info;  // the Info column's text, in file scope; null: nothing decoded in the frame
  guint16 axis_count;
  guint16 finding_count;
  guint16 incident_count;
  guint16 said_count;
  guint8 copy;
  guint8 timing;  // TimingFlags
  // Held when the first pass saw it (HeldFor): in a single pass, shown before the layout or the
  // clock was known.
  guint8 held;
  guint8 clock;    // ClockSource of the timing values
  bool duplicate;  // a copy of a record within its cycle, not judged
  gint64 interval_ns;
  gint64 deviation_ns;
  gint64 latency_ns;
};
// By frame number: frames are numbered from 1 without gaps, so an index finds a frame's record
// for less than a hash map, whose growth and scattered inserts cost the packet list measurably.
// The records are kept in blocks that never move as the capture grows: a growing array would
// copy every record kept so far each time it doubles.
constexpr std::size_t kFrameBlockBits = 12;
constexpr std::size_t kFrameBlock = std::size_t{1} << kFrameBlockBits;
std::vector<std::unique_ptr<FrameRecord[]>> g_frames;
// The record of frame `number`; null when no record was kept in its block.
FrameRecord* frameSlot(std::uint64_t number) {
  const std::uint64_t block = number >> kFrameBlockBits;
  if (block >= g_frames.size() || !g_frames[block]) return nullptr;
  return &g_frames[block][number & (kFrameBlock - 1)];
}
// By axis: the first frame that decodes an axis whose layout came from the PDO structure alone
// (0: none). That frame and those with the axis's findings carry the note, not every frame.
std::vector<guint32> g_structure_only_first;
// By axis: whether its layout came from the PDO structure alone, kept once the layout is decided
// (it does not change after), so that no frame asks the pipeline for each axis.
std::vector<guint8> g_structure_only;
bool g_any_structure_only = false;  // some axis's layout came from the structure alone
// The incidents of the pipeline already kept in a frame's record.
std::size_t g_incidents_kept = 0;
// By incident index, its record (in file scope): a cause a later frame revises (link-fault,
// docs/incidents.md#link-fault) is written into the frame where the incident began, which a
// second pass (tshark -2) shows.
std::vector<IncidentRecord*> g_incident_records;
// The axis arrays kept last, each with the Info text of a frame without findings: in cyclic
// traffic most frames carry the same axes in the same states at the same offsets, alternating
// between a few such arrays (the master copy and the returned one, frames of a split image).
struct SharedAxes {
  const AxisRecord* axes = nullptr;  // in file scope
  std::size_t count = 0;
  const char* info = nullptr;  // in file scope; null until a frame without findings needs it
};
std::array<SharedAxes, 8> g_shared_axes;
std::size_t g_next_shared = 0;  // the slot replaced next
// The slots the last two frames shared: cyclic traffic alternates between a few arrays (the
// master copy and the returned one), so a frame most often matches the one before the last.
std::size_t g_recent_shared[2] = {};
// The digits of a second the capture's timestamps hold (its first EtherCAT frame's), for the
// timing statistics' resolution.
std::optional<int> g_timestamp_digits;

ftenum wordType(WireType type) {
  switch (type) {
    case WireType::I16:
      return FT_INT16;
    case WireType::I32:
      return FT_INT32;
    case WireType::U32:
      return FT_UINT32;
    case WireType::I64:
      return FT_INT64;
    case WireType::F32:
      return FT_FLOAT;
  }
  return FT_NONE;
}

const value_string* makeValueString(const FieldDef& f) {
  auto* vs = g_new0(value_string, f.value_count + 1u);
  for (std::size_t i = 0; i < f.value_count; ++i) {
    vs[i].value = f.values[i].value;
    vs[i].strptr = f.values[i].unit != nullptr
                       ? g_strdup_printf("%s [%s]", f.values[i].name, f.values[i].unit)
                       : f.values[i].name;
  }
  return vs;
}

const true_false_string* makeTfs(const FieldDef& f) {
  auto* tfs = g_new0(true_false_string, 1);
  const ValueName* set = valueName(f, 1);
  const ValueName* clear = valueName(f, 0);
  tfs->true_string = set != nullptr ? set->name : "Set";
  tfs->false_string = clear != nullptr ? clear->name : "Not set";
  return tfs;
}

void fillHeader(header_field_info& h, const char* name, const char* abbrev, ftenum type,
                int display, const void* strings, guint64 bitmask, const char* blurb) {
  h.name = name;
  h.abbrev = abbrev;
  h.type = type;
  h.display = display;
  h.strings = strings;
  h.bitmask = bitmask;
  h.blurb = blurb;
  h.id = -1;
  h.parent = 0;
  h.ref_type = HF_REF_TYPE_NONE;
  h.same_name_prev_id = -1;
  h.same_name_next = nullptr;
}

// The hf_register_info array, generated from the field table.
// A code table of the wire layer's as Wireshark's value names (docs/drive-messages.md).
template <std::size_t N>
const value_string* makeCodeNames(const std::array<diag::CodeText, N>& table) {
  auto* names = g_new0(value_string, N + 1);
  for (std::size_t i = 0; i < N; ++i) names[i] = {table[i].code, table[i].text};
  return names;
}

const value_string* derivedNames(DerivedNames names) {
  switch (names) {
    case DerivedNames::ErrorCodes:
      return makeCodeNames(diag::kErrorCodes);
    case DerivedNames::AbortCodes:
      return makeCodeNames(diag::kAbortCodes);
    case DerivedNames::None:
      break;
  }
  return nullptr;
}

// The emergency register's bit fields are 1001h's bits of the wire layer's table, in its order.
constexpr bool registerBitsAsTheWireLayers() {
  constexpr auto kFirst = static_cast<std::size_t>(Derived::EmcyRegisterGeneric);
  for (std::size_t i = 0; i < diag::kErrorRegisterBits.size(); ++i) {
    if (kDerivedFields[kFirst + i].kind != DerivedKind::Flag ||
        kDerivedFields[kFirst + i].mask != diag::kErrorRegisterBits[i].mask) {
      return false;
    }
  }
  return kFirst + diag::kErrorRegisterBits.size() - 1 ==
         static_cast<std::size_t>(Derived::EmcyRegisterManufacturer);
}
static_assert(registerBitsAsTheWireLayers());

// Each DerivedKind's Wireshark type and display, in the enum's order.
struct DerivedType {
  ftenum type;
  int display;
};
constexpr DerivedType kDerivedTypes[] = {
    {FT_STRING, BASE_NONE},    // Text
    {FT_UINT16, BASE_DEC},     // Index
    {FT_FRAMENUM, BASE_NONE},  // FrameNumber
    {FT_DOUBLE, BASE_NONE},    // Microseconds
    {FT_UINT32, BASE_DEC},     // Unsigned
    {FT_UINT8, BASE_HEX},      // Hex8
    {FT_UINT16, BASE_HEX},     // Hex16
    {FT_UINT32, BASE_HEX},     // Hex32
    {FT_UINT64, BASE_HEX},     // Value
    {FT_BOOLEAN, 8},           // Flag: one bit of an 8-bit parent
    {FT_BYTES, BASE_NONE},     // Bytes
};
static_assert(std::size(kDerivedTypes) == static_cast<std::size_t>(DerivedKind::Bytes) + 1);

void fillDerivedHeader(header_field_info& h, const DerivedFieldDef& d) {
  const DerivedType& t = kDerivedTypes[static_cast<std::size_t>(d.kind)];
  const value_string* names = derivedNames(d.names);
  const void* strings = d.kind == DerivedKind::FrameNumber ? FRAMENUM_TYPE(FT_FRAMENUM_NONE)
                        : names != nullptr                 ? VALS(names)
                                                           : nullptr;
  fillHeader(h, d.label, d.filter, t.type, t.display, strings,
             d.kind == DerivedKind::Flag ? d.mask : 0, d.blurb);
}

hf_register_info* buildFieldRegistrations(std::size_t& count) {
  count = kFieldCount + kDerivedCount;
  auto* hf = g_new0(hf_register_info, count);
  for (std::size_t i = 0; i < kFieldCount; ++i) {
    const FieldDef& f = kFields[i];
    const WordDef& word = wordDef(f.word);
    hf_field[i] = -1;
    hf[i].p_id = &hf_field[i];
    switch (f.kind) {
      case FieldKind::Word: {
        const ftenum type = wordType(word.type);
        const int base = type == FT_FLOAT ? BASE_NONE : type == FT_UINT32 ? BASE_HEX : BASE_DEC;
        fillHeader(hf[i].hfinfo, f.label, f.filter, type, base,
                   f.value_count ? VALS(makeValueString(f)) : nullptr, 0, f.blurb);
        break;
      }
      case FieldKind::Flag:
        fillHeader(hf[i].hfinfo, f.label, f.filter, FT_BOOLEAN, 8 * word.size, TFS(makeTfs(f)),
                   f.mask, f.blurb);
        break;
      case FieldKind::BitRange:
        fillHeader(hf[i].hfinfo, f.label, f.filter, FT_UINT32, BASE_DEC,
                   f.value_count ? VALS(makeValueString(f)) : nullptr, f.mask, f.blurb);
        break;
      case FieldKind::Part:
        fillHeader(hf[i].hfinfo, f.label, f.filter, FT_INT32, BASE_DEC, nullptr, 0, f.blurb);
        break;
    }
  }
  for (std::size_t i = 0; i < kDerivedCount; ++i) {
    const DerivedFieldDef& d = kDerivedFields[i];
    hf_derived[i] = -1;
    hf_register_info& r = hf[kFieldCount + i];
    r.p_id = &hf_derived[i];
    fillDerivedHeader(r.hfinfo, d);
  }
  return hf;
}

// The notes' expert items, from their table (ncservo/pipeline/expert_notes.hpp).
ei_register_info* buildNoteRegistrations() {
  constexpr int kGroups[] = {PI_MALFORMED, PI_UNDECODED, PI_ASSUMPTION, PI_PROTOCOL};
  constexpr int kLevels[] = {PI_CHAT, PI_NOTE, PI_WARN, PI_ERROR};
  auto* ei = g_new0(ei_register_info, kExpertNoteCount);
  for (std::size_t i = 0; i < kExpertNoteCount; ++i) {
    const ExpertNoteDef& note = kExpertNotes[i];
    ei_note[i] = EI_INIT;
    ei[i].ids = &ei_note[i];
    ei[i].eiinfo.name = note.filter;
    ei[i].eiinfo.group = kGroups[static_cast<std::size_t>(note.group)];
    ei[i].eiinfo.severity = kLevels[static_cast<std::size_t>(note.level)];
    ei[i].eiinfo.summary = note.summary;
    // As EXPFILL fills them.
    ei[i].eiinfo.hf_info.p_id = nullptr;
    ei[i].eiinfo.hf_info.hfinfo.id = -1;
    ei[i].eiinfo.hf_info.hfinfo.same_name_prev_id = -1;
  }
  return ei;
}

// One expert item per rule, generated from the rule table, at the rule's default severity.
ei_register_info* buildRuleRegistrations() {
  auto* ei = g_new0(ei_register_info, kRuleCount);
  for (std::size_t i = 0; i < kRuleCount; ++i) {
    const RuleDef& rule = kRules[i];
    ei_rule[i] = EI_INIT;
    ei[i].ids = &ei_rule[i];
    ei[i].eiinfo.name = g_strdup(ruleFilterName(rule).c_str());
    ei[i].eiinfo.group = rule.party == Party::Bus ? PI_SEQUENCE : PI_PROTOCOL;
    ei[i].eiinfo.severity = rule.severity == Severity::Error     ? PI_ERROR
                            : rule.severity == Severity::Warning ? PI_WARN
                                                                 : PI_NOTE;
    ei[i].eiinfo.summary = g_strdup_printf("%s %s", rule.code, rule.slug);
    // As EXPFILL and HFILL fill them.
    ei[i].eiinfo.hf_info.p_id = nullptr;
    ei[i].eiinfo.hf_info.hfinfo.id = -1;
    ei[i].eiinfo.hf_info.hfinfo.same_name_prev_id = -1;
  }
  return ei;
}

int derivedHf(Derived id) {
  return hf_derived[static_cast<std::size_t>(id)];
}

void buildWordItems() {
  for (std::size_t i = 0; i < kFieldCount; ++i) {
    const FieldDef& f = kFields[i];
    WordItems& word = word_items[static_cast<std::size_t>(f.word)];
    const FieldSpan span = fieldSpan(f);
    switch (f.kind) {
      case FieldKind::Word:
        word.row = i;
        word.offset = static_cast<guint>(span.offset);
        word.length = static_cast<gint>(span.length);
        break;
      case FieldKind::Flag:
      case FieldKind::BitRange: {
        std::size_t used = 0;
        while (word.children[used] != nullptr) ++used;
        if (used + 1 < kMaxChildren) {
          word.children[used] = &hf_field[i];
          word.child_rows[used] = i;
        }
        break;
      }
      case FieldKind::Part:
        if (word.part_count < kMaxParts) word.parts[word.part_count++] = i;
        break;
    }
    word.row_end = i + 1;
  }
}

// A preference that cannot be used: said at once, and again on each capture's first frame.
void preferenceFailed(const std::string& text) {
  report_failure("NCSERVO: %s", text.c_str());
  g_preference_errors.push_back(text);
}

void applyPreferences() {
  g_preference_errors.clear();
  auto* settings = new RuleSettings();
  std::optional<Config> config;
  std::vector<AxisConfig> eni_axes;
  std::vector<MailboxArea> eni_mailboxes;
  if (pref_eni_path != nullptr && pref_eni_path[0] != '\0') {
    Result<EniLayout> eni = loadEni(pref_eni_path);
    if (eni) {
      eni_axes = std::move(eni->axes);
      eni_mailboxes = std::move(eni->mailboxes);
    } else {
      preferenceFailed(eni.error().text());
    }
  }
  if (pref_config_path != nullptr && pref_config_path[0] != '\0') {
    Result<Config> loaded = loadConfig(pref_config_path);
    if (loaded) {
      config = std::move(*loaded);
      // Severity overrides are left to Wireshark's own expert-severity table (docs/plugin.md).
      if (Status applied = applyConfig(*config, *settings); !applied) {
        preferenceFailed(applied.error().text());
      }
    } else {
      preferenceFailed(loaded.error().text());
    }
  }
  if (const Result<std::optional<int>> mode = readyModeOf(pref_servo_ready_mode); mode) {
    settings->servo_ready_mode = *mode;
  } else {
    preferenceFailed(mode.error().text());
  }
  auto* options = new DecoderOptions(
      layoutOptions(config ? &*config : nullptr, &eni_axes, pref_default_layout != 0));
  options->mailbox_areas = std::move(eni_mailboxes);
  delete g_options;
  g_options = options;
  delete g_settings;
  g_settings = settings;
}

// The validator of the capture's pipeline; null while its learning window holds the frames.
const Validator* validator() {
  return g_pipeline != nullptr ? g_pipeline->validator() : nullptr;
}

void validateFrame(const PipelineFrame& delivered);
void keepDuplicate(std::uint64_t number);

// The layout is decided: which axes came from the PDO structure alone.
void keepLayout(const DecoderOptions& layout) {
  g_structure_only.assign(layout.axes.size(), 0);
  for (std::size_t axis = 0; axis < layout.axes.size(); ++axis) {
    g_structure_only[axis] = g_pipeline->structureOnly(static_cast<std::uint16_t>(axis));
    g_any_structure_only = g_any_structure_only || g_structure_only[axis] != 0;
  }
}

void initCapture() {
  plugin::resetItemTexts();
  g_held_info = nullptr;
  g_frames.clear();
  g_structure_only_first.clear();
  g_structure_only.clear();
  g_any_structure_only = false;
  g_incidents_kept = 0;
  g_incident_records.clear();
  g_shared_axes = {};
  g_next_shared = 0;
  std::fill(std::begin(g_recent_shared), std::end(g_recent_shared), 0);
  g_timestamp_digits.reset();
  g_layout_misfits.clear();
  g_misfits_taken = false;
  g_first_frame = 0;
  g_capture_open = true;
  delete g_pipeline;
  // Wireshark times the frames and shows them all: no frame clock, no time window.
  g_pipeline = new CapturePipeline({g_options != nullptr ? *g_options : DecoderOptions{},
                                    g_settings != nullptr ? *g_settings : RuleSettings{},
                                    TimeWindow{}, TimestampMode::Capture});
  g_pipeline->setSinks({keepLayout, validateFrame, nullptr, nullptr, keepDuplicate});
  g_pipeline->judgeHeldFrames();
}

void cleanupCapture() {
  delete g_pipeline;
  g_pipeline = nullptr;
  std::vector<std::unique_ptr<FrameRecord[]>>().swap(g_frames);
  std::vector<guint32>().swap(g_structure_only_first);
  std::vector<guint8>().swap(g_structure_only);
  g_any_structure_only = false;
  g_shared_axes = {};
  g_capture_open = false;
}

const char* axisName(const Validator* by, guint16 axis) {
  if (by != nullptr && axis < by->decoder().axes().size()) {
    return by->decoder().axes()[axis].name.c_str();
  }
  return "?";
}
const char* axisName(guint16 axis) {
  return axisName(validator(), axis);
}

LinkType linkTypeOf(const packet_info* pinfo) {
  if (pinfo->rec == nullptr || pinfo->rec->rec_type != REC_TYPE_PACKET) {
    return LinkType::Unsupported;
  }
  switch (pinfo->rec->rec_header.packet_header.pkt_encap) {
    case WTAP_ENCAP_ETHERNET:
      return LinkType::Ethernet;
    case WTAP_ENCAP_SLL:
      return LinkType::LinuxSll;
    case WTAP_ENCAP_SLL2:
      return LinkType::LinuxSll2;
    default:
      return LinkType::Unsupported;
  }
}

// The Info column's text: the axes grouped by drive state, the most common state counted, the
// others named up to kNamedAxes axes and counted beyond ("control active ×26, error: axis3,
// axis17, fault reaction active ×4"), then the rules fired, each once with its count
// ("| COM-005 ×29"): short at 32 axes.
constexpr guint kNamedAxes = 3;

constexpr guint8 kNoState = 0xFF;
const char* stateLabel(guint8 state) {
  return state == kNoState ? "no state" : driveStateName(static_cast<DriveState>(state));
}

bool sameSlave(const SaidRecord& a, const SaidRecord& b) {
  return a.addressed == b.addressed && a.slave == b.slave;
}

// What the drives and ESCs said, after the rules: "| 0x03E9 emergency 0x8611, SDO abort
// 0x1003:2"; the first kNamedSaid named, the rest counted.
constexpr guint kNamedSaid = 3;
void appendSaid(wmem_strbuf_t* text, const FrameRecord& record) {
  for (guint i = 0; i < record.said_count && i < kNamedSaid; ++i) {
    const SaidRecord& r = record.said[i];
    const bool new_slave = i == 0 || !sameSlave(r, record.said[i - 1]);
    if (new_slave) {
      if (r.addressed == kAllSlaves) {
        wmem_strbuf_append(text, " | all slaves ");
      } else {
        wmem_strbuf_append_printf(text, " | %s0x%04X ",
                                  r.addressed == kByStation ? "" : "position ", r.slave);
      }
    } else {
      wmem_strbuf_append(text, ", ");
    }
    switch (r.kind) {
      case SaidKind::Emergency:
        wmem_strbuf_append_printf(text, "emergency 0x%04X", r.code);
        break;
      case SaidKind::SdoUpload:
      case SaidKind::SdoDownload:
        wmem_strbuf_append_printf(text, "SDO %s 0x%04X:%u",
                                  r.kind == SaidKind::SdoUpload ? "upload" : "download", r.index,
                                  r.subindex);
        break;
      case SaidKind::SdoAbort:
        wmem_strbuf_append_printf(text, "SDO abort 0x%04X:%u", r.index, r.subindex);
        break;
      case SaidKind::EscRise:
        wmem_strbuf_append_printf(
            text, "%s +%u", diag::escCounterName(static_cast<diag::EscCounter>(r.code)), r.number);
        break;
      case SaidKind::LinkFault:
        wmem_strbuf_append(text, "link fault");
        break;
    }
  }
  if (record.said_count > kNamedSaid) {
    wmem_strbuf_append_printf(text, " +%u more", record.said_count - kNamedSaid);
  }
}

const char* infoText(const FrameRecord& record) {
  auto stateOf = [&record](guint i) {
    const AxisRecord& r = record.axes[i];
    return (r.flags & kHasState) ? r.state : kNoState;
  };
  // Distinct states in order of first appearance, with their counts.
  guint8 states[kMaxAxesPerFrame];
  guint counts[kMaxAxesPerFrame] = {};
  guint distinct = 0;
  for (guint i = 0; i < record.axis_count; ++i) {
    const guint8 state = stateOf(i);
    guint d = 0;
    while (d < distinct && states[d] != state) ++d;
    if (d == distinct) states[distinct++] = state;
    ++counts[d];
  }
  guint most = 0;
  for (guint d = 1; d < distinct; ++d) {
    if (counts[d] > counts[most]) most = d;
  }
  wmem_strbuf_t* text = wmem_strbuf_new(wmem_file_scope(), " [NCSERVO");
  if (record.held == kHeldForLayout) wmem_strbuf_append(text, " layout being learned");
  if (record.held == kHeldForClock) wmem_strbuf_append(text, " clock being judged");
  if (record.duplicate) wmem_strbuf_append(text, " duplicate record, not judged");
  if (distinct > 0 && counts[most] > 2) {
    wmem_strbuf_append_printf(text, " %s \u00d7%u", stateLabel(states[most]), counts[most]);
  }
  for (guint d = 0; d < distinct; ++d) {
    if (d == most && counts[most] > 2) continue;
    wmem_strbuf_append(text, wmem_strbuf_get_len(text) > 9 ? ", " : " ");
    if (counts[d] > kNamedAxes) {
      wmem_strbuf_append_printf(text, "%s \u00d7%u", stateLabel(states[d]), counts[d]);
      continue;
    }
    wmem_strbuf_append_printf(text, "%s:", stateLabel(states[d]));
    const char* separator = " ";
    for (guint i = 0; i < record.axis_count; ++i) {
      if (stateOf(i) != states[d]) continue;
      wmem_strbuf_append_printf(text, "%s%s", separator, axisName(record.axes[i].axis));
      separator = ", ";
    }
  }
  // Each rule once, in the order of its first finding.
  for (guint i = 0; i < record.finding_count; ++i) {
    const guint8 rule = record.findings[i].rule;
    guint seen = 0;
    while (seen < i && record.findings[seen].rule != rule) ++seen;
    if (seen < i) continue;
    guint count = 0;
    for (guint j = i; j < record.finding_count; ++j) count += record.findings[j].rule == rule;
    wmem_strbuf_append_printf(text, "%s%s", i == 0 ? " | " : " ",
                              ruleDef(static_cast<RuleId>(rule)).code);
    if (count > 1) wmem_strbuf_append_printf(text, " \u00d7%u", count);
  }
  appendSaid(text, record);
  wmem_strbuf_append_c(text, ']');
  return wmem_strbuf_finalize(text);
}

// The frame's axes as the first pass found them, in an array shared with recent frames alike.
SharedAxes& keepAxes(std::uint64_t number, const Observation& view, const Validator& by) {
  const FrameDecode& decode = view.decode;
  static AxisRecord axes[kMaxAxesPerFrame];  // dissection is single-threaded
  // Zeroed whole, padding included, for the comparison below.
  std::memset(axes, 0, decode.axis_count * sizeof(AxisRecord));
  for (std::size_t i = 0; i < decode.axis_count; ++i) {
    const AxisPlacement& placement = decode.axes[i];
    const std::optional<DriveState>& state = view.states[i];
    AxisRecord& r = axes[i];
    r.axis = placement.axis;
    const bool structure_only =
        placement.axis < g_structure_only.size() && g_structure_only[placement.axis];
    r.flags = static_cast<guint8>(
        (placement.has_rx ? kHasRx : 0) | (placement.has_tx ? kHasTx : 0) |
        (placement.rx_malformed ? kRxMalformed : 0) | (placement.tx_malformed ? kTxMalformed : 0) |
        (state ? kHasState : 0) | (structure_only ? kStructureOnly : 0));
    if (structure_only) {
      if (g_structure_only_first.size() <= r.axis) g_structure_only_first.resize(r.axis + 1u, 0);
      if (g_structure_only_first[r.axis] == 0)
        g_structure_only_first[r.axis] = static_cast<guint32>(number);
    }
    r.state = state ? static_cast<guint8>(*state) : 0;
    r.rx_offset = static_cast<guint32>(placement.rx_offset);
    r.tx_offset = static_cast<guint32>(placement.tx_offset);
    const AxisModel* model = by.axis(placement.axis);
    if (model == nullptr) continue;
    const std::vector<FieldEdge>& edges = model->edgesIn(number);
    if (!edges.empty()) {
      r.edge_count = static_cast<guint8>(std::min<std::size_t>(edges.size(), 0xFF));
      r.edges = static_cast<const FieldEdge*>(
          wmem_memdup(wmem_file_scope(), edges.data(), r.edge_count * sizeof(FieldEdge)));
    }
    if (const StateChange* change = model->stateChangeIn(number)) {
      r.change = static_cast<const StateChange*>(
          wmem_memdup(wmem_file_scope(), change, sizeof(StateChange)));
    }
  }
  const std::size_t size = decode.axis_count * sizeof(AxisRecord);
  auto alike = [&](const SharedAxes& shared) {
    return shared.axes != nullptr && shared.count == decode.axis_count &&
           std::memcmp(shared.axes, axes, size) == 0;
  };
  // The slot of the frame before the last first, then that of the last, then the others.
  const std::size_t recent = g_recent_shared[0];
  std::size_t found = g_shared_axes.size();
  if (alike(g_shared_axes[recent])) {
    found = recent;
  } else {
    for (std::size_t k = 0; k < g_shared_axes.size(); ++k) {
      if (k != recent && alike(g_shared_axes[k])) {
        found = k;
        break;
      }
    }
  }
  if (found == g_shared_axes.size()) {
    found = g_next_shared;
    g_next_shared = (g_next_shared + 1) % g_shared_axes.size();
    SharedAxes& slot = g_shared_axes[found];
    slot.axes = static_cast<const AxisRecord*>(wmem_memdup(wmem_file_scope(), axes, size));
    slot.count = decode.axis_count;
    slot.info = nullptr;
  }
  g_recent_shared[0] = g_recent_shared[1];
  g_recent_shared[1] = found;
  return g_shared_axes[found];
}

// The record of a frame, emptied: the window's replay keeps anew what the first pass held.
FrameRecord& freshRecord(std::uint64_t number) {
  const std::uint64_t block = number >> kFrameBlockBits;
  if (block >= g_frames.size()) g_frames.resize(block + 1);
  if (!g_frames[block]) g_frames[block].reset(new FrameRecord[kFrameBlock]());
  return g_frames[block][number & (kFrameBlock - 1)] = FrameRecord{};
}

// The findings `by` reported on the frame (those `keep` accepts, all when null), kept with their
// texts in file scope.
void keepFindings(FrameRecord& record, const Validator& by, bool (*keep)(const Finding&)) {
  const std::vector<Finding>& findings = by.findings();
  const auto kept = static_cast<std::size_t>(
      keep == nullptr ? findings.size() : std::count_if(findings.begin(), findings.end(), keep));
  if (kept == 0) return;
  auto* out =
      static_cast<FindingRecord*>(wmem_alloc0(wmem_file_scope(), kept * sizeof(FindingRecord)));
  std::size_t count = 0;
  for (const Finding& f : findings) {
    if (keep != nullptr && !keep(f)) continue;
    const RuleDef& rule = ruleDef(f.rule);
    FindingRecord& r = out[count++];
    r.rule = static_cast<guint8>(f.rule);
    r.axis = f.axis ? *f.axis : kBusAxis;
    r.since = static_cast<guint32>(f.since.frame);
    r.text = wmem_strdup_printf(wmem_file_scope(), "%s %s: %s: %s", rule.code, rule.slug,
                                f.axis ? axisName(&by, *f.axis) : "bus", f.message.c_str());
  }
  record.findings = out;
  record.finding_count = static_cast<guint16>(std::min<std::size_t>(kept, 0xFFFF));
}

// An incident's cause and evidence into its record, in file scope.
void writeIncident(IncidentRecord& r, const Incident& incident) {
  r.axis = incident.axis ? *incident.axis : kBusAxis;
  r.text = wmem_strdup_printf(wmem_file_scope(), "%s: %s", causeDef(incident.cause).name,
                              incident.cause_text.c_str());
  r.evidence_count = static_cast<guint16>(std::min<std::size_t>(incident.evidence.size(), 0xFFFF));
  auto* frames = static_cast<guint32*>(
      wmem_alloc0(wmem_file_scope(), std::max<std::size_t>(r.evidence_count, 1) * sizeof(guint32)));
  for (guint16 e = 0; e < r.evidence_count; ++e) {
    frames[e] = static_cast<guint32>(incident.evidence[e].at.frame);
  }
  r.evidence = frames;
}

// The incidents that began in the frame, kept with their texts and evidence in file scope; and
// the earlier ones whose cause this frame revised, rewritten in their frames' records.
void keepIncidents(FrameRecord& record) {
  const IncidentDetector* detector = g_pipeline->incidents();
  const std::vector<Incident>& all = detector->incidents();
  for (const std::size_t index : detector->revised()) {
    if (index < g_incident_records.size()) writeIncident(*g_incident_records[index], all[index]);
  }
  if (g_incidents_kept >= all.size()) return;
  const std::size_t count = all.size() - g_incidents_kept;
  auto* out =
      static_cast<IncidentRecord*>(wmem_alloc0(wmem_file_scope(), count * sizeof(IncidentRecord)));
  for (std::size_t i = 0; i < count; ++i) {
    writeIncident(out[i], all[g_incidents_kept + i]);
    g_incident_records.push_back(&out[i]);
  }
  g_incidents_kept = all.size();
  record.incidents = out;
  record.incident_count = static_cast<guint16>(std::min<std::size_t>(count, 0xFFFF));
}

// One thing said, from the library's record of it.
SaidRecord saidOf(const DriveMessage& m) {
  SaidRecord r{};
  r.kind = m.kind == DriveMessage::Kind::Emergency     ? SaidKind::Emergency
           : m.kind == DriveMessage::Kind::SdoUpload   ? SaidKind::SdoUpload
           : m.kind == DriveMessage::Kind::SdoDownload ? SaidKind::SdoDownload
                                                       : SaidKind::SdoAbort;
  r.addressed = m.slave.station ? kByStation : kByPosition;
  r.slave = m.slave.station.value_or(m.slave.position.value_or(0));
  r.index = m.index;
  r.subindex = m.subindex;
  r.code = m.emergency.code;
  r.error_register = m.emergency.error_register;
  std::copy(m.emergency.data.begin(), m.emergency.data.end(), r.data);
  r.number = m.abort_code;
  r.request_frame = static_cast<guint32>(m.request_frame.value_or(0));
  r.has_value = m.value.has_value();
  r.value = m.value.value_or(0);
  r.history = errorHistoryEntry(m).has_value();
  return r;
}

SaidRecord saidOf(const EscErrorDelta& d) {
  SaidRecord r{};
  r.kind = SaidKind::EscRise;
  r.addressed = d.broadcast ? kAllSlaves : d.slave.station ? kByStation : kByPosition;
  r.slave = d.slave.station.value_or(d.slave.position.value_or(0));
  r.code = static_cast<guint16>(d.counter);
  r.error_register = d.port;
  r.number = d.delta;
  return r;
}

SaidRecord saidOf(const LinkFault& f) {
  SaidRecord r{};
  r.kind = SaidKind::LinkFault;
  r.addressed = f.reported.station ? kByStation : kByPosition;
  r.slave = f.reported.station.value_or(f.reported.position.value_or(0));
  r.error_register = f.reported_port;
  r.number = f.errors;
  r.text = wmem_strdup(wmem_file_scope(), linkFaultText(f).c_str());
  return r;
}

// What the drives and the ESCs said in the frame, as `by` read it, kept in file scope and grouped
// by slave (one layer each).
void keepSaid(FrameRecord& record, const Validator& by) {
  const std::vector<DriveMessage>& messages = by.mailbox().frameMessages();
  const std::vector<EscErrorDelta>& deltas = by.escErrors().frameDeltas();
  const std::vector<LinkFault>& faults = by.escErrors().frameLinkFaults();
  const std::size_t count = std::min<std::size_t>(messages.size() + deltas.size() + faults.size(),
                                                  std::numeric_limits<guint16>::max());
  if (count == 0) return;
  auto* out = static_cast<SaidRecord*>(wmem_alloc0(wmem_file_scope(), count * sizeof(SaidRecord)));
  std::size_t n = 0;
  for (const DriveMessage& m : messages) {
    if (n < count) out[n++] = saidOf(m);
  }
  for (const EscErrorDelta& d : deltas) {
    if (n < count) out[n++] = saidOf(d);
  }
  for (const LinkFault& f : faults) {
    if (n < count) out[n++] = saidOf(f);
  }
  std::stable_sort(out, out + n, [](const SaidRecord& a, const SaidRecord& b) {
    return a.addressed != b.addressed ? a.addressed < b.addressed : a.slave < b.slave;
  });
  record.said = out;
  record.said_count = static_cast<guint16>(n);
}

bool saysAnything(const Validator& by) {
  return !by.mailbox().frameMessages().empty() || !by.escErrors().frameDeltas().empty() ||
         !by.escErrors().frameLinkFaults().empty();
}

// Keeps what the validator found in one frame, by frame number.
void validateFrame(const PipelineFrame& delivered) {
  const std::uint64_t number = delivered.number;
  const Observation& view = *delivered.judged;
  const FrameDecode& decode = view.decode;
  const Validator& by = *validator();
  const bool any_findings = !by.findings().empty();
  const IncidentDetector* detector = g_pipeline->incidents();
  const bool any_incidents =
      detector->incidents().size() > g_incidents_kept || !detector->revised().empty();
  const bool any_said = saysAnything(by);
  if (decode.axis_count == 0 && !any_findings && !any_incidents && !any_said) {
    if (FrameRecord* kept = frameSlot(number)) *kept = FrameRecord{};
    return;
  }
  FrameRecord& record = freshRecord(number);
  record.copy = static_cast<guint8>(decode.copy);
  record.axis_count = static_cast<guint16>(decode.axis_count);
  SharedAxes* shared = decode.axis_count > 0 ? &keepAxes(number, view, by) : nullptr;
  record.axes = shared != nullptr ? shared->axes : nullptr;
  const FrameTiming& timing = by.frameTiming();
  record.timing = static_cast<guint8>((timing.interval_ns ? kHasInterval : 0) |
                                      (timing.deviation_ns ? kHasDeviation : 0) |
                                      (timing.latency_ns ? kHasLatency : 0));
  record.interval_ns = timing.interval_ns.value_or(0);
  record.deviation_ns = timing.deviation_ns.value_or(0);
  record.latency_ns = timing.latency_ns.value_or(0);
  record.clock = static_cast<guint8>(g_pipeline->clockStage().choice().source);
  keepFindings(record, by, nullptr);
  keepIncidents(record);
  if (any_said) keepSaid(record, by);
  if (shared == nullptr || any_findings || any_said) {
    record.info = infoText(record);
  } else {
    if (shared->info == nullptr) shared->info = infoText(record);
    record.info = shared->info;
  }
}

// A record the pipeline dropped as a copy of one within its cycle (docs/cli.md#duplicates).
void keepDuplicate(std::uint64_t number) {
  FrameRecord& record = freshRecord(number);
  record.duplicate = true;
  record.info = infoText(record);
}

// A frame the learning window holds, on the first pass: judged in its turn for the findings that
// need no layout; one that may carry process data says that its layout is being learned.
void keepHeldFrame(std::uint64_t number, const EcatFrame& frame) {
  static const std::vector<Finding> kNone;
  const Validator* judge = g_pipeline->heldJudge();
  const std::vector<Finding>& findings = judge != nullptr ? judge->findings() : kNone;
  const bool held = frame.mayCarryProcessData();
  const bool any_findings = std::any_of(findings.begin(), findings.end(), standsWithoutLayout);
  const bool any_said = judge != nullptr && saysAnything(*judge);
  if (!held && !any_findings && !any_said) return;
  FrameRecord& record = freshRecord(number);
  record.held = !held                                  ? kNotHeld
                : g_pipeline->clockStage().assessing() ? kHeldForClock
                                                       : kHeldForLayout;
  if (judge != nullptr) keepFindings(record, *judge, standsWithoutLayout);
  if (any_said) keepSaid(record, *judge);
  if (any_findings || any_said) {
    record.info = infoText(record);
  } else {
    if (g_held_info == nullptr) g_held_info = infoText(record);
    record.info = g_held_info;
  }
}

const FrameRecord* recordOf(const packet_info* pinfo) {
  const FrameRecord* record = frameSlot(pinfo->num);
  return record != nullptr && record->info != nullptr ? record : nullptr;
}

// First pass: run the frame through the capture pipeline (or hold it in the learning window).
void analyseFrame(tvbuff_t* tvb, packet_info* pinfo) {
  const LinkType link = linkTypeOf(pinfo);
  if (link == LinkType::Unsupported || g_pipeline == nullptr) return;
  const guint length = tvb_captured_length(tvb);
  const guint8* data = length > 0 ? tvb_get_ptr(tvb, 0, length) : nullptr;
  const ByteReader bytes(data, data != nullptr ? length : 0);
  static EcatFrame frame;  // 8 KiB; dissection is single-threaded
  walkPacket(link, bytes, frame);
  if (frame.status != WalkStatus::Ok && frame.status != WalkStatus::Truncated) return;
  if (!g_timestamp_digits && pinfo->rec->tsprec >= 0 && pinfo->rec->tsprec <= 9) {
    g_timestamp_digits = pinfo->rec->tsprec;
  }
  const std::int64_t time_ns =
      static_cast<std::int64_t>(pinfo->abs_ts.secs) * 1'000'000'000 + pinfo->abs_ts.nsecs;
  g_pipeline->onWalkedFrame(pinfo->num, time_ns, link, bytes, frame);
  if (g_pipeline->learning()) keepHeldFrame(pinfo->num, frame);
}

// Whether an item is needed: the tree is shown, or a filter, column or tap references the field
// (as proto_field_is_referenced, read from the registration kept at hand-off).
bool wanted(proto_tree* tree, const header_field_info* field) {
  return tree != nullptr && (PTREE_DATA(tree)->visible || field->ref_type != HF_REF_TYPE_NONE);
}
// Whether the tree is shown (-V, -O, the GUI's details), where labels are read.
bool shown(proto_tree* tree) {
  return tree != nullptr && PTREE_DATA(tree)->visible;
}
// Whether an axis gets its protocol item: in a shown tree, for a filter on `ncservo` itself, and
// where Wireshark wants protocols (fake_protocols off: the protocol hierarchy). A reference to
// one of its fields alone needs only that field's items; the axis stays a layer all the same,
// as its layer is counted by the call to its dissector (`ncservo.state#3`).
bool protocolWanted(proto_tree* tree) {
  return tree != nullptr && (PTREE_DATA(tree)->visible || !PTREE_DATA(tree)->fake_protocols ||
                             hfi_protocol->ref_type == HF_REF_TYPE_DIRECT);
}

// One word or part from the value the library already read: Wireshark adds an item from a value
// for less than it takes to read the bytes again. The region was read whole, so the item covers
// captured bytes.
proto_item* addValue(proto_tree* tree, int hf, tvbuff_t* tvb, guint offset, gint length,
                     const FieldValue& v) {
  switch (v.kind) {
    case FieldValue::Kind::Signed:
      return length == 8
                 ? proto_tree_add_int64(tree, hf, tvb, offset, length, v.i)
                 : proto_tree_add_int(tree, hf, tvb, offset, length, static_cast<gint32>(v.i));
    case FieldValue::Kind::Unsigned:
      return proto_tree_add_uint(tree, hf, tvb, offset, length, static_cast<guint32>(v.u));
    case FieldValue::Kind::Float:
      return proto_tree_add_float(tree, hf, tvb, offset, length, static_cast<float>(v.f));
  }
  return nullptr;
}

// The word's bit fields one by one, for a shown tree, as the field table's view says: a parameter
// table by its number; cause bits that are clear and bits at rest hidden behind one line each, so
// that -V on many axes stays readable (hidden items still serve filters and -T fields; -V and the
// details pane skip them).
void addBitsShown(proto_tree* word_tree, tvbuff_t* tvb, guint offset, const WordItems& word,
                  std::uint32_t value) {
  guint clear_causes = 0;
  guint at_rest = 0;
  char at_rest_names[256] = "";
  for (std::size_t c = 0; word.children[c] != nullptr; ++c) {
    const int hf = *word.children[c];
    const FieldDef& f = kFields[word.child_rows[c]];
    if (f.view == FieldView::Cause && (value & f.mask) == 0) {
      ++clear_causes;
      proto_item_set_hidden(proto_tree_add_boolean(word_tree, hf, tvb, offset, word.length, value));
      continue;
    }
    if (isAtRest(f, value)) {
      g_strlcat(at_rest_names, at_rest == 0 ? "" : ", ", sizeof at_rest_names);
      g_strlcat(at_rest_names, f.label, sizeof at_rest_names);
      ++at_rest;
      proto_item_set_hidden(
          f.kind == FieldKind::Flag
              ? proto_tree_add_boolean(word_tree, hf, tvb, offset, word.length, value)
              : proto_tree_add_uint(word_tree, hf, tvb, offset, word.length, value));
      continue;
    }
    if (f.view == FieldView::ParameterTable) {
      proto_tree_add_uint_format_value(word_tree, hf, tvb, offset, word.length, value, "table %u",
                                       parameterTable(f.word, value));
      continue;
    }
    if (f.kind == FieldKind::Flag) {
      proto_tree_add_boolean(word_tree, hf, tvb, offset, word.length, value);
    } else {
      proto_tree_add_uint(word_tree, hf, tvb, offset, word.length, value);
    }
  }
  if (clear_causes > 0) {
    proto_tree_add_subtree_format(word_tree, tvb, offset, word.length, ett_clear_causes, nullptr,
                                  "%u cause bits clear", clear_causes);
  }
  if (at_rest > 0) {
    proto_tree_add_subtree_format(word_tree, tvb, offset, word.length, ett_clear_causes, nullptr,
                                  "At rest: %s", at_rest_names);
  }
}

// What the layers of a frame add, decided once per frame for all of them (the tree and the
// fields' references do not change within a frame): in a shown tree everything; in a tree that
// is not shown, only the items a filter, column or tap references, and only the PDOs they read.
struct FrameWants {
  bool shown;     // shown(tree)
  bool protocol;  // protocolWanted(tree)
  bool derived[kDerivedCount];
  bool read[2];  // the PDOs to read: [Pdo::Rx], [Pdo::Tx]
  // The rows of kFields referenced, by PDO; when the tree is not shown.
  std::size_t count[2];
  std::uint16_t rows[2][kFieldCount];
  bool is(Derived id) const { return derived[static_cast<std::size_t>(id)]; }
};
static_assert(kFieldCount <= 0xFFFF);

void gatherWants(proto_tree* tree, FrameWants& wants) {
  wants.shown = shown(tree);
  wants.protocol = protocolWanted(tree);
  for (std::size_t i = 0; i < kDerivedCount; ++i) wants.derived[i] = wanted(tree, hfi_derived[i]);
  wants.count[0] = wants.count[1] = 0;
  // A part shown only when the status word says so (FieldWhen) reads the TxPDO too.
  bool conditional = false;
  if (!wants.shown) {
    for (std::size_t i = 0; i < kFieldCount; ++i) {
      if (hfi_field[i]->ref_type == HF_REF_TYPE_NONE) continue;
      const auto pdo = static_cast<std::size_t>(wordDef(kFields[i].word).pdo);
      wants.rows[pdo][wants.count[pdo]++] = static_cast<std::uint16_t>(i);
      conditional = conditional || kFields[i].when != FieldWhen::Always;
    }
  }
  constexpr auto kRx = static_cast<std::size_t>(Pdo::Rx);
  constexpr auto kTx = static_cast<std::size_t>(Pdo::Tx);
  wants.read[kRx] = wants.shown || wants.count[kRx] > 0;
  wants.read[kTx] =
      wants.shown || wants.count[kTx] > 0 || conditional || wants.is(Derived::Message);
}

// One referenced item, from its word's value: no subtree, no bitmask call adding every bit.
void addReferencedItem(proto_tree* tree, tvbuff_t* tvb, guint offset, std::size_t row,
                       const PdoValues& values) {
  const FieldDef& f = kFields[row];
  const WordItems& word = word_items[static_cast<std::size_t>(f.word)];
  const auto raw = static_cast<guint32>(values.raw[static_cast<std::size_t>(f.word)]);
  switch (f.kind) {
    case FieldKind::Word:
      addValue(tree, hf_field[row], tvb, offset + word.offset, word.length, fieldValue(f, values));
      break;
    case FieldKind::Flag:
      proto_tree_add_boolean(tree, hf_field[row], tvb, offset + word.offset, word.length, raw);
      break;
    case FieldKind::BitRange:
      proto_tree_add_uint(tree, hf_field[row], tvb, offset + word.offset, word.length, raw);
      break;
    case FieldKind::Part:
      if (fieldApplies(f, values)) {
        const FieldSpan span = fieldSpan(f);
        addValue(tree, hf_field[row], tvb, offset + static_cast<guint>(span.offset),
                 static_cast<gint>(span.length), fieldValue(f, values));
      }
      break;
  }
}

// Adds the words of one PDO, each bit field under its word, as the field table defines them.
// In a tree that is not shown, only the referenced items.
void addPdo(proto_tree* tree, tvbuff_t* tvb, Pdo pdo, guint offset, const PdoValues& values,
            const FrameWants& wants) {
  if (!wants.shown) {
    const auto p = static_cast<std::size_t>(pdo);
    for (std::size_t k = 0; k < wants.count[p]; ++k) {
      addReferencedItem(tree, tvb, offset, wants.rows[p][k], values);
    }
    return;
  }
  const std::size_t first = firstWordOf(pdo);
  for (std::size_t w = first; w < first + wordCountOf(pdo); ++w) {
    const WordItems& word = word_items[w];
    proto_item* item = nullptr;
    if (word.children[0] != nullptr) {
      const auto value = static_cast<std::uint32_t>(values.raw[w]);
      item = proto_tree_add_uint(tree, hf_field[word.row], tvb, offset + word.offset, word.length,
                                 value);
      if ((value & causeMask(kFields[word.row].word)) != 0) {
        char causes[256];
        plugin::sewCausesText(value, causes, sizeof causes);
        proto_item_append_text(item, " (%s)", causes);
      }
      addBitsShown(proto_item_add_subtree(item, ett_word[w]), tvb, offset + word.offset, word,
                   value);
    } else {
      item = addValue(tree, hf_field[word.row], tvb, offset + word.offset, word.length,
                      fieldValue(kFields[word.row], values));
    }
    if (word.part_count == 0) continue;
    proto_tree* word_tree = proto_item_add_subtree(item, ett_word[w]);
    for (std::size_t p = 0; p < word.part_count; ++p) {
      const FieldDef& f = kFields[word.parts[p]];
      if (!fieldApplies(f, values)) continue;
      const FieldSpan span = fieldSpan(f);
      addValue(word_tree, hf_field[word.parts[p]], tvb, offset + static_cast<guint>(span.offset),
               static_cast<gint>(span.length), fieldValue(f, values));
    }
  }
}

// A finding as an item with its details, carrying the expert info of its rule. The expert
// summary is the rule's alone, so that Expert Information groups a rule's findings in one row.
void addFinding(proto_tree* tree, tvbuff_t* tvb, packet_info* pinfo, guint anchor,
                const FindingRecord& f, const FrameWants& wants) {
  proto_item* item =
      proto_tree_add_string(tree, derivedHf(Derived::Finding), tvb, anchor, 0, f.text);
  proto_item_set_generated(item);
  if (f.since != 0 && wants.is(Derived::SinceFrame)) {
    proto_tree* details = proto_item_add_subtree(item, ett_finding);
    proto_item_set_generated(
        proto_tree_add_uint(details, derivedHf(Derived::SinceFrame), tvb, anchor, 0, f.since));
  }
  expert_add_info(pinfo, item, &ei_rule[f.rule]);
}

// docs/incidents.md: the incident's cause, with a link to each frame of its chain.
void addIncident(proto_tree* tree, tvbuff_t* tvb, guint anchor, const IncidentRecord& incident,
                 const FrameWants& wants) {
  if (!wants.is(Derived::Incident) && !wants.is(Derived::IncidentEvidence)) return;
  proto_item* item =
      proto_tree_add_string(tree, derivedHf(Derived::Incident), tvb, anchor, 0, incident.text);
  proto_item_set_generated(item);
  if (incident.evidence_count == 0 || !wants.is(Derived::IncidentEvidence)) return;
  proto_tree* chain = proto_item_add_subtree(item, ett_finding);
  for (guint e = 0; e < incident.evidence_count; ++e) {
    proto_item_set_generated(proto_tree_add_uint(chain, derivedHf(Derived::IncidentEvidence), tvb,
                                                 anchor, 0, incident.evidence[e]));
  }
}

// What the frame dissector hands each axis's layer.
struct LayerData {
  const FrameRecord* record;
  const AxisRecord* axis;  // null: a layer only for findings about the bus
  bool first;              // the frame's first layer, which carries the bus's findings
  const FrameWants* wants;
  ByteReader bytes;        // the frame's captured bytes
  const SaidRecord* said;  // what one slave said in the frame, when the layer is that slave's
  guint said_count;
};

// Findings and incidents about the bus, or about an axis this frame does not carry.
bool frameLevel(const FrameRecord& record, guint16 axis) {
  if (axis == kBusAxis) return true;
  for (guint a = 0; a < record.axis_count; ++a) {
    if (record.axes[a].axis == axis) return false;
  }
  return true;
}

void addAxisItems(proto_tree* tree, tvbuff_t* tvb, const FrameRecord& record, const AxisRecord& r,
                  guint start, const char* name, const char* state, const LayerData& layer) {
  const FrameWants& wants = *layer.wants;
  if (wants.is(Derived::Copy)) {
    proto_item_set_generated(
        proto_tree_add_string(tree, derivedHf(Derived::Copy), tvb, start, 0,
                              copyKindName(static_cast<CopyKind>(record.copy))));
  }
  if (wants.is(Derived::Axis)) {
    proto_tree_add_uint(tree, derivedHf(Derived::Axis), tvb, start, 0, r.axis);
  }
  if (wants.is(Derived::AxisName)) {
    proto_tree_add_string(tree, derivedHf(Derived::AxisName), tvb, start, 0, name);
  }
  const bool message_wanted = (r.flags & kHasTx) && wants.is(Derived::Message);
  PdoValues values;
  if ((r.flags & kHasRx) && wants.read[static_cast<std::size_t>(Pdo::Rx)]) {
    readPdo(Pdo::Rx, layer.bytes, r.rx_offset, values);
  }
  if ((r.flags & kHasTx) && wants.read[static_cast<std::size_t>(Pdo::Tx)]) {
    readPdo(Pdo::Tx, layer.bytes, r.tx_offset, values);
  }
  if (values.has_rx) addPdo(tree, tvb, Pdo::Rx, r.rx_offset, values, wants);
  if (values.has_tx) addPdo(tree, tvb, Pdo::Tx, r.tx_offset, values, wants);
  if (state != nullptr && wants.is(Derived::State)) {
    proto_item_set_generated(
        proto_tree_add_string(tree, derivedHf(Derived::State), tvb, start, 0, state));
  }
  if (values.has_tx && message_wanted) {
    char message[128];
    plugin::messageText(values, message, sizeof message);
    proto_item_set_generated(
        proto_tree_add_string(tree, derivedHf(Derived::Message), tvb, r.tx_offset, 0, message));
  }
  // The transition's own axis under it: a frame's layers are all `ncservo`, so `-e ncservo.axis`
  // on a transition filter lists every axis of the frame (docs/plugin.md).
  const bool transition_axis_wanted =
      wants.is(Derived::TransitionAxis) || wants.is(Derived::TransitionAxisName);
  if (r.change != nullptr && (wants.is(Derived::Transition) || transition_axis_wanted)) {
    char transition[96];
    plugin::transitionText(*r.change, transition, sizeof transition);
    proto_item* item =
        proto_tree_add_string(tree, derivedHf(Derived::Transition), tvb, start, 0, transition);
    proto_item_set_generated(item);
    if (transition_axis_wanted) {
      proto_tree* sub = proto_item_add_subtree(item, ett_transition);
      proto_item_set_generated(
          proto_tree_add_uint(sub, derivedHf(Derived::TransitionAxis), tvb, start, 0, r.axis));
      proto_item_set_generated(
          proto_tree_add_string(sub, derivedHf(Derived::TransitionAxisName), tvb, start, 0, name));
    }
  }
  if (r.edge_count > 0 && wants.is(Derived::Edge)) {
    for (guint e = 0; e < r.edge_count; ++e) {
      char edge[64];
      plugin::edgeText(r.edges[e], edge, sizeof edge);
      proto_item_set_generated(
          proto_tree_add_string(tree, derivedHf(Derived::Edge), tvb, start, 0, edge));
    }
  }
}

// The frame's cycle interval, its deviation from nominal and its return latency, in µs; a shown
// tree gives them their unit, with the decimals the timestamps resolve (as the CLI's text).
void addTimingItems(proto_tree* tree, tvbuff_t* tvb, const FrameRecord& record, guint anchor,
                    const FrameWants& wants) {
  const int decimals =
      timestampResolutionNs(TimestampSource::Capture, g_timestamp_digits.value_or(6)) >= 1000 ? 1
                                                                                              : 3;
  const struct {
    Derived id;
    guint8 flag;
    gint64 ns;
  } items[] = {{Derived::CycleInterval, kHasInterval, record.interval_ns},
               {Derived::CycleDeviation, kHasDeviation, record.deviation_ns},
               {Derived::Latency, kHasLatency, record.latency_ns}};
  if (wants.is(Derived::Clock)) {
    proto_item_set_generated(
        proto_tree_add_string(tree, derivedHf(Derived::Clock), tvb, anchor, 0,
                              clockSourceName(static_cast<ClockSource>(record.clock))));
  }
  for (const auto& item : items) {
    if ((record.timing & item.flag) == 0 || !wants.is(item.id)) continue;
    const double us = static_cast<double>(item.ns) / 1000.0;
    proto_item_set_generated(
        wants.shown ? proto_tree_add_double_format_value(tree, derivedHf(item.id), tvb, anchor, 0,
                                                         us, "%.*f \u00b5s", decimals, us)
                    : proto_tree_add_double(tree, derivedHf(item.id), tvb, anchor, 0, us));
  }
}

// docs/plugin.md: a structure-only layout is noted on the axis's first frame and on the frames
// with its findings.
bool structureOnlyNoted(const FrameRecord& record, const AxisRecord& axis, guint32 frame) {
  if (!(axis.flags & kStructureOnly)) return false;
  if (axis.axis < g_structure_only_first.size() && g_structure_only_first[axis.axis] == frame)
    return true;
  for (guint i = 0; i < record.finding_count; ++i) {
    if (record.findings[i].axis == axis.axis) return true;
  }
  return false;
}

// The capture's notes, on its first decoded frame: the preferences not used and the layout's
// misfits (docs/plugin.md#preferences).
bool notesFrame(const packet_info* pinfo) {
  return pinfo->num == g_first_frame && (!g_preference_errors.empty() || !g_layout_misfits.empty());
}

void addCaptureNotes(packet_info* pinfo, proto_item* root) {
  if (!notesFrame(pinfo)) return;
  for (const std::string& error : g_preference_errors) {
    expert_add_info_format(pinfo, root, noteEi(ExpertNote::PreferenceError),
                           "NCSERVO preference not used: %s", error.c_str());
  }
  for (const std::string& misfit : g_layout_misfits) {
    expert_add_info_format(pinfo, root, noteEi(ExpertNote::LayoutMisfit), "layout does not fit: %s",
                           misfit.c_str());
  }
}

void addDerivedUint(proto_tree* tree, tvbuff_t* tvb, const FrameWants& wants, Derived id,
                    guint32 value) {
  if (wants.is(id))
    proto_item_set_generated(proto_tree_add_uint(tree, derivedHf(id), tvb, 0, 0, value));
}

// An emergency's code, its error register with 1001h's bits below it, and its data.
void addEmergencyItems(proto_tree* tree, tvbuff_t* tvb, const SaidRecord& r,
                       const FrameWants& wants) {
  addDerivedUint(tree, tvb, wants, Derived::EmcyCode, r.code);
  constexpr auto kFirstBit = static_cast<std::size_t>(Derived::EmcyRegisterGeneric);
  constexpr auto kLastBit = static_cast<std::size_t>(Derived::EmcyRegisterManufacturer);
  bool bits_wanted = false;
  for (std::size_t b = kFirstBit; b <= kLastBit; ++b) bits_wanted = bits_wanted || wants.derived[b];
  if (wants.is(Derived::EmcyRegister) || bits_wanted) {
    proto_item* item =
        proto_tree_add_uint(tree, derivedHf(Derived::EmcyRegister), tvb, 0, 0, r.error_register);
    proto_item_set_generated(item);
    if (bits_wanted) {
      proto_tree* bits = proto_item_add_subtree(item, ett_finding);
      for (std::size_t b = kFirstBit; b <= kLastBit; ++b) {
        proto_item_set_generated(
            proto_tree_add_boolean(bits, hf_derived[b], tvb, 0, 0, r.error_register));
      }
    }
  }
  if (wants.is(Derived::EmcyData)) {
    proto_item_set_generated(proto_tree_add_bytes_with_length(tree, derivedHf(Derived::EmcyData),
                                                              tvb, 0, 0, r.data, sizeof r.data));
  }
}

// An SDO answer or abort: the object, the value or the abort code, the request's frame, and a
// 1003h entry's parts (docs/drive-messages.md).
void addSdoItems(proto_tree* tree, tvbuff_t* tvb, const SaidRecord& r, const FrameWants& wants) {
  addDerivedUint(tree, tvb, wants, Derived::SdoIndex, r.index);
  addDerivedUint(tree, tvb, wants, Derived::SdoSubindex, r.subindex);
  if (r.kind == SaidKind::SdoAbort) addDerivedUint(tree, tvb, wants, Derived::SdoAbort, r.number);
  if (r.has_value && wants.is(Derived::SdoValue)) {
    proto_item_set_generated(
        proto_tree_add_uint64(tree, derivedHf(Derived::SdoValue), tvb, 0, 0, r.value));
  }
  const char* object = diag::objectName(r.index);
  if (object != nullptr && wants.is(Derived::SdoObject)) {
    proto_item_set_generated(
        proto_tree_add_string(tree, derivedHf(Derived::SdoObject), tvb, 0, 0, object));
  }
  if (r.request_frame != 0) {
    addDerivedUint(tree, tvb, wants, Derived::SdoRequestIn, r.request_frame);
  }
  if (r.history) {
    const diag::ErrorFieldEntry entry = diag::errorFieldEntry(static_cast<std::uint32_t>(r.value));
    addDerivedUint(tree, tvb, wants, Derived::ErrhistNumber, entry.number);
    addDerivedUint(tree, tvb, wants, Derived::ErrhistClass, entry.error_class);
    addDerivedUint(tree, tvb, wants, Derived::ErrhistCode, entry.code);
  }
}

// Emergencies, aborts and link faults are expert info, on `item` (null without a tree).
void addSaidExpert(packet_info* pinfo, proto_item* item, const SaidRecord& r) {
  if (r.kind == SaidKind::Emergency)
    expert_add_info(pinfo, item, noteEi(ExpertNote::DriveEmergency));
  if (r.kind == SaidKind::SdoAbort) expert_add_info(pinfo, item, noteEi(ExpertNote::SdoAborted));
  if (r.kind == SaidKind::LinkFault) {
    expert_add_info_format(pinfo, item, noteEi(ExpertNote::LinkFaultNamed), "%s", r.text);
  }
}

// What one slave said in the frame, with its expert info.
void addSaidItems(proto_tree* tree, tvbuff_t* tvb, packet_info* pinfo, proto_item* root,
                  const LayerData& layer) {
  const FrameWants& wants = *layer.wants;
  for (guint i = 0; i < layer.said_count; ++i) {
    const SaidRecord& r = layer.said[i];
    switch (r.kind) {
      case SaidKind::Emergency:
        addEmergencyItems(tree, tvb, r, wants);
        break;
      case SaidKind::SdoUpload:
      case SaidKind::SdoDownload:
      case SaidKind::SdoAbort:
        addSdoItems(tree, tvb, r, wants);
        break;
      case SaidKind::EscRise:
        if (r.addressed == kByStation) {
          addDerivedUint(tree, tvb, wants, Derived::EscStation, r.slave);
        }
        addDerivedUint(tree, tvb, wants, Derived::EscPort, r.error_register);
        if (wants.is(Derived::EscCounter)) {
          proto_item_set_generated(
              proto_tree_add_string(tree, derivedHf(Derived::EscCounter), tvb, 0, 0,
                                    diag::escCounterName(static_cast<diag::EscCounter>(r.code))));
        }
        addDerivedUint(tree, tvb, wants, Derived::EscDelta, r.number);
        break;
      case SaidKind::LinkFault:
        if (wants.is(Derived::LinkFault)) {
          proto_item_set_generated(
              proto_tree_add_string(tree, derivedHf(Derived::LinkFault), tvb, 0, 0, r.text));
        }
        break;
    }
    addSaidExpert(pinfo, root, r);
  }
}

// One layer of the protocol per axis, so that Wireshark's layer operator selects an axis:
// `ncservo.state#3` is the third axis of the frame (docs/plugin.md).
int dissectLayer(tvbuff_t* tvb, packet_info* pinfo, proto_tree* tree, void* data) {
  const auto& layer = *static_cast<const LayerData*>(data);
  const FrameRecord& record = *layer.record;
  // A malformed region's expert info, a structure-only layout's note and a held frame's note
  // need an item to be found by their filters.
  const bool structure_only_note =
      layer.axis != nullptr && structureOnlyNoted(record, *layer.axis, pinfo->num);
  const bool protocol_item =
      layer.wants->protocol ||
      (tree != nullptr && layer.axis != nullptr &&
       ((layer.axis->flags & (kRxMalformed | kTxMalformed)) != 0 || structure_only_note)) ||
      (tree != nullptr && (record.held != kNotHeld || record.duplicate)) ||
      (tree != nullptr && layer.first && notesFrame(pinfo)) ||
      (tree != nullptr && layer.said_count > 0);
  proto_item* root = nullptr;
  proto_tree* layer_tree = tree;
  guint start = 0;
  if (layer.axis != nullptr) {
    const AxisRecord& r = *layer.axis;
    // Anchor the axis at its first PDO that was captured; an item past the captured bytes
    // would raise an exception.
    start = (r.flags & kHasRx) ? r.rx_offset : (r.flags & kHasTx) ? r.tx_offset : 0;
    // The name and state only where an item shows them.
    const FrameWants& wants = *layer.wants;
    const char* name =
        protocol_item || wants.is(Derived::AxisName) || wants.is(Derived::TransitionAxisName)
            ? axisName(r.axis)
            : nullptr;
    const char* state = (r.flags & kHasState) && (protocol_item || wants.is(Derived::State))
                            ? driveStateName(static_cast<DriveState>(r.state))
                            : nullptr;
    if (protocol_item) {
      const std::optional<DriveState> known_state =
          (r.flags & kHasState) ? std::optional(static_cast<DriveState>(r.state)) : std::nullopt;
      const plugin::AxisTexts texts = plugin::axisTexts(r.axis, name, known_state);
      name = texts.name;
      state = texts.state;
      root = proto_tree_add_protocol_format(tree, proto_ncservo, tvb, start, 0, "%s", texts.label);
      layer_tree = proto_item_add_subtree(root, ett_axis);
    }
    addAxisItems(layer_tree, tvb, record, r, start, name, state, layer);
    if (layer.first && record.timing != 0) {
      addTimingItems(layer_tree, tvb, record, start, *layer.wants);
    }
    for (const bool rx : {true, false}) {
      if (!(r.flags & (kRxMalformed | kTxMalformed))) break;
      if (!(r.flags & (rx ? kRxMalformed : kTxMalformed))) continue;
      expert_add_info_format(pinfo, root, noteEi(ExpertNote::Malformed),
                             "Axis %u: the %s (%u bytes at frame offset %u) is cut short or lies "
                             "partly outside its datagram",
                             r.axis, rx ? "RxPDO" : "TxPDO",
                             static_cast<unsigned>(rx ? kRxPdoSize : kTxPdoSize),
                             rx ? r.rx_offset : r.tx_offset);
    }
    if (structure_only_note) expert_add_info(pinfo, root, noteEi(ExpertNote::StructureOnly));
  } else if (protocol_item) {
    root = layer.said_count == 0 ? proto_tree_add_item(tree, proto_ncservo, tvb, 0, 0, ENC_NA)
           : layer.said[0].addressed == kAllSlaves
               ? proto_tree_add_protocol_format(tree, proto_ncservo, tvb, 0, 0,
                                                "NC-Servo all slaves (a broadcast read's sum)")
               : proto_tree_add_protocol_format(
                     tree, proto_ncservo, tvb, 0, 0, "NC-Servo %s0x%04X",
                     layer.said[0].addressed == kByStation ? "station " : "position ",
                     layer.said[0].slave);
    layer_tree = proto_item_add_subtree(root, ett_ncservo);
  }
  if (layer.said_count > 0) addSaidItems(layer_tree, tvb, pinfo, root, layer);
  if (layer.first) {
    addCaptureNotes(pinfo, root);
    if (record.held == kHeldForLayout)
      expert_add_info(pinfo, root, noteEi(ExpertNote::LayoutLearning));
    if (record.held == kHeldForClock)
      expert_add_info(pinfo, root, noteEi(ExpertNote::ClockJudging));
    if (record.duplicate && layer.wants->is(Derived::Duplicate)) {
      proto_item_set_generated(proto_tree_add_string(layer_tree, derivedHf(Derived::Duplicate), tvb,
                                                     0, 0, "a copy of a record within its cycle"));
    }
  }
  for (guint i = 0; i < record.finding_count; ++i) {
    const FindingRecord& f = record.findings[i];
    const bool here = layer.axis != nullptr && f.axis == layer.axis->axis;
    if (here || (layer.first && frameLevel(record, f.axis))) {
      addFinding(layer_tree, tvb, pinfo, start, f, *layer.wants);
    }
  }
  for (guint i = 0; i < record.incident_count; ++i) {
    const IncidentRecord& incident = record.incidents[i];
    const bool here = layer.axis != nullptr && incident.axis == layer.axis->axis;
    if (here || (layer.first && frameLevel(record, incident.axis))) {
      addIncident(layer_tree, tvb, start, incident, *layer.wants);
    }
  }
  return static_cast<int>(layer.bytes.size());
}

// Without a tree (the packet list) only the findings' expert info and the Info column are
// needed: Wireshark counts and colours by them.
void addExpertOnly(packet_info* pinfo, const FrameRecord& record) {
  addCaptureNotes(pinfo, nullptr);
  if (record.held == kHeldForLayout)
    expert_add_info(pinfo, nullptr, noteEi(ExpertNote::LayoutLearning));
  if (record.held == kHeldForClock)
    expert_add_info(pinfo, nullptr, noteEi(ExpertNote::ClockJudging));
  for (guint a = 0; g_any_structure_only && a < record.axis_count; ++a) {
    if (structureOnlyNoted(record, record.axes[a], pinfo->num))
      expert_add_info(pinfo, nullptr, noteEi(ExpertNote::StructureOnly));
  }
  for (guint i = 0; i < record.finding_count; ++i) {
    expert_add_info(pinfo, nullptr, &ei_rule[record.findings[i].rule]);
  }
  for (guint i = 0; i < record.said_count; ++i) addSaidExpert(pinfo, nullptr, record.said[i]);
}

int dissectNcservo(tvbuff_t* tvb, packet_info* pinfo, proto_tree* tree, void*) {
  if (!g_capture_open || !proto_is_protocol_enabled(protocol_ncservo)) {
    return 0;
  }
  if (!PINFO_FD_VISITED(pinfo)) {
    analyseFrame(tvb, pinfo);
  } else if (g_pipeline != nullptr) {
    // The capture may have ended inside the learning window: decide with what the first pass
    // held. The plugin has no end of capture: a gap in the last cycle goes unjudged here.
    g_pipeline->endLearning();
    if (!g_misfits_taken) g_layout_misfits = g_pipeline->layoutMisfitsSoFar();
    g_misfits_taken = true;
  }
  const FrameRecord* record = recordOf(pinfo);
  if (record == nullptr) return 0;
  if (g_first_frame == 0) g_first_frame = pinfo->num;
  // The postdissector has no protocol of its own: expert info added here names this one.
  pinfo->current_proto = "NCSERVO";
  // col_append_lstr finds the column's end with strlen, where col_append_str's g_strlcat walks
  // it byte by byte in Wireshark 4.0: the same text for less.
  col_append_lstr(pinfo->cinfo, COL_INFO, record->info, COL_ADD_LSTR_TERMINATOR);
  if (tree == nullptr) {
    addExpertOnly(pinfo, *record);
    return static_cast<int>(tvb_captured_length(tvb));
  }
  static FrameWants wants;  // dissection is single-threaded
  gatherWants(tree, wants);
  const guint length = tvb_captured_length(tvb);
  LayerData layer{record,
                  nullptr,
                  true,
                  &wants,
                  ByteReader(length > 0 ? tvb_get_ptr(tvb, 0, length) : nullptr, length),
                  nullptr,
                  0};
  if (record->axis_count == 0 && record->said_count == 0) {
    call_dissector_only(layer_handle, tvb, pinfo, tree, &layer);
  }
  for (guint i = 0; i < record->axis_count; ++i) {
    layer.axis = &record->axes[i];
    layer.first = i == 0;
    call_dissector_only(layer_handle, tvb, pinfo, tree, &layer);
  }
  // One layer per slave that said something (docs/drive-messages.md).
  layer.axis = nullptr;
  for (guint i = 0; i < record->said_count;) {
    guint end = i + 1;
    while (end < record->said_count && sameSlave(record->said[end], record->said[i])) ++end;
    layer.first = record->axis_count == 0 && i == 0;
    layer.said = &record->said[i];
    layer.said_count = end - i;
    call_dissector_only(layer_handle, tvb, pinfo, tree, &layer);
    i = end;
  }
  return static_cast<int>(tvb_captured_length(tvb));
}

// `tshark -z ncservo,timing`: the timing block of the CLI's text report (docs/timing.md), from
// the statistics of the validator the first pass ran, printed once the capture was read. Its
// tap carries no packets: the listener only needs the end of the capture.
constexpr const char* kTimingStat = "ncservo,timing";
char timing_listener;  // the listener's identity for the tap system

tap_packet_status takeNoPacket(void*, packet_info*, epan_dissect_t*, const void*, tap_flags_t) {
  return TAP_PACKET_DONT_REDRAW;
}

void drawTiming(void*) {
  // A single pass can end inside the learning window: its frames are validated now.
  if (g_pipeline != nullptr) g_pipeline->endLearning();
  const ClockSource clock =
      g_pipeline != nullptr ? g_pipeline->clockStage().choice().source : ClockSource::Capture;
  const bool own_stamps = clock == ClockSource::Capture || clock == ClockSource::Probe;
  const std::string text = timingText(
      validator() != nullptr ? validator()->bus().timing().summary() : TimingSummary{},
      own_stamps ? timestampSourceName(TimestampSource::Capture) : clockSourceName(clock),
      own_stamps ? timestampResolutionNs(TimestampSource::Capture, g_timestamp_digits.value_or(6))
                 : 1);
  std::printf("\n%s\nNCSERVO timing\n%s%s\n", std::string(67, '=').c_str(), text.c_str(),
              std::string(67, '=').c_str());
}

// Whether the statistic started.
bool startTimingStat(const char* arguments, void*) {
  if (std::strcmp(arguments, kTimingStat) != 0) {
    report_failure("NCSERVO: -z %s: %s takes no filter or other arguments", arguments, kTimingStat);
    return false;
  }
  GString* error = register_tap_listener("ncservo", &timing_listener, nullptr, TL_REQUIRES_NOTHING,
                                         nullptr, takeNoPacket, drawTiming, nullptr);
  if (error != nullptr) {
    report_failure("NCSERVO: -z %s: %s", arguments, error->str);
    g_string_free(error, TRUE);
    return false;
  }
  return true;
}

void registerTimingStat() {
  register_tap("ncservo");
  static stat_tap_ui timing_stat = {REGISTER_STAT_GROUP_GENERIC,
                                    "NC-Servo timing",
                                    kTimingStat,
                                    ws::statTapInit<startTimingStat>,
                                    0,
                                    nullptr};
  register_stat_tap_ui(&timing_stat, nullptr);
}

void registerProtocol() {
  proto_ncservo = proto_register_protocol("NC-Servo EtherCAT process data", "NCSERVO", "ncservo");
  std::size_t count = 0;
  hf_register_info* hf = buildFieldRegistrations(count);
  proto_register_field_array(proto_ncservo, hf, static_cast<int>(count));
  buildWordItems();

  static gint* ett[5 + kWordCount];
  ett[0] = &ett_ncservo;
  ett[1] = &ett_axis;
  ett[2] = &ett_finding;
  ett[3] = &ett_clear_causes;
  ett[4] = &ett_transition;
  for (std::size_t w = 0; w < kWordCount; ++w) {
    ett_word[w] = -1;
    ett[5 + w] = &ett_word[w];
  }
  proto_register_subtree_array(ett, static_cast<int>(std::size(ett)));

  expert_module_t* expert = expert_register_protocol(proto_ncservo);
  expert_register_field_array(expert, buildNoteRegistrations(), static_cast<int>(kExpertNoteCount));
  expert_register_field_array(expert, buildRuleRegistrations(), static_cast<int>(kRuleCount));

  module_t* prefs = prefs_register_protocol(proto_ncservo, applyPreferences);
  prefs_register_filename_preference(
      prefs, "config", "Configuration file",
      "TOML configuration file: the axes' layout, timeouts, disabled rules "
      "(docs/configuration.md)",
      &pref_config_path, FALSE);
  prefs_register_filename_preference(
      prefs, "eni", "ENI file",
      "EtherCATConfig.xml (ETG.2100) exported by the configuration tool: the servos' layout when "
      "no configuration file gives one",
      &pref_eni_path, FALSE);
  prefs_register_string_preference(
      prefs, "servo_ready_mode", "Servo_Ready_Mode",
      "The drives' Servo_Ready_Mode parameter (docs/protocol.md §5): auto (inferred per axis), 0 "
      "or 1",
      &pref_servo_ready_mode);
  prefs_register_bool_preference(
      prefs, "default_layout", "Infer the layout from the cyclic traffic",
      "When no configuration, ENI or start-up gives the layout, infer it from the process data "
      "(docs/layout.md); in a single pass the frames of the learning window are not decoded",
      &pref_default_layout);

  register_init_routine(initCapture);
  register_cleanup_routine(cleanupCapture);
  registerTimingStat();
}

void keepRegistrations() {
  for (std::size_t i = 0; i < kFieldCount; ++i) hfi_field[i] = proto_registrar_get_nth(hf_field[i]);
  for (std::size_t i = 0; i < kDerivedCount; ++i) {
    hfi_derived[i] = proto_registrar_get_nth(hf_derived[i]);
  }
  hfi_protocol = proto_registrar_get_nth(proto_ncservo);
  protocol_ncservo = find_protocol_by_id(proto_ncservo);
}

void registerHandoff() {
  keepRegistrations();
  layer_handle = create_dissector_handle(dissectLayer, proto_ncservo);
  // The postdissector belongs to no protocol, so that it adds no layer: the axes' layers are
  // numbered from 1.
  register_postdissector(create_dissector_handle(dissectNcservo, -1));
  applyPreferences();
}

}  // namespace

void plugin_register(void) {
  static proto_plugin plugin;
  plugin.register_protoinfo = registerProtocol;
  plugin.register_handoff = registerHandoff;
  proto_register_plugin(&plugin);
}
