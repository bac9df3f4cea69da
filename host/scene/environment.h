// Environment lighting on the host: equirectangular maps read from Radiance
// .hdr (stb_image) and OpenEXR files, the constant environment, and the
// luminance x sin(theta) distribution the kernels sample. The direction
// convention (OpenEXR's latitude-longitude map, +Y up) is written at the top
// of kernels/lights/environment.cl.
#pragma once

#include "shared/environment.h"
#include "shared/types.h"

#include <glm/glm.hpp>

#include <filesystem>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace wt {

/// A map that cannot be read or used. what() starts with the file's path,
/// e.g. "sky.hdr: truncated: scanline 17 of 512 ends at byte 40213".
struct EnvironmentError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// The environment as the kernels read it (kernels/shared/environment.h).
struct Environment {
  WtEnvironment header{};             ///< passed to kernels by value
  std::vector<WtVec4> texels;         ///< width * height linear RGB radiance before intensity, row 0 = +Y; w = 0. One black texel when constant.
  std::vector<float> marginalCdf;     ///< height + 1 entries, [0] = 0, [height] = 1
  std::vector<float> conditionalCdf;  ///< height rows of width + 1 entries, each [0] = 0, [width] = 1
  double meanLuminance = 0.0;         ///< (1 / 4 pi) x integral of luminance over the sphere, intensity applied (light power estimates)
  std::vector<std::string> warnings;  ///< what was repaired (e.g. clamped texels); each also printed once
  std::string sourceName;             ///< the file, or "constant"
};

/// What the kernels read besides the header, in upload order: texels,
/// marginal_cdf, conditional_cdf. Every span is non-empty (OpenCL has no
/// empty buffers) and stays valid while the Environment lives.
struct EnvironmentUpload {
  std::span<const WtVec4> texels;        ///< __global const float4*
  std::span<const float> marginalCdf;    ///< __global const float*
  std::span<const float> conditionalCdf; ///< __global const float*
};
EnvironmentUpload environmentUpload(const Environment& environment);

/// Read an equirectangular map: .hdr (Radiance RGBE) or .exr (R,G,B[,A] or
/// Y channels of any pixel type, scanline or tiled; mip-mapped files give
/// their level 0). `intensity` scales the radiance, `rotationDegrees` turns
/// the map about +Y (counter-clockwise seen from above). Negative and
/// non-finite values become 0, with one warning. Throws EnvironmentError.
Environment loadEnvironmentMap(const std::filesystem::path& path, float intensity = 1.0f,
                               float rotationDegrees = 0.0f);

/// The same, from a file's bytes in memory: `name`'s extension (.hdr or .exr)
/// picks the format and every message starts with `name`.
Environment loadEnvironmentMapFromMemory(std::span<const unsigned char> bytes, const std::string& name,
                                         float intensity = 1.0f, float rotationDegrees = 0.0f);

/// The same radiance from every direction (nits per channel).
Environment constantEnvironment(glm::vec3 radiance);

/// A map from linear RGB pixels, row-major from the top (+Y) row: repairs
/// bad values as loadEnvironmentMap does and builds the distribution. An
/// all-black map falls back to uniform sphere sampling (WT_ENV_MAP_UNIFORM).
Environment makeEnvironmentMap(int width, int height, std::vector<glm::vec3> rgb, float intensity,
                               float rotationDegrees, const std::string& sourceName);

}  // namespace wt
