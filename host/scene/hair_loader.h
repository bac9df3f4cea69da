// Strand files: Cem Yuksel's .hair format and PLY polylines (the layout of
// hairutil: a vertex element, then a strand element of segment counts, each
// strand's points consecutive). Errors are SceneError naming the file and
// the element, e.g. "Bangs_100.hair: strand 7, point 3: coordinate is not
// finite (nan)".
#pragma once

#include "scene/scene.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace wt {

/// Strands as read, in the file's units.
struct StrandSet {
  std::vector<glm::vec4> points;      ///< x, y, z, radius: strand after strand
  std::vector<std::uint32_t> counts;  ///< points per strand (segments + 1), in order
  bool hasRadius = false;             ///< radii came from the file (.hair: half its thickness); else they are 0
};

/// A .hair file (cyHairFile's layout: a 128-byte header, then the arrays its
/// flags name: segments per strand, points, thickness, transparency, colours).
/// Radii are half the thickness (per point, or the header's default).
StrandSet loadHairFile(const std::string& path);
StrandSet loadHairFromMemory(std::span<const std::uint8_t> bytes, const std::string& name);

/// A PLY file of polylines, ASCII or binary of either byte order: vertex x,
/// y, z (and radius, if present) and an element "strand" whose one scalar
/// property is each strand's segment count; other elements and properties
/// are skipped.
StrandSet loadPlyStrands(const std::string& path);
StrandSet loadPlyStrandsFromMemory(std::span<const std::uint8_t> bytes, const std::string& name);

/// A strand file by its extension (.hair or .ply).
StrandSet loadStrands(const std::string& path);

}  // namespace wt
