#include "ncservo/capture/compressed_output.hpp"

#include <zlib.h>
#include <zstd.h>

#include <cstring>
#include <memory>
#include <vector>

namespace ncservo {
namespace {

constexpr std::size_t kChunk = 1 << 17;
constexpr int kGzipLevel = 6;  // zlib's default
constexpr int kZstdLevel = 3;  // libzstd's default
// 16 + MAX_WBITS: a gzip wrapper, not zlib's (zlib.h, deflateInit2).
constexpr int kGzipWindowBits = 16 + MAX_WBITS;
constexpr int kMemLevel = 8;

struct Extension {
  Compression compression;
  std::string_view extension;
};
constexpr Extension kExtensions[] = {
    {Compression::Gzip, ".gz"},
    {Compression::Zstd, ".zst"},
};

// One compressed stream into `sink`: compress() per write, finish() once at the close.
class Compressor {
 public:
  Compressor(std::FILE* sink, bool close_sink, Compression compression)
      : sink_(sink), close_sink_(close_sink), compression_(compression), out_(kChunk) {}
  ~Compressor() {
    if (gzip_ready_) deflateEnd(&gzip_);
    if (zstd_ != nullptr) ZSTD_freeCStream(zstd_);
  }
  Compressor(const Compressor&) = delete;
  Compressor& operator=(const Compressor&) = delete;

  bool start() {
    if (compression_ == Compression::Gzip) {
      gzip_ready_ = deflateInit2(&gzip_, kGzipLevel, Z_DEFLATED, kGzipWindowBits, kMemLevel,
                                 Z_DEFAULT_STRATEGY) == Z_OK;
      return gzip_ready_;
    }
    zstd_ = ZSTD_createCStream();
    return zstd_ != nullptr && !ZSTD_isError(ZSTD_initCStream(zstd_, kZstdLevel));
  }
  bool compress(const char* data, std::size_t size) { return run(data, size, false); }
  // Ends the stream; false if anything written to the sink failed.
  bool finish() {
    bool ok = run(nullptr, 0, true) && std::fflush(sink_) == 0 && std::ferror(sink_) == 0;
    if (close_sink_ && std::fclose(sink_) != 0) ok = false;
    return ok;
  }

 private:
  bool run(const char* data, std::size_t size, bool end) {
    if (failed_) return false;
    if (compression_ == Compression::Gzip) {
      gzip_.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data));
      gzip_.avail_in = static_cast<uInt>(size);
      int rc = Z_OK;
      do {
        gzip_.next_out = out_.data();
        gzip_.avail_out = static_cast<uInt>(out_.size());
        rc = deflate(&gzip_, end ? Z_FINISH : Z_NO_FLUSH);
        if (rc == Z_STREAM_ERROR) return fail();
        if (!put(out_.size() - gzip_.avail_out)) return false;
      } while (gzip_.avail_out == 0 || (end && rc != Z_STREAM_END));
      return true;
    }
    ZSTD_inBuffer in{data, size, 0};
    for (;;) {
      ZSTD_outBuffer out{out_.data(), out_.size(), 0};
      const std::size_t rc =
          ZSTD_compressStream2(zstd_, &out, &in, end ? ZSTD_e_end : ZSTD_e_continue);
      if (ZSTD_isError(rc)) return fail();
      if (!put(out.pos)) return false;
      // ZSTD_e_continue: done once the input is consumed; ZSTD_e_end: once nothing remains.
      if (end ? rc == 0 : in.pos == in.size) return true;
    }
  }
  bool put(std::size_t count) {
    if (count > 0 && std::fwrite(out_.data(), 1, count, sink_) != count) return fail();
    return true;
  }
  bool fail() {
    failed_ = true;
    return false;
  }

  std::FILE* sink_;
  bool close_sink_;
  Compression compression_;
  std::vector<std::uint8_t> out_;
  z_stream gzip_{};
  bool gzip_ready_ = false;
  ZSTD_CStream* zstd_ = nullptr;
  bool failed_ = false;
};

ssize_t writeCookie(void* cookie, const char* data, std::size_t size) {
  return static_cast<Compressor*>(cookie)->compress(data, size) ? static_cast<ssize_t>(size) : -1;
}
int closeCookie(void* cookie) {
  std::unique_ptr<Compressor> compressor(static_cast<Compressor*>(cookie));
  return compressor->finish() ? 0 : EOF;
}

}  // namespace

Result<std::FILE*> openCompressedOutput(std::FILE* sink, bool close_sink, Compression compression) {
  auto compressor = std::make_unique<Compressor>(sink, close_sink, compression);
  if (compression == Compression::None || !compressor->start()) {
    return fail(fmt::format("cannot start the {} encoder", compressionName(compression)));
  }
  cookie_io_functions_t functions{};
  functions.write = writeCookie;
  functions.close = closeCookie;
  std::FILE* file = fopencookie(compressor.get(), "w", functions);
  if (file == nullptr)
    return fail(fmt::format("cannot open a {} stream", compressionName(compression)));
  compressor.release();  // closeCookie owns it now
  return file;
}

namespace {
const Extension* extensionOf(std::string_view name) {
  for (const Extension& e : kExtensions) {
    if (name.size() > e.extension.size() &&
        name.substr(name.size() - e.extension.size()) == e.extension) {
      return &e;
    }
  }
  return nullptr;
}
}  // namespace

Compression compressionForName(std::string_view name) {
  const Extension* e = extensionOf(name);
  return e != nullptr ? e->compression : Compression::None;
}

std::string_view withoutCompressionExtension(std::string_view name) {
  const Extension* e = extensionOf(name);
  return e != nullptr ? name.substr(0, name.size() - e->extension.size()) : name;
}

}  // namespace ncservo
