// The scene file (docs/scene-format.md): nlohmann-json parses the text, and
// every field is checked here, by a validator that knows each object's
// fields, before it is used. Geometry is gathered first (glTF files loaded,
// transforms composed in double), the origin chosen once everything's place
// is known, and only then written as floats relative to it.
#include "scene/scene_file.h"

#include "output/image_io.h"
#include "scene/generators.h"
#include "scene/gltf_loader.h"
#include "scene/hair_loader.h"
#include "scene/ply.h"
#include "render/tonemap_names.h"
#include "scene/sdf_volume.h"

#include <nlohmann/json.hpp>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <map>
#include <new>
#include <set>
#include <stdexcept>
#include <vector>

namespace wt {
namespace {

namespace fs = std::filesystem;
/// Keeps the file's order of keys, so the first problem reported is the first in the file.
using Json = nlohmann::ordered_json;

constexpr int kVersion = 1;
/// A scene file needs 5 levels (objects[2].centers[7][1]); more is a mistake.
constexpr std::size_t kMaxNesting = 64;
constexpr std::size_t kMaxFileBytes = std::size_t(1) << 30;
constexpr int kMaxImageSide = 16384;
constexpr int kMaxSamples = 1 << 24;
constexpr int kMaxBounces = 1024;
/// Curve points a scene may hold, children included (28-bit primitive ids).
constexpr std::uint64_t kMaxCurvePoints = std::uint64_t(1) << 28;
/// Cells per axis of a procedural SDF grid at most (its corners take 4 bytes each on the host).
constexpr std::int64_t kMaxSdfResolution = 512;
constexpr std::int64_t kMaxChildren = 100000;
/// Spheres a scene may hold, copies included (28-bit primitive ids).
constexpr std::uint64_t kMaxSpheres = std::uint64_t(1) << 28;
/// Transforms in one object's "instances".
constexpr std::size_t kMaxInstances = std::size_t(1) << 20;
/// Floats the SDF grids' and displaced meshes' copies may hold on the host
/// (values; vertices and texels), copies included: a copy is flattened there.
constexpr std::uint64_t kMaxCopiedFloats = std::uint64_t(1) << 30;

// paths and values in messages

bool isIdentifier(std::string_view key) {
  if (key.empty()) return false;
  for (char c : key)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') return false;
  return true;
}

/// The path of `key` inside `path`: "objects[3].radius", or materials["my glass"].
std::string member(const std::string& path, std::string_view key) {
  if (!isIdentifier(key)) return path + "[" + Json(std::string(key)).dump(-1, ' ', false, Json::error_handler_t::replace) + "]";
  return path.empty() ? std::string(key) : path + "." + std::string(key);
}

std::string element(const std::string& path, std::size_t i) { return path + "[" + std::to_string(i) + "]"; }

/// A value as the file wrote it, shortened for a message.
std::string describe(const Json& v) {
  std::string text = v.dump(-1, ' ', false, Json::error_handler_t::replace);
  if (text.size() > 48) text = text.substr(0, 45) + "...";
  return text;
}

std::string joinKeys(std::initializer_list<const char*> keys) {
  std::string text;
  for (const char* k : keys) text += (text.empty() ? "" : ", ") + std::string(k);
  return text;
}

std::string formatNumber(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.9g", v);
  return buffer;
}

std::string lowerExtension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

bool isFinite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool isFinite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

/// A problem found while parsing, at a JSON path; Loader adds the file's name.
struct JsonProblem {
  std::string path;
  std::string problem;
};

/// nlohmann's DOM builder, and what it leaves out: the path of each value
/// (the parser reports a number beyond a double's range without one),
/// duplicate keys (it keeps the last silently), and a nesting limit.
class ParseHandler {
 public:
  explicit ParseHandler(Json& result) : m_dom(result, true) {}

  bool null() { return value(), m_dom.null(); }
  bool boolean(bool v) { return value(), m_dom.boolean(v); }
  bool number_integer(Json::number_integer_t v) { return value(), m_dom.number_integer(v); }
  bool number_unsigned(Json::number_unsigned_t v) { return value(), m_dom.number_unsigned(v); }
  bool number_float(Json::number_float_t v, const Json::string_t& text) { return value(), m_dom.number_float(v, text); }
  bool string(Json::string_t& v) { return value(), m_dom.string(v); }
  bool binary(Json::binary_t& v) { return value(), m_dom.binary(v); }
  bool start_object(std::size_t n) { return open(false), m_dom.start_object(n); }
  bool end_object() { return m_frames.pop_back(), m_dom.end_object(); }
  bool start_array(std::size_t n) { return open(true), m_dom.start_array(n); }
  bool end_array() { return m_frames.pop_back(), m_dom.end_array(); }
  bool key(Json::string_t& k) {
    Frame& f = m_frames.back();
    if (!f.keys.insert(k).second) throw JsonProblem{member(path(m_frames.size() - 1, false), k), "duplicate key"};
    f.key = k;
    return m_dom.key(k);
  }
  template <class Exception>
  bool parse_error(std::size_t position, const std::string& token, const Exception& ex) {
    // 406: a number that overflows a double; the value has no event, so its path is the next one
    if (ex.id == 406)
      throw JsonProblem{path(m_frames.size(), true),
                        "must be a finite number, got " + token + " (beyond the range of a double)"};
    return m_dom.parse_error(position, token, ex);  // throws
  }

 private:
  struct Frame {
    bool array = false;
    std::size_t count = 0;  ///< array: elements begun
    std::string key;        ///< object: the current member
    std::set<std::string> keys;
  };

  void value() {
    if (!m_frames.empty() && m_frames.back().array) ++m_frames.back().count;
  }
  void open(bool array) {
    value();
    if (m_frames.size() >= kMaxNesting)
      throw JsonProblem{path(m_frames.size(), false), "nested more than " + std::to_string(kMaxNesting) + " levels deep"};
    m_frames.push_back({array, 0, {}, {}});
  }
  /// The path through the first `depth` frames; `pending`: the last frame's
  /// next element rather than its current one.
  std::string path(std::size_t depth, bool pending) const {
    std::string text;
    for (std::size_t i = 0; i < depth; ++i) {
      const Frame& f = m_frames[i];
      text = f.array ? element(text, pending && i + 1 == depth ? f.count : f.count - 1) : member(text, f.key);
    }
    return text;
  }

  nlohmann::detail::json_sax_dom_parser<Json> m_dom;
  std::vector<Frame> m_frames;
};

/// A glTF file the scene places, loaded once however often it is placed.
struct IncludedFile {
  Scene scene;                    ///< relative to scene.origin, as loaded
  std::uint32_t materialBase = 0; ///< its materials' first index in the result
  std::uint32_t geometryBase = 0; ///< its geometry ids' offset in the result (copies of one file share them)
};

/// One placement of an included file.
struct Placement {
  std::size_t file;
  glm::dmat4 world;  ///< file's world (its scene.origin added) to the scene file's world
  std::string path;  ///< "objects[2]"
};

/// A sphere in world coordinates, before the origin is subtracted.
struct WorldSphere {
  glm::dvec3 center;
  double radius;
  std::uint32_t material;
  std::string path;  ///< "objects[2]" or "objects[2].centers[5]"
};

/// An "sdf" object, its lattice placed in world coordinates (before the origin is subtracted).
struct WorldSdf {
  SdfGrid grid;
  std::vector<glm::dmat4> instances;  ///< "instances": each copy's world from the grid's (empty: placed once)
  std::uint32_t geometry = 0;         ///< with instances: shared by the copies (PrimitiveInstance::geometry)
  std::string path;  ///< "objects[2]"
};

/// A "displaced" object, its mesh in world coordinates (before the origin is subtracted).
struct WorldDisplaced {
  DisplacedMesh mesh;                   ///< all but the positions
  std::vector<glm::dvec3> positions;    ///< world
  std::vector<glm::dmat4> instances;    ///< "instances": each copy's world from `positions`' (empty: placed once)
  std::uint32_t geometry = 0;           ///< with instances: shared by the copies (PrimitiveInstance::geometry)
  std::string path;                     ///< "objects[2]"
};

/// One copy of a "sphere" or "spheres" object with "instances": the
/// object's spheres as written, moved by `world` (expanded only when the
/// scene is built, so a million copies cost their spheres and no more).
struct SphereCopy {
  std::size_t first = 0, count = 0;  ///< the object's spheres in Loader::m_instancedSpheres
  std::uint32_t geometry = 0;        ///< shared by the object's copies (PrimitiveInstance::geometry)
  glm::dmat4 world{1.0};             ///< the object's own coordinates -> world
  std::size_t object = 0, index = 0; ///< objects[object].instances[index], for messages
};

/// A "curves" object in world coordinates, before the origin is subtracted.
struct WorldCurves {
  std::vector<glm::dvec4> points;      ///< xyz world, w radius (world units); with instances, before them
  std::vector<std::uint32_t> counts;   ///< points per strand
  CurveBasis basis = CurveBasis::kLinear;
  std::uint32_t material = 0;
  std::uint32_t children = 0;
  double childRadius = 0.0;
  std::uint32_t seed = 1;
  std::vector<glm::dmat4> instances;   ///< "instances": each copy's world from `points`' (empty: placed once as they are)
  std::uint32_t geometry = 0;          ///< with instances: shared by the copies (PrimitiveInstance::geometry)
  std::string path;  ///< "objects[2]"
};

/// The "camera" object, in world coordinates.
struct LookAt {
  glm::dvec3 from, to, up;
  double fovDegrees;
};

class Loader {
 public:
  Loader(const std::string& name, const std::string& baseDir, const GltfLoadOptions& options)
      : m_name(name), m_baseDir(baseDir.empty() ? "." : baseDir), m_options(options) {}

  SceneFile run(std::string_view text) {
    if (text.empty()) fail("", "the file is empty");
    Json doc;
    try {
      ParseHandler handler(doc);
      Json::sax_parse(text.begin(), text.end(), &handler);
    } catch (const JsonProblem& p) {
      fail(p.path, p.problem);
    } catch (const Json::parse_error& e) {
      // "[json.exception.parse_error.101] parse error at line 1, column 5: ..." without the bracket
      std::string what = e.what();
      if (auto end = what.find("] "); what.rfind("[json.exception", 0) == 0 && end != std::string::npos)
        what = what.substr(end + 2);
      fail("", "malformed JSON at byte " + std::to_string(e.byte) + ": " + what);
    }
    m_result.scene.sourceName = m_name;
    readDocument(doc);
    return std::move(m_result);
  }

 private:
  [[noreturn]] void fail(const std::string& path, const std::string& problem) const {
    throw SceneError(m_name + ": " + (path.empty() ? "" : path + ": ") + problem);
  }

  // typed reads: each names the path and what was found

  const Json& object(const Json& v, const std::string& path) const {
    if (!v.is_object()) fail(path, "must be an object, got " + describe(v));
    return v;
  }

  void checkKeys(const Json& obj, const std::string& path, std::initializer_list<const char*> allowed) const {
    for (const auto& item : obj.items()) {
      const std::string& key = item.key();
      if (std::none_of(allowed.begin(), allowed.end(), [&](const char* k) { return key == k; }))
        fail(member(path, key), "unknown field (expected one of: " + joinKeys(allowed) + ")");
    }
  }

  static const Json* find(const Json& obj, const char* key) {
    auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
  }

  const Json& require(const Json& obj, const std::string& path, const char* key, const std::string& why = "") const {
    const Json* v = find(obj, key);
    if (!v) fail(member(path, key), "missing (required" + why + ")");
    return *v;
  }

  double number(const Json& v, const std::string& path) const {
    if (!v.is_number()) fail(path, "must be a number, got " + describe(v));
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(path, "must be a finite number, got one beyond the range of a double");
    return d;
  }
  double positive(const Json& v, const std::string& path) const {
    const double d = number(v, path);
    if (!(d > 0.0)) fail(path, "must be > 0, got " + describe(v));
    return d;
  }
  double nonNegative(const Json& v, const std::string& path) const {
    const double d = number(v, path);
    if (!(d >= 0.0)) fail(path, "must be >= 0, got " + describe(v));
    return d;
  }
  double inRange(const Json& v, const std::string& path, double lo, double hi) const {
    const double d = number(v, path);
    if (!(d >= lo && d <= hi))
      fail(path, "must be in [" + formatNumber(lo) + ", " + formatNumber(hi) + "], got " + describe(v));
    return d;
  }
  std::int64_t integer(const Json& v, const std::string& path, std::int64_t lo, std::int64_t hi) const {
    const double d = number(v, path);
    if (d != std::floor(d)) fail(path, "must be an integer, got " + describe(v));
    if (!(d >= double(lo) && d <= double(hi)))
      fail(path, "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + describe(v));
    return std::int64_t(d);
  }
  bool boolean(const Json& v, const std::string& path) const {
    if (!v.is_boolean()) fail(path, "must be true or false, got " + describe(v));
    return v.get<bool>();
  }
  std::string string(const Json& v, const std::string& path) const {
    if (!v.is_string()) fail(path, "must be a string, got " + describe(v));
    return v.get<std::string>();
  }
  const Json& array(const Json& v, const std::string& path, std::size_t size, const char* of) const {
    if (!v.is_array() || v.size() != size)
      fail(path, "must be an array of " + std::to_string(size) + " " + of + ", got " + describe(v));
    return v;
  }
  glm::dvec3 vec3(const Json& v, const std::string& path) const {
    array(v, path, 3, "numbers");
    return {number(v[0], element(path, 0)), number(v[1], element(path, 1)), number(v[2], element(path, 2))};
  }
  /// A colour: 3 numbers >= 0, and <= 1 when `unit` (reflectances).
  glm::vec3 color(const Json& v, const std::string& path, bool unit) const {
    array(v, path, 3, "numbers");
    glm::vec3 c;
    for (int k = 0; k < 3; ++k)
      c[k] = float(unit ? inRange(v[k], element(path, k), 0.0, 1.0) : nonNegative(v[k], element(path, k)));
    if (!isFinite(c)) fail(path, "is beyond the range of a float");
    return c;
  }

  /// A file named by the scene, against the scene file's folder.
  fs::path resolve(const std::string& file) const {
    fs::path p(file);
    return (p.is_absolute() ? p : m_baseDir / p).lexically_normal();
  }
  void requireFile(const fs::path& path, const std::string& where) const {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
      fail(where, (fs::exists(path, ec) ? "not a regular file: " : "no such file: ") + path.string());
  }

  // the document

  void readDocument(const Json& doc) {
    if (!doc.is_object()) fail("", "the top level must be an object, got " + describe(doc));
    const Json& version = require(doc, "", "version", "; this wavetrace reads version " + std::to_string(kVersion));
    if (!version.is_number_integer() || version.get<std::int64_t>() != kVersion)
      fail("version", "unsupported version " + describe(version) + " (this wavetrace reads version " +
                          std::to_string(kVersion) + ")");
    checkKeys(doc, "", {"version", "camera", "environment", "materials", "objects", "render"});
    if (m_options.sceneIndex != -1 || m_options.cameraIndex != 0)
      m_result.scene.addWarning("a glTF scene or camera index applies to .gltf/.glb files, not to scene files; ignored");

    if (const Json* v = find(doc, "render")) readRender(*v, "render");
    if (const Json* v = find(doc, "environment")) readEnvironment(*v, "environment");
    if (const Json* v = find(doc, "materials")) readMaterials(*v, "materials");
    if (const Json* v = find(doc, "camera")) readCamera(*v, "camera");
    if (const Json* v = find(doc, "objects")) {
      if (!v->is_array()) fail("objects", "must be an array, got " + describe(*v));
      for (std::size_t i = 0; i < v->size(); ++i) {
        m_objectIndex = i;
        readObject((*v)[i], element("objects", i));
      }
    }
    build();
  }

  void readRender(const Json& v, const std::string& path) {
    object(v, path);
    checkKeys(v, path, {"width", "height", "spp", "max_bounces", "seed", "exposure", "integrator", "tonemap"});
    SceneFileSettings& s = m_result.settings;
    if (const Json* x = find(v, "width")) s.width = int(integer(*x, member(path, "width"), 1, kMaxImageSide));
    if (const Json* x = find(v, "height")) s.height = int(integer(*x, member(path, "height"), 1, kMaxImageSide));
    if (const Json* x = find(v, "spp")) s.samplesPerPixel = int(integer(*x, member(path, "spp"), 1, kMaxSamples));
    if (const Json* x = find(v, "max_bounces"))
      s.maxBounces = int(integer(*x, member(path, "max_bounces"), 0, kMaxBounces));
    if (const Json* x = find(v, "seed"))
      s.seed = std::uint32_t(integer(*x, member(path, "seed"), 0, std::numeric_limits<std::uint32_t>::max()));
    if (const Json* x = find(v, "exposure")) {
      const std::string where = member(path, "exposure");
      const char* expected = "must be a number of stops in [-1000, 1000], \"auto\", \"auto+STOPS\" or \"auto-STOPS\", got ";
      double stops = 0.0;
      if (x->is_string()) {
        const std::string text = x->get<std::string>();
        if (text.rfind("auto", 0) != 0) fail(where, expected + describe(*x));
        s.autoExposure = true;
        if (text.size() > 4) {
          std::size_t used = 0;
          try {
            if (text[4] == '+' || text[4] == '-') stops = std::stod(text.substr(4), &used);
          } catch (const std::exception&) {
            used = 0;
          }
          if (used != text.size() - 4) fail(where, expected + describe(*x));
        }
      } else {
        stops = number(*x, where);
      }
      if (!(std::fabs(stops) <= 1000.0)) fail(where, expected + describe(*x));
      s.exposureStops = float(stops);
    }
    if (const Json* x = find(v, "integrator")) {
      const std::string name = string(*x, member(path, "integrator"));
      if (name != "path" && name != "minimal")
        fail(member(path, "integrator"), "must be \"path\" or \"minimal\", got " + describe(*x));
      s.integrator = name;
    }
    if (const Json* x = find(v, "tonemap")) {
      const std::string name = string(*x, member(path, "tonemap"));
      if (!parseTonemapOperator(name))
        fail(member(path, "tonemap"), "must be one of " + tonemapOperatorList() + ", got " + describe(*x));
      s.tonemap = name;
    }
  }

  void readEnvironment(const Json& v, const std::string& path) {
    object(v, path);
    checkKeys(v, path, {"color", "map", "intensity", "rotation", "hidden"});
    const Json* color = find(v, "color");
    const Json* map = find(v, "map");
    if (color && map) fail(path, "give \"color\" or \"map\", not both");
    if (!color && !map) fail(path, "needs \"color\" (a constant environment) or \"map\" (an .hdr or .exr file)");
    SceneEnvironment env;
    if (color) {
      env.color = this->color(*color, member(path, "color"), false);
      for (const char* key : {"intensity", "rotation"})
        if (find(v, key)) fail(member(path, key), "applies to a \"map\" only");
    } else {
      const std::string where = member(path, "map");
      const std::string file = string(*map, where);
      if (file.empty()) fail(where, "must name a file, got \"\"");
      const fs::path resolved = resolve(file);
      const std::string ext = lowerExtension(resolved);
      if (ext != ".hdr" && ext != ".exr") fail(where, "must be a .hdr or .exr file, got " + describe(*map));
      requireFile(resolved, where);
      env.map = resolved.string();
      if (const Json* x = find(v, "intensity")) {
        env.intensity = float(nonNegative(*x, member(path, "intensity")));
        if (!std::isfinite(env.intensity)) fail(member(path, "intensity"), "is beyond the range of a float");
      }
      if (const Json* x = find(v, "rotation"))
        env.rotationDegrees = float(std::fmod(number(*x, member(path, "rotation")), 360.0));
    }
    if (const Json* x = find(v, "hidden")) env.hidden = boolean(*x, member(path, "hidden"));
    m_result.settings.environment = env;
  }

  void readMaterials(const Json& v, const std::string& path) {
    object(v, path);
    for (const auto& [name, value] : v.items()) {
      const std::string where = member(path, name);
      if (name.empty()) fail(where, "a material needs a name");
      m_materialIndex[name] = std::uint32_t(m_result.scene.materials.size());
      m_result.scene.materials.push_back(readMaterial(value, where));
      m_result.scene.materialNames.push_back(name);
    }
  }

  WtMaterial readMaterial(const Json& v, const std::string& path) {
    object(v, path);
    std::string type = "pbr";
    if (const Json* x = find(v, "type")) {
      type = string(*x, member(path, "type"));
      if (type != "pbr" && type != "lambert")
        fail(member(path, "type"), "must be \"pbr\" or \"lambert\", got " + describe(*x));
    }
    if (type == "lambert")
      checkKeys(v, path, {"type", "base_color", "emission", "emission_strength", "double_sided"});
    else
      checkKeys(v, path, {"type", "base_color", "metallic", "roughness", "emission", "emission_strength",
                          "double_sided", "transmission", "ior", "thin_walled", "attenuation_color",
                          "attenuation_distance", "specular", "specular_color", "clearcoat",
                          "clearcoat_roughness", "sheen_color", "sheen_roughness", "anisotropy",
                          "anisotropy_rotation", "iridescence", "iridescence_ior", "iridescence_thickness", "priority", "dispersion"});
    auto read = [&](const char* key, double fallback, auto&& reader) {
      const Json* x = find(v, key);
      return x ? reader(*x, member(path, key)) : fallback;
    };
    auto unit = [&](const Json& x, const std::string& p) { return inRange(x, p, 0.0, 1.0); };

    glm::vec3 baseColor(0.8f);
    if (const Json* x = find(v, "base_color")) baseColor = color(*x, member(path, "base_color"), true);
    glm::vec3 emission(0.0f);
    if (const Json* x = find(v, "emission")) emission = color(*x, member(path, "emission"), false);
    const double strength = read("emission_strength", 1.0, [&](const Json& x, const std::string& p) { return nonNegative(x, p); });
    emission *= float(strength);
    if (!isFinite(emission)) fail(member(path, "emission_strength"), "makes the emission overflow a float");
    bool doubleSided = false;
    if (const Json* x = find(v, "double_sided")) doubleSided = boolean(*x, member(path, "double_sided"));
    if (type == "lambert") return makeMaterial(baseColor, emission, doubleSided);

    const float metallic = float(read("metallic", 0.0, unit));
    const float roughness = float(read("roughness", 0.5, unit));
    WtMaterial m = makePbrMaterial(baseColor, metallic, roughness, emission, doubleSided);
    const float transmission = float(read("transmission", 0.0, unit));
    const float ior = float(read("ior", 1.5, [&](const Json& x, const std::string& p) { return inRange(x, p, 1.0, 10.0); }));
    bool thinWalled = false;
    if (const Json* x = find(v, "thin_walled")) thinWalled = boolean(*x, member(path, "thin_walled"));
    glm::vec3 attenuationColor(1.0f);
    if (const Json* x = find(v, "attenuation_color")) attenuationColor = color(*x, member(path, "attenuation_color"), true);
    const double distance = read("attenuation_distance", INFINITY, [&](const Json& x, const std::string& p) { return positive(x, p); });
    const bool attenuates = std::isfinite(distance) && attenuationColor != glm::vec3(1.0f);

    // the layers (glTF's KHR_materials_specular, _clearcoat, _sheen)
    glm::vec3 specularColor(1.0f), sheenColor(0.0f);
    if (const Json* x = find(v, "specular_color")) specularColor = color(*x, member(path, "specular_color"), false);
    if (const Json* x = find(v, "sheen_color")) sheenColor = color(*x, member(path, "sheen_color"), true);
    m = withSpecular(m, float(read("specular", 1.0, unit)), glm::min(specularColor, glm::vec3(1e6f)));
    m = withClearcoat(m, float(read("clearcoat", 0.0, unit)), float(read("clearcoat_roughness", 0.0, unit)));
    m = withSheen(m, sheenColor, float(read("sheen_roughness", 0.0, unit)));
    const double rotation = read("anisotropy_rotation", 0.0, [&](const Json& x, const std::string& p) {
      return inRange(x, p, -1e6, 1e6);
    });
    m = withAnisotropy(m, float(read("anisotropy", 0.0, unit)), float(rotation));
    const double filmIor = read("iridescence_ior", 1.3, [&](const Json& x, const std::string& p) { return inRange(x, p, 1.0, 10.0); });
    const double thickness = read("iridescence_thickness", 400.0, [&](const Json& x, const std::string& p) { return inRange(x, p, 0.0, 1e5); });
    m = withIridescence(m, float(read("iridescence", 0.0, unit)), float(filmIor), float(thickness), float(thickness));
    // ior sets the dielectric's F0 ((ior - 1) / (ior + 1))^2 as well as the interface's index
    m.ior = ior;
    if (metallic >= 1.0f)
      for (const char* key : {"ior", "specular", "specular_color"})
        if (find(v, key)) m_result.scene.addWarning(member(path, key) + " has no effect on a metal (metallic 1); ignored");
    if (!(transmission > 0.0f)) {
      for (const char* key : {"thin_walled", "attenuation_color", "attenuation_distance", "priority", "dispersion"})
        if (find(v, key))
          m_result.scene.addWarning(member(path, key) + " has no effect without transmission; ignored");
      return m;
    }
    if (find(v, "attenuation_color") && !find(v, "attenuation_distance"))
      m_result.scene.addWarning(member(path, "attenuation_color") +
                                " has no effect without attenuation_distance; ignored");
    if (thinWalled && attenuates)
      m_result.scene.addWarning(path + ": attenuation of a thin-walled material has no effect; ignored");
    // a fraction `color` of the light is left after `distance`: sigma = -ln(color) / distance
    glm::vec3 absorption(0.0f);
    if (attenuates)
      for (int k = 0; k < 3; ++k)
        absorption[k] = float(std::min(-std::log(std::max(double(attenuationColor[k]), 1e-300)) / distance, 1e30));
    // the nested-dielectric priority (kernels/shared/media.h): a volume boundary's only
    const double priority = read("priority", 0.0, [&](const Json& x, const std::string& p) {
      return double(integer(x, p, 0, 2147483647));
    });
    // KHR_materials_dispersion's 20 / Abbe number: a volume boundary's only
    const double dispersion = read("dispersion", 0.0, [&](const Json& x, const std::string& p) { return inRange(x, p, 0.0, 1000.0); });
    for (const char* key : {"priority", "dispersion"})
      if (thinWalled && find(v, key))
        m_result.scene.addWarning(member(path, key) + " has no effect on a thin-walled material; ignored");
    m = withPriority(withTransmission(m, transmission, ior, thinWalled, absorption), std::uint32_t(priority));
    if (!thinWalled) m.dispersion = float(dispersion);
    return m;
  }

  void readCamera(const Json& v, const std::string& path) {
    object(v, path);
    checkKeys(v, path, {"from", "to", "up", "fov"});
    LookAt camera;
    camera.from = vec3(require(v, path, "from"), member(path, "from"));
    camera.to = vec3(require(v, path, "to"), member(path, "to"));
    camera.up = glm::dvec3(0.0, 1.0, 0.0);
    if (const Json* x = find(v, "up")) camera.up = vec3(*x, member(path, "up"));
    camera.fovDegrees = 45.0;
    if (const Json* x = find(v, "fov")) {
      camera.fovDegrees = number(*x, member(path, "fov"));
      if (!(camera.fovDegrees > 0.0 && camera.fovDegrees < 180.0))
        fail(member(path, "fov"), "must be in (0, 180) degrees, got " + describe(*x));
    }
    const glm::dvec3 forward = camera.to - camera.from;
    const double distance = glm::length(forward);
    if (!(distance > 0.0) || !std::isfinite(distance))
      fail(member(path, "to"), "must differ from camera.from (the view direction is to - from)");
    const double upLength = glm::length(camera.up);
    if (!(upLength > 0.0) || !std::isfinite(upLength)) fail(member(path, "up"), "must not be (0, 0, 0)");
    const double sine = glm::length(glm::cross(forward / distance, camera.up / upLength));
    if (!(sine > 1e-6)) fail(member(path, "up"), "is parallel to the view direction (to - from)");
    m_camera = camera;
  }

  std::uint32_t materialOf(const Json& obj, const std::string& path) {
    const Json* x = find(obj, "material");
    if (!x) {
      // the documented defaults of a material with no fields
      if (m_defaultMaterial < 0) {
        m_defaultMaterial = int(m_result.scene.materials.size());
        m_result.scene.materials.push_back(makePbrMaterial(glm::vec3(0.8f), 0.0f, 0.5f));
        m_result.scene.materialNames.push_back("(default)");
      }
      return std::uint32_t(m_defaultMaterial);
    }
    const std::string where = member(path, "material");
    const std::string name = string(*x, where);
    auto it = m_materialIndex.find(name);
    if (it == m_materialIndex.end()) {
      std::string known;
      for (const auto& [k, index] : m_materialIndex) known += (known.empty() ? "" : ", ") + k;
      fail(where, "unknown material " + describe(*x) +
                      (known.empty() ? " (the file defines no materials)" : " (defined: " + known + ")"));
    }
    return it->second;
  }

  // objects

  void readObject(const Json& v, const std::string& path) {
    object(v, path);
    const std::string type =
        string(require(v, path, "type", ": gltf, mesh, sphere, spheres, curves, sdf or displaced"), member(path, "type"));
    if (type == "gltf") readGltf(v, path);
    else if (type == "mesh") readMesh(v, path);
    else if (type == "sphere") readSphere(v, path);
    else if (type == "spheres") readSpheres(v, path);
    else if (type == "curves") readCurves(v, path);
    else if (type == "sdf") readSdf(v, path);
    else if (type == "displaced") readDisplaced(v, path);
    else
      fail(member(path, "type"),
           "unknown type \"" + type + "\" (expected one of: gltf, mesh, sphere, spheres, curves, sdf, displaced)");
  }

  /// A triangle mesh (glTF or PLY) displaced along its normals by a map (PNG, JPEG or EXR).
  void readDisplaced(const Json& v, const std::string& path) {
    checkKeys(v, path, {"type", "mesh", "displacement", "scale", "offset", "level", "transform", "material", "instances"});
    WorldDisplaced out;
    out.path = path;
    DisplacedMesh& mesh = out.mesh;
    mesh.scale = float(number(require(v, path, "scale", ": world units per unit of the map"), member(path, "scale")));
    if (const Json* x = find(v, "offset")) mesh.offset = float(number(*x, member(path, "offset")));
    if (!std::isfinite(mesh.scale) || !std::isfinite(mesh.offset))
      fail(path, "scale and offset must be within the range of a float");
    if (const Json* x = find(v, "level")) mesh.level = int(integer(*x, member(path, "level"), 0, WT_DISP_MAX_LEVEL));
    glm::dmat4 transform(1.0);
    if (const Json* t = find(v, "transform")) transform = readTransform(*t, member(path, "transform"));
    out.instances = readInstances(v, path, "keep displacements along the normals");

    // the base mesh, in the file's world
    const std::string meshWhere = member(path, "mesh");
    const Json& meshValue = require(v, path, "mesh", ": a .gltf, .glb or .ply file");
    const std::string meshName = string(meshValue, meshWhere);
    if (meshName.empty()) fail(meshWhere, "must name a file, got \"\"");
    const fs::path meshFile = resolve(meshName);
    const std::string meshExt = lowerExtension(meshFile);
    if (meshExt != ".gltf" && meshExt != ".glb" && meshExt != ".ply")
      fail(meshWhere, "must be a .gltf, .glb or .ply file, got " + describe(meshValue));
    const std::string mapWhere = member(path, "displacement");
    const Json& mapValue = require(v, path, "displacement", ": a .png, .jpg or .exr map");
    const std::string mapName = string(mapValue, mapWhere);
    if (mapName.empty()) fail(mapWhere, "must name a file, got \"\"");
    const fs::path mapFile = resolve(mapName);
    const std::string mapExt = lowerExtension(mapFile);
    if (mapExt != ".png" && mapExt != ".jpg" && mapExt != ".jpeg" && mapExt != ".exr")
      fail(mapWhere, "must be a .png, .jpg or .exr file, got " + describe(mapValue));
    requireFile(meshFile, meshWhere);
    requireFile(mapFile, mapWhere);
    std::vector<glm::dvec3> local;
    bool hasUv = true;
    try {
      if (meshExt == ".ply") {
        PlyMesh ply = loadPlyMesh(meshFile.string());
        hasUv = !ply.texcoords.empty();
        local = std::move(ply.positions);
        mesh.normals = std::move(ply.normals);
        mesh.texcoords = std::move(ply.texcoords);
        mesh.triangles = std::move(ply.triangles);
      } else {
        GltfLoadOptions include;
        include.recenter = false;
        include.maxVertices = m_options.maxVertices;
        include.maxTriangles = m_options.maxTriangles;
        Scene loaded = loadGltf(meshFile.string(), include);
        hasUv = false;
        for (const glm::vec2& t : loaded.texcoords) hasUv |= t.x != 0.0f || t.y != 0.0f;
        for (std::size_t i = 0; i < loaded.positions.size(); ++i) {
          const WtVec4& p = loaded.positions[i];
          local.push_back(glm::dvec3(p.x, p.y, p.z) + loaded.origin);
          mesh.normals.push_back(glm::vec3(loaded.normals[i].x, loaded.normals[i].y, loaded.normals[i].z));
          mesh.texcoords.push_back(loaded.texcoords[i]);
        }
        for (const WtTriangle& t : loaded.triangles) mesh.triangles.push_back({t.v0, t.v1, t.v2});
        for (const std::string& w : loaded.warnings) m_result.scene.addWarning(meshFile.filename().string() + ": " + w);
        // the object's "material" shades the displaced surface; say so rather than drop the file's textures silently
        if (!loaded.materialTextures.empty())
          m_result.scene.addWarning(path + ": " + meshFile.filename().string() +
                                    ": its materials' textures are not applied to a displaced mesh (the object's "
                                    "\"material\" shades it, untextured)");
      }
    } catch (const SceneError& e) {
      fail(meshWhere, e.what());
    }
    if (!hasUv)
      fail(meshWhere, meshFile.filename().string() +
                          (meshExt == ".ply" ? " has no texture coordinates (the map needs them)"
                                             : " has no TEXCOORD_0 (the map needs it)"));
    if (mesh.triangles.empty()) fail(meshWhere, meshFile.filename().string() + " has no triangles");
    // vertices without a normal take the area-weighted mean of their triangles'
    std::vector<glm::dvec3> made(local.size(), glm::dvec3(0.0));
    for (const auto& t : mesh.triangles)
      made[t[0]] += glm::cross(local[t[1]] - local[t[0]], local[t[2]] - local[t[0]]),
          made[t[1]] += glm::cross(local[t[2]] - local[t[1]], local[t[0]] - local[t[1]]),
          made[t[2]] += glm::cross(local[t[0]] - local[t[2]], local[t[1]] - local[t[2]]);
    const glm::dmat3 linear(transform);
    const glm::dmat3 normalMatrix = glm::transpose(glm::inverse(linear));
    const bool flip = glm::determinant(linear) < 0.0;
    for (std::size_t i = 0; i < local.size(); ++i) {
      glm::dvec3 n(mesh.normals[i]);
      if (!(glm::dot(n, n) > 0.0)) n = made[i];
      n = normalMatrix * n;
      const double len = glm::length(n);
      mesh.normals[i] = len > 0.0 && std::isfinite(len) ? glm::vec3(n / len) : glm::vec3(0.0f);
      out.positions.push_back(glm::dvec3(transform * glm::dvec4(local[i], 1.0)));
    }
    if (flip)
      for (auto& t : mesh.triangles) std::swap(t[1], t[2]);

    // the map: the first channel, 8- and 16-bit images scaled to [0, 1], EXR as stored
    const std::string label = mapFile.filename().string();
    try {
      if (mapExt == ".exr") {
        const Image image = readExr(mapFile);
        mesh.mapWidth = std::uint32_t(image.width);
        mesh.mapHeight = std::uint32_t(image.height);
        mesh.map.resize(std::size_t(image.width) * image.height);
        for (std::size_t i = 0; i < mesh.map.size(); ++i) mesh.map[i] = image.rgb[3 * i];
      } else {
        const std::vector<std::uint8_t> bytes = readFileBytes(mapFile.string(), label);
        const DecodedImage image = decodeImage(bytes.data(), bytes.size(), label);
        mesh.mapWidth = image.width;
        mesh.mapHeight = image.height;
        mesh.map.resize(std::size_t(image.width) * image.height);
        for (std::size_t i = 0; i < mesh.map.size(); ++i)
          mesh.map[i] = image.sixteenBit ? float(image.rgba16[4 * i]) / 65535.0f : float(image.rgba8[4 * i]) / 255.0f;
      }
    } catch (const SceneError& e) {
      fail(mapWhere, e.what());
    } catch (const std::exception& e) {
      fail(mapWhere, e.what());
    }
    if (mesh.mapWidth < 1 || mesh.mapHeight < 1) fail(mapWhere, label + " has no texels");
    for (std::size_t i = 0; i < mesh.map.size(); ++i)
      if (!std::isfinite(mesh.map[i]))
        fail(mapWhere, label + ": texel (" + std::to_string(i % mesh.mapWidth) + ", " +
                           std::to_string(i / mesh.mapWidth) + ") is " + (std::isnan(mesh.map[i]) ? "NaN" : "infinite") +
                           " (displacements must be finite)");
    mesh.material = materialOf(v, path);
    if (!out.instances.empty()) out.geometry = m_primitiveGeometries[3]++;
    countCopiedFloats(path, 4 * out.positions.size() + mesh.map.size(), out.instances.size());
    m_displaced.push_back(std::move(out));
  }

  /// A grid of signed distances: a procedural shape at a resolution, or a .vol file.
  void readSdf(const Json& v, const std::string& path) {
    checkKeys(v, path, {"type", "shape", "resolution", "radius", "minor_radius", "half_size", "amplitude", "frequency",
                        "file", "box", "storage", "transform", "material", "instances"});
    const Json* shapeValue = find(v, "shape");
    const Json* file = find(v, "file");
    if (shapeValue && file) fail(path, "give \"shape\" (procedural) or \"file\" (a .vol grid), not both");
    if (!shapeValue && !file) fail(member(path, "shape"), "missing (required: \"shape\", or a \"file\" of a .vol grid)");
    SdfVolume volume;
    if (shapeValue) {
      const std::string where = member(path, "shape");
      const std::string name = string(*shapeValue, where);
      SdfShape shape;
      if (name == "sphere") shape = SdfShape::kSphere;
      else if (name == "torus") shape = SdfShape::kTorus;
      else if (name == "box") shape = SdfShape::kBox;
      else if (name == "noisy_sphere") shape = SdfShape::kNoisySphere;
      else fail(where, "unknown shape " + describe(*shapeValue) + " (expected one of: sphere, torus, box, noisy_sphere)");
      const auto resolution = std::uint32_t(integer(require(v, path, "resolution", ": cells per axis"),
                                                    member(path, "resolution"), 2, kMaxSdfResolution));
      if (find(v, "box")) fail(member(path, "box"), "applies only to a .raw grid (a shape spans [-1, 1]^3: place it by \"transform\")");
      SdfShapeParams params;
      auto optional = [&](const char* key, double& to) {
        if (const Json* x = find(v, key)) to = positive(*x, member(path, key));
      };
      optional("radius", params.radius);
      optional("minor_radius", params.minorRadius);
      optional("half_size", params.halfSize);
      optional("amplitude", params.amplitude);
      optional("frequency", params.frequency);
      volume = makeSdfShape(shape, params, resolution);
    } else {
      for (const char* key : {"radius", "minor_radius", "half_size", "amplitude", "frequency"})
        if (find(v, key)) fail(member(path, key), "applies only to a procedural \"shape\", not to a \"file\"");
      const std::string where = member(path, "file");
      const std::string name = string(*file, where);
      if (name.empty()) fail(where, "must name a file, got \"\"");
      const fs::path resolved = resolve(name);
      const std::string ext = lowerExtension(resolved);
      if (ext != ".vol" && ext != ".raw")
        fail(where, "must be a .vol grid or a .raw grid of float32, got " + describe(*file));
      const bool raw = ext == ".raw";
      // a .raw file is bare values: its shape and box come from the object
      glm::uvec3 cells(0);
      glm::dvec3 lo(-1.0), hi(1.0);
      if (raw) {
        const std::string resPath = member(path, "resolution");
        const Json& res = require(v, path, "resolution", ": cells per axis [x, y, z] of a .raw grid");
        array(res, resPath, 3, "integers (cells per axis)");
        for (std::size_t a = 0; a < 3; ++a)
          cells[int(a)] = std::uint32_t(integer(res[a], element(resPath, a), 1, kSdfMaxCells));
        if (const Json* box = find(v, "box")) {
          const std::string boxPath = member(path, "box");
          array(*box, boxPath, 6, "numbers (min x, y, z, max x, y, z)");
          for (std::size_t a = 0; a < 3; ++a) {
            lo[int(a)] = number((*box)[a], element(boxPath, a));
            hi[int(a)] = number((*box)[a + 3], element(boxPath, a + 3));
            if (!(hi[int(a)] > lo[int(a)])) fail(boxPath, "the maximum must exceed the minimum on every axis");
          }
        }
      } else {
        for (const char* key : {"resolution", "box"})
          if (find(v, key)) fail(member(path, key), "applies only to a procedural \"shape\" or a .raw grid (a .vol file says its own)");
      }
      requireFile(resolved, where);
      try {
        volume = raw ? loadRawSdf(resolved.string(), resolved.filename().string(), cells, lo, hi)
                     : loadVolFile(resolved.string(), resolved.filename().string());
      } catch (const SceneError& e) {
        fail(where, e.what());
      }
    }
    WorldSdf sdf;
    sdf.path = path;
    sdf.grid.cells = volume.cells;
    if (const Json* x = find(v, "storage")) {
      const std::string where = member(path, "storage");
      const std::string storage = string(*x, where);
      if (storage == "dense") sdf.grid.storage = SdfStorage::kDense;
      else if (storage == "sparse") sdf.grid.storage = SdfStorage::kSparse;
      else if (storage != "auto") fail(where, "must be \"dense\", \"sparse\" or \"auto\", got " + describe(*x));
    }
    const std::string problem = sdfSurfaceProblem(volume.values);
    if (!problem.empty()) m_result.scene.addWarning(path + " " + problem + "; it draws nothing");
    sdf.grid.values = std::move(volume.values);
    glm::dmat4 transform(1.0);
    if (const Json* t = find(v, "transform")) transform = readTransform(*t, member(path, "transform"));
    sdf.grid.latticeToScene = transform * volume.latticeToObject();
    sdf.grid.material = materialOf(v, path);
    sdf.instances = readInstances(v, path, nullptr);  // any affine copy of a grid is a grid
    if (!sdf.instances.empty()) sdf.geometry = m_primitiveGeometries[2]++;
    countCopiedFloats(path, sdf.grid.values.size(), sdf.instances.size());
    m_sdfs.push_back(std::move(sdf));
  }

  void readCurves(const Json& v, const std::string& path) {
    checkKeys(v, path, {"type", "file", "strands", "basis", "radius", "radius_scale", "transform", "material",
                        "children", "child_radius", "seed", "instances"});
    const Json* file = find(v, "file");
    const Json* strands = find(v, "strands");
    if (file && strands) fail(path, "give \"file\" (a .hair or .ply file) or \"strands\" (points), not both");
    if (!file && !strands) fail(member(path, "strands"), "missing (required: \"strands\", or a \"file\" of strands)");
    WorldCurves curves;
    curves.path = path;
    if (const Json* x = find(v, "basis")) {
      const std::string basis = string(*x, member(path, "basis"));
      if (basis != "linear" && basis != "bspline")
        fail(member(path, "basis"), "must be \"linear\" or \"bspline\", got " + describe(*x));
      curves.basis = basis == "bspline" ? CurveBasis::kBSpline : CurveBasis::kLinear;
    }
    const Json* radiusValue = find(v, "radius");
    const double radius = radiusValue ? positive(*radiusValue, member(path, "radius")) : 0.0;
    const double radiusScale = find(v, "radius_scale") ? positive(v["radius_scale"], member(path, "radius_scale")) : 1.0;
    glm::dmat4 transform(1.0);
    if (const Json* t = find(v, "transform")) transform = readTransform(*t, member(path, "transform"));
    // radii scale as lengths do: exactly for a uniform scale
    const double lengthScale = std::cbrt(std::fabs(glm::determinant(glm::dmat3(transform))));

    std::vector<glm::dvec4> local;  // the file's or the object's points, radius in w (-1: none)
    if (file) {
      const std::string where = member(path, "file");
      const std::string name = string(*file, where);
      if (name.empty()) fail(where, "must name a file, got \"\"");
      const fs::path resolved = resolve(name);
      const std::string ext = lowerExtension(resolved);
      if (ext != ".hair" && ext != ".ply") fail(where, "must be a .hair or .ply file, got " + describe(*file));
      requireFile(resolved, where);
      StrandSet set;
      try {
        set = loadStrands(resolved.string());
      } catch (const SceneError& e) {
        fail(where, e.what());
      }
      if (!set.hasRadius && !radiusValue)
        fail(member(path, "radius"), "missing (required: " + resolved.filename().string() + " gives no radii)");
      curves.counts = std::move(set.counts);
      local.reserve(set.points.size());
      for (const glm::vec4& p : set.points) local.emplace_back(p);
    } else {
      const std::string where = member(path, "strands");
      if (!strands->is_array() || strands->empty())
        fail(where, "must be an array of strands, each an array of [x, y, z] or [x, y, z, radius] points, got " +
                        describe(*strands));
      for (std::size_t s = 0; s < strands->size(); ++s) {
        const Json& strand = (*strands)[s];
        const std::string strandPath = element(where, s);
        const std::size_t least = curves.basis == CurveBasis::kBSpline ? 4 : 2;
        if (!strand.is_array() || strand.size() < least)
          fail(strandPath, "must be an array of at least " + std::to_string(least) + " points" +
                               (least == 4 ? " (a B-spline segment takes 4)" : "") + ", got " + describe(strand));
        for (std::size_t i = 0; i < strand.size(); ++i) {
          const Json& point = strand[i];
          const std::string pointPath = element(strandPath, i);
          if (!point.is_array() || (point.size() != 3 && point.size() != 4))
            fail(pointPath, "must be [x, y, z] or [x, y, z, radius], got " + describe(point));
          glm::dvec4 p(number(point[0], element(pointPath, 0)), number(point[1], element(pointPath, 1)),
                       number(point[2], element(pointPath, 2)), -1.0);
          if (point.size() == 4) p.w = nonNegative(point[3], element(pointPath, 3));
          else if (!radiusValue)
            fail(pointPath, "has no radius: give [x, y, z, radius], or the object's \"radius\"");
          local.push_back(p);
        }
        curves.counts.push_back(std::uint32_t(strand.size()));
      }
    }

    if (const Json* x = find(v, "children")) curves.children = std::uint32_t(integer(*x, member(path, "children"), 0, kMaxChildren));
    if (const Json* x = find(v, "child_radius")) {
      if (curves.children == 0) fail(member(path, "child_radius"), "applies only with \"children\" > 0");
      curves.childRadius = positive(*x, member(path, "child_radius"));
    } else if (curves.children > 0) {
      fail(member(path, "child_radius"), "missing (required with \"children\": how far children stray from their guide)");
    }
    if (const Json* x = find(v, "seed")) curves.seed = std::uint32_t(integer(*x, member(path, "seed"), 0, std::numeric_limits<std::uint32_t>::max()));
    curves.instances = readInstances(v, path, "keep spheres and curves round");
    if (!curves.instances.empty()) curves.geometry = m_primitiveGeometries[1]++;
    m_curvePoints += std::uint64_t(local.size()) * (std::uint64_t(curves.children) + 1) *
                     std::max<std::uint64_t>(curves.instances.size(), 1);
    if (m_curvePoints > kMaxCurvePoints)
      fail(path, "brings the scene to " + std::to_string(m_curvePoints) + " curve points (children and copies included), more than the " +
                     std::to_string(kMaxCurvePoints) + " supported");

    curves.material = materialOf(v, path);
    curves.points.reserve(local.size());
    for (const glm::dvec4& p : local) {
      const double r = (radiusValue ? radius : p.w) * radiusScale * lengthScale;
      curves.points.push_back(glm::dvec4(glm::dvec3(transform * glm::dvec4(glm::dvec3(p), 1.0)), r));
    }
    m_curves.push_back(std::move(curves));
  }

  void readSphere(const Json& v, const std::string& path) {
    checkKeys(v, path, {"type", "center", "radius", "material", "instances"});
    const glm::dvec3 center = vec3(require(v, path, "center"), member(path, "center"));
    const double radius = positive(require(v, path, "radius"), member(path, "radius"));
    const std::size_t first = m_spheres.size();
    m_spheres.push_back({center, radius, materialOf(v, path), path});
    copySpheres(v, path, first);
  }

  void readSpheres(const Json& v, const std::string& path) {
    checkKeys(v, path, {"type", "centers", "radius", "radii", "material", "instances"});
    const std::string centersPath = member(path, "centers");
    const Json& centers = require(v, path, "centers");
    if (!centers.is_array()) fail(centersPath, "must be an array of [x, y, z] centres, got " + describe(centers));
    const Json* radius = find(v, "radius");
    const Json* radii = find(v, "radii");
    if (radius && radii) fail(path, "give \"radius\" (one for all) or \"radii\" (one per centre), not both");
    if (!radius && !radii) fail(member(path, "radius"), "missing (required: \"radius\", or \"radii\" with one per centre)");
    const std::string radiiPath = member(path, "radii");
    if (radii && (!radii->is_array() || radii->size() != centers.size()))
      fail(radiiPath, "must be an array of " + std::to_string(centers.size()) + " numbers (one per centre), got " +
                          describe(*radii));
    const double shared = radius ? positive(*radius, member(path, "radius")) : 0.0;
    const std::uint32_t material = materialOf(v, path);
    const std::size_t first = m_spheres.size();
    m_spheres.reserve(m_spheres.size() + centers.size());
    for (std::size_t i = 0; i < centers.size(); ++i) {
      const double r = radii ? positive((*radii)[i], element(radiiPath, i)) : shared;
      m_spheres.push_back({vec3(centers[i], element(centersPath, i)), r, material, element(centersPath, i)});
    }
    copySpheres(v, path, first);
  }

  /// An object's "instances": each a transform (as "transform") that keeps
  /// shapes, since a sphere or a round curve must stay one: a rotation, one
  /// scale for every axis (negative: a mirror) and a translation. Empty
  /// when the object has none.
  /// Count an SDF grid's or displaced mesh's floats once per copy (the host
  /// holds every copy) against kMaxCopiedFloats.
  void countCopiedFloats(const std::string& path, std::uint64_t floats, std::size_t copies) {
    m_copiedFloats += floats * std::max<std::uint64_t>(copies, 1);
    if (m_copiedFloats > kMaxCopiedFloats)
      fail(copies > 0 ? member(path, "instances") : path,
           "brings the scene's SDF values, displaced vertices and texels to " + std::to_string(m_copiedFloats) +
               " floats (copies included), more than the " + std::to_string(kMaxCopiedFloats) + " supported");
  }

  /// `keeps`: why the transforms must be similarities ("keep spheres and
  /// curves round"); null for any invertible affine transform (SDF grids).
  std::vector<glm::dmat4> readInstances(const Json& v, const std::string& path, const char* keeps) const {
    const Json* x = find(v, "instances");
    if (!x) return {};
    const std::string where = member(path, "instances");
    if (!x->is_array() || x->empty())
      fail(where, "must be a non-empty array of transforms (each as \"transform\"), got " + describe(*x));
    if (x->size() > kMaxInstances)
      fail(where, "holds " + std::to_string(x->size()) + " transforms, more than the " +
                      std::to_string(kMaxInstances) + " supported");
    std::vector<glm::dmat4> out;
    out.reserve(x->size());
    for (std::size_t k = 0; k < x->size(); ++k) {
      const std::string at = element(where, k);
      const glm::dmat4 m = readTransform((*x)[k], at);
      if (!keeps) {
        out.push_back(m);
        continue;
      }
      // columns of one length and perpendicular, to the digits a typed
      // rotation matrix carries (the renderer checks its copies as closely)
      const glm::dmat3 l(m);
      const glm::dvec3 lengths(glm::length(l[0]), glm::length(l[1]), glm::length(l[2]));
      const double s2 = (glm::dot(l[0], l[0]) + glm::dot(l[1], l[1]) + glm::dot(l[2], l[2])) / 3.0;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          if (!(std::abs(glm::dot(l[i], l[j]) - (i == j ? s2 : 0.0)) <= 1e-5 * s2))
            fail(at, std::string("must ") + keeps + ": a rotation, one scale for all axes and a translation "
                     "(its axes are scaled by " + formatNumber(lengths.x) + ", " + formatNumber(lengths.y) + ", " +
                     formatNumber(lengths.z) + (i == j ? ")" : " and are not perpendicular)"));
      out.push_back(m);
    }
    return out;
  }

  /// With "instances", the spheres read from m_spheres[first] on are the
  /// object's own coordinates: they move to m_instancedSpheres, one
  /// SphereCopy per transform.
  void copySpheres(const Json& v, const std::string& path, std::size_t first) {
    const std::vector<glm::dmat4> instances = readInstances(v, path, "keep spheres and curves round");
    const std::size_t count = m_spheres.size() - first;
    m_sphereCount += count * std::max<std::size_t>(instances.size(), 1);
    if (m_sphereCount > kMaxSpheres)
      fail(path, "brings the scene to " + std::to_string(m_sphereCount) + " spheres (copies included), more than the " +
                     std::to_string(kMaxSpheres) + " supported");
    if (instances.empty()) return;
    const std::size_t own = m_instancedSpheres.size();
    m_instancedSpheres.insert(m_instancedSpheres.end(), m_spheres.begin() + std::ptrdiff_t(first), m_spheres.end());
    m_spheres.resize(first);
    const std::uint32_t geometry = m_primitiveGeometries[0]++;
    for (std::size_t k = 0; k < instances.size(); ++k)
      m_sphereCopies.push_back({own, count, geometry, instances[k], m_objectIndex, k});
  }

  /// Where sphere `s` of copy `c` is named in messages: objects[2].instances[5] (centers[1]).
  std::string copyPath(const SphereCopy& c, const WorldSphere& s) const {
    const std::string object = element("objects", c.object);
    const std::string at = element(member(object, "instances"), c.index);
    return s.path == object ? at : at + " (" + s.path.substr(object.size() + 1) + ")";
  }

  void readGltf(const Json& v, const std::string& path) {
    checkKeys(v, path, {"type", "file", "transform"});
    const std::string where = member(path, "file");
    const Json& fileValue = require(v, path, "file");
    const std::string file = string(fileValue, where);
    if (file.empty()) fail(where, "must name a file, got \"\"");
    const fs::path resolved = resolve(file);
    const std::string ext = lowerExtension(resolved);
    if (ext != ".gltf" && ext != ".glb") fail(where, "must be a .gltf or .glb file, got " + describe(fileValue));
    glm::dmat4 transform(1.0);
    if (const Json* t = find(v, "transform")) transform = readTransform(*t, member(path, "transform"));

    const std::string key = resolved.string();
    auto [it, added] = m_fileIndex.emplace(key, m_files.size());
    if (added) {
      requireFile(resolved, where);
      GltfLoadOptions include;
      // relative to its own origin: the floats keep their precision before
      // the placement moves them (in double)
      include.recenter = true;
      include.maxVertices = m_options.maxVertices;
      include.maxTriangles = m_options.maxTriangles;
      IncludedFile loaded;
      try {
        loaded.scene = loadGltf(key, include);
      } catch (const SceneError& e) {
        fail(where, e.what());
      }
      loaded.materialBase = std::uint32_t(m_result.scene.materials.size());
      loaded.geometryBase = m_nextGeometry;
      for (const GeometryInstance& copy : loaded.scene.instances)
        m_nextGeometry = std::max(m_nextGeometry, loaded.geometryBase + copy.geometry + 1);
      m_result.scene.materials.insert(m_result.scene.materials.end(), loaded.scene.materials.begin(),
                                      loaded.scene.materials.end());
      // the file's textures, their slots renumbered past the scene's
      if (!loaded.scene.materialTextures.empty()) {
        std::uint32_t textureBase = 0;
        try {
          // given up: the included file's texels are not read again
          textureBase = m_result.scene.textures.append(std::move(loaded.scene.textures));
        } catch (const TextureError& e) {
          fail(where, e.what());
        }
        std::vector<WtTextureRef>& refs = m_result.scene.materialTextures;
        refs.resize(std::size_t(loaded.materialBase) * WT_TEXTURE_SLOTS);
        for (WtTextureRef ref : loaded.scene.materialTextures) {
          ref.texture += textureBase;
          refs.push_back(ref);
        }
        m_result.scene.textureSeconds += loaded.scene.textureSeconds;
      }
      m_result.scene.materialNames.insert(m_result.scene.materialNames.end(), loaded.scene.materialNames.begin(),
                                          loaded.scene.materialNames.end());
      const std::string label = resolved.filename().string();
      for (const std::string& w : loaded.scene.warnings) m_result.scene.addWarning(label + ": " + w);
      m_files.push_back(std::move(loaded));
    }
    const IncludedFile& included = m_files[it->second];
    m_placements.push_back({it->second, transform * glm::translate(glm::dmat4(1.0), included.scene.origin), path});
  }

  /// A triangle mesh from a PLY file with one material: an included file of
  /// its own (copies of one file with one material share its geometry).
  void readMesh(const Json& v, const std::string& path) {
    checkKeys(v, path, {"type", "file", "transform", "material"});
    const std::string where = member(path, "file");
    const Json& fileValue = require(v, path, "file");
    const std::string file = string(fileValue, where);
    if (file.empty()) fail(where, "must name a file, got \"\"");
    const fs::path resolved = resolve(file);
    if (lowerExtension(resolved) != ".ply") fail(where, "must be a .ply file, got " + describe(fileValue));
    glm::dmat4 transform(1.0);
    if (const Json* t = find(v, "transform")) transform = readTransform(*t, member(path, "transform"));
    const std::uint32_t material = materialOf(v, path);

    const std::string key = resolved.string() + "\n" + std::to_string(material);
    auto [it, added] = m_fileIndex.emplace(key, m_files.size());
    if (added) {
      requireFile(resolved, where);
      PlyMesh mesh;
      try {
        mesh = loadPlyMesh(resolved.string());
      } catch (const SceneError& e) {
        fail(where, e.what());
      }
      if (mesh.positions.size() > m_options.maxVertices || mesh.triangles.size() > m_options.maxTriangles)
        fail(where, std::to_string(mesh.positions.size()) + " vertices and " + std::to_string(mesh.triangles.size()) +
                        " triangles, more than the " + std::to_string(m_options.maxVertices) + " and " +
                        std::to_string(m_options.maxTriangles) + " supported");
      IncludedFile loaded;
      Scene& scene = loaded.scene;
      scene.sourceName = resolved.filename().string();
      // relative to the centre of its bounds, as glTF files are included: the
      // floats keep their precision before the placement moves them (in double)
      glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
      for (const glm::dvec3& p : mesh.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
      scene.origin = mesh.positions.empty() ? glm::dvec3(0.0) : 0.5 * (lo + hi);
      scene.positions.reserve(mesh.positions.size());
      for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        const glm::vec3 q(mesh.positions[i] - scene.origin);
        const glm::vec3 n = mesh.normals[i];
        scene.positions.push_back({q.x, q.y, q.z, 0.0f});
        scene.normals.push_back({n.x, n.y, n.z, 0.0f});
        scene.texcoords.push_back(mesh.texcoords.empty() ? glm::vec2(0.0f) : mesh.texcoords[i]);
      }
      // triangles name the scene's material itself (materialBase 0)
      for (const auto& t : mesh.triangles) scene.triangles.push_back({t[0], t[1], t[2], material});
      scene.instances.push_back({0, std::uint32_t(scene.triangles.size()), 0, glm::dmat4(1.0)});
      loaded.materialBase = 0;
      loaded.geometryBase = m_nextGeometry++;
      m_files.push_back(std::move(loaded));
    }
    const IncludedFile& included = m_files[it->second];
    m_placements.push_back({it->second, transform * glm::translate(glm::dmat4(1.0), included.scene.origin), path});
  }

  /// translate * rotate * scale (as a glTF node), or a matrix; in double.
  glm::dmat4 readTransform(const Json& v, const std::string& path) const {
    object(v, path);
    checkKeys(v, path, {"translate", "rotate", "quaternion", "scale", "matrix"});
    glm::dmat4 m(1.0);
    if (const Json* x = find(v, "matrix")) {
      const std::string where = member(path, "matrix");
      if (v.size() > 1) fail(where, "cannot be combined with translate, rotate, quaternion or scale");
      array(*x, where, 16, "numbers (column-major, as glTF)");
      double values[16];
      for (std::size_t i = 0; i < 16; ++i) values[i] = number((*x)[i], element(where, i));
      if (values[3] != 0.0 || values[7] != 0.0 || values[11] != 0.0 || values[15] != 1.0)
        fail(where, "must be affine: elements 3, 7, 11 and 15 (the last row) must be 0, 0, 0, 1");
      m = glm::make_mat4(values);
    } else {
      if (find(v, "rotate") && find(v, "quaternion")) fail(path, "give \"rotate\" or \"quaternion\", not both");
      if (const Json* x = find(v, "translate")) m = glm::translate(m, vec3(*x, member(path, "translate")));
      if (const Json* x = find(v, "rotate")) {
        const std::string where = member(path, "rotate");
        array(*x, where, 4, "numbers (axis x, y, z and degrees)");
        const glm::dvec3 axis(number((*x)[0], element(where, 0)), number((*x)[1], element(where, 1)),
                              number((*x)[2], element(where, 2)));
        const double degrees = number((*x)[3], element(where, 3));
        const double length = glm::length(axis);
        if (!(length > 0.0) || !std::isfinite(length)) fail(where, "the axis must not be (0, 0, 0)");
        m = glm::rotate(m, glm::radians(degrees), axis / length);
      }
      if (const Json* x = find(v, "quaternion")) {
        const std::string where = member(path, "quaternion");
        array(*x, where, 4, "numbers (x, y, z, w, as glTF)");
        double q[4];
        for (std::size_t i = 0; i < 4; ++i) q[i] = number((*x)[i], element(where, i));
        glm::dquat rotation(q[3], q[0], q[1], q[2]);  // glm takes w first
        const double length = glm::length(rotation);
        if (!(length > 0.0) || !std::isfinite(length)) fail(where, "must not be (0, 0, 0, 0)");
        m = m * glm::mat4_cast(rotation / length);
      }
      if (const Json* x = find(v, "scale")) {
        const std::string where = member(path, "scale");
        glm::dvec3 s = x->is_number() ? glm::dvec3(number(*x, where)) : vec3(*x, where);
        if (s.x == 0.0 || s.y == 0.0 || s.z == 0.0) fail(where, "must not be 0 (the object would be flat)");
        m = glm::scale(m, s);
      }
    }
    const double determinant = glm::determinant(glm::dmat3(m));
    if (!(determinant != 0.0) || !std::isfinite(determinant))
      fail(path, "is singular or not finite (determinant " + formatNumber(determinant) + ")");
    return m;
  }

  // the scene

  /// The origin (the camera, else the centre of the bounds), then everything
  /// written relative to it.
  void build() {
    Scene& scene = m_result.scene;
    const Placement* cameraSource = nullptr;
    if (!m_camera)
      for (const Placement& p : m_placements)
        if (m_files[p.file].scene.camera) {
          cameraSource = &p;
          break;
        }
    glm::dvec3 origin(0.0);
    if (m_options.recenter) {
      if (m_camera) origin = m_camera->from;
      else if (cameraSource)
        origin = glm::dvec3(cameraSource->world * glm::dvec4(glm::dvec3(m_files[cameraSource->file].scene.camera->cameraToWorld[3]), 1.0));
      else origin = boundsCentre();
    }
    scene.origin = origin;

    std::size_t vertices = 0, triangles = 0;
    for (const Placement& p : m_placements) {
      const Scene& src = m_files[p.file].scene;
      vertices += src.positions.size();
      triangles += src.triangles.size();
      if (vertices > m_options.maxVertices || triangles > m_options.maxTriangles ||
          vertices > std::numeric_limits<std::uint32_t>::max())
        fail(p.path, "brings the scene to " + std::to_string(vertices) + " vertices and " +
                         std::to_string(triangles) + " triangles, more than the " +
                         std::to_string(m_options.maxVertices) + " and " + std::to_string(m_options.maxTriangles) +
                         " supported");
    }
    scene.positions.reserve(vertices);
    scene.normals.reserve(vertices);
    scene.texcoords.reserve(vertices);
    scene.triangles.reserve(triangles);
    for (const Placement& p : m_placements) place(p, origin);

    if (m_camera) {
      CameraDesc desc;
      desc.name = "camera";
      desc.yfov = float(glm::radians(m_camera->fovDegrees));
      // glm::lookAt gives world-to-camera (looking down -Z); relative to the origin first, in double
      const glm::dmat4 view = glm::lookAt(m_camera->from - origin, m_camera->to - origin, m_camera->up);
      desc.cameraToWorld = glm::mat4(glm::inverse(view));
      scene.camera = desc;
    } else if (cameraSource) {
      CameraDesc desc = *m_files[cameraSource->file].scene.camera;
      glm::dmat4 world = cameraSource->world * glm::dmat4(desc.cameraToWorld);
      world[3] -= glm::dvec4(origin, 0.0);
      // a scaling placement scales the camera's distances (the file's camera
      // axes are unit): znear along its view axis, the orthographic extents
      // along theirs; the rays need rigid axes again (as the glTF loader makes them)
      desc.znear = float(desc.znear * glm::length(glm::dvec3(world[2])));
      if (desc.orthographic) {
        desc.xmag = float(desc.xmag * glm::length(glm::dvec3(world[0])));
        desc.ymag = float(desc.ymag * glm::length(glm::dvec3(world[1])));
      }
      desc.cameraToWorld = glm::mat4(rigidCameraTransform(world));
      scene.camera = desc;
    }

    scene.spheres.reserve(scene.spheres.size() + m_sphereCount);
    auto addSphere = [&](const glm::dvec3& world, double r, std::uint32_t material, const auto& path) {
      const glm::vec3 center(world - origin);
      const auto radius = float(r);
      if (!isFinite(center)) fail(path(), "the centre lies beyond the range of a float from the scene's origin");
      if (!(radius > 0.0f) || !std::isfinite(radius))
        fail(path(), "the radius " + formatNumber(r) + " is out of the range of a float");
      scene.spheres.push_back({center, radius, material});
    };
    for (const WorldSphere& s : m_spheres) addSphere(s.center, s.radius, s.material, [&] { return s.path; });
    for (const SphereCopy& c : m_sphereCopies) {
      const double scale = std::cbrt(std::fabs(glm::determinant(glm::dmat3(c.world))));
      scene.primitiveInstances.push_back({WT_PRIM_SPHERE, std::uint32_t(scene.spheres.size()), std::uint32_t(c.count),
                                          c.geometry, glm::translate(glm::dmat4(1.0), -origin) * c.world});
      for (std::size_t i = c.first; i < c.first + c.count; ++i) {
        const WorldSphere& s = m_instancedSpheres[i];
        addSphere(glm::dvec3(c.world * glm::dvec4(s.center, 1.0)), s.radius * scale, s.material,
                  [&] { return copyPath(c, s); });
      }
    }
    for (const WorldCurves& c : m_curves) placeCurves(c, origin);
    // SDF grids and displaced meshes: one per copy with "instances" (each a PrimitiveInstance), else one
    const glm::dmat4 toScene = glm::translate(glm::dmat4(1.0), -origin);
    for (WorldSdf& sdf : m_sdfs) {
      const std::size_t copies = std::max<std::size_t>(sdf.instances.size(), 1);
      for (std::size_t k = 0; k < copies; ++k) {
        const std::string where = sdf.instances.empty() ? sdf.path : element(member(sdf.path, "instances"), k);
        const glm::dmat4 world = sdf.instances.empty() ? glm::dmat4(1.0) : sdf.instances[k];
        SdfGrid grid = k + 1 == copies ? std::move(sdf.grid) : sdf.grid;
        if (!sdf.instances.empty()) grid.latticeToScene = world * grid.latticeToScene;
        grid.latticeToScene[3] -= glm::dvec4(origin, 0.0);
        for (int corner = 0; corner < 8; ++corner) {
          const glm::dvec3 c((corner & 1) ? grid.cells.x : 0u, (corner & 2) ? grid.cells.y : 0u, (corner & 4) ? grid.cells.z : 0u);
          if (!isFinite(glm::vec3(glm::dvec3(grid.latticeToScene * glm::dvec4(c, 1.0)))))
            fail(where, "the grid's box lies beyond the range of a float from the scene's origin");
        }
        if (!sdf.instances.empty())
          scene.primitiveInstances.push_back(
              {WT_PRIM_SDF_GRID, std::uint32_t(scene.sdfGrids.size()), 1u, sdf.geometry, toScene * world});
        scene.sdfGrids.push_back(std::move(grid));
      }
    }
    for (WorldDisplaced& d : m_displaced) {
      const std::size_t copies = std::max<std::size_t>(d.instances.size(), 1);
      for (std::size_t k = 0; k < copies; ++k) {
        const std::string where = d.instances.empty() ? d.path : element(member(d.path, "instances"), k);
        const glm::dmat4 world = d.instances.empty() ? glm::dmat4(1.0) : d.instances[k];
        DisplacedMesh mesh = k + 1 == copies ? std::move(d.mesh) : d.mesh;
        const glm::dmat3 linear(world);
        if (!d.instances.empty()) {
        // a similarity (readInstances): normals turn with it, displacements scale with it, a mirror swaps corners
        const double scale = std::cbrt(std::fabs(glm::determinant(linear)));
        for (glm::vec3& n : mesh.normals) {
          const glm::dvec3 m = linear * glm::dvec3(n);
          const double len = glm::length(m);
          n = len > 0.0 && std::isfinite(len) ? glm::vec3(m / len) : glm::vec3(0.0f);
        }
        if (glm::determinant(linear) < 0.0)
          for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
        mesh.scale = float(scale * double(mesh.scale));
        mesh.offset = float(scale * double(mesh.offset));
        if (!std::isfinite(mesh.scale) || !std::isfinite(mesh.offset))
          fail(where, "the displacement's scale and offset leave the range of a float");
        }
        mesh.positions.clear();
        mesh.positions.reserve(d.positions.size());
        for (std::size_t i = 0; i < d.positions.size(); ++i) {
          const glm::vec3 q(d.instances.empty() ? d.positions[i] - origin : glm::dvec3(world * glm::dvec4(d.positions[i], 1.0)) - origin);
          if (!isFinite(q)) fail(where, "vertex " + std::to_string(i) + " lies beyond the range of a float from the scene's origin");
          mesh.positions.push_back(q);
        }
        if (!d.instances.empty())
          scene.primitiveInstances.push_back(
              {WT_PRIM_DISPLACED, std::uint32_t(scene.displacedMeshes.size()), 1u, d.geometry, toScene * world});
        scene.displacedMeshes.push_back(std::move(mesh));
      }
    }
    if (scene.materials.empty()) {
      scene.materials.push_back(makePbrMaterial(glm::vec3(0.8f), 0.0f, 0.5f));
      scene.materialNames.push_back("(default)");
    }
  }

  /// Centre of everything's bounds (world, double), as the glTF loader does
  /// without a camera; 0 when the scene is empty or beyond float range.
  glm::dvec3 boundsCentre() const {
    glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    for (const Placement& p : m_placements) {
      const Aabb box = m_files[p.file].scene.bounds();
      if (box.empty()) continue;
      for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 c((corner & 1) ? box.hi.x : box.lo.x, (corner & 2) ? box.hi.y : box.lo.y,
                           (corner & 4) ? box.hi.z : box.lo.z);
        const glm::dvec3 w(p.world * glm::dvec4(c, 1.0));
        lo = glm::min(lo, w);
        hi = glm::max(hi, w);
      }
    }
    for (const WorldSphere& s : m_spheres) {
      lo = glm::min(lo, s.center - s.radius);
      hi = glm::max(hi, s.center + s.radius);
    }
    for (const SphereCopy& c : m_sphereCopies) {
      const double scale = std::cbrt(std::fabs(glm::determinant(glm::dmat3(c.world))));
      for (std::size_t i = c.first; i < c.first + c.count; ++i) {
        const WorldSphere& s = m_instancedSpheres[i];
        const glm::dvec3 centre(c.world * glm::dvec4(s.center, 1.0));
        lo = glm::min(lo, centre - scale * s.radius);
        hi = glm::max(hi, centre + scale * s.radius);
      }
    }
    for (const WorldCurves& c : m_curves)
      for (std::size_t k = 0; k < std::max<std::size_t>(c.instances.size(), 1); ++k) {
        const glm::dmat4 m = c.instances.empty() ? glm::dmat4(1.0) : c.instances[k];
        const double scale = std::cbrt(std::fabs(glm::determinant(glm::dmat3(m))));
        for (const glm::dvec4& p : c.points) {
          const glm::dvec3 q(m * glm::dvec4(glm::dvec3(p), 1.0));
          lo = glm::min(lo, q - scale * p.w);
          hi = glm::max(hi, q + scale * p.w);
        }
      }
    for (const WorldSdf& s : m_sdfs)
      for (std::size_t k = 0; k < std::max<std::size_t>(s.instances.size(), 1); ++k) {
        const glm::dmat4 m = (s.instances.empty() ? glm::dmat4(1.0) : s.instances[k]) * s.grid.latticeToScene;
        for (int corner = 0; corner < 8; ++corner) {
          const glm::dvec3 c((corner & 1) ? s.grid.cells.x : 0u, (corner & 2) ? s.grid.cells.y : 0u,
                             (corner & 4) ? s.grid.cells.z : 0u);
          const glm::dvec3 w(m * glm::dvec4(c, 1.0));
          lo = glm::min(lo, w);
          hi = glm::max(hi, w);
        }
      }
    for (const WorldDisplaced& d : m_displaced)
      for (std::size_t k = 0; k < std::max<std::size_t>(d.instances.size(), 1); ++k) {
        const glm::dmat4 m = d.instances.empty() ? glm::dmat4(1.0) : d.instances[k];
        for (const glm::dvec3& p : d.positions) {
          const glm::dvec3 q(m * glm::dvec4(p, 1.0));
          lo = glm::min(lo, q);
          hi = glm::max(hi, q);
        }
      }
    const double kFloatMax = std::numeric_limits<float>::max();
    if (lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z && isFinite(lo) && isFinite(hi) &&
        glm::all(glm::lessThanEqual(glm::max(glm::abs(lo), glm::abs(hi)), glm::dvec3(kFloatMax))))
      return 0.5 * (lo + hi);
    return glm::dvec3(0.0);
  }

  /// Append a curves object's strands, moved to the origin, and their children.
  void placeCurves(const WorldCurves& c, const glm::dvec3& origin) {
    if (!c.instances.empty()) return placeCurveCopies(c, origin);
    Scene& scene = m_result.scene;
    const auto firstGuide = std::uint32_t(scene.curves.size());
    std::size_t next = 0;
    for (std::uint32_t count : c.counts) {
      Curve curve;
      curve.firstPoint = std::uint32_t(scene.curvePoints.size());
      curve.pointCount = count;
      curve.material = c.material;
      curve.basis = c.basis;
      for (std::uint32_t i = 0; i < count; ++i, ++next) {
        const glm::dvec4& p = c.points[next];
        const glm::vec3 q(glm::dvec3(p) - origin);
        const auto r = float(p.w);
        if (!isFinite(q))
          fail(c.path, "strand " + std::to_string(scene.curves.size() - firstGuide) + ", point " + std::to_string(i) +
                           " lies beyond the range of a float from the scene's origin");
        if (!std::isfinite(r))
          fail(c.path, "strand " + std::to_string(scene.curves.size() - firstGuide) + ", point " + std::to_string(i) +
                           ": the radius " + formatNumber(p.w) + " is out of the range of a float");
        scene.curvePoints.push_back({q.x, q.y, q.z, r});
      }
      scene.curves.push_back(curve);
    }
    addChildCurves(scene, firstGuide, std::uint32_t(c.counts.size()), c.children, float(c.childRadius), c.seed);
  }

  /// Append a curves object with "instances": its strands and children made
  /// once about their own centre (so the children are the same in every
  /// copy), then one moved copy per transform, each a PrimitiveInstance.
  void placeCurveCopies(const WorldCurves& c, const glm::dvec3& origin) {
    Scene& scene = m_result.scene;
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (const glm::dvec4& p : c.points) lo = glm::min(lo, glm::dvec3(p)), hi = glm::max(hi, glm::dvec3(p));
    const glm::dvec3 centre = 0.5 * (lo + hi);
    Scene own;
    std::size_t next = 0;
    for (std::uint32_t count : c.counts) {
      own.curves.push_back({std::uint32_t(own.curvePoints.size()), count, c.material, c.basis});
      for (std::uint32_t i = 0; i < count; ++i, ++next) {
        const glm::dvec4& p = c.points[next];
        const glm::vec3 q(glm::dvec3(p) - centre);
        if (!isFinite(q) || !std::isfinite(float(p.w)))
          fail(c.path, "strand " + std::to_string(own.curves.size() - 1) + ", point " + std::to_string(i) +
                           " is beyond the range of a float from the strands' centre");
        own.curvePoints.push_back({q.x, q.y, q.z, float(p.w)});
      }
    }
    addChildCurves(own, 0, std::uint32_t(c.counts.size()), c.children, float(c.childRadius), c.seed);
    for (std::size_t k = 0; k < c.instances.size(); ++k) {
      const glm::dmat4 m = glm::translate(glm::dmat4(1.0), -origin) * c.instances[k] * glm::translate(glm::dmat4(1.0), centre);
      const double scale = std::cbrt(std::fabs(glm::determinant(glm::dmat3(m))));
      const auto firstCurve = std::uint32_t(scene.curves.size());
      for (const Curve& curve : own.curves) {
        Curve moved = curve;
        moved.firstPoint = std::uint32_t(scene.curvePoints.size());
        for (std::uint32_t i = 0; i < curve.pointCount; ++i) {
          const WtVec4& p = own.curvePoints[curve.firstPoint + i];
          const glm::vec3 q(glm::dvec3(m * glm::dvec4(p.x, p.y, p.z, 1.0)));
          const auto r = float(scale * double(p.w));
          if (!isFinite(q) || !std::isfinite(r))
            fail(element(member(c.path, "instances"), k),
                 "strand " + std::to_string(&curve - own.curves.data()) + ", point " + std::to_string(i) +
                     " lies beyond the range of a float from the scene's origin");
          scene.curvePoints.push_back({q.x, q.y, q.z, r});
        }
        scene.curves.push_back(moved);
      }
      scene.primitiveInstances.push_back(
          {WT_PRIM_CURVE, firstCurve, std::uint32_t(own.curves.size()), c.geometry, m});
    }
  }

  /// Append one placed copy of an included file, moved to the origin.
  void place(const Placement& p, const glm::dvec3& origin) {
    Scene& dst = m_result.scene;
    const IncludedFile& file = m_files[p.file];
    const Scene& src = file.scene;
    const glm::dmat3 linear(p.world);
    // the placement's offset to the origin, once, in double: floats see only what is near
    const glm::dvec3 offset = glm::dvec3(p.world[3]) - origin;
    // readTransform refused singular transforms
    const glm::dmat3 normalMatrix = glm::transpose(glm::inverse(linear));
    // a mirroring placement turns counter-clockwise into clockwise: swap two corners
    const bool flip = glm::determinant(linear) < 0.0;

    const auto vertexBase = std::uint32_t(dst.positions.size());
    const auto triangleBase = std::uint32_t(dst.triangles.size());
    for (std::size_t i = 0; i < src.positions.size(); ++i) {
      const WtVec4& sp = src.positions[i];
      const glm::vec3 q(linear * glm::dvec3(sp.x, sp.y, sp.z) + offset);
      if (!isFinite(q))
        fail(p.path, "vertex " + std::to_string(i) + " of " + src.sourceName +
                         " lies beyond the range of a float from the scene's origin");
      dst.positions.push_back({q.x, q.y, q.z, 0.0f});
      const WtVec4& sn = src.normals[i];
      glm::vec3 n(normalMatrix * glm::dvec3(sn.x, sn.y, sn.z));
      const float length = glm::length(n);
      n = std::isfinite(length) && length > 0.0f ? n / length : glm::vec3(0.0f);
      dst.normals.push_back({n.x, n.y, n.z, 0.0f});
      dst.texcoords.push_back(i < src.texcoords.size() ? src.texcoords[i] : glm::vec2(0.0f));
    }
    // the attributes only some files have: every vertex gets one once any does
    auto appendOptional = [&](auto& to, const auto& from, auto fallback, auto convert) {
      if (to.empty() && from.empty()) return;
      to.resize(vertexBase, fallback);
      for (std::size_t i = 0; i < src.positions.size(); ++i) to.push_back(i < from.size() ? convert(from[i]) : fallback);
    };
    appendOptional(dst.texcoords1, src.texcoords1, glm::vec2(0.0f), [](glm::vec2 v) { return v; });
    appendOptional(dst.colors, src.colors, glm::vec4(1.0f), [](glm::vec4 v) { return v; });
    // tangents move with the surface; a mirroring placement flips the bitangent's side
    appendOptional(dst.tangents, src.tangents, glm::vec4(0.0f), [&](glm::vec4 t) {
      const glm::vec3 moved(linear * glm::dvec3(t.x, t.y, t.z));
      const float length = glm::length(moved);
      if (!(length > 0.0f) || !std::isfinite(length)) return glm::vec4(0.0f);
      return glm::vec4(moved / length, (t.w < 0.0f) != flip ? -1.0f : 1.0f);
    });
    for (WtTriangle t : src.triangles) {
      t.v0 += vertexBase, t.v1 += vertexBase, t.v2 += vertexBase;
      if (flip) std::swap(t.v1, t.v2);
      t.material += file.materialBase;
      dst.triangles.push_back(t);
    }
    // copies of one file share its geometry ids: one BVH per geometry serves them all
    glm::dmat4 placement(linear);
    placement[3] = glm::dvec4(offset, 1.0);
    for (GeometryInstance copy : src.instances) {
      copy.firstTriangle += triangleBase;
      copy.geometry += file.geometryBase;
      copy.transform = placement * copy.transform;
      dst.instances.push_back(copy);
    }
    for (PunctualLight light : src.lights) {
      light.position = glm::vec3(linear * glm::dvec3(light.position) + offset);
      const glm::dvec3 direction = linear * glm::dvec3(light.direction);
      if (light.type != WT_LIGHT_POINT) light.direction = glm::vec3(glm::normalize(direction));
      if (!isFinite(light.position) || !isFinite(light.direction))
        fail(p.path, "light '" + light.name + "' lies beyond the range of a float from the scene's origin");
      dst.lights.push_back(light);
    }
  }

  const std::string m_name;
  const fs::path m_baseDir;
  const GltfLoadOptions& m_options;
  SceneFile m_result;
  std::map<std::string, std::uint32_t> m_materialIndex;
  int m_defaultMaterial = -1;
  std::optional<LookAt> m_camera;
  std::vector<IncludedFile> m_files;
  std::map<std::string, std::size_t> m_fileIndex;  ///< resolved path -> m_files
  std::vector<Placement> m_placements;
  std::vector<WorldSphere> m_spheres;
  std::vector<WorldCurves> m_curves;
  std::vector<WorldSdf> m_sdfs;
  std::vector<WorldDisplaced> m_displaced;
  std::uint64_t m_curvePoints = 0;  ///< children and copies included
  std::uint32_t m_nextGeometry = 0;
  std::vector<SphereCopy> m_sphereCopies;
  std::vector<WorldSphere> m_instancedSpheres;  ///< the spheres of objects with "instances", as written
  std::size_t m_sphereCount = 0;                ///< copies included
  std::size_t m_objectIndex = 0;                ///< the object being read
  std::uint32_t m_primitiveGeometries[4] = {0, 0, 0, 0};  ///< the next PrimitiveInstance::geometry of spheres, curves, SDF grids, displaced meshes
  std::uint64_t m_copiedFloats = 0;                 ///< SDF grids' and displaced meshes' floats, copies included
};

}  // namespace

SceneFile loadSceneFileFromMemory(std::string_view json, const std::string& name, const std::string& baseDir,
                                  const GltfLoadOptions& options) {
  try {
    return Loader(name, baseDir, options).run(json);
  } catch (const SceneError&) {
    throw;
  } catch (const nlohmann::json::exception& e) {
    // every access is checked first; this is a safety net, not a path
    throw SceneError(name + ": " + e.what());
  } catch (const std::bad_alloc&) {
    throw SceneError(name + ": out of memory while loading the scene");
  } catch (const std::length_error&) {
    throw SceneError(name + ": out of memory while loading the scene");
  }
}

SceneFile loadSceneFile(const std::string& path, const GltfLoadOptions& options) {
  const fs::path file(path);
  const std::string name = file.filename().string().empty() ? path : file.filename().string();
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    throw SceneError(name + ": cannot open " + path + (fs::exists(file, ec) ? " (not a regular file)" : " (no such file)"));
  const std::uintmax_t size = fs::file_size(file, ec);
  if (!ec && size > kMaxFileBytes)
    throw SceneError(name + ": the file is too large (" + std::to_string(size) + " bytes)");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw SceneError(name + ": cannot open " + path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw SceneError(name + ": cannot read " + path);
  std::string baseDir = file.parent_path().string();
  SceneFile result = loadSceneFileFromMemory(text, name, baseDir.empty() ? "." : baseDir, options);
  result.scene.sourceName = path;
  return result;
}

}  // namespace wt
