// The scene's feature set (host/render/feature_set.h): scenes made to hold
// exactly one feature yield exactly that feature; the switches never depend
// on the image size or the sample count; and the specialised program renders
// the same image as the general one (every switch on).
#include "output/image_io.h"
#include "core/embedded.h"
#include "render/feature_set.h"
#include "render/render_helpers.h"
#include "scene/default_scene.h"
#include "scene/generators.h"
#include "scene/sdf_volume.h"
#include "test_util.h"
#include "texture_helpers.h"

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <set>

namespace wt {
namespace {

using Names = std::set<std::string>;

/// The feature set of `scene` with `settings`, as the renderer derives it.
Names featuresOf(const Scene& scene, const RenderSettings& settings) {
  BvhBuildOptions options;
  options.maxLeafSize = 0;
  options.instancing = settings.instancing;
  SceneBuffers buffers(test::deviceContext(), scene, options);
  std::vector<std::string> names = featureNames(sceneFeatures(scene, buffers, settings));
  return Names(names.begin(), names.end());
}

/// Two Lambertian triangles and nothing else: the base every case adds one feature to.
Scene lambertFloor() { return test::makeFloor(1.0f, 0.0f, makeMaterial(glm::vec3(0.5f))); }
Scene pbrFloor() { return test::makeFloor(1.0f, 0.0f, makePbrMaterial(glm::vec3(0.5f), 0.0f, 0.5f)); }

const Names kPath = {"path_integrator", "nee", "mis", "russian_roulette", "independent_sampler"};
Names with(Names base, std::initializer_list<const char*> more) {
  for (const char* m : more) base.insert(m);
  return base;
}
Names lambertBase() { return with(kPath, {"triangles", "lambertian"}); }
Names pbrBase() { return with(kPath, {"triangles", "pbr"}); }

struct OneFeature {
  const char* name;
  std::function<Scene()> scene;
  std::function<void(RenderSettings&)> settings;
  std::function<Names()> expected;
};

void noSettings(RenderSettings&) {}

std::filesystem::path tinyEnvironmentMap() {
  const std::filesystem::path path = std::filesystem::path(WT_TEST_BINARY_DIR) / "feature_set_env.exr";
  Image image;
  image.width = 4, image.height = 2;
  image.rgb.assign(4 * 2 * 3, 0.5f);
  image.rgbVariance.assign(image.rgb.size(), 0.0f);
  image.samples.assign(8, 1u);
  image.srgba.assign(8 * 4, 255);
  writeImage(path, image);
  return path;
}

const OneFeature kCases[] = {
    {"triangle_only_lambertian", lambertFloor, noSettings, lambertBase},
    {"sphere",
     [] {
       Scene s = lambertFloor();
       s.spheres.push_back({glm::vec3(0.0f, 0.5f, 0.0f), 0.25f, 0});
       return s;
     },
     noSettings, [] { return with(lambertBase(), {"spheres"}); }},
    {"curve",
     [] {
       Scene s = lambertFloor();
       s.curvePoints = {{0.0f, 0.1f, 0.0f, 0.02f}, {0.0f, 0.6f, 0.0f, 0.02f}};
       s.curves.push_back({0, 2, 0, CurveBasis::kLinear});
       return s;
     },
     noSettings, [] { return with(lambertBase(), {"curves"}); }},
    {"sdf_grid",
     [] {
       Scene s = lambertFloor();
       SdfVolume v = makeSdfShape(SdfShape::kSphere, {}, 8);
       SdfGrid g;
       g.cells = v.cells;
       g.values = std::move(v.values);
       g.latticeToScene = glm::translate(glm::dmat4(1.0), glm::dvec3(0.0, 0.5, 0.0)) *
                          glm::scale(glm::dmat4(1.0), glm::dvec3(0.25)) * v.latticeToObject();
       s.sdfGrids.push_back(std::move(g));
       return s;
     },
     noSettings, [] { return with(lambertBase(), {"sdf_grids"}); }},
    {"displaced",
     [] {
       Scene s = lambertFloor();
       Scene d = makeDisplacedSphere(0, glm::vec3(0.0f, 0.5f, 0.0f), 0.25f, 8, 0.05f, -0.025f, 2, s.materials[0]);
       s.displacedMeshes.push_back(std::move(d.displacedMeshes[0]));
       return s;
     },
     noSettings, [] { return with(lambertBase(), {"displaced_meshes"}); }},
    {"instance",
     [] {
       const glm::mat4 copies[2] = {glm::mat4(1.0f), glm::translate(glm::mat4(1.0f), glm::vec3(3.0f, 0.0f, 0.0f))};
       // 2 * 8^2 triangles: enough for a geometry to be stored once (SceneBuffers::kMinInstanceTriangles)
       const Scene grid = makeGrid(8, glm::vec3(0.0f), 1.0f, glm::vec3(1, 0, 0), glm::vec3(0, 0, 1),
                                   makeMaterial(glm::vec3(0.5f)));
       return placeCopies(grid, copies);
     },
     [](RenderSettings& s) { s.instancing = Instancing::On; }, [] { return with(lambertBase(), {"instances"}); }},
    {"environment_map", lambertFloor, [](RenderSettings& s) { s.environmentMap = tinyEnvironmentMap().string(); },
     [] { return with(lambertBase(), {"environment_map"}); }},
    {"constant_sky", lambertFloor, [](RenderSettings& s) { s.background = glm::vec3(1.0f); },
     [] { return with(lambertBase(), {"constant_sky"}); }},
    {"alpha_mask",
     [] {
       Scene s = lambertFloor();
       s.materials[0].alpha_mode = WT_ALPHA_MASK;
       s.materials[0].alpha = 0.25f;
       s.materials[0].alpha_cutoff = 0.5f;
       return s;
     },
     noSettings, [] { return with(lambertBase(), {"alpha_mask", "alpha_test"}); }},
    {"alpha_blend",
     [] {
       Scene s = lambertFloor();
       s.materials[0].alpha_mode = WT_ALPHA_BLEND;
       s.materials[0].alpha = 0.5f;
       return s;
     },
     noSettings, [] { return with(lambertBase(), {"alpha_blend", "alpha_test"}); }},
    {"texture",
     [] {
       Scene s = lambertFloor();
       test::setBaseColorTexture(s, 0, test::addCheckerTexture(s, 4));
       return s;
     },
     noSettings, [] { return with(lambertBase(), {"textures", "texture:base_color"}); }},
    {"normal_map",
     [] {
       Scene s = lambertFloor();
       test::setMaterialTexture(s, 0, WT_TEXTURE_SLOT_NORMAL, test::addCheckerTexture(s, 4));
       return s;
     },
     noSettings, [] { return with(lambertBase(), {"textures", "texture:normal", "normal_maps"}); }},
    {"vertex_colors",
     [] {
       Scene s = lambertFloor();
       s.colors.assign(s.positions.size(), glm::vec4(1.0f, 0.5f, 0.5f, 1.0f));
       return s;
     },
     noSettings, [] { return with(lambertBase(), {"vertex_colors"}); }},
    {"emissive_triangle",
     [] {
       Scene s = lambertFloor();
       s.materials[0] = makeMaterial(glm::vec3(0.5f), glm::vec3(2.0f));
       s.triangles.pop_back();  // half of the square: no rectangle
       return s;
     },
     noSettings, [] { return with(lambertBase(), {"emissive_triangles"}); }},
    {"quad_light",
     [] {
       Scene s = lambertFloor();
       s.materials[0] = makeMaterial(glm::vec3(0.5f), glm::vec3(2.0f));
       return s;
     },
     noSettings, [] { return with(lambertBase(), {"emissive_triangles", "quad_lights"}); }},
    {"quad_light_as_triangles",
     [] {
       Scene s = lambertFloor();
       s.materials[0] = makeMaterial(glm::vec3(0.5f), glm::vec3(2.0f));
       return s;
     },
     [](RenderSettings& s) { s.quadLights = false; }, [] { return with(lambertBase(), {"emissive_triangles"}); }},
    {"emissive_sphere",
     [] {
       Scene s = lambertFloor();
       s.materials.push_back(makeMaterial(glm::vec3(0.0f), glm::vec3(2.0f)));
       s.materialNames.push_back("light");
       s.spheres.push_back({glm::vec3(0.0f, 0.5f, 0.0f), 0.25f, 1});
       return s;
     },
     noSettings, [] { return with(lambertBase(), {"spheres", "emissive_primitives"}); }},
    {"punctual_light",
     [] {
       Scene s = lambertFloor();
       PunctualLight light;
       light.position = glm::vec3(0.0f, 1.0f, 0.0f);
       s.lights.push_back(light);
       return s;
     },
     noSettings, [] { return with(lambertBase(), {"punctual_lights"}); }},
    {"pbr", pbrFloor, noSettings, pbrBase},
    {"transmission",
     [] {
       Scene s = pbrFloor();
       s.materials[0] = withTransmission(s.materials[0], 1.0f);
       return s;
     },
     noSettings, [] { return with(pbrBase(), {"transmission"}); }},
    {"thin_shadows",
     [] {
       // a smooth thin wall: shadow rays cross it (a rough one, or a volume, above: they do not)
       Scene s = pbrFloor();
       s.materials[0] = withTransmission(makePbrMaterial(glm::vec3(0.5f), 0.0f, 0.0f), 1.0f, 1.5f, true);
       return s;
     },
     noSettings, [] { return with(pbrBase(), {"transmission", "thin_shadows"}); }},
    {"rough_thin_wall",
     [] {
       Scene s = pbrFloor();
       s.materials[0] = withTransmission(s.materials[0], 1.0f, 1.5f, true);
       return s;
     },
     noSettings, [] { return with(pbrBase(), {"transmission"}); }},
    {"transmission_behind_a_metallic_texture",
     [] {
       // metallic factor 1, but a metallic-roughness texture can lower it: the
       // transmitting dielectric is reachable (LightsPunctualLamp's glass)
       Scene s = pbrFloor();
       s.materials[0] = withTransmission(makePbrMaterial(glm::vec3(0.5f), 1.0f, 0.5f), 1.0f);
       test::setMaterialTexture(s, 0, WT_TEXTURE_SLOT_METALLIC_ROUGHNESS, test::addCheckerTexture(s, 4));
       return s;
     },
     noSettings, [] { return with(pbrBase(), {"transmission", "textures", "texture:metallic_roughness"}); }},
    {"clearcoat",
     [] {
       Scene s = pbrFloor();
       s.materials[0] = withClearcoat(s.materials[0], 1.0f, 0.1f);
       return s;
     },
     noSettings, [] { return with(pbrBase(), {"clearcoat"}); }},
    {"sheen",
     [] {
       Scene s = pbrFloor();
       s.materials[0] = withSheen(s.materials[0], glm::vec3(0.5f), 0.5f);
       return s;
     },
     noSettings, [] { return with(pbrBase(), {"sheen"}); }},
    {"anisotropy",
     [] {
       Scene s = pbrFloor();
       s.materials[0] = withAnisotropy(s.materials[0], 0.5f, 0.3f);
       return s;
     },
     noSettings, [] { return with(pbrBase(), {"anisotropy"}); }},
    {"iridescence",
     [] {
       Scene s = pbrFloor();
       s.materials[0] = withIridescence(s.materials[0], 0.8f, 1.3f, 100.0f, 400.0f);
       return s;
     },
     noSettings, [] { return with(pbrBase(), {"iridescence"}); }},
    {"specular",
     [] {
       Scene s = pbrFloor();
       s.materials[0] = withSpecular(s.materials[0], 0.5f);
       return s;
     },
     noSettings, [] { return with(pbrBase(), {"specular"}); }},
    {"minimal_integrator", lambertFloor, [](RenderSettings& s) { s.integrator = Integrator::Minimal; },
     [] { return Names{"triangles", "lambertian", "minimal_integrator", "independent_sampler"}; }},
    {"no_nee", lambertFloor, [](RenderSettings& s) { s.useNee = false; },
     [] { return Names{"triangles", "lambertian", "path_integrator", "russian_roulette", "independent_sampler"}; }},
    {"sobol", lambertFloor, [](RenderSettings& s) { s.sobol = true; },
     [] {
       Names n = with(lambertBase(), {"sobol"});
       n.erase("independent_sampler");
       return n;
     }},
    {"no_diffuse_bounces", lambertFloor, [](RenderSettings& s) { s.maxDiffuseBounces = 0; },
     [] { return with(lambertBase(), {"no_diffuse_bounces"}); }},
};

class FeatureDetection : public ::testing::TestWithParam<OneFeature> {};

TEST_P(FeatureDetection, TheSceneHoldsExactlyItsFeature) {
  const OneFeature& c = GetParam();
  RenderSettings settings;
  c.settings(settings);
  const Names got = featuresOf(c.scene(), settings);
  const Names expected = c.expected();
  std::string gotText, expectedText;
  for (const std::string& n : got) gotText += n + " ";
  for (const std::string& n : expected) expectedText += n + " ";
  EXPECT_EQ(got, expected) << c.name << ": got " << gotText << "\nexpected " << expectedText;
}

INSTANTIATE_TEST_SUITE_P(OneEach, FeatureDetection, ::testing::ValuesIn(kCases),
                         [](const ::testing::TestParamInfo<OneFeature>& info) { return std::string(info.param.name); });

TEST(FeatureSwitches, EachFeatureTurnsOnItsSwitchOnly) {
  // the kernel switches follow the feature set: one feature, one switch
  RenderSettings settings;
  BvhBuildOptions options;
  options.maxLeafSize = 0;
  auto defines = [&](const Scene& scene, const RenderSettings& s) {
    BvhBuildOptions o = options;
    o.instancing = s.instancing;
    SceneBuffers buffers(test::deviceContext(), scene, o);
    KernelFeatures k = kernelFeaturesFor(sceneFeatures(scene, buffers, s), test::deviceContext().info());
    setLightFeatures(k, buildLightList(scene, buffers, 0.0));  // as renderKernelFeatures, without a sky
    return kernelDefines(k);
  };
  const std::vector<std::string> base = defines(lambertFloor(), settings);
  for (const std::string& d : base) {
    if (d.find("WT_HAS_") != std::string::npos) {
      EXPECT_NE(d.back(), '1') << d << " is on for a triangle-only Lambertian scene";
    }
  }
  auto changed = [&](const Scene& scene) {
    std::vector<std::string> diff, got = defines(scene, settings);
    for (std::size_t i = 0; i < got.size(); ++i)
      if (got[i] != base[i]) diff.push_back(got[i]);
    return diff;
  };
  Scene sphere = lambertFloor();
  sphere.spheres.push_back({glm::vec3(0.0f, 0.5f, 0.0f), 0.25f, 0});
  EXPECT_EQ(changed(sphere), std::vector<std::string>{"-D WT_HAS_SPHERES=1"});
  Scene lamp = lambertFloor();
  lamp.materials[0] = makeMaterial(glm::vec3(0.5f), glm::vec3(2.0f));
  EXPECT_EQ(changed(lamp), std::vector<std::string>{"-D WT_HAS_QUAD_LIGHTS=1"});
  // a point light is sampled lane by lane; kLightTreeMinEmitters emissive triangles are picked by the tree
  Scene bulb = lambertFloor();
  PunctualLight point;
  point.position = glm::vec3(0.0f, 1.0f, 0.0f);
  bulb.lights.push_back(point);
  EXPECT_EQ(changed(bulb), std::vector<std::string>{"-D WT_HAS_OTHER_LIGHTS=1"});
  Scene soup = makeTriangleSoup(2 * kLightTreeMinEmitters, 5);
  for (WtMaterial& m : soup.materials) m.emission = {1.0f, 1.0f, 1.0f, 0.0f};
  EXPECT_EQ(changed(soup), std::vector<std::string>{"-D WT_HAS_LIGHT_TREE=1"});
  Scene mask = lambertFloor();
  mask.materials[0].alpha_mode = WT_ALPHA_MASK;
  mask.materials[0].alpha = 0.25f;
  EXPECT_EQ(changed(mask), std::vector<std::string>{"-D WT_HAS_ALPHA=1"});
  Scene textured = lambertFloor();
  test::setBaseColorTexture(textured, 0, test::addCheckerTexture(textured, 4));
  EXPECT_EQ(changed(textured), std::vector<std::string>{"-D WT_HAS_TEXTURES=1"});
  Scene coat = pbrFloor();
  coat.materials[0] = withClearcoat(coat.materials[0], 1.0f, 0.1f);
  EXPECT_EQ(changed(coat), (std::vector<std::string>{"-D WT_HAS_PBR=1", "-D WT_HAS_CLEARCOAT=1"}));
  Scene pane = pbrFloor();
  pane.materials[0] = withTransmission(makePbrMaterial(glm::vec3(0.5f), 0.0f, 0.0f), 1.0f, 1.5f, true);
  EXPECT_EQ(changed(pane), (std::vector<std::string>{"-D WT_HAS_PBR=1", "-D WT_HAS_TRANSMISSION=1",
                                                     "-D WT_HAS_THIN_SHADOWS=1"}));
  // vertex colours tint the pane per vertex: its shadow rays still cross it, reading them (connect.cl)
  Scene tinted = pane;
  tinted.colors.assign(tinted.positions.size(), glm::vec4(1.0f));
  EXPECT_EQ(changed(tinted), (std::vector<std::string>{"-D WT_HAS_PBR=1", "-D WT_HAS_TRANSMISSION=1",
                                                       "-D WT_HAS_THIN_SHADOWS=1", "-D WT_HAS_VERTEX_COLORS=1"}));
  // and so do textures (they only scale the roughness down); a rough pane still blocks them
  Scene texturedPane = pane;
  test::setBaseColorTexture(texturedPane, 0, test::addCheckerTexture(texturedPane, 4));
  EXPECT_EQ(changed(texturedPane), (std::vector<std::string>{"-D WT_HAS_PBR=1", "-D WT_HAS_TRANSMISSION=1",
                                                             "-D WT_HAS_THIN_SHADOWS=1", "-D WT_HAS_TEXTURES=1"}));
  texturedPane.materials[0].roughness = 0.2f;
  EXPECT_EQ(changed(texturedPane), (std::vector<std::string>{"-D WT_HAS_PBR=1", "-D WT_HAS_TRANSMISSION=1",
                                                             "-D WT_HAS_TEXTURES=1"}));
}

TEST(FeatureSwitches, NeverDependOnTheImageSizeOrTheSampleCount) {
  // 20000 triangles: at 64x64 pixels a sample's camera rays are 0.2 per
  // triangle, at 512x512 13 per triangle (a rule by rays per triangle would
  // pick two packet widths on a 16-wide device)
  Scene scene = makeTriangleSoup(20000, 7);
  scene.camera = defaultCamera(scene.bounds());
  auto defines = [&](int width, int height, int spp) {
    RenderSettings settings;
    settings.width = width, settings.height = height, settings.samplesPerPixel = spp;
    Renderer renderer(test::deviceContext(), scene, settings);
    return kernelDefines(renderer.kernelFeatures());
  };
  const std::vector<std::string> small = defines(64, 64, 1);
  EXPECT_EQ(defines(512, 512, 1), small) << "the image size changed the build options";
  EXPECT_EQ(defines(64, 64, 1024), small) << "the sample count changed the build options";
  EXPECT_EQ(defines(640, 32, 7), small);
}


// specialised vs general program

/// Two renders of one scene with the same seed whose programs do the same
/// arithmetic, up to the compiler's choices and float rounding: the same
/// image within rounding.
void expectSameUpToRounding(const Image& one, const Image& other, const std::string& name,
                            const std::string& what) {
  ASSERT_EQ(one.rgb.size(), other.rgb.size());
  // Bitwise where possible; PoCL's compiler may order the same float
  // operations differently once more code is compiled in (a last-bit
  // difference), and such a difference can flip a later decision of one
  // sample (roulette, which of two equally distant hits), which moves that
  // pixel's mean by up to one sample's value over spp. So: every channel
  // within rounding (relative 1e-4) except at most 1% of them, and the
  // image means within 4 standard errors of their difference (the per-pixel
  // variances; the two renders are not independent, so this is generous).
  std::size_t bitwise = 0, beyondRounding = 0, first = one.rgb.size();
  double sumDifference = 0.0, varianceOfSum = 0.0, maxRelative = 0.0;
  for (std::size_t i = 0; i < one.rgb.size(); ++i) {
    const float a = one.rgb[i], b = other.rgb[i];
    if (std::memcmp(&a, &b, sizeof(float)) != 0) ++bitwise;
    const double relative = std::fabs(double(a) - double(b)) / std::max(1e-6, std::fabs(double(a)));
    maxRelative = std::max(maxRelative, relative);
    if (relative > 1e-4) {
      ++beyondRounding;
      first = std::min(first, i);
    }
    sumDifference += double(a) - double(b);
    const std::uint32_t n = std::max<std::uint32_t>(1, one.samples[i / 3]);
    varianceOfSum += (double(one.rgbVariance[i]) + double(other.rgbVariance[i])) / n;
  }
  ASSERT_TRUE(std::isfinite(sumDifference));
  EXPECT_LE(beyondRounding, one.rgb.size() / 100)
      << name << ": " << beyondRounding << " of " << one.rgb.size()
      << " channel values differ beyond rounding between the " << what << "; first at pixel "
      << first / 3 << " (" << (first < one.rgb.size() ? one.rgb[first] : 0.0f) << " vs "
      << (first < other.rgb.size() ? other.rgb[first] : 0.0f) << ")";
  EXPECT_LE(std::fabs(sumDifference), 4.0 * std::sqrt(varianceOfSum) + 1e-9)
      << name << ": the image means differ by more than the noise allows";
  std::printf("%s: %zu of %zu channel values not bitwise equal, %zu beyond relative 1e-4, max relative %.3g\n",
              name.c_str(), bitwise, one.rgb.size(), beyondRounding, maxRelative);
}

/// Render `loaded` at a small size with its own feature set's program and
/// with the general program (every switch on), same seed, and compare.
/// The random numbers are a pure function of pixel, sample, bounce and
/// dimension, and a switch only compiles out code a scene cannot reach, so
/// the two programs do the same arithmetic, up to the compiler's choices.
void expectSpecialisedEqualsGeneral(const SceneFile& loaded, const std::string& name) {
  RenderSettings settings;
  settings.width = 40, settings.height = 30;
  settings.maxBounces = 6;
  settings.seed = 11;
  if (const auto& env = loaded.settings.environment) {
    if (env->color) settings.background = *env->color;
    else settings.environmentMap = env->map, settings.environmentIntensity = env->intensity;
  }
  const int spp = 4;
  auto renderWith = [&](bool general, KernelFeatures* used) {
    RenderSettings s = settings;
    s.generalProgram = general;
    Renderer renderer(test::deviceContext(), loaded.scene, s);
    *used = renderer.kernelFeatures();
    for (int i = 0; i < spp; ++i) renderer.renderSample();
    return renderer.readImage();
  };
  KernelFeatures specialisedSwitches, generalSwitches;
  const Image specialised = renderWith(false, &specialisedSwitches);
  const Image general = renderWith(true, &generalSwitches);
  EXPECT_TRUE(generalSwitches.pbr && generalSwitches.textures && generalSwitches.alpha &&
              generalSwitches.primitives[WT_PRIM_SPHERE] && generalSwitches.primitives[WT_PRIM_INSTANCE])
      << "the general program is not every switch on";
  expectSameUpToRounding(specialised, general, name, "specialised and the general program");
}

// Metallic-roughness materials that are exactly Lambertian (specularFactor
// 0, no metal: how glTF states a Lambertian wall) go to the kernels as the
// Lambertian model (RenderSettings::lambertianForms): the program compiles
// no metallic-roughness code when all are, and the image is the one the
// general model renders, within rounding.
TEST(LambertianForms, SpecularZeroRendersAsTheLambertianModelWithTheSameImage) {
  const Scene cornell = loadDefaultScene();
  auto renderWith = [](const Scene& scene, bool forms, KernelFeatures* used) {
    RenderSettings s;
    s.width = 40, s.height = 30;
    s.samplesPerPixel = 4;
    s.seed = 5;
    s.lambertianForms = forms;
    s.powerAtLambertian = false;  // one MIS heuristic for both models (auto's follows the model)
    Renderer renderer(test::deviceContext(), scene, s);
    *used = renderer.kernelFeatures();
    for (int i = 0; i < s.samplesPerPixel; ++i) renderer.renderSample();
    return renderer.readImage();
  };
  {
    SCOPED_TRACE("every material specular 0");
    Scene scene = cornell;
    for (WtMaterial& m : scene.materials) m = withSpecular(m, 0.0f);
    KernelFeatures general, lambertian;
    const Image a = renderWith(scene, false, &general), b = renderWith(scene, true, &lambertian);
    EXPECT_TRUE(general.pbr && general.specular);
    EXPECT_FALSE(lambertian.pbr || lambertian.specular) << "the Lambertian forms compiled metallic-roughness code in";
    expectSameUpToRounding(a, b, "Cornell box, specular 0", "general model and the Lambertian forms");
  }
  {
    SCOPED_TRACE("the red wall keeps its specular lobe");
    Scene scene = cornell;
    for (std::size_t i = 0; i < scene.materials.size(); ++i)
      if (i != 1) scene.materials[i] = withSpecular(scene.materials[i], 0.0f);
    ASSERT_GT(scene.materials[1].base_color.x, 0.5f) << "material 1 is not the red wall";
    KernelFeatures general, lambertian;
    const Image a = renderWith(scene, false, &general), b = renderWith(scene, true, &lambertian);
    EXPECT_TRUE(lambertian.pbr && !lambertian.specular);
    expectSameUpToRounding(a, b, "Cornell box, specular 0 but the red wall", "general model and the Lambertian forms");
  }
}

class SpecialisedProgram : public ::testing::TestWithParam<const char*> {};

TEST_P(SpecialisedProgram, RendersTheSameImageAsTheGeneralProgram) {
  const std::string path = wt::embedded::sourceDirectory().string() + "/scenes/" + GetParam();
  expectSpecialisedEqualsGeneral(loadSceneAny(path), GetParam());
}

INSTANTIATE_TEST_SUITE_P(ExampleScenes, SpecialisedProgram,
                         ::testing::Values("cornell.gltf", "cornell_small_light.gltf", "corridor.gltf",
                                           "glass_tube.json", "mixed.json", "sdf.json", "spheres.json"),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                           std::string n = info.param;
                           std::replace(n.begin(), n.end(), '.', '_');
                           return n;
                         });

class SpecialisedProgramAssets : public ::testing::TestWithParam<const char*> {};

TEST_P(SpecialisedProgramAssets, RendersTheSameImageAsTheGeneralProgram) {
  WT_REQUIRE_ASSET(path, GetParam());
  expectSpecialisedEqualsGeneral(loadSceneAny(path.string()), GetParam());
}

// example scenes that read ../shared/assets
class SpecialisedProgramExampleAssets : public ::testing::TestWithParam<const char*> {};

TEST_P(SpecialisedProgramExampleAssets, RendersTheSameImageAsTheGeneralProgram) {
  WT_REQUIRE_ASSET(hair, "curves/hairutil_testdata/Bangs_100.hair");
  const std::string path = wt::embedded::sourceDirectory().string() + "/scenes/" + GetParam();
  expectSpecialisedEqualsGeneral(loadSceneAny(path), GetParam());
}

INSTANTIATE_TEST_SUITE_P(ExampleScenes, SpecialisedProgramExampleAssets, ::testing::Values("hair.json"),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                           std::string n = info.param;
                           std::replace(n.begin(), n.end(), '.', '_');
                           return n;
                         });

INSTANTIATE_TEST_SUITE_P(SharedGltf, SpecialisedProgramAssets,
                         ::testing::Values("gltf/DamagedHelmet/glTF/DamagedHelmet.gltf",
                                           "gltf/AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf",
                                           "gltf/ClearCoatTest/glTF/ClearCoatTest.gltf",
                                           "gltf/TransmissionTest/glTF/TransmissionTest.gltf",
                                           "gltf/BoxVertexColors/glTF/BoxVertexColors.gltf",
                                           "gltf/LightsPunctualLamp/glTF/LightsPunctualLamp.gltf",
                                           "cornell/saschawillems_CornellBox-Original/CornellBox-Original.gltf"),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                           std::string n = std::filesystem::path(info.param).stem().string();
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

}  // namespace
}  // namespace wt
