// Image output: OpenEXR (32-bit float RGB, linear radiance) and PNG (8-bit
// sRGB), chosen by extension. Files are written under a temporary name and
// renamed, so a failed write never destroys an earlier image.
#pragma once

#include "render/renderer.h"

#include <filesystem>
#include <stdexcept>
#include <string>

namespace wt {

struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class ImageFormat { Exr, Png };

/// The format for a path's extension (.exr, .png, any case). Throws OutputError.
ImageFormat imageFormatFor(const std::filesystem::path& path);

/// Check before rendering that the path has a known extension and that its
/// folder exists and accepts a new file. Throws OutputError naming the path.
void checkWritable(const std::filesystem::path& path);

/// Write the image in the path's format. Throws OutputError.
void writeImage(const std::filesystem::path& path, const Image& image);

/// Read an EXR (tests, reference images): RGB floats, and when the file has
/// wavetrace's mean_variance layer, the variance of each pixel's mean in
/// rgbVariance with samples = 1.
Image readExr(const std::filesystem::path& path);

}  // namespace wt
