// Whether a configured or ENI layout fits the capture (docs/layout.md#a-layout-that-does-not-fit):
// the data at each axis's addresses is held against the protocol's signature
// (ncservo/protocol/pdo_signature.hpp) in each of its first kEveryCycle copies, then in one copy
// in kSampleEvery. An axis whose data fails it in most of those is named in one warning, with
// what failed. Over the whole capture, since data two bytes off can look like a PDO while nothing
// moves; sampled, since the check of every copy cost as much as the rest of validate. Bounded: a
// few counters per axis.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/layout/decoder.hpp"
#include "ncservo/protocol/pdo_signature.hpp"

namespace ncservo {

class LayoutFit {
 public:
  // Each frame's placements, with the bytes they point into.
  void onFrame(const FrameDecode& decode, const ByteReader& bytes);
  // One line per axis whose data does not fit, in axis order.
  std::vector<std::string> warnings(const std::vector<AxisInfo>& axes) const;

 private:
  static constexpr std::uint64_t kEveryCycle = 256;
  static constexpr std::uint64_t kSampleEvery = 16;
  struct Tally {
    std::uint64_t seen = 0;    // copies of the PDO
    std::uint64_t cycles = 0;  // of those, checked
    std::uint64_t failed = 0;  // cycles failing any check
    std::array<std::uint64_t, kSignatureChecks> by_check{};
    std::optional<std::int32_t> undefined_code;  // the first message code outside the set
  };
  struct AxisTally {
    Tally tx, rx;
  };
  std::vector<AxisTally> axes_;
};

}  // namespace ncservo
