// Displaced meshes on the host: the subdivision level, the rows and base
// triangles' shells the kernels read (kernels/geometry/displaced.cl), the
// surface at a hit, and the pre-tessellation the benchmark compares with.
#include "geometry/primitives.h"

#include "bvh/parallel.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

namespace wt {

std::uint32_t displacedLevel(const DisplacedMesh& mesh) {
  if (mesh.level >= 0) return std::uint32_t(std::min(mesh.level, WT_DISP_MAX_LEVEL));
  // the longest base edge in texels along either axis of the map: micro-edges of a texel at most
  double span = 0.0;
  for (const auto& t : mesh.triangles)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = t[e], b = t[(e + 1) % 3];
      if (a >= mesh.texcoords.size() || b >= mesh.texcoords.size()) continue;
      const glm::dvec2 d = glm::dvec2(mesh.texcoords[b] - mesh.texcoords[a]) * glm::dvec2(mesh.mapWidth, mesh.mapHeight);
      const double s = std::max(std::fabs(d.x), std::fabs(d.y));
      if (std::isfinite(s)) span = std::max(span, s);
    }
  if (!(span > 1.0)) return 0;
  return std::uint32_t(std::min(double(WT_DISP_MAX_LEVEL), std::ceil(std::log2(span) - 1e-9)));
}

bool displacedMeshUsable(const DisplacedMesh& m) {
  const std::size_t v = m.positions.size();
  if (m.normals.size() != v || m.texcoords.size() != v || m.triangles.empty()) return false;
  if (m.mapWidth < 1 || m.mapHeight < 1 || m.mapWidth > 65536 || m.mapHeight > 65536) return false;
  if (m.map.size() != std::size_t(m.mapWidth) * m.mapHeight) return false;
  return std::isfinite(m.scale) && std::isfinite(m.offset) && m.level <= WT_DISP_MAX_LEVEL;
}

namespace {

/// The map as the kernel reads it: NaN as 0.
struct MapView {
  const float* texels;
  int w, h;
  float at(int x, int y) const {
    const float v = texels[std::size_t(y) * std::size_t(w) + std::size_t(x)];
    return std::isnan(v) ? 0.0f : v;
  }
};

int wrap(float x, int size) {
  const float fs = float(size);
  return int(x - fs * std::floor(x / fs));
}

/// disp_sample on the host, the same float operations.
float sampleMap(const MapView& m, glm::vec2 uv) {
  const float x = uv.x * float(m.w) - 0.5f, y = uv.y * float(m.h) - 0.5f;
  if (!(std::fabs(x) < 4194304.0f && std::fabs(y) < 4194304.0f)) return 0.0f;
  const float fx0 = std::floor(x), fy0 = std::floor(y);
  const float fx = x - fx0, fy = y - fy0;
  const int x0 = wrap(fx0, m.w), y0 = wrap(fy0, m.h);
  const int x1 = x0 + 1 == m.w ? 0 : x0 + 1, y1 = y0 + 1 == m.h ? 0 : y0 + 1;
  const float a = m.at(x0, y0), b = m.at(x1, y0), c = m.at(x0, y1), d = m.at(x1, y1);
  return (a * (1.0f - fx) + b * fx) * (1.0f - fy) + (c * (1.0f - fx) + d * fx) * fy;
}

/// The micro-vertex at lattice point (i, j) of `perEdge`, as disp_vertex
/// computes it (exact weights for a power of two; a correctly rounded
/// quotient otherwise, the same from both triangles of an edge).
glm::vec3 microVertex(const DisplacedMesh& mesh, const MapView& map, const std::array<std::uint32_t, 3>& t,
                      int perEdge, int i, int j, glm::vec3* normal = nullptr, glm::vec2* uvOut = nullptr,
                      float* displacement = nullptr) {
  const float n = float(perEdge);
  const float wa = float(perEdge - i - j) / n, wb = float(i) / n, wc = float(j) / n;
  const glm::vec3 pa = wa * mesh.positions[t[0]], pb = wb * mesh.positions[t[1]], pc = wc * mesh.positions[t[2]];
  const glm::vec3 p = (pa + pb) + pc;
  const glm::vec3 na = wa * mesh.normals[t[0]], nb = wb * mesh.normals[t[1]], nc = wc * mesh.normals[t[2]];
  const glm::vec3 nrm = (na + nb) + nc;
  const glm::vec2 ua = wa * mesh.texcoords[t[0]], ub = wb * mesh.texcoords[t[1]], uc = wc * mesh.texcoords[t[2]];
  const glm::vec2 uv = (ua + ub) + uc;
  if (normal) *normal = nrm;
  if (uvOut) *uvOut = uv;
  const float d = mesh.scale * sampleMap(map, uv) + mesh.offset;
  if (displacement) *displacement = d;
  const glm::vec3 dn = d * nrm;
  return p + dn;
}

/// The displaced surface's unit shading normal at barycentrics (wb, wc),
/// as disp_tangents and displaced_surface compute it: bump mapping on the
/// smooth base (the base edges made perpendicular to the interpolated
/// normal, tilted by the map's slope from central differences one texel
/// apart), on the interpolated normal's side.
glm::vec3 shadingNormal(const DisplacedMesh& mesh, const MapView& map, const std::array<std::uint32_t, 3>& t, float wb,
                        float wc) {
  const float wa = 1.0f - wb - wc;
  const glm::vec2 t0 = mesh.texcoords[t[0]], t1 = mesh.texcoords[t[1]], t2 = mesh.texcoords[t[2]];
  glm::vec3 nrm = wa * mesh.normals[t[0]] + wb * mesh.normals[t[1]] + wc * mesh.normals[t[2]];
  const glm::vec2 uv = wa * t0 + wb * t1 + wc * t2;
  const float nl = glm::length(nrm);
  nrm = nl > 0.0f && std::isfinite(nl) ? nrm / nl : glm::vec3(0.0f);
  const float du = 1.0f / float(map.w), dv = 1.0f / float(map.h);
  const float hu = (sampleMap(map, uv + glm::vec2(du, 0.0f)) - sampleMap(map, uv - glm::vec2(du, 0.0f))) * (0.5f * float(map.w));
  const float hv = (sampleMap(map, uv + glm::vec2(0.0f, dv)) - sampleMap(map, uv - glm::vec2(0.0f, dv))) * (0.5f * float(map.h));
  const glm::vec2 uvb = t1 - t0, uvc = t2 - t0;
  glm::vec3 eb = mesh.positions[t[1]] - mesh.positions[t[0]], ec = mesh.positions[t[2]] - mesh.positions[t[0]];
  eb -= glm::dot(eb, nrm) * nrm;
  ec -= glm::dot(ec, nrm) * nrm;
  const glm::vec3 sb = eb + (mesh.scale * (hu * uvb.x + hv * uvb.y)) * nrm;
  const glm::vec3 sc = ec + (mesh.scale * (hu * uvc.x + hv * uvc.y)) * nrm;
  glm::vec3 sn = glm::cross(sb, sc);
  const float len = glm::length(sn);
  if (!(len > 0.0f) || !std::isfinite(len)) return glm::vec3(0.0f);
  sn /= len;
  return glm::dot(sn, nrm) < 0.0f ? -sn : sn;
}

/// A min-max pyramid over a map: level k >= 1 holds (min, max) pairs of
/// ceil(w / 2^k) x ceil(h / 2^k) cells, each over the 2 x 2 cells (texels
/// for k = 1) below it that exist.
std::vector<std::vector<float>> minMaxPyramid(const MapView& map) {
  std::vector<std::vector<float>> levels;
  int w = map.w, h = map.h;
  while (w > 1 || h > 1) {
    const int nw = (w + 1) / 2, nh = (h + 1) / 2;
    std::vector<float> next(std::size_t(2) * nw * nh);
    for (int y = 0; y < nh; ++y)
      for (int x = 0; x < nw; ++x) {
        float lo = std::numeric_limits<float>::infinity(), hi = -lo;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) {
            const int sx = 2 * x + dx, sy = 2 * y + dy;
            if (sx >= w || sy >= h) continue;
            if (levels.empty()) {
              lo = std::min(lo, map.at(sx, sy));
              hi = std::max(hi, map.at(sx, sy));
            } else {
              const std::vector<float>& below = levels.back();
              lo = std::min(lo, below[2 * (std::size_t(sy) * w + sx)]);
              hi = std::max(hi, below[2 * (std::size_t(sy) * w + sx) + 1]);
            }
          }
        next[2 * (std::size_t(y) * nw + x)] = lo;
        next[2 * (std::size_t(y) * nw + x) + 1] = hi;
      }
    levels.push_back(std::move(next));
    w = nw;
    h = nh;
  }
  return levels;
}

/// The least and largest map value over the texels a bilinear sample
/// anywhere in the uv box reads, wider than the kernel's own query (every
/// texel of the widened rectangle, or the whole map where it wraps).
glm::dvec2 mapRange(const MapView& map, const std::vector<std::vector<float>>& pyramid, glm::dvec2 lo, glm::dvec2 hi) {
  const glm::dvec2 slack = 1e-5 * (glm::abs(lo) + glm::abs(hi)) + 1e-6;
  auto axis = [](double a, double b, int size, int* from, int* to) {
    const double f0 = std::floor(a) - 1.0, f1 = std::floor(b) + 2.0;
    if (!(f1 - f0 < size) || !(std::fabs(f0) < 4e6 && std::fabs(f1) < 4e6)) {
      *from = 0, *to = size - 1;
      return;
    }
    const int w0 = int(f0 - size * std::floor(f0 / size));
    const int w1 = w0 + int(f1 - f0);
    if (w1 >= size) *from = 0, *to = size - 1;
    else *from = w0, *to = w1;
  };
  int x0, x1, y0, y1;
  axis((lo.x - slack.x) * map.w - 0.5, (hi.x + slack.x) * map.w - 0.5, map.w, &x0, &x1);
  axis((lo.y - slack.y) * map.h - 0.5, (hi.y + slack.y) * map.h - 0.5, map.h, &y0, &y1);
  std::size_t k = 0;
  while (k < pyramid.size() && (((x1 >> k) - (x0 >> k)) > 1 || ((y1 >> k) - (y0 >> k)) > 1)) ++k;
  double vmin = std::numeric_limits<double>::infinity(), vmax = -vmin;
  const int wk = (map.w + (1 << k) - 1) >> k;
  for (int y = y0 >> k; y <= (y1 >> k); ++y)
    for (int x = x0 >> k; x <= (x1 >> k); ++x) {
      if (k == 0) {
        vmin = std::min(vmin, double(map.at(x, y)));
        vmax = std::max(vmax, double(map.at(x, y)));
      } else {
        const std::vector<float>& level = pyramid[k - 1];
        vmin = std::min(vmin, double(level[2 * (std::size_t(y) * wk + x)]));
        vmax = std::max(vmax, double(level[2 * (std::size_t(y) * wk + x) + 1]));
      }
    }
  return {vmin, vmax};
}

bool cornersUsable(const DisplacedMesh& m, const std::array<std::uint32_t, 3>& t) {
  for (std::uint32_t v : t) {
    if (v >= m.positions.size()) return false;
    const glm::vec3 p = m.positions[v], n = m.normals[v];
    const glm::vec2 uv = m.texcoords[v];
    if (!std::isfinite(p.x + p.y + p.z + n.x + n.y + n.z + uv.x + uv.y)) return false;
  }
  return true;
}


/// The distinct values (bit patterns, sorted) of a map that has at most 256
/// of them, as an 8-bit image has; empty for a map with more.
std::vector<std::uint32_t> smallPalette(const std::vector<std::uint32_t>& texels) {
  // open addressing over 1024 slots: at most 257 values ever go in
  constexpr std::size_t kSlots = 1024;
  std::vector<std::uint32_t> slot(kSlots);
  std::vector<bool> used(kSlots, false);
  std::vector<std::uint32_t> values;
  std::uint32_t last = 0;
  bool haveLast = false;
  for (std::uint32_t v : texels) {
    if (haveLast && v == last) continue;
    last = v, haveLast = true;
    std::size_t h = (v * 2654435761u) >> 22;
    while (used[h] && slot[h] != v) h = (h + 1) % kSlots;
    if (used[h]) continue;
    used[h] = true;
    slot[h] = v;
    values.push_back(v);
    if (values.size() > 256) return {};
  }
  std::sort(values.begin(), values.end());
  return values;
}

/// A quadtree node as the kernel's disp_node: its level, orientation and
/// place in its level's lattice.
struct QuadNode {
  std::uint32_t level = 0, inverted = 0, i = 0, j = 0;
};

/// Child k of a node, as displaced_intersect pushes it (children in the
/// order of the corner triples (A, AB, AC), (AB, B, BC), (AC, BC, C), (AB, AC, BC)).
QuadNode childNode(const QuadNode& p, int k) {
  static constexpr int kUpDi[4] = {0, 1, 0, 0}, kUpDj[4] = {0, 0, 1, 0};
  static constexpr int kInvDi[4] = {1, 0, 1, 1}, kInvDj[4] = {0, 1, 1, 1};
  const std::uint32_t di = std::uint32_t(p.inverted ? kInvDi[k] : kUpDi[k]);
  const std::uint32_t dj = std::uint32_t(p.inverted ? kInvDj[k] : kUpDj[k]);
  return {p.level + 1, k == 3 ? 1 - p.inverted : p.inverted, 2 * p.i + di, 2 * p.j + dj};
}

/// A node's corners in the level-L lattice, as disp_node_corners.
std::array<glm::ivec2, 3> nodeCorners(const QuadNode& q, std::uint32_t levelL) {
  const int s = 1 << (levelL - q.level), i = int(q.i), j = int(q.j);
  if (q.inverted) return {glm::ivec2((i + 1) * s, j * s), glm::ivec2(i * s, (j + 1) * s), glm::ivec2((i + 1) * s, (j + 1) * s)};
  return {glm::ivec2(i * s, j * s), glm::ivec2((i + 1) * s, j * s), glm::ivec2(i * s, (j + 1) * s)};
}

/// The box a block's byte q gives a child's low (high: false) side on one
/// axis inside the parent's [lo, hi], as displaced_intersect computes it
/// (float, no contraction): 0 and 255 give the parent's own sides exactly.
float dequantized(float lo, float hi, int q, bool low) {
  const float step = (hi - lo) * (1.0f / 255.0f);
  return low ? lo + float(q) * step : hi - (255.0f - float(q)) * step;
}

/// The byte that bounds `target` from below (low) or above inside [lo, hi]:
/// the tightest whose dequantized side still holds it, 0 or 255 at worst.
std::uint8_t quantized(float lo, float hi, double target, bool low) {
  const double step = (double(hi) - double(lo)) / 255.0;
  double guess = step > 0.0 ? (target - double(lo)) / step : (low ? 0.0 : 255.0);
  int q = std::clamp(int(low ? std::floor(guess) : std::ceil(guess)), 0, 255);
  if (low) {
    while (q > 0 && double(dequantized(lo, hi, q, true)) > target) --q;
    while (q < 255 && double(dequantized(lo, hi, q + 1, true)) <= target) ++q;
  } else {
    while (q < 255 && double(dequantized(lo, hi, q, false)) < target) ++q;
    while (q > 0 && double(dequantized(lo, hi, q - 1, false)) >= target) --q;
  }
  return std::uint8_t(q);
}

/// D, the deepest level whose sub-triangles' boxes are stored, for level L.
std::uint32_t storedDepth(std::uint32_t maxDepth, std::uint32_t level) {
  return level == 0 ? 0 : std::min({level - 1, maxDepth, std::uint32_t(WT_DISP_MAX_DEPTH)});
}

/// A base triangle's boxes as the kernel reads them: the whole triangle's
/// box (the BVH's) and the blocks of its sub-triangles' children's boxes
/// (shared/types.h, WT_PRIM_DISPLACED), each holding its sub-triangle's
/// micro-triangles as the kernel displaces them. Exact over the
/// micro-vertices where the level-D sub-triangles are the micro-triangles'
/// parents (L <= WT_DISP_MAX_DEPTH + 1); deeper, each level-D box bounds
/// its corners moved by the least and the largest displacement over its
/// texels (the pyramid's). Every box is widened by a sliver past rounding.
struct TriangleBoxes {
  Aabb root;
  glm::vec3 slabNormal{0.0f};  ///< the base triangle's unit face normal (zero where it has no area)
  float slabLo = 0.0f, slabHi = 0.0f;  ///< every micro-vertex v has slabLo <= dot(slabNormal, v) <= slabHi
  std::vector<std::uint8_t> blocks;  ///< 24 bytes per sub-triangle of levels 0 to D - 1
  std::vector<float> displacements;  ///< d at every micro-vertex, row by row (j), where L <= D + 1; else empty
  bool finite = true;
};

TriangleBoxes triangleBoxes(const DisplacedMesh& mesh, const MapView& map, const std::vector<std::vector<float>>* pyramid,
                            const std::array<std::uint32_t, 3>& t, std::uint32_t levelL, std::uint32_t depth) {
  const int n = 1 << levelL;
  std::size_t nodes = 0;
  for (std::uint32_t l = 0; l <= depth; ++l) nodes += std::size_t(1) << (2 * l);
  std::vector<Aabb> exact(nodes);
  // the level-D sub-triangles' boxes, then each parent the union of its children's
  const std::size_t firstLeaf = nodes - (std::size_t(1) << (2 * depth));
  std::vector<glm::vec3> grid;
  std::vector<std::size_t> rowStart;
  std::vector<float> displacements;
  if (levelL == 0 || levelL == depth + 1) {
    rowStart.resize(std::size_t(n) + 1);
    for (int j = 0; j <= n; ++j) {
      rowStart[std::size_t(j)] = grid.size();
      for (int i = 0; i + j <= n; ++i) {
        float d;
        grid.push_back(microVertex(mesh, map, t, n, i, j, nullptr, nullptr, &d));
        displacements.push_back(d);
      }
    }
  }
  auto vertex = [&](glm::ivec2 c) { return grid[rowStart[std::size_t(c.y)] + std::size_t(c.x)]; };
  // the slab along the face normal (as stored, a float vector): the heights of the points that bound the shell
  glm::dvec3 faceNormal = glm::cross(glm::dvec3(mesh.positions[t[1]]) - glm::dvec3(mesh.positions[t[0]]),
                                     glm::dvec3(mesh.positions[t[2]]) - glm::dvec3(mesh.positions[t[0]]));
  const double faceLength = glm::length(faceNormal);
  const glm::vec3 slabNormal = faceLength > 0.0 && std::isfinite(faceLength) ? glm::vec3(faceNormal / faceLength) : glm::vec3(0.0f);
  double slabLo = std::numeric_limits<double>::infinity(), slabHi = -slabLo;
  auto height = [&](const glm::dvec3& p) {
    const double h = glm::dot(glm::dvec3(slabNormal), p);
    slabLo = std::min(slabLo, h);
    slabHi = std::max(slabHi, h);
  };
  for (const glm::vec3& v : grid) height(glm::dvec3(v));
  std::vector<QuadNode> level{QuadNode{}};
  for (std::uint32_t l = 0; l < depth; ++l) {
    std::vector<QuadNode> next;
    next.reserve(4 * level.size());
    for (const QuadNode& q : level)
      for (int k = 0; k < 4; ++k) next.push_back(childNode(q, k));
    level = std::move(next);
  }
  for (std::size_t k = 0; k < level.size(); ++k) {
    Aabb& box = exact[firstLeaf + k];
    if (levelL == 0) {
      for (glm::ivec2 c : {glm::ivec2(0, 0), glm::ivec2(1, 0), glm::ivec2(0, 1)}) box.extend(vertex(c));
    } else if (levelL == depth + 1) {
      const std::array<glm::ivec2, 3> c = nodeCorners(level[k], levelL);
      for (glm::ivec2 p : {c[0], c[1], c[2], (c[0] + c[1]) / 2, (c[0] + c[2]) / 2, (c[1] + c[2]) / 2})
        box.extend(vertex(p));
    } else {
      // the corners moved by the least and the largest displacement over the sub-triangle's texels
      const std::array<glm::ivec2, 3> c = nodeCorners(level[k], levelL);
      glm::dvec3 p[3], nn[3];
      glm::dvec2 ulo(std::numeric_limits<double>::infinity()), uhi(-ulo.x);
      for (int e = 0; e < 3; ++e) {
        const double wb = double(c[e].x) / n, wc = double(c[e].y) / n, wa = 1.0 - wb - wc;
        p[e] = wa * glm::dvec3(mesh.positions[t[0]]) + wb * glm::dvec3(mesh.positions[t[1]]) +
               wc * glm::dvec3(mesh.positions[t[2]]);
        nn[e] = wa * glm::dvec3(mesh.normals[t[0]]) + wb * glm::dvec3(mesh.normals[t[1]]) +
                wc * glm::dvec3(mesh.normals[t[2]]);
        const glm::dvec2 uv = wa * glm::dvec2(mesh.texcoords[t[0]]) + wb * glm::dvec2(mesh.texcoords[t[1]]) +
                              wc * glm::dvec2(mesh.texcoords[t[2]]);
        ulo = glm::min(ulo, uv);
        uhi = glm::max(uhi, uv);
      }
      const glm::dvec2 r = mapRange(map, *pyramid, ulo, uhi);
      glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo.x);
      for (int e = 0; e < 3; ++e)
        for (double d : {double(mesh.scale) * r.x + mesh.offset, double(mesh.scale) * r.y + mesh.offset}) {
          lo = glm::min(lo, p[e] + d * nn[e]);
          hi = glm::max(hi, p[e] + d * nn[e]);
          // the sub-triangle's surface is a convex combination of these six points: so are its heights
          height(p[e] + d * nn[e]);
        }
      // float rounding here is a few ulps: the margin below covers it
      box.lo = glm::vec3(lo);
      box.hi = glm::vec3(hi);
    }
  }
  for (std::size_t g = firstLeaf; g-- > 0;)
    for (std::size_t k = 1; k <= 4; ++k) exact[g].extend(exact[4 * g + k]);
  TriangleBoxes out;
  out.displacements = std::move(displacements);
  const glm::dvec3 rlo(exact[0].lo), rhi(exact[0].hi);
  if (!std::isfinite(rlo.x + rlo.y + rlo.z + rhi.x + rhi.y + rhi.z)) {
    out.finite = false;
    return out;
  }
  // past the rounding of the micro-vertices (the kernel's against these) and of the bounds above
  double big = 0.0, extent = 0.0;
  for (int a = 0; a < 3; ++a) {
    big = std::max({big, std::fabs(rlo[a]), std::fabs(rhi[a])});
    extent = std::max(extent, rhi[a] - rlo[a]);
  }
  const double margin = 4e-6 * big + 1e-6 * extent;
  const float inf = std::numeric_limits<float>::infinity();
  // a height is a dot product of a unit vector: up to sqrt(3) times a coordinate's rounding
  out.slabNormal = slabNormal;
  out.slabLo = float(slabLo - 2.0 * margin);
  if (double(out.slabLo) > slabLo - 2.0 * margin) out.slabLo = std::nextafter(out.slabLo, -inf);
  out.slabHi = float(slabHi + 2.0 * margin);
  if (double(out.slabHi) < slabHi + 2.0 * margin) out.slabHi = std::nextafter(out.slabHi, inf);
  for (int a = 0; a < 3; ++a) {
    out.root.lo[a] = float(rlo[a] - margin);
    if (double(out.root.lo[a]) > rlo[a] - margin) out.root.lo[a] = std::nextafter(out.root.lo[a], -inf);
    out.root.hi[a] = float(rhi[a] + margin);
    if (double(out.root.hi[a]) < rhi[a] + margin) out.root.hi[a] = std::nextafter(out.root.hi[a], inf);
  }
  // top down: each child's box in bytes relative to its parent's box as the kernel dequantizes it
  const std::size_t blocks = firstLeaf;
  out.blocks.assign(24 * blocks, 0);
  std::vector<Aabb> stored(nodes);
  stored[0] = out.root;
  for (std::size_t g = 0; g < blocks; ++g) {
    const Aabb& parent = stored[g];
    for (int k = 0; k < 4; ++k) {
      const Aabb& e = exact[4 * g + 1 + std::size_t(k)];
      Aabb& child = stored[4 * g + 1 + std::size_t(k)];
      for (int a = 0; a < 3; ++a) {
        const std::uint8_t lo = quantized(parent.lo[a], parent.hi[a], double(e.lo[a]) - margin, true);
        const std::uint8_t hi = quantized(parent.lo[a], parent.hi[a], double(e.hi[a]) + margin, false);
        out.blocks[24 * g + 4 * std::size_t(a) + std::size_t(k)] = lo;
        out.blocks[24 * g + 12 + 4 * std::size_t(a) + std::size_t(k)] = hi;
        child.lo[a] = dequantized(parent.lo[a], parent.hi[a], lo, true);
        child.hi[a] = dequantized(parent.lo[a], parent.hi[a], hi, false);
      }
    }
  }
  return out;
}

}  // namespace

void gatherDisplaced(const Scene& scene, PrimitiveRows& rows) { gatherDisplacedTo(scene, rows, WT_DISP_MAX_DEPTH); }

void gatherDisplacedTo(const Scene& scene, PrimitiveRows& rows, std::uint32_t maxDepth, int threads) {
  std::vector<DisplacedRef> list;
  list.reserve(scene.displacedMeshes.size());
  for (const DisplacedMesh& m : scene.displacedMeshes) list.push_back({&m, true});
  gatherDisplacedList(list, rows, maxDepth, threads);
}

void gatherDisplacedList(std::span<const DisplacedRef> list, PrimitiveRows& rows, std::uint32_t maxDepth,
                         int threads) {
  rows.dataFirst[WT_PRIM_DISPLACED] = std::uint32_t(rows.data.size());
  rows.infoFirst[WT_PRIM_DISPLACED] = std::uint32_t(rows.info.size());
  const std::size_t meshes = list.size();
  rows.displacedTriangles.clear();
  // rows from the type's first: headers, then vertices (then the boxes, then the maps)
  std::vector<WtVec4> data(WT_DISP_MESH_ROWS * meshes, WtVec4{0, 0, 0, 0});
  std::vector<std::size_t> vertexRow(meshes, 0);
  for (std::size_t mi = 0; mi < meshes; ++mi) {
    const DisplacedMesh& m = *list[mi].mesh;
    if (!list[mi].drawn || !displacedMeshUsable(m)) continue;
    vertexRow[mi] = data.size();
    for (std::size_t v = 0; v < m.positions.size(); ++v) {
      const glm::vec3 p = m.positions[v], n = m.normals[v];
      const glm::vec2 uv = m.texcoords[v];
      data.push_back({p.x, p.y, p.z, uv.x});
      data.push_back({n.x, n.y, n.z, uv.y});
    }
  }
  // the base triangles' boxes follow the vertices, the maps' texels follow those
  std::vector<WtVec4> boxRows;
  std::vector<std::uint32_t> words;  // the maps, as 32-bit words (floats' bits, or four bytes)
  std::vector<std::size_t> texelWord(meshes, 0), paletteWord(meshes, ~std::size_t(0));
  std::uint32_t prims = 0;
  for (std::size_t mi = 0; mi < meshes; ++mi) {
    const DisplacedMesh& m = *list[mi].mesh;
    rows.displacedTriangles.push_back(prims);
    if (!list[mi].drawn) continue;
    if (!displacedMeshUsable(m)) {
      rows.skipped += m.triangles.size();
      continue;
    }
    const MapView map{m.map.data(), int(m.mapWidth), int(m.mapHeight)};
    const std::uint32_t level = displacedLevel(m), depth = storedDepth(maxDepth, level);
    // the pyramid bounds sub-triangles only below the stored depth (levels past WT_DISP_MAX_DEPTH + 1)
    std::vector<std::vector<float>> pyramid;
    if (level > depth + 1) pyramid = minMaxPyramid(map);
    WtVec4* header = &data[WT_DISP_MESH_ROWS * mi];
    header[0] = {m.scale, m.offset, float(m.mapWidth), float(m.mapHeight)};
    auto bits = [](std::uint32_t u) { return std::bit_cast<float>(u); };
    // z: the texels' first float, w: the palette's (below); ~0: float texels
    header[1] = {bits(level), bits(depth), 0.0f, bits(~0u)};
    // a map of at most 256 distinct values (an 8-bit image's) as bytes and a palette of the values' bits
    const std::size_t texels = std::size_t(m.mapWidth) * m.mapHeight;
    std::vector<std::uint32_t> texelBits(texels);
    for (std::size_t y = 0; y < m.mapHeight; ++y)
      for (std::size_t x = 0; x < m.mapWidth; ++x)
        texelBits[y * m.mapWidth + x] = std::bit_cast<std::uint32_t>(map.at(int(x), int(y)));
    const std::vector<std::uint32_t> palette = smallPalette(texelBits);
    if (!palette.empty()) {
      paletteWord[mi] = words.size();
      words.insert(words.end(), palette.begin(), palette.end());
      // bytes in 8 x 8 tiles (64 bytes, one cache line), rows of ceil(w / 8) tiles, as disp_texel reads them
      texelWord[mi] = words.size();
      const std::size_t tilesX = (m.mapWidth + 7) / 8, tilesY = (m.mapHeight + 7) / 8;
      std::vector<std::uint8_t> tiled(64 * tilesX * tilesY, 0);
      for (std::size_t y = 0; y < m.mapHeight; ++y)
        for (std::size_t x = 0; x < m.mapWidth; ++x)
          tiled[64 * ((y / 8) * tilesX + x / 8) + (y % 8) * 8 + x % 8] = std::uint8_t(
              std::lower_bound(palette.begin(), palette.end(), texelBits[y * m.mapWidth + x]) - palette.begin());
      for (std::size_t i = 0; i < tiled.size(); i += 4) {
        std::uint32_t packed;
        std::memcpy(&packed, tiled.data() + i, 4);
        words.push_back(packed);
      }
    } else {
      texelWord[mi] = words.size();
      words.insert(words.end(), texelBits.begin(), texelBits.end());
    }
    // the boxes a chunk of triangles at a time on every thread (each
    // triangle's alone: the same bytes on any number of threads), appended
    // in order; a chunk bounds what waits to be appended (32 KiB a triangle at D = 6)
    constexpr std::size_t kChunk = 1024;
    std::vector<TriangleBoxes> chunk;
    for (std::size_t ti = 0; ti < m.triangles.size(); ++ti) {
      const std::size_t first = ti - ti % kChunk;
      if (ti == first) {
        const std::size_t count = std::min(kChunk, m.triangles.size() - first);
        chunk.assign(count, TriangleBoxes{});
        std::atomic<std::size_t> next{0};
        bvh_detail::runTeam(int(std::min<std::size_t>(std::size_t(bvh_detail::resolveThreads(threads)), count)),
                            [&](int, int, bvh_detail::Barrier&) {
                              for (std::size_t k; (k = next.fetch_add(1, std::memory_order_relaxed)) < count;) {
                                const std::array<std::uint32_t, 3>& t = m.triangles[first + k];
                                if (cornersUsable(m, t))
                                  chunk[k] = triangleBoxes(m, map, pyramid.empty() ? nullptr : &pyramid, t, level, depth);
                                else
                                  chunk[k].finite = false;
                              }
                            });
      }
      const TriangleBoxes& boxes = chunk[ti - first];
      if (!boxes.finite) {
        ++rows.skipped;
        continue;
      }
      const std::array<std::uint32_t, 3>& t = m.triangles[ti];
      // the slab's direction one row before the boxes, which prim_info names
      if (level > 0) boxRows.push_back({boxes.slabNormal.x, boxes.slabNormal.y, boxes.slabNormal.z, 0.0f});
      const std::size_t boxRow = boxRows.size();  // from the boxes' first row, made absolute below
      if (level > 0) {
        boxRows.push_back({boxes.root.lo.x, boxes.root.lo.y, boxes.root.lo.z, boxes.slabLo});
        boxRows.push_back({boxes.root.hi.x, boxes.root.hi.y, boxes.root.hi.z, boxes.slabHi});
        for (std::size_t b = 0; b < boxes.blocks.size(); b += 16) {
          WtVec4 row{0, 0, 0, 0};
          std::memcpy(&row, boxes.blocks.data() + b, std::min<std::size_t>(16, boxes.blocks.size() - b));
          boxRows.push_back(row);
        }
      }
      // the micro-vertices' displacements, when computed above: the walk then reads the map nowhere
      std::uint32_t displacementRow = ~0u;
      if (!boxes.displacements.empty()) {
        displacementRow = std::uint32_t(boxRows.size());
        for (std::size_t v = 0; v < boxes.displacements.size(); v += 4) {
          WtVec4 row{0, 0, 0, 0};
          std::memcpy(&row, boxes.displacements.data() + v,
                      sizeof(float) * std::min<std::size_t>(4, boxes.displacements.size() - v));
          boxRows.push_back(row);
        }
      }
      rows.info.push_back({m.material, std::uint32_t(WT_DISP_MESH_ROWS * mi), std::uint32_t(boxRow), displacementRow});
      rows.info.push_back({std::uint32_t(vertexRow[mi] + WT_DISP_VERTEX_ROWS * t[0]),
                           std::uint32_t(vertexRow[mi] + WT_DISP_VERTEX_ROWS * t[1]),
                           std::uint32_t(vertexRow[mi] + WT_DISP_VERTEX_ROWS * t[2]), std::uint32_t(ti)});
      rows.bounds.push_back(boxes.root);
      rows.ids.push_back(primId(WT_PRIM_DISPLACED, prims++));
    }
  }
  rows.displacedTriangles.push_back(prims);
  rows.count[WT_PRIM_DISPLACED] = prims;
  // the offsets known now: boxes after the headers and vertices, texels after the boxes
  const std::size_t boxFirst = data.size(), floatBase = 4 * (data.size() + boxRows.size());
  for (std::size_t r = rows.infoFirst[WT_PRIM_DISPLACED]; r < rows.info.size(); r += WT_DISP_INFO_ROWS) {
    rows.info[r][2] += std::uint32_t(boxFirst);
    if (rows.info[r][3] != ~0u) rows.info[r][3] += std::uint32_t(boxFirst);
  }
  for (std::size_t mi = 0; mi < meshes; ++mi)
    if (list[mi].drawn && displacedMeshUsable(*list[mi].mesh)) {
      data[WT_DISP_MESH_ROWS * mi + 1].z = std::bit_cast<float>(std::uint32_t(floatBase + texelWord[mi]));
      if (paletteWord[mi] != ~std::size_t(0))
        data[WT_DISP_MESH_ROWS * mi + 1].w = std::bit_cast<float>(std::uint32_t(floatBase + paletteWord[mi]));
    }
  data.insert(data.end(), boxRows.begin(), boxRows.end());
  for (std::size_t i = 0; i < words.size(); i += 4) {
    std::uint32_t v[4] = {0, 0, 0, 0};
    for (std::size_t k = 0; k < 4 && i + k < words.size(); ++k) v[k] = words[i + k];
    WtVec4 row;
    std::memcpy(&row, v, sizeof(row));
    data.push_back(row);
  }
  rows.data.insert(rows.data.end(), data.begin(), data.end());
}

DisplacedTriangleRef displacedTriangle(const PrimitiveRows& rows, std::uint32_t index) {
  const std::size_t row = rows.infoFirst[WT_PRIM_DISPLACED] + WT_DISP_INFO_ROWS * std::size_t(index);
  return {rows.info[row][1] / WT_DISP_MESH_ROWS, rows.info[row + 1][3]};
}

double displacedBaseArea(const Scene& scene, const PrimitiveRows& rows, std::uint32_t index) {
  const DisplacedTriangleRef ref = displacedTriangle(rows, index);
  const DisplacedMesh& mesh = scene.displacedMeshes[ref.mesh];
  const std::array<std::uint32_t, 3>& t = mesh.triangles[ref.triangle];
  const glm::dvec3 p0(mesh.positions[t[0]]), p1(mesh.positions[t[1]]), p2(mesh.positions[t[2]]);
  return 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
}

glm::vec3 displacedPoint(const DisplacedMesh& mesh, std::uint32_t triangle, float li, float lj, glm::vec3* error,
                         glm::vec3* normal, glm::vec3* shading) {
  const MapView map{mesh.map.data(), int(mesh.mapWidth), int(mesh.mapHeight)};
  const std::array<std::uint32_t, 3>& t = mesh.triangles[triangle];
  const int n = 1 << displacedLevel(mesh);
  // the micro-triangle holding (li, lj), as disp_micro_at
  int i = int(std::clamp(std::floor(li), 0.0f, float(n - 1))), j = int(std::clamp(std::floor(lj), 0.0f, float(n - 1)));
  if (i + j > n - 1) i = n - 1 - j;
  const float x = li - float(i), y = lj - float(j);
  glm::ivec2 c[3];
  float b1, b2;
  bool inverted = false;
  if (x + y > 1.0f && i + j <= n - 2) {
    c[0] = {i + 1, j}, c[1] = {i, j + 1}, c[2] = {i + 1, j + 1};
    b1 = 1.0f - x;
    b2 = y - b1;
    inverted = true;
  } else {
    c[0] = {i, j}, c[1] = {i + 1, j}, c[2] = {i, j + 1};
    b1 = x;
    b2 = y;
  }
  glm::vec3 s[3];
  for (int k = 0; k < 3; ++k) s[k] = microVertex(mesh, map, t, n, c[k].x, c[k].y);
  const float b0 = 1.0f - b1 - b2;
  const glm::vec3 p = b0 * s[0] + b1 * s[1] + b2 * s[2];
  constexpr float kEps = 1.1920929e-7f;
  const float gamma7 = 7.0f * 0.5f * kEps / (1.0f - 7.0f * 0.5f * kEps), gamma2 = 2.0f * 0.5f * kEps / (1.0f - kEps);
  const glm::vec3 e1 = s[1] - s[0], e2 = s[2] - s[0];
  *error = gamma7 * (glm::abs(b0 * s[0]) + glm::abs(b1 * s[1]) + glm::abs(b2 * s[2])) + gamma2 * glm::abs(s[0]) +
           glm::vec3(4.0f * kEps * float(n) * (glm::length(e1) + glm::length(e2)));
  glm::vec3 g = glm::cross(e1, e2);
  const float len = glm::length(g);
  *normal = len > 0.0f && std::isfinite(len) ? (inverted ? -g : g) / len : glm::vec3(0.0f);
  if (shading) *shading = shadingNormal(mesh, map, t, li / float(n), lj / float(n));
  return p;
}

glm::vec3 displacedVertex(const DisplacedMesh& mesh, std::uint32_t triangle, int perEdge, int i, int j) {
  const MapView map{mesh.map.data(), int(mesh.mapWidth), int(mesh.mapHeight)};
  return microVertex(mesh, map, mesh.triangles[triangle], perEdge, i, j);
}

double displacedArea(const DisplacedMesh& mesh, std::uint32_t triangle) {
  const MapView map{mesh.map.data(), int(mesh.mapWidth), int(mesh.mapHeight)};
  const std::array<std::uint32_t, 3>& t = mesh.triangles[triangle];
  const int n = 1 << displacedLevel(mesh);
  // the lattice row by row, then its upright and inverted micro-triangles
  std::vector<glm::dvec3> grid;
  std::vector<std::size_t> rowStart(std::size_t(n) + 1);
  for (int j = 0; j <= n; ++j) {
    rowStart[std::size_t(j)] = grid.size();
    for (int i = 0; i + j <= n; ++i) grid.push_back(glm::dvec3(microVertex(mesh, map, t, n, i, j)));
  }
  auto at = [&](int i, int j) { return grid[rowStart[std::size_t(j)] + std::size_t(i)]; };
  auto area = [](glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) { return 0.5 * glm::length(glm::cross(b - a, c - a)); };
  double sum = 0.0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i + j < n; ++i) {
      sum += area(at(i, j), at(i + 1, j), at(i, j + 1));
      if (i + j + 2 <= n) sum += area(at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
    }
  return sum;
}

std::size_t tessellateDisplaced(Scene& scene, int perEdge) {
  const int n = std::max(perEdge, 1);
  std::size_t made = 0;
  std::uint32_t nextGeometry = 0;
  for (const GeometryInstance& g : scene.instances) nextGeometry = std::max(nextGeometry, g.geometry + 1);
  for (const DisplacedMesh& mesh : scene.displacedMeshes) {
    if (!displacedMeshUsable(mesh)) continue;
    const MapView map{mesh.map.data(), int(mesh.mapWidth), int(mesh.mapHeight)};
    const auto firstTriangle = std::uint32_t(scene.triangles.size());
    for (const auto& t : mesh.triangles) {
      if (!cornersUsable(mesh, t)) continue;
      // the lattice's vertices, row by row (j), then its upright and inverted triangles
      const auto base = std::uint32_t(scene.positions.size());
      std::vector<std::uint32_t> rowStart(std::size_t(n) + 2);
      std::uint32_t count = 0;
      for (int j = 0; j <= n; ++j) {
        rowStart[std::size_t(j)] = count;
        for (int i = 0; i + j <= n; ++i, ++count) {
          glm::vec2 uv;
          const glm::vec3 p = microVertex(mesh, map, t, n, i, j, nullptr, &uv);
          const glm::vec3 sn = shadingNormal(mesh, map, t, float(i) / float(n), float(j) / float(n));
          scene.positions.push_back({p.x, p.y, p.z, 0.0f});
          scene.normals.push_back({sn.x, sn.y, sn.z, 0.0f});
          scene.texcoords.push_back(uv);
        }
      }
      auto at = [&](int i, int j) { return base + rowStart[std::size_t(j)] + std::uint32_t(i); };
      for (int j = 0; j < n; ++j)
        for (int i = 0; i + j < n; ++i) {
          scene.triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1), mesh.material});
          if (i + j + 2 <= n) scene.triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), mesh.material});
        }
    }
    const auto added = std::uint32_t(scene.triangles.size()) - firstTriangle;
    made += added;
    if (!scene.instances.empty() && added > 0) scene.instances.push_back({firstTriangle, added, nextGeometry++, glm::dmat4(1.0)});
  }
  // the attributes only some vertices have: every vertex gets one once any does
  if (!scene.texcoords1.empty()) scene.texcoords1.resize(scene.positions.size(), glm::vec2(0.0f));
  if (!scene.colors.empty()) scene.colors.resize(scene.positions.size(), glm::vec4(1.0f));
  if (!scene.tangents.empty()) scene.tangents.resize(scene.positions.size(), glm::vec4(0.0f));
  scene.displacedMeshes.clear();
  return made;
}

}  // namespace wt
