// The field table: every PDO word and bit of docs/protocol.md §1–4 is one row. The Wireshark
// registration, the CLI's decoder and the field documentation are all generated from it.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "ncservo/protocol/pdo_layout.hpp"

namespace ncservo {

enum class FieldKind : std::uint8_t {
  Word,      // the whole word, typed as in kWords
  Flag,      // one bit of a word
  BitRange,  // several bits of a word, shown as an unsigned number
  Part,      // a byte-aligned 32-bit slice of a word, shown as int32
};

// A field shown only under a condition the PDO itself states.
enum class FieldWhen : std::uint8_t { Always, IncrementalEncoder };

struct ValueName {
  std::uint32_t value;
  const char* name;
  const char* unit = nullptr;  // for values that carry a measured quantity (message codes)
};

struct FieldDef {
  Word word;
  FieldKind kind;
  std::uint64_t mask;  // bits of the word this field covers (0 for a whole word)
  const char* label;
  const char* filter;  // display-filter name, public API (docs/fields.md)
  const ValueName* values;
  std::uint8_t value_count;
  FieldWhen when;
  const char* blurb;
  const char* clause;  // where docs/protocol.md defines it
  // For a bit field of the SCW or SSW: its value (from the field's lowest bit) when it asks for
  // nothing and reports nothing, so that a view can show such fields together and briefly.
  std::optional<std::uint32_t> at_rest = std::nullopt;
};

namespace names {
inline constexpr ValueName kSe[] = {{0, "disabled"},
                                    {1, "disabled (armed: 0x1 -> 0x2 enables)"},
                                    {2, "enable (only from 0x1)"},
                                    {3, "disabled"}};
inline constexpr ValueName kEmgon[] = {{0, "emergency (braking ramp)"}, {1, "normal"}};
inline constexpr ValueName kPoslock[] = {{0, "normal"}, {1, "hold position"}};
inline constexpr ValueName kTableLow[] = {{0, "table 1 (5 with ExtPRMTBL)"},
                                          {1, "table 2 (6 with ExtPRMTBL)"},
                                          {2, "table 3 (7 with ExtPRMTBL)"},
                                          {3, "table 4 (8 with ExtPRMTBL)"}};
inline constexpr ValueName kModeSel[] = {
    {0, "speed"}, {1, "current (torque)"}, {2, "position"}, {3, "high-accuracy speed"}};
inline constexpr ValueName kSIntLock[] = {{0, "normal"}, {1, "integrator frozen"}};
inline constexpr ValueName kErrorClear[] = {{0, "no event"}, {1, "clear errors"}};
inline constexpr ValueName kBrake[] = {{0, "internal braking"}, {1, "normal"}};
inline constexpr ValueName kZPulseRequest[] = {{0, "normal"}, {1, "search zero pulse"}};
inline constexpr ValueName kExtTable[] = {{0, "tables 1-4"}, {1, "tables 5-8"}};
inline constexpr ValueName kYesNo[] = {{0, "no"}, {1, "yes"}};
inline constexpr ValueName kSetClear[] = {{0, "clear"}, {1, "set"}};
inline constexpr ValueName kEncoder[] = {{0, "absolute (64-bit position)"},
                                         {1, "incremental (32-bit position)"}};
// docs/protocol.md §5: what the message data means for each defined message code.
inline constexpr ValueName kMsgCode[] = {
    {0, "motor speed", "rpm"}, {1, "motor current", "A"},      {2, "relative current I/In", "%"},
    {3, "bus voltage", "V"},   {4, "motor temperature", "°C"}, {5, "motor power", "kW"}};
}  // namespace names

#define NCSERVO_VALUES(array) names::array, static_cast<std::uint8_t>(std::size(names::array))
#define NCSERVO_NO_VALUES nullptr, 0

// clang-format off
inline constexpr FieldDef kFields[] = {
  // RxPDO (docs/protocol.md §1, §2)
  {Word::Ssp, FieldKind::Word, 0, "Speed set point", "ncservo.ssp", NCSERVO_NO_VALUES, FieldWhen::Always,
   "SSP, speed reference (a 16-bit NC uses the low word only)", "docs/protocol.md §1"},
  {Word::Scw, FieldKind::Word, 0, "Servo control word", "ncservo.scw", NCSERVO_NO_VALUES, FieldWhen::Always,
   "SCW, NC -> servo", "docs/protocol.md §2"},
  {Word::Scw, FieldKind::BitRange, 0x3, "SE", "ncservo.scw.se", NCSERVO_VALUES(kSe), FieldWhen::Always,
   "Servo enable: only 0x2 reached directly from 0x1 enables", "docs/protocol.md §2"},
  {Word::Scw, FieldKind::Flag, 0x4, "EMGON", "ncservo.scw.emgon", NCSERVO_VALUES(kEmgon), FieldWhen::Always,
   "0 = emergency: braking ramp to the Emergency Feed speed", "docs/protocol.md §2"},
  {Word::Scw, FieldKind::Flag, 0x8, "POSLOCK", "ncservo.scw.poslock", NCSERVO_VALUES(kPoslock), FieldWhen::Always,
   "Hold the axis at the position latched on the 0->1 edge", "docs/protocol.md §2", 0},
  {Word::Scw, FieldKind::BitRange, 0x30, "PRMTBL", "ncservo.scw.prmtbl", NCSERVO_VALUES(kTableLow), FieldWhen::Always,
   "Parameter table select, low bits (table = ExtPRMTBL*4 + PRMTBL + 1)", "docs/protocol.md §2"},
  {Word::Scw, FieldKind::BitRange, 0xC0, "ModeSel", "ncservo.scw.modesel", NCSERVO_VALUES(kModeSel), FieldWhen::Always,
   "Regulation mode select (documented as not used yet)", "docs/protocol.md §2"},
  {Word::Scw, FieldKind::Flag, 0x100, "SIntLock", "ncservo.scw.sintlock", NCSERVO_VALUES(kSIntLock), FieldWhen::Always,
   "Freeze the speed-regulator integrator", "docs/protocol.md §2", 0},
  {Word::Scw, FieldKind::Flag, 0x200, "ErrorClear", "ncservo.scw.error_clear", NCSERVO_VALUES(kErrorClear), FieldWhen::Always,
   "Clear drive errors (handshake with SSW.ErrClearAck)", "docs/protocol.md §2", 0},
  {Word::Scw, FieldKind::Flag, 0x400, "Brake", "ncservo.scw.brake", NCSERVO_VALUES(kBrake), FieldWhen::Always,
   "0 = internal braking (documented as not used yet)", "docs/protocol.md §2"},
  {Word::Scw, FieldKind::Flag, 0x800, "ZPulseRequest", "ncservo.scw.zpulse_request", NCSERVO_VALUES(kZPulseRequest), FieldWhen::Always,
   "Search the encoder zero pulse (handshake with SSW.ZPulseAck)", "docs/protocol.md §2", 0},
  {Word::Scw, FieldKind::Flag, 0x1000, "ExtPRMTBL", "ncservo.scw.ext_prmtbl", NCSERVO_VALUES(kExtTable), FieldWhen::Always,
   "Parameter table select, high bit (tables 5-8)", "docs/protocol.md §2"},
  {Word::Scw, FieldKind::BitRange, 0x7FFFE000, "Reserved", "ncservo.scw.reserved", NCSERVO_NO_VALUES, FieldWhen::Always,
   "Must be 0", "docs/protocol.md §2", 0},
  {Word::Scw, FieldKind::Flag, 0x80000000, "PRGDWN", "ncservo.scw.prgdwn", NCSERVO_VALUES(kSetClear), FieldWhen::Always,
   "Named in the bit map, not described (program download)", "docs/protocol.md §2", 0},
  {Word::ExtCode, FieldKind::Word, 0, "Extra data code word", "ncservo.ext_code", NCSERVO_NO_VALUES, FieldWhen::Always,
   "Selects the content of the extra data", "docs/protocol.md §1"},

  // TxPDO (docs/protocol.md §1, §3, §4)
  {Word::ActPos, FieldKind::Word, 0, "Actual position", "ncservo.actpos", NCSERVO_NO_VALUES, FieldWhen::Always,
   "ActPos, raw int64 of all four words", "docs/protocol.md §1"},
  {Word::ActPos, FieldKind::Part, 0xFFFFFFFFull, "Incremental position", "ncservo.actpos.incremental", NCSERVO_NO_VALUES,
   FieldWhen::IncrementalEncoder, "32-bit position of an incremental encoder (words 0-1)", "docs/protocol.md §1"},
  {Word::ActPos, FieldKind::Part, 0xFFFFFFFF00000000ull, "Zero-pulse position", "ncservo.actpos.zero_pulse", NCSERVO_NO_VALUES,
   FieldWhen::IncrementalEncoder, "Position latched at the zero pulse (words 2-3), valid once ZPulseAck was seen",
   "docs/protocol.md §1"},
  {Word::Ssw, FieldKind::Word, 0, "Servo status word", "ncservo.ssw", NCSERVO_NO_VALUES, FieldWhen::Always,
   "SSW, servo -> NC", "docs/protocol.md §3"},
  {Word::Ssw, FieldKind::Flag, 0x1, "ServoEn", "ncservo.ssw.servo_en", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Drive enabled: regulation and power stage live", "docs/protocol.md §3", 0},
  {Word::Ssw, FieldKind::Flag, 0x2, "ServoRDY", "ncservo.ssw.servo_rdy", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Ready, per the Servo_Ready_Mode table", "docs/protocol.md §3, §5", 0},
  {Word::Ssw, FieldKind::Flag, 0x4, "Abs/Incr", "ncservo.ssw.incremental", NCSERVO_VALUES(kEncoder), FieldWhen::Always,
   "Encoder kind", "docs/protocol.md §3"},
  {Word::Ssw, FieldKind::Flag, 0x8, "ZPulseAck", "ncservo.ssw.zpulse_ack", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Zero pulse found after ZPulseRequest", "docs/protocol.md §3", 0},
  {Word::Ssw, FieldKind::Flag, 0x10, "ErrClearAck", "ncservo.ssw.err_clear_ack", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Errors were cleared after ErrorClear", "docs/protocol.md §3", 0},
  {Word::Ssw, FieldKind::Flag, 0x20, "N=0", "ncservo.ssw.n_zero", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Motor speed below the standstill threshold", "docs/protocol.md §3", 0},
  {Word::Ssw, FieldKind::Flag, 0x40, "N=Ns", "ncservo.ssw.n_setpoint", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Motor speed within tolerance of the set point", "docs/protocol.md §3", 0},
  {Word::Ssw, FieldKind::Flag, 0x80, "PulseEnabled", "ncservo.ssw.pulse_enabled", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Power stage (IGBT) switched on", "docs/protocol.md §3", 0},
  {Word::Ssw, FieldKind::BitRange, 0x300, "PRMTBL", "ncservo.ssw.prmtbl", NCSERVO_VALUES(kTableLow), FieldWhen::Always,
   "Active parameter table, low bits", "docs/protocol.md §3"},
  {Word::Ssw, FieldKind::Flag, 0x400, "NoEncoder", "ncservo.ssw.no_encoder", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Axis has no encoder", "docs/protocol.md §3", 0},
  {Word::Ssw, FieldKind::Flag, 0x800, "TempWarning", "ncservo.ssw.temp_warning", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Motor temperature over 80 °C", "docs/protocol.md §3", 0},
  {Word::Ssw, FieldKind::Flag, 0x1000, "ExtPRMTBL", "ncservo.ssw.ext_prmtbl", NCSERVO_VALUES(kExtTable), FieldWhen::Always,
   "Active parameter table, high bit", "docs/protocol.md §3"},
  {Word::Ssw, FieldKind::BitRange, 0xFFFFE000, "Reserved", "ncservo.ssw.reserved", NCSERVO_NO_VALUES, FieldWhen::Always,
   "Must be 0", "docs/protocol.md §3", 0},
  {Word::Sew, FieldKind::Word, 0, "Servo error word", "ncservo.sew", NCSERVO_NO_VALUES, FieldWhen::Always,
   "SEW, servo -> NC", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x1, "ServoErrors", "ncservo.sew.servo_errors", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Summary: set whenever any cause bit is set", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x2, "EncoderErr (E01)", "ncservo.sew.encoder", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Encoder error", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x4, "I2t_Endat (E19)", "ncservo.sew.i2t_endat", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Encoder over-temperature", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x8, "ECatConfigError (E14)", "ncservo.sew.ecat_config", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "EtherCAT configuration error", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::BitRange, 0xFE000010, "Reserved", "ncservo.sew.reserved", NCSERVO_NO_VALUES, FieldWhen::Always,
   "Bit 4 and bits 31..25, must be 0", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x20, "BVErr (E05)", "ncservo.sew.bus_voltage", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Bus over-voltage", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x40, "CurrErr (E06)", "ncservo.sew.current", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Over-current", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x80, "CURROErr (E07)", "ncservo.sew.current_offset", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Current offset error", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x100, "HallErr (E08)", "ncservo.sew.hall", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Hall sensor error", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x200, "HallSErr", "ncservo.sew.hall_sequence", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Hall sequence error", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x400, "SRTErr", "ncservo.sew.servo_runtime", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Servo watchdog", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x800, "CAN1TErr", "ncservo.sew.can1_timeout", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "CAN channel 1 timeout", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x1000, "CAN2TErr", "ncservo.sew.can2_timeout", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "CAN channel 2 timeout", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x2000, "CAN1HErr", "ncservo.sew.can1_hw", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "CAN channel 1 hardware error", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x4000, "CAN2HErr", "ncservo.sew.can2_hw", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "CAN channel 2 hardware error", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x8000, "ECatTErr (E15)", "ncservo.sew.ecat_timeout", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "EtherCAT timeout: no data for 3 cycles", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x10000, "PDPINT (E16)", "ncservo.sew.pdpint", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Power stage fault", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x20000, "PTBLCHKSErr (E30)", "ncservo.sew.param_checksum", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Parameter table checksum error", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x40000, "PRGCHKSErr", "ncservo.sew.program_checksum", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Program checksum error", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x80000, "FollowerErr (E09)", "ncservo.sew.following", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Following error", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x100000, "OverLoad (E20)", "ncservo.sew.overload", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Overload", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x200000, "SFlashErr (E32)", "ncservo.sew.flash", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Parameter flash access error", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x400000, "ECatWatchDog (E31)", "ncservo.sew.ecat_watchdog", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "EtherCAT slave watchdog", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x800000, "OverSpeed (E11)", "ncservo.sew.overspeed", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Over-speed", "docs/protocol.md §4"},
  {Word::Sew, FieldKind::Flag, 0x1000000, "CurrDiffErr (E12)", "ncservo.sew.current_symmetry", NCSERVO_VALUES(kYesNo), FieldWhen::Always,
   "Phase current symmetry error", "docs/protocol.md §4"},
  {Word::MsgCode, FieldKind::Word, 0, "Message code", "ncservo.msg_code", NCSERVO_VALUES(kMsgCode), FieldWhen::Always,
   "Selects the meaning of the message data", "docs/protocol.md §5"},
  {Word::MsgData, FieldKind::Word, 0, "Message data", "ncservo.msg_data", NCSERVO_NO_VALUES, FieldWhen::Always,
   "Value whose meaning the message code gives", "docs/protocol.md §5"},
  {Word::ExtData1, FieldKind::Word, 0, "Extra data 1", "ncservo.ext_data1", NCSERVO_NO_VALUES, FieldWhen::Always,
   "float32", "docs/protocol.md §1"},
  {Word::ExtData2, FieldKind::Word, 0, "Extra data 2", "ncservo.ext_data2", NCSERVO_NO_VALUES, FieldWhen::Always,
   "float32", "docs/protocol.md §1"},
  {Word::ExtData3, FieldKind::Word, 0, "Extra data 3", "ncservo.ext_data3", NCSERVO_NO_VALUES, FieldWhen::Always,
   "float32", "docs/protocol.md §1"},
  {Word::ExtData4, FieldKind::Word, 0, "Extra data 4", "ncservo.ext_data4", NCSERVO_NO_VALUES, FieldWhen::Always,
   "float32", "docs/protocol.md §1"},
};
// clang-format on
#undef NCSERVO_VALUES
#undef NCSERVO_NO_VALUES

inline constexpr std::size_t kFieldCount = std::size(kFields);

constexpr std::size_t popcount64(std::uint64_t v) {
  std::size_t n = 0;
  for (; v != 0; v &= v - 1) ++n;
  return n;
}
constexpr unsigned lowestBit(std::uint64_t mask) {
  unsigned bit = 0;
  while (bit < 64 && !((mask >> bit) & 1)) ++bit;
  return bit;
}
// Whether the word holds the field at the value the table calls at rest (FieldDef::at_rest).
constexpr bool isAtRest(const FieldDef& f, std::uint64_t word) {
  return f.at_rest && ((word & f.mask) >> lowestBit(f.mask)) == *f.at_rest;
}
constexpr std::uint64_t wordMask(Word w) {
  return wordDef(w).size >= 8 ? ~0ull : ((1ull << (8 * wordDef(w).size)) - 1);
}

// The row with this filter name; a typo is a compile error where used in a constant expression.
constexpr const FieldDef& field(std::string_view filter) {
  for (const auto& f : kFields) {
    if (std::string_view(f.filter) == filter) return f;
  }
  throw "no such field";  // not a constant expression: unknown names fail to compile
}
constexpr std::uint32_t mask32(std::string_view filter) {
  return static_cast<std::uint32_t>(field(filter).mask);
}

namespace detail {
constexpr bool startsWith(std::string_view s, std::string_view prefix) {
  return s.substr(0, prefix.size()) == prefix;
}
// Every row: name prefixed and unique, mask inside its word, bit fields of one word disjoint,
// one Word row per word first, rows sorted by word.
constexpr bool fieldTableIsConsistent() {
  for (std::size_t i = 0; i < kFieldCount; ++i) {
    const FieldDef& f = kFields[i];
    if (!startsWith(f.filter, "ncservo.")) return false;
    if ((f.kind == FieldKind::Word) != (f.mask == 0)) return false;
    if ((f.mask & ~wordMask(f.word)) != 0) return false;
    if (f.kind == FieldKind::Flag && popcount64(f.mask) != 1) return false;
    if (f.kind == FieldKind::Part && popcount64(f.mask) != 32) return false;
    if (f.at_rest && (f.kind == FieldKind::Word || f.kind == FieldKind::Part)) return false;
    if (f.at_rest && ((std::uint64_t{*f.at_rest} << lowestBit(f.mask)) & ~f.mask) != 0) {
      return false;
    }
    if (i > 0 && kFields[i - 1].word > f.word) return false;
    if (f.kind == FieldKind::Word && (i > 0 && kFields[i - 1].word == f.word)) return false;
    for (std::size_t j = 0; j < i; ++j) {
      if (std::string_view(kFields[j].filter) == f.filter) return false;
      bool bits = f.kind == FieldKind::Flag || f.kind == FieldKind::BitRange;
      bool otherBits = kFields[j].kind == FieldKind::Flag || kFields[j].kind == FieldKind::BitRange;
      if (bits && otherBits && kFields[j].word == f.word && (kFields[j].mask & f.mask) != 0) {
        return false;
      }
    }
  }
  return true;
}
}  // namespace detail
static_assert(detail::fieldTableIsConsistent(), "field table rows violate the table's invariants");

// --- Protocol facts derived from the table ---

// docs/protocol.md §4: bit 0 summarises the cause bits, which are every other SEW flag.
inline constexpr std::uint32_t kSewSummaryMask = mask32("ncservo.sew.servo_errors");
inline constexpr std::uint32_t kSewCauseMask = [] {
  std::uint32_t all = 0;
  for (const FieldDef& f : kFields) {
    if (f.word == Word::Sew && f.kind == FieldKind::Flag) all |= static_cast<std::uint32_t>(f.mask);
  }
  return all & ~kSewSummaryMask;
}();
static_assert(kSewCauseMask == 0x01FFFFEE, "docs/protocol.md §4: cause bits 1-3 and 5-24");

// docs/protocol.md §5: the message codes with a meaning are the value names of ncservo.msg_code.
inline constexpr const FieldDef& kMessageCodeField = field("ncservo.msg_code");
inline constexpr std::uint64_t kDefinedMessageCodes = [] {  // bit n: code n has a meaning
  std::uint64_t codes = 0;
  for (std::size_t i = 0; i < kMessageCodeField.value_count; ++i) {
    codes |= std::uint64_t{1} << kMessageCodeField.values[i].value;
  }
  return codes;
}();
static_assert(popcount64(kDefinedMessageCodes) == kMessageCodeField.value_count,
              "message codes below 64, each named once");
constexpr bool messageCodeDefined(std::int64_t code) {
  return code >= 0 && code < 64 && ((kDefinedMessageCodes >> code) & 1) != 0;
}
inline constexpr std::uint32_t kLastDefinedMessageCode = [] {
  std::uint32_t last = 0;
  for (std::size_t i = 0; i < kMessageCodeField.value_count; ++i) {
    last = std::max(last, kMessageCodeField.values[i].value);
  }
  return last;
}();

// docs/protocol.md §2–3: parameter table = ExtPRMTBL·4 + PRMTBL + 1, commanded in the SCW,
// active in the SSW.
struct ParameterTableBits {
  std::uint32_t low;   // PRMTBL
  std::uint32_t high;  // ExtPRMTBL
};
inline constexpr ParameterTableBits kScwTableBits{mask32("ncservo.scw.prmtbl"),
                                                  mask32("ncservo.scw.ext_prmtbl")};
inline constexpr ParameterTableBits kSswTableBits{mask32("ncservo.ssw.prmtbl"),
                                                  mask32("ncservo.ssw.ext_prmtbl")};
constexpr const ParameterTableBits& parameterTableBits(Word word) {
  return word == Word::Scw ? kScwTableBits : kSswTableBits;
}
inline constexpr unsigned kParameterTables = 8;
// The table (1..8) that a SCW or SSW selects.
constexpr unsigned parameterTable(Word word, std::uint32_t value) {
  const ParameterTableBits& b = parameterTableBits(word);
  return ((value & b.high) ? 4u : 0u) + ((value & b.low) >> lowestBit(b.low)) + 1u;
}
// The bits of a SCW or SSW that select table 1..8.
constexpr std::uint32_t parameterTableSelection(Word word, unsigned table) {
  const ParameterTableBits& b = parameterTableBits(word);
  const unsigned index = table - 1u;
  return ((index & 3u) << lowestBit(b.low)) | ((index & 4u) ? b.high : 0u);
}
static_assert(parameterTable(Word::Scw, parameterTableSelection(Word::Scw, 7)) == 7 &&
              parameterTable(Word::Ssw, parameterTableSelection(Word::Ssw, 5)) == 5);

}  // namespace ncservo

namespace ncservo {

// Fields the decoder derives rather than reads from one word (docs/fields.md, docs/plugin.md).
enum class Derived : std::uint8_t {
  Axis,
  AxisName,
  Copy,
  State,
  Message,
  Edge,
  Transition,
  Finding,
  SinceFrame,
  CycleInterval,
  CycleDeviation,
  Latency,
};
// What a derived field holds, which gives its type in a registration.
enum class DerivedKind : std::uint8_t {
  Text,
  Index,
  FrameNumber,
  Microseconds,  // a duration, fractional
};
struct DerivedFieldDef {
  Derived id;
  const char* label;
  const char* filter;
  const char* blurb;
  DerivedKind kind = DerivedKind::Text;
};
inline constexpr DerivedFieldDef kDerivedFields[] = {
    {Derived::Axis, "Axis", "ncservo.axis", "Index of the axis in the layout (0-based)",
     DerivedKind::Index},
    {Derived::AxisName, "Axis name", "ncservo.axis_name", "Name of the axis in the layout"},
    {Derived::Copy, "Copy", "ncservo.copy",
     "master = the master's frame (outputs), returned = the copy back from the ring (inputs)"},
    {Derived::State, "Drive state", "ncservo.state",
     "Drive state shown by the process data (docs/protocol.md §6)"},
    {Derived::Message, "Message", "ncservo.message",
     "Message data with its meaning and unit (docs/protocol.md §5)"},
    {Derived::Edge, "Edge", "ncservo.edge",
     "A judged bit field that changed in this frame, e.g. \"SE 0x1→0x2\", \"ServoEn ↑\""},
    {Derived::Transition, "Transition", "ncservo.transition",
     "The drive-state change in this frame, named as in the state timeline (docs/protocol.md §6)"},
    {Derived::Finding, "Finding", "ncservo.finding",
     "A rule's finding with its details (docs/rules.md)"},
    {Derived::SinceFrame, "Since frame", "ncservo.since_frame",
     "Frame where the finding's condition began", DerivedKind::FrameNumber},
    {Derived::CycleInterval, "Cycle interval", "ncservo.cycle.interval",
     "Time since the previous master copy of this cyclic frame, in us (docs/timing.md)",
     DerivedKind::Microseconds},
    {Derived::CycleDeviation, "Cycle deviation", "ncservo.cycle.deviation",
     "The cycle interval minus the nominal cycle (the segment's median so far), in us "
     "(docs/timing.md)",
     DerivedKind::Microseconds},
    {Derived::Latency, "Return latency", "ncservo.latency",
     "Time from the master copy to this returned copy at the capture point, in us "
     "(docs/timing.md)",
     DerivedKind::Microseconds},
};
static_assert(
    [] {
      for (std::size_t i = 0; i < std::size(kDerivedFields); ++i) {
        if (static_cast<std::size_t>(kDerivedFields[i].id) != i) return false;
      }
      return true;
    }(),
    "derived fields in the order of Derived");

}  // namespace ncservo
