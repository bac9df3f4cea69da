// Stage 3 for scenes whose surfaces are all triangles, Lambertian or
// metallic-roughness without extensions (no textures, holes, other primitive
// types, AOVs; the path integrator): the shade kernel over eight paths per
// work-item on float8 lanes. PoCL runs a work-group as a loop over its items
// and vectorises that loop only when the body is scalar, straight-line code,
// which shade is not (float3 values, loops, atomics), so the work-items are
// made wide by hand. The same estimator as shade.cl, term for term: the
// miss, emission hits, the light tree and lights other than triangles and
// rectangles take shade.cl's scalar functions one lane at a time; the rest
// (the surface, light picking, triangle and rectangle sampling, the
// Lambertian BSDF, the metallic-roughness BSDF without extensions in
// bsdf.cl's order, roulette) runs on all lanes at once. The host launches one
// work-item per WT_SHADE_LANES_WIDTH queue entries.

#define WT_SHADE_LANES_WIDTH 8

// Every helper inlined: a lane vector passed by pointer to a called function
// lives in memory, which PoCL keeps per work-item of the group. Under
// Oclgrind, which lacks what inlining a struct's return makes, not inlined
// (as WT_INLINE_STRUCT).
#if WT_NO_SRET_INLINE
#define WT_LANES_INLINE __attribute__((noinline)) inline
#else
#define WT_LANES_INLINE inline __attribute__((always_inline))
#endif

typedef struct V8 {
  float8 x, y, z;
} V8;

WT_LANES_INLINE V8 v8(float8 x, float8 y, float8 z) { return (V8){x, y, z}; }
WT_LANES_INLINE V8 v8_splat(float3 a) { return (V8){(float8)(a.x), (float8)(a.y), (float8)(a.z)}; }
WT_LANES_INLINE V8 v8_add(V8 a, V8 b) { return (V8){a.x + b.x, a.y + b.y, a.z + b.z}; }
WT_LANES_INLINE V8 v8_sub(V8 a, V8 b) { return (V8){a.x - b.x, a.y - b.y, a.z - b.z}; }
WT_LANES_INLINE V8 v8_mul(V8 a, V8 b) { return (V8){a.x * b.x, a.y * b.y, a.z * b.z}; }
WT_LANES_INLINE V8 v8_scale(V8 a, float8 s) { return (V8){a.x * s, a.y * s, a.z * s}; }
WT_LANES_INLINE V8 v8_div(V8 a, float8 s) { return (V8){a.x / s, a.y / s, a.z / s}; }
WT_LANES_INLINE V8 v8_neg(V8 a) { return (V8){-a.x, -a.y, -a.z}; }
WT_LANES_INLINE float8 v8_dot(V8 a, V8 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
WT_LANES_INLINE V8 v8_cross(V8 a, V8 b) {
  return (V8){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
WT_LANES_INLINE float8 v8_length(V8 a) { return sqrt(v8_dot(a, a)); }
WT_LANES_INLINE V8 v8_normalize(V8 a) { return v8_div(a, v8_length(a)); }
/// m ? b : a, per lane (m: a comparison's -1 or 0).
WT_LANES_INLINE V8 v8_select(V8 a, V8 b, int8 m) { return (V8){select(a.x, b.x, m), select(a.y, b.y, m), select(a.z, b.z, m)}; }
WT_LANES_INLINE int8 v8_positive(V8 a) { return a.x > 0.0f || a.y > 0.0f || a.z > 0.0f; }

/// Lane k of a (k a constant once the lane loops unroll).
WT_LANES_INLINE float lane_f(float8 a, int k) {
  float v[8];
  vstore8(a, 0, v);
  return v[k];
}
WT_LANES_INLINE uint lane_u(uint8 a, int k) {
  uint v[8];
  vstore8(a, 0, v);
  return v[k];
}
WT_LANES_INLINE int lane_i(int8 a, int k) {
  int v[8];
  vstore8(a, 0, v);
  return v[k];
}
WT_LANES_INLINE float3 lane_v(V8 a, int k) { return (float3)(lane_f(a.x, k), lane_f(a.y, k), lane_f(a.z, k)); }

/// Element `offset` of rows of `stride` floats at each lane's row.
WT_LANES_INLINE float8 gather_f(__global const float* base, uint8 row, uint stride, uint offset) {
  uint8 i = row * stride + offset;
  return (float8)(base[i.s0], base[i.s1], base[i.s2], base[i.s3], base[i.s4], base[i.s5], base[i.s6], base[i.s7]);
}
WT_LANES_INLINE uint8 gather_u(__global const uint* base, uint8 row, uint stride, uint offset) {
  uint8 i = row * stride + offset;
  return (uint8)(base[i.s0], base[i.s1], base[i.s2], base[i.s3], base[i.s4], base[i.s5], base[i.s6], base[i.s7]);
}
WT_LANES_INLINE V8 gather_v(__global const float4* rows, uint8 row) {
  __global const float* f = (__global const float*)rows;
  return v8(gather_f(f, row, 4u, 0u), gather_f(f, row, 4u, 1u), gather_f(f, row, 4u, 2u));
}

/// Rows `row` of a float4 buffer set to (v, w) where m.
WT_LANES_INLINE void scatter_v(__global float4* rows, uint8 row, int8 m, V8 v, float8 w) {
  #pragma unroll
  for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k)
    if (lane_i(m, k)) rows[lane_u(row, k)] = (float4)(lane_v(v, k), lane_f(w, k));
}

// ---- the sampler (sampler.cl, shared/rng.h, shared/sampler.h) on lanes

WT_LANES_INLINE uint8 rng_hash8(uint8 x) {
  uint8 state = x * 747796405u + 2891336453u;
  uint8 word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}
#if WT_AVOID_BITREVERSE
// Oclgrind cannot run llvm.bitreverse (shared/sampler.h): lane by lane
WT_LANES_INLINE uint8 sampler_reverse_bits8(uint8 x) {
  return (uint8)(sampler_reverse_bits(x.s0), sampler_reverse_bits(x.s1), sampler_reverse_bits(x.s2),
                 sampler_reverse_bits(x.s3), sampler_reverse_bits(x.s4), sampler_reverse_bits(x.s5),
                 sampler_reverse_bits(x.s6), sampler_reverse_bits(x.s7));
}
#else
WT_LANES_INLINE uint8 sampler_reverse_bits8(uint8 x) {
  x = ((x >> 1u) & 0x55555555u) | ((x & 0x55555555u) << 1u);
  x = ((x >> 2u) & 0x33333333u) | ((x & 0x33333333u) << 2u);
  x = ((x >> 4u) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4u);
  x = ((x >> 8u) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8u);
  return (x >> 16u) | (x << 16u);
}
#endif
WT_LANES_INLINE uint8 sampler_lk_permute8(uint8 x, uint8 seed) {
  x ^= x * 0x3d20adeau;
  x += seed;
  x *= (seed >> 16u) | 1u;
  x ^= x * 0x05526c56u;
  x ^= x * 0x53a22864u;
  return x;
}
WT_LANES_INLINE uint8 sampler_sobol_pascal8(uint8 index) {
  index ^= (index >> 1u) & 0x55555555u;
  index ^= (index >> 2u) & 0x33333333u;
  index ^= (index >> 4u) & 0x0f0f0f0fu;
  index ^= (index >> 8u) & 0x00ff00ffu;
  index ^= (index >> 16u) & 0x0000ffffu;
  return index;
}

/// sampler_get2 for each lane's pixel: dimensions dim and dim + 1, bit for bit.
WT_LANES_INLINE void sampler_get2_8(WtFrameParams frame, uint8 pixel, uint dim, float8* a,
                                                          float8* b) {
  if (frame.flags & WT_FLAG_SOBOL) {
    uint8 group_seed = rng_hash8(frame.seed ^ rng_hash8(pixel ^ rng_hash((frame.bounce << 8u) + (dim >> 1u) + 0x9e3779b9u)));
    uint8 index = sampler_reverse_bits8(sampler_lk_permute8((uint8)(sampler_reverse_bits(frame.sample)), group_seed));
    uint8 va = sampler_reverse_bits8(sampler_lk_permute8(index, rng_hash8(group_seed + 1u)));
    uint8 vb = sampler_reverse_bits8(sampler_lk_permute8(sampler_sobol_pascal8(index), rng_hash8(group_seed + 2u)));
    *a = convert_float8(va >> 8u) * (1.0f / 16777216.0f);
    *b = convert_float8(vb >> 8u) * (1.0f / 16777216.0f);
    return;
  }
  uint inner_a = rng_hash(frame.sample ^ rng_hash((frame.bounce << 8u) + dim));
  uint inner_b = rng_hash(frame.sample ^ rng_hash((frame.bounce << 8u) + dim + 1u));
  *a = convert_float8(rng_hash8(frame.seed ^ rng_hash8(pixel ^ inner_a)) >> 8u) * (1.0f / 16777216.0f);
  *b = convert_float8(rng_hash8(frame.seed ^ rng_hash8(pixel ^ inner_b)) >> 8u) * (1.0f / 16777216.0f);
}

// ---- common.h, shared/spawn.h and shared/trig.h on lanes

WT_LANES_INLINE float8 wt_sincospi8(float8 x, float8* cos_out) {
  float8 k = rint(2.0f * x);
  float8 r = x - 0.5f * k;
  float8 t = 3.14159265358979323846f * r;
  float8 t2 = t * t;
  float8 s = t + t * t2 * (-1.6666654611e-1f + t2 * (8.3321608736e-3f + t2 * -1.9515295891e-4f));
  float8 c = 1.0f - 0.5f * t2 +
             t2 * t2 * (4.166664568298827e-2f + t2 * (-1.388731625493765e-3f + t2 * 2.443315711809948e-5f));
  int8 q = convert_int8(k) & 3;
  int8 odd = (q & 1) != 0;
  float8 sin_v = select(s, c, odd), cos_v = select(c, s, odd);
  sin_v = select(sin_v, -sin_v, q == 2 || q == 3);
  cos_v = select(cos_v, -cos_v, q == 1 || q == 2);
  *cos_out = cos_v;
  return sin_v;
}

WT_LANES_INLINE float8 wt_atan2_8(float8 y, float8 x) {
  float8 ax = fabs(x), ay = fabs(y);
  float8 t = ay / ax;
  int8 high = t > 2.414213562373095f;
  int8 mid = !high && t > 0.4142135623730950f;
  float8 base = select(select((float8)(0.0f), (float8)(0.25f * WT_PI), mid), (float8)(0.5f * WT_PI), high);
  t = select(select(t, (t - 1.0f) / (t + 1.0f), mid), -1.0f / t, high);
  float8 z = t * t;
  float8 a = base + ((((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z - 3.33329491539e-1f) * z * t + t);
  a = select(a, (float8)(0.0f), ax == 0.0f && ay == 0.0f);
  a = select(a, WT_PI - a, signbit(x));
  return copysign(a, y);
}

WT_LANES_INLINE float8 spawn_next_up8(float8 v) {
  float8 w = select(v, (float8)(0.0f), v == 0.0f);
  uint8 bits = as_uint8(w);
  float8 up = as_float8(select(bits - 1u, bits + 1u, w >= 0.0f));
  return select(up, v, v == INFINITY);
}
WT_LANES_INLINE float8 spawn_next_down8(float8 v) {
  float8 w = select(v, (float8)(-0.0f), v == 0.0f);
  uint8 bits = as_uint8(w);
  float8 down = as_float8(select(bits + 1u, bits - 1u, w > 0.0f));
  return select(down, v, v == -INFINITY);
}
WT_LANES_INLINE float8 spawn_offset_coordinate8(float8 p, float8 offset) {
  float8 moved = p + offset;
  return select(select(moved, spawn_next_down8(moved), offset < 0.0f), spawn_next_up8(moved), offset > 0.0f);
}
WT_LANES_INLINE V8 ray_offset_origin8(V8 p, V8 p_error, V8 n) {
  float8 d = fabs(n.x) * p_error.x + fabs(n.y) * p_error.y + fabs(n.z) * p_error.z;
  V8 offset = v8_scale(n, d);
  return v8(spawn_offset_coordinate8(p.x, offset.x), spawn_offset_coordinate8(p.y, offset.y),
            spawn_offset_coordinate8(p.z, offset.z));
}
WT_LANES_INLINE float8 spawn_barycentric_error8(float8 b0, float8 b1, float8 b2, float8 p0, float8 p1, float8 p2) {
  return spawn_gamma(7) * (fabs(b0 * p0) + fabs(b1 * p1) + fabs(b2 * p2)) + spawn_gamma(2) * fabs(p0);
}
WT_LANES_INLINE V8 triangle_point8(V8 p0, V8 p1, V8 p2, float8 b1, float8 b2, V8* error) {
  float8 b0 = 1.0f - b1 - b2;
  *error = v8(spawn_barycentric_error8(b0, b1, b2, p0.x, p1.x, p2.x), spawn_barycentric_error8(b0, b1, b2, p0.y, p1.y, p2.y),
              spawn_barycentric_error8(b0, b1, b2, p0.z, p1.z, p2.z));
  return v8_add(v8_add(v8_scale(p0, b0), v8_scale(p1, b1)), v8_scale(p2, b2));
}
WT_LANES_INLINE void frame_from_normal8(V8 n, V8* t, V8* b) {
  float8 sign = copysign((float8)(1.0f), n.z);
  float8 a = -1.0f / (sign + n.z);
  float8 c = n.x * n.y * a;
  *t = v8(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
  *b = v8(c, sign + n.y * n.y * a, -n.y);
}

/// Each lane's triangle's corners (triangle_corners).
WT_LANES_INLINE void triangle_corners8(__global const float4* tri_verts, uint8 prim, V8* p0, V8* p1, V8* p2) {
  __global const float* f = (__global const float*)tri_verts;
  uint8 lane = (prim >> 2u) * (4u * WT_TRIANGLE_BLOCK_ROWS) + (prim & 3u);
  *p0 = v8(gather_f(f, lane, 1u, 0u), gather_f(f, lane, 1u, 4u), gather_f(f, lane, 1u, 8u));
  *p1 = v8(gather_f(f, lane, 1u, 12u), gather_f(f, lane, 1u, 16u), gather_f(f, lane, 1u, 20u));
  *p2 = v8(gather_f(f, lane, 1u, 24u), gather_f(f, lane, 1u, 28u), gather_f(f, lane, 1u, 32u));
}

// ---- lights/light_sampling.cl on lanes

WT_LANES_INLINE float8 light_triangle_solid_angle8(V8 p, V8 p0, V8 p1, V8 p2) {
  V8 a = v8_sub(p0, p), b = v8_sub(p1, p), c = v8_sub(p2, p);
  float8 la = v8_length(a), lb = v8_length(b), lc = v8_length(c);
  float8 numerator = fabs(v8_dot(a, v8_cross(b, c)));
  float8 denominator = la * lb * lc + v8_dot(a, b) * lc + v8_dot(a, c) * lb + v8_dot(b, c) * la;
  return fabs(2.0f * wt_atan2_8(numerator, denominator));
}
WT_LANES_INLINE int8 light_use_spherical8(float8 solid_angle) {
  return solid_angle >= WT_SPHERICAL_MIN_SOLID_ANGLE && solid_angle <= WT_SPHERICAL_MAX_SOLID_ANGLE;
}
WT_LANES_INLINE V8 light_orthonormal8(V8 a, V8 b) {
  V8 v = v8_sub(a, v8_scale(b, v8_dot(a, b)));
  float8 l = v8_length(v);
  return v8_select(v8_splat((float3)(0.0f)), v8_div(v, l), l > 0.0f);
}
WT_LANES_INLINE V8 light_sample_spherical_triangle8(V8 A, V8 B, V8 C, float8 solid_angle, float8 u1, float8 u2) {
  V8 n_ab = light_orthonormal8(B, A), n_ac = light_orthonormal8(C, A);
  float8 cos_alpha = clamp(v8_dot(n_ab, n_ac), -1.0f, 1.0f);
  float8 sin_alpha = sqrt(fmax(0.0f, 1.0f - cos_alpha * cos_alpha));
  float8 cos_area;
  float8 sin_area = wt_sincospi8(u1 * (solid_angle * (1.0f / WT_PI)), &cos_area);
  float8 s = cos_area * sin_alpha - sin_area * cos_alpha, t = -(cos_area * cos_alpha + sin_area * sin_alpha);
  float8 cos_c = v8_dot(A, B);
  float8 k1 = t + cos_alpha, k2 = s - sin_alpha * cos_c;
  float8 cos_b = (k2 + (k2 * t - k1 * s) * cos_alpha) / ((k2 * s + k1 * t) * sin_alpha);
  cos_b = clamp(cos_b, -1.0f, 1.0f);
  V8 c_prime = v8_add(v8_scale(A, cos_b), v8_scale(n_ac, sqrt(fmax(0.0f, 1.0f - cos_b * cos_b))));
  float8 cos_theta = 1.0f - u2 * (1.0f - v8_dot(c_prime, B));
  float8 sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
  return v8_normalize(v8_add(v8_scale(B, cos_theta), v8_scale(light_orthonormal8(c_prime, B), sin_theta)));
}

/// A sampled connection on lanes (LightSample).
typedef struct LightSample8 {
  V8 wi, target, radiance;
  float8 distance, pdf;
  int8 is_delta, ok;
  uint8 prim;
} LightSample8;

/// An area light's sample on the lanes of m (never a delta light).
WT_LANES_INLINE void light_sample8_take(LightSample8* s, int8 m, int8 ok, V8 wi, float8 distance, V8 target,
                                        float8 pdf, V8 le, uint8 prim) {
  s->ok = select(s->ok, ok, m);
  s->wi = v8_select(s->wi, wi, m);
  s->distance = select(s->distance, distance, m);
  s->target = v8_select(s->target, target, m);
  s->pdf = select(s->pdf, pdf, m);
  s->radiance = v8_select(s->radiance, le, m);
  s->is_delta = select(s->is_delta, (int8)(0), m);
  s->prim = select(s->prim, prim, m);
}

/// light_sample's WT_LIGHT_TRIANGLE case for lanes `m`; `row` the lights' rows (16 floats each).
WT_LANES_INLINE void light_sample_triangle8(__global const float* lrow, __global const float4* tri_verts, uint8 index, int8 m,
                                   V8 p, float8 u1, float8 u2, LightSample8* s) {
  uint8 t = as_uint8(gather_f(lrow, index, 16u, 13u));
  float8 two_sided = gather_f(lrow, index, 16u, 3u);
  V8 le = v8(gather_f(lrow, index, 16u, 8u), gather_f(lrow, index, 16u, 9u), gather_f(lrow, index, 16u, 10u));
  V8 p0, p1, p2;
  triangle_corners8(tri_verts, t, &p0, &p1, &p2);
  V8 n = v8_cross(v8_sub(p1, p0), v8_sub(p2, p0));
  float8 solid_angle = light_triangle_solid_angle8(p, p0, p1, p2);
  int8 spherical = light_use_spherical8(solid_angle);
  // uniform by area, converted to solid angle
  float8 su = sqrt(u1);
  float8 b1 = su * (1.0f - u2), b2 = su * u2;
  V8 q_error;
  V8 q = triangle_point8(p0, p1, p2, b1, b2, &q_error);
  float8 area2 = v8_length(n);
  V8 to_light = v8_sub(q, p);
  float8 d2 = v8_dot(to_light, to_light);
  int8 ok = area2 > 0.0f && d2 > 0.0f;
  float8 distance = sqrt(d2);
  V8 wi = v8_div(to_light, distance);
  float8 cos_light = -v8_dot(n, wi) / area2;
  cos_light = select(cos_light, fabs(cos_light), two_sided != 0.0f);
  ok = ok && cos_light > 0.0f;
  V8 n_unit = v8_div(n, area2);
  V8 target = ray_offset_origin8(q, q_error, v8_select(v8_neg(n_unit), n_unit, v8_dot(n, to_light) < 0.0f));
  float8 pdf = (2.0f / area2) * d2 / cos_light;
  if (any(m && spherical)) {
    V8 w = light_sample_spherical_triangle8(v8_normalize(v8_sub(p0, p)), v8_normalize(v8_sub(p1, p)),
                                            v8_normalize(v8_sub(p2, p)), solid_angle, u1, u2);
    float8 facing = v8_dot(n, w);
    int8 ok_s = two_sided != 0.0f || facing < 0.0f;
    float8 dist = v8_dot(n, v8_sub(p0, p)) / facing;
    ok_s = ok_s && dist > 0.0f && isfinite(dist);
    V8 e1 = v8_sub(p1, p0), e2 = v8_sub(p2, p0), tv = v8_sub(p, p0);
    V8 pv = v8_cross(w, e2), qv = v8_cross(tv, e1);
    float8 inv_det = 1.0f / v8_dot(e1, pv);
    float8 sb1 = clamp(v8_dot(tv, pv) * inv_det, 0.0f, 1.0f), sb2 = clamp(v8_dot(w, qv) * inv_det, 0.0f, 1.0f);
    float8 sum = sb1 + sb2;
    int8 over = sum > 1.0f;
    sb1 = select(sb1, sb1 / sum, over);
    sb2 = select(sb2, sb2 / sum, over);
    ok_s = ok_s && isfinite(sb1) && isfinite(sb2);
    V8 sq_error;
    V8 sq = triangle_point8(p0, p1, p2, sb1, sb2, &sq_error);
    V8 nn = v8_normalize(n);
    V8 s_target = ray_offset_origin8(sq, sq_error, v8_select(v8_neg(nn), nn, facing < 0.0f));
    ok = select(ok, ok_s, spherical);
    wi = v8_select(wi, w, spherical);
    distance = select(distance, dist, spherical);
    target = v8_select(target, s_target, spherical);
    pdf = select(pdf, 1.0f / solid_angle, spherical);
  }
  light_sample8_take(s, m, ok, wi, distance, target, pdf, le, t);
}

#if WT_HAS_QUAD_LIGHTS
typedef struct RectView8 {
  float8 x0, y0, x1, y1, z0, l00, l01;
} RectView8;

WT_LANES_INLINE float8 light_rect_view8(V8 p, V8 c, V8 e1, V8 e2, RectView8* v) {
  float8 ex = v8_length(e1), ey = v8_length(e2);
  V8 x = v8_div(e1, ex), y = v8_div(e2, ey);
  V8 d = v8_sub(c, p);
  float8 z0 = -fabs(v8_dot(d, v8_normalize(v8_cross(x, y))));
  float8 x0 = v8_dot(d, x), y0 = v8_dot(d, y), x1 = x0 + ex, y1 = y0 + ey;
  float8 z2 = z0 * z0;
  float8 l00 = sqrt(x0 * x0 + y0 * y0 + z2), l10 = sqrt(x1 * x1 + y0 * y0 + z2);
  float8 l11 = sqrt(x1 * x1 + y1 * y1 + z2), l01 = sqrt(x0 * x0 + y1 * y1 + z2);
  *v = (RectView8){x0, y0, x1, y1, z0, l00, l01};
  float8 triple = -z0 * ex * ey;
  float8 d_00_11 = (x0 * x1 + y0 * y1 + z2) / (l00 * l11);
  float8 n1 = triple / (l00 * l10 * l11), n2 = triple / (l00 * l11 * l01);
  float8 e_1 = 1.0f + (x0 * x1 + y0 * y0 + z2) / (l00 * l10) + d_00_11 + (x1 * x1 + y0 * y1 + z2) / (l10 * l11);
  float8 e_2 = 1.0f + d_00_11 + (x0 * x0 + y0 * y1 + z2) / (l00 * l01) + (x0 * x1 + y1 * y1 + z2) / (l11 * l01);
  return 2.0f * wt_atan2_8(n1 * e_2 + n2 * e_1, e_1 * e_2 - n1 * n2);
}

WT_LANES_INLINE void light_sample_spherical_rect8(RectView8 v, float8 solid_angle, float8 u1, float8 u2, float8* s_out,
                                         float8* t_out) {
  float8 x0 = v.x0, y0 = v.y0, x1 = v.x1, y1 = v.y1, z0 = v.z0;
  float8 z2 = z0 * z0;
  float8 l0 = sqrt(z2 + y0 * y0), l2 = sqrt(z2 + y1 * y1), l3 = sqrt(z2 + x0 * x0);
  float8 inv23 = 1.0f / (l2 * l3), inv30 = 1.0f / (l3 * l0);
  float8 cos_g2 = x0 * y1 * inv23, sin_g2 = -z0 * v.l01 * inv23;
  float8 cos_g3 = -x0 * y0 * inv30, sin_g3 = -z0 * v.l00 * inv30;
  float8 cos_k = cos_g2 * cos_g3 - sin_g2 * sin_g3, sin_k = -(sin_g2 * cos_g3 + cos_g2 * sin_g3);
  float8 cos_a;
  float8 sin_a = wt_sincospi8(u1 * (solid_angle * (1.0f / WT_PI)), &cos_a);
  float8 cos_au = cos_k * cos_a - sin_k * sin_a, sin_au = sin_k * cos_a + cos_k * sin_a;
  float8 b0 = -y0 / l0, b1 = y1 / l2;
  float8 fu = (cos_au * b0 - b1) / sin_au;
  float8 cu = clamp(copysign((float8)(1.0f), fu) * rsqrt(fu * fu + b0 * b0), -1.0f, 1.0f);
  float8 xu = -(cu * z0) / sqrt(fmax(1.0f - cu * cu, 1e-30f));
  xu = clamp(xu, x0, x1);
  float8 dd = sqrt(xu * xu + z2);
  float8 h0 = y0 / sqrt(dd * dd + y0 * y0), h1 = y1 / sqrt(dd * dd + y1 * y1);
  float8 hv = h0 + u2 * (h1 - h0), hv2 = hv * hv;
  float8 yv = select(y1, hv * dd / sqrt(1.0f - hv2), hv2 < 1.0f - 1e-6f);
  yv = clamp(yv, y0, y1);
  *s_out = clamp((xu - x0) / (x1 - x0), 0.0f, 1.0f);
  *t_out = clamp((yv - y0) / (y1 - y0), 0.0f, 1.0f);
}

/// light_sample_quad for lanes `m`.
WT_LANES_INLINE void light_sample_quad8(__global const float* lrow, __global const float4* tri_verts, uint8 index, int8 m,
                               V8 p, float8 u1, float8 u2, LightSample8* s) {
  uint8 first = as_uint8(gather_f(lrow, index, 16u, 13u));
  uint8 second = as_uint8(gather_f(lrow, index, 16u, 1u));
  uint8 corner = convert_uint8(gather_f(lrow, index, 16u, 0u));
  float8 two_sided = gather_f(lrow, index, 16u, 3u);
  V8 le = v8(gather_f(lrow, index, 16u, 8u), gather_f(lrow, index, 16u, 9u), gather_f(lrow, index, 16u, 10u));
  V8 p0, p1, p2;
  triangle_corners8(tri_verts, first, &p0, &p1, &p2);
  // light_quad_rect: the corner at the right angle and its two edges
  int8 k0 = corner == 0u, k1 = corner == 1u;
  V8 c = v8_select(v8_select(p2, p1, k1), p0, k0);
  V8 e1 = v8_sub(v8_select(v8_select(p0, p2, k1), p1, k0), c);
  V8 e2 = v8_sub(v8_select(v8_select(p1, p0, k1), p2, k0), c);
  // light_sample_rect
  V8 n = v8_cross(e1, e2);
  float8 area = v8_length(n);
  int8 ok = area > 0.0f;
  n = v8_div(n, area);
  float8 height = v8_dot(n, v8_sub(p, c));
  ok = ok && (two_sided != 0.0f || height > 0.0f);
  V8 to_centre = v8_sub(v8_add(c, v8_scale(v8_add(e1, e2), (float8)(0.5f))), p);
  int8 spherical = area >= WT_QUAD_SPHERICAL_MIN_RATIO * v8_dot(to_centre, to_centre);
  float8 solid_angle = 0.0f;
  float8 st_x = u1, st_y = u2;
  if (any(m && ok && spherical)) {
    RectView8 view;
    solid_angle = light_rect_view8(p, c, e1, e2, &view);
    spherical = spherical && light_use_spherical8(solid_angle);
    float8 sx, sy;
    light_sample_spherical_rect8(view, solid_angle, u1, u2, &sx, &sy);
    st_x = select(st_x, sx, spherical);
    st_y = select(st_y, sy, spherical);
  } else {
    spherical = (int8)(0);
  }
  V8 q_error;
  V8 q = triangle_point8(c, v8_add(c, e1), v8_add(c, e2), st_x, st_y, &q_error);
  V8 to_light = v8_sub(q, p);
  float8 d2 = v8_dot(to_light, to_light);
  ok = ok && d2 > 0.0f;
  float8 distance = sqrt(d2);
  V8 wi = v8_div(to_light, distance);
  float8 cos_light = fabs(v8_dot(n, wi));
  ok = ok && cos_light > 0.0f;
  V8 target = ray_offset_origin8(q, q_error, v8_select(v8_neg(n), n, height > 0.0f));
  float8 pdf = select(d2 / (cos_light * area), 1.0f / solid_angle, spherical);
  light_sample8_take(s, m, ok, wi, distance, target, pdf, le, select(second, first, st_x + st_y <= 1.0f));
}
#endif

// ---- lights/light_tree.cl on lanes

/// light_tree_importance2's terms for one node per lane (rows of 16 floats, WtLightNode).
WT_LANES_INLINE float8 light_tree_importance8(__global const float* nf, uint8 node, V8 p, V8 n) {
  float8 power = gather_f(nf, node, 16u, 3u);
  float8 lo_x = gather_f(nf, node, 16u, 0u), lo_y = gather_f(nf, node, 16u, 1u), lo_z = gather_f(nf, node, 16u, 2u);
  float8 hi_x = gather_f(nf, node, 16u, 4u), hi_y = gather_f(nf, node, 16u, 5u), hi_z = gather_f(nf, node, 16u, 6u);
  float8 ex = hi_x - lo_x, ey = hi_y - lo_y, ez = hi_z - lo_z;
  float8 r2 = 0.25f * (ex * ex + ey * ey + ez * ez);
  float8 tx = 0.5f * (lo_x + hi_x) - p.x, ty = 0.5f * (lo_y + hi_y) - p.y, tz = 0.5f * (lo_z + hi_z) - p.z;
  float8 d2 = tx * tx + ty * ty + tz * tz;
  float8 inv_d = 1.0f / sqrt(d2), inv_d2 = inv_d * inv_d;
  float8 wx = tx * inv_d, wy = ty * inv_d, wz = tz * inv_d;
  float8 sin_u2 = r2 * inv_d2;
  float8 cos_u = sqrt(fmax(0.0f, 1.0f - sin_u2)), sin_u = fmin(gather_f(nf, node, 16u, 15u) * inv_d, 1.0f);
  float8 cos_a = n.x * wx + n.y * wy + n.z * wz;
  float8 sin_a = sqrt(fmax(0.0f, 1.0f - cos_a * cos_a));
  int8 no_normal = n.x == 0.0f && n.y == 0.0f && n.z == 0.0f;
  float8 cos_i = select(cos_a * cos_u + sin_a * sin_u, (float8)(1.0f), cos_a >= cos_u || no_normal);
  float8 cos_o = gather_f(nf, node, 16u, 11u), sin_o = gather_f(nf, node, 16u, 14u);
  float8 cos_ou = cos_o * cos_u - sin_o * sin_u;
  float8 cos_theta = -(gather_f(nf, node, 16u, 8u) * wx + gather_f(nf, node, 16u, 9u) * wy + gather_f(nf, node, 16u, 10u) * wz);
  float8 sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
  float8 sin_ou = sin_o * cos_u + cos_o * sin_u;
  float8 cos_e = select(cos_theta * cos_ou + sin_theta * sin_ou, (float8)(1.0f), !(cos_o > -cos_u) || !(cos_theta < cos_ou));
  float8 importance = select(power * cos_i * cos_e * inv_d2, (float8)(0.0f), !(cos_i > 0.0f) || !(cos_e > 0.0f));
  importance = select(importance, power / fmax(r2, 1e-30f), d2 <= r2);
  return select(importance, (float8)(0.0f), !(power > 0.0f));
}

/// light_tree_pick for lanes `m`, all lanes descending together: each
/// lane's light-list index (WT_NO_HIT, *pmf 0, where nothing can reach it).
WT_LANES_INLINE uint8 light_tree_pick8(__global const WtLightNode* nodes, V8 p, V8 n, float8 u, int8 m, float8* pmf) {
  __global const float* nf = (__global const float*)nodes;
  __global const uint* nu = (__global const uint*)nodes;
  uint8 k = (uint8)(0u);
  float8 prob = 1.0f;
  int8 reached = m;
  int8 live = m && gather_u(nu, k, 16u, 12u) == 0u;
  while (any(live)) {
    uint8 c = gather_u(nu, k, 16u, 7u);
    float8 il = light_tree_importance8(nf, c, p, n), ir = light_tree_importance8(nf, c + 1u, p, n);
    float8 sum = il + ir;
    int8 lost = live && !(sum > 0.0f);
    reached = reached && !lost;
    live = live && !lost;
    float8 pl = il / sum;
    int8 left = u < pl;
    float8 u_next = fmin(select((u - pl) / (1.0f - pl), u / pl, left), 0x1.fffffep-1f);
    u = select(u, u_next, live);
    prob = select(prob, prob * select(ir / sum, pl, left), live);
    k = select(k, select(c + 1u, c, left), live);
    live = live && gather_u(nu, k, 16u, 12u) == 0u;
  }
  *pmf = select((float8)(0.0f), prob, reached);
  return select((uint8)(WT_NO_HIT), gather_u(nu, k, 16u, 7u), reached);
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
  uint leaf = emitter_leaf[prim];
  if (select_pdf > 0.0f && leaf != WT_LIGHT_NODE_NONE)
    select_pdf *= light_tree_pmf(light_tree, leaf, origin, prev_normal[path].xyz);
  float3 p0, p1, p2;
  float pdf_light;
#if WT_HAS_QUAD_LIGHTS
  uint quad = emitter_quad_or_null[prim];
  if (quad != WT_NO_QUAD) {
    light_quad_rect(tri_verts, lights[quad], &p0, &p1, &p2);
    pdf_light = light_quad_pdf(select_pdf, origin, p0, p1, p2, hit.x, dir, ng);
  } else
#endif
  {
    triangle_corners(tri_verts, prim, &p0, &p1, &p2);
    pdf_light = light_triangle_pdf(select_pdf, origin, p0, p1, p2, hit.x, dir, ng);
  }
  return le * shade_emission_weight(frame, pdf_prev, pdf_light);
}

/// Counter c (x diffuse, y specular, z transmission) of each lane's path's bounce_counts.
WT_LANES_INLINE uint8 gather_count8(__global const ushort4* bounce_counts, uint8 path, uint c) {
  __global const ushort* cf = (__global const ushort*)bounce_counts;
  uint8 i = 4u * path + c;
  return convert_uint8((ushort8)(cf[i.s0], cf[i.s1], cf[i.s2], cf[i.s3], cf[i.s4], cf[i.s5], cf[i.s6], cf[i.s7]));
}

#if WT_HAS_PBR
// ---- bsdf.cl's metallic-roughness BSDF on lanes, for scenes without its
// extensions (switches.h): the base's GGX reflection (metal, and the
// dielectric's F0 WT_PBR_DIELECTRIC_F0) with its multiple scattering over the
// diffuse base; shared/ggx.h and shared/materials.h term for term.

WT_LANES_INLINE float8 ggx_d8(V8 h, float8 alpha) {
  float8 a2 = alpha * alpha;
  float8 t = (h.x * h.x + h.y * h.y) / a2 + h.z * h.z;
  return select(1.0f / (WT_GGX_PI * a2 * t * t), (float8)(0.0f), h.z <= 0.0f);
}
WT_LANES_INLINE float8 ggx_lambda8(V8 v, float8 alpha) {
  float8 z2 = v.z * v.z;
  float8 a2_tan2 = alpha * alpha * (v.x * v.x + v.y * v.y) / z2;
  return select(0.5f * (sqrt(1.0f + a2_tan2) - 1.0f), (float8)(INFINITY), z2 <= 0.0f);
}
/// ggx_schlick(0, c): (1 - c)^5
WT_LANES_INLINE float8 ggx_schlick_m5_8(float8 c) {
  float8 m = fmin(fmax(1.0f - c, 0.0f), 1.0f);
  float8 m2 = m * m;
  return m2 * m2 * m;
}
WT_LANES_INLINE V8 ggx_sample_visible_normal8(V8 v, float8 alpha, float8 u1, float8 u2) {
  V8 sv = v8_normalize(v8(alpha * v.x, alpha * v.y, v.z));
  float8 lensq = sv.x * sv.x + sv.y * sv.y;
  float8 inv = 1.0f / sqrt(lensq);
  int8 tilted = lensq > 0.0f;
  float8 t1x = select((float8)(1.0f), -sv.y * inv, tilted), t1y = select((float8)(0.0f), sv.x * inv, tilted);
  float8 t2x = -sv.z * t1y, t2y = sv.z * t1x, t2z = sv.x * t1y - sv.y * t1x;
  float8 cos_phi;
  float8 sin_phi = wt_sincospi8(2.0f * u2, &cos_phi);
  float8 r = sqrt(u1);
  float8 p1 = r * cos_phi, p2 = r * sin_phi;
  float8 s = 0.5f * (1.0f + sv.z);
  p2 = (1.0f - s) * sqrt(fmax(0.0f, 1.0f - p1 * p1)) + s * p2;
  float8 p3 = sqrt(fmax(0.0f, 1.0f - p1 * p1 - p2 * p2));
  V8 n = v8(p1 * t1x + p2 * t2x + p3 * sv.x, p1 * t1y + p2 * t2y + p3 * sv.y, p2 * t2z + p3 * sv.z);
  return v8_normalize(v8(alpha * n.x, alpha * n.y, fmax(n.z, 0.0f)));
}

/// pbr_table_lookup of each lane's (mu, row).
WT_LANES_INLINE float8 pbr_table_lookup8(__global const float* table, uint offset, float8 mu, float8 y) {
  float8 x = sqrt(fmin(fmax(mu, 0.0f), 1.0f)) * (float)(WT_PBR_TABLE_N - 1);
  uint8 x0 = convert_uint8(fmin(x, (float)(WT_PBR_TABLE_N - 2))), y0 = convert_uint8(fmin(y, (float)(WT_PBR_TABLE_N - 2)));
  float8 fx = x - convert_float8(x0), fy = y - convert_float8(y0);
  uint8 i = y0 * WT_PBR_TABLE_N + x0;
  float8 r00 = gather_f(table, i, 1u, offset), r01 = gather_f(table, i, 1u, offset + 1u);
  float8 r10 = gather_f(table, i, 1u, offset + WT_PBR_TABLE_N), r11 = gather_f(table, i, 1u, offset + WT_PBR_TABLE_N + 1u);
  float8 a = r00 + fx * (r01 - r00);
  float8 b = r10 + fx * (r11 - r10);
  return a + fy * (b - a);
}
/// pbr_table_average at each lane's row.
WT_LANES_INLINE float8 pbr_table_average8(__global const float* table, uint offset, float8 y) {
  uint8 y0 = convert_uint8(fmin(y, (float)(WT_PBR_TABLE_N - 2)));
  float8 fy = y - convert_float8(y0);
  float8 a = gather_f(table, y0, 1u, offset), b = gather_f(table, y0, 1u, offset + 1u);
  return a + fy * (b - a);
}

/// A metallic-roughness material at the lanes' hits with its view of wo
/// (Bsdf and PbrView without the layers), and its techniques' probabilities.
typedef struct Pbr8 {
  V8 base;
  float8 metallic, alpha, row;  ///< row: the tables' (pbr_table_roughness_coord)
  int8 mirror;
  float8 e, s, spec_ss;         ///< PbrView's
  float8 e_avg, s_avg;          ///< base_average's
  float8 t_specular, t_diffuse; ///< bsdf_techniques'
} Pbr8;

/// pbr_moments at cosines mu: E and S.
WT_LANES_INLINE float8 pbr_moments8(__global const float* table, Pbr8 b, float8 mu, float8* s) {
  *s = select(pbr_table_lookup8(table, WT_PBR_TABLE_S, mu, b.row), ggx_schlick_m5_8(mu), b.mirror);
  return select(pbr_table_lookup8(table, WT_PBR_TABLE_E, mu, b.row), (float8)(1.0f), b.mirror);
}
/// pbr_dielectric_albedo for F0 WT_PBR_DIELECTRIC_F0 and specular 1.
WT_LANES_INLINE float8 pbr_dielectric_albedo8(float8 e, float8 s, float8 fms) {
  return WT_PBR_DIELECTRIC_F0 * e + (1.0f - WT_PBR_DIELECTRIC_F0) * s + fms * (1.0f - e);
}

/// bsdf_make, pbr_view and bsdf_techniques at local wo for the lanes' materials.
WT_LANES_INLINE Pbr8 pbr_make8(__global const WtMaterial* materials, __global const float* table, uint8 material, V8 base,
                               float8 wo_z, int8 diffuse, int8 specular) {
  __global const float* mf = (__global const float*)materials;
  const uint mstride = sizeof(WtMaterial) / sizeof(float);
  Pbr8 b;
  b.base = base;
  b.metallic = gather_f(mf, material, mstride, 3u);
  float8 roughness = gather_f(mf, material, mstride, __builtin_offsetof(WtMaterial, roughness) / sizeof(float));
  b.alpha = roughness * roughness;
  b.mirror = roughness < WT_PBR_MIN_ROUGHNESS;
  b.row = sqrt(fmin(fmax((roughness - WT_PBR_MIN_ROUGHNESS) / (1.0f - WT_PBR_MIN_ROUGHNESS), 0.0f), 1.0f)) *
          (float)(WT_PBR_TABLE_N - 1);
  b.e = pbr_moments8(table, b, wo_z, &b.s);
  b.spec_ss = pbr_dielectric_albedo8(b.e, b.s, (float8)(0.0f));
  b.e_avg = select(pbr_table_average8(table, WT_PBR_TABLE_E_AVG, b.row), (float8)(1.0f), b.mirror);
  b.s_avg = select(pbr_table_average8(table, WT_PBR_TABLE_S_AVG, b.row), (float8)(1.0f / 21.0f), b.mirror);
  float8 opaque = 1.0f - b.metallic;
  float8 t_spec = select((float8)(0.0f), b.metallic * b.e + opaque * b.spec_ss, specular);
  float8 t_diff = select((float8)(0.0f),
                         b.metallic * (1.0f - b.e) + opaque * (0.2126f * ((1.0f - b.spec_ss) * base.x) +
                                                               0.7152f * ((1.0f - b.spec_ss) * base.y) +
                                                               0.0722f * ((1.0f - b.spec_ss) * base.z)),
                         diffuse);
  float8 sum = t_spec + t_diff;
  int8 some = sum > 0.0f;
  b.t_specular = select((float8)(0.0f), t_spec / sum, some);
  b.t_diffuse = select((float8)(0.0f), t_diff / sum, some);
  return b;
}

/// pbr_eval: f |cos| for local wo, wi of the lanes' materials; *pdf the mixture's density.
WT_LANES_INLINE V8 pbr_eval8(Pbr8 b, V8 wo, V8 wi, int8 diffuse, int8 specular, __global const float* table, float8* pdf) {
  int8 ok = wo.z > 0.0f && wi.z > 0.0f;
  V8 h = v8_normalize(v8_add(wo, wi));
  float8 oh = fmax(v8_dot(wo, h), 0.0f);
  float8 m5 = ggx_schlick_m5_8(oh);
  float8 s_i;
  float8 e_i = pbr_moments8(table, b, wi.z, &s_i);
  const float f_avg = WT_PBR_DIELECTRIC_F0 + (1.0f - WT_PBR_DIELECTRIC_F0) / 21.0f;
  float8 fms = f_avg * f_avg * b.e_avg / (1.0f - f_avg * (1.0f - b.e_avg));
  float8 opaque = 1.0f - b.metallic;
  // the GGX lobe and its multiple scattering
  int8 spec = ok && specular && !b.mirror;
  float8 d = ggx_d8(h, b.alpha);
  float8 dv = d * (1.0f / (1.0f + ggx_lambda8(wo, b.alpha) + ggx_lambda8(wi, b.alpha))) / (4.0f * wo.z * wi.z);
  V8 f_metal = v8_add(b.base, v8_scale(v8_sub(v8_splat((float3)(1.0f)), b.base), m5));
  float8 f_dielectric = WT_PBR_DIELECTRIC_F0 + (1.0f - WT_PBR_DIELECTRIC_F0) * m5;
  V8 f = v8(( b.metallic * f_metal.x + opaque * f_dielectric) * dv, (b.metallic * f_metal.y + opaque * f_dielectric) * dv,
         (b.metallic * f_metal.z + opaque * f_dielectric) * dv);
  float8 ms = (1.0f - b.e) * (1.0f - e_i) / (WT_PI * fmax(1.0f - b.e_avg, 1e-6f));
  V8 fa = v8_add(b.base, v8_scale(v8_sub(v8_splat((float3)(1.0f)), b.base), 1.0f / 21.0f));
  V8 fms_metal = v8(fa.x * fa.x * b.e_avg / (1.0f - fa.x * (1.0f - b.e_avg)), fa.y * fa.y * b.e_avg / (1.0f - fa.y * (1.0f - b.e_avg)),
                    fa.z * fa.z * b.e_avg / (1.0f - fa.z * (1.0f - b.e_avg)));
  f = v8_add(f, v8(( b.metallic * fms_metal.x + opaque * fms) * ms, (b.metallic * fms_metal.y + opaque * fms) * ms,
                   (b.metallic * fms_metal.z + opaque * fms) * ms));
  f = v8_select(v8_splat((float3)(0.0f)), f, spec);
  float8 pdf_spec = select((float8)(0.0f), (1.0f / (1.0f + ggx_lambda8(wo, b.alpha))) * d / (4.0f * wo.z), spec);
  // the diffuse base under what the GGX lobe leaves, both ways
  int8 diff = ok && diffuse;
  float8 spec_avg = WT_PBR_DIELECTRIC_F0 * b.e_avg + (1.0f - WT_PBR_DIELECTRIC_F0) * b.s_avg + fms * (1.0f - b.e_avg);
  float8 spec_o = pbr_dielectric_albedo8(b.e, b.s, fms), spec_i = pbr_dielectric_albedo8(e_i, s_i, fms);
  float8 keep = (1.0f / WT_PI) * (1.0f - spec_o) * (1.0f - spec_i) / fmax(1.0f - spec_avg, 1e-6f);
  f = v8_add(f, v8_select(v8_splat((float3)(0.0f)), v8_scale(v8_scale(b.base, opaque), keep), diff));
  float8 pdf_diffuse = select((float8)(0.0f), wi.z / WT_PI, diff);
  *pdf = select((float8)(0.0f), b.t_specular * pdf_spec + b.t_diffuse * pdf_diffuse, ok);
  return v8_scale(f, wi.z);
}
#endif

WT_KERNEL void shade(WT_SHADE_KERNEL_PARAMS) {
  const uint count = counters[in_slot];
  const uint first = get_global_id(0) * WT_SHADE_LANES_WIDTH;
  if (first >= count) return;
  const uint8 entry = first + (uint8)(0, 1, 2, 3, 4, 5, 6, 7);
  const int8 valid = entry < count;
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
  uint8 path = gather_u(queue_in, select((uint8)(first), entry, valid), 1u, 0u);
  __global const float* hf = (__global const float*)hits;
  float8 hit_t = gather_f(hf, path, 4u, 0u), hit_b1 = gather_f(hf, path, 4u, 1u), hit_b2 = gather_f(hf, path, 4u, 2u);
  uint8 prim = as_uint8(gather_f(hf, path, 4u, 3u));
  __global const float* tf = (__global const float*)throughput;
  V8 beta = gather_v(throughput, path);
  float8 pdf_prev = gather_f(tf, path, 4u, 3u);
  V8 dir = gather_v(ray_d, path);
  int8 miss = prim == WT_NO_HIT;
  uint8 tri = select(prim, (uint8)(0u), miss);  // a miss reads triangle 0 and uses nothing of it

  // the surface (geometry_local_surface, triangle_surface)
  __global const uint* info = (__global const uint*)tri_info;
  uint8 v0 = gather_u(info, tri, 4u, 0u), v1 = gather_u(info, tri, 4u, 1u), v2 = gather_u(info, tri, 4u, 2u);
  uint8 material = gather_u(info, tri, 4u, 3u);
  V8 p0, p1, p2;
  triangle_corners8(tri_verts, tri, &p0, &p1, &p2);
  V8 p_error;
  V8 p = triangle_point8(p0, p1, p2, hit_b1, hit_b2, &p_error);
  V8 e1 = v8_sub(p1, p0), e2 = v8_sub(p2, p0);
  V8 ng = v8_cross(e1, e2);
  float8 len = v8_length(ng);
  int8 scaled = !(len > 1e-30f && len < 1e30f);
  if (any(scaled && !miss)) {
    // under- or overflowed cross products: triangle_surface's rescaling, lane by lane
    float nx[8], ny[8], nz[8], nl[8];
    vstore8(ng.x, 0, nx), vstore8(ng.y, 0, ny), vstore8(ng.z, 0, nz), vstore8(len, 0, nl);
    for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k) {
      if (!lane_i(scaled, k)) continue;
      float3 a1 = fabs(lane_v(e1, k)), a2 = fabs(lane_v(e2, k));
      float scale = 1.0f / fmax(fmax(fmax(a1.x, a1.y), a1.z), fmax(fmax(a2.x, a2.y), a2.z));
      float3 n = cross(lane_v(e1, k) * scale, lane_v(e2, k) * scale);
      nx[k] = n.x, ny[k] = n.y, nz[k] = n.z, nl[k] = length(n);
    }
    ng = v8(vload8(0, nx), vload8(0, ny), vload8(0, nz));
    len = vload8(0, nl);
  }
  ng = v8_select(v8_splat((float3)(0.0f)), v8_div(ng, len), len > 0.0f && isfinite(len));
  {
    V8 n0 = gather_v(normals, v0), n1 = gather_v(normals, v1), n2 = gather_v(normals, v2);
    float8 b0 = 1.0f - hit_b1 - hit_b2;
    V8 ns_sum = v8_add(v8_add(v8_scale(n0, b0), v8_scale(n1, hit_b1)), v8_scale(n2, hit_b2));
    int8 has_normals = v8_dot(n0, n0) > 0.0f && v8_dot(n1, n1) > 0.0f && v8_dot(n2, n2) > 0.0f;
    float8 ns_len = v8_length(ns_sum);
    n0 = v8_select(ng, v8_div(ns_sum, ns_len), has_normals && ns_len > 0.0f);
    p0 = n0;  // the shading normal, below as ns
  }
  V8 ns = p0;
  __global const float* mf = (__global const float*)materials;
  const uint mstride = sizeof(WtMaterial) / sizeof(float);
  V8 base = v8(gather_f(mf, material, mstride, 0u), gather_f(mf, material, mstride, 1u), gather_f(mf, material, mstride, 2u));
  V8 le = v8(gather_f(mf, material, mstride, 4u), gather_f(mf, material, mstride, 5u), gather_f(mf, material, mstride, 6u));
  float8 le_both = gather_f(mf, material, mstride, 7u);
  int8 inside = v8_dot(ng, dir) > 0.0f;
  int8 active = valid && !miss && v8_dot(ng, ng) != 0.0f;

  // misses and emitters' hits, lane by lane (shade.cl's code)
  int8 emits = active && (le_both != 0.0f || !inside) && v8_positive(le);
  int8 lit = valid && (miss || emits);
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

  V8 wo = v8_neg(dir);
  ng = v8_select(ng, v8_neg(ng), v8_dot(ng, wo) < 0.0f);
  ns = v8_select(ns, v8_neg(ns), v8_dot(ns, ng) < 0.0f);
  ns = v8_select(ns, ng, v8_dot(ns, wo) <= 0.0f);
  V8 frame_t, frame_b;
  frame_from_normal8(ns, &frame_t, &frame_b);
  float8 wo_z = v8_dot(wo, ns);
  // a Lambertian surface scatters by its diffuse lobe alone: past its limit
  // neither light sampling nor the BSDF finds anything (shade.cl's lobes)
  int8 diffuse = gather_count8(bounce_counts, path, 0u) < frame.max_diffuse_bounces;
#if WT_HAS_PBR
  // a metallic-roughness one by the lobes shade.cl allows its path
  int8 pbr = active && gather_u((__global const uint*)mf, material, mstride,
                                __builtin_offsetof(WtMaterial, model) / sizeof(float)) == WT_MATERIAL_PBR;
  uint8 lobes = (as_uint8(diffuse) & WT_LOBE_DIFFUSE) |
                (as_uint8(gather_count8(bounce_counts, path, 1u) < frame.max_specular_bounces) & WT_LOBE_SPECULAR) |
                (as_uint8(gather_count8(bounce_counts, path, 2u) < frame.max_transmission_bounces) & WT_LOBE_TRANSMISSION);
  int8 specular = (lobes & WT_LOBE_SPECULAR) != 0u;
  active = active && (diffuse || (pbr && specular));
  V8 wo_local = v8(v8_dot(wo, frame_t), v8_dot(wo, frame_b), wo_z);
  Pbr8 mat;
  if (any(pbr)) mat = pbr_make8(materials, pbr_table, material, base, wo_z, diffuse, specular);
#else
  active = active && diffuse;
#endif
  if (!any(active)) return;
  V8 origin = ray_offset_origin8(p, p_error, ng);
  float8 u_pick, u_rr, u_lobe, u_tree;
  sampler_get2_8(frame, path, WT_DIM_LIGHT_PICK, &u_pick, &u_rr);
  sampler_get2_8(frame, path, WT_DIM_BSDF_LOBE, &u_lobe, &u_tree);

  // next-event estimation
  uint nee_count = (frame.flags & WT_FLAG_NEE) ? frame.light_count : 0u;
  if (nee_count > 0u) {
    // light_pick
    __global const float* af = (__global const float*)alias;
    float8 scaled_u = u_pick * (float)nee_count;
    uint8 slot = min(convert_uint8(scaled_u), nee_count - 1u);
    float8 remainder = scaled_u - convert_float8(slot);
    uint8 index = select(as_uint8(gather_f(af, slot, 4u, 1u)), slot, remainder < gather_f(af, slot, 4u, 0u));
    float8 pmf = gather_f(af, index, 4u, 2u);
    __global const float* lrow = (__global const float*)lights;
    uint8 type = as_uint8(gather_f(lrow, index, 16u, 12u));
    int8 tree = active && type == WT_LIGHT_TREE;
    if (any(tree)) {
      float8 pmf_tree;
      uint8 picked = light_tree_pick8(light_tree, origin, ng, u_tree, tree, &pmf_tree);
      pmf = select(pmf, pmf * pmf_tree, tree);
      // an emitter nothing reaches: pmf 0, and a valid row to read
      index = select(index, select(picked, (uint8)(0u), picked == WT_NO_HIT), tree);
      type = as_uint8(gather_f(lrow, index, 16u, 12u));
    }
    float8 u1, u2;
    sampler_get2_8(frame, path, WT_DIM_LIGHT_U, &u1, &u2);
    LightSample8 s;
    s.ok = (int8)(0);
    s.wi = s.target = s.radiance = v8_splat((float3)(0.0f));
    s.distance = s.pdf = 0.0f;
    s.is_delta = (int8)(0);
    s.prim = (uint8)(WT_NO_HIT);
    int8 want = active && pmf > 0.0f;
    int8 tri_lights = want && type == WT_LIGHT_TRIANGLE;
    if (any(tri_lights)) light_sample_triangle8(lrow, tri_verts, index, tri_lights, p, u1, u2, &s);
    int8 others = want && !tri_lights;
#if WT_HAS_QUAD_LIGHTS
    int8 quads = want && type == WT_LIGHT_QUAD;
    if (any(quads)) light_sample_quad8(lrow, tri_verts, index, quads, p, u1, u2, &s);
    others = others && !quads;
#endif
    if (any(others)) {
      // point, spot, directional lights and the environment: light_sample, lane by lane
      float wx[8], wy[8], wz[8], tx[8], ty[8], tz[8], rx[8], ry[8], rz[8], di[8], pd[8];
      int ok[8], dl[8];
      uint pr[8];
      vstore8(s.wi.x, 0, wx), vstore8(s.wi.y, 0, wy), vstore8(s.wi.z, 0, wz);
      vstore8(s.target.x, 0, tx), vstore8(s.target.y, 0, ty), vstore8(s.target.z, 0, tz);
      vstore8(s.radiance.x, 0, rx), vstore8(s.radiance.y, 0, ry), vstore8(s.radiance.z, 0, rz);
      vstore8(s.distance, 0, di), vstore8(s.pdf, 0, pd), vstore8(s.ok, 0, ok), vstore8(s.is_delta, 0, dl);
      vstore8(s.prim, 0, pr);
      for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k) {
        if (!lane_i(others, k)) continue;
        LightSample one;
        ok[k] = light_sample(ls, lane_u(index, k), lane_v(p, k), lane_f(u1, k), lane_f(u2, k), &one) ? -1 : 0;
        wx[k] = one.wi.x, wy[k] = one.wi.y, wz[k] = one.wi.z;
        tx[k] = one.target.x, ty[k] = one.target.y, tz[k] = one.target.z;
        rx[k] = one.radiance.x, ry[k] = one.radiance.y, rz[k] = one.radiance.z;
        di[k] = one.distance, pd[k] = one.pdf, dl[k] = one.is_delta, pr[k] = one.prim;
      }
      s.wi = v8(vload8(0, wx), vload8(0, wy), vload8(0, wz));
      s.target = v8(vload8(0, tx), vload8(0, ty), vload8(0, tz));
      s.radiance = v8(vload8(0, rx), vload8(0, ry), vload8(0, rz));
      s.distance = vload8(0, di), s.pdf = vload8(0, pd), s.ok = vload8(0, ok), s.is_delta = vload8(0, dl);
      s.prim = vload8(0, pr);
    }
    // the Lambertian BSDF (bsdf_eval)
    int8 connect = want && s.ok && v8_dot(ng, s.wi) > 0.0f;
    float8 wi_z = v8_dot(s.wi, ns);
    int8 eval_ok = connect && diffuse && wo_z > 0.0f && wi_z > 0.0f;
    float8 pdf_bsdf = select((float8)(0.0f), wi_z / WT_PI, eval_ok);
    V8 f_cos = v8_select(v8_splat((float3)(0.0f)), v8_scale(base, wi_z / WT_PI), eval_ok);
#if WT_HAS_PBR
    int8 pbr_connect = connect && pbr;
    if (any(pbr_connect)) {
      float8 pdf_pbr;
      V8 f_pbr = pbr_eval8(mat, wo_local, v8(v8_dot(s.wi, frame_t), v8_dot(s.wi, frame_b), wi_z), diffuse, specular,
                           pbr_table, &pdf_pbr);
      f_cos = v8_select(f_cos, f_pbr, pbr_connect);
      pdf_bsdf = select(pdf_bsdf, pdf_pbr, pbr_connect);
    }
#endif
    float8 pdf_light = s.pdf * pmf;
    float8 a = pdf_light, b = pdf_bsdf;
    if (frame.flags & WT_FLAG_POWER_HEURISTIC) a *= a, b *= b;
    float8 mis = select((float8)(0.0f), a / (a + b), a + b > 0.0f);
    float8 w = select(mis, (float8)(1.0f), s.is_delta != 0 || (int8)(!(frame.flags & WT_FLAG_MIS) ? -1 : 0));
    V8 contribution = v8_scale(v8_mul(v8_mul(beta, f_cos), s.radiance), w / pdf_light);
    int8 carries = v8_positive(f_cos);
    if (frame.flags & WT_FLAG_CHECK_NONFINITE)
      for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k)
        if (lane_i(carries, k))
          shade_check_finite(frame, counters, lane_u(path, k), lane_v(contribution, k), WT_NONFINITE_LIGHT);
    // the shadow ray from the offset origin at the target, a margin short of it
    int8 finite_light = !isinf(s.distance);
    V8 to_target = v8_sub(s.target, origin);
    float8 target_len = v8_length(to_target);
    V8 shadow_dir = v8_select(s.wi, v8_div(to_target, target_len), finite_light);
    float8 tmax = select((float8)(INFINITY), target_len * (1.0f - WT_SHADOW_MARGIN), finite_light);
    int8 queued = carries && v8_positive(contribution) && tmax > 0.0f;
    if (any(queued)) {
      #pragma unroll
      for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k) {
        if (!lane_i(queued, k)) continue;
        uint pk = lane_u(path, k);
        shadow_queue[compact_shadows ? atomic_inc(&counters[WT_COUNTER_SHADOW]) : first + k] = pk;
        shadow_o[pk] = (float4)(lane_v(origin, k), 0.0f);
        shadow_d[pk] = (float4)(lane_v(shadow_dir, k), lane_f(tmax, k));
        shadow_radiance[pk] = (float4)(lane_v(contribution, k), 0.0f);
        shadow_skip[pk] = (uint2)(lane_u(prim, k), lane_u(s.prim, k));
      }
    }
  }

  // the next direction: the cosine lobe (bsdf_sample's diffuse technique)
  float8 u_b1, u_b2;
  sampler_get2_8(frame, path, WT_DIM_BSDF_U, &u_b1, &u_b2);
  float8 cos_phi;
  float8 sin_phi = wt_sincospi8(2.0f * u_b2, &cos_phi);
  float8 r = sqrt(u_b1);
  V8 wl = v8(r * cos_phi, r * sin_phi, sqrt(fmax(0.0f, 1.0f - u_b1)));
  float8 pdf = wl.z / WT_PI;
  V8 f_cos = v8_scale(base, wl.z / WT_PI);
  int8 go = active && diffuse && wo_z > 0.0f && wl.z > 0.0f && pdf > 0.0f && v8_positive(f_cos);
  V8 weight = v8_div(f_cos, pdf);
#if WT_HAS_PBR
  // or the metallic-roughness BSDF's techniques
  uint8 lobe = (uint8)(WT_LOBE_DIFFUSE);
  int8 pbr_go = active && pbr;
  if (any(pbr_go)) {
    // bsdf_sample: the GGX lobe (or its mirror) or the cosine lobe by u_lobe
    int8 glossy = u_lobe < mat.t_specular;
    int8 delta = glossy && mat.mirror;
    V8 h = ggx_sample_visible_normal8(wo_local, mat.alpha, u_b1, u_b2);
    V8 reflected = v8_sub(v8_scale(h, 2.0f * v8_dot(wo_local, h)), wo_local);
    V8 w = v8_select(wl, v8_select(reflected, v8(-wo_local.x, -wo_local.y, wo_local.z), delta), glossy);
    float8 pdf_pbr;
    V8 f_pbr = pbr_eval8(mat, wo_local, w, diffuse, specular, pbr_table, &pdf_pbr);
    int8 ok = pbr_go && wo_z > 0.0f && w.z > 0.0f && (glossy || (diffuse && mat.t_diffuse > 0.0f)) && pdf_pbr > 0.0f &&
              v8_positive(f_pbr);
    // the mirror: F at mu_o over the probability of its technique (pbr_mirror)
    float8 m5 = ggx_schlick_m5_8(wo_local.z);
    float8 opaque = 1.0f - mat.metallic;
    float8 fd = WT_PBR_DIELECTRIC_F0 + (1.0f - WT_PBR_DIELECTRIC_F0) * m5;
    V8 f_mirror = v8(mat.metallic * (mat.base.x + (1.0f - mat.base.x) * m5) + opaque * fd,
                     mat.metallic * (mat.base.y + (1.0f - mat.base.y) * m5) + opaque * fd,
                     mat.metallic * (mat.base.z + (1.0f - mat.base.z) * m5) + opaque * fd);
    int8 ok_delta = pbr_go && wo_z > 0.0f && mat.t_specular > 0.0f && w.z > 0.0f && v8_positive(f_mirror);
    wl = v8_select(wl, w, pbr);
    weight = v8_select(weight, v8_select(v8_div(f_pbr, pdf_pbr), v8_div(f_mirror, mat.t_specular), delta), pbr);
    pdf = select(pdf, select(pdf_pbr, (float8)(0.0f), delta), pbr);
    lobe = select(lobe, select((uint8)(WT_LOBE_DIFFUSE), (uint8)(WT_LOBE_SPECULAR), glossy), pbr);
    go = select(go, select(ok, ok_delta, delta), pbr);
  }
#endif
  V8 wi = v8_add(v8_add(v8_scale(frame_t, wl.x), v8_scale(frame_b, wl.y)), v8_scale(ns, wl.z));
  go = go && v8_dot(wi, ng) > 0.0f;
  beta = v8_mul(beta, weight);
  if ((frame.flags & WT_FLAG_RR) && frame.bounce >= frame.rr_min_depth) {
    float8 q = fmin(fmax(beta.x, fmax(beta.y, beta.z)), 0.95f);
    go = go && u_rr < q;
    beta = v8_div(beta, q);
  }
  if (frame.flags & WT_FLAG_CHECK_NONFINITE)
    for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k)
      if (lane_i(go, k)) shade_check_finite(frame, counters, lane_u(path, k), lane_v(beta, k), WT_NONFINITE_THROUGHPUT);
  go = go && !(beta.x <= 0.0f && beta.y <= 0.0f && beta.z <= 0.0f);
  if (!any(go)) return;
  scatter_v(throughput, path, go, beta, pdf);
  scatter_v(prev_normal, path, go, ng, (float8)(0.0f));
  scatter_v(ray_o, path, go, origin, (float8)(0.0f));
  scatter_v(ray_d, path, go, wi, (float8)(INFINITY));
  uint survivors = 0u;
  #pragma unroll
  for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k) {
    if (!lane_i(go, k)) continue;
    uint pk = lane_u(path, k);
    ushort4 counts = bounce_counts[pk];
#if WT_HAS_PBR
    if (lane_u(lobe, k) & WT_LOBE_DIFFUSE) counts.x++;
    else counts.y++;
#else
    counts.x++;
#endif
    bounce_counts[pk] = counts;
    ray_skip[pk] = lane_u(prim, k);
    ++survivors;
  }
  uint slot = atomic_add(&counters[out_slot], survivors);
  #pragma unroll
  for (int k = 0; k < WT_SHADE_LANES_WIDTH; ++k)
    if (lane_i(go, k)) queue_out[slot++] = lane_u(path, k);
}
