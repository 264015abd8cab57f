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

// What a view shows of a bit field besides its value (docs/protocol.md §2-4).
enum class FieldView : std::uint8_t {
  Value,           // its value and value name
  Cause,           // a SEW cause bit: shown while set; the clear ones fold into one line
  ParameterTable,  // PRMTBL: the table (1..8) it selects with its word's ExtPRMTBL
};

struct FieldDef {
  Word word;
  FieldKind kind;
  std::uint64_t mask = 0;  // bits of the word this field covers (0 for a whole word)
  const char* label;
  const char* filter;  // display-filter name, public API (docs/fields.md)
  const ValueName* values = nullptr;
  std::uint8_t value_count = 0;
  FieldWhen when = FieldWhen::Always;
  const char* blurb;
  const char* clause;  // where docs/protocol.md defines it
  // For a bit field of the SCW or SSW: its value (from the field's lowest bit) when it asks for
  // nothing and reports nothing, so that a view can show such fields together and briefly: a
  // request not made, an acknowledgement or warning not given, reserved bits zero. Never a bit
  // whose clear value reports the drive's state (ServoEn, ServoRDY, N=0, N=Ns, PulseEnabled):
  // an engineer looks for exactly those (docs/plugin.md).
  std::optional<std::uint32_t> at_rest = std::nullopt;
  FieldView view = FieldView::Value;
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

#define NCSERVO_VALUES(array) \
  .values = names::array, .value_count = static_cast<std::uint8_t>(std::size(names::array))

inline constexpr FieldDef kFields[] = {
    // RxPDO (docs/protocol.md §1, §2)
    {.word = Word::Ssp,
     .kind = FieldKind::Word,
     .label = "Speed set point",
     .filter = "ncservo.ssp",
     .blurb = "SSP, speed reference (a 16-bit NC uses the low word only)",
     .clause = "docs/protocol.md §1"},
    {.word = Word::Scw,
     .kind = FieldKind::Word,
     .label = "Servo control word",
     .filter = "ncservo.scw",
     .blurb = "SCW, NC -> servo",
     .clause = "docs/protocol.md §2"},
    {.word = Word::Scw,
     .kind = FieldKind::BitRange,
     .mask = 0x3,
     .label = "SE",
     .filter = "ncservo.scw.se",
     NCSERVO_VALUES(kSe),
     .blurb = "Servo enable: only 0x2 reached directly from 0x1 enables",
     .clause = "docs/protocol.md §2"},
    {.word = Word::Scw,
     .kind = FieldKind::Flag,
     .mask = 0x4,
     .label = "EMGON",
     .filter = "ncservo.scw.emgon",
     NCSERVO_VALUES(kEmgon),
     .blurb = "0 = emergency: braking ramp to the Emergency Feed speed",
     .clause = "docs/protocol.md §2"},
    {.word = Word::Scw,
     .kind = FieldKind::Flag,
     .mask = 0x8,
     .label = "POSLOCK",
     .filter = "ncservo.scw.poslock",
     NCSERVO_VALUES(kPoslock),
     .blurb = "Hold the axis at the position latched on the 0->1 edge",
     .clause = "docs/protocol.md §2",
     .at_rest = 0},
    {.word = Word::Scw,
     .kind = FieldKind::BitRange,
     .mask = 0x30,
     .label = "PRMTBL",
     .filter = "ncservo.scw.prmtbl",
     NCSERVO_VALUES(kTableLow),
     .blurb = "Parameter table select, low bits (table = ExtPRMTBL*4 + PRMTBL + 1)",
     .clause = "docs/protocol.md §2",
     .view = FieldView::ParameterTable},
    {.word = Word::Scw,
     .kind = FieldKind::BitRange,
     .mask = 0xC0,
     .label = "ModeSel",
     .filter = "ncservo.scw.modesel",
     NCSERVO_VALUES(kModeSel),
     .blurb = "Regulation mode select (documented as not used yet)",
     .clause = "docs/protocol.md §2"},
    {.word = Word::Scw,
     .kind = FieldKind::Flag,
     .mask = 0x100,
     .label = "SIntLock",
     .filter = "ncservo.scw.sintlock",
     NCSERVO_VALUES(kSIntLock),
     .blurb = "Freeze the speed-regulator integrator",
     .clause = "docs/protocol.md §2",
     .at_rest = 0},
    {.word = Word::Scw,
     .kind = FieldKind::Flag,
     .mask = 0x200,
     .label = "ErrorClear",
     .filter = "ncservo.scw.error_clear",
     NCSERVO_VALUES(kErrorClear),
     .blurb = "Clear drive errors (handshake with SSW.ErrClearAck)",
     .clause = "docs/protocol.md §2",
     .at_rest = 0},
    {.word = Word::Scw,
     .kind = FieldKind::Flag,
     .mask = 0x400,
     .label = "Brake",
     .filter = "ncservo.scw.brake",
     NCSERVO_VALUES(kBrake),
     .blurb = "0 = internal braking (documented as not used yet)",
     .clause = "docs/protocol.md §2"},
    {.word = Word::Scw,
     .kind = FieldKind::Flag,
     .mask = 0x800,
     .label = "ZPulseRequest",
     .filter = "ncservo.scw.zpulse_request",
     NCSERVO_VALUES(kZPulseRequest),
     .blurb = "Search the encoder zero pulse (handshake with SSW.ZPulseAck)",
     .clause = "docs/protocol.md §2",
     .at_rest = 0},
    {.word = Word::Scw,
     .kind = FieldKind::Flag,
     .mask = 0x1000,
     .label = "ExtPRMTBL",
     .filter = "ncservo.scw.ext_prmtbl",
     NCSERVO_VALUES(kExtTable),
     .blurb = "Parameter table select, high bit (tables 5-8)",
     .clause = "docs/protocol.md §2"},
    {.word = Word::Scw,
     .kind = FieldKind::BitRange,
     .mask = 0x7FFFE000,
     .label = "Reserved",
     .filter = "ncservo.scw.reserved",
     .blurb = "Must be 0",
     .clause = "docs/protocol.md §2",
     .at_rest = 0},
    {.word = Word::Scw,
     .kind = FieldKind::Flag,
     .mask = 0x80000000,
     .label = "PRGDWN",
     .filter = "ncservo.scw.prgdwn",
     NCSERVO_VALUES(kSetClear),
     .blurb = "Named in the bit map, not described (program download)",
     .clause = "docs/protocol.md §2",
     .at_rest = 0},
    {.word = Word::ExtCode,
     .kind = FieldKind::Word,
     .label = "Extra data code word",
     .filter = "ncservo.ext_code",
     .blurb = "Selects the content of the extra data",
     .clause = "docs/protocol.md §1"},
    // TxPDO (docs/protocol.md §1, §3, §4)
    {.word = Word::ActPos,
     .kind = FieldKind::Word,
     .label = "Actual position",
     .filter = "ncservo.actpos",
     .blurb = "ActPos, raw int64 of all four words",
     .clause = "docs/protocol.md §1"},
    {.word = Word::ActPos,
     .kind = FieldKind::Part,
     .mask = 0xFFFFFFFFull,
     .label = "Incremental position",
     .filter = "ncservo.actpos.incremental",
     .when = FieldWhen::IncrementalEncoder,
     .blurb = "32-bit position of an incremental encoder (words 0-1)",
     .clause = "docs/protocol.md §1"},
    {.word = Word::ActPos,
     .kind = FieldKind::Part,
     .mask = 0xFFFFFFFF00000000ull,
     .label = "Zero-pulse position",
     .filter = "ncservo.actpos.zero_pulse",
     .when = FieldWhen::IncrementalEncoder,
     .blurb = "Position latched at the zero pulse (words 2-3), valid once ZPulseAck was seen",
     .clause = "docs/protocol.md §1"},
    {.word = Word::Ssw,
     .kind = FieldKind::Word,
     .label = "Servo status word",
     .filter = "ncservo.ssw",
     .blurb = "SSW, servo -> NC",
     .clause = "docs/protocol.md §3"},
    {.word = Word::Ssw,
     .kind = FieldKind::Flag,
     .mask = 0x1,
     .label = "ServoEn",
     .filter = "ncservo.ssw.servo_en",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Drive enabled: regulation and power stage live",
     .clause = "docs/protocol.md §3"},
    {.word = Word::Ssw,
     .kind = FieldKind::Flag,
     .mask = 0x2,
     .label = "ServoRDY",
     .filter = "ncservo.ssw.servo_rdy",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Ready, per the Servo_Ready_Mode table",
     .clause = "docs/protocol.md §3, §5"},
    {.word = Word::Ssw,
     .kind = FieldKind::Flag,
     .mask = 0x4,
     .label = "Abs/Incr",
     .filter = "ncservo.ssw.incremental",
     NCSERVO_VALUES(kEncoder),
     .blurb = "Encoder kind",
     .clause = "docs/protocol.md §3"},
    {.word = Word::Ssw,
     .kind = FieldKind::Flag,
     .mask = 0x8,
     .label = "ZPulseAck",
     .filter = "ncservo.ssw.zpulse_ack",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Zero pulse found after ZPulseRequest",
     .clause = "docs/protocol.md §3",
     .at_rest = 0},
    {.word = Word::Ssw,
     .kind = FieldKind::Flag,
     .mask = 0x10,
     .label = "ErrClearAck",
     .filter = "ncservo.ssw.err_clear_ack",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Errors were cleared after ErrorClear",
     .clause = "docs/protocol.md §3",
     .at_rest = 0},
    {.word = Word::Ssw,
     .kind = FieldKind::Flag,
     .mask = 0x20,
     .label = "N=0",
     .filter = "ncservo.ssw.n_zero",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Motor speed below the standstill threshold",
     .clause = "docs/protocol.md §3"},
    {.word = Word::Ssw,
     .kind = FieldKind::Flag,
     .mask = 0x40,
     .label = "N=Ns",
     .filter = "ncservo.ssw.n_setpoint",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Motor speed within tolerance of the set point",
     .clause = "docs/protocol.md §3"},
    {.word = Word::Ssw,
     .kind = FieldKind::Flag,
     .mask = 0x80,
     .label = "PulseEnabled",
     .filter = "ncservo.ssw.pulse_enabled",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Power stage (IGBT) switched on",
     .clause = "docs/protocol.md §3"},
    {.word = Word::Ssw,
     .kind = FieldKind::BitRange,
     .mask = 0x300,
     .label = "PRMTBL",
     .filter = "ncservo.ssw.prmtbl",
     NCSERVO_VALUES(kTableLow),
     .blurb = "Active parameter table, low bits",
     .clause = "docs/protocol.md §3",
     .view = FieldView::ParameterTable},
    {.word = Word::Ssw,
     .kind = FieldKind::Flag,
     .mask = 0x400,
     .label = "NoEncoder",
     .filter = "ncservo.ssw.no_encoder",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Axis has no encoder",
     .clause = "docs/protocol.md §3",
     .at_rest = 0},
    {.word = Word::Ssw,
     .kind = FieldKind::Flag,
     .mask = 0x800,
     .label = "TempWarning",
     .filter = "ncservo.ssw.temp_warning",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Motor temperature over 80 °C",
     .clause = "docs/protocol.md §3",
     .at_rest = 0},
    {.word = Word::Ssw,
     .kind = FieldKind::Flag,
     .mask = 0x1000,
     .label = "ExtPRMTBL",
     .filter = "ncservo.ssw.ext_prmtbl",
     NCSERVO_VALUES(kExtTable),
     .blurb = "Active parameter table, high bit",
     .clause = "docs/protocol.md §3"},
    {.word = Word::Ssw,
     .kind = FieldKind::BitRange,
     .mask = 0xFFFFE000,
     .label = "Reserved",
     .filter = "ncservo.ssw.reserved",
     .blurb = "Must be 0",
     .clause = "docs/protocol.md §3",
     .at_rest = 0},
    {.word = Word::Sew,
     .kind = FieldKind::Word,
     .label = "Servo error word",
     .filter = "ncservo.sew",
     .blurb = "SEW, servo -> NC",
     .clause = "docs/protocol.md §4"},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x1,
     .label = "ServoErrors",
     .filter = "ncservo.sew.servo_errors",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Summary: set whenever any cause bit is set",
     .clause = "docs/protocol.md §4"},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x2,
     .label = "EncoderErr (E01)",
     .filter = "ncservo.sew.encoder",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Encoder error",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x4,
     .label = "I2t_Endat (E19)",
     .filter = "ncservo.sew.i2t_endat",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Encoder over-temperature",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x8,
     .label = "ECatConfigError (E14)",
     .filter = "ncservo.sew.ecat_config",
     NCSERVO_VALUES(kYesNo),
     .blurb = "EtherCAT configuration error",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::BitRange,
     .mask = 0xFE000010,
     .label = "Reserved",
     .filter = "ncservo.sew.reserved",
     .blurb = "Bit 4 and bits 31..25, must be 0",
     .clause = "docs/protocol.md §4"},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x20,
     .label = "BVErr (E05)",
     .filter = "ncservo.sew.bus_voltage",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Bus over-voltage",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x40,
     .label = "CurrErr (E06)",
     .filter = "ncservo.sew.current",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Over-current",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x80,
     .label = "CURROErr (E07)",
     .filter = "ncservo.sew.current_offset",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Current offset error",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x100,
     .label = "HallErr (E08)",
     .filter = "ncservo.sew.hall",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Hall sensor error",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x200,
     .label = "HallSErr",
     .filter = "ncservo.sew.hall_sequence",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Hall sequence error",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x400,
     .label = "SRTErr",
     .filter = "ncservo.sew.servo_runtime",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Servo watchdog",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x800,
     .label = "CAN1TErr",
     .filter = "ncservo.sew.can1_timeout",
     NCSERVO_VALUES(kYesNo),
     .blurb = "CAN channel 1 timeout",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x1000,
     .label = "CAN2TErr",
     .filter = "ncservo.sew.can2_timeout",
     NCSERVO_VALUES(kYesNo),
     .blurb = "CAN channel 2 timeout",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x2000,
     .label = "CAN1HErr",
     .filter = "ncservo.sew.can1_hw",
     NCSERVO_VALUES(kYesNo),
     .blurb = "CAN channel 1 hardware error",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x4000,
     .label = "CAN2HErr",
     .filter = "ncservo.sew.can2_hw",
     NCSERVO_VALUES(kYesNo),
     .blurb = "CAN channel 2 hardware error",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x8000,
     .label = "ECatTErr (E15)",
     .filter = "ncservo.sew.ecat_timeout",
     NCSERVO_VALUES(kYesNo),
     .blurb = "EtherCAT timeout: no data for 3 cycles",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x10000,
     .label = "PDPINT (E16)",
     .filter = "ncservo.sew.pdpint",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Power stage fault",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x20000,
     .label = "PTBLCHKSErr (E30)",
     .filter = "ncservo.sew.param_checksum",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Parameter table checksum error",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x40000,
     .label = "PRGCHKSErr",
     .filter = "ncservo.sew.program_checksum",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Program checksum error",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x80000,
     .label = "FollowerErr (E09)",
     .filter = "ncservo.sew.following",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Following error",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x100000,
     .label = "OverLoad (E20)",
     .filter = "ncservo.sew.overload",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Overload",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x200000,
     .label = "SFlashErr (E32)",
     .filter = "ncservo.sew.flash",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Parameter flash access error",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x400000,
     .label = "ECatWatchDog (E31)",
     .filter = "ncservo.sew.ecat_watchdog",
     NCSERVO_VALUES(kYesNo),
     .blurb = "EtherCAT slave watchdog",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x800000,
     .label = "OverSpeed (E11)",
     .filter = "ncservo.sew.overspeed",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Over-speed",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::Sew,
     .kind = FieldKind::Flag,
     .mask = 0x1000000,
     .label = "CurrDiffErr (E12)",
     .filter = "ncservo.sew.current_symmetry",
     NCSERVO_VALUES(kYesNo),
     .blurb = "Phase current symmetry error",
     .clause = "docs/protocol.md §4",
     .view = FieldView::Cause},
    {.word = Word::MsgCode,
     .kind = FieldKind::Word,
     .label = "Message code",
     .filter = "ncservo.msg_code",
     NCSERVO_VALUES(kMsgCode),
     .blurb = "Selects the meaning of the message data",
     .clause = "docs/protocol.md §5"},
    {.word = Word::MsgData,
     .kind = FieldKind::Word,
     .label = "Message data",
     .filter = "ncservo.msg_data",
     .blurb = "Value whose meaning the message code gives",
     .clause = "docs/protocol.md §5"},
    {.word = Word::ExtData1,
     .kind = FieldKind::Word,
     .label = "Extra data 1",
     .filter = "ncservo.ext_data1",
     .blurb = "float32",
     .clause = "docs/protocol.md §1"},
    {.word = Word::ExtData2,
     .kind = FieldKind::Word,
     .label = "Extra data 2",
     .filter = "ncservo.ext_data2",
     .blurb = "float32",
     .clause = "docs/protocol.md §1"},
    {.word = Word::ExtData3,
     .kind = FieldKind::Word,
     .label = "Extra data 3",
     .filter = "ncservo.ext_data3",
     .blurb = "float32",
     .clause = "docs/protocol.md §1"},
    {.word = Word::ExtData4,
     .kind = FieldKind::Word,
     .label = "Extra data 4",
     .filter = "ncservo.ext_data4",
     .blurb = "float32",
     .clause = "docs/protocol.md §1"},
};
#undef NCSERVO_VALUES

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
    if (f.view == FieldView::Cause && (f.word != Word::Sew || f.kind != FieldKind::Flag)) {
      return false;
    }
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

// The bits of each word whose rows are error causes (FieldView::Cause): none but in the SEW.
inline constexpr std::array<std::uint64_t, kWordCount> kCauseMasks = [] {
  std::array<std::uint64_t, kWordCount> causes{};
  for (const FieldDef& f : kFields) {
    if (f.view == FieldView::Cause) causes[static_cast<std::size_t>(f.word)] |= f.mask;
  }
  return causes;
}();
constexpr std::uint64_t causeMask(Word word) {
  return kCauseMasks[static_cast<std::size_t>(word)];
}
// docs/protocol.md §4: bit 0 summarises the cause bits, which are every other SEW flag.
inline constexpr std::uint32_t kSewSummaryMask = mask32("ncservo.sew.servo_errors");
inline constexpr std::uint32_t kSewCauseMask = static_cast<std::uint32_t>(causeMask(Word::Sew));
static_assert(kSewCauseMask == 0x01FFFFEE, "docs/protocol.md §4: cause bits 1-3 and 5-24");
// docs/protocol.md §4: a drive raises ECatTErr once this many cycles in a row brought it no data
// (docs/rules.md#com-003 reports one that does not).
inline constexpr std::uint32_t kEcatTimeoutCycles = 3;

// docs/protocol.md §4: the name the interface definition gives a cause bit ("OverSpeed"), its
// row's label before the E-number; the reports show it beside the E-number (docs/cli.md).
constexpr std::string_view causeName(const FieldDef& f) {
  const std::string_view label(f.label);
  return label.substr(0, label.find(" ("));
}
// The cause row of a SEW bit; null for a bit that is no cause.
constexpr const FieldDef* sewCauseField(std::uint32_t mask) {
  for (const FieldDef& f : kFields) {
    if (f.word == Word::Sew && f.view == FieldView::Cause && f.mask == mask) return &f;
  }
  return nullptr;
}
static_assert(causeName(*sewCauseField(mask32("ncservo.sew.overspeed"))) == "OverSpeed");

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
// docs/protocol.md §5: the interface definition lists the codes 0..9, but gives only those named
// above (0..5) a meaning. A drive sending one of the others is still a drive of this protocol: the
// layout inference takes it (docs/layout.md), and MSG-001 warns of it (docs/rules.md).
inline constexpr std::uint32_t kLastListedMessageCode = 9;
static_assert(kLastListedMessageCode >= kLastDefinedMessageCode);

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
// The rows that read as a parameter table are the PRMTBL fields of the SCW and SSW.
static_assert([] {
  for (const FieldDef& f : kFields) {
    const bool prmtbl =
        (f.word == Word::Scw || f.word == Word::Ssw) && f.mask == parameterTableBits(f.word).low;
    if ((f.view == FieldView::ParameterTable) != prmtbl) return false;
  }
  return true;
}());

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
  TransitionAxis,
  TransitionAxisName,
  Finding,
  SinceFrame,
  CycleInterval,
  CycleDeviation,
  Latency,
  Clock,
  Incident,
  IncidentEvidence,
  Duplicate,
  // What a drive or an ESC said in the frame (docs/drive-messages.md), one layer per slave.
  EmcyCode,
  EmcyRegister,
  EmcyRegisterGeneric,
  EmcyRegisterCurrent,
  EmcyRegisterVoltage,
  EmcyRegisterTemperature,
  EmcyRegisterCommunication,
  EmcyRegisterProfile,
  EmcyRegisterManufacturer,
  EmcyData,
  SdoIndex,
  SdoSubindex,
  SdoValue,
  SdoAbort,
  SdoObject,
  SdoRequestIn,
  ErrhistNumber,
  ErrhistClass,
  ErrhistCode,
  EscStation,
  EscPort,
  EscCounter,
  EscDelta,
  LinkFault,
};
// What a derived field holds, which gives its type in a registration.
enum class DerivedKind : std::uint8_t {
  Text,
  Index,
  FrameNumber,
  Microseconds,  // a duration, fractional
  Unsigned,      // a count or number, decimal
  Hex8,          // a code or address, hexadecimal
  Hex16,
  Hex32,
  Value,  // an SDO's value (up to 8 bytes), hexadecimal
  Flag,   // one bit of its parent's value: `mask`
  Bytes,
};
// Where a derived field's value names come from (the plugin takes them from the wire layer's
// tables: docs/drive-messages.md).
enum class DerivedNames : std::uint8_t { None, ErrorCodes, AbortCodes };
struct DerivedFieldDef {
  Derived id;
  const char* label;
  const char* filter;
  const char* blurb;
  DerivedKind kind = DerivedKind::Text;
  DerivedNames names = DerivedNames::None;
  std::uint8_t mask = 0;  // Flag: the bit in its parent's value
};
inline constexpr DerivedFieldDef kDerivedFields[] = {
    {.id = Derived::Axis,
     .label = "Axis",
     .filter = "ncservo.axis",
     .blurb = "Index of the axis in the layout (0-based)",
     .kind = DerivedKind::Index},
    {.id = Derived::AxisName,
     .label = "Axis name",
     .filter = "ncservo.axis_name",
     .blurb = "Name of the axis in the layout"},
    {.id = Derived::Copy,
     .label = "Copy",
     .filter = "ncservo.copy",
     .blurb =
         "master = the master's frame (outputs), returned = the copy back from the ring (inputs)"},
    {.id = Derived::State,
     .label = "Drive state",
     .filter = "ncservo.state",
     .blurb = "Drive state shown by the process data (docs/protocol.md §6)"},
    {.id = Derived::Message,
     .label = "Message",
     .filter = "ncservo.message",
     .blurb = "Message data with its meaning and unit (docs/protocol.md §5)"},
    {.id = Derived::Edge,
     .label = "Edge",
     .filter = "ncservo.edge",
     .blurb = "A judged bit field that changed in this frame, e.g. \"SE 0x1→0x2\", \"ServoEn ↑\""},
    {.id = Derived::Transition,
     .label = "Transition",
     .filter = "ncservo.transition",
     .blurb = "The drive-state change in this frame, named as in the state timeline "
              "(docs/protocol.md §6)"},
    // Under the transition: its axis alone, where ncservo.axis gives every layer of the frame.
    {.id = Derived::TransitionAxis,
     .label = "Axis",
     .filter = "ncservo.transition.axis",
     .blurb = "Index of the axis whose drive state changed (0-based)",
     .kind = DerivedKind::Index},
    {.id = Derived::TransitionAxisName,
     .label = "Axis name",
     .filter = "ncservo.transition.axis_name",
     .blurb = "Name of the axis whose drive state changed"},
    {.id = Derived::Finding,
     .label = "Finding",
     .filter = "ncservo.finding",
     .blurb = "A rule's finding with its details (docs/rules.md)"},
    {.id = Derived::SinceFrame,
     .label = "Since frame",
     .filter = "ncservo.since_frame",
     .blurb = "Frame where the finding's condition began",
     .kind = DerivedKind::FrameNumber},
    {.id = Derived::CycleInterval,
     .label = "Cycle interval",
     .filter = "ncservo.cycle.interval",
     .blurb = "Time since the previous master copy of this cyclic frame, in us (docs/timing.md)",
     .kind = DerivedKind::Microseconds},
    {.id = Derived::CycleDeviation,
     .label = "Cycle deviation",
     .filter = "ncservo.cycle.deviation",
     .blurb = "The cycle interval minus the nominal cycle (the segment's median so far), in us "
              "(docs/timing.md)",
     .kind = DerivedKind::Microseconds},
    {.id = Derived::Latency,
     .label = "Return latency",
     .filter = "ncservo.latency",
     .blurb = "Time from the master copy to this returned copy at the capture point, in us "
              "(docs/timing.md)",
     .kind = DerivedKind::Microseconds},
    {.id = Derived::Clock,
     .label = "Clock",
     .filter = "ncservo.clock",
     .blurb = "The clock that timed the cycle interval and latency: capture, probe, bus or cycles "
              "(docs/timing.md#the-clock)"},
    {.id = Derived::Incident,
     .label = "Incident",
     .filter = "ncservo.incident",
     .blurb = "A drive fault, bus outage or fall from OP beginning in this frame: its cause id and "
              "what showed it (docs/incidents.md)"},
    {.id = Derived::IncidentEvidence,
     .label = "Incident evidence",
     .filter = "ncservo.incident.evidence",
     .blurb = "A frame of the incident's chain: a finding or a bus event before it, or what its "
              "cause read (docs/incidents.md)",
     .kind = DerivedKind::FrameNumber},
    {.id = Derived::Duplicate,
     .label = "Duplicate",
     .filter = "ncservo.duplicate",
     .blurb = "An exact copy of a record within its cycle, which the capture holds twice: not "
              "judged (docs/cli.md#duplicates)"},
    {.id = Derived::EmcyCode,
     .label = "Emergency error code",
     .filter = "ncservo.emcy.code",
     .blurb = "A CoE emergency's error code, with the drive's text for it (docs/drive-messages.md)",
     .kind = DerivedKind::Hex16,
     .names = DerivedNames::ErrorCodes},
    {.id = Derived::EmcyRegister,
     .label = "Emergency error register",
     .filter = "ncservo.emcy.register",
     .blurb = "A CoE emergency's error register (object 1001h), its bits below",
     .kind = DerivedKind::Hex8},
    {.id = Derived::EmcyRegisterGeneric,
     .label = "Generic error",
     .filter = "ncservo.emcy.register.generic",
     .blurb = "1001h bit 0",
     .kind = DerivedKind::Flag,
     .mask = 0x01},
    {.id = Derived::EmcyRegisterCurrent,
     .label = "Current",
     .filter = "ncservo.emcy.register.current",
     .blurb = "1001h bit 1",
     .kind = DerivedKind::Flag,
     .mask = 0x02},
    {.id = Derived::EmcyRegisterVoltage,
     .label = "Voltage",
     .filter = "ncservo.emcy.register.voltage",
     .blurb = "1001h bit 2",
     .kind = DerivedKind::Flag,
     .mask = 0x04},
    {.id = Derived::EmcyRegisterTemperature,
     .label = "Temperature",
     .filter = "ncservo.emcy.register.temperature",
     .blurb = "1001h bit 3",
     .kind = DerivedKind::Flag,
     .mask = 0x08},
    {.id = Derived::EmcyRegisterCommunication,
     .label = "Communication error",
     .filter = "ncservo.emcy.register.communication",
     .blurb = "1001h bit 4",
     .kind = DerivedKind::Flag,
     .mask = 0x10},
    {.id = Derived::EmcyRegisterProfile,
     .label = "Device profile specific",
     .filter = "ncservo.emcy.register.profile",
     .blurb = "1001h bit 5",
     .kind = DerivedKind::Flag,
     .mask = 0x20},
    {.id = Derived::EmcyRegisterManufacturer,
     .label = "Manufacturer specific",
     .filter = "ncservo.emcy.register.manufacturer",
     .blurb = "1001h bit 7",
     .kind = DerivedKind::Flag,
     .mask = 0x80},
    {.id = Derived::EmcyData,
     .label = "Emergency data",
     .filter = "ncservo.emcy.data",
     .blurb = "A CoE emergency's five manufacturer-specific bytes",
     .kind = DerivedKind::Bytes},
    {.id = Derived::SdoIndex,
     .label = "SDO index",
     .filter = "ncservo.sdo.index",
     .blurb = "The object an SDO answer or abort is about (docs/drive-messages.md)",
     .kind = DerivedKind::Hex16},
    {.id = Derived::SdoSubindex,
     .label = "SDO subindex",
     .filter = "ncservo.sdo.subindex",
     .blurb = "The object's subindex",
     .kind = DerivedKind::Unsigned},
    {.id = Derived::SdoValue,
     .label = "SDO value",
     .filter = "ncservo.sdo.value",
     .blurb = "The value uploaded or downloaded (up to 8 bytes, little-endian)",
     .kind = DerivedKind::Value},
    {.id = Derived::SdoAbort,
     .label = "SDO abort code",
     .filter = "ncservo.sdo.abort",
     .blurb = "Why the SDO request was aborted, with CiA 301's text",
     .kind = DerivedKind::Hex32,
     .names = DerivedNames::AbortCodes},
    {.id = Derived::SdoObject,
     .label = "SDO object",
     .filter = "ncservo.sdo.object",
     .blurb = "The name of a diagnosis object (1001h, 1003h, 603Fh, 10F3h)"},
    {.id = Derived::SdoRequestIn,
     .label = "SDO request in",
     .filter = "ncservo.sdo.request_in",
     .blurb = "The frame of the request this SDO answer or abort pairs with",
     .kind = DerivedKind::FrameNumber},
    {.id = Derived::ErrhistNumber,
     .label = "Error history: number",
     .filter = "ncservo.errhist.number",
     .blurb = "A 1003h entry's error number (bits 24-31, docs/drive-messages.md)",
     .kind = DerivedKind::Unsigned},
    {.id = Derived::ErrhistClass,
     .label = "Error history: class",
     .filter = "ncservo.errhist.class",
     .blurb = "A 1003h entry's error class (bits 16-23, as 1001h)",
     .kind = DerivedKind::Hex8},
    {.id = Derived::ErrhistCode,
     .label = "Error history: code",
     .filter = "ncservo.errhist.code",
     .blurb = "A 1003h entry's error code (bits 0-15), with the drive's text for it",
     .kind = DerivedKind::Hex16,
     .names = DerivedNames::ErrorCodes},
    {.id = Derived::EscStation,
     .label = "ESC station",
     .filter = "ncservo.esc.station",
     .blurb = "The slave whose ESC error counter rose (docs/drive-messages.md)",
     .kind = DerivedKind::Hex16},
    {.id = Derived::EscPort,
     .label = "ESC port",
     .filter = "ncservo.esc.port",
     .blurb = "The port of the counter (0 for the processing unit's and PDI's)",
     .kind = DerivedKind::Unsigned},
    {.id = Derived::EscCounter,
     .label = "ESC counter",
     .filter = "ncservo.esc.counter",
     .blurb = "Which counter rose: invalid, rx, forwarded, lost-link, processing, pdi, "
              "sm-watchdog, pdi-watchdog"},
    {.id = Derived::EscDelta,
     .label = "ESC counter rise",
     .filter = "ncservo.esc.delta",
     .blurb = "How much the counter rose since its previous read",
     .kind = DerivedKind::Unsigned},
    {.id = Derived::LinkFault,
     .label = "Link fault",
     .filter = "ncservo.link_fault",
     .blurb = "The link the ESC counters name, first in processing order (docs/drive-messages.md)"},
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
