// Texture filtering by the path's footprint (kernels/materials/textured.cl):
// a checkerboard plane seen at grazing angles, emitting its texture, against
// the pixel-box integral of the texture computed here by supersampling the
// same camera rays. Filtering must keep the image's mean (mip levels are
// box filters), stay within a stated bias of the box integral per pixel,
// and at one sample per pixel beat point sampling.
#include "render/render_helpers.h"
#include "test_util.h"
#include "texture_helpers.h"

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>

namespace wt {
namespace {

constexpr int kTexels = 64;      // the checker image, 8 x 8 texels per square
constexpr int kSquare = 8;
constexpr float kUvPerWorld = 0.25f;  // the plane's texture coordinates: world x, z times this
constexpr int kWidth = 64, kHeight = 48;

double checkerTexel(int x, int y) { return ((x / kSquare + y / kSquare) % 2) ? 0.9 : 0.1; }

/// Level 0 of the checker, bilinear with repeat, as texture.cl reads it.
double checkerBilinear(double u, double v) {
  double x = u * kTexels - 0.5, y = v * kTexels - 0.5;
  double fx = std::floor(x), fy = std::floor(y);
  double ax = x - fx, ay = y - fy;
  auto at = [](long long i, long long j) {
    return checkerTexel(int(((i % kTexels) + kTexels) % kTexels), int(((j % kTexels) + kTexels) % kTexels));
  };
  long long i = (long long)fx, j = (long long)fy;
  return (1 - ay) * ((1 - ax) * at(i, j) + ax * at(i + 1, j)) + ay * ((1 - ax) * at(i, j + 1) + ax * at(i + 1, j + 1));
}

Scene checkerPlane() {
  const float half = 400.0f;
  Scene scene = test::makeFloor(half, 0.0f, makeMaterial(glm::vec3(0.0f), glm::vec3(1.0f), true));
  for (std::size_t v = 0; v < scene.positions.size(); ++v)
    scene.texcoords[v] = glm::vec2(scene.positions[v].x, scene.positions[v].z) * kUvPerWorld;
  DecodedImage image;
  image.width = image.height = kTexels;
  image.name = "checker";
  for (int y = 0; y < kTexels; ++y)
    for (int x = 0; x < kTexels; ++x) {
      auto c = std::uint8_t(std::lround(checkerTexel(x, y) * 255.0));
      image.rgba8.insert(image.rgba8.end(), {c, c, c, 255});
    }
  // stored values are exactly k/255: the reference reads the same numbers
  test::setMaterialTexture(scene, 0, WT_TEXTURE_SLOT_EMISSIVE, scene.textures.addTexture(scene.textures.addImage(image, false)));
  // a metre above the plane, looking down at 12 degrees: the far half of the image grazes it
  CameraDesc camera;
  camera.yfov = 0.5f;
  camera.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 1.0f, 0.0f),
                                                  glm::vec3(0.0f, 1.0f - std::tan(0.21f), -1.0f), glm::vec3(0, 1, 0)));
  scene.camera = camera;
  return scene;
}

/// The pixel-box integral of what the camera sees: 32 x 32 stratified rays per pixel.
std::vector<double> boxReference(const Scene& scene) {
  // the checker values as stored (rounded to 8 bits)
  WtCamera cam = makeCamera(*scene.camera, kWidth, kHeight);
  glm::dvec3 o(cam.origin.x, cam.origin.y, cam.origin.z), f(cam.forward.x, cam.forward.y, cam.forward.z);
  glm::dvec3 r(cam.right.x, cam.right.y, cam.right.z), up(cam.up.x, cam.up.y, cam.up.z);
  std::vector<double> out(std::size_t(kWidth) * kHeight);
  constexpr int kSub = 32;
  for (int py = 0; py < kHeight; ++py)
    for (int px = 0; px < kWidth; ++px) {
      double sum = 0.0;
      for (int j = 0; j < kSub; ++j)
        for (int i = 0; i < kSub; ++i) {
          double sx = 2.0 * (px + (i + 0.5) / kSub) / kWidth - 1.0;
          double sy = 1.0 - 2.0 * (py + (j + 0.5) / kSub) / kHeight;
          glm::dvec3 d = glm::normalize(f + sx * r + sy * up);
          if (!(d.y < 0.0)) continue;
          double t = -o.y / d.y;
          glm::dvec3 p = o + t * d;
          if (std::fabs(p.x) > 400.0 || std::fabs(p.z) > 400.0) continue;
          sum += std::round(checkerBilinear(p.x * kUvPerWorld, p.z * kUvPerWorld) * 255.0) / 255.0;
        }
      out[std::size_t(py) * kWidth + px] = sum / (kSub * kSub);
    }
  return out;
}

RenderSettings settings(bool footprint, std::uint32_t seed) {
  RenderSettings s;
  s.width = kWidth;
  s.height = kHeight;
  s.maxBounces = 0;
  s.textureFootprint = footprint;
  s.seed = seed;
  return s;
}

double rmse(const Image& img, const std::vector<double>& ref) {
  double sum = 0.0;
  for (std::size_t p = 0; p < ref.size(); ++p) sum += (img.rgb[3 * p] - ref[p]) * (img.rgb[3 * p] - ref[p]);
  return std::sqrt(sum / double(ref.size()));
}

// Converged, filtering keeps the image's mean within its sampling error
// and each pixel within 0.04 of the box integral (10 % of the checker's
// contrast of 0.8, half its amplitude): isotropic trilinear filtering blurs
// a grazing footprint across as much as along, which is the bias allowed.
TEST(TextureFootprint, ConvergedImageKeepsTheBoxFilteredValue) {
  Scene scene = checkerPlane();
  std::vector<double> ref = boxReference(scene);
  Image img = test::render(scene, settings(true, 1), 256);
  double sumImg = 0.0, sumRef = 0.0, varMean = 0.0, worst = 0.0, meanAbs = 0.0;
  for (std::size_t p = 0; p < ref.size(); ++p) {
    sumImg += img.rgb[3 * p];
    sumRef += ref[p];
    varMean += img.rgbVariance[3 * p] / img.samples[p];
    double d = std::fabs(img.rgb[3 * p] - ref[p]);
    meanAbs += d;
    worst = std::max(worst, d - 4.0 * std::sqrt(img.rgbVariance[3 * p] / img.samples[p]));
  }
  const double n = double(ref.size());
  EXPECT_NEAR(sumImg / n, sumRef / n, 4.0 * std::sqrt(varMean) / n + 2e-3) << "the filtered image's mean moved";
  EXPECT_LT(meanAbs / n, 0.02);
  EXPECT_LT(worst, 0.04) << "a pixel beyond the stated bias (less 4 standard errors)";
  if (HasFailure()) {  // the differences (in hundredths) over every other row and fourth column

    for (int y = 0; y < kHeight; y += 2) {
      std::printf("%2d ", y);
      for (int x = 0; x < kWidth; x += 4) std::printf("%+4.0f", 100 * (img.rgb[3 * (y * kWidth + x)] - ref[y * kWidth + x]));
      std::printf("   ref %.3f img %.3f\n", ref[y * kWidth + 32], img.rgb[3 * (y * kWidth + 32)]);
    }
  }
}

// At one sample per pixel the footprint's level is the better estimate of the
// pixel's box integral than a point on the finest level, over several seeds.
TEST(TextureFootprint, TexelsReadInPlaceGiveTheSameImage) {
  // RenderSettings::sceneOutlivesRenderer lets a CPU device read the scene's
  // texels where they are: the same numbers, so the same image bit for bit
  const Scene scene = checkerPlane();
  RenderSettings s = settings(true, 1);
  const Image copied = test::render(scene, s, 2);
  s.sceneOutlivesRenderer = true;
  const Image inPlace = test::render(scene, s, 2);
  ASSERT_EQ(copied.rgb.size(), inPlace.rgb.size());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < copied.rgb.size(); ++i) differing += copied.rgb[i] != inPlace.rgb[i];
  EXPECT_EQ(differing, 0u) << "of " << copied.rgb.size() << " values";
}

TEST(TextureFootprint, OneSampleErrorBelowPointSampling) {
  Scene scene = checkerPlane();
  std::vector<double> ref = boxReference(scene);
  double filtered = 0.0, point = 0.0;
  for (std::uint32_t seed = 1; seed <= 4; ++seed) {
    filtered += rmse(test::render(scene, settings(true, seed), 1), ref);
    point += rmse(test::render(scene, settings(false, seed), 1), ref);
  }
  EXPECT_LT(filtered, 0.8 * point) << "filtered " << filtered / 4 << ", point sampled " << point / 4;
}

}  // namespace
}  // namespace wt
