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

#ifdef __OPENCL_C_VERSION__
#define WT_CONSTANT __constant
#else
#define WT_CONSTANT static const
#endif

// Direction numbers of Sobol dimensions 1-4 (van der Corput, then Joe and
// Kuo's primitive polynomials x+1, x^2+x+1, x^3+x+1), most significant bit first.
WT_CONSTANT wt_uint kSobolDirections[4][32] = {
    {0x80000000u, 0x40000000u, 0x20000000u, 0x10000000u, 0x08000000u, 0x04000000u, 0x02000000u, 0x01000000u,
     0x00800000u, 0x00400000u, 0x00200000u, 0x00100000u, 0x00080000u, 0x00040000u, 0x00020000u, 0x00010000u,
     0x00008000u, 0x00004000u, 0x00002000u, 0x00001000u, 0x00000800u, 0x00000400u, 0x00000200u, 0x00000100u,
     0x00000080u, 0x00000040u, 0x00000020u, 0x00000010u, 0x00000008u, 0x00000004u, 0x00000002u, 0x00000001u},
    {0x80000000u, 0xc0000000u, 0xa0000000u, 0xf0000000u, 0x88000000u, 0xcc000000u, 0xaa000000u, 0xff000000u,
     0x80800000u, 0xc0c00000u, 0xa0a00000u, 0xf0f00000u, 0x88880000u, 0xcccc0000u, 0xaaaa0000u, 0xffff0000u,
     0x80008000u, 0xc000c000u, 0xa000a000u, 0xf000f000u, 0x88008800u, 0xcc00cc00u, 0xaa00aa00u, 0xff00ff00u,
     0x80808080u, 0xc0c0c0c0u, 0xa0a0a0a0u, 0xf0f0f0f0u, 0x88888888u, 0xccccccccu, 0xaaaaaaaau, 0xffffffffu},
    {0x80000000u, 0xc0000000u, 0x60000000u, 0x90000000u, 0xe8000000u, 0x5c000000u, 0x8e000000u, 0xc5000000u,
     0x68800000u, 0x9cc00000u, 0xee600000u, 0x55900000u, 0x80680000u, 0xc09c0000u, 0x60ee0000u, 0x90550000u,
     0xe8808000u, 0x5cc0c000u, 0x8e606000u, 0xc5909000u, 0x6868e800u, 0x9c9c5c00u, 0xeeee8e00u, 0x5555c500u,
     0x8000e880u, 0xc0005cc0u, 0x60008e60u, 0x9000c590u, 0xe8006868u, 0x5c009c9cu, 0x8e00eeeeu, 0xc5005555u},
    {0x80000000u, 0xc0000000u, 0x20000000u, 0x50000000u, 0xf8000000u, 0x74000000u, 0xa2000000u, 0x93000000u,
     0xd8800000u, 0x25400000u, 0x59e00000u, 0xe6d00000u, 0x78080000u, 0xb40c0000u, 0x82020000u, 0xc3050000u,
     0x208f8000u, 0x51474000u, 0xfbea2000u, 0x75d93000u, 0xa0858800u, 0x914e5400u, 0xdbe79e00u, 0x25db6d00u,
     0x58800080u, 0xe54000c0u, 0x79e00020u, 0xb6d00050u, 0x800800f8u, 0xc00c0074u, 0x200200a2u, 0x50050093u}};

WT_INLINE wt_uint sampler_reverse_bits(wt_uint x) {
  x = ((x >> 1u) & 0x55555555u) | ((x & 0x55555555u) << 1u);
  x = ((x >> 2u) & 0x33333333u) | ((x & 0x33333333u) << 2u);
  x = ((x >> 4u) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4u);
  x = ((x >> 8u) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8u);
  return (x >> 16u) | (x << 16u);
}

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

/// Sobol dimension d (0-3) of point `index`, as 32 fraction bits.
WT_INLINE wt_uint sampler_sobol_bits(wt_uint index, wt_uint d) {
  wt_uint v = 0u;
  for (wt_uint bit = 0u; index != 0u; index >>= 1u, ++bit)
    if (index & 1u) v ^= kSobolDirections[d][bit];
  return v;
}

/// Owen-scrambled Sobol value in [0,1) for the same key as rng_uniform.
WT_INLINE float sampler_sobol(wt_uint pixel, wt_uint sample, wt_uint bounce, wt_uint dim, wt_uint seed) {
  wt_uint group_seed = rng_hash(seed ^ rng_hash(pixel ^ rng_hash((bounce << 8u) + (dim >> 1u) + 0x9e3779b9u)));
  wt_uint index = sampler_owen_scramble(sample, group_seed);
  wt_uint d = dim & 1u;
  wt_uint v = sampler_owen_scramble(sampler_sobol_bits(index, d), rng_hash(group_seed + d + 1u));
  return (float)(v >> 8u) * (1.0f / 16777216.0f);
}

#endif  // WT_SHARED_SAMPLER_H
