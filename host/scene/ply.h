// PLY files (ASCII, binary little- or big-endian): the generic reader the
// strand loader (host/scene/hair_loader.h) and the mesh loader share, and the
// mesh loader. Every count is checked against the bytes that are there before
// anything is allocated, so a truncated or lying header is an error naming
// the file and the element, never a crash or a huge allocation.
#pragma once

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace wt {

/// A PLY file read whole: each element's properties, every value as a double.
struct PlyData {
  struct Property {
    std::string name;
    std::string type;                ///< scalar type, or the item type of a list
    bool list = false;
    std::vector<double> values;      ///< a scalar's value per item; a list's items, item after item
    std::vector<std::uint64_t> ends; ///< list only: item i's values end at ends[i] (and start at ends[i - 1])
  };
  struct Element {
    std::string name;
    std::uint64_t count = 0;
    int headerLine = 0;              ///< the "element" line, for messages
    std::vector<Property> properties;
    /// The scalar property of that name, or null.
    const Property* scalar(const std::string& property) const;
    /// The list property of that name, or null.
    const Property* list(const std::string& property) const;
  };
  std::vector<Element> elements;
  /// The element of that name, or null.
  const Element* find(const std::string& element) const;
};

/// The bytes of the file at `path`; a SceneError naming `name` (the file's
/// name in messages) when it is missing, not a regular file or unreadable.
std::vector<std::uint8_t> readFileBytes(const std::string& path, const std::string& name);

/// Parse a PLY file; `name` prefixes every error (SceneError). `checkHeader`
/// sees the elements and properties (no values yet) before the body is read,
/// so that a file missing what the caller needs fails on that, not on a value.
PlyData readPly(std::span<const std::uint8_t> bytes, const std::string& name,
                const std::function<void(const PlyData&)>& checkHeader = nullptr);

/// A triangle mesh as a PLY file holds it.
struct PlyMesh {
  std::vector<glm::dvec3> positions;
  std::vector<glm::vec3> normals;                  ///< one per position, unit or zero (none)
  std::vector<glm::vec2> texcoords;                ///< empty, or one per position, glTF's convention (v down)
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< counter-clockwise, polygons as fans
};

/// A mesh from a PLY file: element "vertex" with x, y, z (and optionally nx,
/// ny, nz and texture coordinates as s, t / u, v / texture_u, texture_v, whose
/// v runs up as in OBJ; without normals, smooth area-weighted ones are made), element "face" with a list "vertex_indices" (or
/// "vertex_index") of 3 or more vertices. Non-finite positions, indices out of
/// range and faces of fewer than 3 vertices are errors; a face whose corners
/// coincide stays (the BVH builders handle degenerate triangles).
PlyMesh readPlyMesh(std::span<const std::uint8_t> bytes, const std::string& name);
PlyMesh loadPlyMesh(const std::string& path);

}  // namespace wt
