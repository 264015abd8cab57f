// Times of day a person reads (docs/cli.md#times-of-day): a capture's stamps as ISO 8601, in UTC
// or in the machine's local time (`--local-time`), and ISO 8601 times typed for --from/--to.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace ncservo {

enum class TimeZone : std::uint8_t { Utc, Local };

// "2024-05-01T12:00:00.123456Z" (UTC) or "2024-05-01T14:00:00.123456+02:00" (local): `time_ns`
// since the epoch, with the first `digits` (0..9) digits of the second, truncated as a capture's
// precision has it.
std::string isoTime(std::int64_t time_ns, int digits, TimeZone zone);

// "12:00:00.123" (UTC) or "14:00:00.123" (local): the time of day to the millisecond, truncated.
std::string timeOfDay(std::int64_t time_ns, TimeZone zone);
// The same written into `out` (at least kTimeOfDaySize bytes); returns its end. A storm of
// findings writes thousands a second.
inline constexpr std::size_t kTimeOfDaySize = 16;
char* writeTimeOfDay(std::int64_t time_ns, TimeZone zone, char* out);

// Nanoseconds since the epoch of an ISO 8601 date and time, "2024-05-01T12:00:00",
// "2024-05-01 12:00:00.25Z", "2024-05-01T14:00+02:00": a time with no offset is in `zone`.
// Empty when `text` is not one.
std::optional<std::int64_t> parseIsoTime(std::string_view text, TimeZone zone);

}  // namespace ncservo
