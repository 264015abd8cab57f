// The timing block of the text report (docs/timing.md), shared by `validate`, `decode --timing`
// and the plugin's `tshark -z ncservo,timing`, so that all three print the same numbers.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/model/dc_clock.hpp"
#include "ncservo/model/timing.hpp"

namespace ncservo {

// Lines ending in '\n': the cycle statistics, the return latency and the worst of each.
// `timestamps` names what timed the frames ("capture", "probe").
std::string timingText(const TimingSummary& timing, const char* timestamps,
                       std::int64_t resolution_ns);

// The distributed clocks block: a line per slave whose clock was read; nothing when none was.
// `settled_ns` is the bound the settled frames were judged against; `against` names the clock the
// drifts are measured against ("the capture's clock", docs/timing.md#drift).
std::string dcText(const std::vector<DcStation>& stations, std::int64_t settled_ns,
                   std::string_view against);

// The copies a capture missed, told apart from lost cycles (docs/timing.md "Capture loss"), in
// words that agree with their counts; empty when none is missing.
std::string copiesMissingText(std::uint64_t master, std::uint64_t returned);

}  // namespace ncservo
