// What a drive and an ESC say, in words (docs/drive-messages.md, PROTOCOL.md §11): one table per
// concept — the CoE objects a drive's diagnosis uses, the error codes and error numbers of seed 002
// (emergencies and 1003h entries), CiA 301's SDO abort codes, ETG.1000.6's AL status codes. Every
// text the reports, the plugin's value names and the docs show comes from these rows.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "ncservo/wire/ecat_wire.hpp"

namespace ncservo::diag {

// --- Objects (CiA 301, CiA 402, ETG.1020; seed 002 for 1003h) ---
inline constexpr std::uint16_t kErrorRegister = 0x1001;
inline constexpr std::uint16_t kPredefinedErrorField = 0x1003;
inline constexpr std::uint16_t kLastErrorCode = 0x603F;
inline constexpr std::uint16_t kDiagnosisHistory = 0x10F3;
// 1003h: subindex 0 the number of entries (writing 0 clears them), 1..8 newest first.
inline constexpr std::uint8_t kErrorFieldEntries = 8;

struct ObjectDef {
  std::uint16_t index;
  const char* name;
};
inline constexpr std::array<ObjectDef, 4> kObjects{{
    {kErrorRegister, "error register"},
    {kPredefinedErrorField, "pre-defined error field"},
    {kDiagnosisHistory, "diagnosis history"},
    {kLastErrorCode, "error code"},
}};
const char* objectName(std::uint16_t index);  // null for an object not in the table

// 1001h's bits (and an emergency's error register).
struct RegisterBitDef {
  std::uint8_t mask;
  const char* name;
  const char* label;
};
inline constexpr std::array<RegisterBitDef, 7> kErrorRegisterBits{{
    {0x01, "generic", "generic error"},
    {0x02, "current", "current"},
    {0x04, "voltage", "voltage"},
    {0x08, "temperature", "temperature"},
    {0x10, "communication", "communication error"},
    {0x20, "profile", "device profile specific"},
    {0x80, "manufacturer", "manufacturer specific"},
}};

// A 1003h entry (seed 002): error number << 24 | error class (1001h) << 16 | error code.
struct ErrorFieldEntry {
  std::uint8_t number;
  std::uint8_t error_class;
  std::uint16_t code;
};
constexpr ErrorFieldEntry errorFieldEntry(std::uint32_t value) {
  return {static_cast<std::uint8_t>(value >> 24), static_cast<std::uint8_t>(value >> 16),
          static_cast<std::uint16_t>(value & 0xFFFF)};
}

// --- Error codes (seed 002, CiA 301 families) ---
struct CodeText {
  std::uint32_t code;
  const char* text;
};
inline constexpr std::uint16_t kErrorReset = 0x0000;  // an emergency that says the error is gone
inline constexpr std::array<CodeText, 26> kErrorCodes{{
    {0x0000, "error reset or no error"},
    {0x1000, "general error"},
    {0x2300, "current at the controller output too large"},
    {0x3100, "overvoltage or undervoltage at the controller input"},
    {0x4200, "temperature error within the controller"},
    {0x5440, "interlock error"},
    {0x6010, "software reset (watchdog)"},
    {0x6100, "internal software error"},
    {0x6320, "rated current must be set"},
    {0x7113, "ballast resistor thermally overloaded"},
    {0x7121, "motor blocked"},
    {0x7200, "reference voltage correction factor missing"},
    {0x7305, "sensor 1 faulty"},
    {0x7306, "sensor 2 faulty"},
    {0x7307, "sensor n faulty"},
    {0x7600, "nonvolatile memory full or corrupt"},
    {0x8100, "error during fieldbus monitoring"},
    {0x8130, "life guard or heartbeat error"},
    {0x8200, "slave took too long to send PDO messages"},
    {0x8210, "PDO not processed due to a length error"},
    {0x8220, "PDO length exceeded"},
    {0x8240, "unexpected sync length"},
    {0x8400, "speed monitoring: slippage error too large"},
    {0x8611, "following error too large"},
    {0x8612, "limit switch exceeded"},
    {0xFF00, "manufacturer specific"},
}};
// The error number of seed 002, in a 1003h entry's top byte and an emergency's first data byte.
inline constexpr std::array<CodeText, 37> kErrorNumbers{{
    {0, "watchdog reset"},
    {1, "input voltage too high"},
    {2, "output current too high"},
    {3, "input voltage too low"},
    {4, "error at fieldbus"},
    {6, "node guarding request too late"},
    {7, "sensor 1 electrical fault"},
    {8, "sensor 2 electrical fault"},
    {9, "sensor 3 electrical fault"},
    {10, "positive limit switch exceeded"},
    {11, "negative limit switch exceeded"},
    {12, "overtemperature"},
    {13, "following error window and time out exceeded"},
    {14, "nonvolatile memory full"},
    {15, "motor blocked"},
    {16, "nonvolatile memory damaged"},
    {17, "PDO messages too late"},
    {18, "sensor n electrical fault"},
    {19, "PDO length error"},
    {20, "PDO length exceeded"},
    {21, "restart to avoid errors when saving"},
    {22, "rated current must be set"},
    {23, "encoder resolution or pole pairs incorrect"},
    {24, "motor current too high, adjust the PI parameters"},
    {25, "internal software error"},
    {26, "current too high at digital output"},
    {27, "unexpected sync length"},
    {30, "slippage error too large"},
    {32, "reference voltage correction factor missing"},
    {35, "STO fault"},
    {36, "STO changeover"},
    {37, "STO active"},
    {38, "STO self-test error"},
    {40, "ballast resistor thermally overloaded"},
    {43, "logic input voltage too high"},
    {44, "logic input voltage too low"},
    {46, "interlock error"},
}};
// Seed 002's text for an error code; for a code not in it, its CiA 301 family ("current",
// "voltage", …); null for neither.
const char* errorCodeText(std::uint16_t code);
// The error register (1001h) an error of this code sets: the generic bit and its family's (0 for
// an error reset).
std::uint8_t errorRegisterFor(std::uint16_t code);
const char* errorNumberText(std::uint8_t number);

// --- SDO abort codes (CiA 301, ETG.1000.6) ---
inline constexpr std::uint32_t kAbortNoDataAvailable = 0x08000024;
inline constexpr std::array<CodeText, 33> kAbortCodes{{
    {0x05030000, "toggle bit not changed"},
    {0x05040000, "SDO protocol timeout"},
    {0x05040001, "client/server command specifier not valid or unknown"},
    {0x05040002, "invalid block size"},
    {0x05040003, "invalid sequence number"},
    {0x05040004, "CRC error"},
    {0x05040005, "out of memory"},
    {0x06010000, "unsupported access to an object"},
    {0x06010001, "attempt to read a write-only object"},
    {0x06010002, "attempt to write a read-only object"},
    {0x06010003, "subindex cannot be written, subindex 0 must be 0 for write access"},
    {0x06010004, "complete access not supported"},
    {0x06020000, "object does not exist"},
    {0x06040041, "object cannot be mapped to the PDO"},
    {0x06040042, "the mapped objects would exceed the PDO length"},
    {0x06040043, "general parameter incompatibility"},
    {0x06040047, "general internal incompatibility in the device"},
    {0x06060000, "access failed due to a hardware error"},
    {0x06070010, "data type does not match, length of service parameter does not match"},
    {0x06070012, "data type does not match, length of service parameter too high"},
    {0x06070013, "data type does not match, length of service parameter too low"},
    {0x06090011, "subindex does not exist"},
    {0x06090030, "value range of parameter exceeded"},
    {0x06090031, "value of parameter written too high"},
    {0x06090032, "value of parameter written too low"},
    {0x06090036, "maximum value is less than minimum value"},
    {0x060A0023, "resource not available: SDO connection"},
    {0x08000000, "general error"},
    {0x08000020, "data cannot be transferred or stored to the application"},
    {0x08000021, "data cannot be transferred or stored because of local control"},
    {0x08000022, "data cannot be transferred or stored because of the present device state"},
    {0x08000023, "no object dictionary present"},
    {kAbortNoDataAvailable, "no data available"},
}};
const char* abortText(std::uint32_t code);  // null for a code not in the table

// --- AL status codes (ETG.1000.6; SOEM's ethercatprint.c holds the same) ---
struct AlCodeDef {
  std::uint16_t code;
  const char* text;
  bool sync;  // a synchronization, sync-manager watchdog or PLL error (cause `sync-error`)
};
inline constexpr std::array<AlCodeDef, 52> kAlStatusCodes{{
    {0x0000, "no error", false},
    {0x0001, "unspecified error", false},
    {0x0002, "no memory", false},
    {0x0011, "invalid requested state change", false},
    {0x0012, "unknown requested state", false},
    {0x0013, "bootstrap not supported", false},
    {0x0014, "no valid firmware", false},
    {0x0015, "invalid mailbox configuration (BOOT)", false},
    {0x0016, "invalid mailbox configuration (PRE-OP)", false},
    {0x0017, "invalid sync manager configuration", false},
    {0x0018, "no valid inputs available", false},
    {0x0019, "no valid outputs", false},
    {0x001A, "synchronization error", true},
    {0x001B, "sync manager watchdog", true},
    {0x001C, "invalid sync manager types", false},
    {0x001D, "invalid output configuration", false},
    {0x001E, "invalid input configuration", false},
    {0x001F, "invalid watchdog configuration", false},
    {0x0020, "slave needs cold start", false},
    {0x0021, "slave needs INIT", false},
    {0x0022, "slave needs PRE-OP", false},
    {0x0023, "slave needs SAFE-OP", false},
    {0x0024, "invalid input mapping", false},
    {0x0025, "invalid output mapping", false},
    {0x0026, "inconsistent settings", false},
    {0x0027, "free run not supported", false},
    {0x0028, "synchronization not supported", false},
    {0x0029, "free run needs 3-buffer mode", false},
    {0x002A, "background watchdog", false},
    {0x002B, "no valid inputs and outputs", false},
    {0x002C, "fatal sync error", true},
    {0x002D, "no sync error", true},
    {0x002E, "invalid input FMMU configuration", false},
    {0x0030, "invalid DC SYNC configuration", false},
    {0x0031, "invalid DC latch configuration", false},
    {0x0032, "PLL error", true},
    {0x0033, "DC sync IO error", true},
    {0x0034, "DC sync timeout error", true},
    {0x0035, "DC invalid sync cycle time", false},
    {0x0036, "DC invalid SYNC0 cycle time", false},
    {0x0037, "DC invalid SYNC1 cycle time", false},
    {0x0041, "mailbox AoE error", false},
    {0x0042, "mailbox EoE error", false},
    {0x0043, "mailbox CoE error", false},
    {0x0044, "mailbox FoE error", false},
    {0x0045, "mailbox SoE error", false},
    {0x004F, "mailbox VoE error", false},
    {0x0050, "EEPROM no access", false},
    {0x0051, "EEPROM error", false},
    {0x0060, "slave restarted locally", false},
    {0x0061, "device identification value updated", false},
    {0x00F0, "application controller available", false},
}};
const AlCodeDef* alStatusCode(std::uint16_t code);  // null for a code not in the table

// --- Mailbox types, by name (the ones other than CoE are counted, not decoded) ---
const char* mailboxTypeName(std::uint8_t type);  // "CoE", "EoE", …, "other"

// --- ESC error counters, by name (JSON `esc_errors` "counter") ---
// The watchdog counters (0x0442 process data, 0x0443 PDI) count expiries: a slave whose outputs
// stopped coming for longer than its sync manager watchdog, or whose application stopped serving
// its PDI.
enum class EscCounter : std::uint8_t {
  Invalid,
  Rx,
  Forwarded,
  LostLink,
  Processing,
  Pdi,
  SmWatchdog,
  PdiWatchdog
};
// Each counter's name and where it lies (ESC datasheets, PROTOCOL.md §11): its register at port
// 0 and the stride to the next port's; a stride of 0 is the slave's own counter (port 0 only).
struct EscCounterDef {
  const char* name;
  std::uint16_t at_port0;
  std::uint8_t port_stride;
};
inline constexpr std::array<EscCounterDef, 8> kEscCounters{{
    {"invalid", ecat::kRegInvalidFrame0, 2},
    {"rx", ecat::kRegRxError0, 2},
    {"forwarded", ecat::kRegForwardedRxError0, 1},
    {"lost-link", ecat::kRegLostLink0, 1},
    {"processing", ecat::kRegProcessingUnitError, 0},
    {"pdi", ecat::kRegPdiError, 0},
    {"sm-watchdog", ecat::kRegSmWatchdogCounter, 0},
    {"pdi-watchdog", ecat::kRegPdiWatchdogCounter, 0},
}};
constexpr const EscCounterDef& escCounterDef(EscCounter counter) {
  return kEscCounters[static_cast<std::size_t>(counter)];
}
constexpr const char* escCounterName(EscCounter counter) {
  return escCounterDef(counter).name;
}
// The register of a counter of a port (the slave's own counters: port 0).
constexpr std::uint16_t escCounterRegister(EscCounter counter, std::uint8_t port) {
  const EscCounterDef& def = escCounterDef(counter);
  return static_cast<std::uint16_t>(def.at_port0 + def.port_stride * port);
}

template <std::size_t N>
constexpr bool sortedByCode(const std::array<CodeText, N>& table) {
  for (std::size_t i = 1; i < N; ++i) {
    if (table[i - 1].code >= table[i].code) return false;
  }
  return true;
}
static_assert(sortedByCode(kErrorCodes) && sortedByCode(kErrorNumbers) && sortedByCode(kAbortCodes),
              "code tables sorted, each code once");

}  // namespace ncservo::diag
