// chooseTraversal on synthetic batches: what the measured statistics say
// and which traversal they lead to, with no device involved.
#include "device/tracer.h"
#include "geometry/primitives.h"
#include "scene/generators.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace wt {
namespace {

/// width x width camera rays from one eye through a 0.6-wide screen, row by row.
std::vector<Ray> cameraRays(int width) {
  std::vector<Ray> rays;
  for (int y = 0; y < width; ++y)
    for (int x = 0; x < width; ++x) {
      Ray r;
      r.origin = glm::vec3(0.0f, 0.0f, 3.0f);
      r.direction = glm::normalize(glm::vec3(0.6f * ((x + 0.5f) / width - 0.5f), 0.6f * ((y + 0.5f) / width - 0.5f), -1.0f));
      rays.push_back(r);
    }
  return rays;
}

/// Rays leaving a row of points `pitch` apart on the plane z = 0 towards
/// random points of a square of half-size `half` centred 3 above: the
/// shadow rays of neighbouring pixels to one small light.
std::vector<Ray> shadowRays(std::size_t count, float pitch, float half) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-half, half);
  std::vector<Ray> rays;
  for (std::size_t i = 0; i < count; ++i) {
    Ray r;
    r.origin = glm::vec3(pitch * float(i % 1024), pitch * float(i / 1024), 0.0f);
    const glm::vec3 target(0.5f + u(rng), 0.5f + u(rng), 3.0f);
    r.direction = glm::normalize(target - r.origin);
    r.tmax = glm::length(target - r.origin);
    rays.push_back(r);
  }
  return rays;
}

std::vector<Ray> randomRays(std::size_t count) {
  std::mt19937 rng(7);
  std::normal_distribution<float> gauss;
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<Ray> rays(count);
  for (Ray& r : rays) {
    r.origin = glm::vec3(unit(rng), unit(rng), unit(rng));
    r.direction = glm::normalize(glm::vec3(gauss(rng), gauss(rng), gauss(rng)));
  }
  return rays;
}

TEST(TraversalChoice, TimedTrialsKeepTheFastestTrialOfEach) {
  TraversalTrials trials;
  EXPECT_FALSE(trials.faster().has_value()) << "no trial yet";
  trials.add(Traversal::kPacket, 2e-8);
  EXPECT_FALSE(trials.faster().has_value()) << "single rays not tried yet";
  // packets are faster, but one of their trials was interrupted by other work:
  // its time is not an average's share of the choice
  trials.add(Traversal::kSingle, 3e-8);
  trials.add(Traversal::kPacket, 9e-8);
  trials.add(Traversal::kSingle, 3.1e-8);
  ASSERT_TRUE(trials.faster().has_value());
  EXPECT_EQ(*trials.faster(), Traversal::kPacket);
  EXPECT_DOUBLE_EQ(trials.packetRatio(), 2e-8 / 3e-8);
  // a faster single-ray trial turns it
  trials.add(Traversal::kSingle, 1e-8);
  EXPECT_EQ(*trials.faster(), Traversal::kSingle);
  // an empty trial (no rays timed: 0 s) counts as none
  TraversalTrials empty;
  empty.add(Traversal::kPacket, 0.0);
  empty.add(Traversal::kSingle, 1e-8);
  EXPECT_FALSE(empty.faster().has_value());
}

TEST(TraversalChoice, MeasuresCoherenceOctantsAndOriginSpread) {
  EXPECT_EQ(measureRays({}, 8).packets, 0u);
  // one eye: no spread, every packet in one octant, coherence near 1
  const RayBatchStats camera = measureRays(cameraRays(64), 8);
  EXPECT_EQ(camera.originSpread, 0.0);
  EXPECT_GT(camera.coherence, 0.99);
  EXPECT_GT(camera.octantShare, 0.9);  // a packet crosses an axis only at the image's middle
  // origins at x = 0, 1, ..., 7: RMS distance from 3.5 is sqrt(5.25)
  std::vector<Ray> row(8);
  for (std::size_t i = 0; i < row.size(); ++i) row[i].origin = glm::vec3(float(i), 0.0f, 0.0f), row[i].direction = glm::vec3(0, 0, 1);
  EXPECT_NEAR(measureRays(row, 8).originSpread, std::sqrt(5.25), 1e-9);
  // uniform directions: about a third of each packet of 8 shares an octant
  // (the largest of 8 draws from 8 bins), never all of it
  const RayBatchStats random = measureRays(randomRays(80000), 8);
  EXPECT_LT(random.coherence, 0.5);
  EXPECT_LT(random.octantShare, 0.5);
  // a sample of at most maxPackets packets
  EXPECT_EQ(measureRays(randomRays(80000), 8, 100).packets, 100u);
}

TEST(TraversalChoice, PrimitiveScaleIsTheRootOfTheMeanArea) {
  // a unit square as two triangles of area 1/2
  Scene square = makeGrid(1, glm::vec3(0.0f), 0.5f, glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), makeMaterial(glm::vec3(0.5f)));
  EXPECT_NEAR(primitiveScale(square, gatherPrimitives(square)), std::sqrt(0.5), 1e-6);
  // 100 x 100 quads on the same square: 20 000 triangles of 1/20 000
  Scene fine = makeGrid(100, glm::vec3(0.0f), 0.5f, glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), makeMaterial(glm::vec3(0.5f)));
  EXPECT_NEAR(primitiveScale(fine, gatherPrimitives(fine)), std::sqrt(1.0 / 20000.0), 1e-6);
}

TEST(TraversalChoice, PrimitiveScaleCountsEveryType) {
  constexpr double pi = std::numbers::pi;
  const WtMaterial white = makeMaterial(glm::vec3(0.5f));
  auto scaleOf = [](const Scene& scene) { return primitiveScale(scene, gatherPrimitives(scene)); };
  // one round cone 2 long, radii 0.1 and 0.2: its side, pi (r0 + r1) times the slant length
  Scene curve;
  curve.materials.push_back(white);
  curve.curvePoints = {WtVec4{0, 0, 0, 0.1f}, WtVec4{2, 0, 0, 0.2f}};
  curve.curves.push_back(Curve{0, 2, 0, CurveBasis::kLinear});
  const double cone = pi * 0.3 * std::sqrt(4.0 + 0.01);
  EXPECT_NEAR(scaleOf(curve), std::sqrt(cone), 1e-6);
  // beside a sphere of radius 0.5 (area pi) and a unit square of two triangles: the mean of all four
  Scene mixed = makeGrid(1, glm::vec3(0.0f, 0.0f, -5.0f), 0.5f, glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), white);
  mixed.curvePoints = curve.curvePoints;
  mixed.curves = curve.curves;
  mixed.spheres.push_back(Sphere{glm::vec3(5.0f, 0.0f, 0.0f), 0.5f, 0});
  EXPECT_NEAR(scaleOf(mixed), std::sqrt((1.0 + cone + pi) / 4.0), 1e-6);
  // a displaced icosphere (triangles of unequal areas): its base triangles' flat areas, as the same icosphere of triangles
  const Scene flat = makeIcosphere(1, glm::vec3(0.0f), 1.0f, white);
  const Scene displaced = makeDisplacedSphere(1, glm::vec3(0.0f), 1.0f, 4, 0.1f, 0.0f, 2, white);
  ASSERT_EQ(displaced.triangles.size(), 0u);
  EXPECT_NEAR(scaleOf(displaced), scaleOf(flat), 1e-6 * scaleOf(flat));
  // the plane z = 3.5 (voxel units) through 8^3 cells 0.25 wide: one brick of
  // 64 crossed cells, the plane's 2 x 2 inside the grid
  Scene sdf;
  sdf.materials.push_back(white);
  SdfGrid grid;
  grid.cells = glm::uvec3(8);
  for (int z = 0; z <= 8; ++z)
    for (int i = 0; i < 81; ++i) grid.values.push_back(float(z) - 3.5f);
  grid.latticeToScene = glm::dmat4(0.25);
  grid.latticeToScene[3][3] = 1.0;
  sdf.sdfGrids.push_back(grid);
  EXPECT_NEAR(scaleOf(sdf), 2.0, 1e-6);
}

TEST(TraversalChoice, CameraRaysInPacketsRandomRaysNot) {
  for (int width : {8, 16}) {
    // one origin: packets, whatever the scene's scale and query
    const RayBatchStats camera = measureRays(cameraRays(64), std::size_t(width));
    for (double scale : {1e-4, 1.0})
      for (bool occlusion : {false, true})
        EXPECT_EQ(chooseTraversal(camera, scale, occlusion, true), Traversal::kPacket) << width << " " << scale;
    // random directions: streams for any hit on a CPU, else single rays
    const RayBatchStats random = measureRays(randomRays(80000), std::size_t(width));
    EXPECT_EQ(chooseTraversal(random, 1.0, true, true), Traversal::kStream);
    EXPECT_EQ(chooseTraversal(random, 1.0, false, true), Traversal::kSingle);
    EXPECT_EQ(chooseTraversal(random, 1.0, true, false), Traversal::kSingle);
  }
  EXPECT_EQ(chooseTraversal(RayBatchStats{}, 1.0, true, true), Traversal::kStream);
}

TEST(TraversalChoice, ShadowRaysToOneLightByOriginSpreadAgainstThePrimitives) {
  // rays 0.01 apart to a small light point nearly one way (coherence > 0.95)
  const std::vector<Ray> rays = shadowRays(16384, 0.01f, 0.05f);
  const RayBatchStats stats = measureRays(rays, 16);
  ASSERT_GT(stats.coherence, kPacketMinCoherence);
  // a packet of 16 spans 0.15 (RMS 0.046): among big primitives (a Cornell
  // box's walls) it stays in one leaf, packets; among primitives 0.003
  // across (a 1 M-triangle sphere of radius 1) it spans some fifteen leaves
  // at its origins, streams for any hit, single rays for closest hits
  EXPECT_EQ(chooseTraversal(stats, 1.0, true, true), Traversal::kPacket);
  EXPECT_EQ(chooseTraversal(stats, 0.003, true, true), Traversal::kStream);
  EXPECT_EQ(chooseTraversal(stats, 0.003, false, true), Traversal::kSingle);
  // the boundary: n = 1 + 2 spread / (kLeafScales scale) at which n kPacketLaneCost
  // meets the other's cost, 1 / kStreamGain (streams) or 1 (single rays)
  auto boundary = [&](double other) {
    return 2.0 * stats.originSpread / (kLeafScales * (other / kPacketLaneCost - 1.0));
  };
  EXPECT_EQ(chooseTraversal(stats, 1.05 * boundary(1.0 / kStreamGain), true, true), Traversal::kPacket);
  EXPECT_EQ(chooseTraversal(stats, 0.95 * boundary(1.0 / kStreamGain), true, true), Traversal::kStream);
  EXPECT_EQ(chooseTraversal(stats, 1.05 * boundary(1.0), false, true), Traversal::kPacket);
  EXPECT_EQ(chooseTraversal(stats, 0.95 * boundary(1.0), false, true), Traversal::kSingle);
  // between the two: packets beat single rays but not streams
  EXPECT_EQ(chooseTraversal(stats, 0.95 * boundary(1.0 / kStreamGain), false, true), Traversal::kPacket);
  // a light so large that the directions spread: no packets however big the primitives
  const RayBatchStats wide = measureRays(shadowRays(16384, 0.01f, 3.0f), 16);
  EXPECT_LT(wide.coherence, kPacketMinCoherence);
  EXPECT_EQ(chooseTraversal(wide, 10.0, true, true), Traversal::kStream);
}

}  // namespace
}  // namespace wt
