// The bits of the control, status and error words that the library's logic names, each from its
// row in the field table (docs/fields.md), so that a bit is defined once.
#pragma once

#include <cstdint>

#include "ncservo/protocol/fields.hpp"

namespace ncservo::bits {
inline constexpr std::uint32_t kSe = mask32("ncservo.scw.se");
inline constexpr std::uint32_t kEmgon = mask32("ncservo.scw.emgon");
inline constexpr std::uint32_t kScwPrmtbl = mask32("ncservo.scw.prmtbl");
inline constexpr std::uint32_t kErrorClear = mask32("ncservo.scw.error_clear");
inline constexpr std::uint32_t kBrake = mask32("ncservo.scw.brake");
inline constexpr std::uint32_t kZPulseRequest = mask32("ncservo.scw.zpulse_request");
inline constexpr std::uint32_t kScwExtPrmtbl = mask32("ncservo.scw.ext_prmtbl");
inline constexpr std::uint32_t kScwReserved = mask32("ncservo.scw.reserved");
inline constexpr std::uint32_t kServoEn = mask32("ncservo.ssw.servo_en");
inline constexpr std::uint32_t kServoRdy = mask32("ncservo.ssw.servo_rdy");
inline constexpr std::uint32_t kIncremental = mask32("ncservo.ssw.incremental");
inline constexpr std::uint32_t kNoEncoder = mask32("ncservo.ssw.no_encoder");
inline constexpr std::uint32_t kZPulseAck = mask32("ncservo.ssw.zpulse_ack");
inline constexpr std::uint32_t kErrClearAck = mask32("ncservo.ssw.err_clear_ack");
inline constexpr std::uint32_t kNZero = mask32("ncservo.ssw.n_zero");
inline constexpr std::uint32_t kNSetpoint = mask32("ncservo.ssw.n_setpoint");
inline constexpr std::uint32_t kPulseEnabled = mask32("ncservo.ssw.pulse_enabled");
inline constexpr std::uint32_t kSswPrmtbl = mask32("ncservo.ssw.prmtbl");
inline constexpr std::uint32_t kSswExtPrmtbl = mask32("ncservo.ssw.ext_prmtbl");
inline constexpr std::uint32_t kSswReserved = mask32("ncservo.ssw.reserved");
inline constexpr std::uint32_t kServoErrors = mask32("ncservo.sew.servo_errors");
inline constexpr std::uint32_t kSewReserved = mask32("ncservo.sew.reserved");
inline constexpr std::uint32_t kEcatTimeout = mask32("ncservo.sew.ecat_timeout");
inline constexpr std::uint32_t kFollowing = mask32("ncservo.sew.following");
inline constexpr std::uint32_t kOverload = mask32("ncservo.sew.overload");

inline constexpr std::uint32_t kSeEnable = 0x2;   // reached from 0x1 only (docs/protocol.md §2)
inline constexpr std::uint32_t kSePrepare = 0x1;  // the one value SE may enable from
}  // namespace ncservo::bits
