// Wireshark 4.0 plugin: a thin presenter over the ncservo library. The field registration is
// generated from the library's field table; layout, copy detection and drive state come from the
// library's Validator — as are the rules' findings, shown as expert info — computed on the first
// pass and kept per frame (PROTOCOL.md §10).
//
// Wireshark raises exceptions with longjmp: no object with a destructor may be alive in a frame
// of this file across a tvb_* or proto_tree_add_* call. The dissector therefore works on plain
// structs and raw pointers only.
#define WS_BUILD_DLL
#include <epan/expert.h>
#include <epan/packet.h>
#include <epan/prefs.h>
#include <epan/proto_data.h>
#include <fmt/format.h>
#include <wireshark.h>
#include <wiretap/wtap.h>
#include <wsutil/report_message.h>

#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "item_texts.hpp"
#include "ncservo/config.hpp"
#include "ncservo/eni.hpp"
#include "ncservo/ethercat.hpp"
#include "ncservo/fields.hpp"
#include "ncservo/layout_window.hpp"
#include "ncservo/pdo.hpp"
#include "ncservo/rules.hpp"
#include "ncservo/text.hpp"
#include "ncservo/validator.hpp"

extern "C" {
WS_DLL_PUBLIC const char plugin_version[];
WS_DLL_PUBLIC const int plugin_want_major;
WS_DLL_PUBLIC const int plugin_want_minor;
WS_DLL_PUBLIC void plugin_register(void);
}
const char plugin_version[] = NCSERVO_VERSION;
const int plugin_want_major = WIRESHARK_VERSION_MAJOR;
const int plugin_want_minor = WIRESHARK_VERSION_MINOR;

namespace {

using namespace ncservo;

constexpr std::size_t kDerivedCount = std::size(kDerivedFields);
constexpr std::size_t kMaxChildren = 33;  // at most 32 bit fields per word, NULL-terminated

int proto_ncservo = -1;
int hf_field[kFieldCount];
int hf_derived[kDerivedCount];
int ett_ncservo = -1;
int ett_axis = -1;
int ett_word[kWordCount];
// What each PDO word adds, prepared once from the field table so that no frame scans the table.
constexpr std::size_t kMaxParts = 2;
struct WordItems {
  std::size_t row;      // the word's row in kFields; its bit fields and parts follow it
  std::size_t row_end;  // one past the word's last row
  guint offset;         // in its PDO
  gint length;
  int* children[kMaxChildren];   // bit fields drawn by one bitmask call, NULL-terminated
  std::size_t parts[kMaxParts];  // rows of byte-aligned parts, each shown when it applies
  std::size_t part_count;
};
WordItems word_items[kWordCount];
expert_field ei_region_malformed = EI_INIT;
expert_field ei_rule[kRuleCount];  // one expert item per rule: ncservo.rule.<slug>

const char* pref_config_path = "";
const char* pref_eni_path = "";
gboolean pref_default_layout = TRUE;
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

// Options from the preferences, and the state of the capture being dissected: the learning
// window (PROTOCOL.md §9.4), then the validator once the layout is known, and what it found in
// each frame by frame number (the window's frames are validated when it ends, not in their turn).
DecoderOptions* g_options = nullptr;
RuleSettings* g_settings = nullptr;
LayoutWindow* g_window = nullptr;
Validator* g_validator = nullptr;
wmem_map_t* g_records = nullptr;

// What the first pass found in a frame, kept in file scope for later passes.
enum AxisFlags : guint8 {
  kHasRx = 1,
  kHasTx = 2,
  kRxMalformed = 4,
  kTxMalformed = 8,
  kHasState = 16,
};
struct AxisRecord {
  guint16 axis;
  guint8 flags;
  guint8 state;
  guint32 rx_offset;
  guint32 tx_offset;
};
constexpr guint16 kBusAxis = 0xFFFF;
struct FindingRecord {
  guint8 rule;       // RuleId
  guint16 axis;      // kBusAxis for a finding about the bus
  guint32 since;     // frame where the condition began
  const char* text;  // "SE-001 illegal-enable-edge: axis0: ...", in file scope
};
struct FrameRecord {
  guint8 copy;
  guint16 axis_count;
  guint16 finding_count;
  const FindingRecord* findings;
  AxisRecord axes[1];  // axis_count entries (at least one slot allocated)
};

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
    if (d.id == Derived::Axis) {
      fillHeader(r.hfinfo, d.label, d.filter, FT_UINT16, BASE_DEC, nullptr, 0, d.blurb);
    } else {
      fillHeader(r.hfinfo, d.label, d.filter, FT_STRING, BASE_NONE, nullptr, 0, d.blurb);
    }
  }
  return hf;
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
    ei[i].eiinfo.summary = g_strdup_printf("%s %s: %s", rule.code, rule.slug, rule.summary);
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
        if (used + 1 < kMaxChildren) word.children[used] = &hf_field[i];
        break;
      }
      case FieldKind::Part:
        if (word.part_count < kMaxParts) word.parts[word.part_count++] = i;
        break;
    }
    word.row_end = i + 1;
  }
}

void applyPreferences() {
  auto* settings = new RuleSettings();
  std::optional<Config> config;
  std::vector<AxisConfig> eni_axes;
  if (pref_eni_path != nullptr && pref_eni_path[0] != '\0') {
    Result<EniLayout> eni = loadEni(pref_eni_path);
    if (eni) {
      eni_axes = std::move(eni->axes);
    } else {
      report_failure("NCSERVO: %s", eni.error().text().c_str());
    }
  }
  if (pref_config_path != nullptr && pref_config_path[0] != '\0') {
    Result<Config> loaded = loadConfig(pref_config_path);
    if (loaded) {
      config = std::move(*loaded);
      // Severity overrides are left to Wireshark's own expert-severity table (PROTOCOL.md §10).
      if (Status applied = applyConfig(*config, *settings); !applied) {
        report_failure("NCSERVO: %s", applied.error().text().c_str());
      }
    } else {
      report_failure("NCSERVO: %s", loaded.error().text().c_str());
    }
  }
  if (const Result<std::optional<int>> mode = readyModeOf(pref_servo_ready_mode); mode) {
    settings->servo_ready_mode = *mode;
  } else {
    report_failure("NCSERVO: %s", mode.error().text().c_str());
  }
  auto* options = new DecoderOptions(
      layoutOptions(config ? &*config : nullptr, &eni_axes, pref_default_layout != FALSE));
  delete g_options;
  g_options = options;
  delete g_settings;
  g_settings = settings;
}

void startValidator() {
  delete g_validator;
  g_validator =
      new Validator(g_window->options(), g_settings != nullptr ? *g_settings : RuleSettings{});
}

void initCapture() {
  plugin::resetItemTexts();
  g_records = wmem_map_new(wmem_file_scope(), g_direct_hash, g_direct_equal);
  delete g_window;
  g_window = new LayoutWindow(g_options != nullptr ? *g_options : DecoderOptions{});
  delete g_validator;
  g_validator = nullptr;
  if (!g_window->learning()) startValidator();
}

void cleanupCapture() {
  delete g_validator;
  g_validator = nullptr;
  delete g_window;
  g_window = nullptr;
  g_records = nullptr;
}

const char* axisName(guint16 axis) {
  if (g_validator != nullptr && axis < g_validator->decoder().axes().size()) {
    return g_validator->decoder().axes()[axis].name.c_str();
  }
  return "?";
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

// Runs the validator over one frame and keeps what it found, by frame number.
void validateFrame(std::uint64_t number, std::int64_t time_ns, const EcatFrame& frame,
                   const ByteReader& bytes) {
  const ValidatedFrame& view = g_validator->onFrame(number, time_ns, frame, bytes);
  const FrameDecode& decode = view.decode;
  const std::vector<Finding>& findings = g_validator->findings();
  if (decode.axis_count == 0 && findings.empty()) return;
  const std::size_t slots = decode.axis_count > 0 ? decode.axis_count : 1;
  const std::size_t size = sizeof(FrameRecord) + (slots - 1) * sizeof(AxisRecord);
  auto* record = static_cast<FrameRecord*>(wmem_alloc0(wmem_file_scope(), size));
  record->copy = static_cast<guint8>(decode.copy);
  record->axis_count = static_cast<guint16>(decode.axis_count);
  if (!findings.empty()) {
    auto* out = static_cast<FindingRecord*>(
        wmem_alloc0(wmem_file_scope(), findings.size() * sizeof(FindingRecord)));
    for (std::size_t i = 0; i < findings.size(); ++i) {
      const Finding& f = findings[i];
      const RuleDef& rule = ruleDef(f.rule);
      out[i].rule = static_cast<guint8>(f.rule);
      out[i].axis = f.axis ? *f.axis : kBusAxis;
      out[i].since = static_cast<guint32>(f.since.frame);
      out[i].text = wmem_strdup_printf(wmem_file_scope(), "%s %s: %s: %s", rule.code, rule.slug,
                                       f.axis ? axisName(*f.axis) : "bus", f.message.c_str());
    }
    record->findings = out;
    record->finding_count = static_cast<guint16>(std::min<std::size_t>(findings.size(), 0xFFFF));
  }
  for (std::size_t i = 0; i < decode.axis_count; ++i) {
    const AxisPlacement& placement = decode.axes[i];
    const std::optional<DriveState>& state = view.states[i];
    AxisRecord& r = record->axes[i];
    r.axis = placement.axis;
    r.flags =
        static_cast<guint8>((placement.has_rx ? kHasRx : 0) | (placement.has_tx ? kHasTx : 0) |
                            (placement.rx_malformed ? kRxMalformed : 0) |
                            (placement.tx_malformed ? kTxMalformed : 0) | (state ? kHasState : 0));
    r.state = state ? static_cast<guint8>(*state) : 0;
    r.rx_offset = static_cast<guint32>(placement.rx_offset);
    r.tx_offset = static_cast<guint32>(placement.tx_offset);
  }
  wmem_map_insert(g_records, GUINT_TO_POINTER(static_cast<guint>(number)), record);
}

// The window ended: validate its frames with the layout it found, then go on streaming.
void windowDecided() {
  startValidator();
  g_window->replay(validateFrame);
}

const FrameRecord* recordOf(const packet_info* pinfo) {
  return static_cast<const FrameRecord*>(
      wmem_map_lookup(g_records, GUINT_TO_POINTER(static_cast<guint>(pinfo->num))));
}

// First pass: run the library over the frame (or hold it in the learning window).
void analyseFrame(tvbuff_t* tvb, packet_info* pinfo) {
  const LinkType link = linkTypeOf(pinfo);
  if (link == LinkType::Unsupported || g_window == nullptr) return;
  const guint length = tvb_captured_length(tvb);
  const guint8* data = length > 0 ? tvb_get_ptr(tvb, 0, length) : nullptr;
  const ByteReader bytes(data, data != nullptr ? length : 0);
  static EcatFrame frame;  // 8 KiB; dissection is single-threaded
  walkPacket(link, bytes, frame);
  if (frame.status != WalkStatus::Ok && frame.status != WalkStatus::Truncated) return;
  const std::int64_t time_ns =
      static_cast<std::int64_t>(pinfo->abs_ts.secs) * 1'000'000'000 + pinfo->abs_ts.nsecs;
  if (g_window->learning()) {
    g_window->hold(pinfo->num, time_ns, link, bytes, frame);
    if (!g_window->learning()) windowDecided();
    return;
  }
  validateFrame(pinfo->num, time_ns, frame, bytes);
}

// Whether a word's items are needed: the tree is shown, or a filter or column asks for the word or
// one of its fields. Skipping the rest keeps filtering with an invisible tree fast.
bool wordWanted(proto_tree* tree, const WordItems& word) {
  for (std::size_t i = word.row; i < word.row_end; ++i) {
    if (proto_field_is_referenced(tree, hf_field[i])) return true;
  }
  return false;
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

// Adds the words of one PDO, each bit field under its word, as the field table defines them.
void addPdo(proto_tree* tree, tvbuff_t* tvb, Pdo pdo, guint offset, const PdoValues& values) {
  const std::size_t first = firstWordOf(pdo);
  for (std::size_t w = first; w < first + wordCountOf(pdo); ++w) {
    const WordItems& word = word_items[w];
    if (!wordWanted(tree, word)) continue;
    proto_item* item = nullptr;
    if (word.children[0] != nullptr) {
      // BMT_NO_APPEND: the bits are children; appending their names to the word's label
      // would format every bit of every word on every frame.
      item = proto_tree_add_bitmask_value_with_flags(tree, tvb, offset + word.offset,
                                                     hf_field[word.row], ett_word[w], word.children,
                                                     values.raw[w], BMT_NO_APPEND);
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

// Each finding as the expert item of its rule, on the axis's subtree (or the protocol's item).
void addFindings(packet_info* pinfo, const FrameRecord& record, guint16 axis, proto_item* item) {
  for (guint i = 0; i < record.finding_count; ++i) {
    const FindingRecord& f = record.findings[i];
    if (f.axis != axis) continue;
    expert_add_info_format(pinfo, item, &ei_rule[f.rule], "%s", f.text);
  }
}

bool findingsFor(const FrameRecord& record, guint16 axis) {
  for (guint i = 0; i < record.finding_count; ++i) {
    if (record.findings[i].axis == axis) return true;
  }
  return false;
}

void addAxis(proto_tree* tree, tvbuff_t* tvb, packet_info* pinfo, const FrameRecord& record,
             const AxisRecord& r) {
  const std::optional<DriveState> known_state =
      (r.flags & kHasState) ? std::optional(static_cast<DriveState>(r.state)) : std::nullopt;
  const plugin::AxisTexts texts = plugin::axisTexts(r.axis, axisName(r.axis), known_state);
  const char* name = texts.name;
  const char* state = texts.state;
  // Anchor the axis at its first PDO that was captured; an item past the captured bytes would
  // raise an exception.
  const guint start = (r.flags & kHasRx) ? r.rx_offset : (r.flags & kHasTx) ? r.tx_offset : 0;
  proto_item* axis_item = nullptr;
  proto_tree* axis_tree =
      proto_tree_add_subtree(tree, tvb, start, 0, ett_axis, &axis_item, texts.label);
  proto_tree_add_uint(axis_tree, derivedHf(Derived::Axis), tvb, start, 0, r.axis);
  proto_tree_add_string(axis_tree, derivedHf(Derived::AxisName), tvb, start, 0, name);

  // Values for conditions and derived fields; the items themselves read the bytes through tvb.
  const guint length = tvb_captured_length(tvb);
  const ByteReader bytes(length > 0 ? tvb_get_ptr(tvb, 0, length) : nullptr, length);
  PdoValues values;
  if (r.flags & kHasRx) readPdo(Pdo::Rx, bytes, r.rx_offset, values);
  if (r.flags & kHasTx) readPdo(Pdo::Tx, bytes, r.tx_offset, values);
  if (values.has_rx) addPdo(axis_tree, tvb, Pdo::Rx, r.rx_offset, values);
  if (values.has_tx) addPdo(axis_tree, tvb, Pdo::Tx, r.tx_offset, values);
  if (state != nullptr) {
    proto_item_set_generated(
        proto_tree_add_string(axis_tree, derivedHf(Derived::State), tvb, start, 0, state));
  }
  if (values.has_tx) {
    char message[128];
    plugin::messageText(values, message, sizeof message);
    proto_item_set_generated(proto_tree_add_string(axis_tree, derivedHf(Derived::Message), tvb,
                                                   r.tx_offset, 0, message));
  }
  for (const bool rx : {true, false}) {
    if (!(r.flags & (rx ? kRxMalformed : kTxMalformed))) continue;
    expert_add_info_format(pinfo, axis_item, &ei_region_malformed,
                           "Axis %u: the %s (%u bytes at frame offset %u) is cut short or lies "
                           "partly outside its datagram",
                           r.axis, rx ? "RxPDO" : "TxPDO",
                           static_cast<unsigned>(rx ? kRxPdoSize : kTxPdoSize),
                           rx ? r.rx_offset : r.tx_offset);
  }
  col_append_fstr(pinfo->cinfo, COL_INFO, "%s%s%s", name, state ? " " : "", state ? state : "");
  if (findingsFor(record, r.axis)) addFindings(pinfo, record, r.axis, axis_item);
}

int dissectNcservo(tvbuff_t* tvb, packet_info* pinfo, proto_tree* tree, void*) {
  if (g_records == nullptr) return 0;
  if (!PINFO_FD_VISITED(pinfo)) {
    analyseFrame(tvb, pinfo);
  } else if (g_window != nullptr && g_window->learning()) {
    // The capture ended inside the learning window: decide with what the first pass held.
    g_window->finish();
    windowDecided();
  }
  const FrameRecord* record = recordOf(pinfo);
  if (record == nullptr) return 0;
  proto_item* root = proto_tree_add_item(tree, proto_ncservo, tvb, 0, -1, ENC_NA);
  proto_tree* ncservo_tree = proto_item_add_subtree(root, ett_ncservo);
  col_append_str(pinfo->cinfo, COL_INFO, " [NCSERVO ");
  if (record->axis_count > 0) {
    const char* copy =
        plugin::describeCopy(root, static_cast<CopyKind>(record->copy), record->axis_count);
    proto_item_set_generated(
        proto_tree_add_string(ncservo_tree, derivedHf(Derived::Copy), tvb, 0, 0, copy));
  }
  for (guint i = 0; i < record->axis_count; ++i) {
    if (i > 0) col_append_str(pinfo->cinfo, COL_INFO, "; ");
    addAxis(ncservo_tree, tvb, pinfo, *record, record->axes[i]);
  }
  // Findings about the bus, or about an axis this frame does not carry, go on the root item.
  for (guint i = 0; i < record->finding_count; ++i) {
    const FindingRecord& f = record->findings[i];
    bool shown = false;
    for (guint a = 0; a < record->axis_count && f.axis != kBusAxis; ++a) {
      shown = shown || record->axes[a].axis == f.axis;
    }
    if (!shown) expert_add_info_format(pinfo, root, &ei_rule[f.rule], "%s", f.text);
  }
  for (guint i = 0; i < record->finding_count; ++i) {
    col_append_fstr(pinfo->cinfo, COL_INFO, "%s%s", i == 0 ? " | " : " ",
                    ruleDef(static_cast<RuleId>(record->findings[i].rule)).code);
  }
  col_append_str(pinfo->cinfo, COL_INFO, "]");
  return static_cast<int>(tvb_captured_length(tvb));
}

void registerProtocol() {
  proto_ncservo = proto_register_protocol("NC-Servo EtherCAT process data", "NCSERVO", "ncservo");
  std::size_t count = 0;
  hf_register_info* hf = buildFieldRegistrations(count);
  proto_register_field_array(proto_ncservo, hf, static_cast<int>(count));
  buildWordItems();

  static gint* ett[2 + kWordCount];
  ett[0] = &ett_ncservo;
  ett[1] = &ett_axis;
  for (std::size_t w = 0; w < kWordCount; ++w) {
    ett_word[w] = -1;
    ett[2 + w] = &ett_word[w];
  }
  proto_register_subtree_array(ett, static_cast<int>(std::size(ett)));

  static ei_register_info ei[] = {
      {&ei_region_malformed,
       {"ncservo.malformed", PI_MALFORMED, PI_ERROR,
        "A PDO region is cut short or lies partly outside its datagram", EXPFILL}},
  };
  expert_module_t* expert = expert_register_protocol(proto_ncservo);
  expert_register_field_array(expert, ei, static_cast<int>(std::size(ei)));
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
}

void registerHandoff() {
  dissector_handle_t handle = create_dissector_handle(dissectNcservo, proto_ncservo);
  register_postdissector(handle);
  applyPreferences();
}

}  // namespace

void plugin_register(void) {
  static proto_plugin plugin;
  plugin.register_protoinfo = registerProtocol;
  plugin.register_handoff = registerHandoff;
  proto_register_plugin(&plugin);
}
