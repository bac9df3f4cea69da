// A glTF document assembled in code from JSON fragments plus one binary
// buffer: the tests and the stress suite start from a valid file and break
// exactly one element.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

namespace wt::gltf_doc {

constexpr int kUByte = 5121;
constexpr int kUShort = 5123;
constexpr int kUInt = 5125;
constexpr int kFloat = 5126;

inline std::string str(std::size_t v) { return std::to_string(v); }
inline std::string num(float v) {
  std::ostringstream out;
  out.precision(9);
  out << v;
  return out.str();
}

inline std::string base64(const std::vector<unsigned char>& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t chunk = std::uint32_t(bytes[i]) << 16;
    if (i + 1 < bytes.size()) chunk |= std::uint32_t(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) chunk |= bytes[i + 2];
    out += kAlphabet[(chunk >> 18) & 63];
    out += kAlphabet[(chunk >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(chunk >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[chunk & 63] : '=';
  }
  return out;
}

/// A glTF document assembled from JSON fragments plus one binary buffer, so
/// a test can start from a valid file and break exactly one element.
struct GltfDoc {
  std::vector<std::string> accessors, bufferViews, meshes, nodes, materials, cameras, scenes, images, textures,
      samplers;
  std::string extensionsUsed;      ///< JSON array text; empty: absent
  std::string extensionsRequired;  ///< JSON array text; empty: absent
  std::string extensions;          ///< the root "extensions" object text (e.g. KHR_lights_punctual's lights); empty: absent
  int scene = -1;                  ///< the "scene" property; -1: absent
  std::vector<unsigned char> bin;

  /// Append bytes (4-byte aligned) and a buffer view over them.
  int addView(const void* data, std::size_t bytes, std::size_t stride = 0) {
    while (bin.size() % 4 != 0) bin.push_back(0);
    std::size_t offset = bin.size();
    bin.resize(offset + bytes);
    std::memcpy(bin.data() + offset, data, bytes);
    std::string view = "{\"buffer\":0,\"byteOffset\":" + str(offset) + ",\"byteLength\":" + str(bytes);
    if (stride != 0) view += ",\"byteStride\":" + str(stride);
    bufferViews.push_back(view + "}");
    return int(bufferViews.size()) - 1;
  }
  template <typename T>
  int addView(const std::vector<T>& values, std::size_t stride = 0) {
    return addView(values.data(), values.size() * sizeof(T), stride);
  }
  int addAccessor(int view, int componentType, std::size_t count, const char* type,
                  const std::string& extra = "") {
    std::string acc = "{";
    if (view >= 0) acc += "\"bufferView\":" + str(std::size_t(view)) + ",";
    acc += "\"componentType\":" + str(std::size_t(componentType)) + ",\"count\":" + str(count) +
           ",\"type\":\"" + type + "\"" + extra + "}";
    accessors.push_back(acc);
    return int(accessors.size()) - 1;
  }
  int addVec3(const std::vector<glm::vec3>& values) {
    return addAccessor(addView(values), kFloat, values.size(), "VEC3");
  }
  int addVec2(const std::vector<glm::vec2>& values) {
    return addAccessor(addView(values), kFloat, values.size(), "VEC2");
  }
  template <typename T>
  int addIndices(const std::vector<T>& values) {
    int type = sizeof(T) == 1 ? kUByte : sizeof(T) == 2 ? kUShort : kUInt;
    return addAccessor(addView(values), type, values.size(), "SCALAR");
  }
  int addMesh(const std::string& primitives) {
    meshes.push_back("{\"primitives\":[" + primitives + "]}");
    return int(meshes.size()) - 1;
  }
  int addNode(const std::string& node) {
    nodes.push_back(node);
    return int(nodes.size()) - 1;
  }

  /// The document; `bufferUri` empty: no uri (the GLB BIN chunk).
  std::string json(const std::string& bufferUri) const {
    std::string out = "{\"asset\":{\"version\":\"2.0\"}";
    if (scene >= 0) out += ",\"scene\":" + str(std::size_t(scene));
    auto list = [&](const char* key, const std::vector<std::string>& items) {
      if (items.empty()) return;
      out += std::string(",\"") + key + "\":[";
      for (std::size_t i = 0; i < items.size(); ++i) out += (i ? "," : "") + items[i];
      out += "]";
    };
    list("scenes", scenes);
    list("nodes", nodes);
    list("meshes", meshes);
    list("materials", materials);
    list("cameras", cameras);
    list("images", images);
    list("textures", textures);
    list("samplers", samplers);
    list("accessors", accessors);
    list("bufferViews", bufferViews);
    if (!bin.empty()) {
      out += ",\"buffers\":[{\"byteLength\":" + str(bin.size());
      if (!bufferUri.empty()) out += ",\"uri\":\"" + bufferUri + "\"";
      out += "}]";
    }
    if (!extensionsUsed.empty()) out += ",\"extensionsUsed\":" + extensionsUsed;
    if (!extensionsRequired.empty()) out += ",\"extensionsRequired\":" + extensionsRequired;
    if (!extensions.empty()) out += ",\"extensions\":" + extensions;
    return out + "}";
  }
  std::string embedded() const {
    return json("data:application/octet-stream;base64," + base64(bin));
  }
  std::vector<unsigned char> glb() const {
    std::string text = json("");
    while (text.size() % 4 != 0) text += ' ';
    std::vector<unsigned char> payload = bin;
    while (payload.size() % 4 != 0) payload.push_back(0);
    std::vector<unsigned char> out;
    auto u32 = [&](std::uint32_t v) {
      for (int i = 0; i < 4; ++i) out.push_back(static_cast<unsigned char>(v >> (8 * i)));
    };
    std::size_t total = 12 + 8 + text.size() + (payload.empty() ? 0 : 8 + payload.size());
    u32(0x46546C67);  // "glTF"
    u32(2);
    u32(std::uint32_t(total));
    u32(std::uint32_t(text.size()));
    u32(0x4E4F534A);  // "JSON"
    out.insert(out.end(), text.begin(), text.end());
    if (!payload.empty()) {
      u32(std::uint32_t(payload.size()));
      u32(0x004E4942);  // "BIN\0"
      out.insert(out.end(), payload.begin(), payload.end());
    }
    return out;
  }
};

}  // namespace wt::gltf_doc
