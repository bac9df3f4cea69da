// Where paths start in nested dielectrics (host/render/camera_media.h): the
// closed transmitting volumes that hold the camera, outermost first.
#include "render/camera_media.h"
#include "scene/generators.h"

#include <gtest/gtest.h>

#include <vector>

namespace wt {
namespace {

WtMaterial medium(float ior, std::uint32_t priority, bool thinWalled = false) {
  return withPriority(withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.0f), 1.0f, ior, thinWalled,
                                       glm::vec3(0.1f)),
                      priority);
}

/// The stack's used entries, oldest first.
std::vector<wt_uint> entries(const WtMediaStack& s) {
  std::vector<wt_uint> out;
  for (wt_uint id : s.id)
    if (id != WT_MEDIUM_NONE) out.push_back(id);
  return out;
}

/// Boxes 0..n-1 (material i for box i) nested around the origin, box i of
/// half size n + 1 - i: box 0 the outermost.
Scene nestedBoxes(const std::vector<WtMaterial>& materials) {
  Scene scene;
  const float n = float(materials.size());
  for (std::size_t i = 0; i < materials.size(); ++i) {
    const float h = n + 1.0f - float(i);
    appendScene(scene, makeBox(glm::vec3(-h), glm::vec3(h), materials[i]));  // material i
  }
  return scene;
}

// Inside water holding a glass box: both, the water first whatever their
// priorities (the stack's current medium is the glass by priority; by entry
// order among equals); between them only the water; outside neither.
TEST(CameraMedia, NestedBoxesHoldTheCameraOutermostFirst) {
  for (std::uint32_t glassPriority : {0u, 1u}) {
    const Scene scene = nestedBoxes({medium(1.33f, 0), medium(1.5f, glassPriority)});
    EXPECT_EQ(entries(cameraMediaStack(scene, glm::vec3(0.0f))), (std::vector<wt_uint>{0, 1}));
    EXPECT_EQ(entries(cameraMediaStack(scene, glm::vec3(0.3f, 2.5f, -0.2f))), (std::vector<wt_uint>{0}));
    EXPECT_EQ(entries(cameraMediaStack(scene, glm::vec3(0.3f, 3.5f, -0.2f))), (std::vector<wt_uint>{}));
    const WtMediaStack stack = cameraMediaStack(scene, glm::vec3(0.0f));
    EXPECT_EQ(media_current(&stack, scene.materials.data()), 1) << "glass priority " << glassPriority;
  }
}

// Only closed volumes of a refracting medium: an opaque box, a thin-walled
// transmitter and a volume turned inside out (its winding facing in) hold
// no camera.
TEST(CameraMedia, OnlyRefractingVolumesHoldTheCamera) {
  Scene opaque = nestedBoxes({makePbrMaterial(glm::vec3(0.5f), 0.0f, 0.5f)});
  EXPECT_TRUE(entries(cameraMediaStack(opaque, glm::vec3(0.0f))).empty());
  Scene thin = nestedBoxes({medium(1.5f, 0, true)});
  EXPECT_TRUE(entries(cameraMediaStack(thin, glm::vec3(0.0f))).empty());
  Scene inverted = nestedBoxes({medium(1.5f, 0)});
  for (WtTriangle& t : inverted.triangles) std::swap(t.v1, t.v2);
  EXPECT_TRUE(entries(cameraMediaStack(inverted, glm::vec3(0.0f))).empty());
  EXPECT_EQ(entries(cameraMediaStack(nestedBoxes({medium(1.5f, 0)}), glm::vec3(0.0f))), (std::vector<wt_uint>{0}));
}

// A point on a box's diagonal plane and on an axis (where a ray could meet
// an edge) is found inside all the same; analytic spheres by their radius.
TEST(CameraMedia, EdgesAndSpheres) {
  Scene scene = nestedBoxes({medium(1.33f, 0)});
  EXPECT_EQ(entries(cameraMediaStack(scene, glm::vec3(1.0f, 1.0f, 1.0f))).size(), 1u);
  EXPECT_EQ(entries(cameraMediaStack(scene, glm::vec3(0.0f, 0.0f, 1.9f))).size(), 1u);
  scene.materials.push_back(medium(1.5f, 2));
  scene.spheres.push_back({glm::vec3(0.5f, 0.0f, 0.0f), 0.5f, 1u});
  EXPECT_EQ(entries(cameraMediaStack(scene, glm::vec3(0.6f, 0.1f, 0.0f))), (std::vector<wt_uint>{0, 1}));
  EXPECT_EQ(entries(cameraMediaStack(scene, glm::vec3(-0.6f, 0.1f, 0.0f))), (std::vector<wt_uint>{0}));
}

// More volumes than the stack holds: the ones of highest priority stay, as
// media_cross keeps them for a path entering them one by one.
TEST(CameraMedia, AFullStackKeepsTheHighestPriorities) {
  std::vector<WtMaterial> materials;
  const std::uint32_t priorities[6] = {5, 0, 4, 1, 3, 2};
  for (std::uint32_t p : priorities) materials.push_back(medium(1.3f, p));
  const Scene scene = nestedBoxes(materials);
  static_assert(WT_MEDIA_STACK == 4, "the expected entries assume a 4-entry stack");
  EXPECT_EQ(entries(cameraMediaStack(scene, glm::vec3(0.0f))), (std::vector<wt_uint>{0, 2, 4, 5}));
}

}  // namespace
}  // namespace wt
