// Scenes the project makes itself, for tests and benchmarks: closed meshes,
// random triangle soups and large meshes, with no file involved.
#pragma once

#include "scene/scene.h"

#include <cstdint>
#include <span>

namespace wt {

/// A closed, watertight sphere: an icosahedron subdivided `subdivisions`
/// times (20 * 4^s triangles) with shared vertices, projected to the sphere.
/// Outward winding, per-vertex normals, one material.
Scene makeIcosphere(int subdivisions, glm::vec3 center, float radius, const WtMaterial& material);

/// A displaced icosphere (Scene::displacedMeshes, one mesh, no triangles):
/// the icosphere's shared vertices and normals, uv = the unit direction's
/// (x, y) / 2 + 1/2 (one uv per vertex: no uv seams, so the mesh stays
/// closed), a procedural mapSize^2 map in [0, 1] (smooth waves plus a
/// checker of sharp steps), displacement scale h + offset, level -1 (from
/// the texel density) or as given.
Scene makeDisplacedSphere(int subdivisions, glm::vec3 center, float radius, std::uint32_t mapSize, float scale,
                          float offset, int level, const WtMaterial& material);

/// A closed axis-aligned box of 12 triangles over 8 shared corners, wound
/// outwards, one material.
Scene makeBox(glm::vec3 lo, glm::vec3 hi, const WtMaterial& material);

/// A flat grid of n x n quads (2 n^2 triangles, shared vertices) spanning
/// [-half, half]^2 about `center`, in the plane spanned by unit vectors u and
/// v, wound towards u x v; one material.
Scene makeGrid(std::uint32_t n, glm::vec3 center, float half, glm::vec3 u, glm::vec3 v, const WtMaterial& material);

/// `count` random triangles inside the unit cube, edges up to `maxEdge`.
Scene makeTriangleSoup(std::uint32_t count, std::uint32_t seed, float maxEdge = 0.1f);

/// A height field of about `triangleCount` triangles over [-1,1]^2 with
/// bumps, as a stand-in for a large scanned mesh.
Scene makeBumpyGrid(std::uint32_t triangleCount);

/// `count` spheres in [-1,1]^3 (radii from 0.1 to 0.6 of the mean spacing,
/// log-uniform; a Lambertian grey), and four emissive spheres above them.
Scene makeSphereField(std::uint32_t count, std::uint32_t seed = 1);

/// `children` child strands around each of the guide curves [firstGuide,
/// firstGuide + guideCount) of `scene`, appended after its curves: each a
/// copy of its guide moved by a fixed offset drawn uniformly from a disc of
/// radius `spread` across the guide (in a frame carried along the guide
/// without twisting, so a child follows its guide's bends), with the guide's
/// radii, basis and material. Deterministic for a seed.
void addChildCurves(Scene& scene, std::uint32_t firstGuide, std::uint32_t guideCount, std::uint32_t children,
                    float spread, std::uint32_t seed = 1);

/// A head of hair made in code (no file): a sphere of radius 1 at the
/// origin (the head) and `guides` strands of 16 points from its upper part,
/// falling under gravity along it, radius 0.004 tapering to 0.0015, each
/// with `children` children within 0.05 (addChildCurves); a camera in front.
/// 100 guides x 100 children make 10 100 curves of 15 segments (151 500).
Scene makeHairScene(std::uint32_t guides = 100, std::uint32_t children = 100, std::uint32_t seed = 1);

/// Append `src` to `dst` (vertices, triangles, spheres, curves, SDF grids, displaced meshes, materials re-indexed;
/// src's placed copies kept, its geometry ids renumbered past dst's). Both
/// must share one Scene::origin.
void appendScene(Scene& dst, const Scene& src);

/// One copy of `mesh`'s triangles per transform (points by the matrix,
/// normals by its inverse transpose, tangents by its linear part; a mirroring
/// one swaps two corners so the front face stays in front and flips the
/// bitangent's side, as the glTF loader does; texture coordinates and vertex
/// colours kept), each recorded in Scene::instances with its transform as a
/// copy of one geometry; likewise its spheres and curves (radii by the cube
/// root of the determinant), SDF grids (the lattice placed by the transform)
/// and displaced meshes (vertices, normals and corners as triangles',
/// displacements scaled as radii) in Scene::primitiveInstances; the
/// materials and their textures once.
Scene placeCopies(const Scene& mesh, std::span<const glm::mat4> transforms);

/// A Lambertian material; emission from the front face only unless twoSided.
WtMaterial makeMaterial(glm::vec3 albedo, glm::vec3 emission = glm::vec3(0.0f), bool twoSided = false);

/// Whether the kernels may render `m` as the Lambertian model: it is one,
/// or a metallic-roughness material whose every lobe but the diffuse base
/// weighs 0 (metallic factor 0, which a texture only multiplies; specular 0;
/// no transmission, clear coat, sheen, anisotropy or iridescence), so that
/// its BSDF is base colour / pi and its sampling the cosine lobe exactly.
bool isLambertian(const WtMaterial& m);

/// `m` as the kernels get it: the Lambertian model where isLambertian, so
/// such a material costs what a Lambertian one does (the general model
/// evaluates and samples lobes of weight 0).
WtMaterial kernelMaterial(const WtMaterial& m);

/// A glTF metallic-roughness material (values clamped to [0,1]).
WtMaterial makePbrMaterial(glm::vec3 baseColor, float metallic, float roughness,
                           glm::vec3 emission = glm::vec3(0.0f), bool twoSided = false);

/// The transmitting part of a glTF material (KHR_materials_transmission,
/// _ior, _volume): `transmission` of the dielectric becomes an interface of
/// index `ior`; a volume boundary (refracting, absorbing `absorption` per
/// unit length inside) or, when `thinWalled`, a sheet light passes straight
/// through. Values are clamped (transmission to [0,1], ior to [1, 10]).
WtMaterial withTransmission(WtMaterial m, float transmission, float ior = 1.5f, bool thinWalled = false,
                            glm::vec3 absorption = glm::vec3(0.0f));

/// The nested-dielectric priority of a volume boundary (shared/media.h):
/// where closed transmitting volumes overlap, the higher priority's medium
/// fills the overlap and the other's surfaces there are passed through.
WtMaterial withPriority(WtMaterial m, std::uint32_t priority);

/// KHR_materials_dispersion: `dispersion` = 20 / Abbe number (clamped to
/// [0, 1000]); it bends light by wavelength at volume boundaries only.
WtMaterial withDispersion(WtMaterial m, float dispersion);

/// KHR_materials_specular: `specular` (clamped to [0,1]) weighs the
/// dielectric's whole Fresnel term, `specularColor` (>= 0) tints its F0
/// (((ior - 1) / (ior + 1))^2, capped at 1). Specular 0 leaves a purely
/// Lambertian dielectric.
WtMaterial withSpecular(WtMaterial m, float specular, glm::vec3 specularColor = glm::vec3(1.0f));

/// KHR_materials_clearcoat: a GGX dielectric coat (F0 0.04) of weight
/// `clearcoat` and its own `roughness` over the whole material (both
/// clamped to [0,1]).
WtMaterial withClearcoat(WtMaterial m, float clearcoat, float roughness);

/// KHR_materials_sheen: a sheen of `color` and `roughness` (clamped to
/// [0,1]) over the material, under a clear coat; colour 0 is no sheen.
WtMaterial withSheen(WtMaterial m, glm::vec3 color, float roughness);

/// KHR_materials_anisotropy: the base's GGX lobe stretched along the
/// tangent rotated by `rotation` radians (counter-clockwise towards the
/// bitangent), alpha_t = mix(alpha, 1, strength^2), alpha_b = alpha, with
/// strength clamped to [0,1]; strength 0 is isotropic.
WtMaterial withAnisotropy(WtMaterial m, float strength, float rotation);

/// KHR_materials_iridescence: a thin film of index `ior` over the base's
/// reflection lobe, its Fresnel replaced by the film's (Belcour & Barla
/// 2017 as the extension gives it) mixed in by `factor` (clamped to
/// [0,1]); thickness in nm, thicknessMax unless a thickness texture
/// reads mix(thicknessMin, thicknessMax, g). Factor 0 is no film.
WtMaterial withIridescence(WtMaterial m, float factor, float ior, float thicknessMin, float thicknessMax);

}  // namespace wt
