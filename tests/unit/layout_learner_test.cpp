// The servos' layout learnt from a start-up (layout_learner.hpp, docs/protocol.md §9.3): the SM
// and FMMU register writes, byte by byte, then the simulator's start-ups as the truth.
#include "ncservo/layout/layout_learner.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/sim/simulator.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "row_name.hpp"
#include "simulated_setups.hpp"
#include "status_text.hpp"

namespace ncservo {
namespace {

using test::Bytes;
using test::concat;
using test::Dg;
using test::expectSameAxes;
using test::fmmuBlock;
using test::kSetUps;
using test::optionsFor;
using test::physical;
using test::smBlock;

// ---- SM and FMMU writes built byte by byte ----

// SM2 and SM3 of the slave at `station`, of these lengths.
Dg smWrite(std::uint16_t station, std::uint16_t outputs, std::uint16_t inputs,
           std::uint8_t command = ecat::kFpwr) {
  return Dg{command, 1, physical(station, ecat::kRegSyncManager0 + 2 * ecat::kSyncManagerStride),
            concat({smBlock(0x1100, outputs, 0x64), smBlock(0x1180, inputs, 0x20)}), 0};
}
// FMMU0 over SM2 (outputs at `logical`) and FMMU1 over SM3 (inputs 10 bytes after).
Dg fmmuWrite(std::uint16_t station, std::uint32_t logical) {
  return Dg{ecat::kFpwr, 2, physical(station, ecat::kRegFmmu0),
            concat({fmmuBlock(logical, 10, 0x1100, 2), fmmuBlock(logical + 10, 40, 0x1180, 1)}), 0};
}

struct LearnedAxis {
  std::uint16_t station;
  std::uint32_t outputs, inputs;
};
struct WriteCase {
  const char* name;
  std::vector<Dg> frames;  // one datagram per frame, in capture order
  bool returned, paired;   // how every frame is seen (LayoutLearner::onFrame)
  bool saw_configuration, saw_servo;
  std::vector<LearnedAxis> axes;
};
const std::vector<WriteCase>& writeCases() {
  static const std::vector<WriteCase> cases = {
      {"servo SMs and FMMUs give a logical axis",
       {smWrite(0x03E9, 10, 40), fmmuWrite(0x03E9, 0x00020000)},
       false,
       false,
       true,
       true,
       {{0x03E9, 0x00020000, 0x0002000A}}},
      {"servo SMs without FMMUs: no axis yet",
       {smWrite(0x03E9, 10, 40)},
       false,
       false,
       true,
       true,
       {}},
      {"SMs of another slave: no servo", {smWrite(0x03E9, 6, 6)}, false, false, true, false, {}},
      {"lengths of zero configure nothing",
       {smWrite(0x03E9, 0, 0)},
       false,
       false,
       false,
       false,
       {}},
      {"a read of the SM registers is no write",
       {smWrite(0x03E9, 10, 40, ecat::kFprd)},
       false,
       false,
       false,
       false,
       {}},
      {"two servos, in ring order",
       {smWrite(0x03EA, 10, 40), fmmuWrite(0x03EA, 0x00020032), smWrite(0x03E9, 10, 40),
        fmmuWrite(0x03E9, 0x00020000)},
       false,
       false,
       true,
       true,
       {{0x03E9, 0x00020000, 0x0002000A}, {0x03EA, 0x00020032, 0x0002003C}}},
      {"a returned copy whose master copy was captured is not read again",
       {smWrite(0x03E9, 10, 40), fmmuWrite(0x03E9, 0x00020000)},
       true,
       true,
       false,
       false,
       {}},
      {"a returned copy whose master copy was lost is read",
       {smWrite(0x03E9, 10, 40), fmmuWrite(0x03E9, 0x00020000)},
       true,
       false,
       true,
       true,
       {{0x03E9, 0x00020000, 0x0002000A}}},
  };
  return cases;
}

class LearnerWrites : public ::testing::TestWithParam<WriteCase> {};

TEST_P(LearnerWrites, GiveTheServosAxes) {
  const WriteCase& c = GetParam();
  LayoutLearner learner;
  for (const Dg& dg : c.frames) {
    test::FrameBuilder builder;
    builder.add(dg);
    const test::Walked walked = test::walk(builder.bytes());
    learner.onFrame(*walked.frame, walked.reader(), c.returned, c.paired);
  }
  EXPECT_EQ(learner.sawConfiguration(), c.saw_configuration);
  EXPECT_EQ(learner.sawServo(), c.saw_servo);
  ASSERT_EQ(learner.axes().size(), c.axes.size());
  for (std::size_t i = 0; i < c.axes.size(); ++i) {
    SCOPED_TRACE("axis " + std::to_string(i));
    EXPECT_EQ(learner.axes()[i].station, c.axes[i].station);
    EXPECT_EQ(learner.axes()[i].outputs, c.axes[i].outputs);
    EXPECT_EQ(learner.axes()[i].inputs, c.axes[i].inputs);
  }
  EXPECT_EQ(learner.generation() > 0, !c.axes.empty());
}

INSTANTIATE_TEST_SUITE_P(Cases, LearnerWrites, ::testing::ValuesIn(writeCases()),
                         test::rowName<WriteCase>);

TEST(LearnerWrites, DescribeSlaveLayoutNamesEveryRegister) {
  LayoutLearner learner;
  for (const Dg& dg : {smWrite(0x03E9, 10, 40), fmmuWrite(0x03E9, 0x00020000)}) {
    test::FrameBuilder builder;
    builder.add(dg);
    const test::Walked walked = test::walk(builder.bytes());
    learner.onFrame(*walked.frame, walked.reader(), false, false);
  }
  const std::vector<SlaveLayout> slaves = learner.slaves();
  ASSERT_EQ(slaves.size(), 1u);
  EXPECT_TRUE(slaves[0].servo);
  EXPECT_EQ(describeSlaveLayout(slaves[0]),
            "station 0x03E9; SM2 0x1100+10 control 0x64; SM3 0x1180+40 control 0x20; "
            "FMMU0 0x00020000+10 -> 0x1100 write; FMMU1 0x0002000A+40 -> 0x1180 read; servo");
}

// ---- The simulator's start-ups ----

// Feeds the simulator's frames to the learner, telling master and returned copies apart as the
// decoder does (a returned copy repeats the datagram list of the master copy just before it).
// Stops before the first frame that writes an FMMU when `before_fmmus`.
void learn(sim::Simulator& simulator, LayoutLearner& learner, std::size_t max_frames,
           bool before_fmmus = false) {
  auto previous = std::make_unique<EcatFrame>();
  auto frame = std::make_unique<EcatFrame>();
  bool previous_master = false;
  std::size_t n = 0;
  simulator.run([&](const sim::SimFrame& f) {
    ByteReader bytes(f.data, f.size);
    walkPacket(LinkType::Ethernet, bytes, *frame);
    if (before_fmmus && frame->count > 0 && frame->datagrams[0].command == ecat::kFpwr &&
        frame->datagrams[0].ado() == ecat::kRegFmmu0) {
      return false;
    }
    const bool returned = (f.data[6] & 0x02) != 0;  // the slaves' locally-administered bit
    const bool paired = returned && previous_master && frame->sameDatagramList(*previous);
    learner.onFrame(*frame, bytes, returned, paired);
    previous_master = !returned;
    std::swap(previous, frame);
    return ++n < max_frames;
  });
}

class LearnedLayout : public ::testing::TestWithParam<test::SetUp> {};

TEST_P(LearnedLayout, MatchesWhatTheStartUpConfigured) {
  sim::Simulator simulator(optionsFor(GetParam()));
  LayoutLearner learner;
  learn(simulator, learner, 400);  // the start-up and the first cycles
  EXPECT_TRUE(learner.sawConfiguration());
  expectSameAxes(learner.axes(), simulator.layout());
  const auto slaves = learner.slaves();
  ASSERT_EQ(slaves.size(), static_cast<std::size_t>(GetParam().axes + GetParam().io_slaves));
  for (std::size_t pos = 0; pos < slaves.size(); ++pos) {
    EXPECT_EQ(slaves[pos].position, pos);
    EXPECT_EQ(slaves[pos].station, 0x03E9 + pos);
  }
}

INSTANTIATE_TEST_SUITE_P(SimulatedSetUps, LearnedLayout, ::testing::ValuesIn(kSetUps),
                         test::rowName<test::SetUp>);

TEST(LearnedLayout, NothingBeforeTheFmmusAreWritten) {
  sim::SimOptions o;
  o.duration_s = 1.0;
  ASSERT_EQ(test::statusText(sim::resolveOptions(o)), "");
  sim::Simulator simulator(o);
  LayoutLearner learner;
  learn(simulator, learner, 1000, true);  // up to the SM writes, before the FMMU writes
  EXPECT_TRUE(learner.sawConfiguration());
  EXPECT_TRUE(learner.axes().empty());
  EXPECT_EQ(learner.generation(), 0u);
}

TEST(LearnedLayout, NoStartUpNothingLearned) {
  sim::SimOptions o;
  o.duration_s = 1.0;
  o.startup = false;
  ASSERT_EQ(test::statusText(sim::resolveOptions(o)), "");
  sim::Simulator simulator(o);
  LayoutLearner learner;
  learn(simulator, learner, 200);
  EXPECT_FALSE(learner.sawConfiguration());
  EXPECT_TRUE(learner.axes().empty());
}

}  // namespace
}  // namespace ncservo
