// What a check or a model reads of an axis's PDOs, declared as field-table rows (STYLE.md "A rule
// declares what it reads"). The validator's fast path compares exactly the declared bits.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string_view>

#include "ncservo/fields.hpp"

namespace ncservo {

// Bits of the PDO words, and the slave's AL state. A check that reads something it does not
// declare is caught by the fast-path test (tests/unit/fast_path_test.cpp), never skipped silently.
struct Reads {
  std::array<std::uint64_t, kWordCount> bits{};  // per word (kWords order), the bits read
  bool al_state = false;  // the slave's AL state, and which PDOs each frame carries

  constexpr Reads operator|(const Reads& other) const {
    Reads out = *this;
    for (std::size_t w = 0; w < kWordCount; ++w) out.bits[w] |= other.bits[w];
    out.al_state = al_state || other.al_state;
    return out;
  }
  constexpr bool any() const {
    for (std::uint64_t b : bits) {
      if (b != 0) return true;
    }
    return al_state;
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

}  // namespace ncservo
