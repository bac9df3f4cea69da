// Displaced triangle meshes without pre-tessellation. A base triangle with
// corner positions P, normals N and texture coordinates T is displaced along
// its linearly interpolated (not renormalised) normal by d = scale h(uv) +
// offset, h the displacement map sampled bilinearly (repeat wrap). The
// surface is the level-L micro-mesh: the base triangle's barycentric domain
// cut into 4^L micro-triangles (2^L per edge, WT_PRIM_DISPLACED and the rows
// in shared/types.h), each micro-vertex displaced exactly, each
// micro-triangle flat. It is never stored: the ray walks the quadtree of
// sub-triangles (each splits into four at its edge midpoints), bounding each
// by its shell, the box of its corners moved by the least and the largest d
// over the texels its micro-vertices read (a min-max mip pyramid of the map
// answers that in at most four reads). Because P and N are linear in the
// barycentrics, every point P + d N with d in [dmin, dmax] lies in the
// convex hull of the six shell corners: the bound is exact, not a guess. The
// finest level's micro-triangles are intersected by the watertight test
// (triangle.cl). This is the min-max-tree variant of Thonat et al. 2021
// ("Tessellation-free displacement mapping for ray tracing"): the same
// shells and texel hierarchy, with flat micro-triangles at the leaves, so
// the surface equals a tessellation at the same rate (the --tessellate
// comparison) and hits are exact rather than a root search.
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
  uint mips;                   ///< min-max pyramid levels above the texels (the last is 1 x 1)
  __global const float* texels;///< w h floats, row-major from the top (v = 0)
  __global const float* rows;  ///< the type's first row as floats (mip offsets count from here)
  __global const float4* header;
} DispMesh;

/// A base triangle's corners (a, b, c), in its winding's order.
typedef struct DispTri {
  float3 p[3];   ///< positions, world
  float3 n[3];   ///< normals as stored (unit at the corners; interpolated linearly)
  float2 uv[3];  ///< texture coordinates
} DispTri;

inline DispMesh disp_mesh(__global const float4* rows, uint mesh_row) {
  DispMesh m;
  __global const float4* hdr = rows + mesh_row;
  m.header = hdr;
  m.scale = hdr[0].x;
  m.offset = hdr[0].y;
  m.w = (int)hdr[0].z;
  m.h = (int)hdr[0].w;
  uint4 b = as_uint4(hdr[1]);
  m.level = b.x;
  m.mips = b.y;
  m.rows = (__global const float*)rows;
  m.texels = m.rows + b.z;
  return m;
}

/// Mip level k's (>= 1) min-max pairs: the floats' offset from the type's first row.
inline uint disp_mip_offset(DispMesh m, uint k) {
  uint slot = k - 1u;
  return as_uint(((__global const float*)(m.header + 2))[slot]);
}

inline DispTri disp_tri(__global const float4* rows, uint4 corners) {
  DispTri t;
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
  float fs = (float)size;
  return (int)(x - fs * floor(x / fs));
}

inline float disp_texel(DispMesh m, int x, int y) { return m.texels[(uint)y * (uint)m.w + (uint)x]; }

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

/// The texels a bilinear sample anywhere in [lo, hi] (one axis, in texel
/// units less a half) reads: [*a, *b] wrapped into [0, size), contiguous;
/// the whole axis where the range wraps or is not finite.
inline void disp_axis_range(float lo, float hi, int size, int* a, int* b) {
  float f0 = floor(lo), f1 = floor(hi) + 1.0f;
  if (!(f1 - f0 < (float)size) || !(fabs(f0) < 4194304.0f && fabs(f1) < 4194304.0f)) {
    *a = 0;
    *b = size - 1;
    return;
  }
  int w0 = disp_wrap(f0, size);
  int w1 = w0 + (int)(f1 - f0);
  if (w1 >= size) {
    *a = 0;
    *b = size - 1;
    return;
  }
  *a = w0;
  *b = w1;
}

/// The least and the largest map value a bilinear sample at any uv of the
/// box [uv_lo, uv_hi] can take: the texels it reads, through the pyramid's
/// level at which they span two cells per axis at most.
inline float2 disp_map_range(DispMesh m, float2 uv_lo, float2 uv_hi) {
  // a sliver of slack: micro-vertices' uv round a little differently from the corners'
  float2 slack = 1e-6f * (fabs(uv_lo) + fabs(uv_hi)) + 1e-7f;
  float2 lo = (uv_lo - slack) * (float2)((float)m.w, (float)m.h) - 0.5f;
  float2 hi = (uv_hi + slack) * (float2)((float)m.w, (float)m.h) - 0.5f;
  int x0, x1, y0, y1;
  disp_axis_range(lo.x, hi.x, m.w, &x0, &x1);
  disp_axis_range(lo.y, hi.y, m.h, &y0, &y1);
  uint k = 0;
  while (k < m.mips && (((x1 >> k) - (x0 >> k)) > 1 || ((y1 >> k) - (y0 >> k)) > 1)) ++k;
  float vmin = INFINITY, vmax = -INFINITY;
  if (k == 0) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        float v = disp_texel(m, x, y);
        vmin = fmin(vmin, v);
        vmax = fmax(vmax, v);
      }
    return (float2)(vmin, vmax);
  }
  int wk = (m.w + (1 << k) - 1) >> k;
  __global const float* level = m.rows + disp_mip_offset(m, k);
  for (int y = y0 >> k; y <= (y1 >> k); ++y)
    for (int x = x0 >> k; x <= (x1 >> k); ++x) {
      uint c = 2u * ((uint)y * (uint)wk + (uint)x);
      vmin = fmin(vmin, level[c]);
      vmax = fmax(vmax, level[c + 1u]);
    }
  return (float2)(vmin, vmax);
}

/// The base surface at lattice point (i, j) of 2^L per edge (weights
/// (n - i - j, i, j) / n on corners a, b, c): position, normal, uv. The
/// same operations in the same order for every triangle, contraction off:
/// a point on a shared edge is the same bits from both sides.
inline void disp_base(DispTri t, int n, float inv_n, int i, int j, float3* p, float3* nrm, float2* uv) {
#pragma OPENCL FP_CONTRACT OFF
  float wa = (float)(n - i - j) * inv_n, wb = (float)i * inv_n, wc = (float)j * inv_n;
  float3 pa = wa * t.p[0], pb = wb * t.p[1], pc = wc * t.p[2];
  *p = (pa + pb) + pc;
  float3 na = wa * t.n[0], nb = wb * t.n[1], nc = wc * t.n[2];
  *nrm = (na + nb) + nc;
  float2 ua = wa * t.uv[0], ub = wb * t.uv[1], uc = wc * t.uv[2];
  *uv = (ua + ub) + uc;
}

/// The displaced micro-vertex at lattice point (i, j).
inline float3 disp_vertex(DispMesh m, DispTri t, int n, float inv_n, int i, int j) {
#pragma OPENCL FP_CONTRACT OFF
  float3 p, nrm;
  float2 uv;
  disp_base(t, n, inv_n, i, j, &p, &nrm, &uv);
  // no NaN here: the host wrote NaN texels as 0 (gatherDisplaced)
  float d = m.scale * disp_sample(m, uv) + m.offset;
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

/// A shell's bound: a box and a slab along the base triangle's face
/// normal (the range of dot(x, fn) over the shell's six corners). The slab
/// cuts the box down where the sub-triangle lies slanted to the axes.
typedef struct DispShell {
  float3 lo, hi;   ///< box, world
  float slo, shi;  ///< slab: dot(x, fn) in [slo, shi]
} DispShell;

/// The per-ray constants of the shell test.
typedef struct DispRay {
  float3 o, inv_d;
  float on, inv_dn;  ///< dot(o, fn) and 1 / dot(d, fn) (+-1e30 for a ray along the slab)
} DispRay;

/// The ray's entry into the shell in (tmin, tmax), widened for rounding
/// as the BVH's slab tests; INFINITY for a miss.
inline float disp_shell_hit(DispShell sh, DispRay r, float tmin, float tmax) {
  float3 t0 = (sh.lo - r.o) * r.inv_d, t1 = (sh.hi - r.o) * r.inv_d;
  float3 tn = fmin(t0, t1), tf = fmax(t0, t1);
  float s0 = (sh.slo - r.on) * r.inv_dn, s1 = (sh.shi - r.on) * r.inv_dn;
  float ta = fmax(fmax(fmax(tn.x, tn.y), fmax(tn.z, fmin(s0, s1))), tmin);
  float tb = fmin(fmin(fmin(tf.x, tf.y), fmin(tf.z, fmax(s0, s1))), tmax) * (1.0f + 2.0f * spawn_gamma(3));
  return ta <= tb ? ta : INFINITY;
}

/// The shell of the triangle with corners p0, p1, p2 (normals n0, n1, n2),
/// each moved by dlo and by dhi along its normal: a box and a slab along
/// fn, widened past the micro-vertices' rounding. The corners come by
/// value: no pointer into the caller's private arrays, which could keep
/// them out of registers.
inline DispShell disp_shell_between(float3 fn, float3 p0, float3 p1, float3 p2, float3 n0, float3 n1, float3 n2,
                                    float dlo, float dhi) {
  float3 p[3] = {p0, p1, p2}, nn[3] = {n0, n1, n2};
  float3 a = (float3)(INFINITY), b = (float3)(-INFINITY);
  float slo = INFINITY, shi = -INFINITY, mag = 0.0f;
  float3 afn = fabs(fn);
  for (int k = 0; k < 3; ++k) {
    float3 x = p[k] + dlo * nn[k], y = p[k] + dhi * nn[k];
    a = fmin(a, fmin(x, y));
    b = fmax(b, fmax(x, y));
    float sx = dot(x, fn), sy = dot(y, fn);
    slo = fmin(slo, fmin(sx, sy));
    shi = fmax(shi, fmax(sx, sy));
    mag = fmax(mag, fmax(dot(fabs(x), afn), dot(fabs(y), afn)));
  }
  DispShell sh;
  float3 pad = 4e-6f * fmax(fabs(a), fabs(b)) + 1e-6f * (b - a);
  sh.lo = a - pad;
  sh.hi = b + pad;
  float spad = 8e-6f * mag + 1e-6f * (shi - slo);
  sh.slo = slo - spad;
  sh.shi = shi + spad;
  return sh;
}

/// The shell of the sub-triangle with corners (k0, k1, k2) among the
/// points (positions p, normals nn, uv): each corner moved by the least and
/// the largest displacement over its texels.
inline DispShell disp_shell(DispMesh m, float3 fn, const float3* p, const float3* nn, const float2* uv, int k0, int k1,
                            int k2) {
  float2 ulo = fmin(fmin(uv[k0], uv[k1]), uv[k2]), uhi = fmax(fmax(uv[k0], uv[k1]), uv[k2]);
  float2 r = disp_map_range(m, ulo, uhi);
  float d0 = m.scale * r.x + m.offset, d1 = m.scale * r.y + m.offset;
  return disp_shell_between(fn, p[k0], p[k1], p[k2], nn[k0], nn[k1], nn[k2], fmin(d0, d1), fmax(d0, d1));
}

/// Ray (o, d) against displaced base triangle `tri` (its WT_DISP_INFO_ROWS
/// prim_info rows) in (tmin, tmax): the nearest micro-triangle hit, its t,
/// and the hit's lattice coordinates (level-L units) in *li, *lj, which
/// displaced_surface takes back. `rows`: the type's first prim_data row.
inline bool displaced_intersect(__global const float4* rows, __global const uint4* tri, float3 o, float3 d,
                                float tmin, float tmax, float* t_hit, float* li, float* lj) {
  uint4 info = tri[0];
  DispMesh m = disp_mesh(rows, info.y);
  DispTri t = disp_tri(rows, tri[1]);
  uint level_l = m.level;
  int n = 1 << level_l;
  float inv_n = 1.0f / (float)n;
  float3 fn = cross(t.p[1] - t.p[0], t.p[2] - t.p[0]);
  DispRay ray;
  ray.o = o;
  ray.inv_d = 1.0f / select(d, copysign((float3)(1e-30f), d), fabs(d) < 1e-30f);
  ray.on = dot(o, fn);
  float dn = dot(d, fn);
  ray.inv_dn = 1.0f / (fabs(dn) < 1e-30f ? copysign(1e-30f, dn) : dn);
  float best = tmax;
  bool found = false;
  uint stack[3 * WT_DISP_MAX_LEVEL + 4];
  float stack_t[3 * WT_DISP_MAX_LEVEL + 4];
  // the whole triangle's shell first, from its stored displacement range:
  // most triangles the BVH's box lets through stop here
  DispShell whole =
      disp_shell_between(fn, t.p[0], t.p[1], t.p[2], t.n[0], t.n[1], t.n[2], as_float(info.z), as_float(info.w));
  if (disp_shell_hit(whole, ray, tmin, tmax) == INFINITY) return false;
  RayShear shear = triangle_ray_shear(d);
  int sp = 0;
  stack[sp] = disp_node(0u, 0u, 0u, 0u);
  stack_t[sp++] = tmin;
  // the child table: corner triples among [A, B, C, AB, AC, BC] and, per
  // parent orientation, the children's lattice offsets and orientation
  const int child_k[12] = {0, 3, 4, 3, 1, 5, 4, 5, 2, 3, 4, 5};
  const int up_di[4] = {0, 1, 0, 0}, up_dj[4] = {0, 0, 1, 0};
  const int inv_di[4] = {1, 0, 1, 1}, inv_dj[4] = {0, 1, 1, 1};
  while (sp > 0) {
    --sp;
    uint node = stack[sp];
    if (stack_t[sp] > best) continue;
    uint level = node >> 28;
    int2 c[3];
    disp_node_corners(node, level_l, c);
    if (level == level_l) {
      // only the root of a level-0 mesh: one flat triangle
      float3 s0 = disp_vertex(m, t, n, inv_n, c[0].x, c[0].y), s1 = disp_vertex(m, t, n, inv_n, c[1].x, c[1].y),
             s2 = disp_vertex(m, t, n, inv_n, c[2].x, c[2].y);
      float th, b1, b2;
      if (triangle_intersect(o, shear, tmin, best, s0, s1, s2, &th, &b1, &b2)) {
        best = th;
        found = true;
        *li = (float)c[0].x + b1 * (float)(c[1].x - c[0].x) + b2 * (float)(c[2].x - c[0].x);
        *lj = (float)c[0].y + b1 * (float)(c[1].y - c[0].y) + b2 * (float)(c[2].y - c[0].y);
      }
      continue;
    }
    // the six points: corners A, B, C and midpoints AB, AC, BC
    int2 q[6] = {c[0], c[1], c[2], (c[0] + c[1]) / 2, (c[0] + c[2]) / 2, (c[1] + c[2]) / 2};
    uint inverted = (node >> 27) & 1u;
    uint ci = node & 8191u, cj = (node >> 13) & 8191u;
    if (level + 1u == level_l) {
      // the children are micro-triangles: displace the six points, test the four
      float3 s[6];
      for (int k = 0; k < 6; ++k) s[k] = disp_vertex(m, t, n, inv_n, q[k].x, q[k].y);
      for (int k = 0; k < 4; ++k) {
        int k0 = child_k[3 * k], k1 = child_k[3 * k + 1], k2 = child_k[3 * k + 2];
        float th, b1, b2;
        if (triangle_intersect(o, shear, tmin, best, s[k0], s[k1], s[k2], &th, &b1, &b2)) {
          best = th;
          found = true;
          *li = (float)q[k0].x + b1 * (float)(q[k1].x - q[k0].x) + b2 * (float)(q[k2].x - q[k0].x);
          *lj = (float)q[k0].y + b1 * (float)(q[k1].y - q[k0].y) + b2 * (float)(q[k2].y - q[k0].y);
        }
      }
      continue;
    }
    // inner children: their shells, pushed farthest first
    float3 p[6], nn[6];
    float2 uv[6];
    for (int k = 0; k < 6; ++k) disp_base(t, n, inv_n, q[k].x, q[k].y, &p[k], &nn[k], &uv[k]);
    uint kids[4];
    float kt[4];
    int count = 0;
    for (int k = 0; k < 4; ++k) {
      float te = disp_shell_hit(disp_shell(m, fn, p, nn, uv, child_k[3 * k], child_k[3 * k + 1], child_k[3 * k + 2]),
                                ray, tmin, best);
      if (te == INFINITY) continue;
      uint di = (uint)(inverted ? inv_di[k] : up_di[k]), dj = (uint)(inverted ? inv_dj[k] : up_dj[k]);
      uint kid_inv = (k == 3) ? 1u - inverted : inverted;
      // insertion by entry distance, nearest last (popped first)
      uint id = disp_node(level + 1u, kid_inv, 2u * ci + di, 2u * cj + dj);
      int at = count++;
      while (at > 0 && kt[at - 1] < te) {
        kids[at] = kids[at - 1];
        kt[at] = kt[at - 1];
        --at;
      }
      kids[at] = id;
      kt[at] = te;
    }
    for (int k = 0; k < count; ++k) {
      stack[sp] = kids[k];
      stack_t[sp++] = kt[k];
    }
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
  DispTri t = disp_tri(rows, tri[1]);
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

#endif  // WT_GEOMETRY_DISPLACED_CL
