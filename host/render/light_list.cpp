#include "render/light_list.h"

#include "bvh/parallel.h"
#include "render/light_tree.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <numbers>
#include <tuple>

namespace wt {

double luminance(glm::vec3 c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

std::vector<WtAliasSlot> buildAliasTable(std::span<const double> weights) {
  const std::size_t n = weights.size();
  std::vector<WtAliasSlot> table(n);
  double sum = 0.0;
  for (double w : weights) sum += w;
  if (n == 0 || !(sum > 0.0)) return table;
  // Vose: split scaled weights into under- and over-full slots and pair them.
  std::vector<double> scaled(n);
  std::vector<std::uint32_t> small, large;
  for (std::size_t i = 0; i < n; ++i) {
    table[i].pmf = float(weights[i] / sum);
    table[i].alias = std::uint32_t(i);
    scaled[i] = weights[i] / sum * double(n);
    (scaled[i] < 1.0 ? small : large).push_back(std::uint32_t(i));
  }
  while (!small.empty() && !large.empty()) {
    std::uint32_t s = small.back(), l = large.back();
    small.pop_back();
    table[s].threshold = float(scaled[s]);
    table[s].alias = l;
    scaled[l] -= 1.0 - scaled[s];
    if (scaled[l] < 1.0) {
      large.pop_back();
      small.push_back(l);
    }
  }
  // what is left is full up to rounding
  for (std::uint32_t i : small) table[i].threshold = 1.0f, table[i].alias = i;
  for (std::uint32_t i : large) table[i].threshold = 1.0f, table[i].alias = i;
  return table;
}

namespace {

/// The texel of `texture` nearest to uv at `level`, linear RGB and alpha (host
/// twin of kernels/materials/texture.cl for the light list's estimates).
glm::dvec4 texelAt(const TextureSet& set, const WtTexture& texture, std::uint32_t level, glm::dvec2 uv) {
  const WtTextureLevel& l = set.levels[texture.first_level + std::min(level, texture.level_count - 1)];
  auto wrap = [](double x, std::uint32_t size, std::uint32_t mode) {
    double t = x * double(size);
    if (!std::isfinite(t)) t = 0.0;
    long long i = (long long)std::floor(t), n = size;
    if (mode == WT_WRAP_CLAMP) return std::uint32_t(std::clamp(i, 0ll, n - 1));
    if (mode == WT_WRAP_MIRROR) {
      long long m = ((i % (2 * n)) + 2 * n) % (2 * n);
      return std::uint32_t(m < n ? m : 2 * n - 1 - m);
    }
    return std::uint32_t(((i % n) + n) % n);
  };
  const std::uint32_t x = wrap(uv.x, l.width, WT_TEXTURE_WRAP_S(texture.flags));
  const std::uint32_t y = wrap(uv.y, l.height, WT_TEXTURE_WRAP_T(texture.flags));
  const std::size_t index = std::size_t(y) * l.width + x;
  glm::dvec4 c;
  if (texture.flags & WT_TEXTURE_16BIT) {
    const wt_uint a = set.texels[l.offset + 2 * index], b = set.texels[l.offset + 2 * index + 1];
    c = glm::dvec4(a & 0xffffu, a >> 16, b & 0xffffu, b >> 16) / 65535.0;
  } else {
    const wt_uint a = set.texels[l.offset + index];
    c = glm::dvec4(a & 0xffu, (a >> 8) & 0xffu, (a >> 16) & 0xffu, a >> 24) / 255.0;
  }
  if (texture.flags & WT_TEXTURE_SRGB) c = glm::dvec4(srgbToLinear(c.x), srgbToLinear(c.y), srgbToLinear(c.z), c.w);
  return c;
}

/// Texture coordinates of vertex v as texture slot `ref` reads them (its set and transform).
glm::dvec2 slotUv(const Scene& scene, const WtTextureRef& ref, std::uint32_t v) {
  glm::dvec2 st = ref.texcoord == 1 ? (v < scene.texcoords1.size() ? glm::dvec2(scene.texcoords1[v]) : glm::dvec2(0.0))
                                    : (v < scene.texcoords.size() ? glm::dvec2(scene.texcoords[v]) : glm::dvec2(0.0));
  return glm::dvec2(ref.transform_u.x * st.x + ref.transform_u.y * st.y + ref.transform_u.z,
                    ref.transform_v.x * st.x + ref.transform_v.y * st.y + ref.transform_v.z);
}

/// Barycentrics (b1, b2) of stratum (i, j) of a side x side grid over the unit
/// square mapped onto the triangle (square-root map, area-preserving).
glm::dvec2 stratumBarycentrics(int i, int j, int side) {
  const double su = std::sqrt((i + 0.5) / side), v = (j + 0.5) / side;
  return {su * (1.0 - v), su * v};
}

/// The pyramid level whose texels each cover about 1/samples of the uv
/// triangle (a, b, c) on `texture`'s base level.
double levelForSamples(const TextureSet& set, const WtTexture& texture, glm::dvec2 a, glm::dvec2 b, glm::dvec2 c,
                       int samples) {
  const WtTextureLevel& base = set.levels[texture.first_level];
  const double texels = 0.5 * std::fabs((b - a).x * (c - a).y - (b - a).y * (c - a).x) * double(base.width) * base.height;
  return texels > samples ? 0.5 * std::log2(texels / samples) : 0.0;
}

}  // namespace

glm::dvec3 averageEmissiveTexture(const Scene& scene, const WtTriangle& t) {
  const WtMaterial& m = scene.materials[t.material];
  if (!(m.texture_mask & (1u << WT_TEXTURE_SLOT_EMISSIVE))) return glm::dvec3(1.0);
  const WtTextureRef& ref = scene.materialTextures[std::size_t(t.material) * WT_TEXTURE_SLOTS + WT_TEXTURE_SLOT_EMISSIVE];
  const WtTexture& texture = scene.textures.textures[ref.texture];
  const glm::dvec2 a = slotUv(scene, ref, t.v0), b = slotUv(scene, ref, t.v1), c = slotUv(scene, ref, t.v2);
  // the level whose texels are about as large as a sample's share of the
  // triangle, so that kSide^2 nearest texels of the box-filtered pyramid average it
  constexpr int kSide = 4;
  const double level = levelForSamples(scene.textures, texture, a, b, c, kSide * kSide);
  glm::dvec3 sum(0.0);
  for (int i = 0; i < kSide; ++i)
    for (int j = 0; j < kSide; ++j) {
      const glm::dvec2 w = stratumBarycentrics(i, j, kSide);
      sum += glm::dvec3(texelAt(scene.textures, texture, std::uint32_t(std::lround(level)),
                                (1.0 - w.x - w.y) * a + w.x * b + w.y * c));
    }
  return sum / double(kSide * kSide);
}

double meanCoverage(const Scene& scene, const WtTriangle& t) {
  const WtMaterial& m = scene.materials[t.material];
  if (m.alpha_mode != WT_ALPHA_MASK && m.alpha_mode != WT_ALPHA_BLEND) return 1.0;
  const bool textured = m.texture_mask & (1u << WT_TEXTURE_SLOT_BASE_COLOR);
  const bool colored = !scene.colors.empty();
  if (!textured && !colored) {  // the same coverage everywhere: the alpha factor
    const double alpha = m.alpha;
    return m.alpha_mode == WT_ALPHA_MASK ? (alpha >= m.alpha_cutoff ? 1.0 : 0.0) : std::clamp(alpha, 0.0, 1.0);
  }
  const WtTextureRef* ref =
      textured ? &scene.materialTextures[std::size_t(t.material) * WT_TEXTURE_SLOTS + WT_TEXTURE_SLOT_BASE_COLOR] : nullptr;
  const WtTexture* texture = textured ? &scene.textures.textures[ref->texture] : nullptr;
  glm::dvec2 a(0.0), b(0.0), c(0.0);
  if (textured) a = slotUv(scene, *ref, t.v0), b = slotUv(scene, *ref, t.v1), c = slotUv(scene, *ref, t.v2);
  constexpr int kSide = 8;
  // BLEND averages alpha, so a box-filtered level whose texels are a sample's
  // share of the triangle averages it well; MASK thresholds each point as
  // traversal does, at the finest level (a filtered level's alpha would cross
  // the cutoff elsewhere)
  const std::uint32_t level =
      textured && m.alpha_mode == WT_ALPHA_BLEND
          ? std::uint32_t(std::lround(levelForSamples(scene.textures, *texture, a, b, c, kSide * kSide)))
          : 0u;
  auto vertexAlpha = [&](std::uint32_t v) { return v < scene.colors.size() ? double(scene.colors[v].w) : 1.0; };
  double sum = 0.0;
  for (int i = 0; i < kSide; ++i)
    for (int j = 0; j < kSide; ++j) {
      const glm::dvec2 w = stratumBarycentrics(i, j, kSide);
      const double w0 = 1.0 - w.x - w.y;
      double alpha = m.alpha;
      if (colored) alpha *= w0 * vertexAlpha(t.v0) + w.x * vertexAlpha(t.v1) + w.y * vertexAlpha(t.v2);
      if (textured) alpha *= texelAt(scene.textures, *texture, level, w0 * a + w.x * b + w.y * c).w;
      sum += m.alpha_mode == WT_ALPHA_MASK ? (alpha >= m.alpha_cutoff ? 1.0 : 0.0) : std::clamp(alpha, 0.0, 1.0);
    }
  return sum / double(kSide * kSide);
}

std::vector<QuadLight> findQuadLights(const Scene& scene, const SceneBuffers& buffers) {
  // each candidate half: its right-angle corner and the diagonal opposite it, keyed by material and the diagonal's ends
  struct Half {
    std::uint32_t material;
    std::array<float, 3> lo, hi;  ///< the diagonal's ends, ordered
    std::uint32_t leaf, corner;
  };
  std::vector<Half> halves;
  const std::vector<std::uint32_t>& order = buffers.leafOrder();
  auto pos = [&](std::uint32_t v) { return glm::dvec3(scene.positions[v].x, scene.positions[v].y, scene.positions[v].z); };
  for (std::size_t leaf = 0; leaf < order.size(); ++leaf) {
    if (order[leaf] == SceneBuffers::kNoTriangle || buffers.triangleInstance(order[leaf]) != SceneBuffers::kNoTriangle)
      continue;
    const WtTriangle& t = scene.triangles[order[leaf]];
    const WtMaterial& m = scene.materials[t.material];
    if (!(luminance(glm::vec3(m.emission.x, m.emission.y, m.emission.z)) > 0.0) ||
        (m.texture_mask & (1u << WT_TEXTURE_SLOT_EMISSIVE)) || m.alpha_mode == WT_ALPHA_MASK || m.alpha_mode == WT_ALPHA_BLEND)
      continue;
    const std::array<std::uint32_t, 3> v = {t.v0, t.v1, t.v2};
    for (std::uint32_t k = 0; k < 3; ++k) {
      const glm::dvec3 c = pos(v[k]), e1 = pos(v[(k + 1) % 3]) - c, e2 = pos(v[(k + 2) % 3]) - c;
      const double l1 = glm::length(e1), l2 = glm::length(e2);
      if (!(l1 > 0.0 && l2 > 0.0 && std::isfinite(l1 * l2)) || !(std::fabs(glm::dot(e1, e2)) <= kQuadTolerance * l1 * l2))
        continue;
      auto key = [&](std::uint32_t w) {
        return std::array<float, 3>{scene.positions[w].x, scene.positions[w].y, scene.positions[w].z};
      };
      std::array<float, 3> a = key(v[(k + 1) % 3]), b = key(v[(k + 2) % 3]);
      if (b < a) std::swap(a, b);
      halves.push_back({t.material, a, b, std::uint32_t(leaf), k});
      break;  // at most one right angle
    }
  }
  auto sameKey = [](const Half& x, const Half& y) { return x.material == y.material && x.lo == y.lo && x.hi == y.hi; };
  std::sort(halves.begin(), halves.end(), [](const Half& x, const Half& y) {
    return std::tie(x.material, x.lo, x.hi, x.leaf) < std::tie(y.material, y.lo, y.hi, y.leaf);
  });
  std::vector<QuadLight> quads;
  std::vector<bool> used(halves.size(), false);
  for (std::size_t i = 0; i < halves.size(); ++i) {
    if (used[i]) continue;
    const WtTriangle& ti = scene.triangles[order[halves[i].leaf]];
    const std::array<std::uint32_t, 3> vi = {ti.v0, ti.v1, ti.v2};
    const glm::dvec3 c = pos(vi[halves[i].corner]), a = pos(vi[(halves[i].corner + 1) % 3]),
                     b = pos(vi[(halves[i].corner + 2) % 3]);
    const glm::dvec3 normal = glm::cross(a - c, b - c);
    for (std::size_t j = i + 1; j < halves.size() && sameKey(halves[i], halves[j]); ++j) {
      if (used[j]) continue;
      const WtTriangle& tj = scene.triangles[order[halves[j].leaf]];
      const std::array<std::uint32_t, 3> vj = {tj.v0, tj.v1, tj.v2};
      const glm::dvec3 d = pos(vj[halves[j].corner]);
      const glm::dvec3 nj = glm::cross(pos(vj[(halves[j].corner + 1) % 3]) - d, pos(vj[(halves[j].corner + 2) % 3]) - d);
      // the far corner where the first half's edges put it, and both windings facing the same way
      if (!(glm::length(d - (a + b - c)) <= kQuadTolerance * glm::length(a - b)) || !(glm::dot(normal, nj) > 0.0)) continue;
      used[i] = used[j] = true;
      quads.push_back({halves[i].leaf, halves[i].corner, halves[j].leaf});
      break;
    }
  }
  std::sort(quads.begin(), quads.end(), [](const QuadLight& x, const QuadLight& y) { return x.first < y.first; });
  return quads;
}

double environmentPowerEstimate(const Scene& scene, double meanLuminance) {
  Aabb box = scene.bounds();
  double r = box.empty() ? 1.0 : 0.5 * glm::length(box.extent());
  // irradiance pi*L through the bounding sphere's cross-section
  return std::numbers::pi * r * r * std::numbers::pi * meanLuminance;
}

LightList buildLightList(const Scene& scene, const SceneBuffers& buffers, double environmentPower,
                         LightSampler sampler, bool coverageWeights, bool quadLights) {
  LightList list;
  std::vector<double> power;
  Aabb box = scene.bounds();
  const double radius = box.empty() ? 1.0 : 0.5 * glm::length(box.extent());

  // analytic lights
  for (const PunctualLight& src : scene.lights) {
    WtLight l{};
    l.type = std::uint32_t(src.type);
    l.position = {src.position.x, src.position.y, src.position.z, 0.0f};
    l.direction = {src.direction.x, src.direction.y, src.direction.z, 0.0f};
    l.intensity = {src.intensity.x, src.intensity.y, src.intensity.z, 0.0f};
    l.cos_inner = std::cos(src.innerConeAngle);
    l.cos_outer = std::cos(src.outerConeAngle);
    double lum = luminance(src.intensity);
    if (src.type == WT_LIGHT_POINT)
      power.push_back(4.0 * std::numbers::pi * lum);
    else if (src.type == WT_LIGHT_SPOT)
      power.push_back(2.0 * std::numbers::pi * (1.0 - 0.5 * (l.cos_inner + l.cos_outer)) * lum);
    else
      power.push_back(std::numbers::pi * radius * radius * lum);
    list.lights.push_back(l);
  }
  list.analyticCount = std::uint32_t(list.lights.size());

  // emissive triangles, in leaf order (as the kernels index them); a
  // rectangle's two halves are one light, where its first half comes
  const std::vector<std::uint32_t>& order = buffers.leafOrder();
  std::vector<std::uint32_t> lightOfLeaf(order.size(), ~0u);
  std::vector<double> lightArea(list.lights.size(), 0.0);  ///< per light so far: a triangle's or rectangle's area
  std::vector<std::uint32_t> otherHalf(list.lights.size(), ~0u);  ///< per light: a rectangle's second half
  std::vector<std::uint32_t> quadCorner(list.lights.size(), ~0u);  ///< per light: a rectangle's right-angle corner
  std::vector<QuadLight> quads = quadLights ? findQuadLights(scene, buffers) : std::vector<QuadLight>{};
  std::vector<std::uint32_t> quadOfLeaf(order.size(), ~0u);
  for (std::size_t q = 0; q < quads.size(); ++q) quadOfLeaf[quads[q].first] = quadOfLeaf[quads[q].second] = std::uint32_t(q);
  auto pos = [&](std::uint32_t v) { return glm::dvec3(scene.positions[v].x, scene.positions[v].y, scene.positions[v].z); };
  for (std::size_t leaf = 0; leaf < order.size(); ++leaf) {
    if (quadOfLeaf[leaf] != ~0u) {
      const QuadLight& quad = quads[quadOfLeaf[leaf]];
      if (leaf != quad.first) continue;  // its light came with the first half
      const WtTriangle& t = scene.triangles[order[leaf]];
      const std::array<std::uint32_t, 3> v = {t.v0, t.v1, t.v2};
      const glm::dvec3 c = pos(v[quad.corner]);
      const double area = glm::length(glm::cross(pos(v[(quad.corner + 1) % 3]) - c, pos(v[(quad.corner + 2) % 3]) - c));
      const WtVec4& e = scene.materials[t.material].emission;
      const glm::vec3 le(e.x, e.y, e.z);
      WtLight l{};
      l.type = WT_LIGHT_QUAD;
      l.triangle = std::uint32_t(leaf);
      l.intensity = {le.x, le.y, le.z, 0.0f};
      const bool twoSided = e.w != 0.0f;
      // the corner and edges in float as the kernels' triangle_corners reads them (e1 = p1 - c in float)
      auto corner = [&](std::uint32_t k) {
        const auto& q = scene.positions[v[(quad.corner + k) % 3]];
        return glm::vec3(q.x, q.y, q.z);
      };
      const glm::vec3 cf = corner(0), e1 = corner(1) - cf, e2 = corner(2) - cf;
      l.position = {cf.x, cf.y, cf.z, twoSided ? 1.0f : 0.0f};
      l.direction = {e1.x, e1.y, e1.z, std::bit_cast<float>(quad.second)};
      l.intensity.w = e2.x;
      l.cos_inner = e2.y;
      l.cos_outer = e2.z;
      lightOfLeaf[quad.first] = lightOfLeaf[quad.second] = std::uint32_t(list.lights.size());
      power.push_back((twoSided ? 2.0 : 1.0) * std::numbers::pi * area * luminance(le));
      lightArea.push_back(area);
      otherHalf.push_back(quad.second);
      quadCorner.push_back(quad.corner);
      list.lights.push_back(l);
      list.emissiveTriangles += 2;
      ++list.quadLights;
      continue;
    }
    // padding before an instanced geometry; its triangles never emit (SceneBuffers)
    if (order[leaf] == SceneBuffers::kNoTriangle || buffers.triangleInstance(order[leaf]) != SceneBuffers::kNoTriangle)
      continue;
    const WtTriangle& t = scene.triangles[order[leaf]];
    const WtVec4& e = scene.materials[t.material].emission;
    glm::vec3 le(e.x, e.y, e.z);
    if (!(luminance(le) > 0.0)) continue;
    // a textured emitter's power by its texture's average over the triangle
    // (none: BSDF sampling alone finds what little it emits)
    const bool textured = scene.materials[t.material].texture_mask & (1u << WT_TEXTURE_SLOT_EMISSIVE);
    const glm::vec3 average = textured ? glm::vec3(averageEmissiveTexture(scene, t)) * le : le;
    if (!(luminance(average) > 0.0)) continue;
    double area = 0.5 * glm::length(glm::cross(pos(t.v1) - pos(t.v0), pos(t.v2) - pos(t.v0)));
    if (!(area > 0.0)) continue;
    WtLight l{};
    l.type = WT_LIGHT_TRIANGLE;
    l.triangle = std::uint32_t(leaf);
    l.intensity = {le.x, le.y, le.z, 0.0f};
    const bool twoSided = e.w != 0.0f;
    l.position.w = twoSided ? 1.0f : 0.0f;
    l.position.y = textured ? 1.0f : 0.0f;
    // an emitter with holes emits only where it is there (lights/light_sampling.cl)
    const WtMaterial& m = scene.materials[t.material];
    if (m.alpha_mode == WT_ALPHA_MASK || m.alpha_mode == WT_ALPHA_BLEND) {
      const bool alphaTexture = m.texture_mask & (1u << WT_TEXTURE_SLOT_BASE_COLOR);
      l.direction = {float(m.alpha_mode), m.alpha_cutoff, m.alpha, alphaTexture ? 1.0f : 0.0f};
    }
    lightOfLeaf[leaf] = std::uint32_t(list.lights.size());
    // pi * L * area from each emitting face, times the share of it that is there
    // floored: 64 points may miss what little is there, and NEE must still reach it (unbiased)
    const double coverage = coverageWeights ? std::max(meanCoverage(scene, t), kMinCoverageWeight) : 1.0;
    power.push_back((twoSided ? 2.0 : 1.0) * std::numbers::pi * area * luminance(average) * coverage);
    lightArea.push_back(area);
    otherHalf.push_back(~0u);
    quadCorner.push_back(~0u);
    list.lights.push_back(l);
    ++list.emissiveTriangles;
  }
  // the tree by emitters as NEE picks them: a rectangle is one
  const std::size_t emitterCount = list.lights.size() - list.analyticCount;
  const bool useTree = sampler == LightSampler::Tree ||
                       (sampler == LightSampler::Auto && emitterCount >= kLightTreeMinEmitters);
  list.emitterLeaf.assign(order.size(), WT_LIGHT_NODE_NONE);
  list.emitterQuad.assign(order.size(), WT_NO_QUAD);

  // With the tree, the triangles move behind one WT_LIGHT_TREE entry of
  // their total power; the table picks among the entries before them.
  std::uint32_t treeEntry = ~0u;
  std::vector<WtLight> triangleLights;
  if (useTree && emitterCount > 0) {
    const std::size_t first = list.analyticCount;
    triangleLights.assign(list.lights.begin() + std::ptrdiff_t(first), list.lights.end());
    std::vector<double> trianglePower(power.begin() + std::ptrdiff_t(first), power.end());
    list.lights.resize(first);
    power.resize(first);
    double sum = 0.0;
    for (double p : trianglePower) sum += p;
    WtLight entry{};
    entry.type = WT_LIGHT_TREE;
    treeEntry = std::uint32_t(list.lights.size());
    list.lights.push_back(entry);
    power.push_back(sum);
    // the emitters as the tree sees them; light indices are fixed below
    std::vector<LightTreeEmitter> emitters(triangleLights.size());
    for (std::size_t k = 0; k < triangleLights.size(); ++k) {
      const WtTriangle& t = scene.triangles[order[triangleLights[k].triangle]];
      auto corner = [&](std::uint32_t v) { return glm::vec3(scene.positions[v].x, scene.positions[v].y, scene.positions[v].z); };
      emitters[k] = {corner(t.v0), corner(t.v1), corner(t.v2), trianglePower[k], triangleLights[k].position.w != 0.0f,
                     std::uint32_t(k)};
      // a rectangle's fourth corner: its first half's two diagonal ends less its right-angle corner
      if (triangleLights[k].type == WT_LIGHT_QUAD) {
        const std::array<glm::vec3, 3> p = {emitters[k].p0, emitters[k].p1, emitters[k].p2};
        const std::uint32_t c = quadCorner[first + k];
        emitters[k].p3 = p[(c + 1) % 3] + p[(c + 2) % 3] - p[c];
        emitters[k].quad = true;
      }
    }
    LightTree tree = buildLightTree(emitters);
    list.tree = std::move(tree.nodes);
    for (std::size_t k = 0; k < triangleLights.size(); ++k) {
      list.emitterLeaf[triangleLights[k].triangle] = tree.leafOfEmitter[k];
      if (const std::uint32_t second = otherHalf[first + k]; second != ~0u) list.emitterLeaf[second] = tree.leafOfEmitter[k];
    }
  }

  // emissive spheres, displaced base triangles and SDF bricks, one entry
  // each (the tree holds triangles only)
  const WtGeometry& geometry = buffers.geometry;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> primitiveLights;  // emitter slot, light index
  auto addPrimitive = [&](std::uint32_t deviceId, glm::vec3 le, bool twoSided, double weight) {
    WtLight l{};
    l.type = WT_LIGHT_PRIMITIVE;
    l.triangle = deviceId;
    l.intensity = {le.x, le.y, le.z, 0.0f};
    l.direction.w = twoSided ? 1.0f : 0.0f;
    primitiveLights.push_back({geometry.emitter_first[primType(deviceId)] + primIndex(deviceId),
                               std::uint32_t(list.lights.size())});
    power.push_back(weight);
    list.lights.push_back(l);
    return &list.lights.back();
  };
  for (std::size_t i = 0; i < scene.spheres.size(); ++i) {
    const Sphere& sphere = scene.spheres[i];
    const WtVec4& e = scene.materials[sphere.material].emission;
    glm::vec3 le(e.x, e.y, e.z);
    const double area = 4.0 * std::numbers::pi * double(sphere.radius) * double(sphere.radius);
    if (!(luminance(le) > 0.0) || !sphereUsable(sphere) || !std::isfinite(area)) continue;
    // its id on the device (emitting spheres are never instanced, but instanced ones shift them);
    // pi * L * area, from the outside
    WtLight* l = addPrimitive(buffers.devicePrimitive(primId(WT_PRIM_SPHERE, std::uint32_t(i))).first, le, false,
                              std::numbers::pi * area * luminance(le));
    l->position = {sphere.center.x, sphere.center.y, sphere.center.z, sphere.radius};
  }
  // the displaced base triangles' areas first, on every thread: each from
  // its own micro-vertices alone, so the same values on any thread count
  const std::vector<SceneBuffers::SurfaceEmitter>& emitters = buffers.surfaceEmitters();
  std::vector<double> displacedAreas(emitters.size(), 0.0);
  std::atomic<std::size_t> nextEmitter{0};
  bvh_detail::runTeam(int(std::min<std::size_t>(std::size_t(bvh_detail::resolveThreads(0)), emitters.size())),
                      [&](int, int, bvh_detail::Barrier&) {
                        for (std::size_t k; (k = nextEmitter.fetch_add(1, std::memory_order_relaxed)) < emitters.size();)
                          if (primType(emitters[k].id) == WT_PRIM_DISPLACED)
                            displacedAreas[k] = displacedArea(scene.displacedMeshes[emitters[k].source], emitters[k].element);
                      });
  for (std::size_t k = 0; k < emitters.size(); ++k) {
    const SceneBuffers::SurfaceEmitter& s = emitters[k];
    const bool displaced = primType(s.id) == WT_PRIM_DISPLACED;
    const std::uint32_t material =
        displaced ? scene.displacedMeshes[s.source].material : scene.sdfGrids[s.source].material;
    const WtVec4& e = scene.materials[material].emission;
    const glm::vec3 le(e.x, e.y, e.z);
    // the displaced surface's own area; a brick's from its crossed cells, a
    // cell's mean face area each (a weight only: sampling stays unbiased)
    double area;
    if (displaced) {
      area = displacedAreas[k];
    } else {
      area = double(s.element) * sdfCellArea(scene.sdfGrids[s.source]);
    }
    const bool twoSided = e.w != 0.0f;
    if (!(luminance(le) > 0.0) || !(area > 0.0) || !std::isfinite(area)) continue;
    addPrimitive(s.id, le, twoSided, (twoSided ? 2.0 : 1.0) * std::numbers::pi * area * luminance(le));
  }
  list.emissivePrimitives = primitiveLights.size();

  // environment
  std::uint32_t envIndex = ~0u;
  if (environmentPower > 0.0) {
    WtLight l{};
    l.type = WT_LIGHT_ENVIRONMENT;
    envIndex = std::uint32_t(list.lights.size());
    power.push_back(environmentPower);
    list.lights.push_back(l);
  }
  // the tree's leaves point at the triangles, stored after the table's entries
  std::uint32_t treeBase = 0;
  if (treeEntry != ~0u) {
    treeBase = std::uint32_t(list.lights.size());
    list.lights.insert(list.lights.end(), triangleLights.begin(), triangleLights.end());
    for (WtLightNode& n : list.tree)
      if (n.leaf) n.child += treeBase;
  }
  // each rectangle's halves point at its light, where it ended up
  for (std::size_t leaf = 0; leaf < order.size(); ++leaf)
    if (quadOfLeaf[leaf] != ~0u)
      list.emitterQuad[leaf] = treeEntry != ~0u ? treeBase + (lightOfLeaf[leaf] - list.analyticCount) : lightOfLeaf[leaf];

  list.alias = buildAliasTable(power);
  std::size_t emitterSlots = order.size();
  for (std::uint32_t type = 0; type < WT_PRIM_TYPES; ++type)
    if (type != WT_PRIM_TRIANGLE) emitterSlots += buffers.primitiveCount(type);
  list.emitterPdfArea.assign(emitterSlots, 0.0f);
  double total = 0.0;
  for (double p : power) total += p;
  list.sampleable = total > 0.0;
  if (list.sampleable) {
    for (std::size_t leaf = 0; leaf < order.size(); ++leaf)
      if (lightOfLeaf[leaf] != ~0u) {
        // the tree entry's probability, to be multiplied by the tree's choice on the device
        float pick = treeEntry != ~0u ? list.alias[treeEntry].pmf : list.alias[lightOfLeaf[leaf]].pmf;
        list.emitterPdfArea[leaf] = float(pick / lightArea[lightOfLeaf[leaf]]);
      }
    // the other types' entries hold their selection probability alone
    for (auto [slot, light] : primitiveLights) list.emitterPdfArea[slot] = list.alias[light].pmf;
    if (envIndex != ~0u) list.environmentPmf = list.alias[envIndex].pmf;
  }
  return list;
}

void setLightFeatures(KernelFeatures& features, const LightList& lights) {
  features.lightTree = !lights.tree.empty();
  // the alias table's entries: the tree's triangles after them are reached through the tree
  const std::size_t picked = std::min(lights.alias.size(), lights.lights.size());
  features.otherLights = std::any_of(lights.lights.begin(), lights.lights.begin() + std::ptrdiff_t(picked),
                                     [](const WtLight& l) {
                                       return l.type != WT_LIGHT_TRIANGLE && l.type != WT_LIGHT_QUAD &&
                                              l.type != WT_LIGHT_TREE;
                                     });
}

}  // namespace wt
