// Grids of signed distances (SDF grids): values at the corners of a lattice
// of cells, interpolated trilinearly in each cell; the surface is where the
// interpolant changes sign (negative inside). A primitive is a brick of up to
// WT_SDF_BRICK^3 cells that the surface crosses (WT_PRIM_SDF_GRID,
// shared/types.h has the rows); the ray walks the brick's cells in order
// (3D DDA) and solves, per cell the surface crosses, the cubic the
// interpolant makes along the ray exactly: split at the roots of its
// derivative into monotone pieces, the first piece whose ends differ in sign
// holds the first root, found by Newton steps kept inside the bracket
// (Söderlund et al. 2022, "Ray tracing of signed distance function grids",
// JCGT 11(3)). No fixed-epsilon marching: a crossing is never stepped over.
#ifndef WT_GEOMETRY_SDF_GRID_CL
#define WT_GEOMETRY_SDF_GRID_CL

#include "common.h"
#include "geometry/sphere.cl"  // the cone of a brick's sphere, for light sampling

/// The interpolant of one cell along a ray, c0 + c1 t + c2 t^2 + c3 t^3.
typedef struct SdfCubic {
  float c0, c1, c2, c3;
} SdfCubic;

/// The eight corner values of a cell (s[x + 2y + 4z]) as the trilinear
/// polynomial's coefficients a + b x + c y + d z + e xy + f xz + g yz + h xyz.
typedef struct SdfCell {
  float a, b, c, d, e, f, g, h;
} SdfCell;

inline SdfCell sdf_cell(__global const float* v, uint idx, uint sx, uint sxy) {
  float s000 = v[idx], s100 = v[idx + 1], s010 = v[idx + sx], s110 = v[idx + sx + 1];
  float s001 = v[idx + sxy], s101 = v[idx + sxy + 1], s011 = v[idx + sxy + sx], s111 = v[idx + sxy + sx + 1];
  SdfCell k;
  k.a = s000;
  k.b = s100 - s000;
  k.c = s010 - s000;
  k.d = s001 - s000;
  k.e = s110 - s100 - s010 + s000;
  k.f = s101 - s100 - s001 + s000;
  k.g = s011 - s010 - s001 + s000;
  k.h = s111 - s110 - s101 - s011 + s100 + s010 + s001 - s000;
  return k;
}

/// The cell's interpolant along q + t d (q, d in the cell's unit cube's frame).
inline SdfCubic sdf_cell_cubic(SdfCell k, float3 q, float3 d) {
  SdfCubic r;
  r.c3 = k.h * d.x * d.y * d.z;
  r.c2 = k.e * d.x * d.y + k.f * d.x * d.z + k.g * d.y * d.z + k.h * (q.x * d.y * d.z + q.y * d.x * d.z + q.z * d.x * d.y);
  r.c1 = k.b * d.x + k.c * d.y + k.d * d.z + k.e * (q.x * d.y + q.y * d.x) + k.f * (q.x * d.z + q.z * d.x) +
         k.g * (q.y * d.z + q.z * d.y) + k.h * (q.x * q.y * d.z + q.x * q.z * d.y + q.y * q.z * d.x);
  r.c0 = k.a + k.b * q.x + k.c * q.y + k.d * q.z + k.e * q.x * q.y + k.f * q.x * q.z + k.g * q.y * q.z +
         k.h * q.x * q.y * q.z;
  return r;
}

inline float sdf_cubic_eval(SdfCubic p, float t) { return ((p.c3 * t + p.c2) * t + p.c1) * t + p.c0; }
inline float sdf_cubic_slope(SdfCubic p, float t) { return (3.0f * p.c3 * t + 2.0f * p.c2) * t + p.c1; }

/// The root in [lo, hi] of a cubic monotone there whose ends differ in side
/// (g_lo the value at lo): Newton steps, a bisection wherever a step would
/// leave the bracket, until the bracket is `tol` wide.
inline float sdf_cubic_refine(SdfCubic p, float lo, float hi, float g_lo, float tol) {
  bool inside_lo = g_lo < 0.0f;
  float x = 0.5f * (lo + hi);
  for (int i = 0; i < 40; ++i) {
    float gx = sdf_cubic_eval(p, x);
    if ((gx < 0.0f) == inside_lo) lo = x;
    else hi = x;
    if (hi - lo <= tol) break;
    float xn = x - gx / sdf_cubic_slope(p, x);
    x = (xn > lo && xn < hi) ? xn : 0.5f * (lo + hi);
  }
  return 0.5f * (lo + hi);
}

/// The first t in [0, t_end] where the cubic changes side (< 0 against >= 0),
/// or -1. Between consecutive roots of its derivative the cubic is monotone:
/// a change of side between a piece's ends is exactly one root in it, and
/// no change is none (a tangential touch is not a crossing).
inline float sdf_cubic_first_root(SdfCubic p, float t_end) {
  // the derivative 3 c3 t^2 + 2 c2 t + c1, roots by the stable formula
  float a = 3.0f * p.c3, b = 2.0f * p.c2, c = p.c1;
  float s0 = t_end, s1 = t_end;
  if (a != 0.0f) {
    float disc = b * b - 4.0f * a * c;
    if (disc > 0.0f) {
      float q = -0.5f * (b + copysign(sqrt(disc), b));
      float r0 = q / a, r1 = q != 0.0f ? c / q : r0;
      s0 = fmin(r0, r1);
      s1 = fmax(r0, r1);
    }
  } else if (b != 0.0f) {
    s0 = -c / b;
  }
  s0 = clamp(s0, 0.0f, t_end);
  s1 = clamp(s1, s0, t_end);
  float splits[3] = {s0, s1, t_end};
  float tol = 1e-7f * t_end;
  float lo = 0.0f, g_lo = p.c0;
  for (int i = 0; i < 3; ++i) {
    float hi = splits[i];
    if (!(hi > lo)) continue;
    float g_hi = sdf_cubic_eval(p, hi);
    if ((g_lo < 0.0f) != (g_hi < 0.0f)) return sdf_cubic_refine(p, lo, hi, g_lo, tol);
    lo = hi;
    g_lo = g_hi;
  }
  return -1.0f;
}

/// A brick's grid and place in it, unpacked from its prim_info row.
typedef struct SdfBrick {
  __global const float4* grid;  ///< the grid's WT_SDF_GRID_ROWS rows
  __global const float* values; ///< the brick's corner (0, 0, 0): the grid's dense array there, or its own block
  uint sx, sxy;                 ///< strides of y and z in values
  int3 lo, hi;                  ///< its cells in the lattice: [lo, hi)
} SdfBrick;

/// rows: the type's first prim_data row (WtGeometry::data_first).
inline SdfBrick sdf_brick(__global const float4* rows, uint4 info) {
  SdfBrick k;
  k.grid = rows + WT_SDF_GRID_ROWS * info.y;
  float4 dims = k.grid[3];
  uint w = info.w;
  k.lo = (int3)((int)(w & 511u), (int)((w >> 9) & 511u), (int)((w >> 18) & 511u)) * WT_SDF_BRICK;
  k.hi = min(k.lo + WT_SDF_BRICK, convert_int3(dims.xyz));
  uint nx = (uint)dims.x + 1u, ny = (uint)dims.y + 1u;
  bool sparse = (w & WT_SDF_SPARSE) != 0u;
  k.sx = sparse ? (WT_SDF_BRICK + 1) : nx;
  k.sxy = sparse ? (WT_SDF_BRICK + 1) * (WT_SDF_BRICK + 1) : nx * ny;
  k.values = (__global const float*)rows + info.z;
  return k;
}

/// A scene-space point or direction in the grid's lattice (corner (i, j, k) at (i, j, k)).
inline float3 sdf_to_lattice(__global const float4* grid, float3 p, float w) {
  return (float3)(dot(grid[0].xyz, p) + w * grid[0].w, dot(grid[1].xyz, p) + w * grid[1].w,
                  dot(grid[2].xyz, p) + w * grid[2].w);
}

/// Ray (o, d) against `brick` (its WT_SDF_INFO_ROWS prim_info rows) in (tmin, tmax): the first crossing, its
/// t and the brick-local cell it lies in (x + B y + B^2 z, as a float, in
/// *cell). Each cell's span along the ray is widened by a sliver on both
/// sides (never past tmin or tmax): a crossing on a face between cells or
/// bricks is found by one of them or both, never by neither, and the
/// interpolants of neighbouring cells agree on their shared face. A ray that
/// leaves this surface needs no special case: shade spawns it past the
/// hit's error bound (sdf_surface), on the side it heads to.
inline bool sdf_intersect(__global const float4* rows, __global const uint4* brick, float3 o, float3 d, float tmin,
                          float tmax, float* t_hit, float* cell_id) {
  SdfBrick k = sdf_brick(rows, brick[0]);
  __global const uint* crossed = (__global const uint*)(brick + 1);
  float3 ol = sdf_to_lattice(k.grid, o, 1.0f);
  float3 dl = sdf_to_lattice(k.grid, d, 0.0f);
  const float kTiny = 1e-30f;
  float3 inv = 1.0f / select(dl, copysign((float3)(kTiny), dl), fabs(dl) < kTiny);
  float3 lo = convert_float3(k.lo), hi = convert_float3(k.hi);
  float3 t0 = (lo - ol) * inv, t1 = (hi - ol) * inv;
  float3 tn = fmin(t0, t1), tf = fmax(t0, t1);
  float ta = fmax(fmax(tn.x, tn.y), tn.z), tb = fmin(fmin(tf.x, tf.y), tf.z);
  float sliver = 1e-5f * (fabs(ta) + fabs(tb));
  ta = fmax(ta - sliver, tmin);
  tb = fmin(tb + sliver, tmax);
  if (!(ta <= tb)) return false;

  // the walk: the cell the ray enters at ta, then one face crossing at a time
  float3 p = ol + ta * dl;
  int3 cell = clamp(convert_int3_rtn(p), k.lo, k.hi - 1);
  int3 step = select((int3)(-1), (int3)(1), dl > 0.0f);
  float tc0 = ta;
  for (int n = 0; n < 3 * WT_SDF_BRICK + 3; ++n) {
    float3 face = convert_float3(cell + select((int3)(0), (int3)(1), dl > 0.0f));
    float3 tnext = select((face - ol) * inv, (float3)(INFINITY), fabs(dl) < kTiny);
    float tc1 = fmin(fmin(fmin(tnext.x, tnext.y), tnext.z), tb);
    int3 c = cell - k.lo;
    uint bit = (uint)(c.x + WT_SDF_BRICK * (c.y + WT_SDF_BRICK * c.z));
    if ((crossed[bit >> 5] >> (bit & 31u)) & 1u) {
      uint idx = (uint)c.x + (uint)c.y * k.sx + (uint)c.z * k.sxy;
      float pad = 1e-4f * (tc1 - tc0) + 1e-6f * fabs(tc1);
      float ts = fmax(tc0 - pad, tmin), te = fmin(tc1 + pad, tmax);
      if (te > ts) {
        SdfCell kc = sdf_cell(k.values, idx, k.sx, k.sxy);
        // re-centred on the span's start: the cubic's variable stays small
        float3 q = ol + ts * dl - convert_float3(cell);
        float r = sdf_cubic_first_root(sdf_cell_cubic(kc, q, dl), te - ts);
        if (r >= 0.0f) {
          float t = ts + r;
          if (t > tmin && t < tmax) {
            *t_hit = t;
            *cell_id = (float)bit;
            return true;
          }
        }
      }
    }
    if (tc1 >= tb) return false;
    // across the nearest face; a ray out of the brick is done
    if (tnext.x <= tnext.y && tnext.x <= tnext.z) cell.x += step.x;
    else if (tnext.y <= tnext.z) cell.y += step.y;
    else cell.z += step.z;
    if (any(cell < k.lo) || any(cell >= k.hi)) return false;
    tc0 = tc1;
  }
  return false;
}

/// The surface where ray (o, d) crossed brick `info` at t in cell `cell_id`
/// (sdf_intersect's): o + t d, its error bound, the unit normal (the
/// interpolant's gradient, outward; zero where the gradient vanishes), uv
/// (the lattice position's x and y over the grid's size) and a tangent.
/// The error bound covers the sum's rounding, the root's bracket and the
/// distance over which the interpolant's float evaluation can take the
/// wrong side, so a ray spawned past it starts on the side it means to.
inline void sdf_surface(__global const float4* rows, uint4 info, float3 o, float3 d, float t, float cell_id, float3* p,
                        float3* p_error, float3* normal, float2* uv, float3* dpdu) {
  SdfBrick k = sdf_brick(rows, info);
  uint id = (uint)cell_id;
  int3 c = (int3)((int)(id % WT_SDF_BRICK), (int)((id / WT_SDF_BRICK) % WT_SDF_BRICK),
                  (int)(id / (WT_SDF_BRICK * WT_SDF_BRICK)));
  uint idx = (uint)c.x + (uint)c.y * k.sx + (uint)c.z * k.sxy;
  SdfCell kc = sdf_cell(k.values, idx, k.sx, k.sxy);
  float3 pw = o + t * d;
  float3 pl = sdf_to_lattice(k.grid, pw, 1.0f);
  float3 q = pl - convert_float3(k.lo + c);
  float3 grad = (float3)(kc.b + kc.e * q.y + kc.f * q.z + kc.h * q.y * q.z,
                         kc.c + kc.e * q.x + kc.g * q.z + kc.h * q.x * q.z,
                         kc.d + kc.f * q.x + kc.g * q.y + kc.h * q.x * q.y);
  // the gradient in the scene: the lattice map's transpose applied to it
  float3 n = grad.x * k.grid[0].xyz + grad.y * k.grid[1].xyz + grad.z * k.grid[2].xyz;
  float len = length(n);
  *normal = (len > 0.0f && isfinite(len)) ? n / len : (float3)(0.0f);
  *p = pw;
  float glen = length(grad);
  float scale = fabs(kc.a) + fabs(kc.b) + fabs(kc.c) + fabs(kc.d) + fabs(kc.e) + fabs(kc.f) + fabs(kc.g) + fabs(kc.h);
  // lattice units the crossing may move: the ray's rounding into the
  // lattice (relative to the position there) and the interpolant's rounding
  // (relative to its coefficients, over its slope); then into the scene
  float3 apl = fabs(pl);
  // (at most a quarter cell: where the gradient all but vanishes the bound
  // would carry the ray past thin features rather than off the surface)
  float off_lattice = 8.0f * FLT_EPSILON * (fmax(fmax(apl.x, apl.y), apl.z) + 1.0f) +
                      (glen > 0.0f ? fmin(64.0f * FLT_EPSILON * scale / glen, 0.25f) : 0.25f);
  *p_error = spawn_gamma(3) * (fabs(o) + fabs(t * d)) + (float3)(k.grid[3].w * off_lattice);
  float3 dims = k.grid[3].xyz;
  *uv = (float2)(pl.x / dims.x, pl.y / dims.y);
  float3 bt;
  frame_from_normal(len > 0.0f ? *normal : (float3)(0.0f, 1.0f, 0.0f), dpdu, &bt);
}

/// A sphere (centre, radius; world) holding brick `info`'s lattice box: its
/// centre and half-diagonals mapped back by the inverse of the grid's linear
/// map (cofactors), the radius the longest of them with a relative margin.
inline float4 sdf_brick_sphere(__global const float4* rows, uint4 info) {
  SdfBrick k = sdf_brick(rows, info);
  float3 r0 = k.grid[0].xyz, r1 = k.grid[1].xyz, r2 = k.grid[2].xyz;
  float3 shift = (float3)(k.grid[0].w, k.grid[1].w, k.grid[2].w);
  // the inverse's columns: lattice axes as scene vectors
  float3 c0 = cross(r1, r2), c1 = cross(r2, r0), c2 = cross(r0, r1);
  float inv_det = 1.0f / dot(r0, c0);
  c0 *= inv_det, c1 *= inv_det, c2 *= inv_det;
  float3 lo = convert_float3(k.lo), hi = convert_float3(k.hi);
  float3 mid = 0.5f * (lo + hi) - shift, half_size = 0.5f * (hi - lo);
  float3 center = mid.x * c0 + mid.y * c1 + mid.z * c2;
  float3 a = half_size.x * c0, b = half_size.y * c1, c = half_size.z * c2;
  float r2max = fmax(fmax(dot(a + b + c, a + b + c), dot(a + b - c, a + b - c)),
                     fmax(dot(a - b + c, a - b + c), dot(a - b - c, a - b - c)));
  return (float4)(center, sqrt(r2max) * 1.001f + 1e-6f * length(center));
}

/// A point of brick `brick` (its WT_SDF_INFO_ROWS prim_info rows) sampled
/// for next-event estimation from p: a direction uniform in the cone of
/// the brick's sphere (sdf_brick_sphere), then the ray's first crossing of
/// the brick (sdf_intersect). The solid-angle pdf is the cone's wherever
/// the direction crosses the brick (sdf_emitter_pdf), so no point's area
/// density is needed; a direction that misses carries nothing. False from
/// inside the sphere (BSDF sampling alone finds the brick there), on a
/// miss, and on a back face where only the front emits (shade's rule).
inline bool sdf_sample_emitter(__global const float4* rows, __global const uint4* brick, float3 p, float u1, float u2,
                               bool two_sided, float3* wi, float* distance, float3* target, float* pdf) {
  float4 sphere = sdf_brick_sphere(rows, brick[0]);
  float3 pc = sphere.xyz - p;
  float d2 = dot(pc, pc);
  if (!(d2 > sphere.w * sphere.w) || !isfinite(d2)) return false;
  float one_minus_cos_max = sphere_cone_one_minus_cos(sphere.w, d2);
  float cos_t, sin_t;
  float3 dir = sphere_cone_direction(pc / sqrt(d2), one_minus_cos_max, u1, u2, &cos_t, &sin_t);
  float t, cell;
  if (!sdf_intersect(rows, brick, p, dir, 0.0f, INFINITY, &t, &cell)) return false;
  float3 q, q_error, n, dpdu;
  float2 uv;
  sdf_surface(rows, brick[0], p, dir, t, cell, &q, &q_error, &n, &uv, &dpdu);
  float facing = dot(n, dir);
  if (dot(n, n) == 0.0f || (!two_sided && facing > 0.0f)) return false;
  *target = ray_offset_origin(q, q_error, facing < 0.0f ? n : -n);
  *wi = dir;
  *distance = length(q - p);
  *pdf = 1.0f / (2.0f * WT_PI * one_minus_cos_max);
  return *distance > 0.0f;
}

/// The solid-angle pdf with which sdf_sample_emitter reaches, from
/// `origin`, a crossing of the brick at p: the cone's where the direction
/// to p lies in it (by its sine, exact for small cones), else 0.
inline float sdf_emitter_pdf(__global const float4* rows, __global const uint4* brick, float3 origin, float3 p) {
  float4 sphere = sdf_brick_sphere(rows, brick[0]);
  float3 pc = sphere.xyz - origin;
  float d2 = dot(pc, pc);
  if (!(d2 > sphere.w * sphere.w) || !isfinite(d2)) return 0.0f;
  float3 w = pc * rsqrt(d2), dir = normalize(p - origin);
  float3 across = cross(w, dir);
  if (!(dot(w, dir) > 0.0f) || dot(across, across) > sphere.w * sphere.w / d2) return 0.0f;
  return 1.0f / (2.0f * WT_PI * sphere_cone_one_minus_cos(sphere.w, d2));
}

#endif  // WT_GEOMETRY_SDF_GRID_CL
