// SDF grids on the host: their bricks' boxes and rows (kernels/geometry/sdf_grid.cl).
#include "geometry/primitives.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace wt {

bool sdfGridSparse(const SdfGrid& grid) {
  if (grid.storage != SdfStorage::kAuto) return grid.storage == SdfStorage::kSparse;
  return std::uint64_t(grid.cells.x) * grid.cells.y * grid.cells.z > kSdfSparseAboveCells;
}

bool sdfGridUsable(const SdfGrid& grid) {
  const glm::uvec3 c = grid.cells;
  if (c.x < 1 || c.y < 1 || c.z < 1 || c.x > kSdfMaxCells || c.y > kSdfMaxCells || c.z > kSdfMaxCells) return false;
  if (grid.values.size() != std::size_t(c.x + 1) * (c.y + 1) * (c.z + 1)) return false;
  const double det = glm::determinant(glm::dmat3(grid.latticeToScene));
  if (!(det != 0.0) || !std::isfinite(det)) return false;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      if (!std::isfinite(grid.latticeToScene[i][j])) return false;
  return true;
}

namespace {

/// Whether the surface crosses cell (x, y, z): some corner < 0 and some >= 0;
/// a cell with a NaN corner has none (the loaders refuse NaN; grids made in code may not).
bool cellCrossed(const SdfGrid& g, std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  const std::size_t sx = g.cells.x + 1, sxy = sx * (g.cells.y + 1);
  const std::size_t i = x + y * sx + z * sxy;
  const float s[8] = {g.values[i], g.values[i + 1], g.values[i + sx], g.values[i + sx + 1],
                      g.values[i + sxy], g.values[i + sxy + 1], g.values[i + sxy + sx], g.values[i + sxy + sx + 1]};
  bool inside = false, outside = false;
  for (float v : s) {
    if (std::isnan(v)) return false;
    inside |= v < 0.0f;
    outside |= v >= 0.0f;
  }
  return inside && outside;
}

}  // namespace

void gatherSdfGrids(const Scene& scene, PrimitiveRows& rows) {
  std::vector<SdfGridRef> list;
  list.reserve(scene.sdfGrids.size());
  for (const SdfGrid& g : scene.sdfGrids) list.push_back({&g, g.latticeToScene, true});
  gatherSdfGridList(list, rows);
}

void gatherSdfGridList(std::span<const SdfGridRef> list, PrimitiveRows& rows) {
  rows.dataFirst[WT_PRIM_SDF_GRID] = std::uint32_t(rows.data.size());
  rows.infoFirst[WT_PRIM_SDF_GRID] = std::uint32_t(rows.info.size());
  const std::size_t grids = list.size();
  rows.sdfBricks.clear();
  // the grids' rows first, then their values: offsets count floats from the type's first row
  for (const SdfGridRef& ref : list) {
    const SdfGrid& g = *ref.grid;
    const bool usable = sdfGridUsable(g);
    const glm::dmat4 toLattice = usable ? glm::inverse(ref.latticeToScene) : glm::dmat4(1.0);
    for (int r = 0; r < 3; ++r)
      rows.data.push_back({float(toLattice[0][r]), float(toLattice[1][r]), float(toLattice[2][r]), float(toLattice[3][r])});
    // a lattice unit's scene length at most: the linear part's Frobenius norm
    const glm::dmat3 linear(ref.latticeToScene);
    const double unit = std::sqrt(glm::dot(linear[0], linear[0]) + glm::dot(linear[1], linear[1]) + glm::dot(linear[2], linear[2]));
    rows.data.push_back({float(g.cells.x), float(g.cells.y), float(g.cells.z), float(unit)});
  }
  std::vector<float> values;
  const std::size_t base = 4 * WT_SDF_GRID_ROWS * grids;
  constexpr std::uint32_t B = WT_SDF_BRICK;
  std::uint32_t bricks = 0;
  for (std::size_t gi = 0; gi < grids; ++gi) {
    const SdfGrid& g = *list[gi].grid;
    const glm::dmat4& latticeToScene = list[gi].latticeToScene;
    rows.sdfBricks.push_back(bricks);
    if (!list[gi].drawn) continue;
    if (!sdfGridUsable(g)) {
      ++rows.skipped;
      continue;
    }
    const bool sparse = sdfGridSparse(g);
    const std::size_t sx = g.cells.x + 1, sxy = sx * (g.cells.y + 1);
    const std::size_t denseBase = base + values.size();
    if (!sparse) values.insert(values.end(), g.values.begin(), g.values.end());
    const glm::uvec3 nb = (g.cells + (B - 1)) / B;
    for (std::uint32_t bz = 0; bz < nb.z; ++bz)
      for (std::uint32_t by = 0; by < nb.y; ++by)
        for (std::uint32_t bx = 0; bx < nb.x; ++bx) {
          const glm::uvec3 lo(bx * B, by * B, bz * B);
          const glm::uvec3 hi = glm::min(lo + B, g.cells);
          // the box of the cells the surface crosses, in the lattice
          glm::uvec3 cmin(~0u), cmax(0u);
          std::array<std::uint32_t, 16> crossed{};
          for (std::uint32_t z = lo.z; z < hi.z; ++z)
            for (std::uint32_t y = lo.y; y < hi.y; ++y)
              for (std::uint32_t x = lo.x; x < hi.x; ++x)
                if (cellCrossed(g, x, y, z)) {
                  cmin = glm::min(cmin, glm::uvec3(x, y, z));
                  cmax = glm::max(cmax, glm::uvec3(x, y, z));
                  const std::uint32_t bit = (x - lo.x) + B * ((y - lo.y) + B * (z - lo.z));
                  crossed[bit >> 5] |= 1u << (bit & 31u);
                }
          if (cmin.x > cmax.x) continue;
          Aabb box;
          glm::dvec3 blo(1e300), bhi(-1e300);
          for (int corner = 0; corner < 8; ++corner) {
            const glm::dvec3 c((corner & 1) ? cmax.x + 1 : cmin.x, (corner & 2) ? cmax.y + 1 : cmin.y,
                               (corner & 4) ? cmax.z + 1 : cmin.z);
            const glm::dvec3 w(latticeToScene * glm::dvec4(c, 1.0));
            blo = glm::min(blo, w);
            bhi = glm::max(bhi, w);
          }
          // past float rounding, and past the kernel's sliver of overlap between cells
          const glm::dvec3 slack = 1e-6 * (glm::abs(blo) + glm::abs(bhi)) + 1e-4 * (bhi - blo);
          box.lo = glm::vec3(blo - slack);
          box.hi = glm::vec3(bhi + slack);
          if (!std::isfinite(box.lo.x + box.lo.y + box.lo.z + box.hi.x + box.hi.y + box.hi.z)) {
            ++rows.skipped;
            continue;
          }
          std::size_t offset;
          if (sparse) {
            // the brick's own corners; past the grid's end, the last corner again (never read)
            offset = base + values.size();
            for (std::uint32_t z = 0; z <= B; ++z)
              for (std::uint32_t y = 0; y <= B; ++y)
                for (std::uint32_t x = 0; x <= B; ++x) {
                  const std::size_t gx = std::min(lo.x + x, g.cells.x), gy = std::min(lo.y + y, g.cells.y),
                                    gz = std::min(lo.z + z, g.cells.z);
                  values.push_back(g.values[gx + gy * sx + gz * sxy]);
                }
          } else {
            offset = denseBase + lo.x + lo.y * sx + lo.z * sxy;
          }
          const std::uint32_t packed = bx | (by << 9) | (bz << 18) | (sparse ? WT_SDF_SPARSE : 0u);
          rows.info.push_back({g.material, std::uint32_t(gi), std::uint32_t(offset), packed});
          for (std::size_t w = 0; w < crossed.size(); w += 4)
            rows.info.push_back({crossed[w], crossed[w + 1], crossed[w + 2], crossed[w + 3]});
          rows.bounds.push_back(box);
          rows.ids.push_back(primId(WT_PRIM_SDF_GRID, bricks++));
        }
  }
  rows.sdfBricks.push_back(bricks);
  rows.count[WT_PRIM_SDF_GRID] = bricks;
  for (std::size_t i = 0; i < values.size(); i += 4) {
    float v[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    for (std::size_t k = 0; k < 4 && i + k < values.size(); ++k) v[k] = values[i + k];
    rows.data.push_back({v[0], v[1], v[2], v[3]});
  }
}

glm::vec3 sdfGridPoint(const PrimitiveRows& rows, std::uint32_t index, glm::vec3 o, glm::vec3 d, float t, float cell,
                       glm::vec3* error, glm::vec3* normal) {
  const WtVec4* base = rows.data.data() + rows.dataFirst[WT_PRIM_SDF_GRID];
  const std::array<std::uint32_t, 4>& info = rows.info[rows.infoFirst[WT_PRIM_SDF_GRID] + WT_SDF_INFO_ROWS * index];
  const WtVec4* grid = base + WT_SDF_GRID_ROWS * info[1];
  const glm::vec3 m[3] = {{grid[0].x, grid[0].y, grid[0].z}, {grid[1].x, grid[1].y, grid[1].z}, {grid[2].x, grid[2].y, grid[2].z}};
  const glm::vec3 shift(grid[0].w, grid[1].w, grid[2].w);
  const std::uint32_t nx = std::uint32_t(grid[3].x) + 1, ny = std::uint32_t(grid[3].y) + 1;
  const bool sparse = (info[3] & WT_SDF_SPARSE) != 0;
  const std::uint32_t sx = sparse ? WT_SDF_BRICK + 1 : nx, sxy = sparse ? (WT_SDF_BRICK + 1) * (WT_SDF_BRICK + 1) : nx * ny;
  const glm::ivec3 lo(int(info[3] & 511u) * WT_SDF_BRICK, int((info[3] >> 9) & 511u) * WT_SDF_BRICK,
                      int((info[3] >> 18) & 511u) * WT_SDF_BRICK);
  const auto id = std::uint32_t(cell);
  const glm::ivec3 c(int(id % WT_SDF_BRICK), int((id / WT_SDF_BRICK) % WT_SDF_BRICK), int(id / (WT_SDF_BRICK * WT_SDF_BRICK)));
  const float* v = reinterpret_cast<const float*>(base) + info[2] + c.x + c.y * sx + c.z * sxy;
  auto s = [&](int x, int y, int z) { return v[x + y * sx + z * sxy]; };
  const glm::vec3 p = o + t * d;
  const glm::vec3 pl(glm::dot(m[0], p) + shift.x, glm::dot(m[1], p) + shift.y, glm::dot(m[2], p) + shift.z);
  const glm::vec3 q = pl - glm::vec3(lo + c);
  glm::vec3 grad(0.0f);
  float scale = 0.0f;
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 2; ++x) {
        const float w = s(x, y, z), wx = x ? q.x : 1 - q.x, wy = y ? q.y : 1 - q.y, wz = z ? q.z : 1 - q.z;
        grad += w * glm::vec3((x ? 1.0f : -1.0f) * wy * wz, wx * (y ? 1.0f : -1.0f) * wz, wx * wy * (z ? 1.0f : -1.0f));
        scale += std::fabs(w);
      }
  const glm::vec3 n = grad.x * m[0] + grad.y * m[1] + grad.z * m[2];
  const float len = glm::length(n);
  *normal = len > 0.0f && std::isfinite(len) ? n / len : glm::vec3(0.0f);
  // as the kernel's bound: the ray's rounding into the lattice and the interpolant's, into the scene
  constexpr float kEps = 1.1920929e-7f;
  const glm::vec3 apl = glm::abs(pl);
  const float glen = glm::length(grad);
  const float offLattice = 8.0f * kEps * (std::max(apl.x, std::max(apl.y, apl.z)) + 1.0f) +
                           (glen > 0.0f ? std::min(64.0f * kEps * 4.0f * scale / glen, 0.25f) : 0.25f);
  const float gamma3 = 3.0f * 0.5f * kEps / (1.0f - 3.0f * 0.5f * kEps);
  *error = gamma3 * (glm::abs(o) + glm::abs(t * d)) + glm::vec3(grid[3].w * offLattice);
  return p;
}

double sdfBrickArea(const Scene& scene, const PrimitiveRows& rows, std::uint32_t index) {
  const std::size_t row = rows.infoFirst[WT_PRIM_SDF_GRID] + WT_SDF_INFO_ROWS * std::size_t(index);
  std::uint32_t crossed = 0;
  for (std::size_t r = 1; r < WT_SDF_INFO_ROWS; ++r)
    for (std::uint32_t word : rows.info[row + r]) crossed += std::uint32_t(std::popcount(word));
  return double(crossed) * sdfCellArea(scene.sdfGrids[rows.info[row][1]]);
}

double sdfCellArea(const SdfGrid& grid) {
  const double volume = std::abs(glm::determinant(glm::dmat3(grid.latticeToScene)));
  return std::cbrt(volume * volume);
}

}  // namespace wt
