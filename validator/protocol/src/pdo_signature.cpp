#include "ncservo/protocol/pdo_signature.hpp"

#include "ncservo/base/little_endian.hpp"
#include "ncservo/protocol/fields.hpp"
#include "ncservo/protocol/pdo_layout.hpp"
#include "ncservo/protocol/word_bits.hpp"

namespace ncservo {

namespace {
using namespace bits;

std::uint32_t word32(const std::uint8_t* pdo, Word word) {
  return static_cast<std::uint32_t>(loadLe<4>(pdo + wordOffset(word)));
}

// A float32 a drive would send: finite and not denormal.
bool plausibleFloat(std::uint32_t bits) {
  const std::uint32_t exponent = (bits >> 23) & 0xFF;
  const std::uint32_t mantissa = bits & 0x7FFFFF;
  return exponent != 0xFF && (exponent != 0 || mantissa == 0);
}

}  // namespace

const char* signatureCheckName(std::uint32_t check) {
  switch (check) {
    case kSswReservedSet:
      return "SSW reserved bits set";
    case kSewReservedSet:
      return "SEW reserved bits set";
    case kMessageCodeUndefined:
      return "message code outside 0..9";
    case kFloatNotFinite:
      return "message or extra data not a finite float";
    case kScwReservedSet:
      return "SCW reserved bits set";
  }
  return "?";
}

std::uint32_t txSignatureFailures(const std::uint8_t* pdo) {
  std::uint32_t failures = 0;
  if ((word32(pdo, Word::Ssw) & kSswReserved) != 0) failures |= kSswReservedSet;
  if ((word32(pdo, Word::Sew) & kSewReserved) != 0) failures |= kSewReservedSet;
  const auto code = static_cast<std::int32_t>(word32(pdo, Word::MsgCode));
  if (code < 0 || code > kMaxListedMessageCode) failures |= kMessageCodeUndefined;
  for (Word w : {Word::MsgData, Word::ExtData1, Word::ExtData2, Word::ExtData3, Word::ExtData4}) {
    if (!plausibleFloat(word32(pdo, w))) failures |= kFloatNotFinite;
  }
  return failures;
}

std::uint32_t rxSignatureFailures(const std::uint8_t* pdo) {
  return (word32(pdo, Word::Scw) & kScwReserved) != 0 ? kScwReservedSet : 0u;
}

}  // namespace ncservo
