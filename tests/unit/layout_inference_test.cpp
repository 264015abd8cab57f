// The layout inferred from the cyclic traffic (layout_inference.hpp, docs/protocol.md §9.4): for
// each process-image style and axis count, frames built byte by byte from a small model of NC and
// drives give back exactly the layout they were built with; an idle capture decodes from the
// structure alone; neighbours that look alike (I/O terminals with changing inputs, CiA 402 drives
// with 10/40-byte PDOs) are never axes, alone or beside a servo whose message code is out of range
// now and then; a capture that begins inside a drive fault (enabled with no enable requested)
// decodes; empty data, and drives enabled all along that no control word asked to be, are refused.
#include "ncservo/layout/layout_inference.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/protocol/pdo_layout.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

using test::Bytes;
using test::Dg;
using test::FrameBuilder;

enum class Style {
  Soem,        // one LRW: every axis's outputs, then every axis's inputs
  EtherLab,    // one LRW: per slave its outputs then its inputs
  Mixed,       // servos among I/O terminals of other sizes at odd offsets, in one LRW
  Terminals,   // servos among I/O terminals whose inputs are counters and toggling bits
  Cia402,      // per slave outputs then inputs, a CiA 402 drive of 10/40-byte PDOs between servos
  Cia402Slow,  // the same with a drive whose torque changes every 50 cycles (the simulator's)
  SoemCia402,  // outputs then inputs, that drive after each of the first two servos
  // Per slave outputs then inputs, a CiA 402 drive of 12/28-byte PDOs before each servo (the
  // simulator's mixed image): its torque, read one word on as a control word, shows SE 0x2 until
  // it steps at cycle 200 (every 50 ms at 250 us).
  Cia402Torque,
  TwinCat,  // an LWR of outputs and LRDs of inputs in separate areas and frames
  Fixed,    // FPWR to SM2 and FPRD of SM3 per station
};

// EnabledNeverRequested: every drive shows ServoEn from the first cycle to the last while its
// NC never asks for it (SE 0x1 throughout): no control word explains it.
// Running: every axis enabled by SE 0x2 and moving from the first cycle to the last (a capture
// of a running machine: no handshake happens in it).
enum class Motion { Commissioning, IdleEnabledNever, AllZero, EnabledNeverRequested, Running };

// The capture begins inside a drive fault (simulate --start-in fault:FLT-001 with the NC's SE
// already back at 0x1): the drive stays enabled beside a following error (SEW 0x00080001) for
// this many cycles, is cleared by the ErrorClear handshake at cycle 200 and enabled again legally.
constexpr int kFaultStandsCycles = 200;
constexpr int kReEnableCycle = 212;

// One drive and its NC, cycle by cycle: enable by SE 0x1 -> 0x2, ServoEn 3 cycles later, then
// motion with varying message data; an ErrorClear handshake at cycle 200.
struct AxisModel {
  int axis;
  Motion motion;
  std::int64_t position = 0;
  std::int32_t speed = 0;
  bool bad_message = false;      // message code 12 (outside 0..9) in one cycle of 10: MSG-001
  bool starts_in_fault = false;  // enabled beside an error with no enable requested, at first

  int enableCycle() const { return starts_in_fault ? kReEnableCycle : 12 + 3 * axis; }
  bool enabled(int cycle) const {
    if (motion == Motion::EnabledNeverRequested || motion == Motion::Running) return true;
    if (motion != Motion::Commissioning) return false;
    return (starts_in_fault && cycle < kFaultStandsCycles) || cycle >= enableCycle() + 3;
  }

  Bytes rx(int cycle) const {
    std::uint32_t scw = 0x404;  // EMGON, Brake
    if (motion == Motion::AllZero) return test::rxPdo(0, 0);
    if (motion == Motion::Commissioning) {
      if (cycle >= 5 + axis || starts_in_fault) scw |= 0x1;
      if (cycle >= enableCycle()) scw = (scw & ~0x3u) | 0x2;
      if (cycle >= 200 && cycle < 206) scw |= 1u << 9;
    } else if (motion == Motion::Running) {
      scw |= 0x2;
    } else {
      scw |= 0x1;
    }
    return test::rxPdo(speed, scw, static_cast<std::int16_t>(axis));
  }
  Bytes tx(int cycle) const {
    if (motion == Motion::AllZero) return test::txPdo({});
    std::uint32_t ssw = 0x22;  // ServoRDY, N=0
    std::uint32_t sew = 0;
    const bool faulty = starts_in_fault && cycle < 204;
    if (enabled(cycle)) ssw = 0x83 | 0x40;
    if (faulty) {
      ssw &= ~0x2u;  // not ready with an error (Servo_Ready_Mode 0)
      sew = 0x00080001;
    }
    if (motion != Motion::Running && cycle >= 202 && cycle < 208) ssw |= 0x10;
    const int code = bad_message && cycle % 10 == 3 ? 12 : cycle % 4;
    const float data = enabled(cycle) ? 100.0f + static_cast<float>(cycle % 97) * 1.5f : 560.0f;
    return test::txPdo(test::TxValues(position, ssw, sew, code, data,
                                      {0.5f * static_cast<float>(axis), 1.25f, -3.0f, 42.0f}));
  }
  void step(int cycle) {
    if ((motion != Motion::Commissioning && motion != Motion::Running) || !enabled(cycle)) return;
    speed = std::min(speed + 7, 3000);
    position += speed;
  }
};

struct Truth {
  std::vector<AxisConfig> axes;
};

// An I/O terminal's inputs, changing every cycle the way real ones do: a 32-bit timestamp
// counting up, a 16-bit encoder counter, toggling digital inputs, an analog value with noise.
Bytes terminalBytes(std::size_t size, int cycle, int salt) {
  Bytes out;
  const auto c = static_cast<std::uint32_t>(cycle);
  test::putLe(out, 1000u * c + 17u * static_cast<std::uint32_t>(salt), 4);
  test::putLe(out, (c * 3u + static_cast<std::uint32_t>(salt)) & 0xFFFF, 2);
  out.push_back(static_cast<std::uint8_t>((c & 1) ? 0x05 : 0x0A));
  test::putLe(out, 0x3FF0u + ((c * 7u + static_cast<std::uint32_t>(salt)) % 13u), 2);
  out.resize(size, static_cast<std::uint8_t>(c >> 3));
  return out;
}

// A CiA 402 drive's PDOs of 10 and 40 bytes (0x6040 controlword, 0x607A target position, 0x60FF
// target velocity; 0x6041 statusword, 0x6064 position, 0x606C velocity, 0x6077 torque, 0x603F
// error code, 0x60FD digital inputs, 0x60F4 following error, manufacturer objects).
Bytes cia402Rx(int cycle) {
  Bytes out;
  test::putLe(out, 0x000F, 2);
  test::putLe(out, static_cast<std::uint32_t>(500 * cycle), 4);
  test::putLe(out, 500, 4);
  return out;
}
Bytes cia402Tx(int cycle) {
  Bytes out;
  test::putLe(out, 0x1237, 2);
  test::putLe(out, static_cast<std::uint32_t>(500 * cycle), 4);
  test::putLe(out, 500, 4);
  test::putLe(out, static_cast<std::uint32_t>(cycle % 50), 2);
  test::putLe(out, 0, 2);
  test::putLe(out, 0x00030000, 4);
  test::putLe(out, static_cast<std::uint32_t>(cycle % 3), 4);
  for (int i = 0; i < 4; ++i) test::putLe(out, 0x2000u + static_cast<std::uint32_t>(i), 4);
  test::putLe(out, 0, 2);
  return out;
}

// Another CiA 402 drive (the simulator's): position 100 counts a cycle, the torque changing every
// 50 cycles, the rest zero.
Bytes cia402SlowTx(int cycle) {
  Bytes out;
  test::putLe(out, 0x1237, 2);
  test::putLe(out, static_cast<std::uint32_t>(100 * cycle), 4);
  test::putLe(out, 1000, 4);
  test::putLe(out, static_cast<std::uint32_t>(cycle / 50 % 200), 2);
  out.resize(kTxPdoSize, 0);
  return out;
}

// The simulator's CiA 402 drive of the mixed image: outputs (controlword, target position,
// velocity, mode) and inputs (statusword, position, velocity, a torque stepping every 200 cycles
// from 10, zeros).
Bytes cia402TorquePdos(int cycle) {
  Bytes out;
  test::putLe(out, 0x000F, 2);
  test::putLe(out, static_cast<std::uint32_t>(100 * cycle), 4);
  test::putLe(out, 1000, 4);
  test::putLe(out, 8, 2);
  test::putLe(out, 0x1237, 2);
  test::putLe(out, static_cast<std::uint32_t>(25 * cycle), 4);
  test::putLe(out, 1000, 4);
  test::putLe(out, static_cast<std::uint32_t>(10 + cycle / 200), 2);
  out.resize(12 + 28, 0);
  return out;
}

Bytes cia402Pdos(Style style, int cycle) {
  return test::concat(
      {cia402Rx(cycle), style == Style::Cia402Slow ? cia402SlowTx(cycle) : cia402Tx(cycle)});
}

Bytes ioBytes(std::size_t size, int cycle, int salt) {
  Bytes out(size);
  for (std::size_t i = 0; i < size; ++i) {
    out[i] = static_cast<std::uint8_t>((cycle * (7 + salt) + static_cast<int>(i) * 31) & 0xFF);
  }
  return out;
}

// The returned frames of one cycle, and (once) the truth of where each axis sits.
std::vector<Bytes> cycleFrames(Style style, std::vector<AxisModel>& axes, int cycle, Truth* truth) {
  constexpr std::uint32_t kImage = 0x00010000;
  const auto n = static_cast<std::uint16_t>(axes.size());
  auto logical = [&](std::uint32_t out, std::uint32_t in) {
    if (truth == nullptr) return;
    AxisConfig a;
    a.name = "axis" + std::to_string(truth->axes.size());
    a.outputs = out;
    a.inputs = in;
    truth->axes.push_back(a);
  };
  std::vector<Bytes> frames;
  switch (style) {
    case Style::Soem:
    case Style::SoemCia402: {
      const std::uint16_t drives = style == Style::SoemCia402 ? std::min<std::uint16_t>(n, 2) : 0;
      Bytes outputs;
      Bytes inputs;
      std::vector<std::size_t> out_at;
      std::vector<std::size_t> in_at;
      for (std::uint16_t k = 0; k < n; ++k) {
        out_at.push_back(outputs.size());
        in_at.push_back(inputs.size());
        outputs = test::concat({outputs, axes[k].rx(cycle)});
        inputs = test::concat({inputs, axes[k].tx(cycle)});
        if (k < drives) {
          outputs = test::concat({outputs, cia402Rx(cycle)});
          inputs = test::concat({inputs, cia402SlowTx(cycle)});
        }
      }
      for (std::uint16_t k = 0; k < n; ++k) {
        logical(static_cast<std::uint32_t>(kImage + out_at[k]),
                static_cast<std::uint32_t>(kImage + outputs.size() + in_at[k]));
      }
      const auto wkc = static_cast<std::uint16_t>(3 * (n + drives));
      frames.push_back(FrameBuilder()
                           .add(Dg(ecat::kLrw, 1, kImage, test::concat({outputs, inputs}), wkc))
                           .bytes());
      break;
    }
    case Style::EtherLab:
    case Style::Mixed:
    case Style::Terminals:
    case Style::Cia402:
    case Style::Cia402Slow:
    case Style::Cia402Torque: {
      const bool mixed = style == Style::Mixed;
      const bool terminals = style == Style::Terminals;
      Bytes data;
      for (std::uint16_t k = 0; k < n; ++k) {
        if (mixed) data = test::concat({data, ioBytes(1 + k % 3, cycle, k)});
        if (terminals) data = test::concat({data, terminalBytes(3 + 5 * k % 11, cycle, k)});
        if (style == Style::Cia402 || style == Style::Cia402Slow) {
          data = test::concat({data, cia402Pdos(style, cycle)});
        }
        if (style == Style::Cia402Torque) data = test::concat({data, cia402TorquePdos(cycle)});
        const auto out = static_cast<std::uint32_t>(kImage + data.size());
        data = test::concat({data, axes[k].rx(cycle)});
        if (mixed) data = test::concat({data, ioBytes(2 + k % 5, cycle, 40 + k)});
        if (terminals) data = test::concat({data, terminalBytes(9 + 3 * k % 7, cycle, 40 + k)});
        logical(out, static_cast<std::uint32_t>(kImage + data.size()));
        data = test::concat({data, axes[k].tx(cycle)});
      }
      if (mixed) data = test::concat({data, ioBytes(6, cycle, 99)});
      frames.push_back(FrameBuilder().add(Dg(ecat::kLrw, 1, kImage, data, 3 * n + 2)).bytes());
      break;
    }
    case Style::TwinCat: {
      constexpr std::uint32_t kOutputs = 0x01000000;
      constexpr std::uint32_t kInputs = 0x02000000;
      Bytes outputs = ioBytes(3, cycle, 5);
      std::vector<Bytes> inputs(2, ioBytes(1, cycle, 6));
      std::vector<std::uint32_t> in_address{kInputs, kInputs + 0x800};
      for (std::uint16_t k = 0; k < n; ++k) {
        const std::size_t area = k * 2 < n ? 0 : 1;  // the inputs in two datagrams
        logical(static_cast<std::uint32_t>(kOutputs + outputs.size()),
                static_cast<std::uint32_t>(in_address[area] + inputs[area].size()));
        outputs = test::concat({outputs, axes[k].rx(cycle)});
        inputs[area] = test::concat({inputs[area], axes[k].tx(cycle)});
      }
      frames.push_back(FrameBuilder().add(Dg(ecat::kLwr, 1, kOutputs, outputs, n + 1)).bytes());
      FrameBuilder in;
      in.add(Dg(ecat::kLrd, 2, in_address[0], inputs[0], n));
      if (inputs[1].size() > 1) in.add(Dg(ecat::kLrd, 3, in_address[1], inputs[1], n));
      frames.push_back(in.bytes());
      break;
    }
    case Style::Fixed: {
      FrameBuilder frame;
      for (std::uint16_t k = 0; k < n; ++k) {
        const auto station = static_cast<std::uint16_t>(0x3E9 + k);
        frame.add(Dg(ecat::kFpwr, static_cast<std::uint8_t>(2 * k), test::physical(station, 0x1100),
                     axes[k].rx(cycle), 1));
        frame.add(Dg(ecat::kFprd, static_cast<std::uint8_t>(2 * k + 1),
                     test::physical(station, 0x1180), axes[k].tx(cycle), 1));
        if (truth != nullptr) {
          AxisConfig a;
          a.name = "axis" + std::to_string(k);
          a.station = station;
          a.sm_outputs = 0x1100;
          a.sm_inputs = 0x1180;
          truth->axes.push_back(a);
        }
      }
      frames.push_back(frame.bytes());
      break;
    }
  }
  for (AxisModel& a : axes) a.step(cycle);
  return frames;
}

// Runs `cycles` cycles through an inference; returns its decision and the truth.
// SOEM's copy of its one LRW (Style::Soem): this cycle's outputs, the previous cycle's inputs
// (docs/protocol.md §8), WKC 0.
Bytes soemMasterCopy(const Bytes& returned, const Bytes& previous, std::size_t axis_count) {
  Bytes master = returned;
  const std::size_t data = test::kChainOffset + ecat::kDatagramHeaderSize;
  const std::size_t inputs = data + kRxPdoSize * axis_count;
  const std::size_t wkc = data + (kRxPdoSize + kTxPdoSize) * axis_count;
  std::copy(previous.begin() + static_cast<std::ptrdiff_t>(inputs),
            previous.begin() + static_cast<std::ptrdiff_t>(wkc),
            master.begin() + static_cast<std::ptrdiff_t>(inputs));
  master[wkc] = 0;
  master[wkc + 1] = 0;
  return master;
}

// `echo`: SOEM's master copies are captured too, each before its returned copy.
// `faulty_axis`: that axis's message code is out of range in one cycle of 10.
// `fault_axis`: the capture begins inside that axis's drive fault.
InferenceResult infer(Style style, int axis_count, Motion motion, int cycles, Truth& truth,
                      bool echo = false, int faulty_axis = -1, int fault_axis = -1) {
  std::vector<AxisModel> axes;
  for (int k = 0; k < axis_count; ++k) {
    axes.push_back(AxisModel{k, motion, 1000000 * (k + 1), 0, k == faulty_axis, k == fault_axis});
  }
  LayoutInference inference;
  EcatFrame frame;
  std::vector<Bytes> previous;
  for (int c = 0; c < cycles && !inference.settled(); ++c) {
    const std::vector<Bytes> returned = cycleFrames(style, axes, c, c == 0 ? &truth : nullptr);
    for (std::size_t f = 0; f < returned.size(); ++f) {
      if (echo && f < previous.size()) {
        const Bytes master = soemMasterCopy(returned[f], previous[f], axes.size());
        const ByteReader reader(master.data(), master.size());
        walkPacket(LinkType::Ethernet, reader, frame);
        inference.onFrame(frame, reader, false);
      }
      const ByteReader reader(returned[f].data(), returned[f].size());
      walkPacket(LinkType::Ethernet, reader, frame);
      inference.onFrame(frame, reader, true);
    }
    previous = returned;
  }
  return inference.decide();
}

struct Row {
  std::string name;
  Style style;
  int axes;
  Motion motion = Motion::Commissioning;
  bool echo = false;     // SOEM's master copies captured too
  int faulty_axis = -1;  // this axis's message code out of range in one cycle of 10 (MSG-001)
  int fault_axis = -1;   // the capture begins inside this axis's drive fault
  int cycles = 4096;     // cycles captured
};

constexpr std::pair<const char*, Style> kStyles[] = {
    {"soem", Style::Soem},       {"etherlab", Style::EtherLab},
    {"mixed", Style::Mixed},     {"terminals", Style::Terminals},
    {"cia402", Style::Cia402},   {"cia402 slow", Style::Cia402Slow},
    {"twincat", Style::TwinCat}, {"fprd_fpwr", Style::Fixed}};

std::vector<Row> rows() {
  std::vector<Row> out;
  for (const auto& [name, style] : kStyles) {
    for (int n : {1, 3, 8}) {
      out.push_back(Row{std::string(name) + " " + std::to_string(n), style, n});
      out.push_back(Row{std::string(name) + " idle " + std::to_string(n), style, n,
                        Motion::IdleEnabledNever});
    }
  }
  out.push_back(Row{"soem echoed inputs 4", Style::Soem, 4, Motion::Commissioning, true});
  out.push_back(Row{"soem echoed inputs idle 4", Style::Soem, 4, Motion::IdleEnabledNever, true});
  // Beside the simulator's CiA 402 drive, whose TxPDO shifted by a byte or two passes the
  // signature for a while (idle, the control words there fit by chance: RefusedLayout).
  for (int n : {1, 3, 8}) {
    out.push_back(Row{"soem cia402 " + std::to_string(n), Style::SoemCia402, n});
  }
  // A servo faulting one plausibility check now and then (the rules report it) stays an axis,
  // beside CiA 402 drives of 10/40-byte PDOs too, enabled or idle.
  for (const auto& [name, style] :
       {std::pair{"soem", Style::Soem}, std::pair{"cia402", Style::Cia402},
        std::pair{"cia402 slow", Style::Cia402Slow}}) {
    for (const auto& [motion_name, motion] :
         {std::pair{"", Motion::Commissioning}, std::pair{" idle", Motion::IdleEnabledNever}}) {
      out.push_back(
          Row{std::string(name) + motion_name + " bad message code 4", style, 4, motion, false, 1});
    }
  }
  out.push_back(
      Row{"soem cia402 bad message code 4", Style::SoemCia402, 4, Motion::Commissioning, false, 1});
  // Beside a neighbour whose inputs read as a control word agree with every ServoEn for the first
  // 200 cycles: the two windows explain it equally until the torque steps, so the early decision
  // waits for the evidence that tells them apart.
  for (int n : {1, 3, 8}) {
    out.push_back(Row{"cia402 torque " + std::to_string(n), Style::Cia402Torque, n});
  }
  // A recording that begins inside a drive fault beside that neighbour: until the torque steps,
  // the neighbour's word explains the ServoEn the window began with and the control word cannot.
  for (const auto& [n, fault_axis] : {std::pair{1, 0}, std::pair{4, 2}}) {
    out.push_back(Row{"cia402 torque starts in a fault " + std::to_string(n), Style::Cia402Torque,
                      n, Motion::Commissioning, false, -1, fault_axis, 1500});
  }
  // A recording that begins inside a drive fault, the drive enabled beside its error with no
  // enable requested (SE-003 and FLT-001 for the rules), 1.5 s at 1 ms: its ServoEn came from an
  // enable before the capture and is no evidence against its control word (docs/layout.md).
  for (const auto& [name, style] : kStyles) {
    for (const auto& [n, fault_axis] : {std::pair{1, 0}, std::pair{4, 2}}) {
      out.push_back(Row{std::string(name) + " starts in a fault " + std::to_string(n), style, n,
                        Motion::Commissioning, false, -1, fault_axis, 1500});
    }
  }
  return out;
}

class InferredLayout : public ::testing::TestWithParam<Row> {};

// Every axis where it was built, nothing else: with the handshakes when they happen, from the
// structure alone (RxPDO k with TxPDO k in process-image order) when every axis stays idle.
TEST_P(InferredLayout, IsTheLayoutTheFramesWereBuiltWith) {
  Truth truth;
  const bool idle = GetParam().motion == Motion::IdleEnabledNever;
  const InferenceResult result =
      infer(GetParam().style, GetParam().axes, GetParam().motion, GetParam().cycles, truth,
            GetParam().echo, GetParam().faulty_axis, GetParam().fault_axis);
  ASSERT_TRUE(result.refusal.empty()) << result.refusal;
  ASSERT_EQ(result.axes.size(), truth.axes.size());
  for (std::size_t k = 0; k < truth.axes.size(); ++k) {
    const AxisConfig& got = result.axes[k].config;
    const AxisConfig& want = truth.axes[k];
    EXPECT_EQ(got.name, want.name);
    EXPECT_EQ(got.outputs, want.outputs) << "axis " << k;
    EXPECT_EQ(got.inputs, want.inputs) << "axis " << k;
    EXPECT_EQ(got.station, want.station) << "axis " << k;
    EXPECT_EQ(got.sm_outputs, want.sm_outputs) << "axis " << k;
    EXPECT_EQ(got.sm_inputs, want.sm_inputs) << "axis " << k;
    const AxisEvidence& e = result.axes[k].evidence;
    EXPECT_GE(e.confidence, 0.25) << "axis " << k;
    EXPECT_EQ(e.structure_only, idle) << "axis " << k;
    if (idle) {
      EXPECT_TRUE(e.paired_by_order) << "axis " << k;
      EXPECT_EQ(e.handshakes_seen, 0u) << "axis " << k;
      EXPECT_NE(describeEvidence(result.axes[k]).find("structure only, no handshake seen"),
                std::string::npos);
    } else {
      EXPECT_GE(e.enabled_agree, 8u) << "axis " << k;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Styles, InferredLayout, ::testing::ValuesIn(rows()), test::rowName<Row>);

// When the learning window ends: early, once every axis is explained by a handshake it saw happen;
// at its full length when the only agreement is over drives already enabled when it began, which
// a word that merely reads SE 0x2 explains as well (docs/layout.md).
struct WindowLengthRow {
  std::string name;
  Style style;
  Motion motion;
  bool full_length;
};

class LearningWindowLength : public ::testing::TestWithParam<WindowLengthRow> {};

TEST_P(LearningWindowLength, EndsEarlyOnlyOnHandshakesSeen) {
  Truth truth;
  const InferenceResult result = infer(GetParam().style, 4, GetParam().motion, 4096, truth);
  ASSERT_TRUE(result.refusal.empty()) << result.refusal;
  ASSERT_EQ(result.axes.size(), truth.axes.size());
  for (std::size_t k = 0; k < truth.axes.size(); ++k) {
    EXPECT_EQ(result.axes[k].config.outputs, truth.axes[k].outputs) << "axis " << k;
    EXPECT_EQ(result.axes[k].config.inputs, truth.axes[k].inputs) << "axis " << k;
  }
  if (GetParam().full_length) {
    EXPECT_EQ(result.cycles, 4096u);
  } else {
    EXPECT_LT(result.cycles, 4096u);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Cases, LearningWindowLength,
    ::testing::Values(
        WindowLengthRow{"soem commissioning", Style::Soem, Motion::Commissioning, false},
        WindowLengthRow{"soem running", Style::Soem, Motion::Running, true},
        WindowLengthRow{"etherlab running", Style::EtherLab, Motion::Running, true},
        WindowLengthRow{"twincat running", Style::TwinCat, Motion::Running, true},
        WindowLengthRow{"cia402 torque running", Style::Cia402Torque, Motion::Running, true}),
    test::rowName<WindowLengthRow>);

struct RefusalRow {
  std::string name;
  Style style;
  Motion motion;
  const char* says;
};

class RefusedLayout : public ::testing::TestWithParam<RefusalRow> {};

TEST_P(RefusedLayout, DecodesNothingAndSaysWhy) {
  Truth truth;
  const InferenceResult result = infer(GetParam().style, 4, GetParam().motion, 600, truth);
  EXPECT_TRUE(result.axes.empty());
  EXPECT_NE(result.refusal.find(GetParam().says), std::string::npos) << result.refusal;
  EXPECT_NE(result.refusal.find("[[axis]]"), std::string::npos) << result.refusal;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, RefusedLayout,
    ::testing::Values(
        RefusalRow{"all zero soem", Style::Soem, Motion::AllZero, "ambiguous"},
        RefusalRow{"all zero twincat", Style::TwinCat, Motion::AllZero, "ambiguous"},
        // Idle, a control word shifted into the CiA 402 drive's RxPDO fits too.
        RefusalRow{"idle soem cia402", Style::SoemCia402, Motion::IdleEnabledNever, "could be at"},
        // Drives enabled all along that no control word ever asked to be: the
        // enable before the window explains no ServoEn for a whole window.
        RefusalRow{"enabled never requested soem", Style::Soem, Motion::EnabledNeverRequested,
                   "has no control word that fits"},
        RefusalRow{"enabled never requested etherlab", Style::EtherLab,
                   Motion::EnabledNeverRequested, "no control word explains their ServoEn"}),
    test::rowName<RefusalRow>);

// An idle axis whose RxPDO is followed by two zero bytes: the window one byte later keeps a
// non-zero, steady SCW (EMGON only) as well, so the structure cannot tell which is right.
TEST(InferredLayout, ASlotThatFitsByChanceIsRefusedAndSaid) {
  LayoutInference inference;
  EcatFrame frame;
  for (int c = 0; c < 600; ++c) {
    const Bytes tx = test::txPdo(test::TxValues(1000000, 0x22, 0, c % 4, 560.0f, {1, 2, 3, 4}));
    const Bytes data = test::concat({test::rxPdo(0, 0x405), Bytes(2, 0), tx});
    const Bytes bytes = FrameBuilder().add(Dg(ecat::kLrw, 1, 0x00010000, data, 3)).bytes();
    const ByteReader reader(bytes.data(), bytes.size());
    walkPacket(LinkType::Ethernet, reader, frame);
    inference.onFrame(frame, reader, true);
  }
  const InferenceResult result = inference.decide();
  EXPECT_TRUE(result.axes.empty());
  EXPECT_NE(result.refusal.find("1 slot refused: the RxPDO of the status word at LRW "
                                "0x00010000+52 offset 12 could be at LRW 0x00010000+52 offset 0 "
                                "or LRW 0x00010000+52 offset 1"),
            std::string::npos)
      << result.refusal;
}

// CiA 402 drives of 10/40-byte PDOs and nothing else on the bus, in one LRW (per slave its outputs
// then its inputs): never an axis, however long the window.
struct Cia402Row {
  std::string name;
  Style style;
  int drives;
};

class Cia402Alone : public ::testing::TestWithParam<Cia402Row> {};

TEST_P(Cia402Alone, IsNeverAnAxis) {
  LayoutInference inference;
  EcatFrame frame;
  for (int c = 0; c < 4096 && !inference.settled(); ++c) {
    Bytes data;
    for (int d = 0; d < GetParam().drives; ++d)
      data = test::concat({data, cia402Pdos(GetParam().style, c)});
    const auto wkc = static_cast<std::uint16_t>(3 * GetParam().drives);
    const Bytes bytes = FrameBuilder().add(Dg(ecat::kLrw, 1, 0x00010000, data, wkc)).bytes();
    const ByteReader reader(bytes.data(), bytes.size());
    walkPacket(LinkType::Ethernet, reader, frame);
    inference.onFrame(frame, reader, true);
  }
  const InferenceResult result = inference.decide();
  EXPECT_EQ(result.axes.size(), 0u)
      << (result.axes.empty() ? std::string() : describeEvidence(result.axes.front()));
  EXPECT_FALSE(result.refusal.empty());
}

INSTANTIATE_TEST_SUITE_P(Drives, Cia402Alone,
                         ::testing::Values(Cia402Row{"one", Style::Cia402, 1},
                                           Cia402Row{"three", Style::Cia402, 3},
                                           Cia402Row{"one slow", Style::Cia402Slow, 1},
                                           Cia402Row{"three slow", Style::Cia402Slow, 3}),
                         test::rowName<Cia402Row>);

// A capture of SOEM's master copies only, inputs not echoed (gen_capture.py --copies master):
// the outputs alone show the outputs-first layout, each axis's TxPDO after every RxPDO
// (docs/layout.md, "Without inputs").
Bytes masterCopyWithoutInputs(const Bytes& returned, std::size_t axis_count) {
  Bytes master = returned;
  const std::size_t data = test::kChainOffset + ecat::kDatagramHeaderSize;
  const std::size_t inputs = data + kRxPdoSize * axis_count;
  const std::size_t wkc_end = data + (kRxPdoSize + kTxPdoSize) * axis_count + 2;
  std::fill(master.begin() + static_cast<std::ptrdiff_t>(inputs),
            master.begin() + static_cast<std::ptrdiff_t>(wkc_end), 0);
  return master;
}

class MasterCopiesOnly : public ::testing::TestWithParam<int> {};

TEST_P(MasterCopiesOnly, PlaceTheInputsAfterEveryOutput) {
  std::vector<AxisModel> axes;
  for (int k = 0; k < GetParam(); ++k) axes.push_back(AxisModel{k, Motion::Commissioning});
  LayoutInference inference;
  EcatFrame frame;
  Truth truth;
  for (int c = 0; c < 600 && !inference.settled(); ++c) {
    const Bytes returned = cycleFrames(Style::Soem, axes, c, c == 0 ? &truth : nullptr).front();
    const Bytes master = masterCopyWithoutInputs(returned, axes.size());
    const ByteReader reader(master.data(), master.size());
    walkPacket(LinkType::Ethernet, reader, frame);
    inference.onFrame(frame, reader, false);
  }
  const InferenceResult result = inference.decide();
  ASSERT_TRUE(result.refusal.empty()) << result.refusal;
  ASSERT_EQ(result.axes.size(), truth.axes.size());
  for (std::size_t k = 0; k < truth.axes.size(); ++k) {
    EXPECT_EQ(result.axes[k].config.outputs, truth.axes[k].outputs) << "axis " << k;
    EXPECT_EQ(result.axes[k].config.inputs, truth.axes[k].inputs) << "axis " << k;
    EXPECT_TRUE(result.axes[k].evidence.outputs_only) << "axis " << k;
    EXPECT_DOUBLE_EQ(result.axes[k].evidence.confidence, 0.5) << "axis " << k;
  }
}

INSTANTIATE_TEST_SUITE_P(Axes, MasterCopiesOnly, ::testing::Values(2, 4, 8));

// A TxPDO with a rival window 32 bytes on that passes every check as well: the 8 bytes they share
// are the first window's last two extra data words and the second's ActPos (a position whose
// bits are also a plausible float). Nothing tells which is the drive's: the confidence, how far
// the next best overlapping candidate is behind, is 0 and the placement is refused
// (docs/layout.md).
TEST(InferredLayout, ARivalOverlappingTheTxPdosEndIsRefused) {
  constexpr std::size_t kRivalAfter = 32;
  constexpr std::uint32_t kFloat512 = 0x44000000;  // 512.0f
  AxisModel axis{0, Motion::Commissioning};
  LayoutInference inference;
  EcatFrame frame;
  for (int c = 0; c < 4096 && !inference.settled(); ++c) {
    Bytes tx = axis.tx(c);
    Bytes position;
    test::putLe(position, kFloat512 + 50u * static_cast<std::uint32_t>(c), 8);
    std::copy(position.begin(), position.end(), tx.begin());
    std::copy(position.begin(), position.end(), tx.begin() + kRivalAfter);
    const Bytes rival_rest(tx.begin() + static_cast<std::ptrdiff_t>(kTxPdoSize - kRivalAfter),
                           tx.end());
    const Bytes data = test::concat({axis.rx(c), tx, rival_rest});
    axis.step(c);
    const Bytes bytes = FrameBuilder().add(Dg(ecat::kLrw, 1, 0x00010000, data, 3)).bytes();
    const ByteReader reader(bytes.data(), bytes.size());
    walkPacket(LinkType::Ethernet, reader, frame);
    inference.onFrame(frame, reader, true);
  }
  const InferenceResult result = inference.decide();
  EXPECT_TRUE(result.axes.empty()) << describeEvidence(result.axes.front());
  EXPECT_NE(result.refusal.find("the layout is ambiguous: more than one placement fits axis0 "
                                "(RxPDO LRW 0x00010000+82 offset 0, TxPDO LRW 0x00010000+82 "
                                "offset 10, confidence 0 %)"),
            std::string::npos)
      << result.refusal;
}

TEST(InferredLayout, NoCyclicDataIsSaid) {
  LayoutInference inference;
  EXPECT_NE(inference.decide().refusal.find("no cyclic process data"), std::string::npos);
}

}  // namespace
}  // namespace ncservo
