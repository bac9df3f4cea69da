// What a scene and its render settings use: one feature set, derived in one
// place (sceneFeatures), reported by `wavetrace info`, and mapped to the
// kernels' compile-time switches (kernelFeaturesFor). The set is finer than
// the switches: everything is reported, only a few coarse items compile
// code in or out, so few program variants exist.
#pragma once

#include "device/context.h"
#include "device/program.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace wt {

class SceneBuffers;
struct Scene;
struct RenderSettings;

struct FeatureSet {
  // geometry
  bool triangles = false;  ///< the scene has triangles
  std::size_t triangleCount = 0;  ///< for the packet width (packetWidthFor); a statistic, not a switch
  /// Per WT_PRIM_* type beside triangles: the scene has it (instances: SceneBuffers decided)
  std::array<bool, WT_PRIM_TYPES> primitives{};
  int bvhStackSize = 64;   ///< traversal stack entries the BVH needs (SceneBuffers::stackSize)
  // lights
  bool punctualLights = false;     ///< KHR_lights_punctual
  bool emissiveTriangles = false;  ///< a triangle's material emits
  bool emissivePrimitives = false; ///< a sphere's, curve's, displaced mesh's or SDF grid's material emits
  bool emissiveTextures = false;   ///< an emitting material's emission is textured
  bool quadLights = false;         ///< two emissive triangles make a rectangle light (findQuadLights; RenderSettings::quadLights)
  bool environmentMap = false;     ///< an equirectangular map lights the scene
  bool constantSky = false;        ///< a constant, non-black background lights the scene
  // surfaces
  bool lambertian = false;      ///< a material is the Lambertian model
  bool pbr = false;             ///< a material is glTF metallic-roughness
  bool specular = false;        ///< the dielectric's F0 is tinted or weighted (KHR_materials_specular, _ior)
  bool clearcoat = false;       ///< KHR_materials_clearcoat
  bool sheen = false;           ///< KHR_materials_sheen
  bool anisotropy = false;      ///< KHR_materials_anisotropy
  bool iridescence = false;     ///< KHR_materials_iridescence
  bool transmission = false;    ///< KHR_materials_transmission
  bool volume = false;          ///< KHR_materials_volume (absorption inside a refracting boundary)
  bool thinShadows = false;     ///< a smooth thin transmitting wall: shadow rays cross it (WtMaterial::shadow_pass)
  bool textures = false;        ///< a material reads a texture (uploaded)
  std::uint32_t textureSlots = 0;  ///< bit s: some material textures slot s (WT_TEXTURE_SLOT_*)
  bool normalMaps = false;      ///< a normal or clear-coat normal texture
  bool vertexColors = false;    ///< COLOR_0
  bool alphaMask = false;       ///< a material is alphaMode MASK
  bool alphaBlend = false;      ///< a material is alphaMode BLEND
  bool alphaTest = false;       ///< some triangle may have a hole: traversal runs the alpha test
  // integrator
  bool minimalIntegrator = false;  ///< the brute-force reference, else the path tracer
  bool nee = false, mis = false, russianRoulette = false;  ///< path tracer switches in effect
  bool sobol = false;              ///< Owen-scrambled Sobol sampler, else independent
  // bounce limits that are zero
  bool noBounces = false;              ///< max_bounces 0: direct view of emitters only
  bool noDiffuseBounces = false;
  bool noSpecularBounces = false;
  bool noTransmissionBounces = false;

  bool operator==(const FeatureSet&) const = default;
};

/// The feature set of `scene` uploaded as `buffers` and rendered with
/// `settings`: the one place that decides it (the renderer's program, the
/// tracer's, `wavetrace info` all call it).
FeatureSet sceneFeatures(const Scene& scene, const SceneBuffers& buffers, const RenderSettings& settings);

/// The names of the features that are on, in a fixed order ("triangles",
/// "lambertian", "nee", ...): for `wavetrace info` and for tests.
std::vector<std::string> featureNames(const FeatureSet& features);

/// The switches a feature set compiles in, for `device`. Depends on the
/// scene and the device only: never on the image size or the sample count.
KernelFeatures kernelFeaturesFor(const FeatureSet& features, const DeviceInfo& device, int requestedPacketWidth = 0);

/// Every switch on (the general program): renders any scene whose
/// bvhStackSize and packet width it shares, with SceneBuffers holding every
/// surface attribute (BvhBuildOptions::allSurfaceAttributes).
KernelFeatures generalKernelFeatures(const FeatureSet& features, const DeviceInfo& device,
                                     int requestedPacketWidth = 0);

}  // namespace wt
