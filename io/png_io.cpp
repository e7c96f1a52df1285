#include "io/png_io.h"

#include <zlib.h>

#include <array>
#include <cstdlib>
#include <vector>

#include "core/system/errors.h"
#include "io/atomic_file.h"

namespace seamvox {
namespace {

constexpr std::size_t kIdatBytes = 1 << 18;  // compressed bytes per IDAT chunk

void appendBigEndian(std::string& out, std::uint32_t value) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>((value >> shift) & 0xff));
}

/// Appends one chunk: length, type, data, CRC-32 of type and data.
void appendChunk(std::string& out, const char type[5], const unsigned char* data, std::size_t size) {
  appendBigEndian(out, static_cast<std::uint32_t>(size));
  const std::size_t typeAt = out.size();
  out.append(type, 4);
  if (size) out.append(reinterpret_cast<const char*>(data), size);
  const uLong crc = crc32(0L, reinterpret_cast<const Bytef*>(out.data() + typeAt),
                          static_cast<uInt>(size + 4));
  appendBigEndian(out, static_cast<std::uint32_t>(crc));
}

int paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return a;
  return pb <= pc ? b : c;
}

/// Filters one row (prior = the row above, zeros for the first) into out[0..1+n): the filter
/// type byte, then the filtered bytes, choosing the type with the smallest sum of |byte|.
void filterRow(const std::uint8_t* row, const std::uint8_t* prior, std::size_t n,
               std::vector<std::uint8_t>& scratch, std::uint8_t* out) {
  constexpr std::size_t bpp = 3;
  std::uint64_t bestCost = ~std::uint64_t(0);
  for (int type = 0; type < 5; ++type) {
    std::uint8_t* f = scratch.data();
    std::uint64_t cost = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const int a = i >= bpp ? row[i - bpp] : 0, b = prior[i], c = i >= bpp ? prior[i - bpp] : 0;
      const int predictor = type == 0 ? 0 : type == 1 ? a : type == 2 ? b : type == 3 ? (a + b) / 2
                                                                                  : paeth(a, b, c);
      f[i] = static_cast<std::uint8_t>(row[i] - predictor);
      cost += f[i] < 128 ? f[i] : 256 - f[i];
    }
    if (cost < bestCost) {
      bestCost = cost;
      out[0] = static_cast<std::uint8_t>(type);
      std::copy(f, f + n, out + 1);
    }
  }
}

}  // namespace

std::string encodePng(const RgbImage& image, int compressionLevel) {
  if (image.width == 0 || image.height == 0 || image.width > 0x7fffffffu ||
      image.height > 0x7fffffffu) {
    throw InputError("PNG: image size " + std::to_string(image.width) + "x" +
                     std::to_string(image.height) + " cannot be written");
  }
  const std::size_t rowBytes = 3 * std::size_t(image.width);
  if (image.pixels.size() != rowBytes * image.height) {
    throw InputError("PNG: image has " + std::to_string(image.pixels.size()) + " bytes, expected " +
                     std::to_string(rowBytes * image.height));
  }
  std::string out("\x89PNG\r\n\x1a\n", 8);
  unsigned char header[13] = {};
  for (int k = 0; k < 4; ++k) {
    header[k] = static_cast<unsigned char>(image.width >> (24 - 8 * k));
    header[4 + k] = static_cast<unsigned char>(image.height >> (24 - 8 * k));
  }
  header[8] = 8;  // bit depth
  header[9] = 2;  // colour type: RGB (compression, filter, interlace: 0)
  appendChunk(out, "IHDR", header, sizeof header);

  z_stream z{};
  if (deflateInit(&z, compressionLevel) != Z_OK) throw IoError("PNG: cannot start zlib compression");
  std::vector<unsigned char> idat(kIdatBytes);
  z.next_out = idat.data();
  z.avail_out = static_cast<uInt>(idat.size());
  auto flushIdat = [&] {
    const std::size_t used = idat.size() - z.avail_out;
    if (used) appendChunk(out, "IDAT", idat.data(), used);
    z.next_out = idat.data();
    z.avail_out = static_cast<uInt>(idat.size());
  };
  const std::vector<std::uint8_t> zeros(rowBytes, 0);
  std::vector<std::uint8_t> filtered(1 + rowBytes), scratch(rowBytes);
  for (std::uint32_t y = 0; y <= image.height; ++y) {
    const bool finish = y == image.height;
    if (!finish) {
      const std::uint8_t* row = &image.pixels[y * rowBytes];
      filterRow(row, y ? row - rowBytes : zeros.data(), rowBytes, scratch, filtered.data());
    }
    z.next_in = finish ? nullptr : filtered.data();
    z.avail_in = finish ? 0 : static_cast<uInt>(filtered.size());
    for (;;) {
      const int status = deflate(&z, finish ? Z_FINISH : Z_NO_FLUSH);
      if (status == Z_STREAM_END) break;
      if (status != Z_OK && status != Z_BUF_ERROR) {
        deflateEnd(&z);
        throw IoError("PNG: zlib compression failed");
      }
      if (z.avail_out == 0) {
        flushIdat();
      } else if (z.avail_in == 0 && !finish) {
        break;
      }
    }
  }
  flushIdat();
  deflateEnd(&z);
  appendChunk(out, "IEND", nullptr, 0);
  return out;
}

void writePng(const std::string& path, const RgbImage& image) {
  const std::string bytes = encodePng(image);
  AtomicFile file(path);
  file.write(bytes);
  file.commit();
}

void writePng(AtomicFile& file, const RgbImage& image) { file.write(encodePng(image)); }

}  // namespace seamvox
