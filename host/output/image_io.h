// Image output: OpenEXR (32-bit float RGB, linear radiance) and PNG (8-bit
// sRGB), chosen by extension. Files are written under a temporary name and
// renamed, so a failed write never destroys an earlier image.
#pragma once

#include "render/renderer.h"

#include <cstdint>
#include <filesystem>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace wt {

struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class ImageFormat { Exr, Png };

/// A hidden temporary beside `path` (same file system, so a rename onto `path`
/// is atomic), named after this process (".name.tmp<pid>.<n>").
std::filesystem::path temporaryPathFor(const std::filesystem::path& path);
/// Remove `path`'s temporaries whose process no longer runs: a writer killed
/// mid-write leaves one, and nothing else would ever remove it.
void removeStaleTemporaries(const std::filesystem::path& path);

/// The format for a path's extension (.exr, .png, any case). Throws OutputError.
ImageFormat imageFormatFor(const std::filesystem::path& path);

/// Check before rendering that the path has a known extension and that its
/// folder exists and accepts a new file. Throws OutputError naming the path.
void checkWritable(const std::filesystem::path& path);

/// The AOVs `render --aov` writes (docs/command-line.md: --aov), each an
/// EXR layer of that name (variance: the mean_variance layer every EXR has).
enum class Aov : std::uint8_t { Albedo, Normal, Depth, Position, Material, Instance, Variance };
inline constexpr Aov kAllAovs[] = {Aov::Albedo,   Aov::Normal,   Aov::Depth,   Aov::Position,
                                   Aov::Material, Aov::Instance, Aov::Variance};
/// "albedo", "normal", ... (the layer's name).
std::string_view aovName(Aov aov);
/// A comma-separated list of names, or "all"; each once, in kAllAovs' order.
/// Throws std::invalid_argument naming an unknown or empty entry.
std::vector<Aov> parseAovList(std::string_view list);

/// The EXR header attribute (int) holding image.samplesDone, where known.
inline constexpr const char* kExrSamplesAttribute = "wavetraceSamples";

/// Write the image in the path's format; an EXR gets the layers of `aovs`
/// (which need image.aovs, else OutputError; a PNG holds none) and the
/// sample count (kExrSamplesAttribute). Throws OutputError.
void writeImage(const std::filesystem::path& path, const Image& image, std::span<const Aov> aovs = {});

/// One AOV as an EXR of its own, its channels without the layer's prefix
/// (albedo, normal, position, variance: R, G, B; depth: Z; material: id;
/// instance: id, primitive). Throws OutputError.
void writeAovImage(const std::filesystem::path& path, const Image& image, Aov aov);

/// Read an EXR (tests, reference images): RGB floats, and when the file has
/// wavetrace's mean_variance layer, the variance of each pixel's mean in
/// rgbVariance with samples = 1; samplesDone from kExrSamplesAttribute.
Image readExr(const std::filesystem::path& path);

}  // namespace wt
