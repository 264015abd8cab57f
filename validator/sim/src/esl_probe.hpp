// An ET2000 probe in the line from the master to the first slave (docs/protocol.md §8): each frame
// reaches the capture behind a 16-byte ESL header stamped with the exact simulated time, while
// the capture's own timestamp is the PC's, late by up to a few hundred microseconds.
#pragma once

#include <cstdint>

#include "ncservo/sim/options.hpp"

namespace ncservo::sim {

// How late the PC stamps a frame, at most (uniform; tests/tools/wrap_capture.py's --noise-us).
inline constexpr std::int64_t kPcStampNoiseNs = 300'000;

// A sink that hands each frame to `sink` the way the probe captures it; the noise is a pure
// function of `seed`.
FrameSink eslProbeSink(FrameSink sink, std::uint64_t seed);

}  // namespace ncservo::sim
