// Stage 3 for scenes whose surfaces are all triangles, Lambertian or
// metallic-roughness without extensions but transmission (no textures, holes,
// other primitive types, AOVs; the path integrator): the shade kernel over 8 or 16 paths per
// work-item on vector lanes. PoCL runs a work-group as a loop over its items
// and vectorises that loop only when the body is scalar, straight-line code,
// which shade is not (float3 values, loops, atomics), so the work-items are
// made wide by hand. The same estimator as shade.cl, term for term: the
// miss, emission hits, the light tree and lights other than triangles and
// rectangles take shade.cl's scalar functions one lane at a time; the rest
// (the surface, light picking, triangle and rectangle sampling, the
// Lambertian BSDF, the metallic-roughness BSDF without extensions in
// bsdf.cl's order, the smooth boundary of a plain dielectric volume met from
// air or from inside the one volume a path is in, roulette) runs on all lanes
// at once. Paths at other transmitting surfaces, inside volumes or past false
// hits take shade.cl's shade_path. The host launches one work-item per
// WT_SHADE_LANES_WIDTH queue entries.

// The width, 8 or 16, is the device's preferred float vector (the host's
// shadeLanesWidthFor): one register per lane vector on AVX2 and AVX-512.
#define WT_LANES_CAT2(a, b) a##b
#define WT_LANES_CAT(a, b) WT_LANES_CAT2(a, b)
/// name8 or name16: a vector type or built-in at the lanes' width.
#define WT_LANES_N(name) WT_LANES_CAT(name, WT_SHADE_LANES_WIDTH)
typedef WT_LANES_N(float) floatL;
typedef WT_LANES_N(uint) uintL;
typedef WT_LANES_N(int) intL;
typedef WT_LANES_N(ushort) ushortL;
#define vstoreL WT_LANES_N(vstore)
#define vloadL WT_LANES_N(vload)
#define as_uintL WT_LANES_N(as_uint)
#define as_floatL WT_LANES_N(as_float)
#define convert_floatL WT_LANES_N(convert_float)
#define convert_uintL WT_LANES_N(convert_uint)
#define convert_intL WT_LANES_N(convert_int)
/// E(v.s0), E(v.s1), ...: a vector built lane by lane from v's lanes.
#if WT_SHADE_LANES_WIDTH == 16
#define WT_LANES_MAP(E, v) \
  E(v.s0), E(v.s1), E(v.s2), E(v.s3), E(v.s4), E(v.s5), E(v.s6), E(v.s7), E(v.s8), E(v.s9), E(v.sa), E(v.sb), \
      E(v.sc), E(v.sd), E(v.se), E(v.sf)
#define WT_LANES_IOTA (uintL)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15)
#else
#define WT_LANES_MAP(E, v) E(v.s0), E(v.s1), E(v.s2), E(v.s3), E(v.s4), E(v.s5), E(v.s6), E(v.s7)
#define WT_LANES_IOTA (uintL)(0, 1, 2, 3, 4, 5, 6, 7)
#endif
#define WT_LANES_AT_BASE(j) base[j]

// Every helper inlined: a lane vector passed by pointer to a called function
// lives in memory, which PoCL keeps per work-item of the group. Under
// Oclgrind, which lacks what inlining a struct's return makes, not inlined
// (as WT_INLINE_STRUCT).
#if WT_NO_SRET_INLINE
#define WT_LANES_INLINE __attribute__((noinline)) inline
#else
#define WT_LANES_INLINE inline __attribute__((always_inline))
#endif

typedef struct VL {
  floatL x, y, z;
} VL;

WT_LANES_INLINE VL vl(floatL x, floatL y, floatL z) { return (VL){x, y, z}; }
WT_LANES_INLINE VL vl_splat(float3 a) { return (VL){(floatL)(a.x), (floatL)(a.y), (floatL)(a.z)}; }
WT_LANES_INLINE VL vl_add(VL a, VL b) { return (VL){a.x + b.x, a.y + b.y, a.z + b.z}; }
WT_LANES_INLINE VL vl_sub(VL a, VL b) { return (VL){a.x - b.x, a.y - b.y, a.z - b.z}; }
WT_LANES_INLINE VL vl_mul(VL a, VL b) { return (VL){a.x * b.x, a.y * b.y, a.z * b.z}; }
WT_LANES_INLINE VL vl_scale(VL a, floatL s) { return (VL){a.x * s, a.y * s, a.z * s}; }
WT_LANES_INLINE VL vl_div(VL a, floatL s) { return (VL){a.x / s, a.y / s, a.z / s}; }
WT_LANES_INLINE VL vl_neg(VL a) { return (VL){-a.x, -a.y, -a.z}; }
WT_LANES_INLINE floatL vl_dot(VL a, VL b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
WT_LANES_INLINE VL vl_cross(VL a, VL b) {
  return (VL){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
WT_LANES_INLINE floatL vl_length(VL a) { return sqrt(vl_dot(a, a)); }
WT_LANES_INLINE VL vl_normalize(VL a) { return vl_div(a, vl_length(a)); }
/// m ? b : a, per lane (m: a comparison's -1 or 0).
WT_LANES_INLINE VL vl_select(VL a, VL b, intL m) { return (VL){select(a.x, b.x, m), select(a.y, b.y, m), select(a.z, b.z, m)}; }
WT_LANES_INLINE intL vl_positive(VL a) { return a.x > 0.0f || a.y > 0.0f || a.z > 0.0f; }

/// Lane k of a (k a constant once the lane loops unroll). A subscript, which
/// compiles to an element extract: a copy through a private array lives in
/// PoCL's per-work-item memory and costs a store and a reload per lane.
WT_LANES_INLINE float lane_f(floatL a, int k) { return a[k]; }
WT_LANES_INLINE uint lane_u(uintL a, int k) { return a[k]; }
WT_LANES_INLINE int lane_i(intL a, int k) { return a[k]; }
WT_LANES_INLINE float3 lane_v(VL a, int k) { return (float3)(lane_f(a.x, k), lane_f(a.y, k), lane_f(a.z, k)); }

/// Element `offset` of rows of `stride` floats at each lane's row, by a
/// load a lane: for dependent reads in a loop (the light tree's descent),
/// where a gather instruction's latency costs more than eight loads.
WT_LANES_INLINE floatL gather_f_each(__global const float* base, uintL row, uint stride, uint offset) {
  uintL i = row * stride + offset;
  return (floatL)(WT_LANES_MAP(WT_LANES_AT_BASE, i));
}
WT_LANES_INLINE uintL gather_u_each(__global const uint* base, uintL row, uint stride, uint offset) {
  uintL i = row * stride + offset;
  return (uintL)(WT_LANES_MAP(WT_LANES_AT_BASE, i));
}
/// The same, elsewhere.
#if defined(__AVX2__) && WT_SHADE_LANES_WIDTH == 8
// One gather instruction per 8 lanes: a fifth of the IR of a load a lane
// for PoCL's compile, and as fast outside dependent loops. The
// instruction's offsets are signed 32-bit: biased by 2^31 elements (base +
// 2^31, index ^ 2^31), they reach every uint index as the loads above do.
#define WT_GATHER_BASE(b) ((const void*)((ulong)(b) + 0x200000000ul))
WT_LANES_INLINE floatL gather_f(__global const float* base, uintL row, uint stride, uint offset) {
  int8 i = as_int8((row * stride + offset) ^ 0x80000000u);
  return __builtin_ia32_gatherd_ps256((float8)(0.0f), WT_GATHER_BASE(base), i, as_float8((int8)(-1)), 4);
}
WT_LANES_INLINE uintL gather_u(__global const uint* base, uintL row, uint stride, uint offset) {
  int8 i = as_int8((row * stride + offset) ^ 0x80000000u);
  return as_uint8(__builtin_ia32_gatherd_d256((int8)(0), WT_GATHER_BASE(base), i, (int8)(-1), 4));
}
#else
#define gather_f gather_f_each
#define gather_u gather_u_each
#endif
WT_LANES_INLINE VL gather_v(__global const float4* rows, uintL row) {
  __global const float* f = (__global const float*)rows;
  return vl(gather_f(f, row, 4u, 0u), gather_f(f, row, 4u, 1u), gather_f(f, row, 4u, 2u));
}

/// A float4 row per lane as four lane vectors (x: every lane's row's x, ...).
typedef struct ColsL {
  floatL x, y, z, w;
} ColsL;
typedef struct Cols8 {
  float8 x, y, z, w;
} Cols8;

/// 8 rows of 4 to their 4 columns and back (the same shuffles): one load or
/// store a row and 12 shuffles instead of an element insert or extract each.
WT_LANES_INLINE Cols8 lanes_transpose8(float8 a0, float8 a1, float8 a2, float8 a3) {
  float8 t0 = __builtin_shufflevector(a0, a1, 0, 8, 1, 9, 4, 12, 5, 13);
  float8 t1 = __builtin_shufflevector(a0, a1, 2, 10, 3, 11, 6, 14, 7, 15);
  float8 t2 = __builtin_shufflevector(a2, a3, 0, 8, 1, 9, 4, 12, 5, 13);
  float8 t3 = __builtin_shufflevector(a2, a3, 2, 10, 3, 11, 6, 14, 7, 15);
  return (Cols8){__builtin_shufflevector(t0, t2, 0, 1, 8, 9, 4, 5, 12, 13),
                 __builtin_shufflevector(t0, t2, 2, 3, 10, 11, 6, 7, 14, 15),
                 __builtin_shufflevector(t1, t3, 0, 1, 8, 9, 4, 5, 12, 13),
                 __builtin_shufflevector(t1, t3, 2, 3, 10, 11, 6, 7, 14, 15)};
}
#define WT_LANES_PAIR(a, b) __builtin_shufflevector(a, b, 0, 1, 2, 3, 4, 5, 6, 7)
WT_LANES_INLINE Cols8 gather_rows8(__global const float4* rows, uint8 i) {
  // a_k: rows k and k + 4, so the transpose's columns come out in lane order
  return lanes_transpose8(WT_LANES_PAIR(rows[i.s0], rows[i.s4]), WT_LANES_PAIR(rows[i.s1], rows[i.s5]),
                          WT_LANES_PAIR(rows[i.s2], rows[i.s6]), WT_LANES_PAIR(rows[i.s3], rows[i.s7]));
}
WT_LANES_INLINE void scatter_rows8(__global float4* rows, uint8 i, int8 m, float8 x, float8 y, float8 z, float8 w) {
  Cols8 r = lanes_transpose8(x, y, z, w);  // .x: rows 0 and 4, .y: 1 and 5, .z: 2 and 6, .w: 3 and 7
  if (m.s0) rows[i.s0] = r.x.lo;
  if (m.s1) rows[i.s1] = r.y.lo;
  if (m.s2) rows[i.s2] = r.z.lo;
  if (m.s3) rows[i.s3] = r.w.lo;
  if (m.s4) rows[i.s4] = r.x.hi;
  if (m.s5) rows[i.s5] = r.y.hi;
  if (m.s6) rows[i.s6] = r.z.hi;
  if (m.s7) rows[i.s7] = r.w.hi;
}

/// Each lane's row of a float4 buffer, whole.
WT_LANES_INLINE ColsL gather_rows(__global const float4* rows, uintL row) {
#if WT_SHADE_LANES_WIDTH == 16
#define WT_LANES_JOIN(a, b) __builtin_shufflevector(a, b, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15)
  Cols8 lo = gather_rows8(rows, row.lo), hi = gather_rows8(rows, row.hi);
  return (ColsL){WT_LANES_JOIN(lo.x, hi.x), WT_LANES_JOIN(lo.y, hi.y), WT_LANES_JOIN(lo.z, hi.z),
                 WT_LANES_JOIN(lo.w, hi.w)};
#else
  Cols8 c = gather_rows8(rows, row);
  return (ColsL){c.x, c.y, c.z, c.w};
#endif
}
WT_LANES_INLINE VL cols_v(ColsL c) { return (VL){c.x, c.y, c.z}; }

/// Rows `row` of a float4 buffer set to (v, w) where m.
WT_LANES_INLINE void scatter_v(__global float4* rows, uintL row, intL m, VL v, floatL w) {
#if WT_SHADE_LANES_WIDTH == 16
  scatter_rows8(rows, row.lo, m.lo, v.x.lo, v.y.lo, v.z.lo, w.lo);
  scatter_rows8(rows, row.hi, m.hi, v.x.hi, v.y.hi, v.z.hi, w.hi);
#else
  scatter_rows8(rows, row, m, v.x, v.y, v.z, w);
#endif
}

// ---- the sampler (sampler.cl, shared/rng.h, shared/sampler.h) on lanes

WT_LANES_INLINE uintL rng_hashL(uintL x) {
  uintL state = x * 747796405u + 2891336453u;
  uintL word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}
#if WT_AVOID_BITREVERSE
// Oclgrind cannot run llvm.bitreverse (shared/sampler.h): lane by lane
WT_LANES_INLINE uintL sampler_reverse_bitsL(uintL x) {
  return (uintL)(WT_LANES_MAP(sampler_reverse_bits, x));
}
#else
WT_LANES_INLINE uintL sampler_reverse_bitsL(uintL x) {
  x = ((x >> 1u) & 0x55555555u) | ((x & 0x55555555u) << 1u);
  x = ((x >> 2u) & 0x33333333u) | ((x & 0x33333333u) << 2u);
  x = ((x >> 4u) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4u);
  x = ((x >> 8u) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8u);
  return (x >> 16u) | (x << 16u);
}
#endif
WT_LANES_INLINE uintL sampler_lk_permuteL(uintL x, uintL seed) {
  x ^= x * 0x3d20adeau;
  x += seed;
  x *= (seed >> 16u) | 1u;
  x ^= x * 0x05526c56u;
  x ^= x * 0x53a22864u;
  return x;
}
WT_LANES_INLINE uintL sampler_sobol_pascalL(uintL index) {
  index ^= (index >> 1u) & 0x55555555u;
  index ^= (index >> 2u) & 0x33333333u;
  index ^= (index >> 4u) & 0x0f0f0f0fu;
  index ^= (index >> 8u) & 0x00ff00ffu;
  index ^= (index >> 16u) & 0x0000ffffu;
  return index;
}

/// sampler_get2 for each lane's pixel: dimensions dim and dim + 1, bit for bit.
WT_LANES_INLINE void sampler_get2_L(WtFrameParams frame, uintL pixel, uint dim, floatL* a,
                                                          floatL* b) {
  if (frame.flags & WT_FLAG_SOBOL) {
    uintL group_seed = rng_hashL(frame.seed ^ rng_hashL(pixel ^ rng_hash((frame.bounce << 8u) + (dim >> 1u) + 0x9e3779b9u)));
    uintL index = sampler_reverse_bitsL(sampler_lk_permuteL((uintL)(sampler_reverse_bits(frame.sample)), group_seed));
    uintL va = sampler_reverse_bitsL(sampler_lk_permuteL(index, rng_hashL(group_seed + 1u)));
    uintL vb = sampler_reverse_bitsL(sampler_lk_permuteL(sampler_sobol_pascalL(index), rng_hashL(group_seed + 2u)));
    *a = convert_floatL(va >> 8u) * (1.0f / 16777216.0f);
    *b = convert_floatL(vb >> 8u) * (1.0f / 16777216.0f);
    return;
  }
  uint inner_a = rng_hash(frame.sample ^ rng_hash((frame.bounce << 8u) + dim));
  uint inner_b = rng_hash(frame.sample ^ rng_hash((frame.bounce << 8u) + dim + 1u));
  *a = convert_floatL(rng_hashL(frame.seed ^ rng_hashL(pixel ^ inner_a)) >> 8u) * (1.0f / 16777216.0f);
  *b = convert_floatL(rng_hashL(frame.seed ^ rng_hashL(pixel ^ inner_b)) >> 8u) * (1.0f / 16777216.0f);
}

// ---- common.h, shared/spawn.h and shared/trig.h on lanes

WT_LANES_INLINE floatL wt_sincospiL(floatL x, floatL* cos_out) {
  floatL k = rint(2.0f * x);
  floatL r = x - 0.5f * k;
  floatL t = 3.14159265358979323846f * r;
  floatL t2 = t * t;
  floatL s = t + t * t2 * (-1.6666654611e-1f + t2 * (8.3321608736e-3f + t2 * -1.9515295891e-4f));
  floatL c = 1.0f - 0.5f * t2 +
             t2 * t2 * (4.166664568298827e-2f + t2 * (-1.388731625493765e-3f + t2 * 2.443315711809948e-5f));
  intL q = convert_intL(k) & 3;
  intL odd = (q & 1) != 0;
  floatL sin_v = select(s, c, odd), cos_v = select(c, s, odd);
  sin_v = select(sin_v, -sin_v, q == 2 || q == 3);
  cos_v = select(cos_v, -cos_v, q == 1 || q == 2);
  *cos_out = cos_v;
  return sin_v;
}

WT_LANES_INLINE floatL wt_atan2_L(floatL y, floatL x) {
  floatL ax = fabs(x), ay = fabs(y);
  floatL t = ay / ax;
  intL high = t > 2.414213562373095f;
  intL mid = !high && t > 0.4142135623730950f;
  floatL base = select(select((floatL)(0.0f), (floatL)(0.25f * WT_PI), mid), (floatL)(0.5f * WT_PI), high);
  t = select(select(t, (t - 1.0f) / (t + 1.0f), mid), -1.0f / t, high);
  floatL z = t * t;
  floatL a = base + ((((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z - 3.33329491539e-1f) * z * t + t);
  a = select(a, (floatL)(0.0f), ax == 0.0f && ay == 0.0f);
  a = select(a, WT_PI - a, signbit(x));
  return copysign(a, y);
}

WT_LANES_INLINE floatL spawn_next_upL(floatL v) {
  floatL w = select(v, (floatL)(0.0f), v == 0.0f);
  uintL bits = as_uintL(w);
  floatL up = as_floatL(select(bits - 1u, bits + 1u, w >= 0.0f));
  return select(up, v, v == INFINITY);
}
WT_LANES_INLINE floatL spawn_next_downL(floatL v) {
  floatL w = select(v, (floatL)(-0.0f), v == 0.0f);
  uintL bits = as_uintL(w);
  floatL down = as_floatL(select(bits + 1u, bits - 1u, w > 0.0f));
  return select(down, v, v == -INFINITY);
}
WT_LANES_INLINE floatL spawn_offset_coordinateL(floatL p, floatL offset) {
  floatL moved = p + offset;
  return select(select(moved, spawn_next_downL(moved), offset < 0.0f), spawn_next_upL(moved), offset > 0.0f);
}
WT_LANES_INLINE VL ray_offset_originL(VL p, VL p_error, VL n) {
  floatL d = fabs(n.x) * p_error.x + fabs(n.y) * p_error.y + fabs(n.z) * p_error.z;
  VL offset = vl_scale(n, d);
  return vl(spawn_offset_coordinateL(p.x, offset.x), spawn_offset_coordinateL(p.y, offset.y),
            spawn_offset_coordinateL(p.z, offset.z));
}
WT_LANES_INLINE floatL spawn_barycentric_errorL(floatL b0, floatL b1, floatL b2, floatL p0, floatL p1, floatL p2) {
  return spawn_gamma(7) * (fabs(b0 * p0) + fabs(b1 * p1) + fabs(b2 * p2)) + spawn_gamma(2) * fabs(p0);
}
WT_LANES_INLINE VL triangle_pointL(VL p0, VL p1, VL p2, floatL b1, floatL b2, VL* error) {
  floatL b0 = 1.0f - b1 - b2;
  *error = vl(spawn_barycentric_errorL(b0, b1, b2, p0.x, p1.x, p2.x), spawn_barycentric_errorL(b0, b1, b2, p0.y, p1.y, p2.y),
              spawn_barycentric_errorL(b0, b1, b2, p0.z, p1.z, p2.z));
  return vl_add(vl_add(vl_scale(p0, b0), vl_scale(p1, b1)), vl_scale(p2, b2));
}
WT_LANES_INLINE void frame_from_normalL(VL n, VL* t, VL* b) {
  floatL sign = copysign((floatL)(1.0f), n.z);
  floatL a = -1.0f / (sign + n.z);
  floatL c = n.x * n.y * a;
  *t = vl(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
  *b = vl(c, sign + n.y * n.y * a, -n.y);
}

/// Each lane's triangle's corners (triangle_corners).
WT_LANES_INLINE void triangle_cornersL(__global const float4* tri_verts, uintL prim, VL* p0, VL* p1, VL* p2) {
  __global const float* f = (__global const float*)tri_verts;
  uintL lane = (prim >> 2u) * (4u * WT_TRIANGLE_BLOCK_ROWS) + (prim & 3u);
  *p0 = vl(gather_f(f, lane, 1u, 0u), gather_f(f, lane, 1u, 4u), gather_f(f, lane, 1u, 8u));
  *p1 = vl(gather_f(f, lane, 1u, 12u), gather_f(f, lane, 1u, 16u), gather_f(f, lane, 1u, 20u));
  *p2 = vl(gather_f(f, lane, 1u, 24u), gather_f(f, lane, 1u, 28u), gather_f(f, lane, 1u, 32u));
}

// ---- lights/light_sampling.cl on lanes

WT_LANES_INLINE floatL light_triangle_solid_angleL(VL p, VL p0, VL p1, VL p2) {
  VL a = vl_sub(p0, p), b = vl_sub(p1, p), c = vl_sub(p2, p);
  floatL la = vl_length(a), lb = vl_length(b), lc = vl_length(c);
  floatL numerator = fabs(vl_dot(a, vl_cross(b, c)));
  floatL denominator = la * lb * lc + vl_dot(a, b) * lc + vl_dot(a, c) * lb + vl_dot(b, c) * la;
  return fabs(2.0f * wt_atan2_L(numerator, denominator));
}
WT_LANES_INLINE intL light_use_sphericalL(floatL solid_angle) {
  return solid_angle >= WT_SPHERICAL_MIN_SOLID_ANGLE && solid_angle <= WT_SPHERICAL_MAX_SOLID_ANGLE;
}
WT_LANES_INLINE VL light_orthonormalL(VL a, VL b) {
  VL v = vl_sub(a, vl_scale(b, vl_dot(a, b)));
  floatL l = vl_length(v);
  return vl_select(vl_splat((float3)(0.0f)), vl_div(v, l), l > 0.0f);
}
WT_LANES_INLINE VL light_sample_spherical_triangleL(VL A, VL B, VL C, floatL solid_angle, floatL u1, floatL u2) {
  VL n_ab = light_orthonormalL(B, A), n_ac = light_orthonormalL(C, A);
  floatL cos_alpha = clamp(vl_dot(n_ab, n_ac), -1.0f, 1.0f);
  floatL sin_alpha = sqrt(fmax(0.0f, 1.0f - cos_alpha * cos_alpha));
  floatL cos_area;
  floatL sin_area = wt_sincospiL(u1 * (solid_angle * (1.0f / WT_PI)), &cos_area);
  floatL s = cos_area * sin_alpha - sin_area * cos_alpha, t = -(cos_area * cos_alpha + sin_area * sin_alpha);
  floatL cos_c = vl_dot(A, B);
  floatL k1 = t + cos_alpha, k2 = s - sin_alpha * cos_c;
  floatL cos_b = (k2 + (k2 * t - k1 * s) * cos_alpha) / ((k2 * s + k1 * t) * sin_alpha);
  cos_b = clamp(cos_b, -1.0f, 1.0f);
  VL c_prime = vl_add(vl_scale(A, cos_b), vl_scale(n_ac, sqrt(fmax(0.0f, 1.0f - cos_b * cos_b))));
  floatL cos_theta = 1.0f - u2 * (1.0f - vl_dot(c_prime, B));
  floatL sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
  return vl_normalize(vl_add(vl_scale(B, cos_theta), vl_scale(light_orthonormalL(c_prime, B), sin_theta)));
}

/// A sampled connection on lanes (LightSample).
typedef struct LightSampleL {
  VL wi, target, radiance;
  floatL distance, pdf;
  intL is_delta, ok;
  uintL prim;
} LightSampleL;

/// An area light's sample on the lanes of m (never a delta light).
WT_LANES_INLINE void light_sampleL_take(LightSampleL* s, intL m, intL ok, VL wi, floatL distance, VL target,
                                        floatL pdf, VL le, uintL prim) {
  s->ok = select(s->ok, ok, m);
  s->wi = vl_select(s->wi, wi, m);
  s->distance = select(s->distance, distance, m);
  s->target = vl_select(s->target, target, m);
  s->pdf = select(s->pdf, pdf, m);
  s->radiance = vl_select(s->radiance, le, m);
  s->is_delta = select(s->is_delta, (intL)(0), m);
  s->prim = select(s->prim, prim, m);
}

/// light_sample's WT_LIGHT_TRIANGLE case for lanes `m`; `row` the lights' rows (16 floats each).
WT_LANES_INLINE void light_sample_triangleL(__global const float* lrow, __global const float4* tri_verts, uintL index, intL m,
                                   VL p, floatL u1, floatL u2, LightSampleL* s) {
  uintL t = as_uintL(gather_f(lrow, index, 16u, 13u));
  floatL two_sided = gather_f(lrow, index, 16u, 3u);
  VL le = vl(gather_f(lrow, index, 16u, 8u), gather_f(lrow, index, 16u, 9u), gather_f(lrow, index, 16u, 10u));
  VL p0, p1, p2;
  triangle_cornersL(tri_verts, t, &p0, &p1, &p2);
  VL n = vl_cross(vl_sub(p1, p0), vl_sub(p2, p0));
  floatL solid_angle = light_triangle_solid_angleL(p, p0, p1, p2);
  intL spherical = light_use_sphericalL(solid_angle);
  // uniform by area, converted to solid angle
  floatL su = sqrt(u1);
  floatL b1 = su * (1.0f - u2), b2 = su * u2;
  VL q_error;
  VL q = triangle_pointL(p0, p1, p2, b1, b2, &q_error);
  floatL area2 = vl_length(n);
  VL to_light = vl_sub(q, p);
  floatL d2 = vl_dot(to_light, to_light);
  intL ok = area2 > 0.0f && d2 > 0.0f;
  floatL distance = sqrt(d2);
  VL wi = vl_div(to_light, distance);
  floatL cos_light = -vl_dot(n, wi) / area2;
  cos_light = select(cos_light, fabs(cos_light), two_sided != 0.0f);
  ok = ok && cos_light > 0.0f;
  VL n_unit = vl_div(n, area2);
  VL target = ray_offset_originL(q, q_error, vl_select(vl_neg(n_unit), n_unit, vl_dot(n, to_light) < 0.0f));
  floatL pdf = (2.0f / area2) * d2 / cos_light;
  if (any(m && spherical)) {
    VL w = light_sample_spherical_triangleL(vl_normalize(vl_sub(p0, p)), vl_normalize(vl_sub(p1, p)),
                                            vl_normalize(vl_sub(p2, p)), solid_angle, u1, u2);
    floatL facing = vl_dot(n, w);
    intL ok_s = two_sided != 0.0f || facing < 0.0f;
    floatL dist = vl_dot(n, vl_sub(p0, p)) / facing;
    ok_s = ok_s && dist > 0.0f && isfinite(dist);
    VL e1 = vl_sub(p1, p0), e2 = vl_sub(p2, p0), tv = vl_sub(p, p0);
    VL pv = vl_cross(w, e2), qv = vl_cross(tv, e1);
    floatL inv_det = 1.0f / vl_dot(e1, pv);
    floatL sb1 = clamp(vl_dot(tv, pv) * inv_det, 0.0f, 1.0f), sb2 = clamp(vl_dot(w, qv) * inv_det, 0.0f, 1.0f);
    floatL sum = sb1 + sb2;
    intL over = sum > 1.0f;
    sb1 = select(sb1, sb1 / sum, over);
    sb2 = select(sb2, sb2 / sum, over);
    ok_s = ok_s && isfinite(sb1) && isfinite(sb2);
    VL sq_error;
    VL sq = triangle_pointL(p0, p1, p2, sb1, sb2, &sq_error);
    VL nn = vl_normalize(n);
    VL s_target = ray_offset_originL(sq, sq_error, vl_select(vl_neg(nn), nn, facing < 0.0f));
    ok = select(ok, ok_s, spherical);
    wi = vl_select(wi, w, spherical);
    distance = select(distance, dist, spherical);
    target = vl_select(target, s_target, spherical);
    pdf = select(pdf, 1.0f / solid_angle, spherical);
  }
  light_sampleL_take(s, m, ok, wi, distance, target, pdf, le, t);
}

#if WT_HAS_QUAD_LIGHTS
typedef struct RectViewL {
  floatL x0, y0, x1, y1, z0, l00, l01;
} RectViewL;

WT_LANES_INLINE floatL light_rect_viewL(VL p, VL c, VL e1, VL e2, RectViewL* v) {
  floatL ex = vl_length(e1), ey = vl_length(e2);
  VL x = vl_div(e1, ex), y = vl_div(e2, ey);
  VL d = vl_sub(c, p);
  floatL z0 = -fabs(vl_dot(d, vl_normalize(vl_cross(x, y))));
  floatL x0 = vl_dot(d, x), y0 = vl_dot(d, y), x1 = x0 + ex, y1 = y0 + ey;
  floatL z2 = z0 * z0;
  floatL l00 = sqrt(x0 * x0 + y0 * y0 + z2), l10 = sqrt(x1 * x1 + y0 * y0 + z2);
  floatL l11 = sqrt(x1 * x1 + y1 * y1 + z2), l01 = sqrt(x0 * x0 + y1 * y1 + z2);
  *v = (RectViewL){x0, y0, x1, y1, z0, l00, l01};
  floatL triple = -z0 * ex * ey;
  floatL d_00_11 = (x0 * x1 + y0 * y1 + z2) / (l00 * l11);
  floatL n1 = triple / (l00 * l10 * l11), n2 = triple / (l00 * l11 * l01);
  floatL e_1 = 1.0f + (x0 * x1 + y0 * y0 + z2) / (l00 * l10) + d_00_11 + (x1 * x1 + y0 * y1 + z2) / (l10 * l11);
  floatL e_2 = 1.0f + d_00_11 + (x0 * x0 + y0 * y1 + z2) / (l00 * l01) + (x0 * x1 + y1 * y1 + z2) / (l11 * l01);
  return 2.0f * wt_atan2_L(n1 * e_2 + n2 * e_1, e_1 * e_2 - n1 * n2);
}

WT_LANES_INLINE void light_sample_spherical_rectL(RectViewL v, floatL solid_angle, floatL u1, floatL u2, floatL* s_out,
                                         floatL* t_out) {
  floatL x0 = v.x0, y0 = v.y0, x1 = v.x1, y1 = v.y1, z0 = v.z0;
  floatL z2 = z0 * z0;
  floatL l0 = sqrt(z2 + y0 * y0), l2 = sqrt(z2 + y1 * y1), l3 = sqrt(z2 + x0 * x0);
  floatL inv23 = 1.0f / (l2 * l3), inv30 = 1.0f / (l3 * l0);
  floatL cos_g2 = x0 * y1 * inv23, sin_g2 = -z0 * v.l01 * inv23;
  floatL cos_g3 = -x0 * y0 * inv30, sin_g3 = -z0 * v.l00 * inv30;
  floatL cos_k = cos_g2 * cos_g3 - sin_g2 * sin_g3, sin_k = -(sin_g2 * cos_g3 + cos_g2 * sin_g3);
  floatL cos_a;
  floatL sin_a = wt_sincospiL(u1 * (solid_angle * (1.0f / WT_PI)), &cos_a);
  floatL cos_au = cos_k * cos_a - sin_k * sin_a, sin_au = sin_k * cos_a + cos_k * sin_a;
  floatL b0 = -y0 / l0, b1 = y1 / l2;
  floatL fu = (cos_au * b0 - b1) / sin_au;
  floatL cu = clamp(copysign((floatL)(1.0f), fu) * rsqrt(fu * fu + b0 * b0), -1.0f, 1.0f);
  floatL xu = -(cu * z0) / sqrt(fmax(1.0f - cu * cu, 1e-30f));
  xu = clamp(xu, x0, x1);
  floatL dd = sqrt(xu * xu + z2);
  floatL h0 = y0 / sqrt(dd * dd + y0 * y0), h1 = y1 / sqrt(dd * dd + y1 * y1);
  floatL hv = h0 + u2 * (h1 - h0), hv2 = hv * hv;
  floatL yv = select(y1, hv * dd / sqrt(1.0f - hv2), hv2 < 1.0f - 1e-6f);
  yv = clamp(yv, y0, y1);
  *s_out = clamp((xu - x0) / (x1 - x0), 0.0f, 1.0f);
  *t_out = clamp((yv - y0) / (y1 - y0), 0.0f, 1.0f);
}

/// light_sample_quad for lanes `m`.
WT_LANES_INLINE void light_sample_quadL(__global const float* lrow, uintL index, intL m,
                               VL p, floatL u1, floatL u2, LightSampleL* s) {
  // the light's four rows whole (WtLight: a rectangle's c, e1, e2 and halves)
  __global const float4* rows = (__global const float4*)lrow;
  uintL row = index * 4u;
  ColsL r0 = gather_rows(rows, row), r1 = gather_rows(rows, row + 1u), r2 = gather_rows(rows, row + 2u),
        r3 = gather_rows(rows, row + 3u);
  uintL first = as_uintL(r3.y), second = as_uintL(r1.w);
  floatL two_sided = r0.w;
  VL le = cols_v(r2);
  VL c = cols_v(r0), e1 = cols_v(r1), e2 = vl(r2.w, r3.z, r3.w);
  // light_sample_rect
  VL n = vl_cross(e1, e2);
  floatL area = vl_length(n);
  intL ok = area > 0.0f;
  n = vl_div(n, area);
  floatL height = vl_dot(n, vl_sub(p, c));
  ok = ok && (two_sided != 0.0f || height > 0.0f);
  VL to_centre = vl_sub(vl_add(c, vl_scale(vl_add(e1, e2), (floatL)(0.5f))), p);
  intL spherical = area >= WT_QUAD_SPHERICAL_MIN_RATIO * vl_dot(to_centre, to_centre);
  floatL solid_angle = 0.0f;
  floatL st_x = u1, st_y = u2;
  if (any(m && ok && spherical)) {
    RectViewL view;
    solid_angle = light_rect_viewL(p, c, e1, e2, &view);
    spherical = spherical && light_use_sphericalL(solid_angle);
    floatL sx, sy;
    light_sample_spherical_rectL(view, solid_angle, u1, u2, &sx, &sy);
    st_x = select(st_x, sx, spherical);
    st_y = select(st_y, sy, spherical);
  } else {
    spherical = (intL)(0);
  }
  VL q_error;
  VL q = triangle_pointL(c, vl_add(c, e1), vl_add(c, e2), st_x, st_y, &q_error);
  VL to_light = vl_sub(q, p);
  floatL d2 = vl_dot(to_light, to_light);
  ok = ok && d2 > 0.0f;
  floatL distance = sqrt(d2);
  VL wi = vl_div(to_light, distance);
  floatL cos_light = fabs(vl_dot(n, wi));
  ok = ok && cos_light > 0.0f;
  VL target = ray_offset_originL(q, q_error, vl_select(vl_neg(n), n, height > 0.0f));
  floatL pdf = select(d2 / (cos_light * area), 1.0f / solid_angle, spherical);
  light_sampleL_take(s, m, ok, wi, distance, target, pdf, le, select(second, first, st_x + st_y <= 1.0f));
}
#endif

// ---- lights/light_tree.cl on lanes

/// light_tree_importance2's terms for one node per lane (rows of 16 floats, WtLightNode).
WT_LANES_INLINE floatL light_tree_importanceL(__global const float* nf, uintL node, VL p, VL n) {
  floatL power = gather_f_each(nf, node, 16u, 3u);
  floatL lo_x = gather_f_each(nf, node, 16u, 0u), lo_y = gather_f_each(nf, node, 16u, 1u), lo_z = gather_f_each(nf, node, 16u, 2u);
  floatL hi_x = gather_f_each(nf, node, 16u, 4u), hi_y = gather_f_each(nf, node, 16u, 5u), hi_z = gather_f_each(nf, node, 16u, 6u);
  floatL ex = hi_x - lo_x, ey = hi_y - lo_y, ez = hi_z - lo_z;
  floatL r2 = 0.25f * (ex * ex + ey * ey + ez * ez);
  floatL tx = 0.5f * (lo_x + hi_x) - p.x, ty = 0.5f * (lo_y + hi_y) - p.y, tz = 0.5f * (lo_z + hi_z) - p.z;
  floatL d2 = tx * tx + ty * ty + tz * tz;
  floatL inv_d = 1.0f / sqrt(d2), inv_d2 = inv_d * inv_d;
  floatL wx = tx * inv_d, wy = ty * inv_d, wz = tz * inv_d;
  floatL sin_u2 = r2 * inv_d2;
  floatL cos_u = sqrt(fmax(0.0f, 1.0f - sin_u2)), sin_u = fmin(gather_f_each(nf, node, 16u, 15u) * inv_d, 1.0f);
  floatL cos_a = n.x * wx + n.y * wy + n.z * wz;
  floatL sin_a = sqrt(fmax(0.0f, 1.0f - cos_a * cos_a));
  intL no_normal = n.x == 0.0f && n.y == 0.0f && n.z == 0.0f;
  floatL cos_i = select(cos_a * cos_u + sin_a * sin_u, (floatL)(1.0f), cos_a >= cos_u || no_normal);
  floatL cos_o = gather_f_each(nf, node, 16u, 11u), sin_o = gather_f_each(nf, node, 16u, 14u);
  floatL cos_ou = cos_o * cos_u - sin_o * sin_u;
  floatL cos_theta = -(gather_f_each(nf, node, 16u, 8u) * wx + gather_f_each(nf, node, 16u, 9u) * wy + gather_f_each(nf, node, 16u, 10u) * wz);
  floatL sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
  floatL sin_ou = sin_o * cos_u + cos_o * sin_u;
  floatL cos_e = select(cos_theta * cos_ou + sin_theta * sin_ou, (floatL)(1.0f), !(cos_o > -cos_u) || !(cos_theta < cos_ou));
  floatL importance = select(power * cos_i * cos_e * inv_d2, (floatL)(0.0f), !(cos_i > 0.0f) || !(cos_e > 0.0f));
  importance = select(importance, power / fmax(r2, 1e-30f), d2 <= r2);
  return select(importance, (floatL)(0.0f), !(power > 0.0f));
}

/// light_tree_pick for lanes `m`, all lanes descending together: each
/// lane's light-list index (WT_NO_HIT, *pmf 0, where nothing can reach it).
WT_LANES_INLINE uintL light_tree_pickL(__global const WtLightNode* nodes, VL p, VL n, floatL u, intL m, floatL* pmf) {
  __global const float* nf = (__global const float*)nodes;
  __global const uint* nu = (__global const uint*)nodes;
  uintL k = (uintL)(0u);
  floatL prob = 1.0f;
  intL reached = m;
  intL live = m && gather_u_each(nu, k, 16u, 12u) == 0u;
  while (any(live)) {
    uintL c = gather_u_each(nu, k, 16u, 7u);
    floatL il = light_tree_importanceL(nf, c, p, n), ir = light_tree_importanceL(nf, c + 1u, p, n);
    floatL sum = il + ir;
    intL lost = live && !(sum > 0.0f);
    reached = reached && !lost;
    live = live && !lost;
    floatL pl = il / sum;
    intL left = u < pl;
    floatL u_next = fmin(select((u - pl) / (1.0f - pl), u / pl, left), 0x1.fffffep-1f);
    u = select(u, u_next, live);
    prob = select(prob, prob * select(ir / sum, pl, left), live);
    k = select(k, select(c + 1u, c, left), live);
    live = live && gather_u_each(nu, k, 16u, 12u) == 0u;
  }
  *pmf = select((floatL)(0.0f), prob, reached);
  return select((uintL)(WT_NO_HIT), gather_u_each(nu, k, 16u, 7u), reached);
}

/// A miss or an emitter's hit of one lane's path, as shade.cl: the radiance it adds.
inline float3 shade_lane_emission(WtFrameParams frame, EnvScene env, __global const float* emitter_pdf_area,
                                  __global const WtLight* lights, __global const float4* tri_verts,
                                  __global const WtLightNode* light_tree, __global const uint* emitter_leaf,
                                  __global const float4* prev_normal, __global const uint* emitter_quad_or_null,
                                  uint path, uint prim, float3 origin, float3 dir, float4 hit, float3 ng, float3 le,
                                  float pdf_prev) {
  if (prim == WT_NO_HIT) {
    if (frame.bounce == 0 && (frame.flags & WT_FLAG_ENV_HIDDEN)) return (float3)(0.0f);
    float3 env_le = env_eval(env, dir);
    return env_le * shade_emission_weight(frame, pdf_prev, frame.env_pmf * env_pdf(env, dir));
  }
  float select_pdf = frame.bounce > 0u ? emitter_pdf_area[prim] : 0.0f;
#if WT_HAS_LIGHT_TREE
  uint leaf = emitter_leaf[prim];
  if (select_pdf > 0.0f && leaf != WT_LIGHT_NODE_NONE)
    select_pdf *= light_tree_pmf(light_tree, leaf, origin, prev_normal[path].xyz);
#endif
  float3 p0, p1, p2;
  float pdf_light;
#if WT_HAS_QUAD_LIGHTS
  uint quad = emitter_quad_or_null[prim];
  if (quad != WT_NO_QUAD) {
    light_quad_rect(lights[quad], &p0, &p1, &p2);
    pdf_light = light_quad_pdf(select_pdf, origin, p0, p1, p2, hit.x, dir, ng);
  } else
#endif
  {
    triangle_corners(tri_verts, prim, &p0, &p1, &p2);
    pdf_light = light_triangle_pdf(select_pdf, origin, p0, p1, p2, hit.x, dir, ng);
  }
  return le * shade_emission_weight(frame, pdf_prev, pdf_light);
}

/// Each lane's path's bounce_counts (x diffuse, y specular, z transmission, w
/// false hits) as four lane vectors.
typedef struct CountsL {
  uintL x, y, z, w;
} CountsL;
/// Each lane's row as two 32-bit halves (x | y << 16, z | w << 16 on a
/// little-endian device): one 8-byte load a row and two shuffles per 8 lanes,
/// where 16-bit lanes cost an element insert each.
WT_LANES_INLINE uint8 counts_half8(__global const uint2* rows, uint8 i, uint h) {
  uint4 a = (uint4)(rows[i.s0], rows[i.s1]), b = (uint4)(rows[i.s2], rows[i.s3]);
  uint4 c = (uint4)(rows[i.s4], rows[i.s5]), d = (uint4)(rows[i.s6], rows[i.s7]);
  uint8 ab = (uint8)(a, b), cd = (uint8)(c, d);
  return h == 0u ? __builtin_shufflevector(ab, cd, 0, 2, 4, 6, 8, 10, 12, 14)
                 : __builtin_shufflevector(ab, cd, 1, 3, 5, 7, 9, 11, 13, 15);
}
WT_LANES_INLINE CountsL gather_counts(__global const ushort4* rows, uintL path) {
#if defined(__ENDIAN_LITTLE__)
  __global const uint2* r = (__global const uint2*)rows;
#if WT_SHADE_LANES_WIDTH == 16
  uintL lo = WT_LANES_JOIN(counts_half8(r, path.lo, 0u), counts_half8(r, path.hi, 0u));
  uintL hi = WT_LANES_JOIN(counts_half8(r, path.lo, 1u), counts_half8(r, path.hi, 1u));
#else
  uintL lo = counts_half8(r, path, 0u), hi = counts_half8(r, path, 1u);
#endif
  return (CountsL){lo & 0xffffu, lo >> 16u, hi & 0xffffu, hi >> 16u};
#else
  __global const ushort* cf = (__global const ushort*)rows;
#define WT_LANES_AT_CF(j) cf[j]
  uintL i = 4u * path;
  CountsL c;
  c.x = convert_uintL((ushortL)(WT_LANES_MAP(WT_LANES_AT_CF, i)));
  i += 1u;
  c.y = convert_uintL((ushortL)(WT_LANES_MAP(WT_LANES_AT_CF, i)));
  i += 1u;
  c.z = convert_uintL((ushortL)(WT_LANES_MAP(WT_LANES_AT_CF, i)));
  i += 1u;
  c.w = convert_uintL((ushortL)(WT_LANES_MAP(WT_LANES_AT_CF, i)));
#undef WT_LANES_AT_CF
  return c;
#endif
}

#if WT_HAS_PBR
// ---- bsdf.cl's metallic-roughness BSDF on lanes, for scenes without its
// extensions (switches.h): the base's GGX reflection (metal, and the
// dielectric's F0 WT_PBR_DIELECTRIC_F0) with its multiple scattering over the
// diffuse base; shared/ggx.h and shared/materials.h term for term.

WT_LANES_INLINE floatL ggx_dL(VL h, floatL alpha) {
  floatL a2 = alpha * alpha;
  floatL t = (h.x * h.x + h.y * h.y) / a2 + h.z * h.z;
  return select(1.0f / (WT_GGX_PI * a2 * t * t), (floatL)(0.0f), h.z <= 0.0f);
}
WT_LANES_INLINE floatL ggx_lambdaL(VL v, floatL alpha) {
  floatL z2 = v.z * v.z;
  floatL a2_tan2 = alpha * alpha * (v.x * v.x + v.y * v.y) / z2;
  return select(0.5f * (sqrt(1.0f + a2_tan2) - 1.0f), (floatL)(INFINITY), z2 <= 0.0f);
}
/// ggx_schlick(0, c): (1 - c)^5
WT_LANES_INLINE floatL ggx_schlick_m5_L(floatL c) {
  floatL m = fmin(fmax(1.0f - c, 0.0f), 1.0f);
  floatL m2 = m * m;
  return m2 * m2 * m;
}
WT_LANES_INLINE VL ggx_sample_visible_normalL(VL v, floatL alpha, floatL u1, floatL u2) {
  VL sv = vl_normalize(vl(alpha * v.x, alpha * v.y, v.z));
  floatL lensq = sv.x * sv.x + sv.y * sv.y;
  floatL inv = 1.0f / sqrt(lensq);
  intL tilted = lensq > 0.0f;
  floatL t1x = select((floatL)(1.0f), -sv.y * inv, tilted), t1y = select((floatL)(0.0f), sv.x * inv, tilted);
  floatL t2x = -sv.z * t1y, t2y = sv.z * t1x, t2z = sv.x * t1y - sv.y * t1x;
  floatL cos_phi;
  floatL sin_phi = wt_sincospiL(2.0f * u2, &cos_phi);
  floatL r = sqrt(u1);
  floatL p1 = r * cos_phi, p2 = r * sin_phi;
  floatL s = 0.5f * (1.0f + sv.z);
  p2 = (1.0f - s) * sqrt(fmax(0.0f, 1.0f - p1 * p1)) + s * p2;
  floatL p3 = sqrt(fmax(0.0f, 1.0f - p1 * p1 - p2 * p2));
  VL n = vl(p1 * t1x + p2 * t2x + p3 * sv.x, p1 * t1y + p2 * t2y + p3 * sv.y, p2 * t2z + p3 * sv.z);
  return vl_normalize(vl(alpha * n.x, alpha * n.y, fmax(n.z, 0.0f)));
}

/// pbr_table_lookup of each lane's (mu, row).
WT_LANES_INLINE floatL pbr_table_lookupL(__global const float* table, uint offset, floatL mu, floatL y) {
  floatL x = sqrt(fmin(fmax(mu, 0.0f), 1.0f)) * (float)(WT_PBR_TABLE_N - 1);
  uintL x0 = convert_uintL(fmin(x, (float)(WT_PBR_TABLE_N - 2))), y0 = convert_uintL(fmin(y, (float)(WT_PBR_TABLE_N - 2)));
  floatL fx = x - convert_floatL(x0), fy = y - convert_floatL(y0);
  uintL i = y0 * WT_PBR_TABLE_N + x0;
  floatL r00 = gather_f(table, i, 1u, offset), r01 = gather_f(table, i, 1u, offset + 1u);
  floatL r10 = gather_f(table, i, 1u, offset + WT_PBR_TABLE_N), r11 = gather_f(table, i, 1u, offset + WT_PBR_TABLE_N + 1u);
  floatL a = r00 + fx * (r01 - r00);
  floatL b = r10 + fx * (r11 - r10);
  return a + fy * (b - a);
}
/// pbr_table_average at each lane's row.
WT_LANES_INLINE floatL pbr_table_averageL(__global const float* table, uint offset, floatL y) {
  uintL y0 = convert_uintL(fmin(y, (float)(WT_PBR_TABLE_N - 2)));
  floatL fy = y - convert_floatL(y0);
  floatL a = gather_f(table, y0, 1u, offset), b = gather_f(table, y0, 1u, offset + 1u);
  return a + fy * (b - a);
}

/// A metallic-roughness material at the lanes' hits with its view of wo
/// (Bsdf and PbrView without the layers), and its techniques' probabilities.
typedef struct PbrL {
  VL base;
  floatL metallic, alpha, row;  ///< row: the tables' (pbr_table_roughness_coord)
  intL mirror;
  floatL e, s, spec_ss;         ///< PbrView's
  floatL e_avg, s_avg;          ///< base_average's
  floatL t_specular, t_diffuse; ///< bsdf_techniques'
} PbrL;

/// pbr_moments at cosines mu: E and S.
WT_LANES_INLINE floatL pbr_momentsL(__global const float* table, PbrL b, floatL mu, floatL* s) {
  *s = select(pbr_table_lookupL(table, WT_PBR_TABLE_S, mu, b.row), ggx_schlick_m5_L(mu), b.mirror);
  return select(pbr_table_lookupL(table, WT_PBR_TABLE_E, mu, b.row), (floatL)(1.0f), b.mirror);
}
/// pbr_dielectric_albedo for F0 WT_PBR_DIELECTRIC_F0 and specular 1.
WT_LANES_INLINE floatL pbr_dielectric_albedoL(floatL e, floatL s, floatL fms) {
  return WT_PBR_DIELECTRIC_F0 * e + (1.0f - WT_PBR_DIELECTRIC_F0) * s + fms * (1.0f - e);
}

/// bsdf_make, pbr_view and bsdf_techniques at local wo for the lanes' materials.
WT_LANES_INLINE PbrL pbr_makeL(__global const float* table, VL base, floatL metallic, floatL roughness, floatL wo_z,
                               intL diffuse, intL specular) {
  PbrL b;
  b.base = base;
  b.metallic = metallic;
  b.alpha = roughness * roughness;
  b.mirror = roughness < WT_PBR_MIN_ROUGHNESS;
  b.row = sqrt(fmin(fmax((roughness - WT_PBR_MIN_ROUGHNESS) / (1.0f - WT_PBR_MIN_ROUGHNESS), 0.0f), 1.0f)) *
          (float)(WT_PBR_TABLE_N - 1);
  b.e = pbr_momentsL(table, b, wo_z, &b.s);
  b.spec_ss = pbr_dielectric_albedoL(b.e, b.s, (floatL)(0.0f));
  b.e_avg = select(pbr_table_averageL(table, WT_PBR_TABLE_E_AVG, b.row), (floatL)(1.0f), b.mirror);
  b.s_avg = select(pbr_table_averageL(table, WT_PBR_TABLE_S_AVG, b.row), (floatL)(1.0f / 21.0f), b.mirror);
  floatL opaque = 1.0f - b.metallic;
  floatL t_spec = select((floatL)(0.0f), b.metallic * b.e + opaque * b.spec_ss, specular);
  floatL t_diff = select((floatL)(0.0f),
                         b.metallic * (1.0f - b.e) + opaque * (0.2126f * ((1.0f - b.spec_ss) * base.x) +
                                                               0.7152f * ((1.0f - b.spec_ss) * base.y) +
                                                               0.0722f * ((1.0f - b.spec_ss) * base.z)),
                         diffuse);
  floatL sum = t_spec + t_diff;
  intL some = sum > 0.0f;
  b.t_specular = select((floatL)(0.0f), t_spec / sum, some);
  b.t_diffuse = select((floatL)(0.0f), t_diff / sum, some);
  return b;
}

/// pbr_eval: f |cos| for local wo, wi of the lanes' materials; *pdf the mixture's density.
WT_LANES_INLINE VL pbr_evalL(PbrL b, VL wo, VL wi, intL diffuse, intL specular, __global const float* table, floatL* pdf) {
  intL ok = wo.z > 0.0f && wi.z > 0.0f;
  VL h = vl_normalize(vl_add(wo, wi));
  floatL oh = fmax(vl_dot(wo, h), 0.0f);
  floatL m5 = ggx_schlick_m5_L(oh);
  floatL s_i;
  floatL e_i = pbr_momentsL(table, b, wi.z, &s_i);
  const float f_avg = WT_PBR_DIELECTRIC_F0 + (1.0f - WT_PBR_DIELECTRIC_F0) / 21.0f;
  floatL fms = f_avg * f_avg * b.e_avg / (1.0f - f_avg * (1.0f - b.e_avg));
  floatL opaque = 1.0f - b.metallic;
  // the GGX lobe and its multiple scattering
  intL spec = ok && specular && !b.mirror;
  floatL d = ggx_dL(h, b.alpha);
  floatL dv = d * (1.0f / (1.0f + ggx_lambdaL(wo, b.alpha) + ggx_lambdaL(wi, b.alpha))) / (4.0f * wo.z * wi.z);
  VL f_metal = vl_add(b.base, vl_scale(vl_sub(vl_splat((float3)(1.0f)), b.base), m5));
  floatL f_dielectric = WT_PBR_DIELECTRIC_F0 + (1.0f - WT_PBR_DIELECTRIC_F0) * m5;
  VL f = vl(( b.metallic * f_metal.x + opaque * f_dielectric) * dv, (b.metallic * f_metal.y + opaque * f_dielectric) * dv,
         (b.metallic * f_metal.z + opaque * f_dielectric) * dv);
  floatL ms = (1.0f - b.e) * (1.0f - e_i) / (WT_PI * fmax(1.0f - b.e_avg, 1e-6f));
  VL fa = vl_add(b.base, vl_scale(vl_sub(vl_splat((float3)(1.0f)), b.base), 1.0f / 21.0f));
  VL fms_metal = vl(fa.x * fa.x * b.e_avg / (1.0f - fa.x * (1.0f - b.e_avg)), fa.y * fa.y * b.e_avg / (1.0f - fa.y * (1.0f - b.e_avg)),
                    fa.z * fa.z * b.e_avg / (1.0f - fa.z * (1.0f - b.e_avg)));
  f = vl_add(f, vl(( b.metallic * fms_metal.x + opaque * fms) * ms, (b.metallic * fms_metal.y + opaque * fms) * ms,
                   (b.metallic * fms_metal.z + opaque * fms) * ms));
  f = vl_select(vl_splat((float3)(0.0f)), f, spec);
  floatL pdf_spec = select((floatL)(0.0f), (1.0f / (1.0f + ggx_lambdaL(wo, b.alpha))) * d / (4.0f * wo.z), spec);
  // the diffuse base under what the GGX lobe leaves, both ways
  intL diff = ok && diffuse;
  floatL spec_avg = WT_PBR_DIELECTRIC_F0 * b.e_avg + (1.0f - WT_PBR_DIELECTRIC_F0) * b.s_avg + fms * (1.0f - b.e_avg);
  floatL spec_o = pbr_dielectric_albedoL(b.e, b.s, fms), spec_i = pbr_dielectric_albedoL(e_i, s_i, fms);
  floatL keep = (1.0f / WT_PI) * (1.0f - spec_o) * (1.0f - spec_i) / fmax(1.0f - spec_avg, 1e-6f);
  f = vl_add(f, vl_select(vl_splat((float3)(0.0f)), vl_scale(vl_scale(b.base, opaque), keep), diff));
  floatL pdf_diffuse = select((floatL)(0.0f), wi.z / WT_PI, diff);
  *pdf = select((floatL)(0.0f), b.t_specular * pdf_spec + b.t_diffuse * pdf_diffuse, ok);
  return vl_scale(f, wi.z);
}
#endif

WT_KERNEL void shade(WT_SHADE_KERNEL_PARAMS) {
  const uint count = counters[in_slot];
  const uint first = get_global_id(0) * WT_SHADE_LANES_WIDTH;
  if (first >= count) return;
  const uintL entry = first + WT_LANES_IOTA;
#if WT_HAS_TRANSMISSION
  intL valid = entry < count;  // less the lanes shade_path takes (below)
#else
  const intL valid = entry < count;
#endif
  const bool compact_shadows = (frame.flags & WT_FLAG_COMPACT_SHADOWS) != 0u;
  if (!compact_shadows && (frame.flags & WT_FLAG_SHADOW_QUEUE))
    #pragma unroll
    for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k)
      if (lane_i(valid, k)) shadow_queue[first + k] = WT_NO_HIT;
#if WT_HAS_QUAD_LIGHTS
  __global const uint* quad_of = emitter_quad;
#else
  __global const uint* quad_of = 0;
#endif
  EnvScene env = {environment, env_texels, env_marginal_cdf, env_conditional_cdf};
  GeometryScene g = WT_GEOMETRY_SCENE;
  SurfaceScene ss = WT_SURFACE_SCENE;
  LightScene ls = {lights, alias, frame.light_count, tri_verts, env, g, tri_info, ss};

  // lanes past the queue's end shade its first entry and write nothing
  uintL path = first + WT_SHADE_LANES_WIDTH <= count ? vloadL(0, queue_in + first)
                                                     : gather_u(queue_in, select((uintL)(first), entry, valid), 1u, 0u);
  ColsL hit_row = gather_rows(hits, path);
  floatL hit_t = hit_row.x, hit_b1 = hit_row.y, hit_b2 = hit_row.z;
  uintL prim = as_uintL(hit_row.w);
  ColsL beta_pdf = gather_rows(throughput, path);
  VL beta = cols_v(beta_pdf);
  floatL pdf_prev = beta_pdf.w;
  VL dir = cols_v(gather_rows(ray_d, path));
  // the other per-path rows now, so that their cache misses overlap these
  const CountsL counts = gather_counts(bounce_counts, path);
#if WT_HAS_TRANSMISSION
  const ColsL media_row = gather_rows((__global const float4*)media, path);
#endif
  intL miss = prim == WT_NO_HIT;
  uintL tri = select(prim, (uintL)(0u), miss);  // a miss reads triangle 0 and uses nothing of it

  // the surface (geometry_local_surface, triangle_surface)
  ColsL info = gather_rows((__global const float4*)tri_info, tri);
  uintL v0 = as_uintL(info.x), v1 = as_uintL(info.y), v2 = as_uintL(info.z);
  uintL material = as_uintL(info.w);
  VL p0, p1, p2;
  triangle_cornersL(tri_verts, tri, &p0, &p1, &p2);
  VL p_error;
  VL p = triangle_pointL(p0, p1, p2, hit_b1, hit_b2, &p_error);
  VL e1 = vl_sub(p1, p0), e2 = vl_sub(p2, p0);
  VL ng = vl_cross(e1, e2);
  floatL len = vl_length(ng);
  intL scaled = !(len > 1e-30f && len < 1e30f);
  if (any(scaled && !miss)) {
    // under- or overflowed cross products: triangle_surface's rescaling, lane by lane
    float nx[WT_SHADE_LANES_WIDTH], ny[WT_SHADE_LANES_WIDTH], nz[WT_SHADE_LANES_WIDTH],
        nl[WT_SHADE_LANES_WIDTH];
    vstoreL(ng.x, 0, nx), vstoreL(ng.y, 0, ny), vstoreL(ng.z, 0, nz), vstoreL(len, 0, nl);
    for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k) {
      if (!lane_i(scaled, k)) continue;
      float3 a1 = fabs(lane_v(e1, k)), a2 = fabs(lane_v(e2, k));
      float scale = 1.0f / fmax(fmax(fmax(a1.x, a1.y), a1.z), fmax(fmax(a2.x, a2.y), a2.z));
      float3 n = cross(lane_v(e1, k) * scale, lane_v(e2, k) * scale);
      nx[k] = n.x, ny[k] = n.y, nz[k] = n.z, nl[k] = length(n);
    }
    ng = vl(vloadL(0, nx), vloadL(0, ny), vloadL(0, nz));
    len = vloadL(0, nl);
  }
  ng = vl_select(vl_splat((float3)(0.0f)), vl_div(ng, len), len > 0.0f && isfinite(len));
  {
    VL n0 = cols_v(gather_rows(normals, v0)), n1 = cols_v(gather_rows(normals, v1)), n2 = cols_v(gather_rows(normals, v2));
    floatL b0 = 1.0f - hit_b1 - hit_b2;
    VL ns_sum = vl_add(vl_add(vl_scale(n0, b0), vl_scale(n1, hit_b1)), vl_scale(n2, hit_b2));
    intL has_normals = vl_dot(n0, n0) > 0.0f && vl_dot(n1, n1) > 0.0f && vl_dot(n2, n2) > 0.0f;
    floatL ns_len = vl_length(ns_sum);
    n0 = vl_select(ng, vl_div(ns_sum, ns_len), has_normals && ns_len > 0.0f);
    p0 = n0;  // the shading normal, below as ns
  }
  VL ns = p0;
  __global const float* mf = (__global const float*)materials;
  const uint mstride = sizeof(WtMaterial) / sizeof(float);
  // base_color and emission, rows 0 and 1 of the material's (types.h)
  const uint mrows = sizeof(WtMaterial) / sizeof(float4);
  ColsL base_row = gather_rows((__global const float4*)materials, material * mrows);
  VL base = cols_v(base_row);
#if WT_HAS_PBR || WT_HAS_TRANSMISSION
  // row 2: roughness, model, transmission, ior
  _Static_assert(__builtin_offsetof(WtMaterial, roughness) == 32 && __builtin_offsetof(WtMaterial, model) == 36 &&
                     __builtin_offsetof(WtMaterial, transmission) == 40 && __builtin_offsetof(WtMaterial, ior) == 44,
                 "WtMaterial's row 2 is (roughness, model, transmission, ior)");
  ColsL mrow2 = gather_rows((__global const float4*)materials, material * mrows + 2u);
  uintL model = as_uintL(mrow2.y);
#endif
  ColsL emission = gather_rows((__global const float4*)materials, material * mrows + 1u);
  VL le = cols_v(emission);
  floatL le_both = emission.w;
  // A miss under a black constant sky adds 0 x (a finite MIS weight) x (a
  // finite throughput): nothing, so it skips the emission lane loop. A weight
  // is finite where |pdf_prev| < 1e18 (its square, the power heuristic's, is too).
  const bool black_sky = environment.mode == WT_ENV_CONSTANT &&
                         all(vec4_xyz(environment.color) * environment.intensity == (float3)(0.0f));
  intL dark_miss = miss && (intL)(black_sky ? -1 : 0) && isfinite(beta.x) && isfinite(beta.y) && isfinite(beta.z) &&
                   fabs(pdf_prev) < 1e18f;
#if !WT_NO_PREFETCH
  {
    // an emission event's read-modify-write of radiance (below) finds a line
    // no stream prefetch brings: ask for it while the surface is computed
    // (not under Oclgrind, which lacks the intrinsic: tests/oclgrind/prefetch.cl)
    intL may_emit = valid && ((miss && !dark_miss) || vl_positive(le));
    if (any(may_emit))
      for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k)
        if (lane_i(may_emit, k)) __builtin_prefetch(&radiance[lane_u(path, k)], 1);
  }
#endif
#if WT_HAS_TRANSMISSION
  // The smooth interface of a plain dielectric volume (metallic 0,
  // transmission 1, no dispersion), met from air or on the way out of the one
  // volume the path is in, the lanes shade (`glass`: bsdf_sample's smooth
  // interface and media_crossing's two cases for such a stack). Other paths
  // inside a volume, past a false hit (their own bounce, shared/media.h) or
  // at a transmitting surface take shade.cl's estimator one lane at a time;
  // the rest are paths in air at opaque surfaces, which the lanes shade.
  intL glass = (intL)(0);
  floatL glass_eta = 1.0f;  // n far / n near (bsdf.eta at the boundary)
  {
    uintL medium0 = as_uintL(media_row.x);
    intL one_deep = as_uintL(media_row.y) == WT_MEDIUM_NONE && as_uintL(media_row.z) == WT_MEDIUM_NONE &&
                    as_uintL(media_row.w) == WT_MEDIUM_NONE;
    intL in_medium = medium0 != WT_MEDIUM_NONE || !one_deep;
    intL false_hits = counts.w >= WT_FALSE_HIT_STEP;
    intL transmits = !miss && model == WT_MATERIAL_PBR && mrow2.z > 0.0f;
    intL candidate = valid && transmits && !false_hits && one_deep;
    if (any(candidate)) {
      intL from_inside = vl_dot(ng, dir) > 0.0f;
      floatL ior = mrow2.w;
      glass_eta = select(ior, 1.0f / ior, from_inside);
      // in air, or leaving the stack's one volume through its own boundary
      glass = candidate && (medium0 == WT_MEDIUM_NONE || (from_inside && medium0 == material)) &&
              mrow2.z == 1.0f && base_row.w == 0.0f &&
              gather_f(mf, material, mstride, __builtin_offsetof(WtMaterial, volume) / sizeof(float) + 3u) != 0.0f &&
              !(gather_f(mf, material, mstride, __builtin_offsetof(WtMaterial, dispersion) / sizeof(float)) > 0.0f) &&
              (mrow2.x < WT_PBR_MIN_ROUGHNESS ||
               fabs(glass_eta - 1.0f) < 1e-3f);
    }
    intL alone = valid && !glass && (in_medium || false_hits || transmits);
    if (any(alone))
      for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k)
        if (lane_i(alone, k)) shade_path(first + k, WT_SHADE_KERNEL_ARGS);
    valid = valid && !alone;
    if (!any(valid)) return;
  }
  // the volume a glass lane's path leaves absorbs along its segment (Beer-Lambert)
  if (any(glass && vl_dot(ng, dir) > 0.0f)) {
    const uint vo = __builtin_offsetof(WtMaterial, volume) / sizeof(float);
    VL sigma = vl(gather_f(mf, material, mstride, vo), gather_f(mf, material, mstride, vo + 1u),
                  gather_f(mf, material, mstride, vo + 2u));
    floatL d = hit_t * vl_length(dir);
    VL absorbed = vl(exp(-sigma.x * d), exp(-sigma.y * d), exp(-sigma.z * d));
    beta = vl_select(beta, vl_mul(beta, absorbed), glass && vl_dot(ng, dir) > 0.0f && vl_positive(sigma));
  }
#endif
  intL inside = vl_dot(ng, dir) > 0.0f;
  intL active = valid && !miss && vl_dot(ng, ng) != 0.0f;

  // misses and emitters' hits, lane by lane (shade.cl's code)
  intL emits = active && (le_both != 0.0f || !inside) && vl_positive(le);
  intL lit = valid && ((miss && !dark_miss) || emits);
  if (any(lit)) {
    for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k) {
      if (!lane_i(lit, k)) continue;
      uint pk = lane_u(path, k);
      float4 hit = (float4)(lane_f(hit_t, k), lane_f(hit_b1, k), lane_f(hit_b2, k), as_float(lane_u(prim, k)));
      float3 e = shade_lane_emission(frame, env, emitter_pdf_area, lights, tri_verts, light_tree, emitter_leaf,
                                     prev_normal, quad_of, pk, lane_u(prim, k), ray_o[pk].xyz, lane_v(dir, k), hit,
                                     lane_v(ng, k), lane_v(le, k), lane_f(pdf_prev, k));
      float3 emitted = lane_v(beta, k) * e;
      shade_check_finite(frame, counters, pk, emitted, WT_NONFINITE_EMISSION);
      radiance[pk] += (float4)(emitted, 0.0f);
    }
  }
  if (frame.bounce >= frame.max_bounces) return;

  VL wo = vl_neg(dir);
  ng = vl_select(ng, vl_neg(ng), vl_dot(ng, wo) < 0.0f);
  ns = vl_select(ns, vl_neg(ns), vl_dot(ns, ng) < 0.0f);
  ns = vl_select(ns, ng, vl_dot(ns, wo) <= 0.0f);
  VL frame_t, frame_b;
  frame_from_normalL(ns, &frame_t, &frame_b);
  floatL wo_z = vl_dot(wo, ns);
  // a Lambertian surface scatters by its diffuse lobe alone: past its limit
  // neither light sampling nor the BSDF finds anything (shade.cl's lobes)
  intL diffuse = counts.x < frame.max_diffuse_bounces;
#if WT_HAS_PBR
  // a metallic-roughness one by the lobes shade.cl allows its path
  intL pbr = active && model == WT_MATERIAL_PBR;
  uintL lobes = (as_uintL(diffuse) & WT_LOBE_DIFFUSE) |
                (as_uintL(counts.y < frame.max_specular_bounces) & WT_LOBE_SPECULAR) |
                (as_uintL(counts.z < frame.max_transmission_bounces) & WT_LOBE_TRANSMISSION);
  intL specular = (lobes & WT_LOBE_SPECULAR) != 0u;
#if WT_HAS_TRANSMISSION
  // glass scatters by the interface while reflection or transmission is left (bsdf_sample)
  intL through = (lobes & WT_LOBE_TRANSMISSION) != 0u;
  pbr = pbr && !glass;
  active = active && select(diffuse || (pbr && specular), specular || through, glass);
#else
  active = active && (diffuse || (pbr && specular));
#endif
  VL wo_local = vl(vl_dot(wo, frame_t), vl_dot(wo, frame_b), wo_z);
  PbrL mat;
  if (any(pbr)) mat = pbr_makeL(pbr_table, base, base_row.w, mrow2.x, wo_z, diffuse, specular);
#else
  active = active && diffuse;
#endif
  if (!any(active)) return;
  VL origin = ray_offset_originL(p, p_error, ng);
  floatL u_pick, u_rr, u_lobe = 0.0f, u_tree = 0.0f;
  sampler_get2_L(frame, path, WT_DIM_LIGHT_PICK, &u_pick, &u_rr);
  // the lobe pair where a lane picks a metallic-roughness or glass technique
  // by it, or descends the light tree (there, below): a pure function of the
  // path and dimension, drawn late or not at all for the same values
  bool lobe_drawn = false;
#if WT_HAS_PBR
#if WT_HAS_TRANSMISSION
  if (any(active && (pbr || glass))) {
#else
  if (any(active && pbr)) {
#endif
    sampler_get2_L(frame, path, WT_DIM_BSDF_LOBE, &u_lobe, &u_tree);
    lobe_drawn = true;
  }
#endif

  // next-event estimation
  uint nee_count = (frame.flags & WT_FLAG_NEE) ? frame.light_count : 0u;
#if WT_HAS_TRANSMISSION
  if (nee_count > 0u && any(active && !glass)) {
#else
  if (nee_count > 0u) {
#endif
    // light_pick
    __global const float* af = (__global const float*)alias;
    floatL scaled_u = u_pick * (float)nee_count;
    uintL slot = min(convert_uintL(scaled_u), nee_count - 1u);
    floatL remainder = scaled_u - convert_floatL(slot);
    uintL index = select(as_uintL(gather_f(af, slot, 4u, 1u)), slot, remainder < gather_f(af, slot, 4u, 0u));
    floatL pmf = gather_f(af, index, 4u, 2u);
    __global const float* lrow = (__global const float*)lights;
    uintL type = as_uintL(gather_f(lrow, index, 16u, 12u));
#if WT_HAS_TRANSMISSION
    // glass's smooth interface finds nothing by light sampling (its bsdf_eval is 0)
    intL tree = active && !glass && type == WT_LIGHT_TREE;
#else
    intL tree = active && type == WT_LIGHT_TREE;
#endif
#if WT_HAS_LIGHT_TREE
    if (any(tree)) {
      if (!lobe_drawn) sampler_get2_L(frame, path, WT_DIM_BSDF_LOBE, &u_lobe, &u_tree);
      floatL pmf_tree;
      uintL picked = light_tree_pickL(light_tree, origin, ng, u_tree, tree, &pmf_tree);
      pmf = select(pmf, pmf * pmf_tree, tree);
      // an emitter nothing reaches: pmf 0, and a valid row to read
      index = select(index, select(picked, (uintL)(0u), picked == WT_NO_HIT), tree);
      type = as_uintL(gather_f(lrow, index, 16u, 12u));
    }
#endif
    floatL u1, u2;
    sampler_get2_L(frame, path, WT_DIM_LIGHT_U, &u1, &u2);
    LightSampleL s;
    s.ok = (intL)(0);
    s.wi = s.target = s.radiance = vl_splat((float3)(0.0f));
    s.distance = s.pdf = 0.0f;
    s.is_delta = (intL)(0);
    s.prim = (uintL)(WT_NO_HIT);
#if WT_HAS_TRANSMISSION
    intL want = active && !glass && pmf > 0.0f;
#else
    intL want = active && pmf > 0.0f;
#endif
    intL tri_lights = want && type == WT_LIGHT_TRIANGLE;
    if (any(tri_lights)) light_sample_triangleL(lrow, tri_verts, index, tri_lights, p, u1, u2, &s);
    intL others = want && !tri_lights;
#if WT_HAS_QUAD_LIGHTS
    intL quads = want && type == WT_LIGHT_QUAD;
    if (any(quads)) light_sample_quadL(lrow, index, quads, p, u1, u2, &s);
    others = others && !quads;
#endif
#if WT_HAS_OTHER_LIGHTS
    if (any(others)) {
      // point, spot, directional lights and the environment: light_sample, lane by lane
      const int n = WT_SHADE_LANES_WIDTH;
      float wx[n], wy[n], wz[n], tx[n], ty[n], tz[n], rx[n], ry[n], rz[n], di[n], pd[n];
      int ok[n], dl[n];
      uint pr[n];
      vstoreL(s.wi.x, 0, wx), vstoreL(s.wi.y, 0, wy), vstoreL(s.wi.z, 0, wz);
      vstoreL(s.target.x, 0, tx), vstoreL(s.target.y, 0, ty), vstoreL(s.target.z, 0, tz);
      vstoreL(s.radiance.x, 0, rx), vstoreL(s.radiance.y, 0, ry), vstoreL(s.radiance.z, 0, rz);
      vstoreL(s.distance, 0, di), vstoreL(s.pdf, 0, pd), vstoreL(s.ok, 0, ok), vstoreL(s.is_delta, 0, dl);
      vstoreL(s.prim, 0, pr);
      for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k) {
        if (!lane_i(others, k)) continue;
        LightSample one;
        ok[k] = light_sample(ls, lane_u(index, k), lane_v(p, k), lane_f(u1, k), lane_f(u2, k), &one) ? -1 : 0;
        wx[k] = one.wi.x, wy[k] = one.wi.y, wz[k] = one.wi.z;
        tx[k] = one.target.x, ty[k] = one.target.y, tz[k] = one.target.z;
        rx[k] = one.radiance.x, ry[k] = one.radiance.y, rz[k] = one.radiance.z;
        di[k] = one.distance, pd[k] = one.pdf, dl[k] = one.is_delta, pr[k] = one.prim;
      }
      s.wi = vl(vloadL(0, wx), vloadL(0, wy), vloadL(0, wz));
      s.target = vl(vloadL(0, tx), vloadL(0, ty), vloadL(0, tz));
      s.radiance = vl(vloadL(0, rx), vloadL(0, ry), vloadL(0, rz));
      s.distance = vloadL(0, di), s.pdf = vloadL(0, pd), s.ok = vloadL(0, ok), s.is_delta = vloadL(0, dl);
      s.prim = vloadL(0, pr);
    }
#endif
    // the Lambertian BSDF (bsdf_eval)
    intL connect = want && s.ok && vl_dot(ng, s.wi) > 0.0f;
    floatL wi_z = vl_dot(s.wi, ns);
    intL eval_ok = connect && diffuse && wo_z > 0.0f && wi_z > 0.0f;
    floatL pdf_bsdf = select((floatL)(0.0f), wi_z / WT_PI, eval_ok);
    VL f_cos = vl_select(vl_splat((float3)(0.0f)), vl_scale(base, wi_z / WT_PI), eval_ok);
#if WT_HAS_PBR
    intL pbr_connect = connect && pbr;
    if (any(pbr_connect)) {
      floatL pdf_pbr;
      VL f_pbr = pbr_evalL(mat, wo_local, vl(vl_dot(s.wi, frame_t), vl_dot(s.wi, frame_b), wi_z), diffuse, specular,
                           pbr_table, &pdf_pbr);
      f_cos = vl_select(f_cos, f_pbr, pbr_connect);
      pdf_bsdf = select(pdf_bsdf, pdf_pbr, pbr_connect);
    }
#endif
    floatL pdf_light = s.pdf * pmf;
    floatL a = pdf_light, b = pdf_bsdf;
    if (frame.flags & WT_FLAG_POWER_HEURISTIC) a *= a, b *= b;
    else if (frame.flags & WT_FLAG_POWER_LAMBERTIAN) {
      // Lambertian lanes weigh by the power heuristic (shade.cl's shade_power_here)
      intL lambertian = active;
#if WT_HAS_PBR
      lambertian = lambertian && !pbr;
#endif
      a = select(a, a * a, lambertian);
      b = select(b, b * b, lambertian);
    }
    floatL mis = select((floatL)(0.0f), a / (a + b), a + b > 0.0f);
    floatL w = select(mis, (floatL)(1.0f), s.is_delta != 0 || (intL)(!(frame.flags & WT_FLAG_MIS) ? -1 : 0));
    VL contribution = vl_scale(vl_mul(vl_mul(beta, f_cos), s.radiance), w / pdf_light);
    intL carries = vl_positive(f_cos);
    if (frame.flags & WT_FLAG_CHECK_NONFINITE)
      for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k)
        if (lane_i(carries, k))
          shade_check_finite(frame, counters, lane_u(path, k), lane_v(contribution, k), WT_NONFINITE_LIGHT);
    // the shadow ray from the offset origin at the target, a margin short of it
    intL finite_light = !isinf(s.distance);
    VL to_target = vl_sub(s.target, origin);
    floatL target_len = vl_length(to_target);
    VL shadow_dir = vl_select(s.wi, vl_div(to_target, target_len), finite_light);
    floatL tmax = select((floatL)(INFINITY), target_len * (1.0f - WT_SHADOW_MARGIN), finite_light);
    intL queued = carries && vl_positive(contribution) && tmax > 0.0f;
    if (any(queued)) {
      // one atomic for the work-item's shadow rays: each is a full fence on x86
      uint shadow_slot = 0u;
      if (compact_shadows) {
        uint n = 0u;
        #pragma unroll
        for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k) n += lane_i(queued, k) ? 1u : 0u;
        shadow_slot = atomic_add(&counters[WT_COUNTER_SHADOW], n);
      }
      #pragma unroll
      for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k) {
        if (!lane_i(queued, k)) continue;
        uint pk = lane_u(path, k);
        shadow_queue[compact_shadows ? shadow_slot++ : first + k] = pk;
        shadow_o[pk] = (float4)(lane_v(origin, k), 0.0f);
        shadow_d[pk] = (float4)(lane_v(shadow_dir, k), lane_f(tmax, k));
        shadow_radiance[pk] = (float4)(lane_v(contribution, k), 0.0f);
        shadow_skip[pk] = (uint2)(lane_u(prim, k), lane_u(s.prim, k));
      }
    }
  }

  // the next direction: the cosine lobe (bsdf_sample's diffuse technique)
  floatL u_b1, u_b2;
  sampler_get2_L(frame, path, WT_DIM_BSDF_U, &u_b1, &u_b2);
  floatL cos_phi;
  floatL sin_phi = wt_sincospiL(2.0f * u_b2, &cos_phi);
  floatL r = sqrt(u_b1);
  VL wl = vl(r * cos_phi, r * sin_phi, sqrt(fmax(0.0f, 1.0f - u_b1)));
  floatL pdf = wl.z / WT_PI;
  VL f_cos = vl_scale(base, wl.z / WT_PI);
  intL go = active && diffuse && wo_z > 0.0f && wl.z > 0.0f && pdf > 0.0f && vl_positive(f_cos);
  VL weight = vl_div(f_cos, pdf);
#if WT_HAS_PBR
  // or the metallic-roughness BSDF's techniques
  uintL lobe = (uintL)(WT_LOBE_DIFFUSE);
  intL pbr_go = active && pbr;
  if (any(pbr_go)) {
    // bsdf_sample: the GGX lobe (or its mirror) or the cosine lobe by u_lobe
    intL glossy = u_lobe < mat.t_specular;
    intL delta = glossy && mat.mirror;
    VL h = ggx_sample_visible_normalL(wo_local, mat.alpha, u_b1, u_b2);
    VL reflected = vl_sub(vl_scale(h, 2.0f * vl_dot(wo_local, h)), wo_local);
    VL w = vl_select(wl, vl_select(reflected, vl(-wo_local.x, -wo_local.y, wo_local.z), delta), glossy);
    floatL pdf_pbr;
    VL f_pbr = pbr_evalL(mat, wo_local, w, diffuse, specular, pbr_table, &pdf_pbr);
    intL ok = pbr_go && wo_z > 0.0f && w.z > 0.0f && (glossy || (diffuse && mat.t_diffuse > 0.0f)) && pdf_pbr > 0.0f &&
              vl_positive(f_pbr);
    // the mirror: F at mu_o over the probability of its technique (pbr_mirror)
    floatL m5 = ggx_schlick_m5_L(wo_local.z);
    floatL opaque = 1.0f - mat.metallic;
    floatL fd = WT_PBR_DIELECTRIC_F0 + (1.0f - WT_PBR_DIELECTRIC_F0) * m5;
    VL f_mirror = vl(mat.metallic * (mat.base.x + (1.0f - mat.base.x) * m5) + opaque * fd,
                     mat.metallic * (mat.base.y + (1.0f - mat.base.y) * m5) + opaque * fd,
                     mat.metallic * (mat.base.z + (1.0f - mat.base.z) * m5) + opaque * fd);
    intL ok_delta = pbr_go && wo_z > 0.0f && mat.t_specular > 0.0f && w.z > 0.0f && vl_positive(f_mirror);
    wl = vl_select(wl, w, pbr);
    weight = vl_select(weight, vl_select(vl_div(f_pbr, pdf_pbr), vl_div(f_mirror, mat.t_specular), delta), pbr);
    pdf = select(pdf, select(pdf_pbr, (floatL)(0.0f), delta), pbr);
    lobe = select(lobe, select((uintL)(WT_LOBE_DIFFUSE), (uintL)(WT_LOBE_SPECULAR), glossy), pbr);
    go = select(go, select(ok, ok_delta, delta), pbr);
  }
#endif
#if WT_HAS_TRANSMISSION
  // glass: bsdf_sample's smooth interface, its only technique (probability 1):
  // Fresnel's reflectance at wo picks reflection or refraction by u_lobe
  intL crossed = (intL)(0);
  intL glass_go = active && glass;
  if (any(glass_go)) {
    floatL eta = glass_eta;
    // interface_fresnel (ggx_fresnel_dielectric; specular 1 on the lanes)
    floatL c = fmin(fmax(wo_z, 0.0f), 1.0f);
    floatL sin2_c = (1.0f - c * c) / (eta * eta);
    floatL cos_tc = sqrt(fmax(1.0f - sin2_c, 0.0f));
    floatL rs = (c - eta * cos_tc) / (c + eta * cos_tc), rp = (eta * c - cos_tc) / (eta * c + cos_tc);
    floatL f = select(0.5f * (rs * rs + rp * rp), (floatL)(1.0f), sin2_c >= 1.0f);
    floatL p_reflect = select(select((floatL)(0.0f), (floatL)(1.0f), specular), f, specular && through);
    intL reflects = fmin(u_lobe, 0x1.fffffep-1f) < p_reflect;
    // interface_direction about the normal (0, 0, 1)
    floatL sin2_t = (1.0f - wo_z * wo_z) / (eta * eta);
    floatL cos_t = sqrt(1.0f - sin2_t);
    VL refracted = vl_normalize(vl(-wo_local.x / eta, -wo_local.y / eta, -wo_z / eta + (wo_z / eta - cos_t)));
    VL w = vl_select(refracted, vl(-wo_local.x, -wo_local.y, wo_z), reflects);
    // F / p_reflect, or base (1 - F) / (eta^2 (1 - p_reflect)): radiance scaled by 1 / eta^2 on the way
    floatL f_picked = f / p_reflect;
    VL w_weight = vl_select(vl_scale(base, (1.0f - f) / (eta * eta * (1.0f - p_reflect))),
                            vl(f_picked, f_picked, f_picked), reflects);
    wl = vl_select(wl, w, glass);
    weight = vl_select(weight, w_weight, glass);
    pdf = select(pdf, (floatL)(0.0f), glass);
    lobe = select(lobe, select((uintL)(WT_LOBE_TRANSMISSION), (uintL)(WT_LOBE_SPECULAR), reflects), glass);
    go = select(go, glass_go && wo_z > 0.0f && (reflects || sin2_t < 1.0f) && vl_positive(w_weight), glass);
    crossed = glass && !reflects;
  }
#endif
  VL wi = vl_add(vl_add(vl_scale(frame_t, wl.x), vl_scale(frame_b, wl.y)), vl_scale(ns, wl.z));
#if WT_HAS_TRANSMISSION
  // reflection leaves on ng's side, transmission on the other
  go = go && select(vl_dot(wi, ng) > 0.0f, vl_dot(wi, ng) < 0.0f, crossed);
#else
  go = go && vl_dot(wi, ng) > 0.0f;
#endif
  beta = vl_mul(beta, weight);
  if ((frame.flags & WT_FLAG_RR) && frame.bounce >= frame.rr_min_depth) {
    // the throughput without the radiance scaling of the glass the path goes on in (shade.cl)
    floatL n2 = 1.0f;
#if WT_HAS_TRANSMISSION
    n2 = select(n2, select(glass_eta * glass_eta, 1.0f / (glass_eta * glass_eta), inside), glass && (inside != crossed));
#endif
    floatL q = fmin(fmax(beta.x, fmax(beta.y, beta.z)) * n2, 0.95f);
    go = go && u_rr < q;
    beta = vl_div(beta, q);
  }
  if (frame.flags & WT_FLAG_CHECK_NONFINITE)
    for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k)
      if (lane_i(go, k)) shade_check_finite(frame, counters, lane_u(path, k), lane_v(beta, k), WT_NONFINITE_THROUGHPUT);
  go = go && !(beta.x <= 0.0f && beta.y <= 0.0f && beta.z <= 0.0f);
  if (!any(go)) return;
  {
    // the pdf's sign carries a Lambertian lane's power heuristic to the light the ray may find
    intL lambertian = active && (intL)(shade_power_here(frame, true) ? -1 : 0);
#if WT_HAS_PBR
    lambertian = lambertian && !pbr;
#endif
    pdf = select(pdf, -pdf, lambertian);
  }
  // the survivors' slots first: the atomic waits for every store before it to leave the core
  uint survivors = 0u;
  #pragma unroll
  for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k) survivors += lane_i(go, k) ? 1u : 0u;
  uint slot = atomic_add(&counters[out_slot], survivors);
  scatter_v(throughput, path, go, beta, pdf);
#if WT_HAS_TRANSMISSION
  // light may come through glass: the light tree's pmf at a hit the ray finds takes no receiver normal (shade.cl's
  // tree_normal), and a refracted ray leaves from the far side
  scatter_v(prev_normal, path, go, vl_select(ng, vl_splat((float3)(0.0f)), glass && through), (floatL)(0.0f));
  scatter_v(ray_o, path, go, vl_select(origin, ray_offset_originL(p, p_error, vl_neg(ng)), crossed), (floatL)(0.0f));
#else
  scatter_v(prev_normal, path, go, ng, (floatL)(0.0f));
  scatter_v(ray_o, path, go, origin, (floatL)(0.0f));
#endif
  scatter_v(ray_d, path, go, wi, (floatL)(INFINITY));
  #pragma unroll
  for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k) {
    if (!lane_i(go, k)) continue;
    uint pk = lane_u(path, k);
    ushort4 bounces = (ushort4)(lane_u(counts.x, k), lane_u(counts.y, k), lane_u(counts.z, k), lane_u(counts.w, k));
#if WT_HAS_TRANSMISSION
    if (lane_u(lobe, k) & WT_LOBE_DIFFUSE) bounces.x++;
    else if (lane_i(crossed, k)) bounces.z++;
    else bounces.y++;
    // media_cross: into the volume from air, or out of the stack's one volume (or one it lacks)
    if (lane_i(crossed, k))
      media[pk] = (uint4)(lane_i(inside, k) ? WT_MEDIUM_NONE : lane_u(material, k), WT_MEDIUM_NONE, WT_MEDIUM_NONE,
                          WT_MEDIUM_NONE);
#elif WT_HAS_PBR
    if (lane_u(lobe, k) & WT_LOBE_DIFFUSE) bounces.x++;
    else bounces.y++;
#else
    bounces.x++;
#endif
    bounce_counts[pk] = bounces;
    ray_skip[pk] = lane_u(prim, k);
    queue_out[slot++] = pk;
  }
}
