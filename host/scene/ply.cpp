#include "scene/ply.h"

#include "scene/scene.h"

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

[[noreturn]] void fail(const std::string& name, const std::string& problem) { throw SceneError(name + ": " + problem); }

enum class PlyFormat { kAscii, kLittle, kBig };

/// Bytes of a PLY scalar type; 0 for an unknown name.
std::size_t typeSize(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32" || type == "float" || type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

bool isFloat(const std::string& type) {
  return type == "float" || type == "float32" || type == "double" || type == "float64";
}
bool isSigned(const std::string& type) {
  return type == "char" || type == "int8" || type == "short" || type == "int16" || type == "int" || type == "int32";
}

/// Reads the body of a PLY file value by value.
class BodyReader {
 public:
  BodyReader(std::span<const std::uint8_t> bytes, std::size_t offset, PlyFormat format, const std::string& name)
      : m_bytes(bytes), m_pos(offset), m_format(format), m_name(name) {}

  /// One value of `type`, as a double; `where` names it in errors.
  double value(const std::string& type, const std::string& where) {
    if (m_format == PlyFormat::kAscii) return asciiValue(type, where);
    const std::size_t size = typeSize(type);
    if (m_bytes.size() - m_pos < size)
      fail(m_name, where + ": the file ends at byte " + std::to_string(m_bytes.size()) + " (truncated)");
    std::uint8_t raw[8];
    std::memcpy(raw, m_bytes.data() + m_pos, size);
    m_pos += size;
    if (m_format == PlyFormat::kBig) std::reverse(raw, raw + size);
    std::uint64_t bits = 0;
    for (std::size_t k = 0; k < size; ++k) bits |= std::uint64_t(raw[k]) << (8 * k);
    if (isFloat(type)) return size == 4 ? double(std::bit_cast<float>(std::uint32_t(bits))) : std::bit_cast<double>(bits);
    if (isSigned(type)) {
      const int shift = int(64 - 8 * size);
      return double(std::int64_t(bits << shift) >> shift);
    }
    return double(bits);
  }

  /// Bytes left, for checks of counts before they are read.
  std::size_t remaining() const { return m_bytes.size() - m_pos; }

 private:
  double asciiValue(const std::string& type, const std::string& where) {
    while (m_pos < m_bytes.size() && std::isspace(m_bytes[m_pos])) ++m_pos;
    const std::size_t start = m_pos;
    while (m_pos < m_bytes.size() && !std::isspace(m_bytes[m_pos])) ++m_pos;
    if (start == m_pos) fail(m_name, where + ": the file ends before this value (truncated)");
    const std::string token(reinterpret_cast<const char*>(m_bytes.data() + start), m_pos - start);
    double v = 0.0;
    std::size_t used = 0;
    try {
      v = std::stod(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    // "nan" and "inf" parse: the caller checks finiteness where it matters
    if (used != token.size()) fail(m_name, where + ": not a number: \"" + token.substr(0, 32) + "\"");
    if (!isFloat(type) && v != std::floor(v))
      fail(m_name, where + ": must be an integer (" + type + "), got " + token.substr(0, 32));
    return v;
  }

  std::span<const std::uint8_t> m_bytes;
  std::size_t m_pos;
  PlyFormat m_format;
  const std::string& m_name;
};

std::string fileName(const std::string& path) {
  const std::string name = fs::path(path).filename().string();
  return name.empty() ? path : name;
}

}  // namespace

std::vector<std::uint8_t> readFileBytes(const std::string& path, const std::string& name) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    fail(name, "cannot open " + path + (fs::exists(path, ec) ? " (not a regular file)" : " (no such file)"));
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(name, "cannot open " + path);
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) fail(name, "cannot read " + path);
  return bytes;
}

const PlyData::Property* PlyData::Element::scalar(const std::string& property) const {
  for (const Property& p : properties)
    if (p.name == property && !p.list) return &p;
  return nullptr;
}

const PlyData::Property* PlyData::Element::list(const std::string& property) const {
  for (const Property& p : properties)
    if (p.name == property && p.list) return &p;
  return nullptr;
}

const PlyData::Element* PlyData::find(const std::string& element) const {
  for (const Element& e : elements)
    if (e.name == element) return &e;
  return nullptr;
}

PlyData readPly(std::span<const std::uint8_t> bytes, const std::string& name,
                const std::function<void(const PlyData&)>& checkHeader) {
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
  PlyData data;
  std::vector<std::vector<std::string>> listCounts;  // per element and property: a list's count type
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
      PlyData::Element e;
      std::string count;
      words >> e.name >> count;
      std::uint64_t n = 0;
      const auto [end, ec] = std::from_chars(count.data(), count.data() + count.size(), n);
      if (e.name.empty() || ec != std::errc() || end != count.data() + count.size())
        fail(name, where + ": expected \"element <name> <count>\"");
      e.count = n;
      e.headerLine = lineNumber;
      data.elements.push_back(std::move(e));
      listCounts.emplace_back();
    } else if (keyword == "property") {
      if (data.elements.empty()) fail(name, where + ": a property before any element");
      PlyData::Property p;
      std::string type, countType;
      words >> type;
      if (type == "list") {
        words >> countType >> p.type >> p.name;
        if (typeSize(countType) == 0 || isFloat(countType))
          fail(name, where + ": bad list count type \"" + countType.substr(0, 32) + "\"");
        p.list = true;
      } else {
        p.type = type;
        words >> p.name;
      }
      if (typeSize(p.type) == 0) fail(name, where + ": unknown property type \"" + p.type.substr(0, 32) + "\"");
      if (p.name.empty()) fail(name, where + ": a property needs a name");
      data.elements.back().properties.push_back(std::move(p));
      listCounts.back().push_back(countType);
    } else {
      fail(name, where + ": unknown header keyword \"" + keyword.substr(0, 32) + "\"");
    }
  }
  if (!ended) fail(name, "the header has no end_header line (truncated, or not a PLY file)");
  if (!format) fail(name, "the header has no format line");
  if (checkHeader) checkHeader(data);

  BodyReader reader(bytes, pos, *format, name);
  for (std::size_t ei = 0; ei < data.elements.size(); ++ei) {
    PlyData::Element& e = data.elements[ei];
    const std::vector<std::string>& counts = listCounts[ei];
    if (e.properties.empty()) continue;  // nothing to read, whatever the count
    // an element cannot hold more items than the bytes left allow
    std::size_t least = 1;
    if (*format != PlyFormat::kAscii) {
      least = 0;
      for (std::size_t k = 0; k < e.properties.size(); ++k)
        least += e.properties[k].list ? typeSize(counts[k]) : typeSize(e.properties[k].type);
    }
    if (least > 0 && e.count > reader.remaining() / least)
      fail(name, e.name + ": " + std::to_string(e.count) + " items do not fit in the " +
                     std::to_string(reader.remaining()) + " bytes left (truncated, or the count is wrong)");
    for (PlyData::Property& p : e.properties) {
      if (p.list) p.ends.reserve(e.count);
      else p.values.reserve(e.count);
    }
    for (std::uint64_t i = 0; i < e.count; ++i) {
      const std::string where = e.name + " " + std::to_string(i);
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        PlyData::Property& p = e.properties[k];
        if (p.list) {
          const double n = reader.value(counts[k], where + ", " + p.name);
          if (!(n >= 0.0) || n > double(reader.remaining()))
            fail(name, where + ", " + p.name + ": list of " + std::to_string(n) + " items (truncated, or a bad count)");
          for (std::uint64_t j = 0; j < std::uint64_t(n); ++j) p.values.push_back(reader.value(p.type, where + ", " + p.name));
          p.ends.push_back(p.values.size());
          continue;
        }
        p.values.push_back(reader.value(p.type, where + ", " + p.name));
      }
    }
  }
  return data;
}

PlyMesh readPlyMesh(std::span<const std::uint8_t> bytes, const std::string& name) {
  const auto check = [&](const PlyData& data) {
    const PlyData::Element* vertex = data.find("vertex");
    const PlyData::Element* face = data.find("face");
    if (!vertex) fail(name, "no \"vertex\" element");
    if (!face) fail(name, "no \"face\" element: a mesh needs its faces (a list \"vertex_indices\" per face)");
    if (!vertex->scalar("x") || !vertex->scalar("y") || !vertex->scalar("z"))
      fail(name, "line " + std::to_string(vertex->headerLine) + ": vertex needs scalar x, y and z");
    if (!face->list("vertex_indices") && !face->list("vertex_index"))
      fail(name, "line " + std::to_string(face->headerLine) + ": face needs a list \"vertex_indices\" (or \"vertex_index\")");
    if (vertex->count > std::uint64_t(std::numeric_limits<std::uint32_t>::max()))
      fail(name, "vertex: " + std::to_string(vertex->count) + " vertices, more than 32-bit indices reach");
  };
  const PlyData data = readPly(bytes, name, check);
  const PlyData::Element* vertex = data.find("vertex");
  const PlyData::Element* face = data.find("face");
  const PlyData::Property *x = vertex->scalar("x"), *y = vertex->scalar("y"), *z = vertex->scalar("z");
  const PlyData::Property* indices = face->list("vertex_indices");
  if (!indices) indices = face->list("vertex_index");

  PlyMesh mesh;
  const std::size_t n = std::size_t(vertex->count);
  mesh.positions.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const glm::dvec3 p(x->values[i], y->values[i], z->values[i]);
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(p[k]))
        fail(name, "vertex " + std::to_string(i) + ": coordinate is not finite (" + std::to_string(p[k]) + ")");
    mesh.positions[i] = p;
  }
  const PlyData::Property *nx = vertex->scalar("nx"), *ny = vertex->scalar("ny"), *nz = vertex->scalar("nz");
  if (nx && ny && nz) {
    mesh.normals.resize(n);
    // a non-finite normal becomes "none" (zero): the geometric normal serves there
    for (std::size_t i = 0; i < n; ++i) {
      const glm::vec3 v(float(nx->values[i]), float(ny->values[i]), float(nz->values[i]));
      const float length = glm::length(v);
      mesh.normals[i] = std::isfinite(length) && length > 0.0f ? v / length : glm::vec3(0.0f);
    }
  }
  const char* const uvNames[][2] = {{"s", "t"}, {"u", "v"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
  for (const auto& names : uvNames) {
    const PlyData::Property *u = vertex->scalar(names[0]), *v = vertex->scalar(names[1]);
    if (!u || !v) continue;
    mesh.texcoords.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const glm::vec2 uv(float(u->values[i]), 1.0f - float(v->values[i]));
      mesh.texcoords[i] = std::isfinite(uv.x) && std::isfinite(uv.y) ? uv : glm::vec2(0.0f);
    }
    break;
  }

  mesh.triangles.reserve(std::size_t(face->count));
  std::uint64_t begin = 0;
  for (std::uint64_t f = 0; f < face->count; ++f) {
    const std::uint64_t end = indices->ends[f];
    const std::string where = "face " + std::to_string(f);
    if (end - begin < 3) fail(name, where + ": " + std::to_string(end - begin) + " vertices (a face needs 3 or more)");
    std::vector<std::uint32_t> corners;
    for (std::uint64_t k = begin; k < end; ++k) {
      const double index = indices->values[k];
      if (!(index >= 0.0 && index < double(n)))
        fail(name, where + ": vertex index " + std::to_string(std::int64_t(index)) + " out of range (" +
                       std::to_string(n) + " vertices)");
      corners.push_back(std::uint32_t(index));
    }
    for (std::size_t k = 1; k + 1 < corners.size(); ++k) mesh.triangles.push_back({corners[0], corners[k], corners[k + 1]});
    begin = end;
  }
  // no normals in the file: smooth ones, each vertex the area-weighted mean of its faces' (as Mitsuba's reader does)
  if (mesh.normals.empty()) {
    std::vector<glm::dvec3> sum(n, glm::dvec3(0.0));
    for (const auto& t : mesh.triangles) {
      const glm::dvec3 area = glm::cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]);
      for (std::uint32_t v : t) sum[v] += area;
    }
    mesh.normals.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double length = glm::length(sum[i]);
      mesh.normals[i] = length > 0.0 && std::isfinite(length) ? glm::vec3(sum[i] / length) : glm::vec3(0.0f);
    }
  }
  return mesh;
}

PlyMesh loadPlyMesh(const std::string& path) {
  const std::string name = fileName(path);
  return readPlyMesh(readFileBytes(path, name), name);
}

}  // namespace wt
