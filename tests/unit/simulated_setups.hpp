// The simulator's set-ups as the truth for the layout sources (docs/protocol.md §9): what it
// configured is what learning from its start-up and the ENI it writes must give.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "ncservo/config/config.hpp"
#include "ncservo/sim/simulator.hpp"
#include "status_text.hpp"

namespace ncservo::test {

struct SetUp {
  const char* name;
  int axes;
  int io_slaves;
  sim::ImageStyle image;
  std::uint64_t seed = 1;  // mixed: the set-up and the order (seed 1 per slave, 2 outputs first)
};
inline const SetUp kSetUps[] = {
    {"1 axis", 1, 0, sim::ImageStyle::Soem},
    {"4 axes, default layout", 4, 0, sim::ImageStyle::Soem},
    {"3 axes and 2 terminals, interleaved", 3, 2, sim::ImageStyle::EtherLab},
    {"4 axes and 4 terminals, default layout", 4, 4, sim::ImageStyle::Soem},
    {"32 axes and 3 terminals, two frames", 32, 3, sim::ImageStyle::EtherLab},
    {"3 axes among 8 mixed slaves, per slave", 3, 8, sim::ImageStyle::Mixed, 1},
    {"5 axes among 12 mixed slaves, outputs first", 5, 12, sim::ImageStyle::Mixed, 2},
    {"32 axes among 32 mixed slaves", 32, 32, sim::ImageStyle::Mixed, 3},
    {"4 axes and 4 slaves, TwinCAT areas", 4, 4, sim::ImageStyle::TwinCat},
    {"1 axis alone, TwinCAT areas", 1, 0, sim::ImageStyle::TwinCat},
    {"30 axes and 6 slaves, TwinCAT areas, two frames", 30, 6, sim::ImageStyle::TwinCat},
};

inline sim::SimOptions optionsFor(const SetUp& s) {
  sim::SimOptions o;
  o.axes = s.axes;
  o.io_slaves = s.io_slaves;
  o.image = s.image;
  o.seed = s.seed;
  o.duration_s = 1.0;
  EXPECT_EQ(test::statusText(sim::resolveOptions(o)), "");
  return o;
}

inline void expectSameAxes(const std::vector<AxisConfig>& got,
                           const std::vector<AxisConfig>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    SCOPED_TRACE(want[i].name);
    EXPECT_EQ(got[i].outputs, want[i].outputs);
    EXPECT_EQ(got[i].inputs, want[i].inputs);
    EXPECT_EQ(got[i].station, want[i].station);
  }
}

}  // namespace ncservo::test
