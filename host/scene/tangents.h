// Per-vertex tangents for normal maps, for meshes whose file has none.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace wt {

/// Tangents by the rules MikkTSpace (and so glTF) follows: each triangle's
/// tangent from its texture coordinates (dp/du), summed at each corner
/// weighted by the corner's angle, made orthogonal to the vertex normal,
/// with w = +-1 the handedness: bitangent = w cross(n, t) = -dp/dv, up the
/// image, as glTF's v runs down it (the files that carry tangents agree). A vertex whose triangles disagree on handedness (a mirrored UV
/// seam) is split: a copy is appended for the left-handed ones and their
/// corners renamed. `normals` may be empty (the triangles' own normals are
/// used). Returns, for every vertex of the result (the original ones, then
/// the copies), the vertex it copies; `tangents` gets one entry per vertex
/// of the result.
std::vector<std::uint32_t> generateTangents(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                                            std::span<const glm::vec2> texcoords, std::vector<std::uint32_t>& corners,
                                            std::vector<glm::vec4>& tangents);

}  // namespace wt
