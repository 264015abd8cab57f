#include "ncservo/base/wall_time.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <ctime>
#include <limits>

namespace ncservo {

namespace {

constexpr std::int64_t kNsPerSecond = 1'000'000'000;

// Whole seconds, rounded down, and the nanoseconds past them (never negative).
std::pair<std::int64_t, std::int64_t> splitSeconds(std::int64_t time_ns) {
  std::int64_t seconds = time_ns / kNsPerSecond;
  std::int64_t rest = time_ns % kNsPerSecond;
  if (rest < 0) {
    --seconds;
    rest += kNsPerSecond;
  }
  return {seconds, rest};
}

// The calendar of a second, and its offset from UTC in seconds (0 in UTC). A report asks for many
// times within one second (findings, state changes, incidents), so the last second is kept.
struct Calendar {
  std::tm tm{};
  long offset_s = 0;
};
const Calendar& calendarOf(std::int64_t seconds, TimeZone zone) {
  thread_local std::int64_t last_second = std::numeric_limits<std::int64_t>::min();
  thread_local TimeZone last_zone = TimeZone::Utc;
  thread_local Calendar calendar;
  if (seconds != last_second || zone != last_zone) {
    const std::time_t whole = static_cast<std::time_t>(seconds);
    calendar = Calendar{};
    if (zone == TimeZone::Local) {
      localtime_r(&whole, &calendar.tm);
      calendar.offset_s = calendar.tm.tm_gmtoff;
    } else {
      gmtime_r(&whole, &calendar.tm);
    }
    last_second = seconds;
    last_zone = zone;
  }
  return calendar;
}

std::string offsetText(long offset_s) {
  const long minutes = (offset_s < 0 ? -offset_s : offset_s) / 60;
  return fmt::format("{}{:02}:{:02}", offset_s < 0 ? '-' : '+', minutes / 60, minutes % 60);
}

// Reads `count` digits at `at`; false when they are not all there.
bool readDigits(std::string_view text, std::size_t& at, std::size_t count, int& value) {
  if (text.size() < at + count) return false;
  const auto [end, ec] = std::from_chars(text.data() + at, text.data() + at + count, value);
  if (ec != std::errc() || end != text.data() + at + count) return false;
  at += count;
  return true;
}

bool expect(std::string_view text, std::size_t& at, char c) {
  if (at >= text.size() || text[at] != c) return false;
  ++at;
  return true;
}

}  // namespace

std::string isoTime(std::int64_t time_ns, int digits, TimeZone zone) {
  const auto [seconds, nanoseconds] = splitSeconds(time_ns);
  const Calendar& c = calendarOf(seconds, zone);
  std::string text =
      fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}", c.tm.tm_year + 1900, c.tm.tm_mon + 1,
                  c.tm.tm_mday, c.tm.tm_hour, c.tm.tm_min, c.tm.tm_sec);
  digits = std::clamp(digits, 0, 9);
  if (digits > 0) {
    // The first `digits` of the nine: the fraction truncated, as the capture's precision has it.
    const std::string fraction = fmt::format("{:09}", nanoseconds);
    text += '.';
    text.append(fraction, 0, static_cast<std::size_t>(digits));
  }
  text += zone == TimeZone::Utc ? std::string("Z") : offsetText(c.offset_s);
  return text;
}

char* writeTimeOfDay(std::int64_t time_ns, TimeZone zone, char* out) {
  const auto [seconds, nanoseconds] = splitSeconds(time_ns);
  const Calendar& c = calendarOf(seconds, zone);
  return fmt::format_to_n(out, kTimeOfDaySize, "{:02}:{:02}:{:02}.{:03}", c.tm.tm_hour, c.tm.tm_min,
                          c.tm.tm_sec, nanoseconds / 1'000'000)
      .out;
}

std::string timeOfDay(std::int64_t time_ns, TimeZone zone) {
  char text[kTimeOfDaySize];
  return std::string(text, writeTimeOfDay(time_ns, zone, text));
}

std::optional<std::int64_t> parseIsoTime(std::string_view text, TimeZone zone) {
  std::size_t at = 0;
  std::tm tm{};
  int year = 0, month = 0, day = 0, hour = 0, minute = 0, second = 0;
  if (!readDigits(text, at, 4, year) || !expect(text, at, '-') || !readDigits(text, at, 2, month) ||
      !expect(text, at, '-') || !readDigits(text, at, 2, day))
    return std::nullopt;
  if (at >= text.size() || (text[at] != 'T' && text[at] != 't' && text[at] != ' '))
    return std::nullopt;
  ++at;
  if (!readDigits(text, at, 2, hour) || !expect(text, at, ':') || !readDigits(text, at, 2, minute))
    return std::nullopt;
  if (at < text.size() && text[at] == ':' && !(++at, readDigits(text, at, 2, second)))
    return std::nullopt;
  std::int64_t fraction_ns = 0;
  if (at < text.size() && (text[at] == '.' || text[at] == ',')) {
    ++at;
    std::int64_t scale = kNsPerSecond / 10;
    const std::size_t first = at;
    for (; at < text.size() && std::isdigit(static_cast<unsigned char>(text[at])); ++at) {
      fraction_ns += (text[at] - '0') * scale;
      scale /= 10;
    }
    if (at == first) return std::nullopt;
  }
  std::optional<long> offset_s;
  if (at < text.size() && (text[at] == 'Z' || text[at] == 'z')) {
    offset_s = 0;
    ++at;
  } else if (at < text.size() && (text[at] == '+' || text[at] == '-')) {
    const long sign = text[at] == '-' ? -1 : 1;
    ++at;
    int offset_hours = 0, offset_minutes = 0;
    if (!readDigits(text, at, 2, offset_hours)) return std::nullopt;
    if (at < text.size() && text[at] == ':') ++at;
    if (at < text.size() && !readDigits(text, at, 2, offset_minutes)) return std::nullopt;
    if (offset_hours > 23 || offset_minutes > 59) return std::nullopt;
    offset_s = sign * (offset_hours * 3600L + offset_minutes * 60L);
  }
  if (at != text.size() || month < 1 || month > 12 || day < 1 || day > 31 || hour > 23 ||
      minute > 59 || second > 60)
    return std::nullopt;
  tm.tm_year = year - 1900;
  tm.tm_mon = month - 1;
  tm.tm_mday = day;
  tm.tm_hour = hour;
  tm.tm_min = minute;
  tm.tm_sec = second;
  tm.tm_isdst = -1;
  std::tm checked = tm;
  const std::time_t whole = offset_s || zone == TimeZone::Utc ? timegm(&checked) : mktime(&checked);
  // A day the month does not have (2024-02-30) comes back as another day: refused.
  if (checked.tm_mday != day || checked.tm_mon != month - 1) return std::nullopt;
  return (static_cast<std::int64_t>(whole) - offset_s.value_or(0)) * kNsPerSecond + fraction_ns;
}

}  // namespace ncservo
