#include "ncservo/protocol/pdo.hpp"

#include <fmt/format.h>

#include <array>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <utility>

#include "ncservo/protocol/word_bits.hpp"

namespace ncservo {

namespace {
using namespace bits;
constexpr const FieldDef& kMsgCodeField = field("ncservo.msg_code");

std::int64_t signExtend(std::uint64_t raw, unsigned bits) {
  if (bits >= 64) return static_cast<std::int64_t>(raw);
  const std::uint64_t sign = 1ull << (bits - 1);
  return static_cast<std::int64_t>((raw ^ sign) - sign);
}
}  // namespace

FieldValue fieldValue(const FieldDef& field, const PdoValues& values) {
  const WordDef& word = wordDef(field.word);
  const std::uint64_t raw = values.word(field.word);
  FieldValue v{};
  switch (field.kind) {
    case FieldKind::Word:
      if (word.type == WireType::F32) {
        auto bits = static_cast<std::uint32_t>(raw);
        float f;
        std::memcpy(&f, &bits, sizeof f);
        v.kind = FieldValue::Kind::Float;
        v.f = f;
      } else if (word.type == WireType::U32) {
        v.kind = FieldValue::Kind::Unsigned;
        v.u = raw;
      } else {
        v.kind = FieldValue::Kind::Signed;
        v.i = signExtend(raw, 8u * word.size);
      }
      return v;
    case FieldKind::Part:
      v.kind = FieldValue::Kind::Signed;
      v.i = signExtend((raw & field.mask) >> lowestBit(field.mask), 32);
      return v;
    case FieldKind::Flag:
    case FieldKind::BitRange:
      v.kind = FieldValue::Kind::Unsigned;
      v.u = (raw & field.mask) >> lowestBit(field.mask);
      return v;
  }
  return v;
}

bool fieldApplies(const FieldDef& field, const PdoValues& values) {
  if (!values.has(field.word)) return false;
  switch (field.when) {
    case FieldWhen::Always:
      return true;
    case FieldWhen::IncrementalEncoder:
      return (values.ssw() & kIncremental) != 0;
  }
  return false;
}

FieldSpan fieldSpan(const FieldDef& field) {
  const std::size_t word_offset = wordOffset(field.word);
  if (field.kind == FieldKind::Part) {
    return {word_offset + lowestBit(field.mask) / 8, popcount64(field.mask) / 8};
  }
  return {word_offset, wordDef(field.word).size};
}

const ValueName* valueName(const FieldDef& field, std::uint64_t value) {
  for (std::size_t i = 0; i < field.value_count; ++i) {
    if (field.values[i].value == value) return &field.values[i];
  }
  return nullptr;
}

void formatMessage(char* buf, std::size_t size, std::int32_t code, float data) {
  if (size == 0) return;
  const ValueName* name =
      code >= 0 ? valueName(kMsgCodeField, static_cast<std::uint32_t>(code)) : nullptr;
  if (name != nullptr) {
    // fmt, not snprintf: the Wireshark plugin formats this for every axis of every frame, and
    // fmt's {:.1f} gives the same digits as %.1f at a fraction of the cost.
    *fmt::format_to_n(buf, size - 1, "{} {:.1f} {}", name->name, data, name->unit).out = '\0';
  } else {
    std::snprintf(buf, size, "undefined message code %" PRId32 ": %g", code,
                  static_cast<double>(data));
  }
}

}  // namespace ncservo
