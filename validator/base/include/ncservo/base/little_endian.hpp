// The one little-endian codec: loads and stores of bytes whose bounds the caller has checked
// (ByteReader's reads, the PDO codec, the simulator's own buffers). Captured bytes are read through
// ByteReader, which checks the bounds and returns no value on short data.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace ncservo {

// The `count` (at most 8) bytes at `p` as a little-endian number. On a little-endian host one load
// (a memcpy of a constant count once inlined).
inline std::uint64_t loadLe(const std::uint8_t* p, std::size_t count) {
  std::uint64_t value = 0;
  if constexpr (std::endian::native == std::endian::little) {
    std::memcpy(&value, p, count);
  } else {
    for (std::size_t i = 0; i < count; ++i) value |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  }
  return value;
}
template <std::size_t N>
std::uint64_t loadLe(const std::uint8_t* p) {
  static_assert(N <= 8, "at most 8 bytes");
  return loadLe(p, N);
}

// The low `count` (at most 8) bytes of `value` into `p`, least significant first.
inline void storeLe(std::uint8_t* p, std::uint64_t value, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) p[i] = static_cast<std::uint8_t>(value >> (8 * i));
}
template <std::size_t N>
void storeLe(std::uint8_t* p, std::uint64_t value) {
  static_assert(N <= 8, "at most 8 bytes");
  storeLe(p, value, N);
}

// The low `count` bytes of `value` appended to `out`, least significant first.
inline void appendLe(std::vector<std::uint8_t>& out, std::uint64_t value, std::size_t count) {
  const std::size_t at = out.size();
  out.resize(at + count);
  storeLe(out.data() + at, value, count);
}

}  // namespace ncservo
