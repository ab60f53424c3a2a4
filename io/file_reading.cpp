// SPDX-License-Identifier: MIT
#include "io/file_reading.h"

#include <fmt/format.h>
#include <lzma.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <system_error>

#include "io/text_scanning.h"

namespace harap {

using io_internal::Fail;

namespace {

std::string ReadWholeFile(const std::filesystem::path& file) {
  const std::string what = file.string();
  std::error_code error;
  const auto status = std::filesystem::status(file, error);
  if (!std::filesystem::exists(status)) Fail(what, "file not found");
  if (std::filesystem::is_directory(status)) Fail(what, "is a directory, not a file");
  // Devices such as /dev/zero or /dev/urandom never end; pipes (e.g. <(xz -dc ...)) do.
  if (!std::filesystem::is_regular_file(status) && !std::filesystem::is_fifo(status)) {
    Fail(what, "is not a regular file (a device or socket) and cannot be read as one");
  }
  std::ifstream stream(file, std::ios::binary);
  if (!stream) Fail(what, "cannot open the file for reading");
  std::string data;
  const auto size = std::filesystem::file_size(file, error);
  if (!error) data.reserve(static_cast<size_t>(size));
  data.assign(std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>());
  if (stream.bad()) Fail(what, "read error");
  return data;
}

}  // namespace

std::string DecompressXz(std::string_view compressed, const std::string& what) {
  if (compressed.empty()) Fail(what, "not xz-compressed data: the file is empty");
  lzma_stream stream = LZMA_STREAM_INIT;
  // The decoder's memory is set by the dictionary size the file's headers declare (64 MiB for
  // `xz -9`, up to 1.5 GiB for custom settings), so a 100-byte file could make it allocate that
  // much. No mesh file needs more than this limit; a larger request is a corrupt header.
  constexpr uint64_t kDecoderMemoryLimit = uint64_t{512} << 20;
  // LZMA_CONCATENATED: `xz` itself accepts several concatenated streams in one file.
  lzma_ret ret = lzma_stream_decoder(&stream, kDecoderMemoryLimit, LZMA_CONCATENATED);
  if (ret != LZMA_OK)
    Fail(what,
         fmt::format("cannot start the xz decoder (liblzma error {})", static_cast<int>(ret)));
  struct Guard {
    lzma_stream* stream;
    ~Guard() { lzma_end(stream); }
  } guard{&stream};

  std::string out;
  out.resize(std::max<size_t>(size_t{1} << 16, compressed.size() * 6));
  stream.next_in = reinterpret_cast<const uint8_t*>(compressed.data());
  stream.avail_in = compressed.size();
  stream.next_out = reinterpret_cast<uint8_t*>(out.data());
  stream.avail_out = out.size();
  while (true) {
    ret = lzma_code(&stream, LZMA_FINISH);
    if (ret == LZMA_STREAM_END) break;
    if (ret == LZMA_OK) {
      if (stream.avail_out == 0) {
        const size_t used = out.size();
        out.resize(used * 2);
        stream.next_out = reinterpret_cast<uint8_t*>(out.data()) + used;
        stream.avail_out = out.size() - used;
      }
      continue;
    }
    switch (ret) {
      case LZMA_FORMAT_ERROR:
        Fail(what,
             "not xz-compressed data (the name ends in .xz but the xz magic bytes are "
             "missing)");
      case LZMA_DATA_ERROR:
        Fail(what, fmt::format("corrupt xz data (decoding failed after {} compressed bytes)",
                               stream.total_in));
      case LZMA_BUF_ERROR:
        Fail(what, fmt::format("truncated xz data (the compressed stream ends after {} bytes "
                               "without its end marker)",
                               stream.total_in));
      case LZMA_MEM_ERROR:
        Fail(what, "out of memory while decompressing xz data");
      case LZMA_MEMLIMIT_ERROR:
        Fail(what, fmt::format("the xz headers ask for {} MiB of decoder memory (dictionary "
                               "size), more than the {} MiB any mesh file needs: corrupt xz data",
                               lzma_memusage(&stream) >> 20, kDecoderMemoryLimit >> 20));
      case LZMA_OPTIONS_ERROR:
        Fail(what, "unsupported xz compression options");
      default:
        Fail(what,
             fmt::format("xz decompression failed (liblzma error {})", static_cast<int>(ret)));
    }
  }
  out.resize(stream.total_out);
  return out;
}

FileFormat DetectFormat(const std::filesystem::path& file) {
  FileFormat format;
  std::filesystem::path name = file.filename();
  if (io_internal::Lower(name.extension().string()) == ".xz") {
    format.xz = true;
    name = name.stem();
  }
  std::string extension = io_internal::Lower(name.extension().string());
  if (!extension.empty()) extension.erase(0, 1);
  format.extension = extension;
  return format;
}

std::string ReadFileMaybeXz(const std::filesystem::path& file) {
  std::string data = ReadWholeFile(file);
  if (io_internal::Lower(file.extension().string()) == ".xz") {
    return DecompressXz(data, file.string());
  }
  return data;
}

}  // namespace harap
