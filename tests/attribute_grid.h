// A glTF grid carrying every per-vertex attribute the loader keeps (NORMAL,
// TEXCOORD_0, TEXCOORD_1, COLOR_0, TANGENT), each varying over the grid, for
// tests that place one mesh several times: by nodes sharing it, by
// EXT_mesh_gpu_instancing, or written out once per copy.
#pragma once

#include "scene/gltf_doc.h"

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace wt::test {

/// A glTF placement: translation, rotation and scale.
struct Placement {
  glm::vec3 translation{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  ///< glm's (w, x, y, z)
  glm::vec3 scale{1.0f};
  glm::mat4 matrix() const {
    return glm::translate(glm::mat4(1.0f), translation) * glm::mat4_cast(rotation) * glm::scale(glm::mat4(1.0f), scale);
  }
};

enum class GridLayout {
  kNodesShareAMesh,  ///< one node per placement, all naming mesh 0
  kGpuInstancing,    ///< one node placing mesh 0 by EXT_mesh_gpu_instancing
  kMeshPerCopy,      ///< one node and one mesh with its own accessors per placement
};

/// `cells` x `cells` quads over [-1, 1]^2 in the y = 0 plane, facing +y,
/// material 0 (rough dielectric, light grey), placed by `placements` as
/// `layout` says. Attributes of vertex (x, 0, z): normal tilted with x and z,
/// TEXCOORD_0 ((x + 1) / 2, (z + 1) / 2), TEXCOORD_1 another (turned) map,
/// COLOR_0 a colour per vertex, TANGENT turning with x and z in the plane, w 1.
inline gltf_doc::GltfDoc attributeGridDoc(int cells, std::span<const Placement> placements, GridLayout layout) {
  using gltf_doc::str;
  gltf_doc::GltfDoc doc;
  std::vector<glm::vec3> positions, normals;
  std::vector<glm::vec2> uv0, uv1;
  std::vector<glm::vec4> colors, tangents;
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i) {
      const float x = -1.0f + 2.0f * float(i) / float(cells), z = -1.0f + 2.0f * float(j) / float(cells);
      positions.emplace_back(x, 0.0f, z);
      normals.push_back(glm::normalize(glm::vec3(0.15f * x, 1.0f, -0.1f * z)));
      uv0.emplace_back(0.5f * (x + 1.0f), 0.5f * (z + 1.0f));
      uv1.emplace_back(0.5f + 0.375f * z, 0.5f - 0.3f * x);
      colors.emplace_back(0.3f + 0.35f * (x + 1.0f), 0.9f - 0.25f * (z + 1.0f), 0.4f + 0.3f * x * z, 1.0f);
      const float a = 0.8f * x + 0.5f * z;
      tangents.emplace_back(std::cos(a), 0.0f, std::sin(a), 1.0f);
    }
  std::vector<std::uint16_t> indices;
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      const auto v = [&](int di, int dj) { return std::uint16_t((j + dj) * (cells + 1) + i + di); };
      // counter-clockwise seen from +y
      indices.insert(indices.end(), {v(0, 0), v(0, 1), v(1, 0), v(1, 0), v(0, 1), v(1, 1)});
    }
  const auto addMesh = [&] {
    const auto vec4s = [&](const std::vector<glm::vec4>& values) {
      return doc.addAccessor(doc.addView(values), gltf_doc::kFloat, values.size(), "VEC4");
    };
    const std::string attributes =
        "{\"POSITION\":" + str(std::size_t(doc.addVec3(positions))) + ",\"NORMAL\":" + str(std::size_t(doc.addVec3(normals))) +
        ",\"TEXCOORD_0\":" + str(std::size_t(doc.addVec2(uv0))) + ",\"TEXCOORD_1\":" + str(std::size_t(doc.addVec2(uv1))) +
        ",\"COLOR_0\":" + str(std::size_t(vec4s(colors))) + ",\"TANGENT\":" + str(std::size_t(vec4s(tangents))) + "}";
    return doc.addMesh("{\"attributes\":" + attributes + ",\"indices\":" +
                       str(std::size_t(doc.addIndices(indices))) + ",\"material\":0}");
  };
  doc.materials.push_back(
      "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.9,0.85,0.8,1],\"metallicFactor\":0,\"roughnessFactor\":0.8}}");
  const auto trs = [](const Placement& p) {
    using gltf_doc::num;
    const glm::quat& q = p.rotation;
    return "\"translation\":[" + num(p.translation.x) + "," + num(p.translation.y) + "," + num(p.translation.z) +
           "],\"rotation\":[" + num(q.x) + "," + num(q.y) + "," + num(q.z) + "," + num(q.w) + "],\"scale\":[" +
           num(p.scale.x) + "," + num(p.scale.y) + "," + num(p.scale.z) + "]";
  };
  std::string roots;
  if (layout == GridLayout::kGpuInstancing) {
    addMesh();
    std::vector<glm::vec3> t, s;
    std::vector<glm::vec4> r;
    for (const Placement& p : placements) {
      t.push_back(p.translation), s.push_back(p.scale);
      r.emplace_back(p.rotation.x, p.rotation.y, p.rotation.z, p.rotation.w);
    }
    const int rotations = doc.addAccessor(doc.addView(r), gltf_doc::kFloat, r.size(), "VEC4");
    doc.addNode("{\"mesh\":0,\"extensions\":{\"EXT_mesh_gpu_instancing\":{\"attributes\":{\"TRANSLATION\":" +
                str(std::size_t(doc.addVec3(t))) + ",\"ROTATION\":" + str(std::size_t(rotations)) +
                ",\"SCALE\":" + str(std::size_t(doc.addVec3(s))) + "}}}}");
    doc.extensionsUsed = "[\"EXT_mesh_gpu_instancing\"]";
    roots = "0";
  } else {
    if (layout == GridLayout::kNodesShareAMesh) addMesh();
    for (const Placement& p : placements) {
      const int mesh = layout == GridLayout::kMeshPerCopy ? addMesh() : 0;
      const int node = doc.addNode("{\"mesh\":" + str(std::size_t(mesh)) + "," + trs(p) + "}");
      roots += (roots.empty() ? "" : ",") + str(std::size_t(node));
    }
  }
  doc.scenes.push_back("{\"nodes\":[" + roots + "]}");
  return doc;
}

}  // namespace wt::test
