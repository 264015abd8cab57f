// Small text helpers the command line, the configuration and the rule table share: matching a
// name typed by a user (case-insensitive IDs, "did you mean"), quoting a CSV field and writing a
// path as a URI.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace ncservo {

// ASCII case-insensitive equality ("msg-001" names MSG-001).
bool equalsIgnoringCase(std::string_view a, std::string_view b);

// The candidate closest to `typed` by case-insensitive edit distance (insertions, deletions,
// substitutions and swaps of neighbours), if it is close enough to be what the user meant: at
// most a third of its length away, and at least one character. Empty when none is, or when
// `typed` is itself a candidate.
std::optional<std::string> closestName(std::string_view typed,
                                       const std::vector<std::string>& candidates);

// "; did you mean 'X'?" for closestName's answer, or "" when there is none: the end of an
// error message about an unknown name.
std::string didYouMean(std::string_view typed, const std::vector<std::string>& candidates);

// One field of RFC 4180 CSV: as it is, or in double quotes with each quote doubled when it holds
// a comma, a quote, a CR or an LF (`always` quotes it in any case).
std::string csvField(std::string_view text, bool always = false);

// A path as the path of a URI reference (RFC 3986 §2.1, §3.3): every byte but an unreserved
// character (letters, digits, "-._~") and "/" percent-encoded, so a space is "%20" and "ü" (UTF-8)
// "%C3%BC". Encoding ":" too keeps a relative path's first segment from reading as a scheme.
std::string uriPath(std::string_view path);
// The file: URI of an absolute path ("file:///data/Pr%C3%BCfstand%201/x.pcap").
std::string fileUri(std::string_view absolute_path);

}  // namespace ncservo
