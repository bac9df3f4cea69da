// Next-event estimation: pick a light (alias table by power, or uniformly
// among analytic lights for the minimal integrator), sample a point or
// direction on it, and the pdfs MIS needs for lights hit by BSDF sampling.
#ifndef WT_LIGHTS_LIGHT_SAMPLING_CL
#define WT_LIGHTS_LIGHT_SAMPLING_CL

#include "common.h"
#include "geometry/geometry.cl"
#include "shared/lights.h"
#include "lights/environment_adapter.cl"
#include "materials/textured.cl"

/// The light list as the shading stage sees it.
typedef struct LightScene {
  __global const WtLight* lights;
  __global const WtAliasSlot* alias;
  uint light_count;
  __global const float4* tri_verts;  ///< for triangle lights, leaf order
  EnvScene env;
  GeometryScene geometry;            ///< for emissive primitives of other types
  __global const uint4* tri_info;    ///< for textured triangle lights: vertices and material
  SurfaceScene surface;              ///< their texture coordinates and textures
} LightScene;

#if WT_HAS_ALPHA
/// The share of a holed triangle light (alphaMode MASK or BLEND,
/// light.direction: mode, cutoff, factor, 1 where the base colour texture's
/// alpha counts) that is there at barycentrics (b1, b2): MASK all or
/// nothing by the cutoff, BLEND its coverage (the chance that a ray meets
/// it, which is how BSDF sampling finds it through traversal), with
/// coverage read as the alpha test reads it (materials/alpha.cl). Light
/// sampling keeps its pdf: a point in a hole emits nothing, and a path
/// through the hole never hits the emitter there, so MIS stays consistent.
inline float light_triangle_coverage(LightScene ls, WtLight light, float b1, float b2) {
  float alpha = light.direction.z;
#if WT_HAS_VERTEX_COLORS || WT_HAS_TEXTURES
  uint4 v = ls.tri_info[light.triangle];
  float b0 = 1.0f - b1 - b2;
#endif
#if WT_HAS_VERTEX_COLORS
  alpha *= b0 * ls.surface.color[v.x].w + b1 * ls.surface.color[v.y].w + b2 * ls.surface.color[v.z].w;
#endif
#if WT_HAS_TEXTURES
  if (light.direction.w != 0.0f) {
    SurfacePoint sp;
    sp.uv = b0 * ls.surface.uv[v.x] + b1 * ls.surface.uv[v.y] + b2 * ls.surface.uv[v.z];
    sp.uv_scale = (float2)(0.0f);
    sp.footprint = 0.0f;  // the finest level, as traversal's test
    alpha *= material_texture(ls.surface, v.w, WT_TEXTURE_SLOT_BASE_COLOR, sp).w;
  }
#endif
  if ((uint)light.direction.x == WT_ALPHA_MASK) return alpha >= light.direction.y ? 1.0f : 0.0f;
  return fmin(fmax(alpha, 0.0f), 1.0f);
}
#endif

/// A triangle light's radiance at barycentrics (b1, b2): its emission, times
/// the emissive texture there where its material has one (light.position.y),
/// times its coverage where it may have holes (light.direction.x, an alpha mode).
inline float3 light_triangle_radiance(LightScene ls, WtLight light, float b1, float b2) {
  float3 le = vec4_xyz(light.intensity);
#if WT_HAS_ALPHA
  if (light.direction.x != 0.0f) {
    le *= light_triangle_coverage(ls, light, b1, b2);
    if (!(le.x > 0.0f || le.y > 0.0f || le.z > 0.0f)) return le;
  }
#endif
#if WT_HAS_TEXTURES
  if (light.position.y != 0.0f) {
    uint4 v = ls.tri_info[light.triangle];
    float b0 = 1.0f - b1 - b2;
    SurfacePoint sp;
    sp.uv = b0 * ls.surface.uv[v.x] + b1 * ls.surface.uv[v.y] + b2 * ls.surface.uv[v.z];
    sp.uv_scale = (float2)(0.0f);
    sp.footprint = 0.0f;
    le *= material_texture(ls.surface, v.w, WT_TEXTURE_SLOT_EMISSIVE, sp).xyz;
  }
#endif
  return le;
}

/// A sampled connection from a shading point towards a light.
typedef struct LightSample {
  float3 wi;        ///< unit, world, towards the light
  float distance;   ///< to the sampled point; INFINITY for directional and environment
  float3 target;    ///< where a shadow ray ends (finite distance only): the light's position, or the sampled point pushed off the emitter's surface towards the shading point past its rounding error
  float3 radiance;  ///< arriving radiance, or intensity / distance^2 for delta lights
  float pdf;        ///< solid-angle pdf given this light was picked; 1 for delta lights
  int is_delta;     ///< point, spot, directional: BSDF sampling cannot hit these
  uint prim;        ///< the emitter primitive (its shadow ray skips it): a leaf-order triangle or a typed id; WT_NO_HIT for other lights
} LightSample;

// Spherical-triangle sampling (Arvo 1995) where the triangle subtends at
// least this solid angle: uniform in solid angle removes the 1/d^2 and the
// light's cosine from the estimate, which is what makes nearby lights noisy.
// Below it, area sampling is as good and spherical trigonometry loses precision.
#define WT_SPHERICAL_MIN_SOLID_ANGLE 1e-3f
#define WT_SPHERICAL_MAX_SOLID_ANGLE 6.2f

/// Solid angle of triangle (p0, p1, p2) seen from p (Van Oosterom and
/// Strackee 1983).
inline float light_triangle_solid_angle(float3 p, float3 p0, float3 p1, float3 p2) {
  float3 a = p0 - p, b = p1 - p, c = p2 - p;
  float la = length(a), lb = length(b), lc = length(c);
  float numerator = fabs(dot(a, cross(b, c)));
  float denominator = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
  return fabs(2.0f * wt_atan2(numerator, denominator));
}

inline bool light_use_spherical(float solid_angle) {
  return solid_angle >= WT_SPHERICAL_MIN_SOLID_ANGLE && solid_angle <= WT_SPHERICAL_MAX_SOLID_ANGLE;
}

/// Unit vector of a orthogonalised against unit b.
inline float3 light_orthonormal(float3 a, float3 b) {
  float3 v = a - dot(a, b) * b;
  float l = length(v);
  return l > 0.0f ? v / l : (float3)(0.0f);
}

/// A direction uniform in the solid angle of spherical triangle (A, B, C)
/// (unit vectors from the shading point), of area `solid_angle` (Arvo 1995).
/// The angles enter only through their sines and cosines: the sub-triangle's
/// sin and cos of (area - alpha) come from the angle-difference identities,
/// so one polynomial sincos of the area replaces acos, sin and cos.
inline float3 light_sample_spherical_triangle(float3 A, float3 B, float3 C, float solid_angle,
                                              float u1, float u2) {
  // the angle alpha at A between the great arcs AB and AC
  float3 n_ab = light_orthonormal(B, A), n_ac = light_orthonormal(C, A);
  float cos_alpha = clamp(dot(n_ab, n_ac), -1.0f, 1.0f);
  float sin_alpha = sqrt(fmax(0.0f, 1.0f - cos_alpha * cos_alpha));
  // pick the sub-triangle area, then the point C' on arc AC that bounds it
  // phi = (sampled area + pi) - alpha: s = sin(phi), t = cos(phi)
  float cos_area;
  float sin_area = wt_sincospi(u1 * (solid_angle * (1.0f / WT_PI)), &cos_area);
  float s = cos_area * sin_alpha - sin_area * cos_alpha, t = -(cos_area * cos_alpha + sin_area * sin_alpha);
  float cos_c = dot(A, B);
  float k1 = t + cos_alpha, k2 = s - sin_alpha * cos_c;
  float cos_b = (k2 + (k2 * t - k1 * s) * cos_alpha) / ((k2 * s + k1 * t) * sin_alpha);
  cos_b = clamp(cos_b, -1.0f, 1.0f);
  float3 c_prime = cos_b * A + sqrt(fmax(0.0f, 1.0f - cos_b * cos_b)) * n_ac;
  // then uniformly along the arc from B to C' (in cos z)
  float cos_theta = 1.0f - u2 * (1.0f - dot(c_prime, B));
  float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
  return normalize(cos_theta * B + sin_theta * light_orthonormal(c_prime, B));
}

#if WT_HAS_QUAD_LIGHTS
/// A rectangle light's corner c at its right angle and its edges e1, e2
/// (world), as its row holds them (WtLight): the sampler and the pdf of an
/// emitter hit read the same floats.
inline void light_quad_rect(WtLight light, float3* c, float3* e1, float3* e2) {
  *c = vec4_xyz(light.position);
  *e1 = vec4_xyz(light.direction);
  *e2 = (float3)(light.intensity.w, light.cos_inner, light.cos_outer);
}

/// Rectangle (c, e1, e2) seen from a point in the rectangle's own frame
/// (Urena et al.): the point's offsets to its edges along e1 (x0 < x1) and
/// e2 (y0 < y1), minus its distance from the plane (z0 <= 0), and the
/// distances to the corners (x0, y0) and (x0, y1).
typedef struct RectView {
  float x0, y0, x1, y1, z0;
  float l00, l01;
} RectView;

/// The view of rectangle (c, e1, e2) from p (*v) and its solid angle: its
/// two triangles' by Van Oosterom and Strackee from the frame's coordinates,
/// their two half-angles summed in one atan2 (accurate where it is small,
/// unlike the sum of its four angles less 2 pi).
inline float light_rect_view(float3 p, float3 c, float3 e1, float3 e2, RectView* v) {
  float ex = length(e1), ey = length(e2);
  float3 x = e1 / ex, y = e2 / ey;
  float3 d = c - p;
  float z0 = -fabs(dot(d, normalize(cross(x, y))));
  float x0 = dot(d, x), y0 = dot(d, y), x1 = x0 + ex, y1 = y0 + ey;
  float z2 = z0 * z0;
  float l00 = sqrt(x0 * x0 + y0 * y0 + z2), l10 = sqrt(x1 * x1 + y0 * y0 + z2);
  float l11 = sqrt(x1 * x1 + y1 * y1 + z2), l01 = sqrt(x0 * x0 + y1 * y1 + z2);
  *v = (RectView){x0, y0, x1, y1, z0, l00, l01};
  // triangles (00, 10, 11) and (00, 11, 01): tan(omega / 2) = n / e of unit corner vectors
  float triple = -z0 * ex * ey;
  float d_00_11 = (x0 * x1 + y0 * y1 + z2) / (l00 * l11);
  float n1 = triple / (l00 * l10 * l11), n2 = triple / (l00 * l11 * l01);
  float e_1 = 1.0f + (x0 * x1 + y0 * y0 + z2) / (l00 * l10) + d_00_11 + (x1 * x1 + y0 * y1 + z2) / (l10 * l11);
  float e_2 = 1.0f + d_00_11 + (x0 * x0 + y0 * y1 + z2) / (l00 * l01) + (x0 * x1 + y1 * y1 + z2) / (l11 * l01);
  // each half-angle is in [0, pi] and their sum below pi: one atan2 of the sum
  return 2.0f * wt_atan2(n1 * e_2 + n2 * e_1, e_1 * e_2 - n1 * n2);
}

/// Solid angle of rectangle (c, e1, e2) seen from p.
inline float light_quad_solid_angle(float3 p, float3 c, float3 e1, float3 e2) {
  RectView v;
  return light_rect_view(p, c, e1, e2, &v);
}

/// A point uniform in the solid angle `solid_angle` of a rectangle of view
/// v, as its coordinates (s, t) along e1 and e2 in [0, 1] (Urena, Fajardo
/// and King 2013, "An Area-Preserving Parametrization for Spherical
/// Rectangles"). The angle k of the paper enters only by its cosine and
/// sine, from those of the two angles it is made of, and the sub-rectangle's
/// area by its own, so that no difference of angles near pi loses the area
/// when it is small.
inline float2 light_sample_spherical_rect(RectView v, float solid_angle, float u1, float u2) {
  float x0 = v.x0, y0 = v.y0, x1 = v.x1, y1 = v.y1, z0 = v.z0;
  float z2 = z0 * z0;
  // the angles at the x0 edge, g2 (corner x0, y1) and g3 (x0, y0), by cosine and sine
  float l0 = sqrt(z2 + y0 * y0), l2 = sqrt(z2 + y1 * y1), l3 = sqrt(z2 + x0 * x0);
  float inv23 = 1.0f / (l2 * l3), inv30 = 1.0f / (l3 * l0);
  float cos_g2 = x0 * y1 * inv23, sin_g2 = -z0 * v.l01 * inv23;
  float cos_g3 = -x0 * y0 * inv30, sin_g3 = -z0 * v.l00 * inv30;
  // k = 2 pi - g2 - g3, then au = k + u1 solid_angle
  float cos_k = cos_g2 * cos_g3 - sin_g2 * sin_g3, sin_k = -(sin_g2 * cos_g3 + cos_g2 * sin_g3);
  float cos_a;
  float sin_a = wt_sincospi(u1 * (solid_angle * (1.0f / WT_PI)), &cos_a);
  float cos_au = cos_k * cos_a - sin_k * sin_a, sin_au = sin_k * cos_a + cos_k * sin_a;
  float b0 = -y0 / l0, b1 = y1 / l2;
  // the x of the sub-rectangle's far edge
  float fu = (cos_au * b0 - b1) / sin_au;
  float cu = clamp(copysign(1.0f, fu) * rsqrt(fu * fu + b0 * b0), -1.0f, 1.0f);
  float xu = -(cu * z0) / sqrt(fmax(1.0f - cu * cu, 1e-30f));
  xu = clamp(xu, x0, x1);
  // then y along that edge, uniform in the solid angle's measure there
  float dd = sqrt(xu * xu + z2);
  float h0 = y0 / sqrt(dd * dd + y0 * y0), h1 = y1 / sqrt(dd * dd + y1 * y1);
  float hv = h0 + u2 * (h1 - h0), hv2 = hv * hv;
  float yv = hv2 < 1.0f - 1e-6f ? hv * dd / sqrt(1.0f - hv2) : y1;
  yv = clamp(yv, y0, y1);
  return (float2)(clamp((xu - x0) / (x1 - x0), 0.0f, 1.0f), clamp((yv - y0) / (y1 - y0), 0.0f, 1.0f));
}

// Spherical rectangles only where the rectangle is large for its distance:
// area sampling's variance beyond solid angle sampling's grows with (size /
// distance)^2, the area over the squared distance to the centre, and below
// this ratio it is hardly more while it needs no solid angle at all. Tested
// at run time per shading point, from nothing but the two.
#define WT_QUAD_SPHERICAL_MIN_RATIO 0.25f

/// Whether the rectangle (c, e1, e2) of area `area` is sampled by solid
/// angle from p: a large one for its distance, subtending what
/// light_use_spherical allows (*v, *solid_angle then its view).
inline bool light_quad_spherical(float3 p, float3 c, float3 e1, float3 e2, float area, RectView* v,
                                 float* solid_angle) {
  float3 to_centre = c + 0.5f * (e1 + e2) - p;
  if (!(area >= WT_QUAD_SPHERICAL_MIN_RATIO * dot(to_centre, to_centre))) return false;
  *solid_angle = light_rect_view(p, c, e1, e2, v);
  return light_use_spherical(*solid_angle);
}

/// Sample rectangle (c, e1, e2) from p: by solid angle where
/// light_quad_spherical says so, else uniformly by area; *st the point's
/// coordinates along e1 and e2. Fills wi, distance, target and pdf of *s.
/// False for a point behind a single-sided light's front (e1 x e2).
inline bool light_sample_rect(float3 p, float3 c, float3 e1, float3 e2, bool two_sided, float u1, float u2,
                              LightSample* s, float2* st_out) {
  float3 n = cross(e1, e2);
  float area = length(n);
  if (!(area > 0.0f)) return false;
  n /= area;
  // a single-sided light lights only its front (its first half's winding) side
  float height = dot(n, p - c);
  if (!two_sided && !(height > 0.0f)) return false;
  RectView view;
  float solid_angle = 0.0f;
  bool spherical = light_quad_spherical(p, c, e1, e2, area, &view, &solid_angle);
  float2 st = spherical ? light_sample_spherical_rect(view, solid_angle, u1, u2) : (float2)(u1, u2);
  // the point by its first half's barycentrics (outside it past the diagonal), where its rounding error is known
  float3 q_error;
  float3 q = triangle_point(c, c + e1, c + e2, st.x, st.y, &q_error);
  float3 to_light = q - p;
  float d2 = dot(to_light, to_light);
  if (!(d2 > 0.0f)) return false;
  s->distance = sqrt(d2);
  s->wi = to_light / s->distance;
  float cos_light = fabs(dot(n, s->wi));
  if (!(cos_light > 0.0f)) return false;
  s->target = ray_offset_origin(q, q_error, height > 0.0f ? n : -n);
  s->pdf = spherical ? 1.0f / solid_angle : d2 / (cos_light * area);
  *st_out = st;
  return true;
}

/// Sample rectangle light `light` from p (light_sample_rect).
inline bool light_sample_quad(LightScene ls, WtLight light, float3 p, float u1, float u2, LightSample* s) {
  float3 c, e1, e2;
  light_quad_rect(light, &c, &e1, &e2);
  float2 st;
  if (!light_sample_rect(p, c, e1, e2, light.position.w != 0.0f, u1, u2, s, &st)) return false;
  s->radiance = vec4_xyz(light.intensity);
  // the half the point is on, past the diagonal the second (its shadow ray skips it)
  s->prim = st.x + st.y <= 1.0f ? light.triangle : as_uint(light.direction.w);
  return true;
}
#endif

/// Pick a light with probability proportional to its power.
inline uint light_pick(LightScene ls, float u, float* pmf) {
  float scaled = u * (float)ls.light_count;
  uint slot = min((uint)scaled, ls.light_count - 1u);
  float remainder = scaled - (float)slot;
  uint chosen = remainder < ls.alias[slot].threshold ? slot : ls.alias[slot].alias;
  *pmf = ls.alias[chosen].pmf;
  return chosen;
}

inline float light_spot_falloff(WtLight light, float3 from_light) {
  // glTF's recommended smooth falloff between the outer and inner cones
  float cd = dot(vec4_xyz(light.direction), from_light);
  float t = clamp((cd - light.cos_outer) / fmax(light.cos_inner - light.cos_outer, 1e-4f), 0.0f, 1.0f);
  return t * t;
}

/// Sample light `index` from shading point p. False when nothing arrives.
inline bool light_sample(LightScene ls, uint index, float3 p, float u1, float u2, LightSample* s) {
  WtLight light = ls.lights[index];
  s->is_delta = 1;
  s->pdf = 1.0f;
  s->prim = WT_NO_HIT;
  if (light.type == WT_LIGHT_POINT || light.type == WT_LIGHT_SPOT) {
    float3 to_light = vec4_xyz(light.position) - p;
    float d2 = dot(to_light, to_light);
    if (!(d2 > 0.0f)) return false;
    s->distance = sqrt(d2);
    s->wi = to_light / s->distance;
    s->target = vec4_xyz(light.position);
    s->radiance = vec4_xyz(light.intensity) / d2;
    if (light.type == WT_LIGHT_SPOT) s->radiance *= light_spot_falloff(light, -s->wi);
    return true;
  }
  if (light.type == WT_LIGHT_DIRECTIONAL) {
    s->wi = -vec4_xyz(light.direction);
    s->distance = INFINITY;
    s->radiance = vec4_xyz(light.intensity);
    return true;
  }
  s->is_delta = 0;
  if (light.type == WT_LIGHT_TRIANGLE) {
    uint t = light.triangle;
    s->prim = t;
    float3 p0, p1, p2;
    triangle_corners(ls.tri_verts, t, &p0, &p1, &p2);
    float3 n = cross(p1 - p0, p2 - p0);
    float solid_angle = light_triangle_solid_angle(p, p0, p1, p2);
    if (light_use_spherical(solid_angle)) {
      float3 w = light_sample_spherical_triangle(normalize(p0 - p), normalize(p1 - p), normalize(p2 - p),
                                                 solid_angle, u1, u2);
      // distance to the triangle's plane along w; a single-sided light emits on its n side
      float facing = dot(n, w);
      if (light.position.w == 0.0f && !(facing < 0.0f)) return false;
      float dist = dot(n, p0 - p) / facing;
      if (!(dist > 0.0f) || !isfinite(dist)) return false;
      // the sampled point from its barycentrics (Moller-Trumbore), where its
      // rounding error is known
      float3 e1 = p1 - p0, e2 = p2 - p0, tv = p - p0;
      float3 pv = cross(w, e2), qv = cross(tv, e1);
      float inv_det = 1.0f / dot(e1, pv);
      float b1 = clamp(dot(tv, pv) * inv_det, 0.0f, 1.0f), b2 = clamp(dot(w, qv) * inv_det, 0.0f, 1.0f);
      if (b1 + b2 > 1.0f) {
        float sum = b1 + b2;
        b1 /= sum;
        b2 /= sum;
      }
      if (!isfinite(b1) || !isfinite(b2)) return false;
      float3 q_error;
      float3 q = triangle_point(p0, p1, p2, b1, b2, &q_error);
      s->target = ray_offset_origin(q, q_error, facing < 0.0f ? normalize(n) : -normalize(n));
      s->wi = w;
      s->distance = dist;
      s->pdf = 1.0f / solid_angle;
      s->radiance = light_triangle_radiance(ls, light, b1, b2);
      return true;
    }
    // uniform by area (the square-root parameterisation), converted to solid angle
    float su = sqrt(u1);
    float b1 = su * (1.0f - u2), b2 = su * u2;
    float3 q_error;
    float3 q = triangle_point(p0, p1, p2, b1, b2, &q_error);
    float area2 = length(n);
    float3 to_light = q - p;
    float d2 = dot(to_light, to_light);
    if (!(area2 > 0.0f) || !(d2 > 0.0f)) return false;
    s->distance = sqrt(d2);
    s->wi = to_light / s->distance;
    // a single-sided light only emits from its front (n) side
    float cos_light = -dot(n, s->wi) / area2;
    if (light.position.w != 0.0f) cos_light = fabs(cos_light);
    if (!(cos_light > 0.0f)) return false;
    // off the emitter, on the shading point's side of its plane
    s->target = ray_offset_origin(q, q_error, dot(n, to_light) < 0.0f ? n / area2 : -n / area2);
    s->pdf = (2.0f / area2) * d2 / cos_light;
    s->radiance = light_triangle_radiance(ls, light, b1, b2);
    return true;
  }
#if WT_HAS_QUAD_LIGHTS
  if (light.type == WT_LIGHT_QUAD) return light_sample_quad(ls, light, p, u1, u2, s);
#endif
#if WT_HAS_PRIMITIVES
  if (light.type == WT_LIGHT_PRIMITIVE) {
    s->prim = light.triangle;
    s->radiance = vec4_xyz(light.intensity);
    return geometry_sample_emitter(ls.geometry, light.triangle, p, u1, u2, light.direction.w != 0.0f, &s->wi,
                                   &s->distance, &s->target, &s->pdf);
  }
#endif
  // environment
  s->distance = INFINITY;
  s->radiance = env_sample(ls.env, u1, u2, &s->wi, &s->pdf);
  return s->pdf > 0.0f;
}

/// Solid-angle pdf with which light sampling from `origin` reaches emissive
/// triangle (p0, p1, p2) at `distance` along unit `wi`, as light_sample
/// decides between spherical and area sampling; `pdf_area` is the triangle's
/// selection probability over its area (emitterPdfArea).
inline float light_triangle_pdf(float pdf_area, float3 origin, float3 p0, float3 p1, float3 p2,
                                float distance, float3 wi, float3 n_geometric) {
  if (!(pdf_area > 0.0f)) return 0.0f;
  float solid_angle = light_triangle_solid_angle(origin, p0, p1, p2);
  if (light_use_spherical(solid_angle)) {
    float area = 0.5f * length(cross(p1 - p0, p2 - p0));
    return pdf_area * area / solid_angle;  // the selection probability over the solid angle
  }
  float cos_light = fabs(dot(n_geometric, wi));
  return cos_light > 0.0f ? pdf_area * distance * distance / cos_light : 0.0f;
}

#if WT_HAS_QUAD_LIGHTS
/// light_triangle_pdf for rectangle (c, e1, e2), as light_sample_quad
/// decides between spherical and area sampling; `pdf_area` is the
/// rectangle's selection probability over its area (both halves hold it).
inline float light_quad_pdf(float pdf_area, float3 origin, float3 c, float3 e1, float3 e2, float distance, float3 wi,
                            float3 n_geometric) {
  if (!(pdf_area > 0.0f)) return 0.0f;
  float area = length(cross(e1, e2));
  RectView view;
  float solid_angle = 0.0f;
  if (light_quad_spherical(origin, c, e1, e2, area, &view, &solid_angle)) return pdf_area * area / solid_angle;
  float cos_light = fabs(dot(n_geometric, wi));
  return cos_light > 0.0f ? pdf_area * distance * distance / cos_light : 0.0f;
}
#endif

/// MIS weight of a strategy with pdf `a` against one with pdf `b`.
inline float mis_weight(float a, float b, uint flags) {
  if (flags & WT_FLAG_POWER_HEURISTIC) {
    a *= a;
    b *= b;
  }
  return a + b > 0.0f ? a / (a + b) : 0.0f;
}

#endif  // WT_LIGHTS_LIGHT_SAMPLING_CL
