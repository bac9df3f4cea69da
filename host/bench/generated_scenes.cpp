#include "bench/generated_scenes.h"

#include "scene/generators.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <random>

namespace wt {
namespace {

/// A lattice value in [-1, 1] from integer coordinates and a seed (a hash:
/// the same on every host).
float latticeValue(int x, int y, int z, std::uint32_t seed) {
  std::uint32_t h = std::uint32_t(x) * 0x8da6b343u ^ std::uint32_t(y) * 0xd8163841u ^ std::uint32_t(z) * 0xcb1ab31fu ^
                    seed * 0x9e3779b9u;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return float(h >> 8) * 0x1p-23f - 1.0f;
}

/// Smoothly interpolated lattice values, `octaves` of them halving in
/// amplitude and doubling in frequency; about [-1, 1].
float valueNoise(glm::vec3 p, int octaves, std::uint32_t seed) {
  float sum = 0.0f, amplitude = 0.5f;
  for (int o = 0; o < octaves; ++o) {
    glm::vec3 f = glm::floor(p), t = p - f;
    t = t * t * (3.0f - 2.0f * t);
    const int x = int(f.x), y = int(f.y), z = int(f.z);
    auto v = [&](int dx, int dy, int dz) { return latticeValue(x + dx, y + dy, z + dz, seed + std::uint32_t(o)); };
    const float x00 = glm::mix(v(0, 0, 0), v(1, 0, 0), t.x), x10 = glm::mix(v(0, 1, 0), v(1, 1, 0), t.x);
    const float x01 = glm::mix(v(0, 0, 1), v(1, 0, 1), t.x), x11 = glm::mix(v(0, 1, 1), v(1, 1, 1), t.x);
    sum += amplitude * glm::mix(glm::mix(x00, x10, t.y), glm::mix(x01, x11, t.y), t.z);
    amplitude *= 0.5f;
    p *= 2.0f;
  }
  return 2.0f * sum;
}

/// Move every vertex of `mesh` along its normal by `amplitude` x noise.
void displace(Scene& mesh, float frequency, float amplitude, std::uint32_t seed) {
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    WtVec4& p = mesh.positions[i];
    const WtVec4& n = mesh.normals[i];
    const glm::vec3 at(p.x, p.y, p.z), normal(n.x, n.y, n.z);
    const glm::vec3 moved = at + amplitude * valueNoise(frequency * at, 4, seed) * normal;
    p = {moved.x, moved.y, moved.z, 0.0f};
  }
  // the normals no longer match the surface: the geometric normal instead
  for (WtVec4& n : mesh.normals) n = {0.0f, 0.0f, 0.0f, 0.0f};
}

/// A square emitter of half-size `half` at `center` whose front faces `target`.
Scene quadLight(glm::vec3 center, glm::vec3 target, float half, float radiance) {
  const glm::vec3 w = glm::normalize(target - center);
  const glm::vec3 helper = std::abs(w.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  glm::vec3 u = glm::normalize(glm::cross(helper, w)), v = glm::cross(w, u);
  if (glm::dot(glm::cross(u, v), w) < 0.0f) std::swap(u, v);  // makeGrid faces u x v
  Scene light = makeGrid(1, center, half, u, v, makeMaterial(glm::vec3(0.0f), glm::vec3(radiance)));
  light.materialNames = {"light"};
  return light;
}

CameraDesc lookingAt(glm::vec3 eye, glm::vec3 target) {
  CameraDesc camera;
  camera.cameraToWorld = glm::inverse(glm::lookAt(eye, target, glm::vec3(0, 1, 0)));
  camera.name = "generated";
  return camera;
}

}  // namespace

const std::vector<std::string>& generatedSceneNames() {
  static const std::vector<std::string> names{"soup", "displaced-sphere", "forest", "many-lights"};
  return names;
}

std::optional<Scene> makeGeneratedScene(std::string_view name, std::uint32_t triangles) {
  if (name == "soup") return makeLitSoup(std::max<std::uint32_t>(triangles / 4, 1));
  if (name == "displaced-sphere") return makeDisplacedSphere(triangles);
  if (name == "forest") return makeForest();
  if (name == "many-lights") return makeManyLights();
  return std::nullopt;
}

Scene makeLitSoup(std::uint32_t count, std::uint32_t seed) {
  Scene scene = makeTriangleSoup(count, seed, 0.05f);
  scene.sourceName = "lit soup";
  appendScene(scene, quadLight(glm::vec3(0.5f, 1.8f, 0.5f), glm::vec3(0.5f), 0.05f, 50.0f));
  scene.camera = lookingAt(glm::vec3(0.5f, 0.9f, 2.6f), glm::vec3(0.5f));
  return scene;
}

Scene makeDisplacedSphere(std::uint32_t triangles, std::uint32_t seed) {
  // the subdivision level nearest to `triangles` (log scale), 1 to 9
  const double level = std::log(std::max(double(triangles), 20.0) / 20.0) / std::log(4.0);
  const int subdivisions = std::clamp(int(std::lround(level)), 1, 9);
  Scene scene = makeIcosphere(subdivisions, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.7f)));
  scene.sourceName = "displaced sphere";
  displace(scene, 6.0f, 0.08f, seed);
  appendScene(scene, quadLight(glm::vec3(1.6f, 2.2f, 1.4f), glm::vec3(0.0f), 0.15f, 100.0f));
  scene.camera = lookingAt(glm::vec3(0.0f, 0.4f, 3.4f), glm::vec3(0.0f));
  return scene;
}

Scene makeForest(std::uint32_t trees, std::uint32_t seed) {
  // one tree: a noisy crown on a trunk
  Scene tree = makeIcosphere(3, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.2f, 0.5f, 0.2f)));
  displace(tree, 3.0f, 0.25f, seed);
  for (WtVec4& p : tree.positions) p = {0.9f * p.x, 2.2f + 1.4f * p.y, 0.9f * p.z, 0.0f};
  appendScene(tree, makeBox(glm::vec3(-0.12f, 0.0f, -0.12f), glm::vec3(0.12f, 1.2f, 0.12f),
                            makeMaterial(glm::vec3(0.4f, 0.3f, 0.2f))));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> along(-19.0f, 19.0f), turn(0.0f, 6.2831853f), size(0.7f, 1.3f);
  std::vector<glm::mat4> placed;
  placed.reserve(trees);
  for (std::uint32_t i = 0; i < trees; ++i) {
    const float x = along(rng), z = along(rng), angle = turn(rng), s = size(rng);
    glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(x, 0.0f, z));
    m = glm::rotate(m, angle, glm::vec3(0, 1, 0));
    placed.push_back(glm::scale(m, glm::vec3(s)));
  }
  Scene scene = placeCopies(tree, placed);
  scene.sourceName = "forest";
  appendScene(scene, makeGrid(1, glm::vec3(0.0f), 20.0f, glm::vec3(0, 0, 1), glm::vec3(1, 0, 0),
                              makeMaterial(glm::vec3(0.5f))));
  appendScene(scene, quadLight(glm::vec3(8.0f, 30.0f, 10.0f), glm::vec3(0.0f), 0.5f, 1000.0f));
  scene.camera = lookingAt(glm::vec3(0.0f, 7.0f, 26.0f), glm::vec3(0.0f, 1.0f, 0.0f));
  return scene;
}

Scene makeManyLights(std::uint32_t lights, std::uint32_t seed) {
  Scene scene = makeGrid(1, glm::vec3(0.0f), 10.0f, glm::vec3(0, 0, 1), glm::vec3(1, 0, 0),
                         makeMaterial(glm::vec3(0.6f)));
  scene.sourceName = "many lights";
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> along(-9.5f, 9.5f), width(0.1f, 0.6f), height(0.3f, 3.0f);
  for (int i = 0; i < 300; ++i) {
    const glm::vec3 c(along(rng), 0.0f, along(rng));
    const glm::vec3 half(width(rng), height(rng), width(rng));
    appendScene(scene, makeBox(c - glm::vec3(half.x, 0.0f, half.z), c + half, makeMaterial(glm::vec3(0.5f))));
  }
  for (std::uint32_t i = 0; i < lights; ++i) {
    const glm::vec3 c(along(rng), 5.0f, along(rng));
    appendScene(scene, quadLight(c, c - glm::vec3(0.0f, 1.0f, 0.0f), 0.08f, 200.0f));
  }
  scene.camera = lookingAt(glm::vec3(0.0f, 4.0f, 14.0f), glm::vec3(0.0f, 0.8f, 0.0f));
  return scene;
}

}  // namespace wt
