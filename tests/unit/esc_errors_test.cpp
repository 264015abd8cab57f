// The ESCs' error counters (esc_errors.hpp, PROTOCOL.md §11): deltas per slave and port between
// reads, a first read as baseline, clears and wraps, a BRD's sum, and which link the counters
// name (the first slave in ring order with RX errors it did not get forwarded). The register
// bytes are written out from PROTOCOL.md §11.
#include "ncservo/model/esc_errors.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "frame_builder.hpp"

namespace ncservo {
namespace {

using test::Bytes;
using test::Dg;
using test::FrameBuilder;
using test::physical;

std::uint16_t apAdp(std::uint16_t position) {
  return static_cast<std::uint16_t>((0x10000u - position) & 0xFFFFu);
}

// 0x0300-0x0313: per port n invalid frames (0x0300 + 2n) and RX errors (0x0301 + 2n), forwarded
// (0x0308 + n), processing unit 0x030C, PDI 0x030D, lost links 0x0310 + n.
struct Regs {
  std::array<std::uint8_t, 4> invalid{}, rx{}, forwarded{}, lost{};
  std::uint8_t processing = 0, pdi = 0;
  Bytes bytes() const {
    Bytes out(20, 0);
    for (int n = 0; n < 4; ++n) {
      out[2 * n] = invalid[n];
      out[2 * n + 1] = rx[n];
      out[8 + n] = forwarded[n];
      out[16 + n] = lost[n];
    }
    out[12] = processing;
    out[13] = pdi;
    return out;
  }
};

struct Harness {
  EscErrorTracker tracker;
  FrameAddressing addressing;
  std::vector<BusEvent> events;
  std::uint64_t frame = 0;

  void feed(const std::vector<Dg>& dgs, bool returned) {
    FrameBuilder builder;
    for (const Dg& dg : dgs) builder.add(dg);
    const Bytes bytes = builder.bytes();
    const test::Walked w = test::walk(bytes);
    addressing.beginFrame(*w.frame, returned, true);
    ++frame;
    tracker.onFrame(*w.frame, w.reader(), addressing, Stamp{frame, std::int64_t(frame)}, events);
  }
  // Station 1001 + p at ring position p, as a start-up assigns them.
  void assign(std::uint16_t slaves) {
    for (std::uint16_t p = 0; p < slaves; ++p) {
      Bytes station;
      test::putLe(station, 1001 + p, 2);
      feed({Dg{ecat::kApwr, 0, physical(apAdp(p), ecat::kRegStationAddress), station, 0}}, false);
    }
  }
  // One frame reading every slave's counters (FPRD per slave), master copy then returned copy.
  void poll(const std::vector<Regs>& regs) {
    std::vector<Dg> master, back;
    for (std::size_t p = 0; p < regs.size(); ++p) {
      const auto station = static_cast<std::uint16_t>(1001 + p);
      master.push_back(Dg{ecat::kFprd, 0, physical(station, 0x0300), Bytes(20, 0), 0});
      back.push_back(Dg{ecat::kFprd, 0, physical(station, 0x0300), regs[p].bytes(), 1});
    }
    feed(master, false);
    feed(back, true);
  }
};

TEST(EscErrors, FirstReadIsTheBaseline) {
  Harness h;
  h.assign(3);
  Regs dirty;
  dirty.rx[0] = 40;  // counted before the capture
  h.poll({Regs{}, dirty, Regs{}});
  EXPECT_TRUE(h.tracker.deltas().empty());
  EXPECT_TRUE(h.events.empty());
}

TEST(EscErrors, NamesTheLinkIntoPortZero) {
  Harness h;
  h.assign(4);
  h.poll({Regs{}, Regs{}, Regs{}, Regs{}});
  // The cable between 1002 (port 1) and 1003 (port 0) corrupts 3 frames: 1003 counts them as
  // invalid at port 0; 1004 gets them forwarded.
  Regs third, fourth;
  third.invalid[0] = 3;
  fourth.invalid[0] = 0;
  fourth.forwarded[0] = 3;
  h.poll({Regs{}, Regs{}, third, fourth});
  ASSERT_EQ(h.tracker.linkFaults().size(), 1u);
  const LinkFault& f = h.tracker.linkFaults()[0];
  ASSERT_TRUE(f.upstream);
  EXPECT_EQ(f.upstream->station, 1002);
  EXPECT_EQ(f.upstream_port, 1);
  EXPECT_EQ(f.downstream.station, 1003);
  EXPECT_EQ(f.downstream_port, 0);
  EXPECT_EQ(f.errors, 3u);
  EXPECT_EQ(linkFaultText(f), "the link between station 0x03EA port 1 and station 0x03EB port 0");
  // The deltas: 1003 invalid port 0 by 3, 1004 forwarded port 0 by 3.
  ASSERT_EQ(h.tracker.deltas().size(), 2u);
  EXPECT_EQ(h.tracker.deltas()[0].slave.station, 1003);
  EXPECT_EQ(h.tracker.deltas()[0].counter, diag::EscCounter::Invalid);
  EXPECT_EQ(h.tracker.deltas()[1].counter, diag::EscCounter::Forwarded);
  ASSERT_EQ(h.events.size(), 1u);
  const auto& e = std::get<LinkErrorEvent>(h.events[0].data);
  EXPECT_FALSE(e.lost);
  EXPECT_EQ(e.link.reported.station, 1003);
  EXPECT_EQ(linkFaultText(e.link), linkFaultText(f));
}

// PROTOCOL.md §11: each port's errors that no upstream slave forwarded are its own link's, so two
// bad cables read in one frame are two faults, in processing order.
TEST(EscErrors, TwoBadLinksInOneReadAreTwoFaults) {
  Harness h;
  h.assign(4);
  h.poll({Regs{}, Regs{}, Regs{}, Regs{}});
  Regs second, third, fourth;
  second.rx[0] = 2;         // the cable 1001 -> 1002
  third.forwarded[0] = 2;   // ... forwarded by 1003, which counts them as invalid too,
  third.invalid[0] = 7;     // with 5 of its own: the cable 1002 -> 1003
  fourth.forwarded[0] = 7;  // 1004 sees both, forwarded
  h.poll({Regs{}, second, third, fourth});
  ASSERT_EQ(h.tracker.linkFaults().size(), 2u);
  EXPECT_EQ(linkFaultText(h.tracker.linkFaults()[0]),
            "the link between station 0x03E9 port 1 and station 0x03EA port 0");
  EXPECT_EQ(h.tracker.linkFaults()[0].errors, 2u);
  EXPECT_EQ(linkFaultText(h.tracker.linkFaults()[1]),
            "the link between station 0x03EA port 1 and station 0x03EB port 0");
  EXPECT_EQ(h.tracker.linkFaults()[1].errors, 5u);
  EXPECT_EQ(h.events.size(), 2u);
}

TEST(EscErrors, ForwardedErrorsAloneNameNoLink) {
  Harness h;
  h.assign(2);
  h.poll({Regs{}, Regs{}});
  Regs second;
  second.rx[0] = 2;
  second.forwarded[0] = 2;
  h.poll({Regs{}, second});
  EXPECT_TRUE(h.tracker.linkFaults().empty());
}

TEST(EscErrors, PortOneNamesTheCableToTheNextSlave) {
  Harness h;
  h.assign(3);
  h.poll({Regs{}, Regs{}, Regs{}});
  Regs first;
  first.rx[1] = 5;
  h.poll({first, Regs{}, Regs{}});
  ASSERT_EQ(h.tracker.linkFaults().size(), 1u);
  EXPECT_EQ(linkFaultText(h.tracker.linkFaults()[0]),
            "the link between station 0x03E9 port 1 and station 0x03EA port 0");
}

TEST(EscErrors, ClearedOrWrappedCounters) {
  Harness h;
  h.assign(1);
  Regs r;
  r.lost[1] = 200;
  h.poll({r});
  r.lost[1] = 2;  // lower than before: cleared, then rose by 2
  h.poll({r});
  ASSERT_EQ(h.tracker.deltas().size(), 1u);
  EXPECT_EQ(h.tracker.deltas()[0].counter, diag::EscCounter::LostLink);
  EXPECT_EQ(h.tracker.deltas()[0].port, 1);
  EXPECT_EQ(h.tracker.deltas()[0].delta, 2u);
  ASSERT_EQ(h.events.size(), 1u);
  EXPECT_TRUE(std::get<LinkErrorEvent>(h.events[0].data).lost);
  EXPECT_EQ(std::get<LinkErrorEvent>(h.events[0].data).link.reported_port, 1);
  // A write clears them: the next read's 4 is a rise of 4 from 0, not of 2.
  h.feed({Dg{ecat::kFpwr, 0, physical(1001, 0x0310), Bytes(4, 0), 0}}, false);
  r.lost[1] = 4;
  h.poll({r});
  ASSERT_EQ(h.tracker.deltas().size(), 2u);
  EXPECT_EQ(h.tracker.deltas()[1].delta, 4u);
}

TEST(EscErrors, BroadcastIsOnlyASum) {
  Harness h;
  Regs r;
  h.feed({Dg{ecat::kBrd, 0, physical(0, 0x0300), r.bytes(), 3}}, true);
  r.rx[0] = 7;
  h.feed({Dg{ecat::kBrd, 0, physical(0, 0x0300), r.bytes(), 3}}, true);
  ASSERT_EQ(h.tracker.deltas().size(), 1u);
  EXPECT_TRUE(h.tracker.deltas()[0].broadcast);
  EXPECT_EQ(h.tracker.deltas()[0].delta, 7u);
  EXPECT_TRUE(h.tracker.linkFaults().empty());  // names no slave
  EXPECT_TRUE(h.events.empty());
}

TEST(EscErrors, ProcessingAndPdiCounted) {
  Harness h;
  h.assign(1);
  h.poll({Regs{}});
  Regs r;
  r.processing = 1;
  r.pdi = 2;
  h.poll({r});
  ASSERT_EQ(h.tracker.deltas().size(), 2u);
  EXPECT_EQ(h.tracker.deltas()[0].counter, diag::EscCounter::Processing);
  EXPECT_EQ(h.tracker.deltas()[1].counter, diag::EscCounter::Pdi);
  EXPECT_TRUE(h.tracker.linkFaults().empty());
}

// 0x0442 (process data) and 0x0443 (PDI): how often the slave's watchdogs expired, rises between
// reads as the error counters' (the first read the baseline), cleared by a write; a read that
// also covers 0x0440 (the status) takes them from their place in it.
TEST(EscErrors, WatchdogExpiriesCounted) {
  struct Row {
    const char* name;
    std::uint16_t ado;     // where the read starts
    std::size_t counters;  // where 0x0442 lies in its data
  };
  for (const Row& row : {Row{"0x0442", 0x0442, 0}, Row{"from 0x0440", 0x0440, 2}}) {
    Harness h;
    h.assign(1);
    auto read = [&](std::uint8_t sm, std::uint8_t pdi) {
      Bytes data(row.counters + 2, 0);
      data[row.counters] = sm;
      data[row.counters + 1] = pdi;
      h.feed({Dg{ecat::kFprd, 0, physical(1001, row.ado), Bytes(data.size(), 0), 0}}, false);
      h.feed({Dg{ecat::kFprd, 0, physical(1001, row.ado), data, 1}}, true);
    };
    read(4, 0);  // the baseline
    EXPECT_TRUE(h.tracker.deltas().empty()) << row.name;
    read(6, 1);
    ASSERT_EQ(h.tracker.deltas().size(), 2u) << row.name;
    EXPECT_EQ(h.tracker.deltas()[0].counter, diag::EscCounter::SmWatchdog) << row.name;
    EXPECT_EQ(h.tracker.deltas()[0].delta, 2u) << row.name;
    EXPECT_EQ(h.tracker.deltas()[1].counter, diag::EscCounter::PdiWatchdog) << row.name;
    EXPECT_EQ(h.tracker.deltas()[1].delta, 1u) << row.name;
    EXPECT_EQ(std::string(diag::escCounterName(diag::EscCounter::SmWatchdog)), "sm-watchdog");
    // a write clears them: the next read's 1 is one expiry
    h.feed({Dg{ecat::kFpwr, 0, physical(1001, 0x0442), Bytes(2, 0), 0}}, false);
    read(1, 1);
    ASSERT_EQ(h.tracker.deltas().size(), 4u) << row.name;
    EXPECT_EQ(h.tracker.deltas()[2].delta, 1u) << row.name;
    EXPECT_TRUE(h.tracker.linkFaults().empty()) << row.name;
  }
}

}  // namespace
}  // namespace ncservo
