// Plain-data layouts shared by the host (g++) and the kernels (OpenCL C).
// One definition, two compilers: only 4-byte scalars, no float3, explicit
// padding. The host static_asserts every size (host/device/scene_buffers.cpp).
#ifndef WT_SHARED_TYPES_H
#define WT_SHARED_TYPES_H

#ifdef __OPENCL_C_VERSION__
typedef uint wt_uint;
#else
#include <cstdint>
typedef std::uint32_t wt_uint;
#endif

/// Four floats; positions and directions keep w as padding or a flag.
typedef struct WtVec4 {
  float x, y, z, w;
} WtVec4;

/// A triangle of the scene (host side). On the device a triangle is its
/// corners in tri_verts (WT_TRIANGLE_BLOCK) and its vertex indices and
/// material in tri_info (a uint4: v0, v1, v2, material), both in BVH leaf
/// order.
typedef struct WtTriangle {
  wt_uint v0, v1, v2;  ///< indices into the vertex arrays
  wt_uint material;    ///< index into the material array
} WtTriangle;

/// tri_verts holds the leaf-order triangles in blocks of WT_TRIANGLE_BLOCK:
/// block b covers triangles 4b .. 4b + 3, one per lane, as nine float4
/// rows (WT_TRIANGLE_BLOCK_ROWS; 144 bytes, which touch three cache lines
/// at most). Row 3k + a is axis a (x, y, z) of corner k of the four
/// triangles. A four-lane leaf test loads the nine rows as they are, with
/// no gathering or shuffling, and each leaf is laid out to touch no more
/// blocks than its size needs (packLeavesIntoBlocks, host/bvh/bvh4.h). The
/// vertex indices that shading needs live in tri_info, out of the blocks:
/// traversal reads a quarter fewer bytes (docs/lab/2026-12-05-performance-log.md,
/// "Triangle blocks without their index rows").
#define WT_TRIANGLE_BLOCK 4
#define WT_TRIANGLE_BLOCK_ROWS 9

/// Binary BVH node, 32 bytes. Children of an internal node are adjacent:
/// left = first, right = first + 1. Node 0 is the root.
typedef struct WtBvhNode {
  float lo_x, lo_y, lo_z;  ///< box minimum, world space
  wt_uint first;           ///< internal: left child index; leaf: first primitive
  float hi_x, hi_y, hi_z;  ///< box maximum, world space
  wt_uint count;           ///< 0 for an internal node, primitive count of a leaf
} WtBvhNode;

/// 4-wide BVH node, 128 bytes, collapsed from the binary tree (host/bvh/bvh4.h).
/// The four child boxes are stored per axis and bound (structure of arrays),
/// so the kernel tests all four with float4 arithmetic. A child is an inner
/// node (count 0, child = node index), a leaf (count > 0, child = first
/// primitive in leaf order) or an empty slot (WT_BVH4_EMPTY with an inverted
/// box, lo = +inf and hi = -inf, which the slab test never enters). Node 0 is
/// the root.
typedef struct WtBvh4Node {
  float lo_x[4], hi_x[4];  ///< child boxes, world space
  float lo_y[4], hi_y[4];
  float lo_z[4], hi_z[4];
  wt_uint child[4];        ///< inner: node index; leaf: first primitive; WT_BVH4_EMPTY: no child
  wt_uint count[4];        ///< 0 for an inner node or an empty slot, primitive count of a leaf
} WtBvh4Node;
#define WT_BVH4_EMPTY 0xffffffffu
/// An inner child slot's node index with this bit set names an oriented node
/// (primitive trees only): a WtBvh4Oriented in the node's slot, whose child
/// boxes are in a frame of their own, so a ray is rotated into it before the
/// slab test. Thin diagonal curve segments fill a fraction of the
/// axis-aligned boxes around them; boxes aligned to their run fit them.
#define WT_BVH4_ORIENTED 0x80000000u

/// An oriented node, 128 bytes (the size of WtBvh4Node, whose child and
/// count it keeps in place): its frame and its child boxes in it, the boxes
/// on a grid of 255 steps per axis so that the frame fits the node's two
/// cache lines. A world point p is at rows * (p - centre) in the frame; the
/// rows are orthonormal within float rounding, so distances along a ray are
/// the same in both. Byte j of grid is plane j in WtBvh4Node's order (lo_x[4],
/// hi_x[4], lo_y[4], ...) at origin + byte * step on its axis, never inside
/// the child's true box; an empty slot has lo 255 and hi 0.
typedef struct WtBvh4Oriented {
  float rows[3][4];     ///< rotation rows (x, y, z), world to frame; w: the frame's centre, world space
  float origin[3];      ///< the grid's low corner, frame space
  float step[3];        ///< the grid's step per axis, frame space
  wt_uint grid[6];      ///< 24 bytes: the child boxes' planes in steps, WtBvh4Node's order
  wt_uint child[4];     ///< as WtBvh4Node
  wt_uint count[4];
} WtBvh4Oriented;

/// A primitive's identity in hits, skips and lights: its geometry type in
/// the top four bits (WT_PRIM_*) and its index among that type's primitives
/// below them. Triangles are type 0, so a triangle's id is its leaf-order
/// index and the triangle paths never unpack it. WT_NO_HIT (all ones) is no
/// primitive.
#define WT_PRIM_TYPE_SHIFT 28
#define WT_PRIM_INDEX_MASK 0x0fffffffu
#define WT_PRIM_TRIANGLE 0u  ///< kernels/geometry/triangle.cl, in their own BVH (nodes, tri_verts)
/// The other types' tags, WT_PRIM_<TAG>, from the list in kernels/geometry/types.def.
#include "geometry/types.def"
#ifdef __OPENCL_C_VERSION__
enum {
#else
enum : wt_uint {
#endif
  WT_GEOMETRY_TYPES(WT_GEOMETRY_TAG)
};
/// Type slots in WtGeometry: triangles and the list's types.
#define WT_PRIM_TYPES (1 WT_GEOMETRY_TYPES(WT_GEOMETRY_ONE))
/// WT_PRIM_SPHERE: kernels/geometry/sphere.cl.
/// WT_PRIM_CURVE: kernels/geometry/curve.cl, one segment (a round cone) of a curve.
/// WT_PRIM_INSTANCE: a placed copy of a geometry stored once (kernels/geometry/instance.cl).
/// Triangles: its own 4-wide tree in `nodes` after the scene's, its
/// triangles in tri_verts/tri_info after the scene's (leaf order). Spheres
/// or curves (WT_INSTANCE_PRIMITIVES): its own tree in prim_nodes after the
/// scene's, its primitives' rows after the scene's in their type's block.
/// A hit on it keeps the geometry's primitive (a leaf-order triangle or a
/// typed id) in the hit and the instance's typed id beside it (hit_instance).
/// prim_data rows per instance: object-from-scene as three float4 rows of a
/// 3x4 matrix (xyz the linear part's row, w the translation), then
/// scene-from-object the same way. prim_info: x = the geometry's root node,
/// y = WT_INSTANCE_* flags.
#define WT_INSTANCE_ROWS 6
#define WT_INSTANCE_MIRRORED 1u  ///< the transform's determinant is negative (the copy's corners 1 and 2 swapped)
#define WT_INSTANCE_PRIMITIVES 2u  ///< the root is a node of prim_nodes (spheres, curves, SDF grids, displaced meshes), not of nodes (triangles)
/// WT_PRIM_DISPLACED: a base triangle of a displaced mesh (kernels/geometry/displaced.cl),
/// intersected as 4^L micro-triangles that are never stored (their
/// corners' displacements are, up to level WT_DISP_MAX_DEPTH + 1). prim_data: per
/// mesh WT_DISP_MESH_ROWS rows: (scale, offset, map width, map height),
/// then as uint bits (L, D the deepest level with stored boxes, the
/// texels' first float, the palette's first float or ~0); then per vertex WT_DISP_VERTEX_ROWS rows
/// (position xyz and u, normal xyz and v); then per base triangle (L > 0)
/// its slab's direction nrm (xyz: the unit face normal, or zero), then its
/// boxes: two rows (the whole triangle's box: low xyz, high xyz; in w the
/// least and the largest height dot(nrm, p) over its shell), then for each
/// sub-triangle of levels 0 to D - 1 in level order (node k's children are
/// 4k + 1 to 4k + 4) a block of 24 bytes, its four children's
/// boxes relative to its own (uchar4 rows: low x, y, z, high x, y, z; low =
/// parent low + q step, high = parent high - (255 - q) step, step = parent
/// extent / 255), padded to a whole row, then where L <= D + 1 (the boxes
/// exact) the displacement d of every micro-vertex (i, j) of the level-L
/// lattice, row j after row j - 1 (index j (2^(L+1) + 3 - j) / 2 + i),
/// padded to a whole row; then the maps' texels: floats
/// row by row, or for a map of at most 256 distinct values its palette
/// (the values' bits, sorted) and a
/// byte a texel in 8 x 8 tiles, rows of ceil(w / 8) tiles. Float
/// offsets and row indices count from the type's first row. prim_info per
/// base triangle, WT_DISP_INFO_ROWS rows: (material, its mesh's first row,
/// its boxes' first row, its displacements' first row or ~0 for none),
/// then its corners' first rows in winding order
/// and its index in its mesh (mesh = first row / WT_DISP_MESH_ROWS).
#define WT_DISP_MESH_ROWS 2       ///< prim_data rows per displaced mesh
#define WT_DISP_VERTEX_ROWS 2     ///< prim_data rows per vertex
#define WT_DISP_INFO_ROWS 2       ///< prim_info rows per base triangle
#define WT_DISP_MAX_LEVEL 10      ///< L at most: 1024 micro-edges per base edge
#define WT_DISP_MAX_DEPTH 6       ///< D at most (D = min(L - 1, this)): 1365 stored blocks, 32 KiB a base triangle
/// WT_PRIM_SDF_GRID: a brick of up to WT_SDF_BRICK^3 cells of a grid of signed distances that
/// the surface crosses (kernels/geometry/sdf_grid.cl). prim_data: per grid
/// WT_SDF_GRID_ROWS rows (lattice-from-scene as a 3x4 matrix, then (cells
/// x, y, z, the longest world edge of a cell)), then the grids' corner
/// values, four floats a row. prim_info per brick, WT_SDF_INFO_ROWS rows:
/// x = material, y = grid, z = its first value (floats from the type's
/// first row), w = the brick's coordinates (9 bits each, x lowest) and
/// WT_SDF_SPARSE; then which of its cells the surface crosses, 512 bits
/// (cell x + 8 y + 64 z at bit i & 31 of word i >> 5), so the walk skips the
/// others without reading their corners.
#define WT_SDF_BRICK 8          ///< cells per brick edge
#define WT_SDF_GRID_ROWS 4      ///< prim_data rows per grid
#define WT_SDF_INFO_ROWS 5      ///< prim_info rows per brick: its row, then its cells' crossing mask
#define WT_SDF_SPARSE (1u << 27)  ///< the brick's values are its own (WT_SDF_BRICK + 1)^3 corners, x fastest; else the grid's dense array

/// The primitives other than triangles (kernels/geometry/geometry.cl): one
/// BVH over all of them whose leaves are ranges of prim_refs (typed ids),
/// and per type its rows of prim_data (float4) and prim_info (uint4).
/// prim_data rows per prim_refs entry, in leaf order after the types' rows
/// (WtGeometry::leaf_joints): a curve segment's two joint spheres (x, y, z,
/// r, its sign bit as in the curve's rows), so the walk rejects most entries
/// four at once from memory read in order and the segment test reads its
/// joints from there; other entries' rows have r = -infinity (always tested). Three entries' rows of padding follow the last.
#define WT_LEAF_JOINT_ROWS 2
typedef struct WtGeometry {
  wt_uint node_count;      ///< nodes of the primitive BVH; 0: no such primitives
  wt_uint triangle_count;  ///< leaf-order triangles: emitter slots [0, triangle_count) are triangles, the other types' follow (emitter_pdf_area)
  wt_uint leaf_joints;     ///< where the leaf joints (WT_LEAF_JOINT_ROWS per prim_refs entry) start in prim_data
  wt_uint pad1;
  wt_uint data_first[WT_PRIM_TYPES];     ///< per type: where its rows start in prim_data
  wt_uint info_first[WT_PRIM_TYPES];     ///< per type: where its rows start in prim_info
  wt_uint emitter_first[WT_PRIM_TYPES];  ///< per type: its first emitter slot (emitter_pdf_area)
} WtGeometry;

/// Stream traversal of any-hit queries (kernels/bvh_stream.cl): a work-item
/// takes WT_STREAM_WINDOW consecutive rays, groups them by the octant of
/// their direction and walks the tree once per WT_STREAM_RAYS of them (one
/// bit each in a 64-bit mask).
#define WT_STREAM_RAYS 64
#define WT_STREAM_WINDOW 256

/// A surface: Lambertian (scenes made in code, analytic tests, and glTF's
/// KHR_materials_unlit as a black emitter) or glTF metallic-roughness with
/// its layers (kernels/materials/bsdf.cl), with emission. Textured values
/// are multiplied into the factors below before bsdf_make.
typedef struct WtMaterial {
  WtVec4 base_color;  ///< linear RGB base colour in [0,1]; w = metallic in [0,1] (PBR only)
  WtVec4 emission;    ///< emitted radiance (nits) per channel (factor x strength); w = 1: both faces emit (doubleSided), 0: the front face only (counter-clockwise winding)
  float roughness;    ///< perceptual roughness in [0,1], alpha = roughness^2 (PBR only)
  wt_uint model;      ///< WT_MATERIAL_*
  float transmission; ///< KHR_materials_transmission factor in [0,1]: the share of the dielectric that is a transmitting interface (PBR only)
  float ior;          ///< KHR_materials_ior: index of refraction of that interface (1.5 by default)
  WtVec4 volume;      ///< KHR_materials_volume: xyz absorption coefficient per unit length inside (world units); w = 1: a volume boundary (refracts), 0: thin-walled (passes straight through)
  float alpha;         ///< base colour alpha factor in [0,1] (times the texture's and COLOR_0's alpha)
  wt_uint alpha_mode;  ///< WT_ALPHA_*
  float alpha_cutoff;  ///< WT_ALPHA_MASK: coverage below it is a hole
  wt_uint texture_mask;///< bit s: slot s (WT_TEXTURE_SLOT_*) is textured, by material_textures[material * WT_TEXTURE_SLOTS + s]
  WtVec4 specular;    ///< KHR_materials_specular: xyz specularColorFactor (>= 0, tints the dielectric's F0 = ((ior-1)/(ior+1))^2, capped at 1), w specularFactor in [0,1] (weight of the dielectric's whole Fresnel term); (1,1,1,1) without it (PBR only)
  WtVec4 sheen;       ///< KHR_materials_sheen: xyz sheenColorFactor in [0,1] (linear RGB; 0: no sheen), w sheenRoughnessFactor in [0,1] (PBR only)
  float clearcoat;           ///< KHR_materials_clearcoat clearcoatFactor in [0,1] (0: no coat; PBR only)
  float clearcoat_roughness; ///< clearcoatRoughnessFactor in [0,1], alpha = roughness^2
  float anisotropy;          ///< KHR_materials_anisotropy anisotropyStrength in [0,1] (0: isotropic; PBR only)
  float anisotropy_rotation; ///< anisotropyRotation: radians counter-clockwise from the tangent, in the tangent-bitangent plane
  WtVec4 iridescence; ///< KHR_materials_iridescence: x iridescenceFactor in [0,1] (0: none; PBR only), y the film's iridescenceIor, z iridescenceThicknessMinimum, w iridescenceThicknessMaximum (nm); the thickness is w where no thickness texture is read
  wt_uint priority;   ///< nested dielectrics (shared/media.h): where volume boundaries overlap, the medium of higher priority fills the overlap (extras.wavetrace.priority; 0 by default)
  float dispersion;   ///< KHR_materials_dispersion: 20 / V_d (Abbe number V_d); 0: the index is the same at every wavelength (volume boundaries only: shared/media.h)
  wt_uint shadow_pass;  ///< 1: a smooth thin wall that shadow rays cross, tinted by its straight-through transmission (SceneBuffers sets it: thinShadowPass; kernels/connect.cl)
  wt_uint pad1;
} WtMaterial;

#define WT_ALPHA_OPAQUE 0u  ///< alpha is ignored
#define WT_ALPHA_MASK 1u    ///< covered where alpha >= alpha_cutoff, a hole elsewhere
#define WT_ALPHA_BLEND 2u   ///< covered with probability alpha (stochastic transparency)

/// A material's texture slots (WtMaterial::texture_mask) and which channels
/// each one multiplies into.
#define WT_TEXTURE_SLOT_BASE_COLOR 0u          ///< rgb: base colour (sRGB), a: alpha
#define WT_TEXTURE_SLOT_METALLIC_ROUGHNESS 1u  ///< g: roughness, b: metallic
#define WT_TEXTURE_SLOT_NORMAL 2u              ///< tangent-space normal, xy scaled by WtTextureRef::scale
#define WT_TEXTURE_SLOT_EMISSIVE 3u            ///< rgb: emission (sRGB)
#define WT_TEXTURE_SLOT_TRANSMISSION 4u        ///< r: KHR_materials_transmission
#define WT_TEXTURE_SLOT_SPECULAR 5u            ///< a: KHR_materials_specular specularFactor
#define WT_TEXTURE_SLOT_SPECULAR_COLOR 6u      ///< rgb: specularColorFactor (sRGB)
#define WT_TEXTURE_SLOT_CLEARCOAT 7u           ///< r: KHR_materials_clearcoat clearcoatFactor
#define WT_TEXTURE_SLOT_CLEARCOAT_ROUGHNESS 8u ///< g: clearcoatRoughnessFactor
#define WT_TEXTURE_SLOT_CLEARCOAT_NORMAL 9u    ///< tangent-space normal of the coat, xy scaled by WtTextureRef::scale
#define WT_TEXTURE_SLOT_SHEEN_COLOR 10u        ///< rgb: KHR_materials_sheen sheenColorFactor (sRGB)
#define WT_TEXTURE_SLOT_SHEEN_ROUGHNESS 11u    ///< a: sheenRoughnessFactor
#define WT_TEXTURE_SLOT_ANISOTROPY 12u         ///< rg: direction in [-1,1] tangent-bitangent space (rotated by anisotropy_rotation), b: strength
#define WT_TEXTURE_SLOT_IRIDESCENCE 13u        ///< r: KHR_materials_iridescence iridescenceFactor
#define WT_TEXTURE_SLOT_IRIDESCENCE_THICKNESS 14u  ///< g: thickness = mix(minimum, maximum, g)
#define WT_TEXTURE_SLOTS 16u                   ///< slot 15 is free

/// One textured slot of a material: which texture (WtTexture, shared/textures.h),
/// read at which texture coordinate set, moved by KHR_texture_transform.
typedef struct WtTextureRef {
  wt_uint texture;     ///< index into the texture table
  wt_uint texcoord;    ///< 0: TEXCOORD_0, 1: TEXCOORD_1
  float scale;         ///< normal textures: normalTexture.scale; 1 otherwise
  wt_uint pad;
  WtVec4 transform_u;  ///< u' = x u + y v + z (w unused)
  WtVec4 transform_v;  ///< v' = x u + y v + z
} WtTextureRef;

#define WT_MATERIAL_DIFFUSE 0u  ///< Lambertian: base_color / pi
#define WT_MATERIAL_PBR 1u      ///< glTF 2.0 metallic-roughness

#define WT_CAMERA_PERSPECTIVE 0
#define WT_CAMERA_ORTHOGRAPHIC 1

/// Pinhole or orthographic camera, world space. A primary ray for image
/// coordinates (sx, sy) in [-1,1]^2 (y up) has direction
/// forward + sx*right + sy*up (perspective), or origin offset
/// sx*right + sy*up and direction forward (orthographic).
typedef struct WtCamera {
  WtVec4 origin;   ///< world; w = projection (WT_CAMERA_*)
  WtVec4 right;    ///< world; scaled by tan(yfov/2)*aspect, or by xmag
  WtVec4 up;       ///< world; scaled by tan(yfov/2), or by ymag
  WtVec4 forward;  ///< world, unit; w = near distance (ray tmin)
} WtCamera;

/// Per-launch constants of the wavefront loop, passed by value.
typedef struct WtFrameParams {
  wt_uint width;        ///< image width, pixels
  wt_uint height;       ///< image height, pixels
  wt_uint sample;       ///< sample index of this pass
  wt_uint bounce;       ///< bounce of this extend/shade pair (0 = camera ray)
  wt_uint max_bounces;  ///< last bounce whose hit is shaded
  wt_uint seed;         ///< user seed
  float exposure;       ///< tonemap scale: 2^stops times the physical camera's (host/render/tonemap.h)
  wt_uint max_diffuse_bounces;   ///< diffuse bounces a path may take (cosine-sampled directions)
  wt_uint light_count;     ///< entries in the light list (0: no light sampling)
  wt_uint analytic_count;  ///< lights [0, analytic_count) are point, spot or directional
  wt_uint flags;           ///< WT_FLAG_* integrator switches
  wt_uint rr_min_depth;    ///< Russian roulette starts at this bounce
  float env_pmf;           ///< probability that light selection picks the environment (0: not a light)
  wt_uint accumulate_mode; ///< WT_ACCUMULATE_*
  wt_uint max_specular_bounces;     ///< specular bounces a path may take (GGX and mirror reflection)
  wt_uint max_transmission_bounces; ///< transmission bounces a path may take (refraction, thin-walled transmission)
} WtFrameParams;

/// Precision of the per-pixel running mean (WtFrameParams::accumulate_mode).
#define WT_ACCUMULATE_SINGLE 0u  ///< float Welford updates
#define WT_ACCUMULATE_KAHAN 1u   ///< float with compensated increments
#define WT_ACCUMULATE_DOUBLE 2u  ///< double (devices with fp64 only)

/// Integrator switches in WtFrameParams::flags (runtime: no rebuild).
#define WT_FLAG_NEE 1u            ///< next-event estimation towards every light
#define WT_FLAG_MIS 2u            ///< weight NEE and BSDF hits of lights by MIS
#define WT_FLAG_POWER_HEURISTIC 4u ///< power heuristic (beta 2) instead of the balance heuristic
#define WT_FLAG_RR 8u             ///< Russian roulette
#define WT_FLAG_SOBOL 16u         ///< Owen-scrambled Sobol sampler instead of independent hashes
#define WT_FLAG_ENV_HIDDEN 32u    ///< camera rays that escape see black; the environment still lights the scene
#define WT_FLAG_CHECK_NONFINITE 64u ///< shade records the first NaN/Inf it makes (WT_COUNTER_FIRST_NONFINITE) so the host can stop there
#define WT_FLAG_COMPACT_SHADOWS 128u ///< shade appends shadow rays to its queue with an atomic counter, dense for connect_packet; otherwise entry i is item i's (WT_NO_HIT: none) and no atomic is contended
#define WT_FLAG_TEXTURE_FOOTPRINT 256u ///< textures are read at the mip level of the path's footprint (materials/textured.cl); otherwise at the finest
#define WT_FLAG_SHADOW_QUEUE 512u ///< the connect stage runs: shade clears its shadow-queue entries (without it the shadow buffers hold one entry)
#define WT_FLAG_POWER_LAMBERTIAN 1024u ///< the power heuristic at Lambertian vertices (where cosine sampling matches f cos exactly), the balance heuristic elsewhere
#define WT_FLAG_BLANK_ACCUMULATION 2048u ///< accumulate: the state and sample counts were never written (read as zero; all written), so the host need not clear them first
#define WT_FLAG_MEAN_IN_STATE 4096u ///< tonemap: `mean` is the accumulation state (float4[4] per pixel, the float mean first: single and Kahan modes), read in place without accumulate_resolve

/// Slots of the queue-counter buffer.
#define WT_COUNTER_QUEUE_A 0      ///< paths in queue A
#define WT_COUNTER_QUEUE_B 1      ///< paths in queue B
#define WT_COUNTER_NONFINITE 2    ///< samples discarded as NaN/Inf
#define WT_COUNTER_SHADOW 3       ///< entries of the shadow queue: shadow rays appended (WT_FLAG_COMPACT_SHADOWS), else the bounce's path count (set by the host)
#define WT_COUNTER_FIRST_NONFINITE 4  ///< path (= pixel) of the first NaN/Inf shade made; 0xffffffff: none (WT_FLAG_CHECK_NONFINITE)
#define WT_COUNTER_NONFINITE_WHERE 5  ///< its bounce (low 16 bits) and quantity (WT_NONFINITE_* << 16)
#define WT_COUNTER_COUNT 6

/// Which quantity turned non-finite (WT_COUNTER_NONFINITE_WHERE).
#define WT_NONFINITE_EMISSION 1u    ///< emission or sky radiance added at a hit or miss
#define WT_NONFINITE_LIGHT 2u       ///< a next-event contribution
#define WT_NONFINITE_THROUGHPUT 3u  ///< the path throughput after a bounce

#endif  // WT_SHARED_TYPES_H
