// Shared by the libFuzzer targets: what an input's option byte selects, and one frame through the
// whole library path the CLI and the plugin take (walker, layout, session, model, rules).
#pragma once

#include <cstddef>
#include <cstdint>

#include "ncservo/config/config.hpp"
#include "ncservo/layout/decoder.hpp"
#include "ncservo/rules/rules.hpp"
#include "ncservo/rules/validator.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo::fuzz {

// Option byte: bits 0-1 link type, bit 2 no default layout, bit 3 a configured layout (two
// logical axes and one station axis), bit 4 Servo_Ready_Mode 1.
inline LinkType linkFromOptions(std::uint8_t options) {
  switch (options & 3) {
    case 1:
      return LinkType::LinuxSll;
    case 2:
      return LinkType::LinuxSll2;
    default:
      return LinkType::Ethernet;
  }
}

inline DecoderOptions decoderFromOptions(std::uint8_t options) {
  DecoderOptions decoder;
  decoder.default_layout = (options & 4) == 0;
  if ((options & 8) != 0) {
    AxisConfig x;
    x.name = "X";
    x.outputs = 0x00010000;
    x.inputs = 0x00010014;
    AxisConfig y;
    y.name = "Y";
    y.outputs = 0x0001000A;
    y.inputs = 0x0001003C;
    AxisConfig z;
    z.name = "Z";
    z.station = 0x03EA;
    z.sm_outputs = 0x1100;
    z.sm_inputs = 0x1180;
    decoder.axes = {x, y, z};
  }
  return decoder;
}

inline RuleSettings settingsFromOptions(std::uint8_t options) {
  RuleSettings settings;
  if ((options & 16) != 0) settings.servo_ready_mode = 1;
  return settings;
}

// Walks one captured packet and gives it to the validator; reads everything the view offers so
// that a bad offset shows up under the sanitizers.
inline std::size_t feedFrame(Validator& validator, LinkType link, std::uint64_t number,
                             std::int64_t time_ns, const std::uint8_t* data, std::size_t size,
                             EcatFrame& frame) {
  const ByteReader bytes(data, size);
  walkPacket(link, bytes, frame);
  if (frame.status == WalkStatus::NotEtherCat || frame.status == WalkStatus::NotDatagrams) return 0;
  const Observation& view = validator.onFrame(number, time_ns, frame, bytes);
  std::size_t seen = view.decode.axis_count + validator.findings().size();
  for (std::size_t i = 0; i < view.decode.axis_count; ++i) {
    PdoValues values;  // as the plugin reads them at the placements
    readFrameValues(view.decode.axes[i], bytes, values);
    seen += values.has_rx + values.has_tx + view.states[i].has_value();
  }
  for (const Finding& f : validator.findings()) seen += f.message.size();
  return seen;
}

// What a report reads at the end of a capture.
inline std::size_t summarise(const Validator& validator) {
  std::size_t seen = validator.decoder().noServoReason().size() + validator.cycles();
  const CycleTimeSummary cycle = validator.cycleTime();
  seen += cycle.median_us.has_value() + cycle.p99_us.has_value();
  for (std::size_t i = 0; i < validator.axisCount(); ++i) seen += validator.axis(i) != nullptr;
  return seen;
}

}  // namespace ncservo::fuzz
