// Owen-scrambled Sobol points (Burley 2020, "Practical hash-based Owen
// scrambling"), padded in pairs: every pair of dimensions (2k, 2k+1) of a
// bounce is the first two Sobol dimensions -- a (0,2)-sequence, so each pair
// is stratified in 2D -- with its sample index shuffled and its values
// scrambled by hashes of (pixel, bounce, pair, seed). Same arguments as
// rng_uniform, so the two samplers are interchangeable. Shared by host
// (tests) and kernels.
#ifndef WT_SHARED_SAMPLER_H
#define WT_SHARED_SAMPLER_H

#include "shared/rng.h"

#if defined(WT_AVOID_BITREVERSE) && WT_AVOID_BITREVERSE
// Oclgrind cannot run llvm.bitreverse, which the compiler makes of the
// shift-and-mask form below: reverse one bit at a time instead.
WT_INLINE wt_uint sampler_reverse_bits(wt_uint x) {
  wt_uint r = 0u;
  for (int i = 0; i < 32; ++i) {
    r = (r << 1u) | (x & 1u);
    x >>= 1u;
  }
  return r;
}
#else
WT_INLINE wt_uint sampler_reverse_bits(wt_uint x) {
  x = ((x >> 1u) & 0x55555555u) | ((x & 0x55555555u) << 1u);
  x = ((x >> 2u) & 0x33333333u) | ((x & 0x33333333u) << 2u);
  x = ((x >> 4u) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4u);
  x = ((x >> 8u) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8u);
  return (x >> 16u) | (x << 16u);
}
#endif

// A hash in which each bit depends only on itself and the bits below it
// (Laine-Karras style, Burley's constants): applied to bit-reversed values it
// is an Owen scramble.
WT_INLINE wt_uint sampler_lk_permute(wt_uint x, wt_uint seed) {
  x ^= x * 0x3d20adeau;
  x += seed;
  x *= (seed >> 16u) | 1u;
  x ^= x * 0x05526c56u;
  x ^= x * 0x53a22864u;
  return x;
}

WT_INLINE wt_uint sampler_owen_scramble(wt_uint x, wt_uint seed) {
  return sampler_reverse_bits(sampler_lk_permute(sampler_reverse_bits(x), seed));
}

/// The first two Sobol dimensions of point `index`, as 32 fraction bits:
/// dimension 0 is the bit-reversed index (van der Corput); dimension 1 has
/// direction numbers v_(i+1) = v_i ^ (v_i >> 1) (primitive polynomial x+1).
/// The direction-number loop; the samplers use sampler_sobol_pascal below,
/// which tests hold to this definition bit for bit.
WT_INLINE wt_uint sampler_sobol_bits(wt_uint index, wt_uint d) {
  if (d == 0u) return sampler_reverse_bits(index);
  wt_uint v = 0x80000000u, result = 0u;
  for (wt_uint bit = 0u; bit < 32u; ++bit) {
    result ^= (0u - ((index >> bit) & 1u)) & v;
    v ^= v >> 1u;
  }
  return result;
}

/// Dimension 1 bit-reversed: sampler_reverse_bits(sampler_sobol_bits(index, 1)).
/// Counting bit positions of the result from the top, v_i is (1 + y)^i, so
/// the result is the index's polynomial a(y) at y + 1: a Taylor shift over
/// GF(2), in five steps of "each block's low half ^= its high half" instead
/// of 32 iterations.
WT_INLINE wt_uint sampler_sobol_pascal(wt_uint index) {
  index ^= (index >> 1u) & 0x55555555u;
  index ^= (index >> 2u) & 0x33333333u;
  index ^= (index >> 4u) & 0x0f0f0f0fu;
  index ^= (index >> 8u) & 0x00ff00ffu;
  index ^= (index >> 16u) & 0x0000ffffu;
  return index;
}

/// Owen-scrambled Sobol value in [0,1) for the same key as rng_uniform.
WT_INLINE float sampler_sobol(wt_uint pixel, wt_uint sample, wt_uint bounce, wt_uint dim, wt_uint seed) {
  wt_uint group_seed = rng_hash(seed ^ rng_hash(pixel ^ rng_hash((bounce << 8u) + (dim >> 1u) + 0x9e3779b9u)));
  wt_uint index = sampler_owen_scramble(sample, group_seed);
  wt_uint d = dim & 1u;
  // sampler_owen_scramble of the Sobol point, its two bit reversals cancelled
  wt_uint point = d == 0u ? index : sampler_sobol_pascal(index);
  wt_uint v = sampler_reverse_bits(sampler_lk_permute(point, rng_hash(group_seed + d + 1u)));
  return (float)(v >> 8u) * (1.0f / 16777216.0f);
}

#endif  // WT_SHARED_SAMPLER_H
