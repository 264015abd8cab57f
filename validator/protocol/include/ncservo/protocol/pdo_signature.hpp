// The signature of this protocol's PDOs (docs/protocol.md §1–5), one PDO at a time: what any
// servo of the protocol sends whatever its state. Data that fails it in most cycles is not this
// protocol's PDO (a layout that does not fit, a neighbour that only looks alike).
#pragma once

#include <cstdint>

namespace ncservo {

// The checks a PDO's data can fail, as bits of a mask.
enum SignatureFailure : std::uint32_t {
  kSswReservedSet = 1u << 0,        // SSW bits 31..13
  kSewReservedSet = 1u << 1,        // SEW bits 4 and 31..25
  kMessageCodeUndefined = 1u << 2,  // outside the listed codes 0..9
  kFloatNotFinite = 1u << 3,        // message data or extra data infinite, NaN or denormal
  kScwReservedSet = 1u << 4,        // SCW bits 30..13
};
inline constexpr int kSignatureChecks = 5;
// "SSW reserved bits set", for messages; `check` is one bit of SignatureFailure.
const char* signatureCheckName(std::uint32_t check);

inline constexpr std::int32_t kMaxListedMessageCode = 9;  // docs/protocol.md §5

// The checks the 40 bytes of a TxPDO at `pdo` fail.
std::uint32_t txSignatureFailures(const std::uint8_t* pdo);
// The checks the 10 bytes of an RxPDO at `pdo` fail.
std::uint32_t rxSignatureFailures(const std::uint8_t* pdo);

}  // namespace ncservo
