#include "ncservo/wire/diagnosis_texts.hpp"

#include <algorithm>

#include "ncservo/wire/ecat_wire.hpp"

namespace ncservo::diag {
namespace {

template <std::size_t N>
const char* lookup(const std::array<CodeText, N>& table, std::uint32_t code) {
  auto it = std::lower_bound(table.begin(), table.end(), code,
                             [](const CodeText& row, std::uint32_t c) { return row.code < c; });
  return it != table.end() && it->code == code ? it->text : nullptr;
}

// CiA 301's error code families, by the code's high byte (then its high nibble), and the bit of
// the error register (1001h) an error of the family sets beside the generic bit.
struct Family {
  std::uint16_t mask;
  std::uint16_t value;
  const char* text;
  std::uint8_t register_bit;
};
constexpr std::array<Family, 13> kFamilies{{
    {0xFF00, 0x1000, "generic error", 0},
    {0xF000, 0x2000, "current", 0x02},
    {0xF000, 0x3000, "voltage", 0x04},
    {0xF000, 0x4000, "temperature", 0x08},
    {0xFF00, 0x5000, "device hardware", 0},
    {0xF000, 0x6000, "device software", 0},
    {0xF000, 0x7000, "additional modules", 0},
    {0xFF00, 0x8100, "communication", 0x10},
    {0xFF00, 0x8200, "protocol error", 0x10},
    {0xFF00, 0x8600, "position control", 0x20},
    {0xF000, 0x8000, "monitoring", 0x20},
    {0xFF00, 0x9000, "external error", 0},
    {0xFF00, 0xFF00, "device specific", 0x80},
}};
const Family* familyOf(std::uint16_t code) {
  for (const Family& f : kFamilies) {
    if ((code & f.mask) == f.value) return &f;
  }
  return nullptr;
}

}  // namespace

const char* objectName(std::uint16_t index) {
  for (const ObjectDef& o : kObjects) {
    if (o.index == index) return o.name;
  }
  return nullptr;
}

const char* errorCodeText(std::uint16_t code) {
  if (const char* text = lookup(kErrorCodes, code)) return text;
  const Family* family = familyOf(code);
  return family != nullptr ? family->text : nullptr;
}

std::uint8_t errorRegisterFor(std::uint16_t code) {
  if (code == kErrorReset) return 0;
  const Family* family = familyOf(code);
  return static_cast<std::uint8_t>(0x01 | (family != nullptr ? family->register_bit : 0));
}

const char* errorNumberText(std::uint8_t number) {
  return lookup(kErrorNumbers, number);
}

const char* abortText(std::uint32_t code) {
  return lookup(kAbortCodes, code);
}

const AlCodeDef* alStatusCode(std::uint16_t code) {
  for (const AlCodeDef& row : kAlStatusCodes) {
    if (row.code == code) return &row;
  }
  return nullptr;
}

const char* mailboxTypeName(std::uint8_t type) {
  switch (type) {
    case ecat::kMailboxTypeError:
      return "error";
    case ecat::kMailboxTypeAoe:
      return "AoE";
    case ecat::kMailboxTypeEoe:
      return "EoE";
    case ecat::kMailboxTypeCoe:
      return "CoE";
    case ecat::kMailboxTypeFoe:
      return "FoE";
    case ecat::kMailboxTypeSoe:
      return "SoE";
    case ecat::kMailboxTypeVoe:
      return "VoE";
    default:
      return "other";
  }
}

}  // namespace ncservo::diag
