// glTF 2.0 to Scene. tinygltf parses the JSON and resolves buffers; every
// offset, length, stride and index is then checked here before it is read,
// because tinygltf 2.7 leaves most of that to the caller (and does not apply
// sparse accessors at all).
#include "scene/gltf_loader.h"

#include "scene/generators.h"
#include "scene/tangents.h"
#include "texture/texture.h"

#include <tiny_gltf.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <optional>
#include <sstream>
#include <type_traits>
#include <utility>
#include <vector>

namespace wt {
namespace {

constexpr const char* kEmissiveStrength = "KHR_materials_emissive_strength";
constexpr const char* kLightsPunctual = "KHR_lights_punctual";
constexpr const char* kTransmission = "KHR_materials_transmission";
constexpr const char* kIor = "KHR_materials_ior";
constexpr const char* kVolume = "KHR_materials_volume";
constexpr const char* kTextureTransform = "KHR_texture_transform";
constexpr const char* kSpecular = "KHR_materials_specular";
constexpr const char* kClearcoat = "KHR_materials_clearcoat";
constexpr const char* kSheen = "KHR_materials_sheen";
constexpr const char* kUnlit = "KHR_materials_unlit";
constexpr const char* kAnisotropy = "KHR_materials_anisotropy";
constexpr const char* kIridescence = "KHR_materials_iridescence";
constexpr const char* kDispersion = "KHR_materials_dispersion";
constexpr const char* kGpuInstancing = "EXT_mesh_gpu_instancing";
/// Extensions whose absence changes where the geometry is or how its bytes
/// read: a file that requires one cannot be drawn correctly without it.
constexpr std::array<const char*, 3> kGeometryExtensions = {
    "KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_mesh_quantization"};
/// Nodes reached through shared children multiply; stop runaway graphs.
constexpr std::size_t kMaxNodeInstances = std::size_t(1) << 22;
/// An accessor without a buffer view is materialized as zeros; its count is
/// not backed by file bytes, so it gets its own limit.
constexpr std::size_t kMaxUnbackedElements = std::size_t(1) << 26;
constexpr std::uint32_t kGlbMagic = 0x46546C67;      // "glTF"
constexpr std::uint32_t kGlbChunkJson = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kGlbChunkBin = 0x004E4942;   // "BIN\0"

using tinygltf::Accessor;
using tinygltf::Model;

// glTF enums as text

std::string componentTypeName(int componentType) {
  switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: return "BYTE";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return "UNSIGNED_BYTE";
    case TINYGLTF_COMPONENT_TYPE_SHORT: return "SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return "UNSIGNED_SHORT";
    case TINYGLTF_COMPONENT_TYPE_INT: return "INT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return "UNSIGNED_INT";
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return "FLOAT";
    case TINYGLTF_COMPONENT_TYPE_DOUBLE: return "DOUBLE";
    default: return std::to_string(componentType);
  }
}

const char* accessorTypeName(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    case TINYGLTF_TYPE_MAT2: return "MAT2";
    case TINYGLTF_TYPE_MAT3: return "MAT3";
    case TINYGLTF_TYPE_MAT4: return "MAT4";
    default: return "UNKNOWN";
  }
}

const char* vectorTypeName(int components) {
  switch (components) {
    case 1: return "SCALAR";
    case 2: return "VEC2";
    case 3: return "VEC3";
    default: return "VEC4";
  }
}

const char* modeName(int mode) {
  switch (mode) {
    case TINYGLTF_MODE_POINTS: return "POINTS";
    case TINYGLTF_MODE_LINE: return "LINES";
    case TINYGLTF_MODE_LINE_LOOP: return "LINE_LOOP";
    case TINYGLTF_MODE_LINE_STRIP: return "LINE_STRIP";
    case TINYGLTF_MODE_TRIANGLES: return "TRIANGLES";
    case TINYGLTF_MODE_TRIANGLE_STRIP: return "TRIANGLE_STRIP";
    case TINYGLTF_MODE_TRIANGLE_FAN: return "TRIANGLE_FAN";
    default: return "unknown";
  }
}

/// Bytes per component of the types glTF 2.0 allows; 0 for anything else
/// (tinygltf also lets INT and DOUBLE through, which glTF does not define).
std::size_t componentSize(int componentType) {
  switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

int componentCount(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    default: return 0;  // matrices are never read here
  }
}

std::string joinNames(const std::vector<int>& componentTypes) {
  std::string text;
  for (std::size_t i = 0; i < componentTypes.size(); ++i) {
    if (i > 0) text += i + 1 == componentTypes.size() ? " or " : ", ";
    text += componentTypeName(componentTypes[i]);
  }
  return text;
}

std::string formatVec3(const glm::vec3& v) {
  std::ostringstream out;
  out << '(' << v.x << ", " << v.y << ", " << v.z << ')';
  return out.str();
}

/// a * b + c, or false when it does not fit a size_t.
bool mulAdd(std::size_t a, std::size_t b, std::size_t c, std::size_t* result) {
  std::size_t product = 0;
  return !__builtin_mul_overflow(a, b, &product) && !__builtin_add_overflow(product, c, result);
}

/// a + b, or the largest size_t when that does not fit (counts from the file can be anything).
std::size_t saturatingAdd(std::size_t a, std::size_t b) {
  std::size_t sum = 0;
  return __builtin_add_overflow(a, b, &sum) ? std::numeric_limits<std::size_t>::max() : sum;
}

std::uint32_t readU32(const unsigned char* p) {
  // glTF is little-endian, and so is every machine we build for
  std::uint32_t v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

/// One component as a number; integer types are mapped to [0,1] or [-1,1]
/// when `normalized` (glTF 2.0, "Animation" / "Accessor data types").
double readComponent(const unsigned char* p, int componentType, bool normalized) {
  switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      std::int8_t v;
      std::memcpy(&v, p, 1);
      return normalized ? std::max(double(v) / 127.0, -1.0) : double(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return normalized ? double(p[0]) / 255.0 : double(p[0]);
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      std::int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(double(v) / 32767.0, -1.0) : double(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      std::uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? double(v) / 65535.0 : double(v);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      std::uint32_t v = readU32(p);
      return normalized ? double(v) / 4294967295.0 : double(v);
    }
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
      float v;
      std::memcpy(&v, p, 4);
      return double(v);
    }
    default: return 0.0;  // unreachable: component types are checked before reading
  }
}

/// Components per element of the types readAccessor produces.
template <typename T>
constexpr int kComponents = std::is_arithmetic_v<T> ? 1 : int(sizeof(T) / sizeof(float));

template <typename T>
T readElement(const unsigned char* p, int componentType, bool normalized) {
  const std::size_t size = componentSize(componentType);
  T element{};
  for (int c = 0; c < kComponents<T>; ++c) {
    double v = readComponent(p + std::size_t(c) * size, componentType, normalized);
    if constexpr (std::is_arithmetic_v<T>)
      element = T(v);  // integer T only reads unsigned integer components
    else
      element[c] = float(v);
  }
  return element;
}

/// Room for n elements, growing the capacity at least twofold: reserving
/// exactly what one more instance needs reallocates (and copies) the whole
/// scene for every instance, quadratic in the instance count.
template <class T>
void reserveGrowing(std::vector<T>& v, std::size_t n) {
  if (n > v.capacity()) v.reserve(std::max(n, 2 * v.capacity()));
}

bool isFinite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Keep every image's bytes as they are: the converter decodes the images
/// materials use, once it knows how (sRGB or linear), and warns for the
/// formats it cannot read rather than failing the load.
bool keepImageBytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                    const unsigned char* bytes, int size, void*) {
  image->image.assign(bytes, bytes + std::max(size, 0));
  image->width = image->height = -1;
  return true;
}

/// How a primitive reads one accessor, for the checks and the messages.
struct AccessorUse {
  std::string where;               ///< "mesh 0, primitive 1"
  std::string semantic;            ///< "POSITION", "indices", ...
  std::vector<int> componentTypes; ///< allowed component types
  bool integersNormalized = false; ///< integer components must be normalized
};

/// A primitive decoded once, in mesh space, and reused by every node that
/// instances its mesh.
struct DecodedPrimitive {
  bool skipped = false;
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;     ///< empty: the primitive has none
  std::vector<glm::vec2> texcoords;   ///< empty: the primitive has none
  std::vector<glm::vec2> texcoords1;  ///< TEXCOORD_1; empty: none
  std::vector<glm::vec4> colors;      ///< COLOR_0 (alpha 1 for a VEC3 one); empty: none
  std::vector<glm::vec4> tangents;    ///< TANGENT (xyz, w the bitangent's sign), from the file or generated for a normal map; empty: none
  std::vector<std::uint32_t> corners; ///< 3 per triangle, indices into positions
  std::uint32_t material = 0;
  glm::dvec3 lo{0.0}, hi{0.0};        ///< bounds of positions, mesh space
  std::uint32_t geometry = 0;         ///< the same for primitives of the same positions, indices and mode
};

/// A node's mesh in the world (before the origin is subtracted).
struct MeshInstance {
  std::size_t node, mesh;
  glm::dmat4 world;
};

/// A node's KHR_lights_punctual light, placed once the origin is known.
struct LightInstance {
  std::string nodeLabel;
  const tinygltf::Value* extension;  ///< in the model, which outlives the conversion
  glm::dmat4 world;
};

class Converter {
 public:
  Converter(const Model& model, std::string name, const GltfLoadOptions& options, Scene& scene)
      : m_model(model), m_name(std::move(name)), m_options(options), m_scene(scene) {}

  void run() {
    checkExtensions();
    convertMaterials();
    addPendingTextures();
    traverse(chooseRoots());
    chooseCamera();
    chooseOrigin();
    for (const MeshInstance& instance : m_meshInstances) emitMesh(instance);
    for (const LightInstance& instance : m_lightInstances)
      placeLight(instance.nodeLabel, *instance.extension, instance.world);
    if (m_scene.camera) m_scene.camera->cameraToWorld = glm::mat4(shifted(m_cameraWorld));
    reportDegenerateTriangles();
    if (m_scene.materials.empty()) defaultMaterial();
    if (!m_model.animations.empty())
      m_scene.addWarning("animations are not supported; the static pose is drawn");
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw SceneError(m_name + ": " + what); }

  // extensions

  void checkExtensions() {
    for (const std::string& ext : m_model.extensionsRequired) {
      if (std::find(kGeometryExtensions.begin(), kGeometryExtensions.end(), ext) !=
          kGeometryExtensions.end())
        fail("requires extension " + ext + ", which is not supported");
    }
    for (const std::string& ext : m_model.extensionsUsed) {
      if (ext == kEmissiveStrength || ext == kLightsPunctual || ext == kTransmission || ext == kIor ||
          ext == kVolume || ext == kSpecular || ext == kClearcoat || ext == kSheen || ext == kUnlit || ext == kAnisotropy ||
          ext == kIridescence || ext == kDispersion ||
          ext == kGpuInstancing || ext == kTextureTransform)
        continue;
      bool required = std::find(m_model.extensionsRequired.begin(), m_model.extensionsRequired.end(),
                                ext) != m_model.extensionsRequired.end();
      m_scene.addWarning(ext + " is not supported; ignored" +
                         (required ? " (the file marks it required; the result may look wrong)" : ""));
    }
  }

  // materials

  std::uint32_t defaultMaterial() {
    if (m_defaultMaterial < 0) {
      m_defaultMaterial = int(m_scene.materials.size());
      // the specification's default material: every factor at its default
      m_scene.materials.push_back(makePbrMaterial(glm::vec3(1.0f), 1.0f, 1.0f));
      m_scene.materialNames.push_back("default");
    }
    return std::uint32_t(m_defaultMaterial);
  }

  void convertMaterials() {
    for (std::size_t i = 0; i < m_model.materials.size(); ++i) {
      const tinygltf::Material& src = m_model.materials[i];
      const std::string label = "material " + std::to_string(i) +
                                (src.name.empty() ? "" : " '" + src.name + "'");
      const tinygltf::PbrMetallicRoughness& pbr = src.pbrMetallicRoughness;

      glm::vec3 albedo(1.0f);
      if (pbr.baseColorFactor.size() >= 3)
        albedo = glm::vec3(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]),
                           float(pbr.baseColorFactor[2]));
      if (!isFinite(albedo)) fail(label + ": baseColorFactor is not finite");
      glm::vec3 clamped = glm::clamp(albedo, glm::vec3(0.0f), glm::vec3(1.0f));
      if (clamped != albedo)
        m_scene.addWarning(label + ": baseColorFactor " + formatVec3(albedo) +
                           " is outside [0,1]; clamped");

      glm::vec3 emissive(0.0f);
      if (src.emissiveFactor.size() >= 3)
        emissive = glm::vec3(float(src.emissiveFactor[0]), float(src.emissiveFactor[1]),
                             float(src.emissiveFactor[2]));
      float strength = 1.0f;
      auto ext = src.extensions.find(kEmissiveStrength);
      if (ext != src.extensions.end() && ext->second.IsObject() &&
          ext->second.Has("emissiveStrength") && ext->second.Get("emissiveStrength").IsNumber())
        strength = float(ext->second.Get("emissiveStrength").GetNumberAsDouble());
      glm::vec3 emission = emissive * strength;
      if (!isFinite(emission)) fail(label + ": emission is not finite");
      if (glm::any(glm::lessThan(emission, glm::vec3(0.0f)))) {
        m_scene.addWarning(label + ": negative emission " + formatVec3(emission) + "; clamped to 0");
        emission = glm::max(emission, glm::vec3(0.0f));
      }

      auto unitFactor = [&](double v, const char* what) {
        if (!std::isfinite(v)) fail(label + ": " + what + " is not finite");
        if (v < 0.0 || v > 1.0) m_scene.addWarning(label + ": " + what + " " + std::to_string(v) + " is outside [0,1]; clamped");
        return float(std::clamp(v, 0.0, 1.0));
      };
      const float metallic = unitFactor(pbr.metallicFactor, "metallicFactor");
      const float roughness = unitFactor(pbr.roughnessFactor, "roughnessFactor");

      // glTF draws a single-sided material's back face not at all: it emits from the front only
      WtMaterial material = makePbrMaterial(clamped, metallic, roughness, emission, src.doubleSided);
      if (pbr.baseColorFactor.size() >= 4) material.alpha = unitFactor(pbr.baseColorFactor[3], "baseColorFactor alpha");
      setAlphaMode(src, label, material);
      material = withTransmissionExtensions(src, label, material);
      material = withLayerExtensions(src, label, material);
      material.priority = nestedPriority(src, label, material);
      material.dispersion = dispersionOf(src, label, material);

      // textures (occlusion is not one: a path tracer finds the occlusion itself)
      std::array<WtTextureRef, WT_TEXTURE_SLOTS> refs{};
      auto slot = [&](std::uint32_t s, const char* name, const TextureUse& use, bool srgb) {
        if (use.index < 0) return;
        if (std::optional<WtTextureRef> ref = textureRef(label + " " + name, use, srgb)) {
          refs[s] = *ref;
          material.texture_mask |= 1u << s;
        }
      };
      slot(WT_TEXTURE_SLOT_BASE_COLOR, "baseColorTexture", TextureUse(pbr.baseColorTexture), true);
      slot(WT_TEXTURE_SLOT_METALLIC_ROUGHNESS, "metallicRoughnessTexture", TextureUse(pbr.metallicRoughnessTexture), false);
      slot(WT_TEXTURE_SLOT_NORMAL, "normalTexture", TextureUse(src.normalTexture), false);
      slot(WT_TEXTURE_SLOT_EMISSIVE, "emissiveTexture", TextureUse(src.emissiveTexture), true);
      // the extensions' textures, where the extension's factor leaves them something to scale
      auto extensionSlot = [&](const char* extension, const char* name, std::uint32_t s, bool srgb, bool used,
                               bool normal = false) {
        auto it = src.extensions.find(extension);
        if (!used || it == src.extensions.end() || !it->second.IsObject() || !it->second.Has(name)) return;
        slot(s, name, extensionTextureUse(it->second.Get(name), label + " " + extension + " " + name, normal), srgb);
      };
      const bool coated = material.clearcoat > 0.0f;
      const bool sheen = material.sheen.x > 0.0f || material.sheen.y > 0.0f || material.sheen.z > 0.0f;
      extensionSlot(kTransmission, "transmissionTexture", WT_TEXTURE_SLOT_TRANSMISSION, false, material.transmission > 0.0f);
      extensionSlot(kSpecular, "specularTexture", WT_TEXTURE_SLOT_SPECULAR, false, true);
      extensionSlot(kSpecular, "specularColorTexture", WT_TEXTURE_SLOT_SPECULAR_COLOR, true, true);
      extensionSlot(kClearcoat, "clearcoatTexture", WT_TEXTURE_SLOT_CLEARCOAT, false, coated);
      extensionSlot(kClearcoat, "clearcoatRoughnessTexture", WT_TEXTURE_SLOT_CLEARCOAT_ROUGHNESS, false, coated);
      extensionSlot(kClearcoat, "clearcoatNormalTexture", WT_TEXTURE_SLOT_CLEARCOAT_NORMAL, false, coated, true);
      extensionSlot(kSheen, "sheenColorTexture", WT_TEXTURE_SLOT_SHEEN_COLOR, true, sheen);
      extensionSlot(kSheen, "sheenRoughnessTexture", WT_TEXTURE_SLOT_SHEEN_ROUGHNESS, false, sheen);
      extensionSlot(kAnisotropy, "anisotropyTexture", WT_TEXTURE_SLOT_ANISOTROPY, false, material.anisotropy > 0.0f);
      const bool iridescent = material.iridescence.x > 0.0f;
      extensionSlot(kIridescence, "iridescenceTexture", WT_TEXTURE_SLOT_IRIDESCENCE, false, iridescent);
      extensionSlot(kIridescence, "iridescenceThicknessTexture", WT_TEXTURE_SLOT_IRIDESCENCE_THICKNESS, false, iridescent);
      // unlit: the base colour texture colours the emission (unlitMaterial moves the slot)
      if (material.texture_mask != 0u) {
        m_scene.materialTextures.resize(m_scene.materials.size() * WT_TEXTURE_SLOTS);
        m_scene.materialTextures.insert(m_scene.materialTextures.end(), refs.begin(), refs.end());
      }
      if (materialExtension(src, label, kUnlit)) material = unlitMaterial(src, label, material);
      m_scene.materials.push_back(material);
      m_scene.materialNames.push_back(src.name.empty() ? "material " + std::to_string(i) : src.name);
    }
  }

  /// alphaMode and alphaCutoff (kernels/materials/alpha.cl). An unknown mode
  /// is drawn as OPAQUE (the specification's default) and a negative cutoff
  /// as 0, each with a warning naming the material; a cutoff that is not a
  /// number is an error.
  void setAlphaMode(const tinygltf::Material& src, const std::string& label, WtMaterial& material) {
    if (src.alphaMode == "MASK") {
      material.alpha_mode = WT_ALPHA_MASK;
    } else if (src.alphaMode == "BLEND") {
      material.alpha_mode = WT_ALPHA_BLEND;
    } else {
      material.alpha_mode = WT_ALPHA_OPAQUE;
      if (src.alphaMode != "OPAQUE")
        m_scene.addWarning(label + ": alphaMode '" + src.alphaMode +
                           "' is not OPAQUE, MASK or BLEND; drawn as OPAQUE");
    }
    // tinygltf gives the specification's default, 0.5, where the file has none
    double cutoff = src.alphaCutoff;
    if (!std::isfinite(cutoff)) fail(label + ": alphaCutoff is not finite");
    if (cutoff < 0.0) {
      m_scene.addWarning(label + ": alphaCutoff " + std::to_string(cutoff) + " is negative; 0 used (nothing is cut out)");
      cutoff = 0.0;
    }
    material.alpha_cutoff = float(cutoff);
  }

  /// Where a material reads a texture: glTF's textureInfo.
  struct TextureUse {
    int index = -1;
    int texCoord = 0;
    double scale = 1.0;  ///< normalTexture.scale
    const tinygltf::ExtensionMap* extensions = nullptr;
    const tinygltf::Value* transform = nullptr;  ///< KHR_texture_transform of an extension's textureInfo
    TextureUse() = default;
    explicit TextureUse(const tinygltf::TextureInfo& t) : index(t.index), texCoord(t.texCoord), extensions(&t.extensions) {}
    explicit TextureUse(const tinygltf::NormalTextureInfo& t)
        : index(t.index), texCoord(t.texCoord), scale(t.scale), extensions(&t.extensions) {}
    explicit TextureUse(const tinygltf::OcclusionTextureInfo& t)
        : index(t.index), texCoord(t.texCoord), extensions(&t.extensions) {}
  };

  /// An extension's textureInfo, which tinygltf leaves as JSON (`normal`: a
  /// normalTextureInfo, with its scale).
  TextureUse extensionTextureUse(const tinygltf::Value& v, const std::string& who, bool normal = false) const {
    if (!v.IsObject()) fail(who + " is not an object");
    TextureUse use;
    auto integer = [&](const char* name, int fallback) {
      if (!v.Has(name)) return fallback;
      const tinygltf::Value& n = v.Get(name);
      if (!n.IsNumber() || n.GetNumberAsDouble() != std::floor(n.GetNumberAsDouble()) ||
          std::fabs(n.GetNumberAsDouble()) > 1e9)
        fail(who + ": " + name + " is not an integer");
      return int(n.GetNumberAsDouble());
    };
    use.index = integer("index", -1);
    if (use.index < 0) fail(who + ": index is missing or negative");
    use.texCoord = integer("texCoord", 0);
    if (normal) use.scale = extensionNumber(v, "scale", 1.0, who);
    if (v.Has("extensions") && v.Get("extensions").IsObject() && v.Get("extensions").Has(kTextureTransform))
      use.transform = &v.Get("extensions").Get(kTextureTransform);
    return use;
  }

  /// The slot reference for texture use `use` (`who` names the material and
  /// slot), or nothing, with a warning, where the texture cannot be read (an
  /// unsupported image format or texture coordinate set): the material
  /// keeps its factors there.
  std::optional<WtTextureRef> textureRef(const std::string& who, const TextureUse& use, bool srgb) {
    if (std::size_t(use.index) >= m_model.textures.size())
      fail(who + " references missing texture " + std::to_string(use.index));
    const tinygltf::Value* transform = use.transform;
    if (use.extensions) {
      auto it = use.extensions->find(kTextureTransform);
      if (it != use.extensions->end()) transform = &it->second;
    }
    WtTextureRef ref{};
    ref.texture = 0;
    ref.texcoord = std::uint32_t(use.texCoord);
    ref.scale = float(use.scale);
    if (!std::isfinite(ref.scale)) fail(who + ": scale is not finite");
    ref.transform_u = {1.0f, 0.0f, 0.0f, 0.0f};
    ref.transform_v = {0.0f, 1.0f, 0.0f, 0.0f};
    if (transform) {
      if (!transform->IsObject()) fail(who + ": " + kTextureTransform + " is not an object");
      const std::string where = who + " " + kTextureTransform;
      auto pair = [&](const char* name, glm::dvec2 fallback) {
        if (!transform->Has(name)) return fallback;
        const tinygltf::Value& a = transform->Get(name);
        if (!a.IsArray() || a.ArrayLen() != 2 || !a.Get(0).IsNumber() || !a.Get(1).IsNumber() ||
            !std::isfinite(a.Get(0).GetNumberAsDouble()) || !std::isfinite(a.Get(1).GetNumberAsDouble()))
          fail(where + ": " + name + " is not an array of 2 finite numbers");
        return glm::dvec2(a.Get(0).GetNumberAsDouble(), a.Get(1).GetNumberAsDouble());
      };
      const glm::dvec2 offset = pair("offset", glm::dvec2(0.0)), scale = pair("scale", glm::dvec2(1.0));
      const double rotation = extensionNumber(*transform, "rotation", 0.0, where);
      if (transform->Has("texCoord")) ref.texcoord = std::uint32_t(extensionNumber(*transform, "texCoord", 0.0, where));
      // uv' = translation * rotation * scale * uv (the extension's matrices)
      const double c = std::cos(rotation), s = std::sin(rotation);
      ref.transform_u = {float(c * scale.x), float(s * scale.y), float(offset.x), 0.0f};
      ref.transform_v = {float(-s * scale.x), float(c * scale.y), float(offset.y), 0.0f};
    }
    if (ref.texcoord > 1) {
      m_scene.addWarning(who + ": TEXCOORD_" + std::to_string(ref.texcoord) +
                         " is not supported (TEXCOORD_0 and _1 are); the texture is ignored");
      return std::nullopt;
    }
    const tinygltf::Texture& texture = m_model.textures[std::size_t(use.index)];
    const std::string textureLabel = "texture " + std::to_string(use.index);
    if (texture.source < 0) {
      // only an extension's source (KHR_texture_basisu, EXT_texture_webp), warned for by name
      m_scene.addWarning(textureLabel + " has no PNG or JPEG source; the materials using it keep their factors");
      return std::nullopt;
    }
    if (std::size_t(texture.source) >= m_model.images.size())
      fail(textureLabel + " references missing image " + std::to_string(texture.source));
    if (texture.sampler >= 0 && std::size_t(texture.sampler) >= m_model.samplers.size())
      fail(textureLabel + " references missing sampler " + std::to_string(texture.sampler));
    const auto key = std::make_pair(use.index, srgb);
    if (auto it = m_textureIndex.find(key); it != m_textureIndex.end()) {
      if (it->second < 0) return std::nullopt;
      ref.texture = std::uint32_t(it->second);
      return ref;
    }
    const std::optional<std::uint32_t> image = imageIndex(std::size_t(texture.source), srgb);
    if (!image) {
      m_textureIndex[key] = -1;
      return std::nullopt;
    }
    int wrapS = -1, wrapT = -1, mag = -1, min = -1;
    if (texture.sampler >= 0) {
      const tinygltf::Sampler& sampler = m_model.samplers[std::size_t(texture.sampler)];
      wrapS = sampler.wrapS, wrapT = sampler.wrapT, mag = sampler.magFilter, min = sampler.minFilter;
    }
    // added once the images are (addPendingTextures), at the index it will have
    ref.texture = std::uint32_t(m_scene.textures.textures.size() + m_pendingTextures.size());
    m_pendingTextures.push_back({*image, wrapS, wrapT, mag, min});
    m_textureIndex[key] = int(ref.texture);
    return ref;
  }

  /// Decode the images the materials use and build their mips, on several
  /// threads, then add the textures made of them, in the order met.
  void addPendingTextures() {
    if (!m_pendingImages.empty()) {
      const auto start = std::chrono::steady_clock::now();
      try {
        const std::vector<std::uint32_t> added =
            m_scene.textures.addEncodedImages(m_pendingImages, m_options.textureThreads);
        for (std::size_t i = 0; i < added.size(); ++i)
          if (added[i] != m_firstPendingImage + i) throw std::logic_error("glTF loader: texture image indices out of step");
      } catch (const TextureError& e) {
        fail(e.what());
      }
      m_scene.textureSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      m_pendingImages.clear();
    }
    for (const PendingTexture& t : m_pendingTextures) m_scene.textures.addTexture(t.image, t.wrapS, t.wrapT, t.mag, t.min);
    m_pendingTextures.clear();
  }

  /// Image `index` decoded and added to the scene's textures (once per
  /// encoding), or nothing, with a warning, for a format we do not read.
  std::optional<std::uint32_t> imageIndex(std::size_t index, bool srgb) {
    const auto key = std::make_pair(index, srgb);
    if (auto it = m_imageIndex.find(key); it != m_imageIndex.end()) return it->second;
    const tinygltf::Image& image = m_model.images[index];
    const std::string label = "image " + std::to_string(index) +
                              (!image.uri.empty() && image.uri.rfind("data:", 0) != 0 ? " ('" + image.uri + "')"
                               : !image.name.empty()                                  ? " '" + image.name + "'"
                                                                                      : "");
    if (image.image.empty()) fail(label + ": no image data (a missing or empty file?)");
    const ImageFileFormat format = sniffImageFormat(image.image.data(), image.image.size());
    std::optional<std::uint32_t> result;
    if (!isDecodableFormat(format)) {
      m_scene.addWarning(label + " is " + imageFormatName(format) +
                         ", which is not supported (PNG and JPEG are); the materials using it keep their factors");
    } else {
      // decoded later with the others (addPendingTextures), at the index it will have
      if (m_pendingImages.empty()) m_firstPendingImage = m_scene.textures.imageCount();
      result = std::uint32_t(m_firstPendingImage + m_pendingImages.size());
      m_pendingImages.push_back({image.image.data(), image.image.size(), label, srgb});
    }
    m_imageIndex[key] = result;
    return result;
  }

  /// A number of an extension object: `fallback` when absent, an error when
  /// present but not a finite number.
  double extensionNumber(const tinygltf::Value& ext, const char* name, double fallback,
                         const std::string& who) const {
    if (!ext.Has(name)) return fallback;
    const tinygltf::Value& v = ext.Get(name);
    if (!v.IsNumber() || !std::isfinite(v.GetNumberAsDouble())) fail(who + ": " + name + " is not a finite number");
    return v.GetNumberAsDouble();
  }

  /// A material's extension object `name`; none when absent, an error when not an object.
  const tinygltf::Value* materialExtension(const tinygltf::Material& src, const std::string& label,
                                           const char* name) const {
    auto it = src.extensions.find(name);
    if (it == src.extensions.end()) return nullptr;
    if (!it->second.IsObject()) fail(label + ": " + name + " is not an object");
    return &it->second;
  }

  /// A factor in [0,1] of an extension object: `fallback` when absent,
  /// clamped with a warning when outside, an error when not a finite number.
  float extensionUnit(const tinygltf::Value& ext, const char* name, double fallback, const std::string& where) {
    double v = extensionNumber(ext, name, fallback, where);
    if (v < 0.0 || v > 1.0) m_scene.addWarning(where + " " + name + " " + std::to_string(v) + " is outside [0,1]; clamped");
    return float(std::clamp(v, 0.0, 1.0));
  }

  /// An RGB factor of an extension object: `fallback` when absent, each
  /// component clamped to [0,1] (or only to >= 0 where not `unit`) with a
  /// warning, an error when not an array of 3 finite numbers.
  glm::vec3 extensionColor(const tinygltf::Value& ext, const char* name, glm::vec3 fallback, bool unit,
                           const std::string& where) {
    if (!ext.Has(name)) return fallback;
    const tinygltf::Value& c = ext.Get(name);
    if (!c.IsArray() || c.ArrayLen() != 3) fail(where + ": " + name + " is not an array of 3 numbers");
    glm::dvec3 color;
    for (int k = 0; k < 3; ++k) {
      if (!c.Get(k).IsNumber() || !std::isfinite(c.Get(k).GetNumberAsDouble()))
        fail(where + ": " + name + " is not an array of 3 finite numbers");
      color[k] = c.Get(k).GetNumberAsDouble();
    }
    glm::dvec3 clamped = glm::clamp(color, glm::dvec3(0.0), glm::dvec3(unit ? 1.0 : INFINITY));
    if (clamped != color)
      m_scene.addWarning(where + ": " + name + " " + formatVec3(glm::vec3(color)) + " is outside " +
                         (unit ? "[0,1]" : "[0,inf)") + "; clamped");
    return glm::vec3(clamped);
  }

  /// KHR_materials_specular, _clearcoat and _sheen on a converted material:
  /// their factors (their textures are read with the others, in convertMaterials).
  WtMaterial withLayerExtensions(const tinygltf::Material& src, const std::string& label, WtMaterial m) {
    if (const tinygltf::Value* ext = materialExtension(src, label, kSpecular)) {
      const std::string where = label + " " + kSpecular;
      float specular = extensionUnit(*ext, "specularFactor", 1.0, where);
      // F0 = ((ior - 1) / (ior + 1))^2 x colour is capped at 1 by the BSDF; any non-negative colour is valid
      glm::vec3 color = extensionColor(*ext, "specularColorFactor", glm::vec3(1.0f), false, where);
      m = withSpecular(m, specular, glm::min(color, glm::vec3(1e6f)));
      if (m.base_color.w == 1.0f && (specular != 1.0f || color != glm::vec3(1.0f)))
        m_scene.addWarning(where + " has no effect on a metal (metallicFactor 1)");
      if (m.transmission > 0.0f && color != glm::vec3(1.0f))
        m_scene.addWarning(where + " specularColorFactor tints the opaque part's reflection only; transmission's "
                                   "Fresnel term is weighted by specularFactor alone");
    }
    if (const tinygltf::Value* ext = materialExtension(src, label, kClearcoat)) {
      const std::string where = label + " " + kClearcoat;
      float coat = extensionUnit(*ext, "clearcoatFactor", 0.0, where);
      float roughness = extensionUnit(*ext, "clearcoatRoughnessFactor", 0.0, where);
      m = withClearcoat(m, coat, roughness);
    }
    if (const tinygltf::Value* ext = materialExtension(src, label, kSheen)) {
      const std::string where = label + " " + kSheen;
      glm::vec3 color = extensionColor(*ext, "sheenColorFactor", glm::vec3(0.0f), true, where);
      float roughness = extensionUnit(*ext, "sheenRoughnessFactor", 0.0, where);
      m = withSheen(m, color, roughness);
    }
    if (const tinygltf::Value* ext = materialExtension(src, label, kAnisotropy)) {
      const std::string where = label + " " + kAnisotropy;
      float strength = extensionUnit(*ext, "anisotropyStrength", 0.0, where);
      double rotation = extensionNumber(*ext, "anisotropyRotation", 0.0, where);
      m = withAnisotropy(m, strength, float(rotation));
    }
    if (const tinygltf::Value* ext = materialExtension(src, label, kIridescence)) {
      const std::string where = label + " " + kIridescence;
      float factor = extensionUnit(*ext, "iridescenceFactor", 0.0, where);
      double ior = extensionNumber(*ext, "iridescenceIor", 1.3, where);
      if (ior < 1.0) fail(where + ": iridescenceIor " + std::to_string(ior) + " is below 1");
      double thin = extensionNumber(*ext, "iridescenceThicknessMinimum", 100.0, where);
      double thick = extensionNumber(*ext, "iridescenceThicknessMaximum", 400.0, where);
      if (thin < 0.0 || thick < 0.0) fail(where + ": a thickness is negative");
      m = withIridescence(m, factor, float(ior), float(thin), float(thick));
    }
    return m;
  }

  /// KHR_materials_unlit: what glTF viewers show -- the base colour as it is,
  /// whatever the lighting. In a path tracer that is a surface that emits
  /// radiance equal to its base colour (from the front face, or both faces
  /// when double-sided) and scatters nothing: camera rays see the base
  /// colour, reflections and refractions of it show the same, and it lights
  /// its surroundings as an emitter of that radiance would (it joins the
  /// light list). A black Lambertian emitter says exactly that, so the
  /// kernels need nothing new. Emission, metal, roughness and the other
  /// extensions are the fallbacks the extension keeps for viewers without
  /// it, and are ignored. (When material textures arrive, this material's
  /// baseColorTexture belongs in its emissive slot.)
  WtMaterial unlitMaterial(const tinygltf::Material& src, const std::string& label, const WtMaterial& m) {
    for (const char* other : {kTransmission, kVolume, kSpecular, kClearcoat, kSheen, kAnisotropy, kIridescence, kDispersion})
      if (src.extensions.count(other))
        m_scene.addWarning(label + ": " + other + " has no effect on a " + kUnlit + " material; ignored");
    WtMaterial unlit = makeMaterial(glm::vec3(0.0f), glm::vec3(m.base_color.x, m.base_color.y, m.base_color.z), src.doubleSided);
    unlit.alpha = m.alpha, unlit.alpha_mode = m.alpha_mode, unlit.alpha_cutoff = m.alpha_cutoff;
    // the base colour texture (and nothing else) colours what it emits
    unlit.texture_mask = 0u;
    const std::size_t first = m_scene.materials.size() * WT_TEXTURE_SLOTS;
    if ((m.texture_mask & (1u << WT_TEXTURE_SLOT_BASE_COLOR)) && m_scene.materialTextures.size() >= first + WT_TEXTURE_SLOTS) {
      m_scene.materialTextures[first + WT_TEXTURE_SLOT_EMISSIVE] = m_scene.materialTextures[first + WT_TEXTURE_SLOT_BASE_COLOR];
      unlit.texture_mask = 1u << WT_TEXTURE_SLOT_EMISSIVE;
    }
    return unlit;
  }

  /// The nested-dielectric priority (kernels/shared/media.h) from the
  /// material's `"extras": {"wavetrace": {"priority": N}}`, an integer in
  /// [0, 2^31); 0 without it. It matters only on a volume boundary (said once
  /// where it is set on any other material).
  std::uint32_t nestedPriority(const tinygltf::Material& src, const std::string& label, const WtMaterial& m) {
    if (!src.extras.IsObject() || !src.extras.Has("wavetrace")) return 0u;
    const tinygltf::Value& ours = src.extras.Get("wavetrace");
    const std::string where = label + " extras.wavetrace";
    if (!ours.IsObject()) fail(where + " is not an object");
    if (!ours.Has("priority")) return 0u;
    const tinygltf::Value& v = ours.Get("priority");
    const double p = v.IsNumber() ? v.GetNumberAsDouble() : -1.0;
    if (!(p >= 0.0 && p < 2147483648.0 && p == std::floor(p)))
      fail(where + ".priority is not an integer in [0, 2147483647]");
    const bool boundary = m.model == WT_MATERIAL_PBR && m.transmission > 0.0f && m.volume.w != 0.0f;
    if (!boundary && p != 0.0)
      m_scene.addWarning(where + ".priority has no effect on a material that bounds no volume (transmission and a "
                         "non-zero KHR_materials_volume thicknessFactor); ignored");
    return std::uint32_t(p);
  }

  /// KHR_materials_dispersion's `dispersion` (20 / Abbe number, >= 0; 0
  /// without it). It bends light by wavelength at volume boundaries only
  /// (said once where it is set on any other material).
  float dispersionOf(const tinygltf::Material& src, const std::string& label, const WtMaterial& m) {
    const tinygltf::Value* ext = materialExtension(src, label, kDispersion);
    if (!ext) return 0.0f;
    const std::string where = label + " " + kDispersion;
    const double d = extensionNumber(*ext, "dispersion", 0.0, where);
    if (d < 0.0) fail(where + ": dispersion " + std::to_string(d) + " is negative");
    const bool boundary = m.model == WT_MATERIAL_PBR && m.transmission > 0.0f && m.volume.w != 0.0f;
    if (!boundary && d > 0.0) {
      m_scene.addWarning(where + " has no effect on a material that bounds no volume (transmission and a "
                         "non-zero KHR_materials_volume thicknessFactor); ignored");
      return 0.0f;
    }
    return float(std::min(d, 1e3));
  }

  /// KHR_materials_transmission, _ior and _volume on a converted material.
  WtMaterial withTransmissionExtensions(const tinygltf::Material& src, const std::string& label, WtMaterial m) {
    auto find = [&](const char* name) { return materialExtension(src, label, name); };
    const tinygltf::Value* transmission = find(kTransmission);
    const tinygltf::Value* ior = find(kIor);
    const tinygltf::Value* volume = find(kVolume);
    const std::string who = label + ": ";

    float factor = 0.0f;
    if (transmission) {
      double t = extensionNumber(*transmission, "transmissionFactor", 0.0, label + " " + kTransmission);
      if (t < 0.0 || t > 1.0)
        m_scene.addWarning(who + kTransmission + " transmissionFactor " + std::to_string(t) + " is outside [0,1]; clamped");
      factor = float(std::clamp(t, 0.0, 1.0));
    }
    float eta = 1.5f;
    if (ior) {
      double v = extensionNumber(*ior, "ior", 1.5, label + " " + kIor);
      if (v == 0.0) {
        m_scene.addWarning(who + kIor + " ior 0 (reflection at full weight, for KHR_materials_specular) is not supported; 1.5 used");
        v = 1.5;
      } else if (v < 1.0 || v > 10.0) {
        m_scene.addWarning(who + kIor + " ior " + std::to_string(v) + " is outside [1,10]; clamped");
        v = std::clamp(v, 1.0, 10.0);
      }
      eta = float(v);
    }
    if (!(factor > 0.0f)) {
      if (volume) m_scene.addWarning(who + kVolume + " without transmission has no effect; ignored");
      // the opaque dielectric's F0 follows the index (((ior - 1) / (ior + 1))^2)
      m.ior = eta;
      return m;
    }
    bool thinWalled = true;
    glm::vec3 absorption(0.0f);
    if (volume) {
      const std::string where = label + " " + kVolume;
      double thickness = extensionNumber(*volume, "thicknessFactor", 0.0, where);
      if (thickness < 0.0) fail(where + ": thicknessFactor " + std::to_string(thickness) + " is negative");
      thinWalled = thickness == 0.0;
      // thicknessTexture, like the factor's value, is a rasteriser's stand-in
      // for the distance through the mesh; a path tracer walks that distance
      // through the geometry itself (the extension leaves both to renderers
      // that cannot), so it is read past without a warning
      double distance = extensionNumber(*volume, "attenuationDistance", INFINITY, where);
      if (volume->Has("attenuationDistance") && !(distance > 0.0))
        fail(where + ": attenuationDistance " + std::to_string(distance) + " is not positive");
      glm::dvec3 color(1.0);
      if (volume->Has("attenuationColor")) {
        const tinygltf::Value& c = volume->Get("attenuationColor");
        if (!c.IsArray() || c.ArrayLen() != 3) fail(where + ": attenuationColor is not an array of 3 numbers");
        for (int k = 0; k < 3; ++k) {
          if (!c.Get(k).IsNumber() || !std::isfinite(c.Get(k).GetNumberAsDouble()))
            fail(where + ": attenuationColor is not an array of 3 finite numbers");
          color[k] = c.Get(k).GetNumberAsDouble();
        }
        if (glm::any(glm::lessThan(color, glm::dvec3(0.0))) || glm::any(glm::greaterThan(color, glm::dvec3(1.0))))
          m_scene.addWarning(where + ": attenuationColor " + formatVec3(glm::vec3(color)) + " is outside [0,1]; clamped");
        color = glm::clamp(color, glm::dvec3(0.0), glm::dvec3(1.0));
      }
      // a fraction `color` of the light is left after `distance`: sigma = -ln(color) / distance
      if (std::isfinite(distance))
        for (int k = 0; k < 3; ++k)
          absorption[k] = float(std::min(-std::log(std::max(color[k], 1e-300)) / distance, 1e30));
      if (thinWalled && glm::any(glm::greaterThan(absorption, glm::vec3(0.0f))))
        m_scene.addWarning(where + ": attenuation of a thin-walled material (thicknessFactor 0) has no effect; ignored");
    }
    return withTransmission(m, factor, eta, thinWalled, absorption);
  }

  // buffers and accessors

  /// The bytes of a buffer view, checked against its buffer.
  std::pair<const unsigned char*, std::size_t> viewBytes(int viewIndex, const std::string& who) const {
    if (viewIndex < 0 || std::size_t(viewIndex) >= m_model.bufferViews.size())
      fail(who + ": references missing buffer view " + std::to_string(viewIndex));
    const tinygltf::BufferView& view = m_model.bufferViews[std::size_t(viewIndex)];
    const std::string label = "buffer view " + std::to_string(viewIndex);
    if (view.buffer < 0 || std::size_t(view.buffer) >= m_model.buffers.size())
      fail(label + ": references missing buffer " + std::to_string(view.buffer));
    const std::vector<unsigned char>& data = m_model.buffers[std::size_t(view.buffer)].data;
    std::size_t end = 0;
    if (__builtin_add_overflow(view.byteOffset, view.byteLength, &end) || end > data.size()) {
      std::ostringstream msg;
      msg << label << ": extends past the end of buffer " << view.buffer << " (needs "
          << view.byteOffset << " + " << view.byteLength << " bytes, has " << data.size() << ")";
      fail(msg.str());
    }
    return {data.data() + view.byteOffset, view.byteLength};
  }

  /// Read an accessor as T (uint32_t, glm::vec2, glm::vec3): bounds-checked,
  /// strided, converted from any allowed component type, sparse applied.
  template <typename T>
  std::vector<T> readAccessor(int index, const AccessorUse& use) const {
    constexpr int kN = kComponents<T>;
    const std::string user = use.where + ": " + use.semantic;
    if (index < 0 || std::size_t(index) >= m_model.accessors.size())
      fail(user + " references missing accessor " + std::to_string(index));
    const Accessor& acc = m_model.accessors[std::size_t(index)];
    if (componentCount(acc.type) != kN)
      fail(user + " accessor has type " + accessorTypeName(acc.type) + ", expected " +
           vectorTypeName(kN));
    if (std::find(use.componentTypes.begin(), use.componentTypes.end(), acc.componentType) ==
        use.componentTypes.end())
      fail(user + " accessor has component type " + componentTypeName(acc.componentType) +
           ", expected " + joinNames(use.componentTypes));
    if (use.integersNormalized && acc.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT && !acc.normalized)
      fail(user + " accessor has " + componentTypeName(acc.componentType) +
           " components that are not normalized");

    const std::string label = "accessor " + std::to_string(index);
    const std::string usedBy = "; read as " + use.semantic + " of " + use.where;
    const std::size_t elementSize = componentSize(acc.componentType) * std::size_t(kN);
    // integer formats are never normalized when read as integers
    const bool normalized = acc.normalized && !std::is_integral_v<T>;
    std::vector<T> out;

    if (acc.bufferView >= 0) {
      auto [bytes, length] = viewBytes(acc.bufferView, label);
      const std::size_t viewStride = m_model.bufferViews[std::size_t(acc.bufferView)].byteStride;
      if (viewStride != 0 && viewStride < elementSize)
        fail(label + ": byteStride " + std::to_string(viewStride) + " of buffer view " +
             std::to_string(acc.bufferView) + " is smaller than the element size " +
             std::to_string(elementSize) + usedBy);
      const std::size_t stride = viewStride != 0 ? viewStride : elementSize;
      if (acc.count > 0) {
        std::size_t needed = 0;
        if (!mulAdd(acc.count - 1, stride, elementSize, &needed) ||
            __builtin_add_overflow(needed, acc.byteOffset, &needed))
          fail(label + ": count " + std::to_string(acc.count) + " with stride " +
               std::to_string(stride) + " overflows" + usedBy);
        if (needed > length)
          fail(label + ": extends past the end of buffer view " + std::to_string(acc.bufferView) +
               " (needs " + std::to_string(needed) + " bytes, has " + std::to_string(length) + ")" +
               usedBy);
      }
      out.resize(acc.count);
      const unsigned char* p = bytes + acc.byteOffset;
      for (std::size_t i = 0; i < acc.count; ++i, p += stride)
        out[i] = readElement<T>(p, acc.componentType, normalized);
    } else {
      // no buffer view: all zeros, unless sparse values overwrite some
      if (acc.count > kMaxUnbackedElements)
        fail(label + ": count " + std::to_string(acc.count) +
             " is too large for an accessor without a buffer view" + usedBy);
      out.assign(acc.count, T{});
    }

    if (acc.sparse.isSparse) applySparse(acc, label, usedBy, elementSize, normalized, out);
    return out;
  }

  /// Overwrite the elements listed by a sparse accessor (tinygltf parses the
  /// description but leaves applying it to us).
  template <typename T>
  void applySparse(const Accessor& acc, const std::string& label, const std::string& usedBy,
                   std::size_t elementSize, bool normalized, std::vector<T>& out) const {
    const auto& sparse = acc.sparse;
    if (sparse.count < 1 || std::size_t(sparse.count) > acc.count)
      fail(label + ": sparse count " + std::to_string(sparse.count) + " is not in [1, " +
           std::to_string(acc.count) + "]" + usedBy);
    const int indexType = sparse.indices.componentType;
    if (indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
        indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      fail(label + ": sparse indices have component type " + componentTypeName(indexType) +
           ", expected UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT" + usedBy);
    if (sparse.indices.byteOffset < 0 || sparse.values.byteOffset < 0)
      fail(label + ": negative sparse byteOffset" + usedBy);

    const std::size_t count = std::size_t(sparse.count);
    const std::size_t indexSize = componentSize(indexType);
    auto [indexBytes, indexLength] = viewBytes(sparse.indices.bufferView, label + " sparse indices");
    auto [valueBytes, valueLength] = viewBytes(sparse.values.bufferView, label + " sparse values");
    std::size_t indexNeeded = 0, valueNeeded = 0;
    // sparse indices and values are tightly packed (byteStride does not apply)
    if (!mulAdd(count, indexSize, std::size_t(sparse.indices.byteOffset), &indexNeeded) ||
        indexNeeded > indexLength)
      fail(label + ": sparse indices extend past the end of buffer view " +
           std::to_string(sparse.indices.bufferView) + " (needs " + std::to_string(indexNeeded) +
           " bytes, has " + std::to_string(indexLength) + ")" + usedBy);
    if (!mulAdd(count, elementSize, std::size_t(sparse.values.byteOffset), &valueNeeded) ||
        valueNeeded > valueLength)
      fail(label + ": sparse values extend past the end of buffer view " +
           std::to_string(sparse.values.bufferView) + " (needs " + std::to_string(valueNeeded) +
           " bytes, has " + std::to_string(valueLength) + ")" + usedBy);

    const unsigned char* indices = indexBytes + sparse.indices.byteOffset;
    const unsigned char* values = valueBytes + sparse.values.byteOffset;
    for (std::size_t k = 0; k < count; ++k) {
      auto target = std::size_t(readComponent(indices + k * indexSize, indexType, false));
      if (target >= out.size())
        fail(label + ": sparse index " + std::to_string(target) + " out of range (" +
             std::to_string(out.size()) + " elements)" + usedBy);
      out[target] = readElement<T>(values + k * elementSize, acc.componentType, normalized);
    }
  }

  // primitives

  const DecodedPrimitive& primitive(std::size_t meshIndex, std::size_t primIndex) {
    auto& slots = m_decoded[meshIndex];
    if (slots.empty()) slots.resize(m_model.meshes[meshIndex].primitives.size());
    if (!slots[primIndex])
      slots[primIndex] = std::make_unique<DecodedPrimitive>(decode(meshIndex, primIndex));
    return *slots[primIndex];
  }

  DecodedPrimitive decode(std::size_t meshIndex, std::size_t primIndex) {
    const tinygltf::Primitive& prim = m_model.meshes[meshIndex].primitives[primIndex];
    const std::string where =
        "mesh " + std::to_string(meshIndex) + ", primitive " + std::to_string(primIndex);
    DecodedPrimitive out;

    const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
    if (mode >= TINYGLTF_MODE_POINTS && mode <= TINYGLTF_MODE_LINE_STRIP) {
      m_scene.addWarning(std::string(modeName(mode)) + " primitives are not supported; skipped");
      out.skipped = true;
      return out;
    }
    if (mode > TINYGLTF_MODE_TRIANGLE_FAN) fail(where + ": invalid mode " + std::to_string(mode));

    auto attribute = [&](const char* semantic) {
      auto it = prim.attributes.find(semantic);
      return it == prim.attributes.end() ? -1 : it->second;
    };
    const int positionAccessor = attribute("POSITION");
    if (positionAccessor < 0) {
      // the spec lets a primitive omit positions; there is nothing to draw
      m_scene.addWarning(where + ": no POSITION attribute; skipped");
      out.skipped = true;
      return out;
    }
    // meshes that share their accessors share one geometry (GeometryInstance)
    out.geometry = m_geometries.emplace(std::array<int, 3>{positionAccessor, prim.indices, mode},
                                        std::uint32_t(m_geometries.size()))
                       .first->second;
    const std::vector<int> kFloat = {TINYGLTF_COMPONENT_TYPE_FLOAT};
    out.positions = readAccessor<glm::vec3>(positionAccessor, {where, "POSITION", kFloat});
    if (!out.positions.empty()) {
      out.lo = glm::dvec3(std::numeric_limits<double>::infinity());
      out.hi = -out.lo;
      for (const glm::vec3& p : out.positions)
        if (isFinite(p)) out.lo = glm::min(out.lo, glm::dvec3(p)), out.hi = glm::max(out.hi, glm::dvec3(p));
    }
    const std::size_t vertexCount = out.positions.size();
    if (vertexCount > std::numeric_limits<std::uint32_t>::max())
      fail(where + ": " + std::to_string(vertexCount) + " vertices do not fit 32-bit indices");

    if (int normal = attribute("NORMAL"); normal >= 0) {
      out.normals = readAccessor<glm::vec3>(normal, {where, "NORMAL", kFloat});
      if (out.normals.size() != vertexCount)
        fail(where + ": NORMAL has " + std::to_string(out.normals.size()) + " elements, POSITION has " +
             std::to_string(vertexCount));
    }
    auto checkCount = [&](std::size_t count, const char* semantic) {
      if (count != vertexCount)
        fail(where + ": " + semantic + " has " + std::to_string(count) + " elements, POSITION has " +
             std::to_string(vertexCount));
    };
    const std::vector<int> kUnitTypes = {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                                         TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT};
    if (int uv = attribute("TEXCOORD_0"); uv >= 0) {
      out.texcoords = readAccessor<glm::vec2>(uv, {where, "TEXCOORD_0", kUnitTypes, true});
      checkCount(out.texcoords.size(), "TEXCOORD_0");
    }
    if (int uv = attribute("TEXCOORD_1"); uv >= 0) {
      out.texcoords1 = readAccessor<glm::vec2>(uv, {where, "TEXCOORD_1", kUnitTypes, true});
      checkCount(out.texcoords1.size(), "TEXCOORD_1");
    }
    if (int color = attribute("COLOR_0"); color >= 0) {
      const bool rgb = std::size_t(color) < m_model.accessors.size() &&
                       m_model.accessors[std::size_t(color)].type == TINYGLTF_TYPE_VEC3;
      if (rgb) {
        for (const glm::vec3& c : readAccessor<glm::vec3>(color, {where, "COLOR_0", kUnitTypes, true}))
          out.colors.emplace_back(c, 1.0f);
      } else {
        out.colors = readAccessor<glm::vec4>(color, {where, "COLOR_0", kUnitTypes, true});
      }
      checkCount(out.colors.size(), "COLOR_0");
      for (glm::vec4& c : out.colors)  // the spec's range; NaN becomes 0
        c = glm::clamp(c, glm::vec4(0.0f), glm::vec4(1.0f)), c = glm::vec4(std::isnan(c.x) ? 0.0f : c.x,
            std::isnan(c.y) ? 0.0f : c.y, std::isnan(c.z) ? 0.0f : c.z, std::isnan(c.w) ? 0.0f : c.w);
    }
    if (int tangent = attribute("TANGENT"); tangent >= 0) {
      out.tangents = readAccessor<glm::vec4>(tangent, {where, "TANGENT", kFloat});
      checkCount(out.tangents.size(), "TANGENT");
    }
    if (!prim.targets.empty())
      m_scene.addWarning("morph targets are not supported; the base shape is drawn");

    // vertex references in drawing order
    std::vector<std::uint32_t> refs;
    if (prim.indices >= 0) {
      refs = readAccessor<std::uint32_t>(
          prim.indices, {where, "indices",
                         {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                          TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT}});
      for (std::uint32_t index : refs)
        if (index >= vertexCount)
          fail(where + ": index " + std::to_string(index) + " out of range (" +
               std::to_string(vertexCount) + " vertices)");
    } else {
      refs.resize(vertexCount);
      for (std::size_t i = 0; i < vertexCount; ++i) refs[i] = std::uint32_t(i);
    }

    // triangles, in the winding the spec gives for each mode
    const std::size_t n = refs.size();
    if (mode == TINYGLTF_MODE_TRIANGLES) {
      if (n % 3 != 0)
        fail(where + ": " + std::to_string(n) + (prim.indices >= 0 ? " indices" : " vertices") +
             " is not a multiple of 3 for TRIANGLES");
      out.corners = std::move(refs);
    } else if (n >= 3) {
      out.corners.reserve(3 * (n - 2));
      for (std::size_t i = 0; i + 2 < n; ++i) {
        if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
          const std::size_t odd = i % 2;
          out.corners.insert(out.corners.end(), {refs[i], refs[i + 1 + odd], refs[i + 2 - odd]});
        } else {
          out.corners.insert(out.corners.end(), {refs[i + 1], refs[i + 2], refs[0]});
        }
      }
    }

    if (prim.material >= 0) {
      if (std::size_t(prim.material) >= m_model.materials.size())
        fail(where + ": references missing material " + std::to_string(prim.material));
      out.material = std::uint32_t(prim.material);
    } else {
      out.material = defaultMaterial();
    }
    if (prim.material >= 0 && out.tangents.empty()) generateTangentsFor(m_model.materials[std::size_t(prim.material)], out);
    return out;
  }

  /// Tangents for a primitive whose material has a normal map, or is
  /// anisotropic (KHR_materials_anisotropy's direction is given in tangent
  /// space), and whose file gives none (glTF asks for MikkTSpace's, from the
  /// normal texture's coordinates, else TEXCOORD_0); a vertex split at a
  /// mirrored seam gets a geometry of its own, so no other primitive shares it.
  void generateTangentsFor(const tinygltf::Material& material, DecodedPrimitive& out) {
    const int coatNormalSet = clearcoatNormalTexCoord(material);
    const bool normalMap = material.normalTexture.index >= 0 || coatNormalSet >= 0;
    if (!normalMap && !anisotropic(material)) return;
    // the normal texture's set, else the clear coat's
    const int set = material.normalTexture.index >= 0 ? material.normalTexture.texCoord : coatNormalSet;
    const std::vector<glm::vec2>& uv = normalMap && set == 1 ? out.texcoords1 : out.texcoords;
    if (uv.empty()) {
      // a normal texture is left out, warned where the material is read; anisotropy is kept, its direction not
      if (!normalMap)
        m_scene.addWarning("material '" + material.name + "': " + kAnisotropy +
                           " on a primitive without TANGENT or TEXCOORD_0; its direction there is arbitrary");
      return;
    }
    const std::size_t before = out.positions.size();
    std::vector<std::uint32_t> sources = generateTangents(out.positions, out.normals, uv, out.corners, out.tangents);
    if (sources.size() == before) return;
    auto extend = [&](auto& v) {
      if (v.empty()) return;
      for (std::size_t i = before; i < sources.size(); ++i) v.push_back(v[sources[i]]);
    };
    extend(out.positions), extend(out.normals), extend(out.texcoords), extend(out.texcoords1), extend(out.colors);
    out.geometry = std::uint32_t(m_geometries.size() + m_splitGeometries++ + (1u << 30));
  }

  /// Whether a material has KHR_materials_anisotropy with a strength above 0.
  /// The texture coordinate set of a KHR_materials_clearcoat
  /// clearcoatNormalTexture (a coat of factor 0 reads none); -1: none.
  static int clearcoatNormalTexCoord(const tinygltf::Material& material) {
    auto it = material.extensions.find(kClearcoat);
    if (it == material.extensions.end() || !it->second.IsObject() || !it->second.Has("clearcoatNormalTexture")) return -1;
    const tinygltf::Value& factor = it->second.Has("clearcoatFactor") ? it->second.Get("clearcoatFactor") : tinygltf::Value();
    if (!factor.IsNumber() || !(factor.GetNumberAsDouble() > 0.0)) return -1;
    const tinygltf::Value& info = it->second.Get("clearcoatNormalTexture");
    if (!info.IsObject() || !info.Has("texCoord") || !info.Get("texCoord").IsNumber()) return 0;
    return info.Get("texCoord").GetNumberAsDouble() == 1.0 ? 1 : 0;
  }

  static bool anisotropic(const tinygltf::Material& material) {
    auto it = material.extensions.find(kAnisotropy);
    if (it == material.extensions.end() || !it->second.IsObject() || !it->second.Has("anisotropyStrength")) return false;
    const tinygltf::Value& v = it->second.Get("anisotropyStrength");
    return v.IsNumber() && v.GetNumberAsDouble() > 0.0;
  }

  /// Append one placed copy of a primitive to the scene.
  void emitMesh(const MeshInstance& instance) {
    const std::size_t primCount = m_model.meshes[instance.mesh].primitives.size();
    for (std::size_t p = 0; p < primCount; ++p)
      emit(primitive(instance.mesh, p), shifted(instance.world), instance.node, instance.mesh, p);
  }

  /// Append one placed copy of a primitive to the scene; `world` maps mesh
  /// space to scene space (world space less the origin).
  void emit(const DecodedPrimitive& prim, const glm::dmat4& world, std::size_t nodeIndex,
            std::size_t meshIndex, std::size_t primIndex) {
    if (prim.skipped) return;
    const std::size_t base = m_scene.positions.size();
    const std::size_t count = prim.positions.size();
    if (count > std::numeric_limits<std::uint32_t>::max() - base)
      fail("the scene has more vertices than 32-bit indices can address");

    const glm::dmat3 linear(world);
    const double determinant = glm::determinant(linear);
    // A singular transform has no inverse transpose: normals fall back to the
    // geometric normal (of triangles that, flattened, are left out anyway).
    const glm::dmat3 normalMatrix =
        determinant != 0.0 ? glm::transpose(glm::inverse(linear)) : glm::dmat3(0.0);
    if (determinant == 0.0 || !std::isfinite(determinant))
      m_scene.addWarning("node " + std::to_string(nodeIndex) + ": its transform is singular (a zero scale); "
                         "mesh " + std::to_string(meshIndex) + " is flattened and draws nothing");
    // A mirroring transform turns counter-clockwise into clockwise; swap two
    // corners so the front face stays the front face.
    const bool flip = determinant < 0.0;

    reserveGrowing(m_scene.positions, base + count);
    reserveGrowing(m_scene.normals, base + count);
    reserveGrowing(m_scene.texcoords, base + count);
    for (std::size_t i = 0; i < count; ++i) {
      glm::vec3 p(world * glm::dvec4(glm::dvec3(prim.positions[i]), 1.0));
      if (!isFinite(p))
        fail("mesh " + std::to_string(meshIndex) + ", primitive " + std::to_string(primIndex) +
             " (node " + std::to_string(nodeIndex) + "): vertex " + std::to_string(i) +
             " has a non-finite position " + formatVec3(p));
      m_scene.positions.push_back({p.x, p.y, p.z, 0.0f});

      glm::vec3 n(0.0f);
      if (!prim.normals.empty()) {
        glm::vec3 transformed(normalMatrix * glm::dvec3(prim.normals[i]));
        float length = glm::length(transformed);
        // zero, NaN and infinite normals all mean "use the geometric normal"
        if (std::isfinite(length) && length > 0.0f) n = transformed / length;
      }
      m_scene.normals.push_back({n.x, n.y, n.z, 0.0f});

      glm::vec2 uv = prim.texcoords.empty() ? glm::vec2(0.0f) : prim.texcoords[i];
      if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) uv = glm::vec2(0.0f);
      m_scene.texcoords.push_back(uv);
    }
    // the attributes only some primitives have: every vertex gets one once any does
    auto append = [&](auto& dst, const auto& src, auto fallback, auto convert) {
      if (src.empty() && dst.empty()) return;
      dst.resize(base, fallback);
      for (std::size_t i = 0; i < count; ++i) dst.push_back(src.empty() ? fallback : convert(src[i]));
    };
    append(m_scene.texcoords1, prim.texcoords1, glm::vec2(0.0f), [](glm::vec2 uv) {
      return std::isfinite(uv.x) && std::isfinite(uv.y) ? uv : glm::vec2(0.0f);
    });
    append(m_scene.colors, prim.colors, glm::vec4(1.0f), [](glm::vec4 c) { return c; });
    // a tangent moves with the surface (the linear part); a mirror flips the bitangent's side
    append(m_scene.tangents, prim.tangents, glm::vec4(0.0f), [&](glm::vec4 t) {
      glm::vec3 moved(linear * glm::dvec3(t.x, t.y, t.z));
      float length = glm::length(moved);
      if (!(length > 0.0f) || !std::isfinite(length)) return glm::vec4(0.0f);
      return glm::vec4(moved / length, (t.w < 0.0f) != flip ? -1.0f : 1.0f);
    });

    const auto offset = std::uint32_t(base);
    if (prim.corners.size() >= 3)
      m_scene.instances.push_back({std::uint32_t(m_scene.triangles.size()), std::uint32_t(prim.corners.size() / 3),
                                   prim.geometry, world});
    reserveGrowing(m_scene.triangles, m_scene.triangles.size() + prim.corners.size() / 3);
    for (std::size_t t = 0; t + 2 < prim.corners.size(); t += 3) {
      WtTriangle tri;
      tri.v0 = offset + prim.corners[t];
      tri.v1 = offset + prim.corners[t + (flip ? 2 : 1)];
      tri.v2 = offset + prim.corners[t + (flip ? 1 : 2)];
      tri.material = prim.material;
      m_scene.triangles.push_back(tri);
      if (zeroArea(tri) && m_degenerateTriangles++ == 0)
        m_firstDegenerate = "mesh " + std::to_string(meshIndex) + ", primitive " + std::to_string(primIndex) +
                            " (node " + std::to_string(nodeIndex) + "), triangle " + std::to_string(t / 3);
    }
  }

  bool zeroArea(const WtTriangle& tri) const {
    auto pos = [&](std::uint32_t v) {
      const WtVec4& p = m_scene.positions[v];
      return glm::vec3(p.x, p.y, p.z);
    };
    glm::vec3 n = glm::cross(pos(tri.v1) - pos(tri.v0), pos(tri.v2) - pos(tri.v0));
    return glm::dot(n, n) == 0.0f;
  }

  void reportDegenerateTriangles() {
    if (m_degenerateTriangles == 0) return;
    m_scene.addWarning(std::to_string(m_degenerateTriangles) + " of " + std::to_string(m_scene.triangles.size()) +
                       " triangles have zero area (repeated or collinear corners, first: " + m_firstDegenerate +
                       "); they are not drawn");
  }

  // origin

  /// The scene is stored relative to an origin chosen in double precision
  /// (the camera's position, else the centre of the geometry), so that float
  /// coordinates are finest where the image is made: a scene placed 1e6
  /// units from the world origin renders as it does at the origin.
  void chooseOrigin() {
    m_origin = glm::dvec3(0.0);
    if (!m_options.recenter) return;
    if (m_scene.camera) {
      m_origin = glm::dvec3(m_cameraWorld[3]);
      m_scene.origin = m_origin;
      return;
    }
    glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    for (const MeshInstance& instance : m_meshInstances) {
      const std::size_t primCount = m_model.meshes[instance.mesh].primitives.size();
      for (std::size_t p = 0; p < primCount; ++p) {
        const DecodedPrimitive& prim = primitive(instance.mesh, p);
        if (prim.skipped || prim.positions.empty()) continue;
        for (int corner = 0; corner < 8; ++corner) {
          glm::dvec3 c((corner & 1) ? prim.hi.x : prim.lo.x, (corner & 2) ? prim.hi.y : prim.lo.y,
                       (corner & 4) ? prim.hi.z : prim.lo.z);
          glm::dvec3 w(instance.world * glm::dvec4(c, 1.0));
          lo = glm::min(lo, w);
          hi = glm::max(hi, w);
        }
      }
    }
    // Geometry beyond float range fails to load at its first vertex (emit);
    // an origin in the middle of it would blame the wrong one.
    const double kFloatMax = std::numeric_limits<float>::max();
    if (lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z &&
        glm::all(glm::lessThanEqual(glm::max(glm::abs(lo), glm::abs(hi)), glm::dvec3(kFloatMax))))
      m_origin = 0.5 * (lo + hi);
    m_scene.origin = m_origin;
  }

  /// A world transform moved to the scene's origin.
  glm::dmat4 shifted(glm::dmat4 world) const {
    world[3] -= glm::dvec4(m_origin, 0.0);
    return world;
  }

  // nodes

  glm::dmat4 localMatrix(std::size_t nodeIndex) const {
    const tinygltf::Node& node = m_model.nodes[nodeIndex];
    const std::string label = "node " + std::to_string(nodeIndex);
    auto check = [&](const std::vector<double>& values, std::size_t expected, const char* what) {
      if (!values.empty() && values.size() != expected)
        fail(label + ": " + what + " has " + std::to_string(values.size()) + " values, expected " +
             std::to_string(expected));
      for (double v : values)
        if (!std::isfinite(v)) fail(label + ": " + what + " is not finite");
    };
    check(node.matrix, 16, "matrix");
    check(node.translation, 3, "translation");
    check(node.rotation, 4, "rotation");
    check(node.scale, 3, "scale");

    if (!node.matrix.empty()) return glm::make_mat4(node.matrix.data());  // both column-major
    glm::dmat4 local(1.0);
    if (!node.translation.empty())
      local = glm::translate(local, glm::dvec3(node.translation[0], node.translation[1], node.translation[2]));
    if (!node.rotation.empty()) {
      // glTF stores (x, y, z, w); glm::dquat takes w first
      glm::dquat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
      double length = glm::length(q);
      if (!(length > 0.0) || !std::isfinite(length))
        fail(label + ": rotation is not a valid quaternion");
      local = local * glm::mat4_cast(q / length);
    }
    if (!node.scale.empty())
      local = glm::scale(local, glm::dvec3(node.scale[0], node.scale[1], node.scale[2]));
    return local;
  }

  const glm::dmat4& cachedLocal(std::size_t nodeIndex) {
    if (!m_localDone[nodeIndex]) {
      m_local[nodeIndex] = localMatrix(nodeIndex);
      m_localDone[nodeIndex] = true;
    }
    return m_local[nodeIndex];
  }

  std::vector<int> chooseRoots() {
    const std::size_t sceneCount = m_model.scenes.size();
    int index = m_options.sceneIndex;
    if (index < -1 || index >= int(sceneCount))
      fail("scene " + std::to_string(index) + " out of range (" + std::to_string(sceneCount) +
           " scenes)");
    if (index == -1 && m_model.defaultScene >= 0) {
      if (std::size_t(m_model.defaultScene) >= sceneCount)
        fail("default scene " + std::to_string(m_model.defaultScene) + " does not exist (" +
             std::to_string(sceneCount) + " scenes)");
      index = m_model.defaultScene;
    }
    if (index == -1 && sceneCount > 0) index = 0;
    m_rootsLabel = "scene " + std::to_string(index);
    if (index >= 0) return m_model.scenes[std::size_t(index)].nodes;

    // No scenes at all: draw every node that is nobody's child.
    m_scene.addWarning("the file has no scenes; drawing all root nodes");
    m_rootsLabel = "root nodes";
    std::vector<bool> isChild(m_model.nodes.size(), false);
    for (const tinygltf::Node& node : m_model.nodes)
      for (int child : node.children)
        if (child >= 0 && std::size_t(child) < isChild.size()) isChild[std::size_t(child)] = true;
    std::vector<int> roots;
    for (std::size_t i = 0; i < isChild.size(); ++i)
      if (!isChild[i]) roots.push_back(int(i));
    return roots;
  }

  /// Depth-first, parents before children, with an explicit stack so deep
  /// hierarchies cannot overflow the call stack.
  void traverse(const std::vector<int>& roots) {
    const std::size_t nodeCount = m_model.nodes.size();
    m_local.assign(nodeCount, glm::dmat4(1.0));
    m_localDone.assign(nodeCount, false);
    m_decoded.clear();
    m_decoded.resize(m_model.meshes.size());
    std::vector<bool> onPath(nodeCount, false);
    struct Frame {
      std::size_t node;
      glm::dmat4 world;
      std::size_t nextChild;
    };
    std::vector<Frame> stack;
    std::size_t instances = 0;

    auto enter = [&](int nodeIndex, const glm::dmat4& parentWorld, const std::string& parentLabel) {
      if (nodeIndex < 0 || std::size_t(nodeIndex) >= nodeCount)
        fail(parentLabel + ": references missing node " + std::to_string(nodeIndex));
      const auto index = std::size_t(nodeIndex);
      if (onPath[index])
        fail("node " + std::to_string(index) + ": is its own ancestor (cycle in the node graph)");
      if (++instances > kMaxNodeInstances)
        fail("the node graph expands to more than " + std::to_string(kMaxNodeInstances) +
             " node instances");
      glm::dmat4 world = parentWorld * cachedLocal(index);
      visit(index, world);
      onPath[index] = true;
      stack.push_back({index, world, 0});
    };

    for (int root : roots) {
      enter(root, glm::dmat4(1.0), m_rootsLabel);
      while (!stack.empty()) {
        Frame& top = stack.back();
        const std::vector<int>& children = m_model.nodes[top.node].children;
        if (top.nextChild < children.size()) {
          int child = children[top.nextChild++];
          glm::dmat4 parentWorld = top.world;  // `top` dies when the stack grows
          enter(child, parentWorld, "node " + std::to_string(top.node));
        } else {
          onPath[top.node] = false;
          stack.pop_back();
        }
      }
    }
  }

  /// Note what a node holds; meshes and lights are placed once the origin is known.
  void visit(std::size_t nodeIndex, const glm::dmat4& world) {
    const tinygltf::Node& node = m_model.nodes[nodeIndex];
    const std::string label = "node " + std::to_string(nodeIndex);
    if (node.camera >= 0) {
      if (std::size_t(node.camera) >= m_model.cameras.size())
        fail(label + ": references missing camera " + std::to_string(node.camera));
      m_cameraNodes.push_back({nodeIndex, world});
    }
    if (auto ext = node.extensions.find(kLightsPunctual); ext != node.extensions.end())
      m_lightInstances.push_back({label, &ext->second, world});
    if (node.mesh >= 0) {
      if (std::size_t(node.mesh) >= m_model.meshes.size())
        fail(label + ": references missing mesh " + std::to_string(node.mesh));
      if (node.skin >= 0)
        m_scene.addWarning("skinning is not supported; skinned meshes are drawn in their bind pose");
      const auto meshIndex = std::size_t(node.mesh);
      for (const glm::dmat4& placed : gpuInstances(node, label, world)) {
        const auto [vertices, triangles] = meshSize(meshIndex);
        m_sceneVertices = saturatingAdd(m_sceneVertices, vertices);
        m_sceneTriangles = saturatingAdd(m_sceneTriangles, triangles);
        // counted before anything is decoded: instancing must not let a small
        // file take all memory
        if (m_sceneVertices > m_options.maxVertices || m_sceneTriangles > m_options.maxTriangles)
          fail(label + ": mesh " + std::to_string(meshIndex) + " brings the flattened scene to " +
               std::to_string(m_sceneVertices) + " vertices and " + std::to_string(m_sceneTriangles) +
               " triangles, more than the " + std::to_string(m_options.maxVertices) + " and " +
               std::to_string(m_options.maxTriangles) + " supported");
        m_meshInstances.push_back({nodeIndex, meshIndex, placed});
      }
    }
  }

  /// Where a node's mesh is placed: at the node (`world`), or, with
  /// EXT_mesh_gpu_instancing, once per instance, world x T x R x S of the
  /// instance's TRANSLATION, ROTATION and SCALE (each optional, all of one count).
  std::vector<glm::dmat4> gpuInstances(const tinygltf::Node& node, const std::string& label,
                                       const glm::dmat4& world) const {
    auto ext = node.extensions.find(kGpuInstancing);
    if (ext == node.extensions.end()) return {world};
    const std::string where = label + ": " + kGpuInstancing;
    // (tinygltf's Value::Get asserts an object, and reads an empty one as null)
    static const tinygltf::Value kNone;
    const tinygltf::Value& attributes =
        ext->second.IsObject() && ext->second.Has("attributes") ? ext->second.Get("attributes") : kNone;
    if (attributes.Type() != tinygltf::NULL_TYPE && !attributes.IsObject())
      fail(where + ": 'attributes' is not an object");
    auto accessorOf = [&](const char* name) {
      if (!attributes.IsObject() || !attributes.Has(name)) return -1;
      const tinygltf::Value& v = attributes.Get(name);
      if (!v.IsInt() && !v.IsNumber()) fail(where + ": attributes." + name + " is not an accessor index");
      return v.GetNumberAsInt();
    };
    const std::vector<int> kFloat = {TINYGLTF_COMPONENT_TYPE_FLOAT};
    std::vector<glm::vec3> translation, scale;
    std::vector<glm::vec4> rotation;
    if (int a = accessorOf("TRANSLATION"); a >= 0) translation = readAccessor<glm::vec3>(a, {where, "TRANSLATION", kFloat});
    if (int a = accessorOf("ROTATION"); a >= 0)
      rotation = readAccessor<glm::vec4>(
          a, {where, "ROTATION", {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_SHORT},
              true});
    if (int a = accessorOf("SCALE"); a >= 0) scale = readAccessor<glm::vec3>(a, {where, "SCALE", kFloat});
    const std::size_t count = std::max({translation.size(), rotation.size(), scale.size()});
    if (count == 0) fail(where + ": no TRANSLATION, ROTATION or SCALE accessor with instances");
    for (auto [name, size] : {std::pair{"TRANSLATION", translation.size()}, std::pair{"ROTATION", rotation.size()},
                              std::pair{"SCALE", scale.size()}})
      if (size != 0 && size != count)
        fail(where + ": " + name + " has " + std::to_string(size) + " instances, another attribute " +
             std::to_string(count));
    std::vector<glm::dmat4> placed(count, world);
    for (std::size_t i = 0; i < count; ++i) {
      const std::string instance = where + ": instance " + std::to_string(i);
      glm::dmat4 local(1.0);
      if (!translation.empty()) {
        if (!isFinite(translation[i])) fail(instance + ": TRANSLATION is not finite");
        local = glm::translate(local, glm::dvec3(translation[i]));
      }
      if (!rotation.empty()) {
        const glm::vec4 r = rotation[i];  // (x, y, z, w)
        glm::dquat q(r.w, r.x, r.y, r.z);
        const double length = glm::length(q);
        if (!(length > 0.0) || !std::isfinite(length)) fail(instance + ": ROTATION is not a valid quaternion");
        local = local * glm::mat4_cast(q / length);
      }
      if (!scale.empty()) {
        if (!isFinite(scale[i])) fail(instance + ": SCALE is not finite");
        local = glm::scale(local, glm::dvec3(scale[i]));
      }
      placed[i] = world * local;
    }
    return placed;
  }

  /// Vertices and triangles one instance of a mesh adds, from the accessor
  /// counts alone (nothing decoded). A count decode() would refuse (past its
  /// buffer view, or too many unbacked zeros) counts only what could be read,
  /// so that decode() still names the real problem.
  std::pair<std::size_t, std::size_t> meshSize(std::size_t meshIndex) {
    if (m_meshSizes.empty()) m_meshSizes.resize(m_model.meshes.size());
    auto& cached = m_meshSizes[meshIndex];
    if (cached) return *cached;
    std::size_t vertices = 0, triangles = 0;
    auto count = [&](int index) -> std::size_t {
      if (index < 0 || std::size_t(index) >= m_model.accessors.size()) return 0;
      const Accessor& acc = m_model.accessors[std::size_t(index)];
      if (acc.bufferView < 0) return acc.count <= kMaxUnbackedElements ? acc.count : 0;
      if (std::size_t(acc.bufferView) >= m_model.bufferViews.size()) return 0;
      const std::size_t element = componentSize(acc.componentType) * std::size_t(componentCount(acc.type));
      if (element == 0) return 0;
      return std::min(acc.count, m_model.bufferViews[std::size_t(acc.bufferView)].byteLength / element);
    };
    for (const tinygltf::Primitive& prim : m_model.meshes[meshIndex].primitives) {
      const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
      if (mode < TINYGLTF_MODE_TRIANGLES || mode > TINYGLTF_MODE_TRIANGLE_FAN) continue;  // skipped or refused
      auto position = prim.attributes.find("POSITION");
      if (position == prim.attributes.end()) continue;
      const std::size_t n = count(position->second);
      const std::size_t refs = prim.indices >= 0 ? count(prim.indices) : n;
      vertices = saturatingAdd(vertices, n);
      triangles = saturatingAdd(triangles, mode == TINYGLTF_MODE_TRIANGLES ? refs / 3 : refs >= 3 ? refs - 2 : 0);
    }
    cached = std::pair(vertices, triangles);
    return *cached;
  }

  // lights

  void placeLight(const std::string& nodeLabel, const tinygltf::Value& ext, const glm::dmat4& worldUnshifted) {
    const glm::mat4 world(shifted(worldUnshifted));
    if (!ext.IsObject() || !ext.Has("light") || !ext.Get("light").IsInt())
      fail(nodeLabel + ": " + kLightsPunctual + " has no integer 'light'");
    int index = ext.Get("light").GetNumberAsInt();
    if (index < 0 || std::size_t(index) >= m_model.lights.size())
      fail(nodeLabel + ": references missing light " + std::to_string(index) + " (" +
           std::to_string(m_model.lights.size()) + " lights)");
    const tinygltf::Light& src = m_model.lights[std::size_t(index)];
    const std::string label = "light " + std::to_string(index);
    PunctualLight light;
    light.name = src.name.empty() ? label : src.name;
    if (src.type == "point") light.type = WT_LIGHT_POINT;
    else if (src.type == "spot") light.type = WT_LIGHT_SPOT;
    else if (src.type == "directional") light.type = WT_LIGHT_DIRECTIONAL;
    else fail(label + ": unknown type '" + src.type + "'");
    glm::vec3 color(1.0f);
    if (!src.color.empty()) {
      if (src.color.size() != 3) fail(label + ": color must have 3 components");
      color = glm::vec3(float(src.color[0]), float(src.color[1]), float(src.color[2]));
    }
    if (!std::isfinite(src.intensity) || src.intensity < 0.0 || !std::isfinite(color.x) ||
        !std::isfinite(color.y) || !std::isfinite(color.z) || glm::any(glm::lessThan(color, glm::vec3(0.0f))))
      fail(label + ": intensity and color must be finite and non-negative");
    light.intensity = color * float(src.intensity);
    if (src.range > 0.0)
      m_scene.addWarning("light range is not supported (lights reach every distance, inverse square)");
    light.position = glm::vec3(world[3]);
    if (!isFinite(light.position)) fail(nodeLabel + ": " + label + " is placed at a non-finite position");
    // a point light has no direction, so a zero scale does not matter to it
    glm::vec3 forward = -glm::vec3(world[2]);
    if (light.type != WT_LIGHT_POINT && (!(glm::length(forward) > 0.0f) || !std::isfinite(glm::length(forward))))
      fail(nodeLabel + ": the transform of " + label + " has no direction (zero scale)");
    if (light.type != WT_LIGHT_POINT) light.direction = glm::normalize(forward);
    if (light.type == WT_LIGHT_SPOT) {
      light.innerConeAngle = float(src.spot.innerConeAngle);
      light.outerConeAngle = float(src.spot.outerConeAngle);
      if (!(light.innerConeAngle >= 0.0f && light.innerConeAngle < light.outerConeAngle &&
            light.outerConeAngle <= 1.5707964f))
        fail(label + ": spot cone angles must satisfy 0 <= inner < outer <= pi/2");
    }
    m_scene.lights.push_back(light);
  }

  // cameras

  void chooseCamera() {
    if (m_cameraNodes.empty()) return;
    const int index = m_options.cameraIndex;
    if (index < 0 || std::size_t(index) >= m_cameraNodes.size())
      fail("camera " + std::to_string(index) + " out of range (" +
           std::to_string(m_cameraNodes.size()) + " camera nodes in " + m_rootsLabel + ")");
    const auto& [nodeIndex, world] = m_cameraNodes[std::size_t(index)];
    const tinygltf::Node& node = m_model.nodes[nodeIndex];
    const tinygltf::Camera& src = m_model.cameras[std::size_t(node.camera)];
    const std::string label = "camera " + std::to_string(node.camera);

    // the camera's axes come from its node: they must exist
    const double determinant = glm::determinant(glm::dmat3(world));
    if (!(std::abs(determinant) > 0.0) || !std::isfinite(determinant) || !std::isfinite(world[3].x + world[3].y + world[3].z))
      fail(label + " (node " + std::to_string(nodeIndex) + "): its node's transform is singular or not finite "
           "(a zero scale), so the camera has no view direction");
    // rigid axes: glTF asks for a camera node without scale, but files scale
    // the camera with its scene. The rays need an orthonormal basis (a sheared
    // or non-uniformly scaled one skews the image): keep -Z's direction, make
    // +Y perpendicular to it, X last (on its side, so a mirroring node mirrors)
    const glm::dmat4 rigid = rigidCameraTransform(world);
    const glm::dvec3 axes = glm::dvec3(rigid[0]) + glm::dvec3(rigid[1]) + glm::dvec3(rigid[2]);
    if (!std::isfinite(axes.x + axes.y + axes.z))
      fail(label + " (node " + std::to_string(nodeIndex) + "): its node's axes are too close to parallel "
           "to give the camera a view direction");
    // distances in the camera's own units (znear, orthographic extents) are
    // world distances times the node's scale along that axis
    const double scaleZ = glm::length(glm::dvec3(world[2]));
    const double scaleY = glm::length(glm::dvec3(world[1]));
    const double scaleX = glm::length(glm::dvec3(world[0]));
    CameraDesc desc;
    m_cameraWorld = rigid;  // shifted to the origin once it is chosen
    desc.cameraToWorld = glm::mat4(rigid);
    desc.name = !src.name.empty() ? src.name : !node.name.empty() ? node.name : label;
    auto positive = [&](double v, const char* what) {
      const auto f = float(v);  // the check is on the float: a scaled extent may leave its range
      if (!std::isfinite(f) || !(f > 0.0f)) fail(label + ": " + what + " must be positive and finite");
      return f;
    };
    if (src.type == "perspective") {
      desc.orthographic = false;
      desc.yfov = positive(src.perspective.yfov, "yfov");
      desc.aspectRatio = src.perspective.aspectRatio > 0.0
                             ? positive(src.perspective.aspectRatio, "aspectRatio")
                             : 0.0f;
      // yfov is an angle: a uniform scale leaves it; a non-uniform one is not
      // rigid, and the frustum keeps the file's yfov and the image's aspect
      desc.znear = src.perspective.znear >= 0.0 && std::isfinite(src.perspective.znear)
                       ? float(src.perspective.znear * scaleZ)
                       : 0.0f;
    } else if (src.type == "orthographic") {
      desc.orthographic = true;
      // the spec only forbids zero; a negative magnification mirrors the image
      desc.xmag = positive(std::fabs(src.orthographic.xmag) * scaleX, "xmag (times the node's scale)");
      desc.ymag = positive(std::fabs(src.orthographic.ymag) * scaleY, "ymag (times the node's scale)");
      desc.znear = src.orthographic.znear >= 0.0 && std::isfinite(src.orthographic.znear)
                       ? float(src.orthographic.znear * scaleZ)
                       : 0.0f;
    } else {
      fail(label + ": unknown type '" + src.type + "'");
    }
    // zfar is not read: a path tracer has no depth buffer to fit, and cutting
    // rays at a far plane would only remove light that is there
    m_scene.camera = desc;
  }

  const Model& m_model;
  const std::string m_name;
  const GltfLoadOptions& m_options;
  Scene& m_scene;
  int m_defaultMaterial = -1;
  std::string m_rootsLabel;
  std::vector<glm::dmat4> m_local;
  std::vector<bool> m_localDone;
  std::vector<std::vector<std::unique_ptr<DecodedPrimitive>>> m_decoded;
  std::map<std::array<int, 3>, std::uint32_t> m_geometries;  ///< (POSITION, indices, mode) -> GeometryInstance::geometry
  struct PendingTexture {
    std::uint32_t image;
    int wrapS, wrapT, mag, min;  ///< the glTF sampler's codes
  };
  std::vector<EncodedImage> m_pendingImages;  ///< bytes in m_model, which outlives the conversion
  std::size_t m_firstPendingImage = 0;
  std::vector<PendingTexture> m_pendingTextures;
  std::map<std::pair<int, bool>, int> m_textureIndex;  ///< (glTF texture, sRGB) -> scene texture; -1: left out
  std::map<std::pair<std::size_t, bool>, std::optional<std::uint32_t>> m_imageIndex;  ///< (glTF image, sRGB) -> TextureSet image
  std::uint32_t m_splitGeometries = 0;  ///< geometries of their own for primitives whose vertices tangents split
  std::vector<std::pair<std::size_t, glm::dmat4>> m_cameraNodes;
  std::vector<MeshInstance> m_meshInstances;  ///< in traversal order
  std::vector<LightInstance> m_lightInstances;
  glm::dmat4 m_cameraWorld{1.0};
  glm::dvec3 m_origin{0.0};
  std::size_t m_degenerateTriangles = 0;
  std::string m_firstDegenerate;
  std::vector<std::optional<std::pair<std::size_t, std::size_t>>> m_meshSizes;  ///< per mesh: vertices, triangles
  std::size_t m_sceneVertices = 0;
  std::size_t m_sceneTriangles = 0;
};

/// Check the GLB container ourselves: tinygltf 2.7 does not count the BIN
/// chunk's 8-byte header when it checks the chunk against the file length,
/// and would read past the end of a truncated file. Returns the length to
/// hand to tinygltf (the header's, which may be less than the bytes we have).
std::size_t checkGlb(const unsigned char* bytes, std::size_t size, const std::string& name) {
  auto fail = [&](const std::string& what) { throw SceneError(name + ": " + what); };
  if (size < 12)
    fail("truncated .glb: " + std::to_string(size) + " bytes, the header alone needs 12");
  const std::uint32_t version = readU32(bytes + 4);
  const std::uint32_t length = readU32(bytes + 8);
  if (version != 2) fail("unsupported glTF binary version " + std::to_string(version));
  if (length > size)
    fail("truncated .glb: the header says " + std::to_string(length) + " bytes, the file has " +
         std::to_string(size));
  if (length < 20) fail("truncated .glb: no room for the JSON chunk header");
  const std::uint64_t jsonLength = readU32(bytes + 12);
  if (readU32(bytes + 16) != kGlbChunkJson) fail(".glb: the first chunk is not JSON");
  const std::uint64_t jsonEnd = 20 + jsonLength;
  if (jsonEnd > length)
    fail("truncated .glb: the JSON chunk needs " + std::to_string(jsonEnd) + " bytes, the file has " +
         std::to_string(length));
  if (jsonEnd + 8 <= length) {
    const std::uint64_t binLength = readU32(bytes + jsonEnd);
    const std::uint32_t binType = readU32(bytes + jsonEnd + 4);
    if (binType == kGlbChunkBin && jsonEnd + 8 + binLength > length)
      fail("truncated .glb: the BIN chunk needs " + std::to_string(jsonEnd + 8 + binLength) +
           " bytes, the file has " + std::to_string(length));
  }
  return length;
}

Scene loadFromBytes(const unsigned char* bytes, std::size_t size, bool expectBinary,
                    const std::string& name, const std::string& sourceName,
                    const std::string& baseDir, const GltfLoadOptions& options) {
  if (size > std::numeric_limits<unsigned int>::max())
    throw SceneError(name + ": file is too large (" + std::to_string(size) + " bytes)");

  const bool binary = size >= 4 && readU32(bytes) == kGlbMagic;
  if (expectBinary && !binary) throw SceneError(name + ": not a binary glTF file (no 'glTF' magic)");

  tinygltf::Model model;
  tinygltf::TinyGLTF parser;
  parser.SetImageLoader(&keepImageBytes, nullptr);
  std::string err, warn;
  bool ok = false;
  try {
    if (binary) {
      std::size_t length = checkGlb(bytes, size, name);
      ok = parser.LoadBinaryFromMemory(&model, &err, &warn, bytes, unsigned(length), baseDir);
    } else {
      ok = parser.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(bytes),
                                      unsigned(size), baseDir);
    }
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception& e) {
    // tinygltf 2.7 throws on a few malformed inputs (empty data URIs, empty BIN buffers)
    throw SceneError(name + ": glTF parse error: " + e.what());
  }
  // tinygltf's warnings are all about image files, which we do not read
  (void)warn;
  if (!ok) {
    while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
    throw SceneError(name + ": glTF parse error: " + (err.empty() ? "unknown error" : err));
  }

  Scene scene;
  scene.sourceName = sourceName;
  try {
    Converter(model, name, options, scene).run();
  } catch (const std::bad_alloc&) {
    throw SceneError(name + ": out of memory while converting the scene");
  } catch (const std::length_error&) {
    throw SceneError(name + ": out of memory while converting the scene");
  }
  return scene;
}

}  // namespace

Scene loadGltf(const std::string& path, const GltfLoadOptions& options) {
  namespace fs = std::filesystem;
  const fs::path file(path);
  const std::string name = file.filename().string().empty() ? path : file.filename().string();
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    throw SceneError(name + ": cannot open " + path +
                     (fs::exists(file, ec) ? " (not a regular file)" : " (no such file)"));
  std::ifstream in(file, std::ios::binary);
  if (!in) throw SceneError(name + ": cannot open " + path);
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw SceneError(name + ": cannot read " + path);
  if (bytes.empty()) throw SceneError(name + ": the file is empty");

  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  std::string baseDir = file.parent_path().string();
  if (baseDir.empty()) baseDir = ".";
  return loadFromBytes(bytes.data(), bytes.size(), ext == ".glb", name, path, baseDir, options);
}

Scene loadGltfFromMemory(std::string_view contents, const std::string& name,
                         const std::string& baseDir, const GltfLoadOptions& options) {
  if (contents.empty()) throw SceneError(name + ": the scene text is empty");
  return loadFromBytes(reinterpret_cast<const unsigned char*>(contents.data()), contents.size(),
                       false, name, name, baseDir, options);
}

Scene loadGlbFromMemory(std::span<const unsigned char> bytes, const std::string& name,
                        const std::string& baseDir, const GltfLoadOptions& options) {
  return loadFromBytes(bytes.data(), bytes.size(), true, name, name, baseDir, options);
}

}  // namespace wt
