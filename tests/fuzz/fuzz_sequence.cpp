// libFuzzer target: a sequence of packets through one validator, so that the layout, the axis
// models, the cycle clock and the rules' timers carry state from frame to frame.
// Input: an option byte (fuzz_common.hpp), then records of
//   u16 little-endian length | u16 little-endian time step in 10 us units (0xFFFF = step back
//   by 1 ms) | `length` packet bytes (fewer if the input ends).
#include <cstddef>
#include <cstdint>

#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace ncservo;
  if (size < 1) return 0;
  const std::uint8_t options = data[0];
  const LinkType link = fuzz::linkFromOptions(options);
  Validator validator(fuzz::decoderFromOptions(options), fuzz::settingsFromOptions(options));
  static EcatFrame frame;
  std::size_t at = 1;
  std::uint64_t number = 0;
  std::int64_t time_ns = 1700000000LL * 1000000000LL;
  while (at + 4 <= size) {
    const std::size_t length = data[at] | (data[at + 1] << 8);
    const std::uint16_t step = static_cast<std::uint16_t>(data[at + 2] | (data[at + 3] << 8));
    at += 4;
    const std::size_t captured = length < size - at ? length : size - at;
    time_ns += step == 0xFFFF ? -1000000 : static_cast<std::int64_t>(step) * 10000;
    fuzz::feedFrame(validator, link, ++number, time_ns, data + at, captured, frame);
    at += captured;
  }
  fuzz::summarise(validator);
  return 0;
}
