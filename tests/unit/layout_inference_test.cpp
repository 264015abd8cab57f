// The layout inferred from the cyclic traffic (layout_inference.hpp, docs/protocol.md §9.4): for
// each process-image style and axis count, frames built byte by byte from a small model of NC and
// drives give back exactly the layout they were built with; idle or empty data is refused.
#include "ncservo/layout/layout_inference.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "frame_builder.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

using test::Bytes;
using test::Dg;
using test::FrameBuilder;

enum class Style {
  Soem,      // one LRW: every axis's outputs, then every axis's inputs
  EtherLab,  // one LRW: per slave its outputs then its inputs
  Mixed,     // servos among I/O terminals of other sizes at odd offsets, in one LRW
  TwinCat,   // an LWR of outputs and LRDs of inputs in separate areas and frames
  Fixed,     // FPWR to SM2 and FPRD of SM3 per station
};

enum class Motion { Commissioning, IdleEnabledNever, AllZero };

// One drive and its NC, cycle by cycle: enable by SE 0x1 -> 0x2, ServoEn 3 cycles later, then
// motion with varying message data; an ErrorClear handshake at cycle 200.
struct AxisModel {
  int axis;
  Motion motion;
  std::int64_t position = 0;
  std::int32_t speed = 0;

  Bytes rx(int cycle) const {
    std::uint32_t scw = 0x404;  // EMGON, Brake
    if (motion == Motion::AllZero) return test::rxPdo(0, 0);
    if (motion == Motion::Commissioning) {
      if (cycle >= 5 + axis) scw |= 0x1;
      if (cycle >= 12 + 3 * axis) scw = (scw & ~0x3u) | 0x2;
      if (cycle >= 200 && cycle < 206) scw |= 1u << 9;
    } else {
      scw |= 0x1;
    }
    return test::rxPdo(speed, scw, static_cast<std::int16_t>(axis));
  }
  Bytes tx(int cycle) const {
    if (motion == Motion::AllZero) return test::txPdo({});
    std::uint32_t ssw = 0x22;  // ServoRDY, N=0
    const bool enabled = motion == Motion::Commissioning && cycle >= 15 + 3 * axis;
    if (enabled) ssw = 0x83 | 0x40;
    if (cycle >= 202 && cycle < 208) ssw |= 0x10;
    const int code = cycle % 4;
    const float data = enabled ? 100.0f + static_cast<float>(cycle % 97) * 1.5f : 560.0f;
    return test::txPdo(test::TxValues(position, ssw, 0, code, data,
                                      {0.5f * static_cast<float>(axis), 1.25f, -3.0f, 42.0f}));
  }
  void step(int cycle) {
    if (motion != Motion::Commissioning || cycle < 15 + 3 * axis) return;
    speed = std::min(speed + 7, 3000);
    position += speed;
  }
};

struct Truth {
  std::vector<AxisConfig> axes;
};

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
    case Style::Soem: {
      Bytes data;
      for (const AxisModel& a : axes) data = test::concat({data, a.rx(cycle)});
      for (const AxisModel& a : axes) data = test::concat({data, a.tx(cycle)});
      for (std::uint16_t k = 0; k < n; ++k) logical(kImage + 10 * k, kImage + 10 * n + 40 * k);
      frames.push_back(FrameBuilder().add(Dg(ecat::kLrw, 1, kImage, data, 3 * n)).bytes());
      break;
    }
    case Style::EtherLab:
    case Style::Mixed: {
      const bool mixed = style == Style::Mixed;
      Bytes data;
      for (std::uint16_t k = 0; k < n; ++k) {
        if (mixed) data = test::concat({data, ioBytes(1 + k % 3, cycle, k)});
        const auto out = static_cast<std::uint32_t>(kImage + data.size());
        data = test::concat({data, axes[k].rx(cycle)});
        if (mixed) data = test::concat({data, ioBytes(2 + k % 5, cycle, 40 + k)});
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
InferenceResult infer(Style style, int axis_count, Motion motion, int cycles, Truth& truth) {
  std::vector<AxisModel> axes;
  for (int k = 0; k < axis_count; ++k) {
    axes.push_back(AxisModel{k, motion, 1000000 * (k + 1), 0});
  }
  LayoutInference inference;
  EcatFrame frame;
  for (int c = 0; c < cycles && !inference.settled(); ++c) {
    for (const Bytes& bytes : cycleFrames(style, axes, c, c == 0 ? &truth : nullptr)) {
      const ByteReader reader(bytes.data(), bytes.size());
      walkPacket(LinkType::Ethernet, reader, frame);
      inference.onFrame(frame, reader, true);
    }
  }
  return inference.decide();
}

struct Row {
  std::string name;
  Style style;
  int axes;
};

std::vector<Row> rows() {
  const std::pair<const char*, Style> styles[] = {{"soem", Style::Soem},
                                                  {"etherlab", Style::EtherLab},
                                                  {"mixed", Style::Mixed},
                                                  {"twincat", Style::TwinCat},
                                                  {"fprd_fpwr", Style::Fixed}};
  std::vector<Row> out;
  for (const auto& [name, style] : styles) {
    for (int n : {1, 3, 8})
      out.push_back(Row{std::string(name) + " " + std::to_string(n), style, n});
  }
  return out;
}

class InferredLayout : public ::testing::TestWithParam<Row> {};

TEST_P(InferredLayout, IsTheLayoutTheFramesWereBuiltWith) {
  Truth truth;
  const InferenceResult result =
      infer(GetParam().style, GetParam().axes, Motion::Commissioning, 4096, truth);
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
    EXPECT_GE(result.axes[k].evidence.confidence, 0.25) << "axis " << k;
    EXPECT_GE(result.axes[k].evidence.enabled_agree, 8u) << "axis " << k;
  }
}

INSTANTIATE_TEST_SUITE_P(Styles, InferredLayout, ::testing::ValuesIn(rows()), test::rowName<Row>);

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
    ::testing::Values(RefusalRow{"all zero soem", Style::Soem, Motion::AllZero, "ambiguous"},
                      RefusalRow{"all zero twincat", Style::TwinCat, Motion::AllZero, "ambiguous"},
                      RefusalRow{"idle never enabled", Style::Soem, Motion::IdleEnabledNever,
                                 "ambiguous"}),
    test::rowName<RefusalRow>);

TEST(InferredLayout, NoCyclicDataIsSaid) {
  LayoutInference inference;
  EXPECT_NE(inference.decide().refusal.find("no cyclic process data"), std::string::npos);
}

}  // namespace
}  // namespace ncservo
