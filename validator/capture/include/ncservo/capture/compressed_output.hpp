// Compressing what a writer of FILE*s writes (gzip through zlib, zstd through libzstd), streamed:
// the capture writers write into the returned FILE* as into any file, so the compressed capture is
// never held in memory (docs/protocol.md §8: Wireshark opens both).
#pragma once

#include <cstdio>
#include <string_view>

#include "ncservo/base/error.hpp"
#include "ncservo/capture/capture_reader.hpp"

namespace ncservo {

// A FILE* whose bytes reach `sink` compressed. Closing it finishes the stream, flushes `sink`
// and closes it too when `close_sink` is set; it fails if any write to `sink` failed.
Result<std::FILE*> openCompressedOutput(std::FILE* sink, bool close_sink, Compression compression);

// What a file name's last extension asks for: ".gz" gzip, ".zst" zstd, else none.
Compression compressionForName(std::string_view name);
// The name without that extension ("x.pcapng.zst" -> "x.pcapng").
std::string_view withoutCompressionExtension(std::string_view name);

}  // namespace ncservo
