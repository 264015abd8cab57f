// libFuzzer target: one captured packet through the walker, the layout decoder, the session and
// the rules, as the plugin sees a single frame. Input: an option byte (fuzz_common.hpp), then the
// packet's captured bytes.
#include <cstddef>
#include <cstdint>

#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace ncservo;
  if (size < 1) return 0;
  const std::uint8_t options = data[0];
  Validator validator(fuzz::decoderFromOptions(options), fuzz::settingsFromOptions(options));
  static EcatFrame frame;  // large: keep it off the stack
  // The same bytes twice: the second time as the copy back from the ring, and through the
  // decoder's cache of frame shapes.
  fuzz::feedFrame(validator, fuzz::linkFromOptions(options), 1, 0, data + 1, size - 1, frame);
  fuzz::feedFrame(validator, fuzz::linkFromOptions(options), 2, 1000000, data + 1, size - 1, frame);
  fuzz::summarise(validator);
  return 0;
}
