// What a check or a model reads of an axis's PDOs, declared as field-table rows (docs/rules.md,
// "reads"). The validator's fast path compares exactly the declared bits.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/protocol/fields.hpp"

namespace ncservo {

// Bits of the PDO words, words read only through a classification of their value, and the
// slave's AL state. A check that reads something it does not declare is caught by the fast-path
// test (tests/unit/fast_path_test.cpp), never skipped silently.
using WordClass = bool (*)(std::uint64_t raw);
struct Reads {
  std::array<std::uint64_t, kWordCount> bits{};  // per word (kWords order), the bits read
  // Per word, a class the value is read through (MSG-001: defined or not): a change of value
  // within its class changes nothing. Two different classes of one word read the whole word.
  std::array<WordClass, kWordCount> classes{};
  // The slave's AL state, and outside the states that exchange inputs (ecat::exchangesInputs)
  // which PDOs each frame carries.
  bool al_state = false;
  // What the axis's drive said over its mailbox (its emergencies, its 1003h read), where the
  // axis's station is known (docs/drive-messages.md#the-rules).
  bool mailbox = false;

  constexpr Reads operator|(const Reads& other) const {
    Reads out = *this;
    for (std::size_t w = 0; w < kWordCount; ++w) {
      out.bits[w] |= other.bits[w];
      if (out.classes[w] == nullptr) {
        out.classes[w] = other.classes[w];
      } else if (other.classes[w] != nullptr && other.classes[w] != out.classes[w]) {
        out.classes[w] = nullptr;
        out.bits[w] = wordMask(kWords[w].word);
      }
    }
    out.al_state = al_state || other.al_state;
    out.mailbox = mailbox || other.mailbox;
    return out;
  }
  constexpr bool any() const {
    for (std::size_t w = 0; w < kWordCount; ++w) {
      if (bits[w] != 0 || classes[w] != nullptr) return true;
    }
    return al_state || mailbox;
  }
};
// The fields of the field table named by their filter names (a whole word for a word's row);
// an unknown name does not compile.
constexpr Reads readsOf(std::initializer_list<std::string_view> filters, bool al_state = false) {
  Reads out;
  for (std::string_view filter : filters) {
    const FieldDef& f = field(filter);
    out.bits[static_cast<std::size_t>(f.word)] |= f.mask != 0 ? f.mask : wordMask(f.word);
  }
  out.al_state = al_state;
  return out;
}
// A field-table row a declaration covers: a word's row when the whole word or its class is read,
// else each bit field whose bits are all read.
struct FieldRead {
  const FieldDef* field;
  bool through_class;  // the word is read only through its class
};
// The rows a declaration covers, in field-table order (the AL state and the mailbox are no rows:
// Reads::al_state, Reads::mailbox).
std::vector<FieldRead> fieldsRead(const Reads& reads);
// "scw.se, ssw.servo_en, msg_code (its class)": the field-table rows a declaration covers, for
// the rule reference; "-" for none.
std::string describeReads(const Reads& reads);

// The fields named (as readsOf) and what the axis's drive said over its mailbox.
constexpr Reads readsWithMailbox(std::initializer_list<std::string_view> filters) {
  Reads out = readsOf(filters);
  out.mailbox = true;
  return out;
}

// A word (by its row's filter name) read only through `word_class`.
constexpr Reads readsThrough(std::string_view filter, WordClass word_class) {
  Reads out;
  out.classes[static_cast<std::size_t>(field(filter).word)] = word_class;
  return out;
}

}  // namespace ncservo
