// The sampler every stage draws from: independent hashes or Owen-scrambled
// Sobol (WT_FLAG_SOBOL), keyed by (pixel, sample, bounce, dimension, seed).
#ifndef WT_SAMPLER_CL
#define WT_SAMPLER_CL

#include "common.h"
#include "shared/dims.h"
#include "shared/sampler.h"

inline float sampler_get(WtFrameParams frame, uint pixel, uint dim) {
  return (frame.flags & WT_FLAG_SOBOL)
             ? sampler_sobol(pixel, frame.sample, frame.bounce, dim, frame.seed)
             : rng_uniform(pixel, frame.sample, frame.bounce, dim, frame.seed);
}

// the pairs generate and shade draw with sampler_get2: an even dimension and the next
#if (WT_DIM_PIXEL_X & 1u) || WT_DIM_PIXEL_Y != WT_DIM_PIXEL_X + 1u || (WT_DIM_BSDF_U & 1u) || \
    WT_DIM_BSDF_V != WT_DIM_BSDF_U + 1u || (WT_DIM_LIGHT_U & 1u) || WT_DIM_LIGHT_V != WT_DIM_LIGHT_U + 1u || \
    (WT_DIM_LIGHT_PICK & 1u) || WT_DIM_RUSSIAN_ROULETTE != WT_DIM_LIGHT_PICK + 1u || (WT_DIM_BSDF_LOBE & 1u) || \
    WT_DIM_LIGHT_TREE != WT_DIM_BSDF_LOBE + 1u
#error "shared/dims.h: the dimensions drawn in pairs must be (even, even + 1)"
#endif

/// Dimensions dim and dim + 1 (dim even) at once, bit for bit
/// (sampler_get(dim), sampler_get(dim + 1)): a Sobol pair shares its
/// scrambled index (sampler_sobol's steps, once). Always inlined: PoCL
/// otherwise calls it with a copy of the frame parameters, which made the
/// pair dearer than two single values (docs/lab/2026-12-05-shade-speed.md).
inline __attribute__((always_inline)) float2 sampler_get2(WtFrameParams frame, uint pixel, uint dim) {
  if (frame.flags & WT_FLAG_SOBOL) {
    uint group_seed = rng_hash(frame.seed ^ rng_hash(pixel ^ rng_hash((frame.bounce << 8u) + (dim >> 1u) + 0x9e3779b9u)));
    uint index = sampler_owen_scramble(frame.sample, group_seed);
    uint2 v = (uint2)(sampler_reverse_bits(sampler_lk_permute(index, rng_hash(group_seed + 1u))),
                      sampler_reverse_bits(sampler_lk_permute(sampler_sobol_pascal(index), rng_hash(group_seed + 2u))));
    return convert_float2(v >> 8u) * (1.0f / 16777216.0f);
  }
  return (float2)(rng_uniform(pixel, frame.sample, frame.bounce, dim, frame.seed),
                  rng_uniform(pixel, frame.sample, frame.bounce, dim + 1u, frame.seed));
}

#endif  // WT_SAMPLER_CL
