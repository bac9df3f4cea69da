// Instancing on a real scene (kernels/geometry/instance.cl): glTF nodes
// sharing a mesh stored once. Skips when ../shared/assets is absent.
#include "device_fixture.h"
#include "instancing_checks.h"
#include "scene/gltf_loader.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <random>

namespace wt {
namespace {

using test::hitsAgree;
using test::withInstancing;

/// MetalRoughSpheresNoTextures: 98 copies of one sphere mesh (glTF nodes
/// sharing it) stored once; rays from its camera hit the same triangles as
/// the flattened scene's.
TEST(InstancingAssets, MetalRoughSpheres) {
  WT_REQUIRE_ASSET(path, "gltf/MetalRoughSpheresNoTextures/glTF/MetalRoughSpheresNoTextures.gltf");
  const Scene scene = loadGltf(path.string());
  Tracer on(test::deviceContext(), scene, withInstancing(Instancing::On));
  Tracer off(test::deviceContext(), scene, withInstancing(Instancing::Off));
  EXPECT_GE(on.sceneBuffers().instanceCount(), 98u);
  const double ratio = double(on.sceneBuffers().triangleBytes()) / double(off.sceneBuffers().triangleBytes());
  EXPECT_LT(ratio, 1.5 / 98.0) << on.sceneBuffers().triangleBytes() << " against " << off.sceneBuffers().triangleBytes();
  // rays from the camera's position through the scene's bounds
  const Aabb bounds = scene.bounds();
  const CameraDesc camera = scene.camera ? *scene.camera : defaultCamera(bounds);
  const glm::vec3 eye(camera.cameraToWorld[3]);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Ray> rays(20000);
  for (Ray& r : rays) {
    const glm::vec3 target = bounds.lo + (bounds.hi - bounds.lo) * glm::vec3(u(rng), u(rng), u(rng));
    r.origin = eye;
    r.direction = glm::normalize(target - eye);
  }
  const std::vector<RayHit> flat = off.traceClosest(rays);
  const std::vector<RayHit> got = on.traceClosest(rays, Traversal::kPacket);
  int bad = 0, edges = 0;
  for (std::size_t i = 0; i < rays.size(); ++i)
    if (!hitsAgree(scene, rays[i], got[i], flat[i], &edges) && ++bad <= 5)
      ADD_FAILURE() << "ray " << i << ": instanced " << got[i].triangle << " t=" << got[i].t << ", flattened "
                    << flat[i].triangle << " t=" << flat[i].t;
  EXPECT_EQ(bad, 0);
  EXPECT_LT(edges, int(rays.size() / 100));
}

}  // namespace
}  // namespace wt
