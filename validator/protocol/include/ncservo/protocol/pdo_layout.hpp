// The two process-data objects of one axis, word by word (docs/protocol.md §1).
// Offsets are derived from the sizes in declaration order, and proven to give 10 and 40 bytes.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace ncservo {

enum class Pdo : std::uint8_t { Rx, Tx };  // Rx: NC -> servo (outputs); Tx: servo -> NC (inputs)

enum class WireType : std::uint8_t { I16, I32, U32, I64, F32 };

enum class Word : std::uint8_t {
  Ssp,
  Scw,
  ExtCode,
  ActPos,
  Ssw,
  Sew,
  MsgCode,
  MsgData,
  ExtData1,
  ExtData2,
  ExtData3,
  ExtData4,
};
inline constexpr std::size_t kWordCount = 12;

struct WordDef {
  Word word;
  Pdo pdo;
  std::uint8_t size;  // bytes
  WireType type;
  const char* name;  // as the interface definition names it
};

// In wire order within each PDO.
inline constexpr std::array<WordDef, kWordCount> kWords{{
    {.word = Word::Ssp, .pdo = Pdo::Rx, .size = 4, .type = WireType::I32, .name = "SSP"},
    {.word = Word::Scw, .pdo = Pdo::Rx, .size = 4, .type = WireType::U32, .name = "SCW"},
    {.word = Word::ExtCode, .pdo = Pdo::Rx, .size = 2, .type = WireType::I16, .name = "ExtCode"},
    {.word = Word::ActPos, .pdo = Pdo::Tx, .size = 8, .type = WireType::I64, .name = "ActPos"},
    {.word = Word::Ssw, .pdo = Pdo::Tx, .size = 4, .type = WireType::U32, .name = "SSW"},
    {.word = Word::Sew, .pdo = Pdo::Tx, .size = 4, .type = WireType::U32, .name = "SEW"},
    {.word = Word::MsgCode, .pdo = Pdo::Tx, .size = 4, .type = WireType::I32, .name = "MsgCode"},
    {.word = Word::MsgData, .pdo = Pdo::Tx, .size = 4, .type = WireType::F32, .name = "MsgData"},
    {.word = Word::ExtData1, .pdo = Pdo::Tx, .size = 4, .type = WireType::F32, .name = "ExtData1"},
    {.word = Word::ExtData2, .pdo = Pdo::Tx, .size = 4, .type = WireType::F32, .name = "ExtData2"},
    {.word = Word::ExtData3, .pdo = Pdo::Tx, .size = 4, .type = WireType::F32, .name = "ExtData3"},
    {.word = Word::ExtData4, .pdo = Pdo::Tx, .size = 4, .type = WireType::F32, .name = "ExtData4"},
}};

constexpr const WordDef& wordDef(Word w) {
  return kWords[static_cast<std::size_t>(w)];
}

// Byte offset of each word inside its PDO: the sum of the sizes of the words before it, worked
// out once, so that a word's offset is a load even where a loop over words hides its constant.
inline constexpr std::array<std::size_t, kWordCount> kWordOffsets = [] {
  std::array<std::size_t, kWordCount> offsets{};
  std::array<std::size_t, 2> next{};  // by Pdo
  for (const auto& def : kWords) {
    std::size_t& at = next[static_cast<std::size_t>(def.pdo)];
    offsets[static_cast<std::size_t>(def.word)] = at;
    at += def.size;
  }
  return offsets;
}();

constexpr std::size_t wordOffset(Word w) {
  return kWordOffsets[static_cast<std::size_t>(w)];
}

constexpr std::size_t pdoSize(Pdo pdo) {
  std::size_t size = 0;
  for (const auto& def : kWords) size += def.pdo == pdo ? def.size : 0;
  return size;
}

inline constexpr std::size_t kRxPdoSize = pdoSize(Pdo::Rx);
inline constexpr std::size_t kTxPdoSize = pdoSize(Pdo::Tx);
// The same, as constants for hot paths (pdoSize loops over the table when `pdo` is not constant).
constexpr std::size_t sizeOfPdo(Pdo pdo) {
  return pdo == Pdo::Rx ? kRxPdoSize : kTxPdoSize;
}
// Words of one PDO are contiguous in kWords (checked below): [first, first + count).
constexpr std::size_t firstWordOf(Pdo pdo) {
  return pdo == Pdo::Rx ? 0 : 3;
}
constexpr std::size_t wordCountOf(Pdo pdo) {
  return pdo == Pdo::Rx ? 3 : kWordCount - 3;
}

namespace detail {
constexpr bool wordsInEnumOrder() {
  for (std::size_t i = 0; i < kWords.size(); ++i) {
    if (static_cast<std::size_t>(kWords[i].word) != i) return false;
    if (i > 0 && kWords[i].pdo < kWords[i - 1].pdo) return false;
  }
  return true;
}
}  // namespace detail

static_assert(detail::wordsInEnumOrder(), "kWords must list Word values in order, Rx before Tx");
static_assert(kWords[firstWordOf(Pdo::Rx) + wordCountOf(Pdo::Rx) - 1].pdo == Pdo::Rx &&
                  kWords[firstWordOf(Pdo::Tx)].pdo == Pdo::Tx,
              "firstWordOf/wordCountOf match the word table");
static_assert(kRxPdoSize == 10, "RxPDO is 10 bytes (docs/protocol.md §1)");
static_assert(kTxPdoSize == 40, "TxPDO is 40 bytes (docs/protocol.md §1)");
static_assert(wordOffset(Word::Scw) == 4 && wordOffset(Word::ExtCode) == 8);
static_assert(wordOffset(Word::Ssw) == 8 && wordOffset(Word::MsgData) == 20 &&
              wordOffset(Word::ExtData4) == 36);

}  // namespace ncservo
