// Bounds-checked little-endian reads over untrusted capture bytes (docs/hostile-input.md).
// Every read returns std::nullopt instead of reading past the end; nothing here throws.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>

#include "ncservo/base/little_endian.hpp"

namespace ncservo {

// A fixed-size record of the captured bytes whose bounds were checked once (a datagram header):
// its fields are read at offsets checked against its size at compile time. It points into the
// ByteReader's bytes (no copy: a copy to the stack and loads across it stall the CPU).
template <std::size_t N>
class ByteRecord {
 public:
  explicit ByteRecord(const std::uint8_t* data) : bytes_(data) {}

  template <std::size_t Offset>
  std::uint8_t u8() const {
    static_assert(Offset + 1 <= N, "field outside the record");
    return bytes_[Offset];
  }
  template <std::size_t Offset>
  std::uint16_t le16() const {
    return static_cast<std::uint16_t>(le<Offset, 2>());
  }
  template <std::size_t Offset>
  std::uint32_t le32() const {
    return static_cast<std::uint32_t>(le<Offset, 4>());
  }
  template <std::size_t Offset>
  std::uint64_t le64() const {
    return le<Offset, 8>();
  }

 private:
  template <std::size_t Offset, std::size_t Count>
  std::uint64_t le() const {
    static_assert(Offset + Count <= N, "field outside the record");
    return loadLe<Count>(bytes_ + Offset);
  }

  const std::uint8_t* bytes_;
};

class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  std::size_t size() const { return size_; }
  const std::uint8_t* data() const { return data_; }
  bool has(std::size_t offset, std::size_t count) const {
    return offset <= size_ && count <= size_ - offset;
  }

  // The N bytes at `offset` as a record, when all of them were captured.
  template <std::size_t N>
  std::optional<ByteRecord<N>> record(std::size_t offset) const {
    if (!has(offset, N)) return std::nullopt;
    return ByteRecord<N>(data_ + offset);
  }

  std::optional<std::uint8_t> u8(std::size_t offset) const {
    if (!has(offset, 1)) return std::nullopt;
    return data_[offset];
  }
  std::optional<std::uint16_t> le16(std::size_t offset) const {
    if (!has(offset, 2)) return std::nullopt;
    return static_cast<std::uint16_t>(loadLe<2>(data_ + offset));
  }
  std::optional<std::uint16_t> be16(std::size_t offset) const {
    if (!has(offset, 2)) return std::nullopt;
    return static_cast<std::uint16_t>((data_[offset] << 8) | data_[offset + 1]);
  }
  std::optional<std::uint32_t> le32(std::size_t offset) const {
    if (!has(offset, 4)) return std::nullopt;
    return static_cast<std::uint32_t>(loadLe<4>(data_ + offset));
  }
  std::optional<std::uint64_t> le64(std::size_t offset) const {
    if (!has(offset, 8)) return std::nullopt;
    return loadLe<8>(data_ + offset);
  }
  // The `count` (at most 8) bytes at `offset` as a little-endian number.
  std::optional<std::uint64_t> le(std::size_t offset, std::size_t count) const {
    if (count > 8 || !has(offset, count)) return std::nullopt;
    return loadLe(data_ + offset, count);
  }
  std::optional<float> leFloat(std::size_t offset) const {
    auto bits = le32(offset);
    if (!bits) return std::nullopt;
    float value;
    std::memcpy(&value, &*bits, sizeof value);
    return value;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
};

}  // namespace ncservo
