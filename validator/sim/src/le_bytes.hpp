// Little-endian bytes of the simulator's own buffers (ESC memory, datagrams it builds); captured
// bytes are read through ByteReader.
#pragma once

#include <cstddef>
#include <cstdint>

namespace ncservo::sim {

inline void putLe(std::uint8_t* out, std::uint64_t value, std::size_t size) {
  for (std::size_t i = 0; i < size; ++i) out[i] = static_cast<std::uint8_t>(value >> (8 * i));
}
inline std::uint64_t getLe(const std::uint8_t* in, std::size_t size) {
  std::uint64_t value = 0;
  for (std::size_t i = 0; i < size; ++i) value |= static_cast<std::uint64_t>(in[i]) << (8 * i);
  return value;
}

}  // namespace ncservo::sim
