// Kernel sources (embedded at build time, or a folder on disk for kernel
// development) and the program build, specialised by the scene's features.
#pragma once

#include "device/context.h"
#include "shared/types.h"

#include <array>
#include <cstddef>

#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace wt {

/// What a program compiles in; becomes -D options (kernelDefines), every one
/// always set (kernels/switches.h fails the build on a missing one). Made from
/// the scene's feature set by kernelFeaturesFor (host/render/feature_set.h).
/// Keep the set coarse so few variants exist and PoCL's cache keeps them warm.
struct KernelFeatures {
  bool integratorMinimal = true;  ///< the brute-force reference (--integrator minimal), else the path integrator
  int bvhStackSize = 64;          ///< traversal stack entries; >= BVH depth + 1, rounded up to 32
  bool pbr = false;               ///< a material uses the metallic-roughness model (else all are Lambertian)
  bool transmission = false;      ///< a metallic-roughness material transmits (KHR_materials_transmission)
  /// A material is a smooth thin wall that shadow rays cross
  /// (WtMaterial::shadow_pass): connect and shade take WT_THIN_SHADOW_PARAMS
  bool thinShadows = false;
  /// Two emissive triangles make a rectangle light, sampled as one
  /// (WT_LIGHT_QUAD; set by the renderer from its light list): shade takes
  /// WT_QUAD_SHADE_PARAMS
  bool quadLights = false;
  /// The light list picks its emissive triangles by the light tree
  /// (WT_LIGHT_TREE): shade compiles the tree's pick and pmf in
  bool lightTree = true;
  /// NEE may pick a light other than a triangle, a rectangle or the tree
  /// (point, spot, directional, the environment, another type's primitive):
  /// the lanes shade compiles their lane-by-lane sampling in
  bool otherLights = true;
  bool textures = false;          ///< a material reads a texture (materials/textured.cl)
  bool vertexColors = false;      ///< the scene's vertices have COLOR_0
  bool specular = false;          ///< a dielectric's F0 is not 0.04 or its Fresnel is weighted (KHR_materials_specular, KHR_materials_ior)
  bool clearcoat = false;         ///< a material has a clear coat (KHR_materials_clearcoat)
  bool sheen = false;             ///< a material has a sheen (KHR_materials_sheen)
  bool anisotropy = false;        ///< a material's specular lobe is anisotropic (KHR_materials_anisotropy)
  bool iridescence = false;       ///< a material's base reflection has a thin film (KHR_materials_iridescence)
  /// A triangle's material can have a hole (alphaMode MASK or BLEND,
  /// SceneBuffers::hasAlpha): traversal runs the alpha test
  /// (kernels/materials/alpha.cl) and its kernels take WT_ALPHA_PARAMS
  bool alpha = false;
  /// The geometry types beside triangles compiled in, by WT_PRIM_* (each
  /// primitiveTypes() entry's define; SceneBuffers::primitiveTypesPresent)
  std::array<bool, WT_PRIM_TYPES> primitives{};
  int packetWidth = 8;            ///< rays per packet (WT_PACKET_WIDTH): 8 or 16, packetWidthFor (device and scene only)
  /// WT_STREAM_PREFETCH: streams ask for a node's children as it arrives, and
  /// keep their rays' order (streamPrefetchFor)
  bool streamPrefetch = false;
  /// WT_AOV: shade and accumulate record the AOVs (kernels/aov.cl); set by
  /// the renderer from RenderSettings::aovs, never by the scene
  bool aov = false;
  /// WT_BVH_COST: traversal counts the nodes a ray visits (the bvh-cost
  /// debug view only; needs aov)
  bool bvhCost = false;
  /// WT_SHADE_LANES: shade runs shadeLanesWidth paths per work-item on
  /// vector lanes (kernels/shade_lanes.cl); set by the renderer
  /// (renderKernelFeatures) where every surface is a triangle, Lambertian or
  /// metallic-roughness without extensions or textures, and launched over a
  /// work-item per shadeLanesWidth queue entries
  bool shadeLanes = false;
  int shadeLanesWidth = 8;  ///< WT_SHADE_LANES_WIDTH: 8 or 16 (shadeLanesWidthFor); only with shadeLanes
};

/// Paths per shade work-item on lanes: `requested` (8 or 16) when non-zero,
/// else 16 where the device's native float vector is 16 wide (AVX-512 CPUs),
/// else 8. Throws DeviceError for any other request.
int shadeLanesWidthFor(const DeviceInfo& device, int requested = 0);

/// Whether streams (kernels/bvh_stream.cl) should ask for a node's children
/// as it arrives, and keep their rays in order rather than grouped by
/// octant: where the scene's nodes and triangles (`sceneBytes`) do not fit
/// in the device's global memory cache, or the device reports none. The
/// requests hide memory latency, so they only pay where the tree comes from
/// memory (docs/lab/2026-12-04-performance-log.md, "Streams: the children's
/// data asked for early").
bool streamPrefetchFor(const DeviceInfo& device, std::size_t sceneBytes);

/// Triangles above which a 16-wide device still gets packets of 8: a
/// packet's camera rays then spread over several leaves, and 16 lanes pay
/// for the union. Fixed by the scene, never by the image size, so that a
/// resolution change never recompiles: the rule it replaces (camera rays per
/// triangle below 3) evaluated at a reference image of 1024x1024 pixels,
/// where the packets of 8 were measured faster on the 1 M-triangle scenes
/// (docs/lab/2026-12-05-features.md).
constexpr std::size_t kWidePacketMaxTriangles = (std::size_t{1024} * 1024) / 3;

/// Rays per packet for a device and a scene: `requested` (8 or 16) when
/// non-zero, else 16 where the device's native float vector is 16 wide
/// (AVX-512 CPUs) and the scene has at most kWidePacketMaxTriangles
/// triangles (`triangles`; 0: not known, 16), else 8. Throws DeviceError for
/// any other request.
int packetWidthFor(const DeviceInfo& device, int requested = 0, std::size_t triangles = 0);

/// Set pbr, transmission, specular, clearcoat, sheen, anisotropy and iridescence from the materials
/// a scene holds: only scenes that use a material layer compile it in.
void setMaterialFeatures(KernelFeatures& features, std::span<const WtMaterial> materials);

/// The build options for a feature set, e.g. "-D WT_INTEGRATOR_MINIMAL=1 ...".
std::vector<std::string> kernelDefines(const KernelFeatures& features);

/// Read kernels from this folder instead of the embedded copies (developer
/// option, --kernel-dir; also the WT_KERNEL_DIR environment variable).
void setKernelDirectory(const std::optional<std::filesystem::path>& dir);
/// The folder kernels are read from (setKernelDirectory, else WT_KERNEL_DIR);
/// none: the embedded copies.
std::optional<std::filesystem::path> kernelDirectory();

/// Kernel files the binary does not embed (the test kernels,
/// kernels/*_tests.cl, which stay in the source tree) are read from this
/// folder; only the tests set it. The kernel folder, when set, still wins.
void setKernelFallbackDirectory(const std::optional<std::filesystem::path>& dir);

/// The source of `file` (relative to kernels/) with every `#include "..."`
/// expanded once, resolved against the including file's folder and then the
/// kernels root; `#line` directives keep build logs pointing at real files.
std::string expandKernelSource(const std::string& file);

/// Build kernels/<root> (the renderer's program by default) for the
/// context's device, through the program cache (device/program_cache.h).
/// Throws DeviceError carrying the device's build log.
cl::Program buildProgram(Context& context, const KernelFeatures& features,
                         const std::string& root = "wavetrace.cl");

/// The frame program's build options: WT_AOV (accumulate's AOV fold), the
/// only switch its kernels read.
std::vector<std::string> frameProgramDefines(bool aov);

/// Build the frame program (kernels/frame.cl: accumulate, accumulate_resolve
/// and the tonemap kernels) like buildProgram. Its code reads no scene
/// switch, so every feature set shares one build per context (and one entry
/// in the program cache and PoCL's): a new scene compiles the render stages only.
cl::Program buildFrameProgram(Context& context, bool aov);

}  // namespace wt
