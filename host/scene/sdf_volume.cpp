// SDF grids from .vol files and from procedural shapes.
#include "scene/sdf_volume.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

namespace wt {

glm::dmat4 SdfVolume::latticeToObject() const {
  const glm::dvec3 edge = (hi - lo) / glm::dvec3(cells);
  return glm::scale(glm::translate(glm::dmat4(1.0), lo), edge);
}

double sdfShapeDistance(SdfShape shape, const SdfShapeParams& k, glm::dvec3 p) {
  switch (shape) {
    case SdfShape::kSphere:
      return glm::length(p) - k.radius;
    case SdfShape::kTorus: {
      const glm::dvec2 q(glm::length(glm::dvec2(p.x, p.z)) - k.radius, p.y);
      return glm::length(q) - k.minorRadius;
    }
    case SdfShape::kBox: {
      const glm::dvec3 q = glm::abs(p) - glm::dvec3(k.halfSize);
      return glm::length(glm::max(q, glm::dvec3(0.0))) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
    }
    case SdfShape::kNoisySphere: {
      // a few products of sines: smooth, deterministic, no table to ship
      const glm::dvec3 f = k.frequency * p;
      const double n = std::sin(f.x) * std::sin(f.y + 1.3) * std::sin(f.z + 2.1) +
                       0.5 * std::sin(2.1 * f.x + 0.7) * std::sin(1.9 * f.y + 2.9) * std::sin(2.3 * f.z + 0.4);
      return glm::length(p) - k.radius - k.amplitude * n / 1.5;
    }
  }
  return 0.0;
}

SdfVolume makeSdfShape(SdfShape shape, const SdfShapeParams& params, std::uint32_t resolution) {
  SdfVolume v;
  v.cells = glm::uvec3(resolution);
  v.lo = glm::dvec3(-1.0);
  v.hi = glm::dvec3(1.0);
  const std::size_t n = resolution + 1;
  const double edge = 2.0 / resolution;
  v.values.resize(n * n * n);
  for (std::size_t z = 0; z < n; ++z)
    for (std::size_t y = 0; y < n; ++y)
      for (std::size_t x = 0; x < n; ++x) {
        const glm::dvec3 p = glm::dvec3(-1.0) + edge * glm::dvec3(double(x), double(y), double(z));
        v.values[x + n * (y + n * z)] = float(sdfShapeDistance(shape, params, p) / edge);
      }
  return v;
}

namespace {

constexpr std::size_t kVolHeaderBytes = 48;  // "VOL", version, encoding, 3 sizes, channels, 6 floats

std::int32_t readInt(const unsigned char* p) {
  std::int32_t v;
  std::memcpy(&v, p, 4);
  return v;
}
float readFloat(const unsigned char* p) {
  float v;
  std::memcpy(&v, p, 4);
  return v;
}

/// The values from the box's units to voxel units (over the shortest cell
/// edge), refusing a NaN or infinite one by its index and corner.
template <typename Fail>
void toVoxelUnits(SdfVolume& v, Fail&& fail) {
  const glm::dvec3 edge = (v.hi - v.lo) / glm::dvec3(v.cells);
  const double unit = std::min(edge.x, std::min(edge.y, edge.z));
  const std::size_t nx = v.cells.x + 1, ny = v.cells.y + 1;
  for (std::size_t i = 0; i < v.values.size(); ++i) {
    if (!std::isfinite(v.values[i])) {
      const std::size_t x = i % nx, y = (i / nx) % ny, z = i / (nx * ny);
      fail("value " + std::to_string(i) + " (x " + std::to_string(x) + ", y " + std::to_string(y) + ", z " +
           std::to_string(z) + ") is " + (std::isnan(v.values[i]) ? "NaN" : "infinite"));
    }
    v.values[i] = float(double(v.values[i]) / unit);
  }
}

}  // namespace

SdfVolume loadVolFile(const std::string& path, const std::string& name) {
  auto fail = [&](const std::string& problem) { throw SceneError(name + ": " + problem); };
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("cannot open " + path);
  unsigned char h[kVolHeaderBytes];
  in.read(reinterpret_cast<char*>(h), kVolHeaderBytes);
  if (in.gcount() < 3 || std::memcmp(h, "VOL", 3) != 0) fail("not a .vol grid (the file does not start with \"VOL\")");
  if (std::size_t(in.gcount()) < kVolHeaderBytes)
    fail("truncated: the header takes 48 bytes, the file has " + std::to_string(in.gcount()));
  if (h[3] != 3) fail("version " + std::to_string(int(h[3])) + " is not supported (only version 3)");
  const std::int32_t encoding = readInt(h + 4);
  if (encoding != 1)
    fail("encoding " + std::to_string(encoding) + " is not supported (only 1, float32)");
  const std::int32_t res[3] = {readInt(h + 8), readInt(h + 12), readInt(h + 16)};
  const std::int32_t channels = readInt(h + 20);
  if (channels != 1) fail("has " + std::to_string(channels) + " channels; a signed distance grid has 1");
  for (int a = 0; a < 3; ++a)
    if (res[a] < 2 || res[a] > std::int32_t(kSdfMaxCells) + 1)
      fail(std::string("resolution ") + "xyz"[a] + " is " + std::to_string(res[a]) + " (must be 2 .. " +
           std::to_string(kSdfMaxCells + 1) + " corners)");
  SdfVolume v;
  for (int a = 0; a < 3; ++a) {
    v.lo[a] = readFloat(h + 24 + 4 * a);
    v.hi[a] = readFloat(h + 36 + 4 * a);
    if (!(v.hi[a] > v.lo[a]) || !std::isfinite(v.hi[a] - v.lo[a]))
      fail(std::string("the bounding box is empty or not finite along ") + "xyz"[a]);
  }
  v.cells = glm::uvec3(res[0] - 1, res[1] - 1, res[2] - 1);
  const std::size_t count = std::size_t(res[0]) * res[1] * res[2];
  v.values.resize(count);
  in.read(reinterpret_cast<char*>(v.values.data()), std::streamsize(count * sizeof(float)));
  if (std::size_t(in.gcount()) != count * sizeof(float))
    fail("truncated: " + std::to_string(res[0]) + " x " + std::to_string(res[1]) + " x " + std::to_string(res[2]) +
         " values take " + std::to_string(count * sizeof(float)) + " bytes after the header, the file has " +
         std::to_string(in.gcount()));
  toVoxelUnits(v, fail);
  return v;
}

SdfVolume loadRawSdf(const std::string& path, const std::string& name, glm::uvec3 cells, glm::dvec3 lo, glm::dvec3 hi) {
  auto fail = [&](const std::string& problem) { throw SceneError(name + ": " + problem); };
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) fail("cannot open " + path);
  const auto size = std::uint64_t(in.tellg());
  SdfVolume v;
  v.cells = cells;
  v.lo = lo;
  v.hi = hi;
  const std::uint64_t count = std::uint64_t(cells.x + 1) * (cells.y + 1) * (cells.z + 1);
  if (size != count * sizeof(float))
    fail("has " + std::to_string(size) + " bytes; " + std::to_string(cells.x + 1) + " x " + std::to_string(cells.y + 1) +
         " x " + std::to_string(cells.z + 1) + " float32 corner values take " + std::to_string(count * sizeof(float)));
  in.seekg(0);
  v.values.resize(count);
  in.read(reinterpret_cast<char*>(v.values.data()), std::streamsize(count * sizeof(float)));
  if (std::uint64_t(in.gcount()) != count * sizeof(float)) fail("cannot read " + path);
  toVoxelUnits(v, fail);
  return v;
}

void writeVolFile(const std::string& path, glm::uvec3 corners, const std::vector<float>& values, glm::dvec3 lo,
                  glm::dvec3 hi) {
  std::ofstream out(path, std::ios::binary);
  const std::int32_t header[6] = {1, std::int32_t(corners.x), std::int32_t(corners.y), std::int32_t(corners.z), 1, 0};
  out.write("VOL\3", 4);
  out.write(reinterpret_cast<const char*>(header), 5 * 4);
  const float box[6] = {float(lo.x), float(lo.y), float(lo.z), float(hi.x), float(hi.y), float(hi.z)};
  out.write(reinterpret_cast<const char*>(box), sizeof(box));
  out.write(reinterpret_cast<const char*>(values.data()), std::streamsize(values.size() * sizeof(float)));
  if (!out) throw SceneError(path + ": cannot write");
}

std::string sdfSurfaceProblem(const std::vector<float>& values) {
  bool inside = false, outside = false;
  for (float v : values) {
    inside |= v < 0.0f;
    outside |= v >= 0.0f;
  }
  if (inside && outside) return "";
  return std::string("has no surface: every value is ") + (inside ? "negative (all inside)" : "positive or zero (all outside)");
}

}  // namespace wt
