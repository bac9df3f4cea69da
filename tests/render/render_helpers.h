// Shared pieces of the render tests: scenes built in code, a render call and
// a statistical comparison of two images by regions.
#pragma once

#include "device_fixture.h"
#include "render/renderer.h"
#include "scene/generators.h"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

namespace wt::test {

inline Image render(const Scene& scene, RenderSettings settings, int spp) {
  Renderer renderer(deviceContext(), scene, settings);
  for (int s = 0; s < spp; ++s) renderer.renderSample();
  Image image = renderer.readImage();
  EXPECT_EQ(renderer.stats().nonFiniteSamples, 0u);
  return image;
}

/// Two quads (four triangles) spanning [-half, half]^2 in the y = height plane.
inline Scene makeFloor(float half, float height, const WtMaterial& material, bool faceDown = false) {
  Scene scene;
  glm::vec3 corners[4] = {{-half, height, -half}, {half, height, -half}, {half, height, half}, {-half, height, half}};
  for (const glm::vec3& c : corners) {
    scene.positions.push_back({c.x, c.y, c.z, 0});
    scene.normals.push_back({0, 0, 0, 0});
    scene.texcoords.emplace_back(0.0f);
  }
  if (faceDown) {
    scene.triangles.push_back({0, 1, 2, 0});
    scene.triangles.push_back({0, 2, 3, 0});
  } else {
    scene.triangles.push_back({0, 2, 1, 0});
    scene.triangles.push_back({0, 3, 2, 0});
  }
  scene.materials.push_back(material);
  scene.materialNames.push_back("floor");
  return scene;
}

/// An orthographic camera at `eye` looking straight down, seeing 2*ymag across.
inline CameraDesc topDownCamera(glm::vec3 eye, float ymag) {
  CameraDesc c;
  c.orthographic = true;
  c.ymag = c.xmag = ymag;
  // camera -Z along world -Y, camera +Y along world -Z
  c.cameraToWorld = glm::mat4(glm::vec4(1, 0, 0, 0), glm::vec4(0, 0, -1, 0), glm::vec4(0, 1, 0, 0),
                              glm::vec4(eye, 1));
  return c;
}

/// Mean of a channel over a pixel block and the variance of that mean,
/// from the per-pixel sample variances.
struct BlockStat {
  double mean = 0.0, varianceOfMean = 0.0;
};

inline BlockStat blockStat(const Image& img, int x0, int y0, int x1, int y1, int channel) {
  BlockStat s;
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x, ++n) {
      std::size_t p = std::size_t(y) * img.width + x;
      s.mean += img.rgb[3 * p + channel];
      s.varianceOfMean += img.rgbVariance[3 * p + channel] / std::max<std::uint32_t>(img.samples[p], 1);
    }
  s.mean /= n;
  s.varianceOfMean /= double(n) * n;
  return s;
}

/// Every pixel's mean is `expected` within `zLimit` standard errors (from the
/// pixel's own variance) plus a relative float allowance and 1e-7.
inline void expectUniform(const Image& img, glm::dvec3 expected, double relFloat, double zLimit,
                          const std::string& what) {
  int bad = 0;
  for (std::size_t p = 0; p < img.samples.size(); ++p)
    for (int c = 0; c < 3; ++c) {
      double mean = img.rgb[3 * p + c];
      double se = std::sqrt(img.rgbVariance[3 * p + c] / img.samples[p]);
      double tol = zLimit * se + relFloat * std::abs(expected[c]) + 1e-7;
      if (std::abs(mean - expected[c]) > tol && ++bad <= 5)
        ADD_FAILURE() << what << ": pixel " << p << " channel " << c << ": " << mean << " vs " << expected[c]
                      << " (tolerance " << tol << ")";
    }
  EXPECT_EQ(bad, 0) << what;
}

/// Compare two renders of the same scene region by region: each block's
/// channel means must agree within `zLimit` standard errors of their
/// difference. Returns the largest |z| seen (for diagnostics).
inline double expectSameImage(const Image& a, const Image& b, int blocks, double zLimit,
                              const std::string& what) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  double worst = 0.0;
  int failures = 0;
  for (int by = 0; by < blocks; ++by)
    for (int bx = 0; bx < blocks; ++bx)
      for (int c = 0; c < 3; ++c) {
        int x0 = bx * a.width / blocks, x1 = (bx + 1) * a.width / blocks;
        int y0 = by * a.height / blocks, y1 = (by + 1) * a.height / blocks;
        BlockStat sa = blockStat(a, x0, y0, x1, y1, c), sb = blockStat(b, x0, y0, x1, y1, c);
        double se = std::sqrt(sa.varianceOfMean + sb.varianceOfMean);
        double diff = sa.mean - sb.mean;
        if (se == 0.0) {
          EXPECT_NEAR(sa.mean, sb.mean, 1e-5 * std::max(1.0, std::abs(sb.mean))) << what;
          continue;
        }
        double z = diff / se;
        worst = std::max(worst, std::abs(z));
        if (std::abs(z) > zLimit && ++failures <= 5)
          ADD_FAILURE() << what << ": block (" << bx << "," << by << ") channel " << c << ": "
                        << sa.mean << " vs " << sb.mean << " (z = " << z << ", standard error " << se << ")";
      }
  EXPECT_EQ(failures, 0) << what;
  return worst;
}

/// The scene the tests that render one sphere in several representations
/// share: a grey floor, the unit ball at the origin as `addBall` places it
/// (material and geometry), a small sphere light above, seen from the front.
inline Scene ballOnFloor(const std::function<void(Scene&)>& addBall) {
  Scene s = makeFloor(4.0f, -1.0f, makeMaterial(glm::vec3(0.6f)));
  addBall(s);
  s.materials.push_back(makeMaterial(glm::vec3(0.0f), glm::vec3(30.0f)));
  s.materialNames.push_back("light");
  s.spheres.push_back({glm::vec3(1.5f, 2.5f, 1.0f), 0.3f, std::uint32_t(s.materials.size() - 1)});
  CameraDesc camera;
  camera.cameraToWorld =
      glm::inverse(glm::lookAt(glm::vec3(0.0f, 1.0f, 4.0f), glm::vec3(0.0f, -0.2f, 0.0f), glm::vec3(0, 1, 0)));
  s.camera = camera;
  return s;
}

/// Two ballOnFloor scenes render the same 32x32 image within noise (256
/// samples each, independent seeds, 4x4 blocks at z 4.5).
inline void expectSameBallImage(const Scene& a, const Scene& b, const std::string& what) {
  RenderSettings settings;
  settings.width = settings.height = 32;
  settings.maxBounces = 3;
  settings.background = glm::vec3(0.05f);
  settings.seed = 5;
  const Image first = render(a, settings, 256);
  settings.seed = 6;
  const Image second = render(b, settings, 256);
  expectSameImage(first, second, 4, 4.5, what);
}

}  // namespace wt::test
