// Counter-based random numbers: a pure function of (pixel, sample, bounce,
// dimension, seed), so the image never depends on scheduling or device
// count. Shared by host (tests) and kernels.
//
// Dimensions are named in shared/dims.h (WT_DIM_*), one per use; a new use
// takes the next free one there. Stochastic transparency
// (kernels/materials/alpha.cl) keys its numbers by WT_DIM_ALPHA_EXTEND and
// WT_DIM_ALPHA_SHADOW: one per (ray, triangle), which the sampler's fixed
// dimensions cannot give.
#ifndef WT_SHARED_RNG_H
#define WT_SHARED_RNG_H

#include "shared/dims.h"
#include "shared/types.h"

#ifdef __OPENCL_C_VERSION__
#define WT_INLINE inline
#else
#define WT_INLINE static inline
#endif

// PCG-style integer hash (Jarzynski and Olano 2020, "pcg" variant).
WT_INLINE wt_uint rng_hash(wt_uint x) {
  wt_uint state = x * 747796405u + 2891336453u;
  wt_uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

// Uniform float in [0,1): 24 random bits, so 1.0 is never returned.
WT_INLINE float rng_uniform(wt_uint pixel, wt_uint sample, wt_uint bounce, wt_uint dim,
                            wt_uint seed) {
  wt_uint h = rng_hash(seed ^ rng_hash(pixel ^ rng_hash(sample ^ rng_hash((bounce << 8u) + dim))));
  return (float)(h >> 8u) * (1.0f / 16777216.0f);
}

/// Stochastic transparency's numbers (kernels/materials/alpha.cl): a key per
/// launch (the host computes it: sample, bounce, stage dimension, seed), a
/// stream per ray of the launch, and one uniform per triangle the ray meets
/// (the stage dimensions: WT_DIM_ALPHA_EXTEND and WT_DIM_ALPHA_SHADOW, shared/dims.h).
WT_INLINE wt_uint rng_alpha_key(wt_uint sample, wt_uint bounce, wt_uint dim, wt_uint seed) {
  return rng_hash(seed ^ rng_hash(sample ^ rng_hash((bounce << 8u) + dim)));
}
WT_INLINE wt_uint rng_alpha_ray(wt_uint key, wt_uint ray) { return rng_hash(key ^ rng_hash(ray)); }
/// The stream of a ray inside instance `instance` (a typed id): each copy of
/// a geometry stored once draws its own numbers for its triangles.
WT_INLINE wt_uint rng_alpha_instance(wt_uint ray_stream, wt_uint instance) {
  return rng_hash(ray_stream ^ rng_hash(instance + 0x7f4a7c15u));
}
WT_INLINE float rng_alpha_uniform(wt_uint ray_stream, wt_uint prim) {
  return (float)(rng_hash(ray_stream ^ rng_hash(prim + 0x9e3779b9u)) >> 8u) * (1.0f / 16777216.0f);
}

#endif  // WT_SHARED_RNG_H
