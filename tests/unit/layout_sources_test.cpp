// Layout sources of PROTOCOL.md §9 other than the configuration file: learning from the start-up
// (LayoutLearner) and the ENI file. The simulator's set-ups are the truth: what it configured is
// what learning and the ENI it writes must give.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "ncservo/eni.hpp"
#include "ncservo/ethercat.hpp"
#include "ncservo/layout_learner.hpp"
#include "ncservo/sim/simulator.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

struct SetUp {
  const char* name;
  int axes;
  int io_slaves;
  sim::LayoutKind layout;
};
const SetUp kSetUps[] = {
    {"1 axis", 1, 0, sim::LayoutKind::Default},
    {"4 axes, default layout", 4, 0, sim::LayoutKind::Default},
    {"3 axes and 2 terminals, interleaved", 3, 2, sim::LayoutKind::Interleaved},
    {"4 axes and 4 terminals, default layout", 4, 4, sim::LayoutKind::Default},
    {"32 axes and 3 terminals, two frames", 32, 3, sim::LayoutKind::Interleaved},
};

sim::SimOptions optionsFor(const SetUp& s) {
  sim::SimOptions o;
  o.axes = s.axes;
  o.io_slaves = s.io_slaves;
  o.layout = s.layout;
  o.duration_s = 1.0;
  EXPECT_EQ(sim::resolveOptions(o), "");
  return o;
}

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

void expectSameAxes(const std::vector<AxisConfig>& got,
                    const std::vector<sim::SimAxisLayout>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    SCOPED_TRACE(want[i].name);
    EXPECT_EQ(got[i].outputs, want[i].outputs);
    EXPECT_EQ(got[i].inputs, want[i].inputs);
    EXPECT_EQ(got[i].station, want[i].station);
  }
}

class LearnedLayout : public ::testing::TestWithParam<SetUp> {};

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

TEST_P(LearnedLayout, EniGivesTheSameLayout) {
  sim::Simulator simulator(optionsFor(GetParam()));
  const EniResult eni = parseEni(simulator.eni(), "sim.xml");
  ASSERT_TRUE(eni.ok()) << eni.error->text();
  EXPECT_EQ(eni.slaves, static_cast<std::size_t>(GetParam().axes + GetParam().io_slaves));
  expectSameAxes(eni.axes, simulator.layout());
}

INSTANTIATE_TEST_SUITE_P(SimulatedSetUps, LearnedLayout, ::testing::ValuesIn(kSetUps),
                         test::rowName<SetUp>);

TEST(LearnedLayout, NothingBeforeTheFmmusAreWritten) {
  sim::SimOptions o;
  o.duration_s = 1.0;
  ASSERT_EQ(sim::resolveOptions(o), "");
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
  ASSERT_EQ(sim::resolveOptions(o), "");
  sim::Simulator simulator(o);
  LayoutLearner learner;
  learn(simulator, learner, 200);
  EXPECT_FALSE(learner.sawConfiguration());
  EXPECT_TRUE(learner.axes().empty());
}

struct EniCase {
  const char* name;
  const char* xml;
  std::size_t axes;
  std::uint32_t line;  // of the error; 0 = no error
  const char* message;
};
const char* const kServo =
    "<Slave><Info><Name>X</Name><PhysAddr>#x3E9</PhysAddr></Info><ProcessData>"
    "<Send><BitStart>208</BitStart><BitLength>80</BitLength></Send>"
    "<Recv><BitStart>288</BitStart><BitLength>320</BitLength></Recv></ProcessData></Slave>\n";
const EniCase kEniCases[] = {
    {"one servo in an LRW",
     "<EtherCATConfig><Config>\n%s<Cyclic><Frame><Cmd><Cmd>12</Cmd><Addr>#x00010000</Addr>"
     "<DataLength>50</DataLength><InputOffs>26</InputOffs><OutputOffs>26</OutputOffs></Cmd>"
     "</Frame></Cyclic></Config></EtherCATConfig>",
     1, 0, ""},
    {"not XML", "<EtherCATConfig>\n<Config>\n</EtherCATConfig>", 0, 3, "not well-formed XML"},
    {"not an ENI", "<EtherCATInfo/>", 0, 0, "not an ENI file"},
    {"a command without its address",
     "<EtherCATConfig><Config>\n<Cyclic><Frame>\n<Cmd><Cmd>12</Cmd><DataLength>50</DataLength>"
     "</Cmd></Frame></Cyclic></Config></EtherCATConfig>",
     0, 3, "<Cmd> has no <Addr>"},
    {"a length that is no number",
     "<EtherCATConfig><Config>\n<Cyclic><Frame><Cmd><Cmd>12</Cmd><Addr>1</Addr>\n"
     "<DataLength>fifty</DataLength></Cmd></Frame></Cyclic></Config></EtherCATConfig>",
     0, 3, "<DataLength> is not a number: 'fifty'"},
    {"a servo outside every cyclic command",
     "<EtherCATConfig><Config>\n%s<Cyclic><Frame><Cmd><Cmd>12</Cmd><Addr>#x00010000</Addr>"
     "<DataLength>8</DataLength><InputOffs>100</InputOffs><OutputOffs>100</OutputOffs></Cmd>"
     "</Frame></Cyclic></Config></EtherCATConfig>",
     0, 2, "slave 'X': its outputs (image bit 208) are in no cyclic LRD/LWR/LRW command"},
};

class EniFile : public ::testing::TestWithParam<EniCase> {};
TEST_P(EniFile, ParsesOrNamesTheLine) {
  const EniCase& c = GetParam();
  std::string xml = c.xml;
  if (auto at = xml.find("%s"); at != std::string::npos) xml.replace(at, 2, kServo);
  const EniResult r = parseEni(xml, "eni.xml");
  if (c.message[0] == '\0') {
    ASSERT_TRUE(r.ok()) << r.error->text();
    ASSERT_EQ(r.axes.size(), c.axes);
    EXPECT_EQ(r.axes[0].outputs, 0x00010000u);
    EXPECT_EQ(r.axes[0].inputs, 0x0001000Au);
    EXPECT_EQ(r.axes[0].station, 0x3E9);
    EXPECT_EQ(r.axes[0].name, "X");
    return;
  }
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error->line, c.line) << r.error->text();
  EXPECT_NE(r.error->text().find(c.message), std::string::npos) << r.error->text();
  EXPECT_EQ(r.error->text().rfind("eni.xml", 0), 0u);
}
INSTANTIATE_TEST_SUITE_P(Cases, EniFile, ::testing::ValuesIn(kEniCases), test::rowName<EniCase>);

}  // namespace
}  // namespace ncservo
