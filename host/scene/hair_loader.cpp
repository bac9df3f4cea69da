// .hair and PLY strand readers (PLY parsing: scene/ply.h). Every count is
// checked against the bytes that are there before anything is allocated, so
// a truncated or lying header is an error, never a crash or a huge allocation.
#include "scene/hair_loader.h"

#include "scene/ply.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <sstream>

namespace wt {
namespace {

namespace fs = std::filesystem;

/// Strands the traversal can index (28-bit primitive ids, host/geometry).
constexpr std::uint64_t kMaxPoints = std::uint64_t(1) << 28;

[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw SceneError(name + ": " + problem);
}

std::string formatFloat(float v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", double(v));
  return buffer;
}

std::string fileName(const std::string& path) {
  const std::string name = fs::path(path).filename().string();
  return name.empty() ? path : name;
}

/// Little-endian reads at known-valid offsets.
std::uint32_t readU32(const std::uint8_t* p) {
  return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[3]) << 24;
}
float readF32(const std::uint8_t* p) { return std::bit_cast<float>(readU32(p)); }

void checkPoint(const glm::vec3& p, const std::string& name, const std::string& where) {
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(p[k])) fail(name, where + ": coordinate is not finite (" + formatFloat(p[k]) + ")");
}

/// "strand 7, point 3" for point i of the file.
std::string strandPoint(const std::vector<std::uint32_t>& counts, std::size_t i) {
  std::size_t strand = 0;
  while (strand < counts.size() && i >= counts[strand]) i -= counts[strand++];
  return "strand " + std::to_string(strand) + ", point " + std::to_string(i);
}

// .hair

constexpr std::size_t kHairHeader = 128;
enum HairArrays : std::uint32_t {
  kHairSegments = 1,
  kHairPoints = 2,
  kHairThickness = 4,
  kHairTransparency = 8,
  kHairColors = 16,
};

}  // namespace

StrandSet loadHairFromMemory(std::span<const std::uint8_t> bytes, const std::string& name) {
  if (bytes.size() < kHairHeader)
    fail(name, "header: the file has " + std::to_string(bytes.size()) + " bytes, a .hair header needs 128");
  if (std::memcmp(bytes.data(), "HAIR", 4) != 0) fail(name, "header: not a .hair file (it does not begin with HAIR)");
  const std::uint32_t strands = readU32(&bytes[4]), pointCount = readU32(&bytes[8]), arrays = readU32(&bytes[12]);
  const std::uint32_t defaultSegments = readU32(&bytes[16]);
  const float defaultThickness = readF32(&bytes[20]);
  if (!(arrays & kHairPoints)) fail(name, "header: the file has no points array (flag 2 is not set)");
  if (pointCount > kMaxPoints)
    fail(name, "header: " + std::to_string(pointCount) + " points, more than the " + std::to_string(kMaxPoints) +
                   " supported");

  // every array's size, checked against the file before anything is read
  const std::uint64_t segmentBytes = (arrays & kHairSegments) ? 2ull * strands : 0;
  struct Array {
    const char* what;
    std::uint32_t flag;
    std::uint64_t bytes;
  };
  const Array layout[] = {{"segments", kHairSegments, segmentBytes},
                          {"points", kHairPoints, 12ull * pointCount},
                          {"thickness", kHairThickness, 4ull * pointCount},
                          {"transparency", kHairTransparency, 4ull * pointCount},
                          {"colors", kHairColors, 12ull * pointCount}};
  std::uint64_t offset = kHairHeader, pointsAt = 0, thicknessAt = 0;
  for (const Array& a : layout) {
    if (!(arrays & a.flag)) continue;
    if (offset + a.bytes > bytes.size())
      fail(name, std::string("the file ends at byte ") + std::to_string(bytes.size()) + ", inside the " + a.what +
                     " array (bytes " + std::to_string(offset) + " to " + std::to_string(offset + a.bytes) +
                     "): truncated, or the header's counts are wrong");
    if (a.flag == kHairPoints) pointsAt = offset;
    if (a.flag == kHairThickness) thicknessAt = offset;
    offset += a.bytes;
  }

  StrandSet set;
  set.hasRadius = true;
  std::uint64_t needed = 0;
  if (arrays & kHairSegments) {
    set.counts.resize(strands);
    for (std::uint32_t s = 0; s < strands; ++s) {
      set.counts[s] = std::uint32_t(bytes[kHairHeader + 2 * s]) | std::uint32_t(bytes[kHairHeader + 2 * s + 1]) << 8;
      set.counts[s] += 1;
      needed += set.counts[s];
    }
  } else {
    needed = std::uint64_t(strands) * (std::uint64_t(defaultSegments) + 1);
    if (needed == pointCount) set.counts.assign(strands, defaultSegments + 1);
  }
  if (needed != pointCount)
    fail(name, "header: the strands' segments need " + std::to_string(needed) + " points, the header says " +
                   std::to_string(pointCount));
  if (!(arrays & kHairThickness) && !(std::isfinite(defaultThickness) && defaultThickness >= 0.0f))
    fail(name, "header: the default thickness must be finite and >= 0, got " + formatFloat(defaultThickness));

  set.points.resize(pointCount);
  for (std::uint32_t i = 0; i < pointCount; ++i) {
    const std::uint8_t* p = &bytes[pointsAt + 12ull * i];
    const glm::vec3 xyz(readF32(p), readF32(p + 4), readF32(p + 8));
    float thickness = defaultThickness;
    if (arrays & kHairThickness) thickness = readF32(&bytes[thicknessAt + 4ull * i]);
    if (!std::isfinite(xyz.x) || !std::isfinite(xyz.y) || !std::isfinite(xyz.z))
      checkPoint(xyz, name, strandPoint(set.counts, i));
    if (!(std::isfinite(thickness) && thickness >= 0.0f))
      fail(name, strandPoint(set.counts, i) + ": thickness must be finite and >= 0, got " + formatFloat(thickness));
    set.points[i] = glm::vec4(xyz, 0.5f * thickness);
  }
  return set;
}

StrandSet loadPlyStrandsFromMemory(std::span<const std::uint8_t> bytes, const std::string& name) {
  const auto check = [&](const PlyData& data) {
    const PlyData::Element* vertex = data.find("vertex");
    const PlyData::Element* strand = data.find("strand");
    if (!vertex) fail(name, "no \"vertex\" element");
    if (!strand)
      fail(name, "no \"strand\" element: strands need their segment counts (an element \"strand\" with one property, "
                 "e.g. \"property ushort nsegs\")");
    if (!vertex->scalar("x") || !vertex->scalar("y") || !vertex->scalar("z"))
      fail(name, "line " + std::to_string(vertex->headerLine) + ": vertex needs scalar x, y and z");
    if (strand->properties.size() != 1 || strand->properties[0].list)
      fail(name, "line " + std::to_string(strand->headerLine) +
                     ": \"strand\" must have exactly one scalar property (its segment count)");
    if (vertex->count > kMaxPoints)
      fail(name, "vertex: " + std::to_string(vertex->count) + " points, more than the " + std::to_string(kMaxPoints) +
                     " supported");
  };
  const PlyData data = readPly(bytes, name, check);
  const PlyData::Element* vertex = data.find("vertex");
  const PlyData::Element* strand = data.find("strand");
  const PlyData::Property *px = vertex->scalar("x"), *py = vertex->scalar("y"), *pz = vertex->scalar("z");
  const PlyData::Property* pr = vertex->scalar("radius");

  StrandSet set;
  set.hasRadius = pr != nullptr;
  set.points.resize(vertex->count);
  for (std::size_t i = 0; i < set.points.size(); ++i)
    set.points[i] = glm::vec4(float(px->values[i]), float(py->values[i]), float(pz->values[i]), pr ? float(pr->values[i]) : 0.0f);
  const std::vector<double>& segments = strand->properties[0].values;
  set.counts.resize(strand->count);
  for (std::size_t i = 0; i < set.counts.size(); ++i) {
    if (!(segments[i] >= 0.0 && segments[i] < double(kMaxPoints)))
      fail(name, "strand " + std::to_string(i) + ": segment count " + std::to_string(segments[i]) + " out of range");
    set.counts[i] = std::uint32_t(segments[i]) + 1;
  }

  std::uint64_t needed = 0;
  for (std::uint32_t c : set.counts) needed += c;
  if (needed != set.points.size())
    fail(name, "strand: the strands' segments need " + std::to_string(needed) + " points, there are " +
                   std::to_string(set.points.size()) + " vertices");
  for (std::size_t i = 0; i < set.points.size(); ++i) {
    const glm::vec4& p = set.points[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      checkPoint(glm::vec3(p), name, "vertex " + std::to_string(i) + " (" + strandPoint(set.counts, i) + ")");
    if (!(std::isfinite(p.w) && p.w >= 0.0f))
      fail(name, "vertex " + std::to_string(i) + " (" + strandPoint(set.counts, i) +
                     "): radius must be finite and >= 0, got " + formatFloat(p.w));
  }
  return set;
}

StrandSet loadHairFile(const std::string& path) {
  const std::string name = fileName(path);
  const std::vector<std::uint8_t> bytes = readFileBytes(path, name);
  return loadHairFromMemory(bytes, name);
}

StrandSet loadPlyStrands(const std::string& path) {
  const std::string name = fileName(path);
  const std::vector<std::uint8_t> bytes = readFileBytes(path, name);
  return loadPlyStrandsFromMemory(bytes, name);
}

StrandSet loadStrands(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".hair") return loadHairFile(path);
  if (ext == ".ply") return loadPlyStrands(path);
  throw SceneError(fileName(path) + ": not a strand file (expected .hair or .ply)");
}

}  // namespace wt
