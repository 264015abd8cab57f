// The one error convention: whatever can fail returns Result<T> — the value, or an
// Error saying where (file, line, key or frame) and what, in words a user can act on.
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <string>
#include <tl/expected.hpp>
#include <utility>

namespace ncservo {

struct Error {
  std::string path;         // the file it is about; empty when none
  std::uint64_t line = 0;   // 1-based line of a text file; 0 when none
  std::uint64_t frame = 0;  // 1-based frame of a capture; 0 when none
  std::string key;          // dotted configuration key, e.g. "axis[1].outputs"; empty when none
  std::string message;

  // "PATH:LINE: key 'K': MESSAGE", "PATH: frame N: MESSAGE", or just what is known of that.
  std::string text() const {
    std::string out = path;
    if (line != 0) out += fmt::format(":{}", line);
    if (!out.empty()) out += ": ";
    if (frame != 0) out += fmt::format("frame {}: ", frame);
    if (!key.empty()) out += fmt::format("key '{}': ", key);
    return out + message;
  }
};

template <class T>
using Result = tl::expected<T, Error>;
using Status = Result<void>;

// `return fail("...")` in a function returning any Result.
inline tl::unexpected<Error> fail(std::string message) {
  return tl::unexpected<Error>(Error{{}, 0, 0, {}, std::move(message)});
}
inline tl::unexpected<Error> fail(Error error) {
  return tl::unexpected<Error>(std::move(error));
}

}  // namespace ncservo
