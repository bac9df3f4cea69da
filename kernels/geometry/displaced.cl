// Displaced triangle meshes without pre-tessellation. A base triangle with
// corner positions P, normals N and texture coordinates T is displaced along
// its linearly interpolated (not renormalised) normal by d = scale h(uv) +
// offset, h the displacement map sampled bilinearly (repeat wrap). The
// surface is the level-L micro-mesh: the base triangle's barycentric domain
// cut into 4^L micro-triangles (2^L per edge, WT_PRIM_DISPLACED and the rows
// in shared/types.h), each micro-vertex displaced exactly, each
// micro-triangle flat. It is never stored, only each micro-vertex's d where
// the boxes below are exact (a float a vertex, computed on the host by the
// same float operations as disp_sample, so the same bits, and read instead
// of four texels): the ray walks the quadtree of
// sub-triangles (each splits into four at its edge midpoints), testing each
// sub-triangle's box, and tests the micro-triangles of the sub-triangles
// it reaches at the finest level, four at a time (triangle_test4_lanes).
// The boxes are stored, eight bits a coordinate relative to the parent's
// box (rounded outwards), computed on the host from the micro-vertices
// themselves (gatherDisplaced): exact bounds of the flat micro-triangles,
// far tighter than bounds from the map's range over texels. Beside the
// root's box, a slab along the face normal bounds the whole shell: a
// tilted triangle's box is far thicker than its shell, and a ray leaving
// the surface crosses its neighbours' boxes above their shells. Below the
// stored depth (levels past WT_DISP_MAX_DEPTH + 1) a sub-triangle's box
// bounds all of its descendants, which the walk then visits untested.
// This is a min-max hierarchy as in Thonat et al. 2021 ("Tessellation-free
// displacement mapping for ray tracing"), kept per base triangle over the
// micro-mesh rather than over the map's texels, with flat micro-triangles
// at the leaves, so the surface equals a tessellation at the same rate
// (the --tessellate comparison) and hits are exact rather than a root
// search.
//
// Watertight across base triangles: a micro-vertex is the weighted sum of
// the corners with exact weights (multiples of 2^-L) and no contraction; on
// an edge the third weight is exactly zero, so a vertex there is
// fl(fl(wx Px) + fl(wy Py)) from either triangle (addition commutes): the
// same bits, as are its normal, uv, map sample and displaced position.
#ifndef WT_GEOMETRY_DISPLACED_CL
#define WT_GEOMETRY_DISPLACED_CL

#include "common.h"
#include "geometry/triangle.cl"

/// A displaced mesh's header rows (WT_DISP_MESH_ROWS) unpacked.
typedef struct DispMesh {
  float scale, offset;         ///< d = scale h + offset, world units
  int w, h;                    ///< the map's texels per axis
  uint level;                  ///< L: 2^L micro-edges per base edge
  uint depth;                  ///< D: the deepest level whose sub-triangles' boxes are stored
  __global const float* texels;///< w h floats, row-major from the top (v = 0); null for a paletted map
  __global const uchar* bytes; ///< a paletted map's texels, indices into palette, in 8 x 8 tiles (one cache line; rows of ceil(w / 8) tiles)
  __global const float* palette;///< a paletted map's values (a map of at most 256 distinct values: 8-bit images)
} DispMesh;

/// A base triangle's corners (a, b, c), in its winding's order.
typedef struct DispTri {
  float3 p[3];   ///< positions, world
  float3 n[3];   ///< normals as stored (unit at the corners; interpolated linearly)
  float2 uv[3];  ///< texture coordinates
  __global const float* d;  ///< d at every micro-vertex, row by row (j), as the map gives it; null: sample the map
} DispTri;

inline DispMesh disp_mesh(__global const float4* rows, uint mesh_row) {
  DispMesh m;
  __global const float4* hdr = rows + mesh_row;
  m.scale = hdr[0].x;
  m.offset = hdr[0].y;
  m.w = (int)hdr[0].z;
  m.h = (int)hdr[0].w;
  uint4 b = as_uint4(hdr[1]);
  m.level = b.x;
  m.depth = b.y;
  __global const float* first = (__global const float*)rows + b.z;
  bool paletted = b.w != 0xffffffffu;
  m.texels = paletted ? 0 : first;
  m.bytes = (__global const uchar*)first;
  m.palette = (__global const float*)rows + b.w;
  return m;
}

/// Base triangle `tri`'s corners and stored displacements (its WT_DISP_INFO_ROWS prim_info rows).
inline DispTri disp_tri(__global const float4* rows, __global const uint4* tri) {
  DispTri t;
  uint stored = tri[0].w;
  t.d = stored == 0xffffffffu ? 0 : (__global const float*)(rows + stored);
  uint4 corners = tri[1];
  uint idx[3] = {corners.x, corners.y, corners.z};
  for (int k = 0; k < 3; ++k) {
    float4 a = rows[idx[k]], b = rows[idx[k] + 1u];
    t.p[k] = a.xyz;
    t.n[k] = b.xyz;
    t.uv[k] = (float2)(a.w, b.w);
  }
  return t;
}

/// Wrap a texel coordinate (an integer-valued float of magnitude below 2^24) into [0, size).
inline int disp_wrap(float x, int size) {
  // inside the map (the common case): no division
  int xi = (int)x;
  if (xi >= 0 && xi < size) return xi;
  float fs = (float)size;
  return (int)(x - fs * floor(x / fs));
}

inline float disp_texel(DispMesh m, int x, int y) {
  if (m.texels) return m.texels[(uint)y * (uint)m.w + (uint)x];
  // tiled: a bilinear footprint and its neighbours' mostly share a cache line
  uint tiles_x = ((uint)m.w + 7u) >> 3;
  uint tile = ((uint)y >> 3) * tiles_x + ((uint)x >> 3);
  return m.palette[m.bytes[64u * tile + (((uint)y & 7u) << 3) + ((uint)x & 7u)]];
}

/// The map at uv, bilinear between texel centres, repeating; 0 where uv is
/// not finite or beyond 2^22 repeats (the loaders refuse such uv).
inline float disp_sample(DispMesh m, float2 uv) {
  float x = uv.x * (float)m.w - 0.5f, y = uv.y * (float)m.h - 0.5f;
  if (!(fabs(x) < 4194304.0f && fabs(y) < 4194304.0f)) return 0.0f;
  float fx0 = floor(x), fy0 = floor(y);
  float fx = x - fx0, fy = y - fy0;
  int x0 = disp_wrap(fx0, m.w), y0 = disp_wrap(fy0, m.h);
  int x1 = x0 + 1 == m.w ? 0 : x0 + 1, y1 = y0 + 1 == m.h ? 0 : y0 + 1;
  float a = disp_texel(m, x0, y0), b = disp_texel(m, x1, y0), c = disp_texel(m, x0, y1), d = disp_texel(m, x1, y1);
  return (a * (1.0f - fx) + b * fx) * (1.0f - fy) + (c * (1.0f - fx) + d * fx) * fy;
}

/// The displaced micro-vertex at lattice point (i, j) of 2^L per edge
/// (weights (n - i - j, i, j) / n on corners a, b, c): the base position
/// moved by d along the base normal. The same operations in the same order
/// for every triangle, contraction off: a point on a shared edge is the
/// same bits from both sides.
inline float3 disp_vertex(DispMesh m, DispTri t, int n, float inv_n, int i, int j) {
#pragma OPENCL FP_CONTRACT OFF
  float wa = (float)(n - i - j) * inv_n, wb = (float)i * inv_n, wc = (float)j * inv_n;
  float3 pa = wa * t.p[0], pb = wb * t.p[1], pc = wc * t.p[2];
  float3 p = (pa + pb) + pc;
  float3 na = wa * t.n[0], nb = wb * t.n[1], nc = wc * t.n[2];
  float3 nrm = (na + nb) + nc;
  float d;
  if (t.d) {
    // the host's d, the same float operations on the same uv as below (gatherDisplaced): no map read
    d = t.d[j * (2 * n + 3 - j) / 2 + i];
  } else {
    float2 ua = wa * t.uv[0], ub = wb * t.uv[1], uc = wc * t.uv[2];
    float2 uv = (ua + ub) + uc;
    // no NaN here: the host wrote NaN texels as 0 (gatherDisplaced)
    d = m.scale * disp_sample(m, uv) + m.offset;
  }
  float3 dn = d * nrm;
  return p + dn;
}

/// A quadtree node: level (top four bits), inverted (bit 27), i (bits 0-12)
/// and j (bits 13-25) in that level's lattice. Upright (i, j) has corners
/// (i, j), (i + 1, j), (i, j + 1); inverted (i + 1, j), (i, j + 1), (i + 1, j + 1).
inline uint disp_node(uint level, uint inverted, uint i, uint j) { return (level << 28) | (inverted << 27) | (j << 13) | i; }

/// Node `node`'s corners in the level-L lattice (s = 2^(L - level)).
inline void disp_node_corners(uint node, uint level_l, int2* c) {
  uint level = node >> 28;
  int s = 1 << (level_l - level);
  int i = (int)(node & 8191u), j = (int)((node >> 13) & 8191u);
  if ((node >> 27) & 1u) {
    c[0] = (int2)((i + 1) * s, j * s);
    c[1] = (int2)(i * s, (j + 1) * s);
    c[2] = (int2)((i + 1) * s, (j + 1) * s);
  } else {
    c[0] = (int2)(i * s, j * s);
    c[1] = (int2)((i + 1) * s, j * s);
    c[2] = (int2)(i * s, (j + 1) * s);
  }
}

/// The six micro-vertices q[0..5] of a leaf from the stored displacements,
/// less o, in the shear's axis order: disp_vertex's float operations in
/// the same order, one vertex a lane (the same bits as six calls).
inline void disp_leaf_vertices(DispTri t, int n, float inv_n, const int2* q, float3 o, RayShear shear, float* x,
                               float* y, float* z) {
#pragma OPENCL FP_CONTRACT OFF
  int8 i = (int8)(q[0].x, q[1].x, q[2].x, q[3].x, q[4].x, q[5].x, q[0].x, q[0].x);
  int8 j = (int8)(q[0].y, q[1].y, q[2].y, q[3].y, q[4].y, q[5].y, q[0].y, q[0].y);
  float8 wa = convert_float8((int8)(n) - i - j) * inv_n, wb = convert_float8(i) * inv_n, wc = convert_float8(j) * inv_n;
  int8 at = j * ((int8)(2 * n + 3) - j) / 2 + i;
  float8 d = (float8)(t.d[at.s0], t.d[at.s1], t.d[at.s2], t.d[at.s3], t.d[at.s4], t.d[at.s5], t.d[at.s0], t.d[at.s0]);
  float8 px = (wa * t.p[0].x + wb * t.p[1].x) + wc * t.p[2].x;
  float8 py = (wa * t.p[0].y + wb * t.p[1].y) + wc * t.p[2].y;
  float8 pz = (wa * t.p[0].z + wb * t.p[1].z) + wc * t.p[2].z;
  float8 nx = (wa * t.n[0].x + wb * t.n[1].x) + wc * t.n[2].x;
  float8 ny = (wa * t.n[0].y + wb * t.n[1].y) + wc * t.n[2].y;
  float8 nz = (wa * t.n[0].z + wb * t.n[1].z) + wc * t.n[2].z;
  float8 ax = (px + d * nx) - o.x, ay = (py + d * ny) - o.y, az = (pz + d * nz) - o.z;
  float8 sx = shear.kx == 0 ? ax : (shear.kx == 1 ? ay : az);
  float8 sy = shear.ky == 0 ? ax : (shear.ky == 1 ? ay : az);
  float8 sz = shear.kz == 0 ? ax : (shear.kz == 1 ? ay : az);
  x[0] = sx.s0, x[1] = sx.s1, x[2] = sx.s2, x[3] = sx.s3, x[4] = sx.s4, x[5] = sx.s5;
  y[0] = sy.s0, y[1] = sy.s1, y[2] = sy.s2, y[3] = sy.s3, y[4] = sy.s4, y[5] = sy.s5;
  z[0] = sz.s0, z[1] = sz.s1, z[2] = sz.s2, z[3] = sz.s3, z[4] = sz.s4, z[5] = sz.s5;
}

/// The four micro-triangles of level L - 1 node `node` (corners c) against
/// the ray, at once: the six micro-vertices (corners A, B, C, midpoints AB,
/// AC, BC) displaced, the children's corner triples of `child_k` in the
/// lanes. A nearer hit than *best moves *best and the lattice point *li, *lj.
inline bool disp_leaf_hit(DispMesh m, DispTri t, int n, float inv_n, int2 c0, int2 c1, int2 c2, float3 o,
                          RayShear shear, float tmin, float* best, float* li, float* lj) {
  int2 q[6] = {c0, c1, c2, (c0 + c1) / 2, (c0 + c2) / 2, (c1 + c2) / 2};
  float x[6], y[6], z[6];
  if (t.d) {
    disp_leaf_vertices(t, n, inv_n, q, o, shear, x, y, z);
  } else {
    for (int k = 0; k < 6; ++k) {
      float3 a = disp_vertex(m, t, n, inv_n, q[k].x, q[k].y) - o;
      x[k] = vec3_component(a, shear.kx);
      y[k] = vec3_component(a, shear.ky);
      z[k] = vec3_component(a, shear.kz);
    }
  }
  // lanes: (A, AB, AC), (AB, B, BC), (AC, BC, C), (AB, AC, BC), as the quadtree's children
  TriangleLanes h = triangle_test4_lanes(
      shear, tmin, *best, (float4)(x[0], x[3], x[4], x[3]), (float4)(y[0], y[3], y[4], y[3]),
      (float4)(z[0], z[3], z[4], z[3]), (float4)(x[3], x[1], x[5], x[4]), (float4)(y[3], y[1], y[5], y[4]),
      (float4)(z[3], z[1], z[5], z[4]), (float4)(x[4], x[5], x[2], x[5]), (float4)(y[4], y[5], y[2], y[5]),
      (float4)(z[4], z[5], z[2], z[5]));
  if (!triangle_any4(h)) return false;
  float th, b1, b2;
  uint lane = triangle_nearest4(h, 0u, &th, &b1, &b2);
  const int child_k[12] = {0, 3, 4, 3, 1, 5, 4, 5, 2, 3, 4, 5};
  int2 k0 = q[child_k[3u * lane]], k1 = q[child_k[3u * lane + 1u]], k2 = q[child_k[3u * lane + 2u]];
  *best = th;
  *li = (float)k0.x + b1 * (float)(k1.x - k0.x) + b2 * (float)(k2.x - k0.x);
  *lj = (float)k0.y + b1 * (float)(k1.y - k0.y) + b2 * (float)(k2.y - k0.y);
  return true;
}

/// The part of the ray (o, d) inside the slab lo <= dot(nrm, p) <= hi, widened
/// past every rounding of this computation: *enter at most, *leave at least
/// the exact distances for the stored floats (an unbounded interval where the
/// ray runs too close to parallel to the slab to tell, or nrm is zero).
inline void disp_slab_interval(float3 nrm, float lo, float hi, float3 o, float3 d, float* enter, float* leave) {
  float s = dot(nrm, o), ds = dot(nrm, d);
  float3 an = fabs(nrm);
  // a dot product of three is within gamma(3) of the sum of its terms' magnitudes
  float es = spawn_gamma(5) * (dot(an, fabs(o)) + fmax(fabs(lo), fabs(hi)));
  float ed = spawn_gamma(5) * dot(an, fabs(d));
  float ad = fabs(ds);
  *enter = -INFINITY;
  *leave = INFINITY;
  if (!(ad > 2.0f * ed)) return;
  // distances to the entering and the leaving side along |ds|, numerators widened by their error
  float ne = (ds > 0.0f ? lo - s : s - hi) - es, nx = (ds > 0.0f ? hi - s : s - lo) + es;
  float te = ne / (ne >= 0.0f ? ad + ed : ad - ed), tx = nx / (nx >= 0.0f ? ad - ed : ad + ed);
  // fmax, fmin: a NaN (overflowing input) leaves that side open
  *enter = fmax(te - spawn_gamma(2) * fabs(te), -INFINITY);
  *leave = fmin(tx + spawn_gamma(2) * fabs(tx), INFINITY);
}

// Larger and smaller of two distances, without fmax and fmin's NaN rules (no NaN here: finite boxes, inv_d finite)
inline float4 disp_max4(float4 a, float4 b) { return a > b ? a : b; }
inline float4 disp_min4(float4 a, float4 b) { return a < b ? a : b; }

/// Ray (o, d) against displaced base triangle `tri` (its WT_DISP_INFO_ROWS
/// prim_info rows) in (tmin, tmax): the nearest micro-triangle hit, its t,
/// and the hit's lattice coordinates (level-L units) in *li, *lj, which
/// displaced_surface takes back. `rows`: the type's first prim_data row.
/// The base triangle's own box (the root's, stored) is tested first: a BVH
/// leaf bounds several base triangles; then its slab along the face normal
/// (the shell's heights), which also bounds the ray's part every box below
/// is tested on. The corners are read only when the
/// walk reaches a leaf (most base triangles a ray enters are left above).
/// With `any_hit` (shadow rays) the first micro-triangle hit found in the
/// interval ends the walk, not necessarily the nearest.
inline bool displaced_intersect(__global const float4* rows, __global const uint4* tri, float3 o, float3 d,
                                float tmin, float tmax, bool any_hit, float* t_hit, float* li, float* lj) {
  uint4 info = tri[0];
  DispMesh m = disp_mesh(rows, info.y);
  uint level_l = m.level, depth = m.depth;
  int n = 1 << level_l;
  float inv_n = 1.0f / (float)n;
  float best = tmax;
  bool found = false;
  if (level_l == 0u) {
    // one flat triangle: the base triangle's corners displaced
    DispTri t = disp_tri(rows, tri);
    RayShear shear = triangle_ray_shear(d);
    float3 s0 = disp_vertex(m, t, n, inv_n, 0, 0), s1 = disp_vertex(m, t, n, inv_n, 1, 0),
           s2 = disp_vertex(m, t, n, inv_n, 0, 1);
    float th, b1, b2;
    if (!triangle_intersect(o, shear, tmin, best, s0, s1, s2, &th, &b1, &b2)) return false;
    *t_hit = th;
    *li = b1;
    *lj = b2;
    return true;
  }
  __global const float4* box_rows = rows + info.z;
  // the children's boxes, four a block (x, y, z of the lows, then of the highs), node by node in level order
  __global const uchar4* blocks = (__global const uchar4*)(box_rows + 2);
  float3 inv_d = 1.0f / select(d, copysign((float3)(1e-30f), d), fabs(d) < 1e-30f);
  float widen = 1.0f + 2.0f * spawn_gamma(3);
  float4 root_lo = box_rows[0], root_hi = box_rows[1];
  float slab_enter, slab_leave;
  {
    // a BVH leaf's box bounds several base triangles: this one's own first, before its corners are read
    float3 t0 = (root_lo.xyz - o) * inv_d, t1 = (root_hi.xyz - o) * inv_d;
    float3 near3 = fmin(t0, t1), far3 = fmax(t0, t1);
    float enter = fmax(fmax(near3.x, near3.y), fmax(near3.z, tmin));
    float leave = fmin(fmin(far3.x, far3.y), fmin(far3.z, best)) * widen;
    if (!(enter <= leave)) return false;
    // the shell's slab along the face normal, thinner than the box where the triangle is tilted: the walk
    // tests every box below on the ray's part inside it too
    disp_slab_interval(box_rows[-1].xyz, root_lo.w, root_hi.w, o, d, &slab_enter, &slab_leave);
    if (!(fmax(enter, slab_enter) <= fmin(leave, slab_leave * widen))) return false;
  }
  float4 slab_enter4 = (float4)(slab_enter);
  // the corners and the shear only where a leaf is reached
  DispTri t;
  RayShear shear;
  bool corners = false;
  // at most 3 pending per level and 4 pushed, and a push writes all four children (the misses past the top)
  uint stack[3 * WT_DISP_MAX_LEVEL + 4], stack_index[3 * WT_DISP_MAX_LEVEL + 4];
  float stack_t[3 * WT_DISP_MAX_LEVEL + 4];
  float4 stack_lo[3 * WT_DISP_MAX_LEVEL + 4], stack_hi[3 * WT_DISP_MAX_LEVEL + 4];
  int sp = 0;
  stack[sp] = disp_node(0u, 0u, 0u, 0u);
  stack_index[sp] = 0u;
  stack_t[sp] = tmin;
  stack_lo[sp] = root_lo;
  stack_hi[sp++] = root_hi;
  const int up_di[4] = {0, 1, 0, 0}, up_dj[4] = {0, 0, 1, 0};
  const int inv_di[4] = {1, 0, 1, 1}, inv_dj[4] = {0, 1, 1, 1};
  while (sp > 0) {
    --sp;
    uint node = stack[sp];
    if (stack_t[sp] > best) continue;
    uint level = node >> 28;
    if (level + 1u == level_l) {
      int2 c[3];
      disp_node_corners(node, level_l, c);
      if (!corners) {
        t = disp_tri(rows, tri);
        shear = triangle_ray_shear(d);
        corners = true;
      }
      found |= disp_leaf_hit(m, t, n, inv_n, c[0], c[1], c[2], o, shear, tmin, &best, li, lj);
      if (found && any_hit) break;
      continue;
    }
    uint inverted = (node >> 27) & 1u;
    uint ci = node & 8191u, cj = (node >> 13) & 8191u;
    uint index = stack_index[sp];
    float4 plo = stack_lo[sp], phi = stack_hi[sp];
    float4 lx, ly, lz, hx, hy, hz, tn;
    int4 ok;
    if (level < depth) {
      // the four children's boxes: parent low + q step for the lows, parent high - (255 - q) step for the
      // highs, so that 0 and 255 give the parent's own sides exactly
      __global const uchar4* q = blocks + 6u * index;
      float4 step = (phi - plo) * (1.0f / 255.0f);
      lx = plo.x + convert_float4(q[0]) * step.x, ly = plo.y + convert_float4(q[1]) * step.y,
      lz = plo.z + convert_float4(q[2]) * step.z;
      hx = phi.x - (255.0f - convert_float4(q[3])) * step.x, hy = phi.y - (255.0f - convert_float4(q[4])) * step.y,
      hz = phi.z - (255.0f - convert_float4(q[5])) * step.z;
      float4 tx0 = (lx - o.x) * inv_d.x, tx1 = (hx - o.x) * inv_d.x;
      float4 ty0 = (ly - o.y) * inv_d.y, ty1 = (hy - o.y) * inv_d.y;
      float4 tz0 = (lz - o.z) * inv_d.z, tz1 = (hz - o.z) * inv_d.z;
      tn = disp_max4(disp_max4(disp_min4(tx0, tx1), disp_min4(ty0, ty1)), disp_max4(disp_min4(tz0, tz1), (float4)(tmin)));
      float4 tf = disp_min4(disp_min4(disp_max4(tx0, tx1), disp_max4(ty0, ty1)),
                            disp_min4(disp_max4(tz0, tz1), (float4)(fmin(best, slab_leave)))) * widen;
      // the order stays the boxes' own (tn); the slab only drops children
      ok = disp_max4(tn, slab_enter4) <= tf;
    } else {
      // below the stored depth: every child, in the parent's box, untested
      lx = (float4)(plo.x), ly = (float4)(plo.y), lz = (float4)(plo.z);
      hx = (float4)(phi.x), hy = (float4)(phi.y), hz = (float4)(phi.z);
      tn = (float4)(stack_t[sp]);
      ok = (int4)(-1);
    }
    // the children hit, farthest first (pushed first, popped last), ties in child order: child k goes
    // to place sp + rank, rank the hit children before it; the others are written past the top, unused
    float t4[4] = {tn.s0, tn.s1, tn.s2, tn.s3};
    int h4[4] = {ok.s0 != 0, ok.s1 != 0, ok.s2 != 0, ok.s3 != 0};
    int count = h4[0] + h4[1] + h4[2] + h4[3];
    float lo4[3][4] = {{lx.s0, lx.s1, lx.s2, lx.s3}, {ly.s0, ly.s1, ly.s2, ly.s3}, {lz.s0, lz.s1, lz.s2, lz.s3}};
    float hi4[3][4] = {{hx.s0, hx.s1, hx.s2, hx.s3}, {hy.s0, hy.s1, hy.s2, hy.s3}, {hz.s0, hz.s1, hz.s2, hz.s3}};
    int misses = 0;
#pragma unroll
    for (int k = 0; k < 4; ++k) {
      int rank = 0;
#pragma unroll
      for (int j = 0; j < 4; ++j)
        rank += (j != k) & h4[j] & ((t4[j] > t4[k]) | ((t4[j] == t4[k]) & (j < k)));
      int at = sp + (h4[k] ? rank : count + misses);
      misses += 1 - h4[k];
      uint di = (uint)(inverted ? inv_di[k] : up_di[k]), dj = (uint)(inverted ? inv_dj[k] : up_dj[k]);
      uint kid_inv = (k == 3) ? 1u - inverted : inverted;
      stack[at] = disp_node(level + 1u, kid_inv, 2u * ci + di, 2u * cj + dj);
      stack_index[at] = 4u * index + 1u + (uint)k;
      stack_t[at] = t4[k];
      stack_lo[at] = (float4)(lo4[0][k], lo4[1][k], lo4[2][k], 0.0f);
      stack_hi[at] = (float4)(hi4[0][k], hi4[1][k], hi4[2][k], 0.0f);
    }
    sp += count;
  }
  if (found) *t_hit = best;
  return found;
}

/// The micro-triangle holding lattice point (li, lj) and the point's
/// barycentrics in it: its corners in *c, b1 and b2; whether it is inverted.
inline bool disp_micro_at(int n, float li, float lj, int2* c, float* b1, float* b2) {
  float fi = clamp(floor(li), 0.0f, (float)(n - 1)), fj = clamp(floor(lj), 0.0f, (float)(n - 1));
  int i = (int)fi, j = (int)fj;
  if (i + j > n - 1) i = n - 1 - j;
  float x = li - (float)i, y = lj - (float)j;
  if (x + y > 1.0f && i + j <= n - 2) {
    c[0] = (int2)(i + 1, j);
    c[1] = (int2)(i, j + 1);
    c[2] = (int2)(i + 1, j + 1);
    // point = c0 + b1 (c1 - c0) + b2 (c2 - c0) = (i + 1 - b1, j + b1 + b2)
    *b1 = 1.0f - x;
    *b2 = y - *b1;
    return true;
  }
  c[0] = (int2)(i, j);
  c[1] = (int2)(i + 1, j);
  c[2] = (int2)(i, j + 1);
  *b1 = x;
  *b2 = y;
  return false;
}

/// The displaced surface's tangents at lattice point (li, lj), as bump
/// mapping on the smooth base: the base edges (along b1 and b2) made
/// perpendicular to the interpolated normal, tilted along it by the map's
/// slope (central differences one texel apart). With no displacement their
/// cross product is the interpolated normal, as a triangle's shading normal.
inline void disp_tangents(DispMesh m, DispTri t, float li, float lj, float inv_n, float3* sb, float3* sc,
                          float3* nrm_unit) {
  float wb = li * inv_n, wc = lj * inv_n, wa = 1.0f - wb - wc;
  float3 nrm = wa * t.n[0] + wb * t.n[1] + wc * t.n[2];
  float2 uv = wa * t.uv[0] + wb * t.uv[1] + wc * t.uv[2];
  float len = length(nrm);
  nrm = (len > 0.0f && isfinite(len)) ? nrm / len : (float3)(0.0f);
  float du = 1.0f / (float)m.w, dv = 1.0f / (float)m.h;
  float hu = (disp_sample(m, uv + (float2)(du, 0.0f)) - disp_sample(m, uv - (float2)(du, 0.0f))) * (0.5f * (float)m.w);
  float hv = (disp_sample(m, uv + (float2)(0.0f, dv)) - disp_sample(m, uv - (float2)(0.0f, dv))) * (0.5f * (float)m.h);
  float2 uvb = t.uv[1] - t.uv[0], uvc = t.uv[2] - t.uv[0];
  float3 eb = t.p[1] - t.p[0], ec = t.p[2] - t.p[0];
  eb -= dot(eb, nrm) * nrm;
  ec -= dot(ec, nrm) * nrm;
  *sb = eb + (m.scale * (hu * uvb.x + hv * uvb.y)) * nrm;
  *sc = ec + (m.scale * (hu * uvc.x + hv * uvc.y)) * nrm;
  *nrm_unit = nrm;
}

/// The surface where a ray hit base triangle `tri` at lattice point (li,
/// lj) (displaced_intersect's): the point from the micro-triangle's
/// barycentrics with its error bound, the micro-triangle's unit normal (the
/// base winding's side), the displaced surface's shading normal (on the
/// side of the interpolated normal), the mesh's uv and dp/du.
inline void displaced_surface(__global const float4* rows, __global const uint4* tri, float li, float lj, float3* p,
                              float3* p_error, float3* ng, float3* ns, float2* uv, float3* dpdu) {
  uint4 info = tri[0];
  DispMesh m = disp_mesh(rows, info.y);
  DispTri t = disp_tri(rows, tri);
  int n = 1 << m.level;
  float inv_n = 1.0f / (float)n;
  int2 c[3];
  float b1, b2;
  bool inverted = disp_micro_at(n, li, lj, c, &b1, &b2);
  float3 s0 = disp_vertex(m, t, n, inv_n, c[0].x, c[0].y), s1 = disp_vertex(m, t, n, inv_n, c[1].x, c[1].y),
         s2 = disp_vertex(m, t, n, inv_n, c[2].x, c[2].y);
  float3 err;
  *p = triangle_point(s0, s1, s2, b1, b2, &err);
  // the lattice point's own rounding moves the point along the micro-triangle
  float3 e1 = s1 - s0, e2 = s2 - s0;
  *p_error = err + (float3)(4.0f * FLT_EPSILON * (float)n * (length(e1) + length(e2)));
  float3 g = cross(e1, e2);
  float len = length(g);
  // upright micro-triangles wind as (a, b, c), inverted ones the other way
  float sign = inverted ? -1.0f : 1.0f;
  *ng = (len > 0.0f && isfinite(len)) ? sign * g / len : (float3)(0.0f);
  float3 sb, sc, nrm;
  disp_tangents(m, t, li, lj, inv_n, &sb, &sc, &nrm);
  float3 sn = cross(sb, sc);
  float sl = length(sn);
  sn = (sl > 0.0f && isfinite(sl)) ? sn / sl : *ng;
  if (dot(sn, nrm) < 0.0f) sn = -sn;
  *ns = sn;
  float wb = li * inv_n, wc = lj * inv_n, wa = 1.0f - wb - wc;
  *uv = wa * t.uv[0] + wb * t.uv[1] + wc * t.uv[2];
  *dpdu = sb;
}

/// The micro-triangle holding lattice point (li, lj) (disp_micro_at): its
/// displaced corners and whether it is inverted; its barycentrics in *b1, *b2.
inline bool disp_micro_corners(DispMesh m, DispTri t, int n, float inv_n, float li, float lj, float3* s0, float3* s1,
                               float3* s2, float* b1, float* b2) {
  int2 c[3];
  bool inverted = disp_micro_at(n, li, lj, c, b1, b2);
  *s0 = disp_vertex(m, t, n, inv_n, c[0].x, c[0].y);
  *s1 = disp_vertex(m, t, n, inv_n, c[1].x, c[1].y);
  *s2 = disp_vertex(m, t, n, inv_n, c[2].x, c[2].y);
  return inverted;
}

/// A point of base triangle `tri`'s displaced surface sampled for
/// next-event estimation from p, as solid angle. Uniform in the base
/// triangle's barycentric domain: each of the 4^L micro-triangles is picked
/// with probability 4^-L and is sampled uniformly (the lattice maps onto it
/// affinely), so the area pdf is 1 / (4^L its area), which
/// displaced_emitter_pdf gives a BSDF hit. False where the micro-triangle
/// is degenerate or turns its back to p and only its front emits (shade's rule).
inline bool displaced_sample_emitter(__global const float4* rows, __global const uint4* tri, float3 p, float u1,
                                     float u2, bool two_sided, float3* wi, float* distance, float3* target,
                                     float* pdf) {
  DispMesh m = disp_mesh(rows, tri[0].y);
  DispTri t = disp_tri(rows, tri);
  int n = 1 << m.level;
  float inv_n = 1.0f / (float)n;
  float su = sqrt(u1);
  float3 s0, s1, s2;
  float b1, b2;
  bool inverted = disp_micro_corners(m, t, n, inv_n, (float)n * (su * (1.0f - u2)), (float)n * (su * u2), &s0, &s1,
                                     &s2, &b1, &b2);
  float3 q_error;
  float3 q = triangle_point(s0, s1, s2, b1, b2, &q_error);
  float3 e1 = s1 - s0, e2 = s2 - s0;
  q_error += (float3)(4.0f * FLT_EPSILON * (float)n * (length(e1) + length(e2)));
  float3 g = cross(e1, e2);
  float area2 = length(g);
  float3 to_light = q - p;
  float d2 = dot(to_light, to_light);
  if (!(area2 > 0.0f) || !isfinite(area2) || !(d2 > 0.0f) || !isfinite(d2)) return false;
  float3 ng = (inverted ? -g : g) / area2;
  float dist = sqrt(d2);
  float3 w = to_light / dist;
  float facing = dot(ng, w);
  if (!two_sided && facing > 0.0f) return false;
  float cos_light = fabs(facing);
  if (!(cos_light > 0.0f)) return false;
  *target = ray_offset_origin(q, q_error, facing < 0.0f ? ng : -ng);
  *wi = w;
  *distance = dist;
  *pdf = d2 / (cos_light * 0.5f * area2 * (float)n * (float)n);
  return isfinite(*pdf);
}

/// The solid-angle pdf with which displaced_sample_emitter reaches, from
/// `origin`, the hit at p (unit geometric normal ng, lattice point (li, lj)).
inline float displaced_emitter_pdf(__global const float4* rows, __global const uint4* tri, float3 origin, float3 p,
                                   float3 ng, float li, float lj) {
  DispMesh m = disp_mesh(rows, tri[0].y);
  DispTri t = disp_tri(rows, tri);
  int n = 1 << m.level;
  float inv_n = 1.0f / (float)n;
  float3 s0, s1, s2;
  float b1, b2;
  disp_micro_corners(m, t, n, inv_n, li, lj, &s0, &s1, &s2, &b1, &b2);
  float area = 0.5f * length(cross(s1 - s0, s2 - s0));
  float3 to_hit = p - origin;
  float d2 = dot(to_hit, to_hit);
  float cos_light = fabs(dot(ng, to_hit)) * rsqrt(d2);
  float pdf = d2 / (cos_light * area * (float)n * (float)n);
  return (area > 0.0f && cos_light > 0.0f && isfinite(pdf)) ? pdf : 0.0f;
}

#endif  // WT_GEOMETRY_DISPLACED_CL
