// The sampler's dimensions: every number a stage draws is keyed by (pixel,
// sample, bounce, dimension, seed), and each use has its own dimension here,
// for host and kernels alike. The Sobol sampler stratifies pairs (2k, 2k+1)
// together (shared/sampler.h), so the two halves of a 2D sample share a pair.
// tests/contract/test_sampler_dims.cpp checks that the values are distinct and
// that no kernel passes a literal dimension.
#ifndef WT_SHARED_DIMS_H
#define WT_SHARED_DIMS_H

#define WT_DIM_PIXEL_X 0u          ///< generate: jitter within the pixel, x
#define WT_DIM_PIXEL_Y 1u          ///< generate: jitter within the pixel, y
#define WT_DIM_BSDF_U 2u           ///< shade: the BSDF sample's direction, first uniform
#define WT_DIM_BSDF_V 3u           ///< shade: the BSDF sample's direction, second uniform
#define WT_DIM_LIGHT_U 4u          ///< shade: the point on the picked light, first uniform
#define WT_DIM_LIGHT_V 5u          ///< shade: the point on the picked light, second uniform
#define WT_DIM_LIGHT_PICK 6u       ///< shade: which light NEE samples
#define WT_DIM_RUSSIAN_ROULETTE 7u ///< shade: whether the path survives
#define WT_DIM_BSDF_LOBE 8u        ///< shade: which lobe the BSDF samples
#define WT_DIM_LIGHT_TREE 9u       ///< shade: which emitter the light tree picks
#define WT_DIM_ALPHA_EXTEND 10u    ///< extend: stochastic transparency's launch key (rng_alpha_key)
#define WT_DIM_ALPHA_SHADOW 11u    ///< connect: the same for shadow rays
#define WT_DIM_WAVELENGTH 12u      ///< shade: the channel a path carries alone past a dispersive interface (shared/media.h)
#define WT_DIM_COUNT 13u           ///< dimensions in use per bounce (a bounce's dimensions are below 256)

#endif  // WT_SHARED_DIMS_H
