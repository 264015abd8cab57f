// The ENI file as a layout source (eni.hpp, docs/protocol.md §9.2): the simulator's set-ups are the
// truth, and a broken file is named with its line.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "ncservo/layout/eni.hpp"
#include "ncservo/sim/simulator.hpp"
#include "row_name.hpp"
#include "simulated_setups.hpp"

namespace ncservo {
namespace {

using test::expectSameAxes;
using test::kSetUps;
using test::optionsFor;

class EniOfSetUp : public ::testing::TestWithParam<test::SetUp> {};

TEST_P(EniOfSetUp, GivesTheSimulatedLayout) {
  sim::Simulator simulator(optionsFor(GetParam()));
  const Result<EniLayout> eni = parseEni(simulator.eni(), "sim.xml");
  ASSERT_TRUE(eni.has_value()) << eni.error().text();
  EXPECT_EQ(eni->slaves, static_cast<std::size_t>(GetParam().axes + GetParam().io_slaves));
  expectSameAxes(eni->axes, simulator.layout());
}

INSTANTIATE_TEST_SUITE_P(SimulatedSetUps, EniOfSetUp, ::testing::ValuesIn(kSetUps),
                         test::rowName<test::SetUp>);

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
    {"one servo in the LRW of a second task",
     "<EtherCATConfig><Config>\n%s<Cyclic><CycleTime>10000</CycleTime><Frame><Cmd><Cmd>12</Cmd>"
     "<Addr>#x00020000</Addr><DataLength>4</DataLength><InputOffs>2074</InputOffs>"
     "<OutputOffs>2074</OutputOffs></Cmd></Frame></Cyclic><Cyclic><CycleTime>1000</CycleTime>"
     "<Frame><Cmd><Cmd>12</Cmd><Addr>#x00010000</Addr><DataLength>50</DataLength>"
     "<InputOffs>26</InputOffs><OutputOffs>26</OutputOffs></Cmd></Frame></Cyclic></Config>"
     "</EtherCATConfig>",
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
  const Result<EniLayout> r = parseEni(xml, "eni.xml");
  if (c.message[0] == '\0') {
    ASSERT_TRUE(r.has_value()) << r.error().text();
    ASSERT_EQ(r->axes.size(), c.axes);
    EXPECT_EQ(r->axes[0].outputs, 0x00010000u);
    EXPECT_EQ(r->axes[0].inputs, 0x0001000Au);
    EXPECT_EQ(r->axes[0].station, 0x3E9);
    EXPECT_EQ(r->axes[0].name, "X");
    return;
  }
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().line, c.line) << r.error().text();
  EXPECT_NE(r.error().text().find(c.message), std::string::npos) << r.error().text();
  EXPECT_EQ(r.error().text().rfind("eni.xml", 0), 0u);
}
INSTANTIATE_TEST_SUITE_P(Cases, EniFile, ::testing::ValuesIn(kEniCases), test::rowName<EniCase>);

// Each task's frames carry that task's <CycleTime> (docs/layout.md#eni-cycle-times).
TEST(EniTasks, EachFrameHasItsTasksCycleTime) {
  sim::SimOptions options;
  options.axes = 2;
  options.io_slaves = 2;
  options.io_task_us = 10000;
  options.duration_s = 1.0;
  ASSERT_EQ(test::statusText(sim::resolveOptions(options)), "");
  sim::Simulator simulator(options);
  const Result<EniLayout> eni = parseEni(simulator.eni(), "sim.xml");
  ASSERT_TRUE(eni.has_value()) << eni.error().text();
  ASSERT_EQ(eni->frames.size(), 2u);
  EXPECT_EQ(eni->frames[0].cycle_us, 1000u);
  EXPECT_EQ(eni->frames[1].cycle_us, 10000u);
  EXPECT_EQ(eni->axes.size(), 2u);
}

// ETG.2100's Slave/Mailbox/Send and Recv starts: SM0 and SM1 of every slave that has a station
// address and both; a slave without them has none (docs/drive-messages.md).
TEST(EniMailboxes, EachSlavesAreas) {
  const std::string xml =
      "<EtherCATConfig><Config>\n"
      "<Slave><Info><Name>A</Name><PhysAddr>1001</PhysAddr></Info>"
      "<Mailbox><Send><Start>#x1000</Start><Length>128</Length></Send>"
      "<Recv><Start>4224</Start><Length>128</Length></Recv></Mailbox></Slave>\n"
      "<Slave><Info><Name>B</Name><PhysAddr>1002</PhysAddr></Info></Slave>\n"
      "<Slave><Info><Name>C</Name></Info>"
      "<Mailbox><Send><Start>#x1800</Start></Send><Recv><Start>#x1C00</Start></Recv></Mailbox>"
      "</Slave>\n"
      "</Config></EtherCATConfig>";
  const Result<EniLayout> eni = parseEni(xml, "eni.xml");
  ASSERT_TRUE(eni.has_value()) << eni.error().text();
  EXPECT_EQ(eni->slaves, 3u);
  ASSERT_EQ(eni->mailboxes.size(), 1u);
  EXPECT_EQ(eni->mailboxes[0].station, 1001);
  EXPECT_EQ(eni->mailboxes[0].out_start, 0x1000);
  EXPECT_EQ(eni->mailboxes[0].in_start, 0x1080);
}

TEST(EniMailboxes, AStartThatIsNoNumberNamesItsLine) {
  const Result<EniLayout> eni = parseEni(
      "<EtherCATConfig><Config>\n<Slave><Info><PhysAddr>1001</PhysAddr></Info><Mailbox>\n"
      "<Send><Start>x</Start></Send><Recv><Start>1</Start></Recv></Mailbox></Slave>"
      "</Config></EtherCATConfig>",
      "eni.xml");
  ASSERT_FALSE(eni.has_value());
  EXPECT_EQ(eni.error().line, 3u);
  EXPECT_NE(eni.error().text().find("<Start> is not a number"), std::string::npos)
      << eni.error().text();
}

}  // namespace
}  // namespace ncservo
