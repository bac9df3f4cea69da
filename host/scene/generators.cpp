#include "scene/generators.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <stdexcept>
#include <cmath>
#include <map>
#include <random>
#include <utility>

namespace wt {
namespace {

WtVec4 toVec4(glm::vec3 v, float w = 0.0f) { return {v.x, v.y, v.z, w}; }

}  // namespace

WtMaterial makeMaterial(glm::vec3 albedo, glm::vec3 emission, bool twoSided) {
  WtMaterial m{};
  m.base_color = toVec4(albedo);
  m.emission = toVec4(emission, twoSided ? 1.0f : 0.0f);
  m.roughness = 1.0f;
  m.model = WT_MATERIAL_DIFFUSE;
  m.ior = 1.5f;
  m.volume = {0.0f, 0.0f, 0.0f, 0.0f};
  m.alpha = 1.0f;
  m.alpha_mode = WT_ALPHA_OPAQUE;
  m.alpha_cutoff = 0.5f;
  m.texture_mask = 0u;
  m.specular = {1.0f, 1.0f, 1.0f, 1.0f};
  m.sheen = {0.0f, 0.0f, 0.0f, 0.0f};
  m.clearcoat = 0.0f;
  m.clearcoat_roughness = 0.0f;
  m.anisotropy = m.anisotropy_rotation = 0.0f;
  m.iridescence = {0.0f, 1.3f, 100.0f, 400.0f};
  m.priority = 0u;
  m.dispersion = 0.0f;
  m.shadow_pass = m.pad1 = 0u;
  return m;
}

WtMaterial makePbrMaterial(glm::vec3 baseColor, float metallic, float roughness, glm::vec3 emission, bool twoSided) {
  WtMaterial m = makeMaterial(glm::clamp(baseColor, glm::vec3(0.0f), glm::vec3(1.0f)), emission, twoSided);
  m.base_color.w = std::clamp(metallic, 0.0f, 1.0f);
  m.roughness = std::clamp(roughness, 0.0f, 1.0f);
  m.model = WT_MATERIAL_PBR;
  return m;
}

bool isLambertian(const WtMaterial& m) {
  if (m.model == WT_MATERIAL_DIFFUSE) return true;
  return m.model == WT_MATERIAL_PBR && m.base_color.w == 0.0f && m.specular.w == 0.0f && m.transmission == 0.0f &&
         m.clearcoat == 0.0f && m.sheen.x == 0.0f && m.sheen.y == 0.0f && m.sheen.z == 0.0f && m.anisotropy == 0.0f &&
         m.iridescence.x == 0.0f;
}

WtMaterial kernelMaterial(const WtMaterial& m) {
  WtMaterial k = m;
  if (isLambertian(m)) k.model = WT_MATERIAL_DIFFUSE;
  return k;
}

WtMaterial withTransmission(WtMaterial m, float transmission, float ior, bool thinWalled, glm::vec3 absorption) {
  m.model = WT_MATERIAL_PBR;
  m.transmission = std::clamp(transmission, 0.0f, 1.0f);
  m.ior = std::clamp(ior, 1.0f, 10.0f);
  glm::vec3 sigma = glm::max(absorption, glm::vec3(0.0f));
  m.volume = toVec4(thinWalled ? glm::vec3(0.0f) : sigma, thinWalled ? 0.0f : 1.0f);
  return m;
}

WtMaterial withPriority(WtMaterial m, std::uint32_t priority) {
  m.priority = priority;
  return m;
}

WtMaterial withDispersion(WtMaterial m, float dispersion) {
  m.dispersion = std::clamp(dispersion, 0.0f, 1000.0f);
  return m;
}

WtMaterial withSpecular(WtMaterial m, float specular, glm::vec3 specularColor) {
  m.model = WT_MATERIAL_PBR;
  m.specular = toVec4(glm::max(specularColor, glm::vec3(0.0f)), std::clamp(specular, 0.0f, 1.0f));
  return m;
}

WtMaterial withClearcoat(WtMaterial m, float clearcoat, float roughness) {
  m.model = WT_MATERIAL_PBR;
  m.clearcoat = std::clamp(clearcoat, 0.0f, 1.0f);
  m.clearcoat_roughness = std::clamp(roughness, 0.0f, 1.0f);
  return m;
}

WtMaterial withSheen(WtMaterial m, glm::vec3 color, float roughness) {
  m.model = WT_MATERIAL_PBR;
  m.sheen = toVec4(glm::clamp(color, glm::vec3(0.0f), glm::vec3(1.0f)), std::clamp(roughness, 0.0f, 1.0f));
  return m;
}

WtMaterial withAnisotropy(WtMaterial m, float strength, float rotation) {
  m.model = WT_MATERIAL_PBR;
  m.anisotropy = std::clamp(strength, 0.0f, 1.0f);
  // one turn is no turn: keep the angle small for the device's cos and sin
  m.anisotropy_rotation = std::isfinite(rotation) ? std::remainder(rotation, 2.0f * float(M_PI)) : 0.0f;
  return m;
}

WtMaterial withIridescence(WtMaterial m, float factor, float ior, float thicknessMin, float thicknessMax) {
  m.model = WT_MATERIAL_PBR;
  m.iridescence.x = std::isfinite(factor) ? std::clamp(factor, 0.0f, 1.0f) : 0.0f;
  m.iridescence.y = ior;
  m.iridescence.z = std::max(thicknessMin, 0.0f);
  m.iridescence.w = std::max(thicknessMax, 0.0f);
  return m;
}

Scene makeIcosphere(int subdivisions, glm::vec3 center, float radius, const WtMaterial& material) {
  // unit icosahedron
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<glm::vec3> verts = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0},
                                  {0, -1, t}, {0, 1, t},  {0, -1, -t}, {0, 1, -t},
                                  {t, 0, -1}, {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (glm::vec3& v : verts) v = glm::normalize(v);
  std::vector<glm::uvec3> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                   {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                   {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                   {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  // subdivide, sharing each edge's midpoint so the mesh stays closed
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<unsigned, unsigned>, unsigned> midpoints;
    auto midpoint = [&](unsigned a, unsigned b) {
      auto key = std::minmax(a, b);
      auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      verts.push_back(glm::normalize(verts[a] + verts[b]));
      unsigned index = unsigned(verts.size() - 1);
      midpoints.emplace(key, index);
      return index;
    };
    std::vector<glm::uvec3> next;
    next.reserve(faces.size() * 4);
    for (const glm::uvec3& f : faces) {
      unsigned ab = midpoint(f.x, f.y), bc = midpoint(f.y, f.z), ca = midpoint(f.z, f.x);
      next.push_back({f.x, ab, ca});
      next.push_back({f.y, bc, ab});
      next.push_back({f.z, ca, bc});
      next.push_back({ab, bc, ca});
    }
    faces = std::move(next);
  }
  Scene scene;
  scene.sourceName = "icosphere";
  for (const glm::vec3& v : verts) {
    scene.positions.push_back(toVec4(center + radius * v));
    scene.normals.push_back(toVec4(v));
    scene.texcoords.emplace_back(0.0f);
  }
  for (const glm::uvec3& f : faces) scene.triangles.push_back({f.x, f.y, f.z, 0});
  scene.materials.push_back(material);
  scene.materialNames.push_back("icosphere");
  return scene;
}

Scene makeDisplacedSphere(int subdivisions, glm::vec3 center, float radius, std::uint32_t mapSize, float scale,
                          float offset, int level, const WtMaterial& material) {
  const Scene base = makeIcosphere(subdivisions, center, radius, material);
  Scene scene;
  scene.sourceName = "displaced icosphere";
  DisplacedMesh mesh;
  for (std::size_t i = 0; i < base.positions.size(); ++i) {
    const WtVec4 p = base.positions[i], n = base.normals[i];
    mesh.positions.emplace_back(p.x, p.y, p.z);
    mesh.normals.emplace_back(n.x, n.y, n.z);
    mesh.texcoords.emplace_back(0.5f + 0.5f * n.x, 0.5f + 0.5f * n.y);
  }
  for (const WtTriangle& t : base.triangles) mesh.triangles.push_back({t.v0, t.v1, t.v2});
  const std::uint32_t size = std::max<std::uint32_t>(mapSize, 1);
  mesh.mapWidth = mesh.mapHeight = size;
  for (std::uint32_t y = 0; y < size; ++y)
    for (std::uint32_t x = 0; x < size; ++x) {
      const double u = (x + 0.5) / size, v = (y + 0.5) / size;
      const double waves = 0.5 + 0.3 * std::sin(6.283185307179586 * 3.0 * u) * std::cos(6.283185307179586 * 2.0 * v);
      const bool checker = ((x * 8 / size) + (y * 8 / size)) % 2 == 1;
      mesh.map.push_back(float(waves + (checker ? 0.15 : 0.0)));
    }
  mesh.scale = scale;
  mesh.offset = offset;
  mesh.level = level;
  mesh.material = 0;
  scene.displacedMeshes.push_back(std::move(mesh));
  scene.materials.push_back(material);
  scene.materialNames.push_back("displaced");
  return scene;
}

Scene makeBox(glm::vec3 lo, glm::vec3 hi, const WtMaterial& material) {
  Scene scene;
  scene.sourceName = "box";
  for (int i = 0; i < 8; ++i) {
    glm::vec3 p((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
    scene.positions.push_back(toVec4(p));
    scene.normals.push_back({0, 0, 0, 0});
    scene.texcoords.emplace_back(0.0f);
  }
  const unsigned faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    scene.triangles.push_back({f[0], f[1], f[2], 0});
    scene.triangles.push_back({f[0], f[2], f[3], 0});
  }
  scene.materials.push_back(material);
  scene.materialNames.push_back("box");
  return scene;
}

Scene makeGrid(std::uint32_t n, glm::vec3 center, float half, glm::vec3 u, glm::vec3 v, const WtMaterial& material) {
  Scene scene;
  scene.sourceName = "grid";
  for (std::uint32_t y = 0; y <= n; ++y)
    for (std::uint32_t x = 0; x <= n; ++x) {
      float a = half * (2.0f * float(x) / float(n) - 1.0f), b = half * (2.0f * float(y) / float(n) - 1.0f);
      scene.positions.push_back(toVec4(center + a * u + b * v));
      scene.normals.push_back({0, 0, 0, 0});
      scene.texcoords.emplace_back(0.0f);
    }
  for (std::uint32_t y = 0; y < n; ++y)
    for (std::uint32_t x = 0; x < n; ++x) {
      std::uint32_t i = y * (n + 1) + x;
      scene.triangles.push_back({i, i + 1, i + n + 2, 0});
      scene.triangles.push_back({i, i + n + 2, i + n + 1, 0});
    }
  scene.materials.push_back(material);
  scene.materialNames.push_back("grid");
  return scene;
}

Scene makeTriangleSoup(std::uint32_t count, std::uint32_t seed, float maxEdge) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), edge(-maxEdge, maxEdge);
  Scene scene;
  scene.sourceName = "triangle soup";
  for (std::uint32_t i = 0; i < count; ++i) {
    glm::vec3 a(unit(rng), unit(rng), unit(rng));
    glm::vec3 b = a + glm::vec3(edge(rng), edge(rng), edge(rng));
    glm::vec3 c = a + glm::vec3(edge(rng), edge(rng), edge(rng));
    std::uint32_t base = std::uint32_t(scene.positions.size());
    for (const glm::vec3& p : {a, b, c}) {
      scene.positions.push_back(toVec4(p));
      scene.normals.push_back({0, 0, 0, 0});
      scene.texcoords.emplace_back(0.0f);
    }
    scene.triangles.push_back({base, base + 1, base + 2, 0});
  }
  scene.materials.push_back(makeMaterial(glm::vec3(0.8f)));
  scene.materialNames.push_back("default");
  return scene;
}

Scene makeBumpyGrid(std::uint32_t triangleCount) {
  std::uint32_t n = std::max<std::uint32_t>(1, std::uint32_t(std::sqrt(triangleCount / 2.0)));
  Scene scene;
  scene.sourceName = "bumpy grid";
  scene.positions.reserve(std::size_t(n + 1) * (n + 1));
  for (std::uint32_t y = 0; y <= n; ++y) {
    for (std::uint32_t x = 0; x <= n; ++x) {
      float u = 2.0f * float(x) / float(n) - 1.0f, v = 2.0f * float(y) / float(n) - 1.0f;
      float h = 0.1f * std::sin(9.0f * u) * std::cos(7.0f * v) + 0.02f * std::sin(61.0f * u + 47.0f * v);
      scene.positions.push_back({u, h, v, 0.0f});
      scene.normals.push_back({0, 0, 0, 0});
      scene.texcoords.emplace_back(0.5f * (u + 1.0f), 0.5f * (v + 1.0f));
    }
  }
  scene.triangles.reserve(std::size_t(2) * n * n);
  for (std::uint32_t y = 0; y < n; ++y) {
    for (std::uint32_t x = 0; x < n; ++x) {
      std::uint32_t i = y * (n + 1) + x;
      scene.triangles.push_back({i, i + n + 1, i + 1, 0});
      scene.triangles.push_back({i + 1, i + n + 1, i + n + 2, 0});
    }
  }
  scene.materials.push_back(makeMaterial(glm::vec3(0.8f)));
  scene.materialNames.push_back("default");
  return scene;
}

Scene makeSphereField(std::uint32_t count, std::uint32_t seed) {
  Scene scene;
  scene.sourceName = "sphere field";
  scene.materials = {makeMaterial(glm::vec3(0.6f)), makeMaterial(glm::vec3(0.0f), glm::vec3(20.0f))};
  scene.materialNames = {"grey", "light"};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-1.0f, 1.0f), logScale(std::log(0.1f), std::log(0.6f));
  const float spacing = 2.0f / std::cbrt(float(std::max<std::uint32_t>(count, 1)));
  scene.spheres.reserve(count + 4);
  for (std::uint32_t i = 0; i < count; ++i)
    scene.spheres.push_back({glm::vec3(pos(rng), pos(rng), pos(rng)), spacing * std::exp(logScale(rng)), 0});
  for (int k = 0; k < 4; ++k)
    scene.spheres.push_back({glm::vec3(k % 2 ? 0.8f : -0.8f, 1.6f, k / 2 ? 0.8f : -0.8f), 0.1f, 1});
  return scene;
}

void addChildCurves(Scene& scene, std::uint32_t firstGuide, std::uint32_t guideCount, std::uint32_t children,
                    float spread, std::uint32_t seed) {
  if (children == 0) return;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::vector<glm::vec3> across1, across2;
  for (std::uint32_t g = firstGuide; g < firstGuide + guideCount; ++g) {
    const Curve guide = scene.curves[g];  // a copy: the vectors grow below
    const std::uint32_t n = guide.pointCount;
    if (n == 0) continue;
    // a frame across the guide at each point, carried along by projection
    // (a rotation-minimising frame for steps that turn by less than 90 degrees)
    across1.assign(n, glm::vec3(0.0f));
    across2.assign(n, glm::vec3(0.0f));
    glm::vec3 previous(0.0f);
    for (std::uint32_t i = 0; i < n; ++i) {
      const WtVec4& a = scene.curvePoints[guide.firstPoint + (i > 0 ? i - 1 : 0)];
      const WtVec4& b = scene.curvePoints[guide.firstPoint + std::min(i + 1, n - 1)];
      glm::vec3 tangent(b.x - a.x, b.y - a.y, b.z - a.z);
      const float length = glm::length(tangent);
      tangent = length > 0.0f && std::isfinite(length) ? tangent / length : glm::vec3(0, 1, 0);
      glm::vec3 u = previous - glm::dot(previous, tangent) * tangent;
      if (!(glm::length(u) > 1e-3f)) {
        // the first frame, or a turn too sharp to carry it: any direction across
        const glm::vec3 other = std::fabs(tangent.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
        u = glm::cross(tangent, other);
      }
      u = glm::normalize(u);
      across1[i] = u;
      across2[i] = glm::cross(tangent, u);
      previous = u;
    }
    for (std::uint32_t c = 0; c < children; ++c) {
      float x, y;
      do x = unit(rng), y = unit(rng);
      while (x * x + y * y > 1.0f);
      Curve child = guide;
      child.firstPoint = std::uint32_t(scene.curvePoints.size());
      for (std::uint32_t i = 0; i < n; ++i) {
        const WtVec4 p = scene.curvePoints[guide.firstPoint + i];
        const glm::vec3 q = glm::vec3(p.x, p.y, p.z) + spread * (x * across1[i] + y * across2[i]);
        scene.curvePoints.push_back({q.x, q.y, q.z, p.w});
      }
      scene.curves.push_back(child);
    }
  }
}

Scene makeHairScene(std::uint32_t guides, std::uint32_t children, std::uint32_t seed) {
  Scene scene;
  scene.sourceName = "hair (generated)";
  scene.materials = {makePbrMaterial(glm::vec3(0.8f, 0.6f, 0.5f), 0.0f, 0.6f),
                     makePbrMaterial(glm::vec3(0.35f, 0.2f, 0.1f), 0.0f, 0.35f)};
  scene.materialNames = {"head", "hair"};
  scene.spheres.push_back({glm::vec3(0.0f), 1.0f, 0});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), u01(0.0f, 1.0f);
  constexpr int kPoints = 16;
  constexpr float kStep = 0.11f, kLift = 1.01f;
  for (std::uint32_t g = 0; g < guides; ++g) {
    // a root on the cap above y = 0.2, uniform in area
    const float y = 0.2f + 0.8f * u01(rng), phi = 2.0f * 3.14159265f * u01(rng);
    const float ring = std::sqrt(1.0f - y * y);
    glm::vec3 p = kLift * glm::vec3(ring * std::cos(phi), y, -ring * std::sin(phi));
    glm::vec3 dir = glm::normalize(p);
    Curve c;
    c.firstPoint = std::uint32_t(scene.curvePoints.size());
    c.pointCount = kPoints;
    c.material = 1;
    for (int i = 0; i < kPoints; ++i) {
      const float radius = 0.004f - 0.0025f * float(i) / float(kPoints - 1);
      scene.curvePoints.push_back({p.x, p.y, p.z, radius});
      // gravity and a little waviness; the strand rests on the head
      dir = glm::normalize(dir + glm::vec3(0.0f, -0.35f, 0.0f) + 0.15f * glm::vec3(unit(rng), unit(rng), unit(rng)));
      p += kStep * dir;
      if (glm::length(p) < kLift) p = kLift * glm::normalize(p);
    }
    scene.curves.push_back(c);
  }
  addChildCurves(scene, 0, guides, children, 0.05f, seed + 1);
  CameraDesc camera;
  camera.name = "front";
  camera.yfov = 0.6f;
  camera.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 0.4f, 4.6f), glm::vec3(0.0f, -0.1f, 0.0f), glm::vec3(0, 1, 0)));
  scene.camera = camera;
  return scene;
}

void appendScene(Scene& dst, const Scene& src) {
  // scenes made in code have no textures; a loaded one may only be the destination
  if (!src.materialTextures.empty()) throw std::invalid_argument("appendScene: the appended scene has textures");
  std::uint32_t vertexBase = std::uint32_t(dst.positions.size());
  std::uint32_t materialBase = std::uint32_t(dst.materials.size());
  std::uint32_t triangleBase = std::uint32_t(dst.triangles.size());
  std::uint32_t geometryBase = 0;
  for (const GeometryInstance& copy : dst.instances) geometryBase = std::max(geometryBase, copy.geometry + 1);
  for (GeometryInstance copy : src.instances) {
    copy.firstTriangle += triangleBase;
    copy.geometry += geometryBase;
    dst.instances.push_back(copy);
  }
  dst.positions.insert(dst.positions.end(), src.positions.begin(), src.positions.end());
  dst.normals.insert(dst.normals.end(), src.normals.begin(), src.normals.end());
  dst.texcoords.insert(dst.texcoords.end(), src.texcoords.begin(), src.texcoords.end());
  // the attributes only some scenes have: every vertex gets one once either has them
  auto appendOptional = [&](auto& to, const auto& from, auto fallback) {
    if (to.empty() && from.empty()) return;
    to.resize(vertexBase, fallback);
    if (from.empty()) to.resize(vertexBase + src.positions.size(), fallback);
    else to.insert(to.end(), from.begin(), from.end());
  };
  appendOptional(dst.texcoords1, src.texcoords1, glm::vec2(0.0f));
  appendOptional(dst.colors, src.colors, glm::vec4(1.0f));
  appendOptional(dst.tangents, src.tangents, glm::vec4(0.0f));
  for (WtTriangle t : src.triangles) {
    t.v0 += vertexBase, t.v1 += vertexBase, t.v2 += vertexBase, t.material += materialBase;
    dst.triangles.push_back(t);
  }
  // copies of spheres and curves: their items and geometry ids past dst's, per type
  std::uint32_t primitiveGeometryBase = 0;
  for (const PrimitiveInstance& copy : dst.primitiveInstances)
    primitiveGeometryBase = std::max(primitiveGeometryBase, copy.geometry + 1);
  for (PrimitiveInstance copy : src.primitiveInstances) {
    copy.first += std::uint32_t(copy.type == WT_PRIM_SPHERE     ? dst.spheres.size()
                                : copy.type == WT_PRIM_CURVE    ? dst.curves.size()
                                : copy.type == WT_PRIM_SDF_GRID ? dst.sdfGrids.size()
                                                                : dst.displacedMeshes.size());
    copy.geometry += primitiveGeometryBase;
    dst.primitiveInstances.push_back(copy);
  }
  for (SdfGrid grid : src.sdfGrids) {
    grid.material += materialBase;
    dst.sdfGrids.push_back(std::move(grid));
  }
  for (DisplacedMesh mesh : src.displacedMeshes) {
    mesh.material += materialBase;
    dst.displacedMeshes.push_back(std::move(mesh));
  }
  for (Sphere sphere : src.spheres) {
    sphere.material += materialBase;
    dst.spheres.push_back(sphere);
  }
  const auto pointBase = std::uint32_t(dst.curvePoints.size());
  for (Curve curve : src.curves) {
    curve.firstPoint += pointBase;
    curve.material += materialBase;
    dst.curves.push_back(curve);
  }
  dst.curvePoints.insert(dst.curvePoints.end(), src.curvePoints.begin(), src.curvePoints.end());
  dst.materials.insert(dst.materials.end(), src.materials.begin(), src.materials.end());
  dst.materialNames.insert(dst.materialNames.end(), src.materialNames.begin(), src.materialNames.end());
}

Scene placeCopies(const Scene& mesh, std::span<const glm::mat4> transforms) {
  Scene scene;
  scene.sourceName = mesh.sourceName + " copies";
  scene.materials = mesh.materials;
  scene.materialNames = mesh.materialNames;
  scene.materialTextures = mesh.materialTextures;
  scene.textures = mesh.textures;
  for (const glm::mat4& transform : transforms) {
    const std::uint32_t vertexBase = std::uint32_t(scene.positions.size());
    const glm::mat3 linear(transform);
    const glm::mat3 normalMatrix = glm::transpose(glm::inverse(linear));
    // a mirroring transform swaps two corners, as the loader does, so the front face stays in front
    const bool flip = glm::determinant(linear) < 0.0f;
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
      const WtVec4& p = mesh.positions[v];
      const glm::vec3 moved(transform * glm::vec4(p.x, p.y, p.z, 1.0f));
      scene.positions.push_back({moved.x, moved.y, moved.z, 0.0f});
      const WtVec4& n = mesh.normals[v];
      glm::vec3 normal = normalMatrix * glm::vec3(n.x, n.y, n.z);
      if (glm::dot(normal, normal) > 0.0f) normal = glm::normalize(normal);
      scene.normals.push_back({normal.x, normal.y, normal.z, 0.0f});
      scene.texcoords.push_back(v < mesh.texcoords.size() ? mesh.texcoords[v] : glm::vec2(0.0f));
    }
    // the attributes only some meshes have, as the loader places them: TEXCOORD_1 and COLOR_0 as they
    // are, a tangent moved with the surface (the linear part) and its bitangent's side flipped by a mirror
    scene.texcoords1.insert(scene.texcoords1.end(), mesh.texcoords1.begin(), mesh.texcoords1.end());
    scene.colors.insert(scene.colors.end(), mesh.colors.begin(), mesh.colors.end());
    for (const glm::vec4& t : mesh.tangents) {
      const glm::vec3 moved = linear * glm::vec3(t);
      const float length = glm::length(moved);
      scene.tangents.push_back(length > 0.0f && std::isfinite(length)
                                   ? glm::vec4(moved / length, (t.w < 0.0f) != flip ? -1.0f : 1.0f)
                                   : glm::vec4(0.0f));
    }
    scene.instances.push_back(
        {std::uint32_t(scene.triangles.size()), std::uint32_t(mesh.triangles.size()), 0, glm::dmat4(transform)});
    for (WtTriangle t : mesh.triangles) {
      t.v0 += vertexBase, t.v1 += vertexBase, t.v2 += vertexBase;
      if (flip) std::swap(t.v1, t.v2);
      scene.triangles.push_back(t);
    }
    // spheres and curves: radii scale by the cube root of the determinant (as scene files place them)
    const float radiusScale = float(std::cbrt(std::abs(glm::determinant(glm::dmat3(transform)))));
    if (!mesh.spheres.empty())
      scene.primitiveInstances.push_back({WT_PRIM_SPHERE, std::uint32_t(scene.spheres.size()),
                                          std::uint32_t(mesh.spheres.size()), 0, glm::dmat4(transform)});
    for (Sphere s : mesh.spheres) {
      s.center = glm::vec3(transform * glm::vec4(s.center, 1.0f));
      s.radius *= radiusScale;
      scene.spheres.push_back(s);
    }
    if (!mesh.curves.empty())
      scene.primitiveInstances.push_back({WT_PRIM_CURVE, std::uint32_t(scene.curves.size()),
                                          std::uint32_t(mesh.curves.size()), 0, glm::dmat4(transform)});
    const auto pointBase = std::uint32_t(scene.curvePoints.size());
    for (Curve c : mesh.curves) {
      c.firstPoint += pointBase;
      scene.curves.push_back(c);
    }
    for (const WtVec4& p : mesh.curvePoints) {
      const glm::vec3 moved(transform * glm::vec4(p.x, p.y, p.z, 1.0f));
      scene.curvePoints.push_back({moved.x, moved.y, moved.z, p.w * radiusScale});
    }
    // SDF grids: the lattice placed by the transform (any affine one), values as they are
    if (!mesh.sdfGrids.empty())
      scene.primitiveInstances.push_back({WT_PRIM_SDF_GRID, std::uint32_t(scene.sdfGrids.size()),
                                          std::uint32_t(mesh.sdfGrids.size()), 0, glm::dmat4(transform)});
    for (SdfGrid g : mesh.sdfGrids) {
      g.latticeToScene = glm::dmat4(transform) * g.latticeToScene;
      scene.sdfGrids.push_back(std::move(g));
    }
    // displaced meshes: vertices and normals moved, displacements scaled as radii, corners swapped by a mirror
    if (!mesh.displacedMeshes.empty())
      scene.primitiveInstances.push_back({WT_PRIM_DISPLACED, std::uint32_t(scene.displacedMeshes.size()),
                                          std::uint32_t(mesh.displacedMeshes.size()), 0, glm::dmat4(transform)});
    for (DisplacedMesh d : mesh.displacedMeshes) {
      for (glm::vec3& p : d.positions) p = glm::vec3(glm::dmat4(transform) * glm::dvec4(glm::dvec3(p), 1.0));
      for (glm::vec3& n : d.normals) {
        const glm::vec3 m = normalMatrix * n;
        n = glm::dot(m, m) > 0.0f ? glm::normalize(m) : m;
      }
      if (flip)
        for (auto& t : d.triangles) std::swap(t[1], t[2]);
      d.scale *= radiusScale;
      d.offset *= radiusScale;
      scene.displacedMeshes.push_back(std::move(d));
    }
  }
  return scene;
}

}  // namespace wt
