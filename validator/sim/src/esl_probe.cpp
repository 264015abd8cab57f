#include "esl_probe.hpp"

#include <algorithm>
#include <memory>
#include <vector>

#include "ncservo/base/little_endian.hpp"
#include "ncservo/sim/models.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo::sim {
namespace {

static_assert(esl::kMagic.size() == esl::kFlagsOffset);
// The master's frames pass the probe on its port 0, the returned ones on port 1.
constexpr std::uint16_t kMasterPort = esl::kPortBits[0].mask, kReturnPort = esl::kPortBits[1].mask;
constexpr std::int64_t kPcStampStepNs = 1000;  // the PC's stamps never repeat or go back
constexpr std::uint64_t kNoiseSeedSalt = 0x45534CULL;

struct EslProbe {
  FrameSink sink;
  Rng noise;
  std::int64_t last_capture_ns = 0;
  std::vector<std::uint8_t> bytes;

  bool capture(const SimFrame& frame) {
    bytes.assign(esl::kMagic.begin(), esl::kMagic.end());
    bytes.resize(esl::kHeaderSize);
    const std::uint16_t flags =
        (frame.returned ? kReturnPort : kMasterPort) | esl::kFlagTimestampValid;
    storeLe(&bytes[esl::kFlagsOffset], flags, 2);
    storeLe(&bytes[esl::kTimestampOffset], static_cast<std::uint64_t>(frame.time_ns), 8);
    bytes.insert(bytes.end(), frame.data, frame.data + frame.size);
    const std::int64_t late = noise.between(0, kPcStampNoiseNs);
    const std::int64_t capture_ns =
        std::max(last_capture_ns + kPcStampStepNs, frame.time_ns + late);
    last_capture_ns = capture_ns;
    return sink(SimFrame{capture_ns, bytes.data(), bytes.size(), frame.returned});
  }
};

}  // namespace

FrameSink eslProbeSink(FrameSink sink, std::uint64_t seed) {
  auto probe =
      std::make_shared<EslProbe>(EslProbe{std::move(sink), Rng(seed ^ kNoiseSeedSalt), 0, {}});
  return [probe](const SimFrame& frame) { return probe->capture(frame); };
}

}  // namespace ncservo::sim
