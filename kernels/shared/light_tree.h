// The light tree's importance of a node at a shading point, shared by host
// (tests) and kernels (kernels/lights/light_tree.cl): Conty Estevez and
// Kulla 2018's bound on what the node's emitters can contribute, power x
// the largest receiver cosine x the largest emitter cosine / distance^2,
// where the cosines are widened by the angle the node's bounding sphere
// subtends. Zero only where no emitter below can send light onto the
// receiver's side of its plane.
#ifndef WT_SHARED_LIGHT_TREE_H
#define WT_SHARED_LIGHT_TREE_H

#include "shared/lights.h"

#ifdef __OPENCL_C_VERSION__
#define WT_LT_INLINE inline
#define WT_LT_GLOBAL __global
#else
#include <cmath>
#define WT_LT_INLINE static inline
#define WT_LT_GLOBAL
#endif

/// cos(max(0, a - b)) from the cosines and sines of angles a in [0, pi] and b in [0, pi/2].
WT_LT_INLINE float light_tree_cos_minus(float cos_a, float cos_b, float sin_b) {
  if (cos_a >= cos_b) return 1.0f;
  float sin_a = sqrt(fmax(0.0f, 1.0f - cos_a * cos_a));
  return cos_a * cos_b + sin_a * sin_b;
}

/// Importance of `node` at point p with unit normal n (the receiver's
/// geometric normal on the side light is gathered from). The node stores
/// its sphere's radius and its cone's sine, so that the sines of the sphere's
/// half-angle (r / d) and of the cone's need no square root: four where the
/// cone counts, against seven from the cosines alone.
WT_LT_INLINE float light_tree_importance(WT_LT_GLOBAL const WtLightNode* node, float px, float py, float pz,
                                         float nx, float ny, float nz) {
  if (!(node->power > 0.0f)) return 0.0f;
  float ex = node->hi_x - node->lo_x, ey = node->hi_y - node->lo_y, ez = node->hi_z - node->lo_z;
  float r2 = 0.25f * (ex * ex + ey * ey + ez * ez);
  float tx = 0.5f * (node->lo_x + node->hi_x) - px, ty = 0.5f * (node->lo_y + node->hi_y) - py,
        tz = 0.5f * (node->lo_z + node->hi_z) - pz;
  float d2 = tx * tx + ty * ty + tz * tz;
  // within the bounding sphere light may come from anywhere
  if (d2 <= r2) return node->power / fmax(r2, 1e-30f);
  float inv_d = 1.0f / sqrt(d2), inv_d2 = inv_d * inv_d;
  float wx = tx * inv_d, wy = ty * inv_d, wz = tz * inv_d;
  float sin_u2 = r2 * inv_d2;
  float cos_u = sqrt(fmax(0.0f, 1.0f - sin_u2)), sin_u = fmin(node->radius * inv_d, 1.0f);
  // receiver: the smallest angle to its normal any point of the sphere has
  // (a zero normal: a receiver lit from both sides, which bounds nothing)
  float cos_i = (nx == 0.0f && ny == 0.0f && nz == 0.0f) ? 1.0f
                                                         : light_tree_cos_minus(nx * wx + ny * wy + nz * wz, cos_u, sin_u);
  if (!(cos_i > 0.0f)) return 0.0f;
  // emitter: the smallest angle between -w and a normal in the cone, widened
  // by the sphere; Lambertian emitters send nothing beyond pi/2 of it
  float cos_e = 1.0f;
  float cos_o = node->cos_theta_o;
  if (cos_o > -cos_u) {  // theta_o + theta_u < pi: the cone does not cover every direction
    float sin_o = node->sin_theta_o;
    float cos_ou = cos_o * cos_u - sin_o * sin_u;  // cos(theta_o + theta_u)
    float cos_theta = -(node->axis_x * wx + node->axis_y * wy + node->axis_z * wz);
    if (cos_theta < cos_ou) {
      float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
      float sin_ou = sin_o * cos_u + cos_o * sin_u;
      cos_e = cos_theta * cos_ou + sin_theta * sin_ou;  // cos(theta - theta_o - theta_u)
      if (!(cos_e > 0.0f)) return 0.0f;
    }
  }
  return node->power * cos_i * cos_e * inv_d2;
}

#endif  // WT_SHARED_LIGHT_TREE_H
