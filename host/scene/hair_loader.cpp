// .hair and PLY strand readers. Every count is checked against the bytes
// that are there before anything is allocated, so a truncated or lying
// header is an error, never a crash or a huge allocation.
#include "scene/hair_loader.h"

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

std::vector<std::uint8_t> readFile(const std::string& path, const std::string& name) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    fail(name, "cannot open " + path + (fs::exists(path, ec) ? " (not a regular file)" : " (no such file)"));
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(name, "cannot open " + path);
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) fail(name, "cannot read " + path);
  return bytes;
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

// PLY

enum class PlyFormat { kAscii, kLittle, kBig };

struct PlyProperty {
  std::string name;
  std::string type;       ///< scalar type, or the item type of a list
  std::string countType;  ///< list: the count's type; "" for a scalar
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  int headerLine = 0;
};

/// Bytes of a PLY scalar type; 0 for an unknown name.
std::size_t plyTypeSize(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32" || type == "float" || type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

bool plyIsFloat(const std::string& type) {
  return type == "float" || type == "float32" || type == "double" || type == "float64";
}
bool plyIsSigned(const std::string& type) {
  return type == "char" || type == "int8" || type == "short" || type == "int16" || type == "int" || type == "int32";
}

/// Reads the body of a PLY file value by value.
class PlyReader {
 public:
  PlyReader(std::span<const std::uint8_t> bytes, std::size_t offset, PlyFormat format, const std::string& name)
      : m_bytes(bytes), m_pos(offset), m_format(format), m_name(name) {}

  /// One value of `type`, as a double; `where` names it in errors.
  double value(const std::string& type, const std::string& where) {
    if (m_format == PlyFormat::kAscii) return asciiValue(type, where);
    const std::size_t size = plyTypeSize(type);
    if (m_bytes.size() - m_pos < size)
      fail(m_name, where + ": the file ends at byte " + std::to_string(m_bytes.size()) + " (truncated)");
    std::uint8_t raw[8];
    std::memcpy(raw, m_bytes.data() + m_pos, size);
    m_pos += size;
    if (m_format == PlyFormat::kBig) std::reverse(raw, raw + size);
    std::uint64_t bits = 0;
    for (std::size_t k = 0; k < size; ++k) bits |= std::uint64_t(raw[k]) << (8 * k);
    if (plyIsFloat(type)) return size == 4 ? double(std::bit_cast<float>(std::uint32_t(bits))) : std::bit_cast<double>(bits);
    if (plyIsSigned(type)) {
      const int shift = int(64 - 8 * size);
      return double(std::int64_t(bits << shift) >> shift);
    }
    return double(bits);
  }

  /// Bytes left, for checks of binary counts before they are read.
  std::size_t remaining() const { return m_bytes.size() - m_pos; }

 private:
  double asciiValue(const std::string& type, const std::string& where) {
    while (m_pos < m_bytes.size() && std::isspace(m_bytes[m_pos])) ++m_pos;
    const std::size_t start = m_pos;
    while (m_pos < m_bytes.size() && !std::isspace(m_bytes[m_pos])) ++m_pos;
    if (start == m_pos) fail(m_name, where + ": the file ends before this value (truncated)");
    const char* first = reinterpret_cast<const char*>(m_bytes.data() + start);
    const char* last = reinterpret_cast<const char*>(m_bytes.data() + m_pos);
    const std::string token(first, last);
    double v = 0.0;
    std::size_t used = 0;
    try {
      v = std::stod(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    // "nan" and "inf" parse: the caller checks finiteness where it matters
    if (used != token.size()) fail(m_name, where + ": not a number: \"" + token.substr(0, 32) + "\"");
    if (!plyIsFloat(type) && v != std::floor(v))
      fail(m_name, where + ": must be an integer (" + type + "), got " + token.substr(0, 32));
    return v;
  }

  std::span<const std::uint8_t> m_bytes;
  std::size_t m_pos;
  PlyFormat m_format;
  const std::string& m_name;
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
  // the header: lines up to end_header
  std::size_t pos = 0;
  int lineNumber = 0;
  auto nextLine = [&](std::string& line) {
    if (pos >= bytes.size()) return false;
    const std::size_t start = pos;
    while (pos < bytes.size() && bytes[pos] != '\n') ++pos;
    line.assign(reinterpret_cast<const char*>(bytes.data() + start), pos - start);
    if (pos < bytes.size()) ++pos;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    ++lineNumber;
    return true;
  };
  std::string line;
  if (!nextLine(line) || line != "ply") fail(name, "line 1: not a PLY file (it does not begin with \"ply\")");
  std::optional<PlyFormat> format;
  std::vector<PlyElement> elements;
  bool ended = false;
  while (!ended && nextLine(line)) {
    const std::string where = "line " + std::to_string(lineNumber);
    if (line.size() > 4096) fail(name, where + ": header line too long");
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      ended = true;
    } else if (keyword == "format") {
      std::string kind, version;
      words >> kind >> version;
      if (kind == "ascii") format = PlyFormat::kAscii;
      else if (kind == "binary_little_endian") format = PlyFormat::kLittle;
      else if (kind == "binary_big_endian") format = PlyFormat::kBig;
      else fail(name, where + ": unknown format \"" + kind.substr(0, 32) + "\"");
    } else if (keyword == "element") {
      PlyElement e;
      std::string count;
      words >> e.name >> count;
      std::uint64_t n = 0;
      const auto [end, ec] = std::from_chars(count.data(), count.data() + count.size(), n);
      if (e.name.empty() || ec != std::errc() || end != count.data() + count.size())
        fail(name, where + ": expected \"element <name> <count>\"");
      e.count = n;
      e.headerLine = lineNumber;
      elements.push_back(std::move(e));
    } else if (keyword == "property") {
      if (elements.empty()) fail(name, where + ": a property before any element");
      PlyProperty p;
      std::string type;
      words >> type;
      if (type == "list") {
        words >> p.countType >> p.type >> p.name;
        if (plyTypeSize(p.countType) == 0 || plyIsFloat(p.countType))
          fail(name, where + ": bad list count type \"" + p.countType.substr(0, 32) + "\"");
      } else {
        p.type = type;
        words >> p.name;
      }
      if (plyTypeSize(p.type) == 0) fail(name, where + ": unknown property type \"" + p.type.substr(0, 32) + "\"");
      if (p.name.empty()) fail(name, where + ": a property needs a name");
      elements.back().properties.push_back(p);
    } else {
      fail(name, where + ": unknown header keyword \"" + keyword.substr(0, 32) + "\"");
    }
  }
  if (!ended) fail(name, "the header has no end_header line (truncated, or not a PLY file)");
  if (!format) fail(name, "the header has no format line");

  // the elements we need, and where their properties are
  const PlyElement* vertex = nullptr;
  const PlyElement* strand = nullptr;
  for (const PlyElement& e : elements) {
    if (e.name == "vertex") vertex = &e;
    if (e.name == "strand") strand = &e;
  }
  if (!vertex) fail(name, "no \"vertex\" element");
  if (!strand)
    fail(name, "no \"strand\" element: strands need their segment counts (an element \"strand\" with one property, "
               "e.g. \"property ushort nsegs\")");
  auto find = [&](const PlyElement& e, const char* prop) -> int {
    for (std::size_t k = 0; k < e.properties.size(); ++k)
      if (e.properties[k].name == prop && e.properties[k].countType.empty()) return int(k);
    return -1;
  };
  const int px = find(*vertex, "x"), py = find(*vertex, "y"), pz = find(*vertex, "z");
  if (px < 0 || py < 0 || pz < 0) fail(name, "line " + std::to_string(vertex->headerLine) + ": vertex needs scalar x, y and z");
  const int pr = find(*vertex, "radius");
  int segs = -1;
  for (std::size_t k = 0; k < strand->properties.size(); ++k)
    if (strand->properties[k].countType.empty() && segs < 0) segs = int(k);
  if (segs < 0 || strand->properties.size() != 1)
    fail(name, "line " + std::to_string(strand->headerLine) + ": \"strand\" must have exactly one scalar property (its segment count)");
  if (vertex->count > kMaxPoints)
    fail(name, "vertex: " + std::to_string(vertex->count) + " points, more than the " + std::to_string(kMaxPoints) +
                   " supported");

  StrandSet set;
  set.hasRadius = pr >= 0;
  PlyReader reader(bytes, pos, *format, name);
  for (const PlyElement& e : elements) {
    const bool isVertex = &e == vertex, isStrand = &e == strand;
    // a binary element of scalars cannot hold more items than the bytes left
    if (*format != PlyFormat::kAscii) {
      std::size_t least = 0;
      for (const PlyProperty& p : e.properties) least += p.countType.empty() ? plyTypeSize(p.type) : plyTypeSize(p.countType);
      if (least > 0 && e.count > reader.remaining() / least)
        fail(name, e.name + ": " + std::to_string(e.count) + " items do not fit in the " +
                       std::to_string(reader.remaining()) + " bytes left (truncated, or the count is wrong)");
    } else if (e.count > reader.remaining()) {
      fail(name, e.name + ": " + std::to_string(e.count) + " items do not fit in the " +
                     std::to_string(reader.remaining()) + " bytes left (truncated, or the count is wrong)");
    }
    if (isVertex) set.points.resize(e.count);
    if (isStrand) set.counts.resize(e.count);
    for (std::uint64_t i = 0; i < e.count; ++i) {
      const std::string where = e.name + " " + std::to_string(i);
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        const PlyProperty& p = e.properties[k];
        if (!p.countType.empty()) {
          const double n = reader.value(p.countType, where + ", " + p.name);
          if (!(n >= 0.0) || n > double(reader.remaining()))
            fail(name, where + ", " + p.name + ": list of " + std::to_string(n) + " items (truncated, or a bad count)");
          for (std::uint64_t j = 0; j < std::uint64_t(n); ++j) reader.value(p.type, where + ", " + p.name);
          continue;
        }
        const double v = reader.value(p.type, where + ", " + p.name);
        if (isVertex) {
          if (int(k) == px) set.points[i].x = float(v);
          else if (int(k) == py) set.points[i].y = float(v);
          else if (int(k) == pz) set.points[i].z = float(v);
          else if (int(k) == pr) set.points[i].w = float(v);
        } else if (isStrand) {
          if (!(v >= 0.0 && v < double(kMaxPoints)))
            fail(name, "strand " + std::to_string(i) + ": segment count " + std::to_string(v) + " out of range");
          set.counts[i] = std::uint32_t(v) + 1;
        }
      }
    }
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
  const std::vector<std::uint8_t> bytes = readFile(path, name);
  return loadHairFromMemory(bytes, name);
}

StrandSet loadPlyStrands(const std::string& path) {
  const std::string name = fileName(path);
  const std::vector<std::uint8_t> bytes = readFile(path, name);
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
