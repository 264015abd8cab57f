#include "ncservo/base/text.hpp"

#include <algorithm>
#include <cstddef>

namespace ncservo {

namespace {

char lower(char c) {
  return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c;
}

// Optimal string alignment distance (Damerau-Levenshtein without repeated edits of a substring),
// case-insensitive.
std::size_t editDistance(std::string_view a, std::string_view b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) &&
          lower(a[i - 2]) == lower(b[j - 1])) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[n][m];
}

}  // namespace

bool equalsIgnoringCase(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(),
                                            [](char x, char y) { return lower(x) == lower(y); });
}

std::optional<std::string> closestName(std::string_view typed,
                                       const std::vector<std::string>& candidates) {
  std::optional<std::string> best;
  std::size_t best_distance = 0;
  for (const std::string& candidate : candidates) {
    const std::size_t distance = editDistance(typed, candidate);
    if (distance == 0) return std::nullopt;
    const std::size_t limit = std::max<std::size_t>(1, candidate.size() / 3);
    if (distance <= limit && (!best || distance < best_distance)) {
      best = candidate;
      best_distance = distance;
    }
  }
  if (best || typed.size() < 2) return best;
  // A name cut short ("warn" for "warning") is what the user meant when it begins one name only.
  for (const std::string& candidate : candidates) {
    if (candidate.size() <= typed.size() ||
        !equalsIgnoringCase(typed, std::string_view(candidate).substr(0, typed.size())))
      continue;
    if (best) return std::nullopt;
    best = candidate;
  }
  return best;
}

std::string didYouMean(std::string_view typed, const std::vector<std::string>& candidates) {
  const std::optional<std::string> name = closestName(typed, candidates);
  return name ? "; did you mean '" + *name + "'?" : std::string();
}

std::string csvField(std::string_view text, bool always) {
  if (!always && text.find_first_of(",\"\r\n") == std::string_view::npos) return std::string(text);
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

std::string uriPath(std::string_view path) {
  std::string uri;
  uri.reserve(path.size());
  for (const char c : path) {
    const bool unreserved = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                            (c >= '0' && c <= '9') || c == '-' || c == '.' || c == '_' || c == '~';
    if (unreserved || c == '/') {
      uri += c;
      continue;
    }
    constexpr char kHex[] = "0123456789ABCDEF";
    const auto byte = static_cast<unsigned char>(c);
    uri += {'%', kHex[byte >> 4], kHex[byte & 0xF]};
  }
  return uri;
}

std::string fileUri(std::string_view absolute_path) {
  return "file://" + uriPath(absolute_path);
}

}  // namespace ncservo
