#include "render/feature_set.h"

#include "device/scene_buffers.h"
#include "geometry/primitives.h"
#include "render/light_list.h"
#include "render/renderer.h"
#include "scene/scene.h"

#include <algorithm>

namespace wt {
namespace {

bool emits(const WtMaterial& m) { return m.emission.x > 0.0f || m.emission.y > 0.0f || m.emission.z > 0.0f; }

}  // namespace

FeatureSet sceneFeatures(const Scene& scene, const SceneBuffers& buffers, const RenderSettings& settings) {
  FeatureSet f;
  auto material = [&](std::uint32_t index) -> const WtMaterial* {
    return index < scene.materials.size() ? &scene.materials[index] : nullptr;
  };

  // geometry
  f.triangleCount = scene.triangles.size();
  f.triangles = !scene.triangles.empty();
  f.primitives = buffers.primitiveTypesPresent();
  f.bvhStackSize = buffers.stackSize();

  // lights: what emits, by kind
  f.punctualLights = !scene.lights.empty();
  for (const WtTriangle& t : scene.triangles) {
    const WtMaterial* m = material(t.material);
    if (!m || !emits(*m)) continue;
    f.emissiveTriangles = true;
    if (buffers.hasTextures() && (m->texture_mask & (1u << WT_TEXTURE_SLOT_EMISSIVE))) f.emissiveTextures = true;
  }
  for (const Sphere& s : scene.spheres)
    if (const WtMaterial* m = material(s.material); m && emits(*m)) f.emissivePrimitives = true;
  for (const Curve& c : scene.curves)
    if (const WtMaterial* m = material(c.material); m && emits(*m)) f.emissivePrimitives = true;
  for (const DisplacedMesh& d : scene.displacedMeshes)
    if (const WtMaterial* m = material(d.material); m && emits(*m)) f.emissivePrimitives = true;
  for (const SdfGrid& g : scene.sdfGrids)
    if (const WtMaterial* m = material(g.material); m && emits(*m)) f.emissivePrimitives = true;
  // the light list makes the same pairs (buildLightList)
  f.quadLights = f.emissiveTriangles && settings.quadLights && !findQuadLights(scene, buffers).empty();
  f.environmentMap = !settings.environmentMap.empty() && settings.environmentIntensity > 0.0f;
  f.constantSky = settings.environmentMap.empty() &&
                  (settings.background.x > 0.0f || settings.background.y > 0.0f || settings.background.z > 0.0f);

  // surfaces, as the device gets them: the layers by the one rule that compiles them in (setMaterialFeatures)
  KernelFeatures layers;
  setMaterialFeatures(layers, buffers.kernelMaterials());
  f.pbr = layers.pbr;
  f.specular = layers.specular;
  f.clearcoat = layers.clearcoat;
  f.sheen = layers.sheen;
  f.anisotropy = layers.anisotropy;
  f.iridescence = layers.iridescence;
  f.transmission = layers.transmission;
  f.thinShadows = layers.transmission && layers.thinShadows;
  for (const WtMaterial& m : buffers.kernelMaterials()) {
    if (m.model == WT_MATERIAL_DIFFUSE) f.lambertian = true;
    if (m.model == WT_MATERIAL_PBR && m.transmission > 0.0f && m.volume.w > 0.0f &&
        (m.volume.x > 0.0f || m.volume.y > 0.0f || m.volume.z > 0.0f))
      f.volume = true;
    if (m.alpha_mode == WT_ALPHA_MASK) f.alphaMask = true;
    if (m.alpha_mode == WT_ALPHA_BLEND) f.alphaBlend = true;
  }
  f.textures = buffers.hasTextures();
  if (f.textures)
    for (const WtMaterial& m : scene.materials) f.textureSlots |= m.texture_mask;
  f.normalMaps = (f.textureSlots & ((1u << WT_TEXTURE_SLOT_NORMAL) | (1u << WT_TEXTURE_SLOT_CLEARCOAT_NORMAL))) != 0;
  f.vertexColors = buffers.hasVertexColors();
  f.alphaTest = buffers.hasAlpha();

  // integrator
  f.minimalIntegrator = settings.integrator == Integrator::Minimal;
  if (!f.minimalIntegrator) {
    f.nee = settings.useNee;
    f.mis = settings.useNee && settings.useMis;
    f.russianRoulette = settings.useRussianRoulette;
  }
  f.sobol = settings.sobol;

  // bounce limits, as the frame parameters clamp them (renderer.cpp, frameParams)
  auto zero = [&](int limit) { return (limit < 0 ? settings.maxBounces : std::min(limit, settings.maxBounces)) == 0; };
  f.noBounces = settings.maxBounces == 0;
  f.noDiffuseBounces = zero(settings.maxDiffuseBounces);
  f.noSpecularBounces = zero(settings.maxSpecularBounces);
  f.noTransmissionBounces = zero(settings.maxTransmissionBounces);
  return f;
}

std::vector<std::string> featureNames(const FeatureSet& f) {
  static const char* kSlots[WT_TEXTURE_SLOTS] = {
      "base_color", "metallic_roughness", "normal", "emissive", "transmission", "specular",
      "specular_color", "clearcoat", "clearcoat_roughness", "clearcoat_normal", "sheen_color", "sheen_roughness",
      "anisotropy", "iridescence", "iridescence_thickness", "slot15"};
  std::vector<std::string> names;
  auto add = [&](bool on, const char* name) {
    if (on) names.emplace_back(name);
  };
  add(f.triangles, "triangles");
  for (const PrimitiveType& t : primitiveTypes()) add(f.primitives[t.id], t.feature);
  add(f.punctualLights, "punctual_lights");
  add(f.emissiveTriangles, "emissive_triangles");
  add(f.quadLights, "quad_lights");
  add(f.emissivePrimitives, "emissive_primitives");
  add(f.emissiveTextures, "emissive_textures");
  add(f.environmentMap, "environment_map");
  add(f.constantSky, "constant_sky");
  add(f.lambertian, "lambertian");
  add(f.pbr, "pbr");
  add(f.specular, "specular");
  add(f.clearcoat, "clearcoat");
  add(f.sheen, "sheen");
  add(f.anisotropy, "anisotropy");
  add(f.iridescence, "iridescence");
  add(f.transmission, "transmission");
  add(f.volume, "volume");
  add(f.thinShadows, "thin_shadows");
  add(f.textures, "textures");
  for (std::uint32_t s = 0; s < WT_TEXTURE_SLOTS; ++s)
    if (f.textureSlots & (1u << s)) names.push_back(std::string("texture:") + kSlots[s]);
  add(f.normalMaps, "normal_maps");
  add(f.vertexColors, "vertex_colors");
  add(f.alphaMask, "alpha_mask");
  add(f.alphaBlend, "alpha_blend");
  add(f.alphaTest, "alpha_test");
  add(f.minimalIntegrator, "minimal_integrator");
  add(!f.minimalIntegrator, "path_integrator");
  add(f.nee, "nee");
  add(f.mis, "mis");
  add(f.russianRoulette, "russian_roulette");
  add(f.sobol, "sobol");
  add(!f.sobol, "independent_sampler");
  add(f.noBounces, "no_bounces");
  add(f.noDiffuseBounces, "no_diffuse_bounces");
  add(f.noSpecularBounces, "no_specular_bounces");
  add(f.noTransmissionBounces, "no_transmission_bounces");
  return names;
}

KernelFeatures kernelFeaturesFor(const FeatureSet& f, const DeviceInfo& device, int requestedPacketWidth) {
  KernelFeatures k;
  k.integratorMinimal = f.minimalIntegrator;
  k.bvhStackSize = f.bvhStackSize;
  k.pbr = f.pbr;
  k.transmission = f.transmission;
  k.thinShadows = f.thinShadows;
  k.quadLights = f.quadLights;
  k.specular = f.specular;
  k.clearcoat = f.clearcoat;
  k.sheen = f.sheen;
  k.anisotropy = f.anisotropy;
  k.iridescence = f.iridescence;
  k.textures = f.textures;
  k.vertexColors = f.vertexColors;
  k.alpha = f.alphaTest;
  k.primitives = f.primitives;
  k.packetWidth = packetWidthFor(device, requestedPacketWidth, f.triangleCount);
  k.streamPrefetch = false;  // by the scene's size where it is uploaded (Renderer, Tracer: streamPrefetchFor)
  return k;
}

KernelFeatures generalKernelFeatures(const FeatureSet& f, const DeviceInfo& device, int requestedPacketWidth) {
  KernelFeatures k = kernelFeaturesFor(f, device, requestedPacketWidth);
  // the integrator is an algorithm, not a feature a scene has: kept
  k.pbr = k.transmission = k.specular = k.clearcoat = k.sheen = k.anisotropy = k.iridescence = k.thinShadows = true;
  k.textures = k.vertexColors = k.alpha = k.quadLights = true;
  k.primitives.fill(true);
  k.primitives[WT_PRIM_TRIANGLE] = false;  // triangles are always compiled in: no switch
  return k;
}

}  // namespace wt
