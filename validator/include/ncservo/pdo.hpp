// Reading one axis's PDOs out of captured bytes, and the values of the field table's rows.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "ncservo/byte_reader.hpp"
#include "ncservo/fields.hpp"
#include "ncservo/pdo_layout.hpp"

namespace ncservo {

// Raw words of one axis as seen in one place (one frame, or the latest of each PDO).
struct PdoValues {
  std::array<std::uint64_t, kWordCount> raw{};  // zero-extended wire bits of each word
  bool has_rx = false;
  bool has_tx = false;

  bool has(Word w) const { return wordDef(w).pdo == Pdo::Rx ? has_rx : has_tx; }
  std::uint64_t word(Word w) const { return raw[static_cast<std::size_t>(w)]; }
  std::uint32_t scw() const { return static_cast<std::uint32_t>(word(Word::Scw)); }
  std::uint32_t ssw() const { return static_cast<std::uint32_t>(word(Word::Ssw)); }
  std::uint32_t sew() const { return static_cast<std::uint32_t>(word(Word::Sew)); }
  std::int32_t msgCode() const { return static_cast<std::int32_t>(word(Word::MsgCode)); }
  float msgData() const {
    auto bits = static_cast<std::uint32_t>(word(Word::MsgData));
    float value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
};

// Reads the 10- or 40-byte PDO at `offset`; false (values untouched) when the bytes are short.
bool readPdo(Pdo pdo, const ByteReader& bytes, std::size_t offset, PdoValues& out);

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

// "motor speed 1500.0 rpm" (PROTOCOL.md §5) into buf; never allocates, always terminates.
void formatMessage(char* buf, std::size_t size, std::int32_t code, float data);

}  // namespace ncservo
