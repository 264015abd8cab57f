// Where something was seen in a capture.
#pragma once

#include <cstdint>

namespace ncservo {

// Wireshark's 1-based frame number and the capture time.
struct Stamp {
  std::uint64_t frame = 0;
  std::int64_t time_ns = 0;  // absolute capture time
};

}  // namespace ncservo
