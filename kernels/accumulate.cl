// Stage 4: fold this pass's radiance into the per-pixel running mean and
// second moment (Welford). Non-finite samples are counted, never folded in.
#include "common.h"

__kernel void accumulate(WtFrameParams frame, __global const float4* radiance,
                         __global float4* mean, __global float4* m2,
                         __global uint* sample_count, __global uint* counters) {
  uint i = get_global_id(0);
  if (i >= frame.width * frame.height) return;
  float4 value = radiance[i];
  if (!all(isfinite(value.xyz))) {
    atomic_inc(&counters[WT_COUNTER_NONFINITE]);
    return;
  }
  uint n = sample_count[i] + 1u;
  float4 old_mean = mean[i];
  float4 delta = value - old_mean;
  float4 new_mean = old_mean + delta / (float)n;
  m2[i] += delta * (value - new_mean);
  mean[i] = new_mean;
  sample_count[i] = n;
}
