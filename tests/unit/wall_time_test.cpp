// Times of day as a person reads them and ISO 8601 times typed for --from/--to (wall_time.hpp),
// against calendars written out by hand. Local time is a POSIX TZ rule set here, so the rows
// hold on any machine: CET (+01:00) in winter, CEST (+02:00) in summer.
#include "ncservo/base/wall_time.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <ctime>
#include <optional>
#include <string>

#include "ncservo/pipeline/capture_pipeline.hpp"

namespace ncservo {
namespace {

constexpr std::int64_t kSecond = 1'000'000'000;
constexpr std::int64_t kMay1At10 = 1714557600 * kSecond;   // 2024-05-01T10:00:00Z (CEST)
constexpr std::int64_t kJan15Late = 1705363199 * kSecond;  // 2024-01-15T23:59:59Z (CET)

class InBerlin : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const char* tz = std::getenv("TZ")) saved_ = tz;
    setenv("TZ", "CET-1CEST,M3.5.0,M10.5.0/3", 1);
    tzset();
  }
  void TearDown() override {
    if (saved_) {
      setenv("TZ", saved_->c_str(), 1);
    } else {
      unsetenv("TZ");
    }
    tzset();
  }

 private:
  std::optional<std::string> saved_;
};

struct IsoCase {
  std::int64_t time_ns;
  int digits;
  TimeZone zone;
  const char* text;
};
const IsoCase kIsoCases[] = {
    {kMay1At10 + 123'456'789, 6, TimeZone::Utc, "2024-05-01T10:00:00.123456Z"},
    {kMay1At10 + 123'456'789, 9, TimeZone::Utc, "2024-05-01T10:00:00.123456789Z"},
    {kMay1At10 + 999'999'999, 3, TimeZone::Utc, "2024-05-01T10:00:00.999Z"},  // truncated
    {kMay1At10, 0, TimeZone::Utc, "2024-05-01T10:00:00Z"},
    {kMay1At10 + 500'000'000, 6, TimeZone::Local, "2024-05-01T12:00:00.500000+02:00"},
    {kJan15Late, 3, TimeZone::Local, "2024-01-16T00:59:59.000+01:00"},  // the next day there
    {-1, 9, TimeZone::Utc, "1969-12-31T23:59:59.999999999Z"},           // before the epoch
};

TEST_F(InBerlin, IsoTimeWritesEachZone) {
  for (const IsoCase& c : kIsoCases) {
    EXPECT_EQ(isoTime(c.time_ns, c.digits, c.zone), c.text) << c.text;
  }
}

TEST_F(InBerlin, TimeOfDayToTheMillisecond) {
  EXPECT_EQ(timeOfDay(kMay1At10 + 41 * 60 * kSecond + 7'123'999'999, TimeZone::Utc),
            "10:41:07.123");
  EXPECT_EQ(timeOfDay(kMay1At10 + 41 * 60 * kSecond + 7'123'999'999, TimeZone::Local),
            "12:41:07.123");
  EXPECT_EQ(timeOfDay(kJan15Late, TimeZone::Local), "00:59:59.000");
}

struct ParseCase {
  const char* text;
  TimeZone zone;
  std::optional<std::int64_t> time_ns;
};
const ParseCase kParseCases[] = {
    {"2024-05-01T10:00:00Z", TimeZone::Utc, kMay1At10},
    {"2024-05-01T10:00:00", TimeZone::Utc, kMay1At10},  // no offset: in the zone asked for
    {"2024-05-01 10:00:00.25Z", TimeZone::Local, kMay1At10 + kSecond / 4},
    {"2024-05-01T12:00:00+02:00", TimeZone::Utc, kMay1At10},
    {"2024-05-01T12:00+0200", TimeZone::Utc, kMay1At10},
    {"2024-05-01T09:30:00-00:30", TimeZone::Utc, kMay1At10},
    {"2024-05-01T12:00:00", TimeZone::Local, kMay1At10},   // CEST: +02:00
    {"2024-01-16T00:59:59", TimeZone::Local, kJan15Late},  // CET: +01:00
    {"2024-05-01T10:00:00.123456789Z", TimeZone::Utc, kMay1At10 + 123'456'789},
    {"2024-02-30T10:00:00Z", TimeZone::Utc, std::nullopt},  // no such day
    {"2024-05-01T24:00:00Z", TimeZone::Utc, std::nullopt},
    {"2024-05-01", TimeZone::Utc, std::nullopt},  // a date alone is not a time
    {"10:41:00", TimeZone::Utc, std::nullopt},    // nor a time without its date
    {"2024-05-01T10:00:00.Z", TimeZone::Utc, std::nullopt},
    {"2024-05-01T10:00:00Zjunk", TimeZone::Utc, std::nullopt},
    {"2024-5-1T10:00:00Z", TimeZone::Utc, std::nullopt},
    {"", TimeZone::Utc, std::nullopt},
};

TEST_F(InBerlin, ParseIsoTimeTakesOffsetsAndRefusesTheRest) {
  for (const ParseCase& c : kParseCases) {
    EXPECT_EQ(parseIsoTime(c.text, c.zone), c.time_ns) << c.text;
  }
}

TEST_F(InBerlin, TimeWindowTakesSecondsOrIsoTimes) {
  const auto window =
      timeWindowOf(std::string("1.5"), std::string("2024-05-01T12:00:02+02:00"), TimeZone::Utc);
  ASSERT_TRUE(window) << window.error().text();
  EXPECT_EQ(window->from_ns, 1'500'000'000);
  EXPECT_FALSE(window->from_absolute);
  EXPECT_EQ(window->to_ns, kMay1At10 + 2 * kSecond);
  EXPECT_TRUE(window->to_absolute);
  // The capture starts at 10:00:00 UTC: 1.5 s in is inside, 2.5 s in is after --to.
  EXPECT_FALSE(window->contains(kSecond, kMay1At10));
  EXPECT_TRUE(window->contains(2 * kSecond, kMay1At10));
  EXPECT_FALSE(window->contains(2 * kSecond + 1, kMay1At10));
  const auto local =
      timeWindowOf(std::string("2024-05-01T12:00:01"), std::nullopt, TimeZone::Local);
  ASSERT_TRUE(local);
  EXPECT_EQ(local->from_ns, kMay1At10 + kSecond);
}

TEST_F(InBerlin, TimeWindowRefusesWhatIsNeither) {
  for (const char* bad : {"yesterday", "2024-13-01T00:00:00Z", "1e999", "nan"}) {
    const auto window = timeWindowOf(std::string(bad), std::nullopt, TimeZone::Utc);
    ASSERT_FALSE(window) << bad;
    EXPECT_NE(window.error().text().find(std::string("--from ") + bad), std::string::npos)
        << window.error().text();
  }
  EXPECT_FALSE(timeWindowOf(std::string("2024-05-01T10:00:02Z"),
                            std::string("2024-05-01T10:00:01Z"), TimeZone::Utc));
}

}  // namespace
}  // namespace ncservo
