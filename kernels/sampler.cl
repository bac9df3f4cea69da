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

#endif  // WT_SAMPLER_CL
