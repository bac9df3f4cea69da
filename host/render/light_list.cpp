#include "render/light_list.h"

#include "render/light_tree.h"

#include <cmath>
#include <numbers>

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

double environmentPowerEstimate(const Scene& scene, double meanLuminance) {
  Aabb box = scene.bounds();
  double r = box.empty() ? 1.0 : 0.5 * glm::length(box.extent());
  // irradiance pi*L through the bounding sphere's cross-section
  return std::numbers::pi * r * r * std::numbers::pi * meanLuminance;
}

LightList buildLightList(const Scene& scene, const SceneBuffers& buffers, double environmentPower,
                         LightSampler sampler) {
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

  // emissive triangles, in leaf order (as the kernels index them)
  const std::vector<std::uint32_t>& order = buffers.leafOrder();
  std::vector<std::uint32_t> lightOfLeaf(order.size(), ~0u);
  std::vector<double> areas;
  for (std::size_t leaf = 0; leaf < order.size(); ++leaf) {
    // padding before an instanced geometry; its triangles never emit (SceneBuffers)
    if (order[leaf] == SceneBuffers::kNoTriangle || buffers.triangleInstance(order[leaf]) != SceneBuffers::kNoTriangle)
      continue;
    const WtTriangle& t = scene.triangles[order[leaf]];
    const WtVec4& e = scene.materials[t.material].emission;
    glm::vec3 le(e.x, e.y, e.z);
    if (!(luminance(le) > 0.0)) continue;
    auto pos = [&](std::uint32_t v) { return glm::dvec3(scene.positions[v].x, scene.positions[v].y, scene.positions[v].z); };
    double area = 0.5 * glm::length(glm::cross(pos(t.v1) - pos(t.v0), pos(t.v2) - pos(t.v0)));
    if (!(area > 0.0)) continue;
    WtLight l{};
    l.type = WT_LIGHT_TRIANGLE;
    l.triangle = std::uint32_t(leaf);
    l.intensity = {le.x, le.y, le.z, 0.0f};
    const bool twoSided = e.w != 0.0f;
    l.position.w = twoSided ? 1.0f : 0.0f;
    lightOfLeaf[leaf] = std::uint32_t(list.lights.size());
    // pi * L * area from each emitting face
    power.push_back((twoSided ? 2.0 : 1.0) * std::numbers::pi * area * luminance(le));
    areas.push_back(area);
    list.lights.push_back(l);
  }
  list.emissiveTriangles = areas.size();
  const bool useTree = sampler == LightSampler::Tree ||
                       (sampler == LightSampler::Auto && list.emissiveTriangles >= kLightTreeMinEmitters);
  list.emitterLeaf.assign(order.size(), WT_LIGHT_NODE_NONE);

  // With the tree, the triangles move behind one WT_LIGHT_TREE entry of
  // their total power; the table picks among the entries before them.
  std::uint32_t treeEntry = ~0u;
  std::vector<WtLight> triangleLights;
  if (useTree && list.emissiveTriangles > 0) {
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
      auto pos = [&](std::uint32_t v) { return glm::vec3(scene.positions[v].x, scene.positions[v].y, scene.positions[v].z); };
      emitters[k] = {pos(t.v0), pos(t.v1), pos(t.v2), trianglePower[k], triangleLights[k].position.w != 0.0f,
                     std::uint32_t(k)};
    }
    LightTree tree = buildLightTree(emitters);
    list.tree = std::move(tree.nodes);
    for (std::size_t k = 0; k < triangleLights.size(); ++k)
      list.emitterLeaf[triangleLights[k].triangle] = tree.leafOfEmitter[k];
  }

  // emissive spheres, one entry each (the tree holds triangles only)
  const WtGeometry& geometry = buffers.geometry;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> sphereLights;  // emitter slot, light index
  for (std::size_t i = 0; i < scene.spheres.size(); ++i) {
    const Sphere& sphere = scene.spheres[i];
    const WtVec4& e = scene.materials[sphere.material].emission;
    glm::vec3 le(e.x, e.y, e.z);
    const double area = 4.0 * std::numbers::pi * double(sphere.radius) * double(sphere.radius);
    if (!(luminance(le) > 0.0) || !sphereUsable(sphere) || !std::isfinite(area)) continue;
    WtLight l{};
    l.type = WT_LIGHT_PRIMITIVE;
    l.triangle = primId(WT_PRIM_SPHERE, std::uint32_t(i));
    l.position = {sphere.center.x, sphere.center.y, sphere.center.z, sphere.radius};
    l.intensity = {le.x, le.y, le.z, 0.0f};
    sphereLights.push_back({geometry.emitter_first[WT_PRIM_SPHERE] + std::uint32_t(i),
                            std::uint32_t(list.lights.size())});
    power.push_back(std::numbers::pi * area * luminance(le));  // pi * L * area, from the outside
    list.lights.push_back(l);
  }
  list.emissivePrimitives = sphereLights.size();

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
  if (treeEntry != ~0u) {
    const std::uint32_t base = std::uint32_t(list.lights.size());
    list.lights.insert(list.lights.end(), triangleLights.begin(), triangleLights.end());
    for (WtLightNode& n : list.tree)
      if (n.leaf) n.child += base;
  }

  list.alias = buildAliasTable(power);
  std::size_t emitterSlots = order.size();
  for (std::uint32_t type = 0; type < WT_PRIM_TYPES; ++type)
    if (type != WT_PRIM_TRIANGLE) emitterSlots += buffers.primitiveCount(type);
  list.emitterPdfArea.assign(emitterSlots, 0.0f);
  double total = 0.0;
  for (double p : power) total += p;
  list.sampleable = total > 0.0;
  if (list.sampleable) {
    std::size_t k = 0;
    for (std::size_t leaf = 0; leaf < order.size(); ++leaf)
      if (lightOfLeaf[leaf] != ~0u) {
        // the tree entry's probability, to be multiplied by the tree's choice on the device
        float pick = treeEntry != ~0u ? list.alias[treeEntry].pmf : list.alias[lightOfLeaf[leaf]].pmf;
        list.emitterPdfArea[leaf] = float(pick / areas[k++]);
      }
    // the other types' entries hold their selection probability alone
    for (auto [slot, light] : sphereLights) list.emitterPdfArea[slot] = list.alias[light].pmf;
    if (envIndex != ~0u) list.environmentPmf = list.alias[envIndex].pmf;
  }
  return list;
}

}  // namespace wt
