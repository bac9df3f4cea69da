// The AOV buffers' layout and accumulate's fold of one sample into the sums
// (kernels/aov.cl writes the samples). Reads WT_AOV and no other switch: the
// frame program (frame.cl) includes it.
#ifndef WT_AOV_FOLD_CL
#define WT_AOV_FOLD_CL

// aov_sample: 4 float4 per pixel
//   [0] albedo rgb, w: 1 once found (0 while the path is on a specular chain)
//   [1] normal xyz (world, shading, facing the ray), w: surfaces hit (path length)
//   [2] camera hit's world position xyz, w: its distance along the camera ray (INFINITY: a miss)
//   [3] camera hit's texture coordinates xy (barycentrics without TEXCOORD_0), z: nodes the
//       camera ray visited (WT_BVH_COST, written by extend; else 0), w: 1 if the camera ray hit
// aov_accum: the same four summed over samples, except [0].w the sample
// count and [2], [3].xy, [3].w summed over the samples whose camera ray hit.
#define WT_AOV_SAMPLE_SLOTS 4u

#if WT_AOV
/// Add this sample's values to the pixel's sums.
inline void aov_fold(__global const float4* a, __global float4* sum) {
  float4 albedo = a[0], normal = a[1], hit = a[2], uv = a[3];
  sum[0] += (float4)(albedo.xyz, 1.0f);
  sum[1] += normal;
  if (uv.w != 0.0f) {
    sum[2] += hit;
    sum[3] += uv;
  } else {
    sum[3].z += uv.z;
  }
}
#endif  // WT_AOV
#endif  // WT_AOV_FOLD_CL
