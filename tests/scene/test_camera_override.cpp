// --look-from, --look-at, --up, --fov and --frame over a scene's camera:
// positions in the file's world coordinates, whatever the scene's origin.
#include "scene/camera_override.h"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace {

constexpr double kTol = 1e-5;

wt::Scene sceneWithCamera(glm::dvec3 origin) {
  wt::Scene scene;
  scene.origin = origin;
  // one triangle, so the bounds exist: x in [-1, 1], y in [0, 2], z = 0 (relative to the origin)
  scene.positions = {{-1, 0, 0, 0}, {1, 0, 0, 0}, {0, 2, 0, 0}};
  scene.triangles.push_back({0, 1, 2, 0});
  wt::CameraDesc camera;  // at (0, 1, 5) relative, looking down -Z, up +Y
  camera.cameraToWorld = glm::translate(glm::mat4(1.0f), glm::vec3(0, 1, 5));
  camera.yfov = 0.5f;
  scene.camera = camera;
  return scene;
}

glm::dvec3 eye(const wt::Scene& s) { return glm::dvec3(s.camera->cameraToWorld[3]); }
glm::dvec3 forward(const wt::Scene& s) { return -glm::normalize(glm::dvec3(s.camera->cameraToWorld[2])); }
glm::dvec3 upAxis(const wt::Scene& s) { return glm::normalize(glm::dvec3(s.camera->cameraToWorld[1])); }

void expectNear(glm::dvec3 a, glm::dvec3 b, double tol = kTol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

TEST(CameraOverride, LookFromAndAtAreWorldCoordinatesWhateverTheOrigin) {
  const glm::dvec3 origin(1e6, -2.0, 3.0);
  wt::Scene scene = sceneWithCamera(origin);
  wt::CameraOverride o;
  o.from = origin + glm::dvec3(4, 1, 0);
  o.at = origin + glm::dvec3(0, 1, 0);
  wt::applyCameraOverride(scene, o);
  expectNear(eye(scene), {4, 1, 0}, 1e-3);  // float matrix after a 1e6 subtraction in double
  expectNear(forward(scene), {-1, 0, 0});
  expectNear(upAxis(scene), {0, 1, 0});     // the camera's own up kept
  EXPECT_FLOAT_EQ(scene.camera->yfov, 0.5f);
}

TEST(CameraOverride, LookAtAloneTurnsInPlaceAndLookFromAloneKeepsTheDirection) {
  wt::Scene turned = sceneWithCamera({0, 0, 0});
  wt::CameraOverride at;
  at.at = glm::dvec3(5, 1, 5);
  wt::applyCameraOverride(turned, at);
  expectNear(eye(turned), {0, 1, 5});
  expectNear(forward(turned), {1, 0, 0});

  wt::Scene moved = sceneWithCamera({0, 0, 0});
  wt::CameraOverride from;
  from.from = glm::dvec3(3, 3, 3);
  wt::applyCameraOverride(moved, from);
  expectNear(eye(moved), {3, 3, 3});
  expectNear(forward(moved), {0, 0, -1});
}

TEST(CameraOverride, UpSetsTheRollAndStraightDownFallsBackToAnotherAxis) {
  wt::Scene rolled = sceneWithCamera({0, 0, 0});
  wt::CameraOverride o;
  o.up = glm::dvec3(1, 0, 0);
  wt::applyCameraOverride(rolled, o);
  expectNear(upAxis(rolled), {1, 0, 0});
  expectNear(forward(rolled), {0, 0, -1});

  // looking straight down its old up axis: the roll comes from world +Y or +Z, never NaN
  wt::Scene down = sceneWithCamera({0, 0, 0});
  wt::CameraOverride d;
  d.from = glm::dvec3(0, 10, 0);
  d.at = glm::dvec3(0, 0, 0);
  wt::applyCameraOverride(down, d);
  expectNear(forward(down), {0, -1, 0});
  EXPECT_TRUE(std::isfinite(upAxis(down).x + upAxis(down).y + upAxis(down).z));
  EXPECT_NEAR(glm::dot(upAxis(down), forward(down)), 0.0, kTol);
}

TEST(CameraOverride, FovAloneChangesOnlyTheFieldOfView) {
  wt::Scene scene = sceneWithCamera({0, 0, 0});
  wt::CameraOverride o;
  o.fovDegrees = 90.0;
  wt::applyCameraOverride(scene, o);
  EXPECT_NEAR(scene.camera->yfov, M_PI / 2, 1e-6);
  expectNear(eye(scene), {0, 1, 5});
  expectNear(forward(scene), {0, 0, -1});
}

TEST(CameraOverride, FrameLooksAtTheBoundsAndStandsFurtherBackForANarrowerFov) {
  wt::Scene wide = sceneWithCamera({0, 0, 0});
  wt::CameraOverride o;
  o.frame = true;
  wt::applyCameraOverride(wide, o);
  const glm::dvec3 centre(0, 1, 0);
  const glm::dvec3 toCentre = glm::normalize(centre - eye(wide));
  expectNear(forward(wide), toCentre);

  wt::Scene narrow = sceneWithCamera({0, 0, 0});
  o.fovDegrees = 10.0;
  wt::applyCameraOverride(narrow, o);
  EXPECT_NEAR(narrow.camera->yfov, glm::radians(10.0), 1e-6);
  // the bounds' sphere fills the view: distance = radius / sin(fov / 2)
  const double radius = 0.5 * std::sqrt(2.0 * 2.0 + 2.0 * 2.0);
  EXPECT_NEAR(glm::length(eye(narrow) - centre), radius / std::sin(glm::radians(5.0)), 1e-3);
  EXPECT_GT(glm::length(eye(narrow) - centre), glm::length(eye(wide) - centre));
}

TEST(CameraOverride, NoSceneCameraStartsFromTheFramingCamera) {
  wt::Scene scene = sceneWithCamera({0, 0, 0});
  scene.camera.reset();
  wt::CameraOverride o;
  o.at = glm::dvec3(0, 1, 0);
  wt::applyCameraOverride(scene, o);
  ASSERT_TRUE(scene.camera.has_value());
  expectNear(forward(scene), glm::normalize(glm::dvec3(0, 1, 0) - eye(scene)));
}

void expectRefused(wt::CameraOverride o, const char* option, bool orthographic = false) {
  wt::Scene scene = sceneWithCamera({0, 0, 0});
  scene.camera->orthographic = orthographic;
  try {
    wt::applyCameraOverride(scene, o);
    ADD_FAILURE() << "accepted; expected an error naming " << option;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(option), std::string::npos) << e.what();
  }
}

TEST(CameraOverride, DegenerateCamerasAreRefusedNamingTheOption) {
  wt::CameraOverride same;
  same.from = glm::dvec3(1, 2, 3);
  same.at = glm::dvec3(1, 2, 3);
  expectRefused(same, "--look-at");
  wt::CameraOverride parallelUp;
  parallelUp.at = glm::dvec3(0, 5, 5);
  parallelUp.up = glm::dvec3(0, 1, 0);
  expectRefused(parallelUp, "--up");
  wt::CameraOverride zeroUp;
  zeroUp.up = glm::dvec3(0, 0, 0);
  expectRefused(zeroUp, "--up");
  for (double fov : {0.0, 180.0, -5.0, std::nan("")}) {
    wt::CameraOverride f;
    f.fovDegrees = fov;
    expectRefused(f, "--fov");
  }
  wt::CameraOverride nan;
  nan.from = glm::dvec3(std::nan(""), 0, 0);
  expectRefused(nan, "--look-from");
  wt::CameraOverride frameAndFrom;
  frameAndFrom.frame = true;
  frameAndFrom.from = glm::dvec3(0, 0, 1);
  expectRefused(frameAndFrom, "--frame");
  wt::CameraOverride fovOrtho;
  fovOrtho.fovDegrees = 40.0;
  expectRefused(fovOrtho, "--fov", /*orthographic=*/true);
}

}  // namespace
