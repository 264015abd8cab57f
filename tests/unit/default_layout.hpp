// Test helper: the outputs-first layout of docs/protocol.md §9.4 (an LRW of n×10 output bytes then
// n×40 input bytes, or an LWR of n×10 and an LRD of n×40), as the LayoutWindow hands it to the
// decoder once the inference has decided it. Tests that drive a Decoder or Validator directly
// with such frames give it explicitly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "ncservo/layout/decoder.hpp"
#include "ncservo/protocol/pdo_layout.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo::test {

inline void appendDefaultAxes(DecoderOptions& options, std::size_t n, std::uint32_t outputs,
                              std::uint32_t inputs) {
  for (std::size_t k = 0; k < n; ++k) {
    AxisConfig axis;
    axis.name = "axis" + std::to_string(options.axes.size());
    axis.outputs = static_cast<std::uint32_t>(outputs + kRxPdoSize * k);
    axis.inputs = static_cast<std::uint32_t>(inputs + kTxPdoSize * k);
    options.axes.push_back(axis);
  }
  options.explicit_source = LayoutSource::Inferred;
}

// n axes in an outputs-first LRW at `address`.
inline DecoderOptions inferredDefault(std::size_t n, std::uint32_t address = 0x00010000) {
  DecoderOptions options;
  appendDefaultAxes(options, n, address, static_cast<std::uint32_t>(address + kRxPdoSize * n));
  return options;
}

// The outputs-first datagrams of one frame, axes numbered in datagram order; `fallback` when
// the frame has none.
inline DecoderOptions defaultLayoutOf(const EcatFrame& frame, DecoderOptions fallback = {}) {
  DecoderOptions options;
  for (std::size_t d = 0; d < frame.count; ++d) {
    const Datagram& dg = frame.datagrams[d];
    if (dg.command == ecat::kLrw && dg.length > 0 && dg.length % (kRxPdoSize + kTxPdoSize) == 0) {
      const std::size_t n = dg.length / (kRxPdoSize + kTxPdoSize);
      appendDefaultAxes(options, n, dg.address,
                        static_cast<std::uint32_t>(dg.address + kRxPdoSize * n));
    } else if (dg.command == ecat::kLwr && dg.length > 0 && dg.length % kRxPdoSize == 0) {
      const std::size_t n = dg.length / kRxPdoSize;
      for (std::size_t j = 0; j < frame.count; ++j) {
        if (frame.datagrams[j].command == ecat::kLrd &&
            frame.datagrams[j].length == n * kTxPdoSize) {
          appendDefaultAxes(options, n, dg.address, frame.datagrams[j].address);
          break;
        }
      }
    }
  }
  return options.axes.empty() ? fallback : options;
}

}  // namespace ncservo::test
