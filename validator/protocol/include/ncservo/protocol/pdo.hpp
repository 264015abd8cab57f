// Reading one axis's PDOs out of captured bytes, and the values of the field table's rows.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/base/little_endian.hpp"
#include "ncservo/protocol/fields.hpp"
#include "ncservo/protocol/pdo_layout.hpp"

namespace ncservo {

// Raw words of one axis as seen in one place (one frame, or the latest of each PDO).
struct PdoValues {
  std::array<std::uint64_t, kWordCount> raw{};  // zero-extended wire bits of each word
  bool has_rx = false;
  bool has_tx = false;

  bool has(Word w) const { return wordDef(w).pdo == Pdo::Rx ? has_rx : has_tx; }
  std::uint64_t word(Word w) const { return raw[static_cast<std::size_t>(w)]; }
  // Sets a word from its wire bits; bits beyond the word's size are dropped, as `raw` holds them
  // zero-extended.
  void set(Word w, std::uint64_t bits) {
    const unsigned width = 8u * wordDef(w).size;
    raw[static_cast<std::size_t>(w)] =
        width >= 64 ? bits : bits & ((std::uint64_t{1} << width) - 1);
  }
  void setFloat(Word w, float value) {
    std::uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    set(w, bits);
  }
  float floatOf(Word w) const {
    auto bits = static_cast<std::uint32_t>(word(w));
    float value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
  std::int32_t ssp() const { return static_cast<std::int32_t>(word(Word::Ssp)); }
  std::uint32_t scw() const { return static_cast<std::uint32_t>(word(Word::Scw)); }
  std::uint32_t ssw() const { return static_cast<std::uint32_t>(word(Word::Ssw)); }
  std::uint32_t sew() const { return static_cast<std::uint32_t>(word(Word::Sew)); }
  std::int32_t msgCode() const { return static_cast<std::int32_t>(word(Word::MsgCode)); }
  float msgData() const { return floatOf(Word::MsgData); }
};

namespace detail {
// Each word's offset inside its PDO, computed once at compile time.
inline constexpr std::array<std::uint8_t, kWordCount> kWordOffsets = [] {
  std::array<std::uint8_t, kWordCount> offsets{};
  for (const WordDef& def : kWords) {
    offsets[static_cast<std::size_t>(def.word)] = static_cast<std::uint8_t>(wordOffset(def.word));
  }
  return offsets;
}();

// Reads every word of one PDO, unrolled at compile time from kWords.
template <Pdo P, std::size_t... I>
void readWords(const std::uint8_t* base, PdoValues& out, std::index_sequence<I...>) {
  ((kWords[I].pdo == P ? (void)(out.raw[I] = loadLe<kWords[I].size>(base + kWordOffsets[I]))
                       : (void)0),
   ...);
}
}  // namespace detail

// Reads the 10- or 40-byte PDO at `offset`; false (values untouched) when the bytes are short.
// Inline, one PDO at a time: the hot path of every frame.
template <Pdo P>
bool readPdoOf(const ByteReader& bytes, std::size_t offset, PdoValues& out) {
  // One bounds check for the whole PDO; every word lies inside it (kWordOffsets, pdoSize).
  if (!bytes.has(offset, sizeOfPdo(P))) return false;
  detail::readWords<P>(bytes.data() + offset, out, std::make_index_sequence<kWordCount>{});
  (P == Pdo::Rx ? out.has_rx : out.has_tx) = true;
  return true;
}
inline bool readPdo(Pdo pdo, const ByteReader& bytes, std::size_t offset, PdoValues& out) {
  return pdo == Pdo::Rx ? readPdoOf<Pdo::Rx>(bytes, offset, out)
                        : readPdoOf<Pdo::Tx>(bytes, offset, out);
}

namespace detail {
// Writes every word of one PDO, unrolled at compile time from kWords (readWords' mirror).
template <Pdo P, std::size_t... I>
void writeWords(const PdoValues& values, std::uint8_t* base, std::index_sequence<I...>) {
  ((kWords[I].pdo == P ? storeLe<kWords[I].size>(base + kWordOffsets[I], values.raw[I]) : (void)0),
   ...);
}
}  // namespace detail

// Writes the words of one PDO from `values` into the sizeOfPdo(P) bytes at `out`, as readPdo
// reads them: the same word table, so what one writes the other reads back.
template <Pdo P>
void writePdoOf(const PdoValues& values, std::uint8_t* out) {
  detail::writeWords<P>(values, out, std::make_index_sequence<kWordCount>{});
}
inline void writePdo(Pdo pdo, const PdoValues& values, std::uint8_t* out) {
  pdo == Pdo::Rx ? writePdoOf<Pdo::Rx>(values, out) : writePdoOf<Pdo::Tx>(values, out);
}

// One word of a PDO whose bytes start at `pdo` (already bounds-checked for the whole PDO).
inline std::uint64_t loadWordAt(const std::uint8_t* pdo, Word w) {
  const auto i = static_cast<std::size_t>(w);
  const std::uint8_t* p = pdo + detail::kWordOffsets[i];
  switch (kWords[i].size) {
    case 2:
      return loadLe<2>(p);
    case 4:
      return loadLe<4>(p);
    default:
      return loadLe<8>(p);
  }
}

namespace detail {
template <Pdo P, std::size_t... I>
void clearWords(PdoValues& out, std::index_sequence<I...>) {
  ((kWords[I].pdo == P ? (void)(out.raw[I] = 0) : (void)0), ...);
}
}  // namespace detail

// The words of one PDO set to zero and marked absent (unrolled: on the hot path).
template <Pdo P>
void clearPdoOf(PdoValues& out) {
  detail::clearWords<P>(out, std::make_index_sequence<kWordCount>{});
  (P == Pdo::Rx ? out.has_rx : out.has_tx) = false;
}

struct FieldValue {
  enum class Kind : std::uint8_t { Signed, Unsigned, Float } kind;
  std::int64_t i = 0;
  std::uint64_t u = 0;
  double f = 0;
};

// The value a row of the field table shows for these words (its PDO must be present).
FieldValue fieldValue(const FieldDef& field, const PdoValues& values);
// Whether a row is shown at all for these words (PDO present and its condition holds).
bool fieldApplies(const FieldDef& field, const PdoValues& values);
// Bytes of the PDO a row covers: offset inside the PDO and length.
struct FieldSpan {
  std::size_t offset;
  std::size_t length;
};
FieldSpan fieldSpan(const FieldDef& field);

// The value's name from the row's value names, or nullptr.
const ValueName* valueName(const FieldDef& field, std::uint64_t value);

// "motor speed 1500.0 rpm" (docs/protocol.md §5) into buf; never allocates, always terminates.
void formatMessage(char* buf, std::size_t size, std::int32_t code, float data);

}  // namespace ncservo
