// The two integrators against closed forms and against each other: `path`
// (NEE, MIS, Russian roulette) must converge to what `minimal` converges to.
#include "render/render_helpers.h"
#include "scene/default_scene.h"
#include "test_util.h"

#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <numbers>
#include <filesystem>

#include <stb_image_write.h>

namespace wt {
namespace {

using test::expectSameImage;
using test::expectUniform;
using test::render;

RenderSettings small(Integrator integrator, int size = 16) {
  RenderSettings s;
  s.width = s.height = size;
  s.integrator = integrator;
  s.seed = 11;
  return s;
}


// ---- analytic lights -------------------------------------------------------------

Scene floorUnder(PunctualLight light, float albedo) {
  Scene scene = test::makeFloor(10.0f, 0.0f, makeMaterial(glm::vec3(albedo)));
  scene.lights.push_back(light);
  return scene;
}

TEST(Integrators, PointLightInverseSquare) {
  const float albedo = 0.6f, h = 2.5f;
  PunctualLight light;
  light.type = WT_LIGHT_POINT;
  light.position = {0.0f, h, 0.0f};
  light.intensity = {3.0f, 2.0f, 1.0f};
  Scene scene = floorUnder(light, albedo);
  // a footprint of 2e-3 h: radiance varies by < 1e-6 across it
  scene.camera = test::topDownCamera({0.0f, 1.0f, 0.0f}, 1e-3f * h);
  glm::vec3 expected = albedo / std::numbers::pi_v<float> * light.intensity / (h * h);
  for (Integrator integrator : {Integrator::Minimal, Integrator::Path}) {
    RenderSettings s = small(integrator, 8);
    s.maxBounces = 1;
    expectUniform(render(scene, s, 4), expected, 1e-5, 0.0, "point light");
  }
}

TEST(Integrators, SpotLightConeFalloff) {
  const float albedo = 0.5f, h = 2.0f;
  PunctualLight light;
  light.type = WT_LIGHT_SPOT;
  light.position = {0.0f, h, 0.0f};
  light.direction = {0.0f, -1.0f, 0.0f};
  light.intensity = glm::vec3(10.0f);
  light.innerConeAngle = 0.3f;
  light.outerConeAngle = 0.5f;
  Scene scene = floorUnder(light, albedo);
  // look at a point 0.4 rad off the axis: between the cones
  const float theta = 0.4f, x = h * std::tan(theta), d2 = h * h + x * x;
  scene.camera = test::topDownCamera({x, 1.0f, 0.0f}, 1e-6f);
  float t = (std::cos(theta) - std::cos(0.5f)) / (std::cos(0.3f) - std::cos(0.5f));
  glm::vec3 expected = albedo / std::numbers::pi_v<float> * light.intensity * (t * t) * (h / std::sqrt(d2)) / d2;
  for (Integrator integrator : {Integrator::Minimal, Integrator::Path}) {
    RenderSettings s = small(integrator, 4);
    s.maxBounces = 1;
    expectUniform(render(scene, s, 2), expected, 2e-4, 0.0, "spot light");
  }
}

TEST(Integrators, DirectionalLightCosine) {
  const float albedo = 0.8f, angle = 0.7f;
  PunctualLight light;
  light.type = WT_LIGHT_DIRECTIONAL;
  light.direction = glm::normalize(glm::vec3(std::sin(angle), -std::cos(angle), 0.0f));
  light.intensity = glm::vec3(2.0f);
  Scene scene = floorUnder(light, albedo);
  scene.camera = test::topDownCamera({0.0f, 1.0f, 0.0f}, 0.5f);
  glm::vec3 expected = albedo / std::numbers::pi_v<float> * light.intensity * std::cos(angle);
  for (Integrator integrator : {Integrator::Minimal, Integrator::Path}) {
    RenderSettings s = small(integrator, 8);
    s.maxBounces = 1;
    expectUniform(render(scene, s, 2), expected, 1e-5, 0.0, "directional light");
  }
}

// ---- area light: a square emitter over a plane point ----------------------------

/// Irradiance at the origin (normal +y) from a polygon of uniform radiance L
/// (Lambert's formula: E = L/2 * sum over edges of angle * cos to the normal).
double polygonIrradiance(const std::vector<glm::dvec3>& poly, double radiance) {
  double sum = 0.0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    glm::dvec3 a = glm::normalize(poly[i]), b = glm::normalize(poly[(i + 1) % poly.size()]);
    double angle = std::acos(glm::clamp(glm::dot(a, b), -1.0, 1.0));
    glm::dvec3 g = glm::normalize(glm::cross(a, b));
    sum += angle * g.y;
  }
  return 0.5 * radiance * std::abs(sum);
}

TEST(Integrators, SquareEmitterIrradianceMatchesClosedForm) {
  // heights from grazing (0.1: the light's edge is seen at a few degrees,
  // where shadow rays once hit the light itself) to far
  for (float h : {0.1f, 1.0f, 3.0f}) {
    const float albedo = 0.5f, half = 0.5f, le = 4.0f;
    Scene scene = test::makeFloor(20.0f, 0.0f, makeMaterial(glm::vec3(albedo)));
    Scene lamp = test::makeFloor(half, h, makeMaterial(glm::vec3(0.0f), glm::vec3(le)), /*faceDown=*/true);
    // shift the lamp off-centre so the closed form is not symmetric; at
    // h = 0.1 the point below sits outside the lamp's footprint, lit at grazing angles
    const float shift = h < 0.5f ? 0.7f : 0.3f;
    for (WtVec4& p : lamp.positions) p.x += shift;
    appendScene(scene, lamp);
    scene.camera = test::topDownCamera({0.0f, 0.5f * h, 0.0f}, 1e-4f);
    std::vector<glm::dvec3> poly = {{-half + shift, h, -half}, {half + shift, h, -half}, {half + shift, h, half}, {-half + shift, h, half}};
    double expected = albedo / std::numbers::pi * polygonIrradiance(poly, le);
    // path on shade's lanes and on one path per work-item: the Lambertian floor weighs by the
    // power heuristic (auto), so both sides of its MIS must agree on it in each
    for (auto [integrator, lanes] : {std::pair{Integrator::Minimal, true}, std::pair{Integrator::Path, true},
                                     std::pair{Integrator::Path, false}}) {
      RenderSettings s = small(integrator, 8);
      s.maxBounces = 1;
      s.shadeLanes = lanes;
      Image img = render(scene, s, integrator == Integrator::Minimal ? 512 : 64);
      test::BlockStat all = test::blockStat(img, 0, 0, img.width, img.height, 1);
      const char* name = integrator == Integrator::Minimal ? "minimal" : lanes ? "path" : "path, one path per work-item";
      EXPECT_NEAR(all.mean, expected, 5.0 * std::sqrt(all.varianceOfMean) + 1e-3 * expected) << name << " h=" << h;
      EXPECT_LT(std::sqrt(all.varianceOfMean), 0.03 * expected) << "too few samples to test anything: " << name << " h=" << h;
    }
  }
}

// ---- environment: the furnace ------------------------------------------------------

TEST(Integrators, ConvexDiffuseSphereUnderUniformSkyReflectsItsAlbedo) {
  // A convex object never sees itself: one bounce to the sky, radiance a * L.
  const float albedo = 0.7f;
  Scene scene = makeIcosphere(3, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(albedo)));
  for (WtVec4& n : scene.normals) n = {0, 0, 0, 0};
  CameraDesc cam;
  cam.cameraToWorld = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, 4.0f));
  cam.yfov = 0.2f;  // the sphere fills the frame
  scene.camera = cam;
  for (Integrator integrator : {Integrator::Minimal, Integrator::Path}) {
    RenderSettings s = small(integrator, 8);
    s.background = glm::vec3(1.0f, 0.5f, 0.25f);
    s.maxBounces = 4;
    Image img = render(scene, s, 64);
    expectUniform(img, albedo * s.background, 1e-4, 5.0, "furnace");
  }
}

// White metallic-roughness spheres reflect everything at every roughness:
// the energy compensation's job. Tolerance: 5 standard errors plus 1% for
// the albedo table's interpolation (measured below 0.6% but at the most
// grazing angles, tests/kernels/test_bsdf.cpp).
TEST(Integrators, WhitePbrSpheresUnderAUniformSkyReflectEverything) {
  for (auto [metallic, roughness] : {std::pair{0.0f, 0.3f}, std::pair{0.0f, 1.0f}, std::pair{1.0f, 0.0f},
                                     std::pair{1.0f, 0.5f}, std::pair{1.0f, 1.0f}}) {
    Scene scene = makeIcosphere(3, glm::vec3(0.0f), 1.0f, makePbrMaterial(glm::vec3(1.0f), metallic, roughness));
    for (WtVec4& n : scene.normals) n = {0, 0, 0, 0};
    CameraDesc cam;
    cam.cameraToWorld = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, 4.0f));
    cam.yfov = 0.2f;
    scene.camera = cam;
    for (Integrator integrator : {Integrator::Minimal, Integrator::Path}) {
      RenderSettings s = small(integrator, 8);
      s.background = glm::vec3(1.0f, 0.5f, 0.25f);
      s.maxBounces = 4;
      Image img = render(scene, s, 128);
      expectUniform(img, s.background, 0.01, 5.0,
                    "white PBR, metallic " + std::to_string(metallic) + ", roughness " + std::to_string(roughness));
    }
  }
}

// The same through the renderer for the layers (compiled in from the
// scene's materials): white spheres under a clear coat, a white sheen, a
// tinted and weighted F0 of a denser ior, all three at once, keep all the
// sky's light; and specularFactor 0 leaves a Lambertian sphere that shows
// its base colour times the sky.
TEST(Integrators, WhiteLayeredSpheresUnderAUniformSkyReflectEverything) {
  WtMaterial tinted = withSpecular(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.4f), 0.7f, glm::vec3(1.0f, 0.5f, 0.25f));
  tinted.ior = 2.0f;
  const std::pair<WtMaterial, const char*> cases[] = {
      {withClearcoat(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.6f), 1.0f, 0.2f), "clear coat over a dielectric"},
      {withClearcoat(makePbrMaterial(glm::vec3(1.0f), 1.0f, 0.3f), 0.8f, 0.0f), "mirror coat over a metal"},
      {withSheen(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.8f), glm::vec3(1.0f), 0.5f), "white sheen"},
      {tinted, "tinted specular, ior 2"},
      {withSheen(withClearcoat(tinted, 0.6f, 0.3f), glm::vec3(1.0f), 0.7f), "all layers"},
  };
  for (const auto& [material, name] : cases) {
    Scene scene = makeIcosphere(3, glm::vec3(0.0f), 1.0f, material);
    for (WtVec4& n : scene.normals) n = {0, 0, 0, 0};
    CameraDesc cam;
    cam.cameraToWorld = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, 4.0f));
    cam.yfov = 0.2f;
    scene.camera = cam;
    RenderSettings s = small(Integrator::Path, 8);
    s.background = glm::vec3(1.0f, 0.5f, 0.25f);
    s.maxBounces = 4;
    expectUniform(render(scene, s, test::testSize(128, 32)), s.background, 0.01, 5.0, name);
  }
  const glm::vec3 base(0.8f, 0.5f, 0.2f);
  Scene lambert = makeIcosphere(3, glm::vec3(0.0f), 1.0f, withSpecular(makePbrMaterial(base, 0.0f, 0.3f), 0.0f));
  for (WtVec4& n : lambert.normals) n = {0, 0, 0, 0};
  CameraDesc cam;
  cam.cameraToWorld = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, 4.0f));
  cam.yfov = 0.2f;
  lambert.camera = cam;
  RenderSettings s = small(Integrator::Path, 8);
  s.background = glm::vec3(1.0f);
  s.maxBounces = 1;
  s.lambertianForms = false;  // the general model's specular 0 (the renderer would hand it over as Lambertian)
  expectUniform(render(lambert, s, 64), base, 0.01, 5.0, "specular 0: a Lambertian sphere");
  // and the layers are compiled in where a scene has them: a base that
  // reflects nothing stays black; over it, the coat alone (the sphere's
  // x < 0 half) and the sheen alone (x > 0) still light the sphere. One
  // scene for both: its program is the "all layers" case's.
  const WtMaterial black = withSpecular(makePbrMaterial(glm::vec3(0.0f), 0.0f, 0.5f), 0.0f);
  Scene layer = lambert;
  layer.materials[0] = black;
  Image img = render(layer, s, 16);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(test::blockStat(img, 0, 0, img.width, img.height, c).mean, 0.0) << "nothing";
  layer.materials[0] = withClearcoat(black, 1.0f, 0.3f);
  layer.materials.push_back(withSheen(black, glm::vec3(1.0f), 0.5f));
  layer.materialNames.push_back("sheen alone");
  for (WtTriangle& t : layer.triangles)
    if (layer.positions[t.v0].x + layer.positions[t.v1].x + layer.positions[t.v2].x > 0.0f) t.material = 1;
  img = render(layer, s, 16);
  // the columns at the seam (x = 0 is the image's middle) see both halves
  for (auto [x0, name] : {std::pair{0, "coat alone"}, std::pair{img.width - 3, "sheen alone"}})
    for (int c = 0; c < 3; ++c)
      EXPECT_GT(test::blockStat(img, x0, 0, x0 + 3, img.height, c).mean, 0.02) << name << ", channel " << c;
}

// KHR_materials_anisotropy through the renderer: the scene's tangents
// (around the view axis) reach the shading frame (a frame broken to NaN
// turns the sphere black), and a white anisotropic sphere under a uniform
// sky never shows more than the sky (5 standard errors and 1% per pixel),
// and is not black. The grazing views where the anisotropic tables'
// interpolation errs most are too thin a rim at this size to catch an
// energy gain or loss: Bsdf.WhiteAnisotropicMaterialsReflectEverything
// does that.
TEST(Integrators, WhiteAnisotropicSpheresUnderAUniformSkyReflectAtMostTheSky) {
  const std::pair<WtMaterial, const char*> cases[] = {
      {withAnisotropy(makePbrMaterial(glm::vec3(1.0f), 1.0f, 0.3f), 0.8f, 0.4f), "anisotropic metal"},
      {withAnisotropy(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.1f), 0.7f, 0.0f), "anisotropic dielectric"},
  };
  for (const auto& [material, name] : cases) {
    Scene scene = makeIcosphere(3, glm::vec3(0.0f), 1.0f, material);
    for (WtVec4& n : scene.normals) n = {0, 0, 0, 0};
    scene.tangents.clear();
    for (const WtVec4& p : scene.positions) {
      glm::vec3 t(-p.y, p.x, 0.0f);  // around the view axis: the limb is seen along the bitangent (zero at the poles)
      float len = glm::length(t);
      scene.tangents.push_back(len > 1e-6f ? glm::vec4(t / len, 1.0f) : glm::vec4(0.0f));
    }
    CameraDesc cam;
    cam.cameraToWorld = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, 4.0f));
    cam.yfov = 0.2f;
    scene.camera = cam;
    RenderSettings s = small(Integrator::Path, 8);
    s.background = glm::vec3(1.0f, 0.5f, 0.25f);
    s.maxBounces = 4;
    Image img = render(scene, s, 128);
    int over = 0;
    double mean = 0.0;
    for (std::size_t p = 0; p < img.samples.size(); ++p)
      for (int c = 0; c < 3; ++c) {
        double v = img.rgb[3 * p + c], se = std::sqrt(img.rgbVariance[3 * p + c] / img.samples[p]);
        mean += v / s.background[c] / double(3 * img.samples.size());
        if (v > s.background[c] * 1.01 + 5.0 * se + 1e-7 && ++over <= 5)
          ADD_FAILURE() << name << ": pixel " << p << " channel " << c << ": " << v << " over the sky " << s.background[c];
      }
    EXPECT_EQ(over, 0) << name;
    EXPECT_GT(mean, 0.5) << name << ": the sphere keeps half the sky at least";
  }
}

// Per-lobe bounce limits cut paths exactly where the total limit would: on
// a Lambertian scene two diffuse bounces are two bounces, bit for bit; with
// no lobe left, a glossy scene shows emission only, as with no bounces.
TEST(Integrators, LobeBounceLimitsCutPathsWhereTheySay) {
  Scene lambert = test::makeFloor(2.0f, 0.0f, makeMaterial(glm::vec3(0.6f)));
  appendScene(lambert, makeIcosphere(2, glm::vec3(0.0f, 0.5f, 0.0f), 0.5f, makeMaterial(glm::vec3(0.4f, 0.7f, 0.3f))));
  CameraDesc cam;
  cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 1.5f, 3.0f), glm::vec3(0.0f, 0.3f, 0.0f), glm::vec3(0, 1, 0)));
  lambert.camera = cam;
  for (Integrator integrator : {Integrator::Minimal, Integrator::Path}) {
    RenderSettings total = small(integrator, 16);
    total.background = glm::vec3(0.4f, 0.5f, 0.7f);
    total.maxBounces = 2;
    RenderSettings diffuse = total;
    diffuse.maxBounces = 8;
    diffuse.maxDiffuseBounces = 2;
    EXPECT_EQ(render(lambert, total, 4).rgb, render(lambert, diffuse, 4).rgb);
  }
  Scene glossy = lambert;
  glossy.materials[0] = makePbrMaterial(glm::vec3(0.6f), 0.0f, 0.4f, glm::vec3(0.3f));
  glossy.materials[1] = makePbrMaterial(glm::vec3(0.9f, 0.6f, 0.3f), 1.0f, 0.2f);
  RenderSettings none = small(Integrator::Path, 16);
  none.background = glm::vec3(0.4f, 0.5f, 0.7f);
  none.maxBounces = 0;
  RenderSettings noLobes = none;
  noLobes.maxBounces = 8;
  noLobes.maxDiffuseBounces = noLobes.maxSpecularBounces = 0;
  EXPECT_EQ(render(glossy, none, 4).rgb, render(glossy, noLobes, 4).rgb);
  // and specular bounces alone: a mirror sphere without them is black
  Scene mirror = makeIcosphere(3, glm::vec3(0.0f), 1.0f, makePbrMaterial(glm::vec3(1.0f), 1.0f, 0.0f));
  CameraDesc close;
  close.cameraToWorld = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, 4.0f));
  close.yfov = 0.2f;
  mirror.camera = close;
  RenderSettings sky = small(Integrator::Path, 8);
  sky.background = glm::vec3(1.0f);
  sky.maxSpecularBounces = 0;
  for (float v : render(mirror, sky, 4).rgb) EXPECT_EQ(v, 0.0f);
  sky.maxSpecularBounces = 1;
  expectUniform(render(mirror, sky, 4), glm::vec3(1.0f), 1e-4, 5.0, "a white mirror shows the sky");
}

// ---- path against minimal ----------------------------------------------------------

/// Renders with `minimal` (the settings given) and with `path`, and requires
/// the two images to agree; with `checkPower`, each must also be precise
/// enough that a 5 % bias over the image would be many standard errors.
void expectPathMatchesMinimal(const Scene& scene, const RenderSettings& minimal, int minimalSpp, int pathSpp,
                              const char* what, bool checkPower) {
  Image reference = render(scene, minimal, minimalSpp);
  RenderSettings p = minimal;
  p.integrator = Integrator::Path;
  Image img = render(scene, p, pathSpp);
  expectSameImage(reference, img, 4, 5.0, what);
  if (!checkPower) return;
  for (const Image* i : {&reference, &img}) {
    test::BlockStat all = test::blockStat(*i, 0, 0, i->width, i->height, 1);
    EXPECT_LT(std::sqrt(all.varianceOfMean), 0.01 * all.mean) << what;
  }
}

TEST(Integrators, PathMatchesMinimalOnCornell) {
  Scene scene = loadDefaultScene();
  RenderSettings s = small(Integrator::Minimal, 16);
  s.maxBounces = 4;
  // (the z test scales with the renders' variances: a quarter of the samples in the sanitizer pass)
  Image reference = render(scene, s, test::testSize(768, 192));
  for (auto [nee, mis, rr, label] : {std::tuple{true, true, true, "path"}, std::tuple{true, false, false, "NEE only"},
                                     std::tuple{false, false, true, "BSDF only + RR"},
                                     std::tuple{true, true, false, "NEE+MIS, no RR"}}) {
    RenderSettings p = s;
    p.integrator = Integrator::Path;
    p.useNee = nee, p.useMis = mis, p.useRussianRoulette = rr;
    p.rrMinDepth = 1;
    Image img = render(scene, p, nee ? test::testSize(128, 32) : test::testSize(768, 192));
    expectSameImage(reference, img, 4, 5.0, label);
  }
}

TEST(Integrators, PathMatchesMinimalWithAnalyticLightsAndSky) {
  // a floor and a wall, lit by a point, a spot and the sky
  Scene scene = test::makeFloor(2.0f, 0.0f, makeMaterial(glm::vec3(0.6f, 0.5f, 0.4f)));
  Scene wall = test::makeFloor(1.0f, 0.0f, makeMaterial(glm::vec3(0.3f, 0.7f, 0.3f)));
  for (WtVec4& p : wall.positions) std::swap(p.y, p.z), p.y += 1.0f, p.z -= 1.0f;
  appendScene(scene, wall);
  PunctualLight point;
  point.type = WT_LIGHT_POINT;
  point.position = {0.5f, 1.0f, 0.5f};
  point.intensity = {2.0f, 2.0f, 1.5f};
  PunctualLight spot;
  spot.type = WT_LIGHT_SPOT;
  spot.position = {-0.7f, 1.5f, 0.2f};
  spot.direction = glm::normalize(glm::vec3(0.3f, -1.0f, -0.2f));
  spot.intensity = glm::vec3(6.0f);
  spot.innerConeAngle = 0.2f;
  spot.outerConeAngle = 0.6f;
  scene.lights = {point, spot};
  CameraDesc cam;
  cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 2.0f, 3.0f), glm::vec3(0.0f, 0.3f, 0.0f), glm::vec3(0, 1, 0)));
  scene.camera = cam;
  RenderSettings s = small(Integrator::Minimal, 16);
  s.maxBounces = 3;
  s.background = glm::vec3(0.2f, 0.3f, 0.5f);
  expectPathMatchesMinimal(scene, s, 256, 256, "analytic lights and sky", false);
}

// Glossy surfaces: a rough dielectric floor, a gold sphere, a rougher steel
// one and a mirror, lit by a point light, a spot, a small emitter and the
// sky; minimal finds the emitter and the sky by BSDF sampling alone. (Point
// lights in the highlights of much smoother GGX make fireflies in both
// integrators, whose noise would hide a 5% bias from this test.)
TEST(Integrators, PathMatchesMinimalOnGlossySurfaces) {
  Scene scene = test::makeFloor(2.0f, 0.0f, makePbrMaterial(glm::vec3(0.6f, 0.5f, 0.4f), 0.0f, 0.35f));
  appendScene(scene, makeIcosphere(2, glm::vec3(-0.5f, 0.45f, 0.0f), 0.45f,
                                   makePbrMaterial(glm::vec3(1.0f, 0.78f, 0.34f), 1.0f, 0.35f)));
  appendScene(scene, makeIcosphere(2, glm::vec3(0.55f, 0.4f, 0.2f), 0.4f,
                                   makePbrMaterial(glm::vec3(0.56f, 0.57f, 0.58f), 1.0f, 0.45f)));
  appendScene(scene, makeIcosphere(2, glm::vec3(0.1f, 0.2f, 0.7f), 0.2f,
                                   makePbrMaterial(glm::vec3(0.95f), 1.0f, 0.0f)));  // a mirror
  Scene emitter = test::makeFloor(0.3f, 1.6f, makeMaterial(glm::vec3(0.0f), glm::vec3(6.0f)), /*faceDown=*/true);
  appendScene(scene, emitter);
  PunctualLight point;
  point.type = WT_LIGHT_POINT;
  point.position = {1.2f, 2.5f, 1.8f};
  point.intensity = {4.0f, 4.0f, 3.0f};
  PunctualLight spot;
  spot.type = WT_LIGHT_SPOT;
  spot.position = {1.2f, 1.5f, -0.8f};
  spot.direction = glm::normalize(glm::vec3(0.0f, -1.0f, -0.3f));
  spot.intensity = glm::vec3(4.0f);
  spot.innerConeAngle = 0.2f;
  spot.outerConeAngle = 0.5f;
  scene.lights = {point, spot};
  CameraDesc cam;
  cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 1.2f, 2.8f), glm::vec3(0.0f, 0.4f, 0.0f), glm::vec3(0, 1, 0)));
  scene.camera = cam;
  RenderSettings s = small(Integrator::Minimal, 16);
  s.maxBounces = 3;
  s.background = glm::vec3(0.2f, 0.3f, 0.5f);
  expectPathMatchesMinimal(scene, s, 4096, 1024, "glossy surfaces", true);
}

TEST(Integrators, SobolSamplerConvergesToTheSameImage) {
  Scene scene = loadDefaultScene();
  RenderSettings s = small(Integrator::Path, 16);
  s.maxBounces = 3;
  Image independent = render(scene, s, 128);
  s.sobol = true;
  Image sobol = render(scene, s, 128);
  // Sobol's error is lower than its sample variance suggests: the test errs on the safe side
  expectSameImage(independent, sobol, 4, 5.0, "independent vs Sobol");
}

TEST(Integrators, PathMatchesMinimalUnderAnEnvironmentMap) {
  // a map with a small hot spot over a dim gradient: importance sampling matters
  const int w = 64, h = 32;
  std::vector<float> rgb(3 * w * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float* p = &rgb[3 * (y * w + x)];
      p[0] = 0.2f + 0.3f * float(y) / h, p[1] = 0.3f, p[2] = 0.5f - 0.3f * float(y) / h;
      if (x >= 20 && x < 24 && y >= 8 && y < 12) p[0] = p[1] = p[2] = 30.0f;
    }
  std::filesystem::path map = test::scratchDir("integrators") / "hotspot.hdr";
  ASSERT_TRUE(stbi_write_hdr(map.c_str(), w, h, 3, rgb.data()));

  Scene scene = test::makeFloor(3.0f, 0.0f, makeMaterial(glm::vec3(0.7f)));
  appendScene(scene, makeIcosphere(2, glm::vec3(0.0f, 0.6f, 0.0f), 0.6f, makeMaterial(glm::vec3(0.5f, 0.6f, 0.8f))));
  CameraDesc cam;
  cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 1.5f, 3.5f), glm::vec3(0.0f, 0.4f, 0.0f), glm::vec3(0, 1, 0)));
  scene.camera = cam;
  RenderSettings s = small(Integrator::Minimal, 16);
  s.maxBounces = 3;
  s.environmentMap = map.string();
  s.environmentRotationDegrees = 30.0f;
  expectPathMatchesMinimal(scene, s, 2048, 256, "environment map", true);
}

TEST(Integrators, MisHeuristicsAgree) {
  Scene scene = loadDefaultScene();
  RenderSettings s = small(Integrator::Path, 16);
  s.maxBounces = 3;
  s.powerAtLambertian = false;
  Image balance = render(scene, s, 128);
  s.powerHeuristic = true;
  s.seed = 12;
  Image power = render(scene, s, 128);
  expectSameImage(balance, power, 4, 5.0, "balance vs power heuristic");
}

}  // namespace
}  // namespace wt
