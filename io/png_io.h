#pragma once
/// PNG output of rendered pictures: 8-bit RGB, no interlacing, zlib-compressed rows.
#include <string>

#include "core/synth/render.h"

namespace seamvox {

class AtomicFile;

/// The complete PNG file (signature, IHDR, IDAT chunks, IEND) of an image. Each row is filtered
/// with the PNG filter that makes it smallest by the usual sum-of-differences estimate.
/// Throws InputError for an empty image or a pixel array of the wrong size.
std::string encodePng(const RgbImage& image, int compressionLevel = 6);

/// Writes encodePng(image) to path atomically (io/atomic_file.h). Throws IoError naming the path.
void writePng(const std::string& path, const RgbImage& image);
/// The same into an open output (e.g. one of an OutputSet); the caller commits.
void writePng(AtomicFile& file, const RgbImage& image);

}  // namespace seamvox
