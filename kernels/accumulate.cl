// Stage 5: fold this pass's radiance into each pixel's running mean and
// second moment (Welford). Non-finite samples are counted, never folded in.
// Three precisions (WtFrameParams::accumulate_mode), as Falcor's
// AccumulatePass offers: single, single with compensated (Kahan) updates, and
// double where the device has fp64. The per-pixel state is 64 bytes in every
// mode; accumulate_resolve turns it into float mean and m2 for tonemapping
// and read-back. Part of the frame program (frame.cl): reads WT_AOV only.
#ifndef WT_ACCUMULATE_CL
#define WT_ACCUMULATE_CL

#include "shared/types.h"
#include "base.h"
#include "aov_fold.cl"

/// One Welford update in single precision.
inline void accumulate_single(float4 x, float n, float4* mean, float4* m2) {
  float4 delta = x - *mean;
  float4 new_mean = *mean + delta / n;
  *m2 += delta * (x - new_mean);
  *mean = new_mean;
}

/// The same with each increment compensated (Kahan): the low bits an
/// increment loses against a large running value are carried to the next.
/// Relies on FP_CONTRACT OFF (base.h): a fused multiply-add would undo it.
inline void accumulate_kahan(float4 x, float n, float4* mean, float4* m2, float4* c_mean,
                             float4* c_m2) {
  float4 delta = x - *mean;
  float4 y = delta / n - *c_mean;
  float4 t = *mean + y;
  *c_mean = (t - *mean) - y;
  float4 y2 = delta * (x - t) - *c_m2;
  float4 t2 = *m2 + y2;
  *c_m2 = (t2 - *m2) - y2;
  *mean = t;
  *m2 = t2;
}

#if WT_HAS_FP64
inline void accumulate_double(float4 x, double n, double4* mean, double4* m2) {
  double4 xd = convert_double4(x);
  double4 delta = xd - *mean;
  double4 new_mean = *mean + delta / n;
  *m2 += delta * (xd - new_mean);
  *mean = new_mean;
}
#endif

WT_KERNEL void accumulate(WtFrameParams frame, __global const float4* radiance,
                          __global float4* state, __global uint* sample_count,
                          __global uint* counters, __global const float4* aov_sample,
                          __global float4* aov_accum) {
  uint i = get_global_id(0);
  if (i >= frame.width * frame.height) return;
#if WT_AOV
  aov_fold(aov_sample + WT_AOV_SAMPLE_SLOTS * i, aov_accum + WT_AOV_SAMPLE_SLOTS * i);
#endif
  float4 value = radiance[i];
  __global float4* s = state + 4u * i;
  // the first fold into never-written buffers: zero where the state was read, every word written
  const bool blank = (frame.flags & WT_FLAG_BLANK_ACCUMULATION) != 0u;
  if (!all(isfinite(value.xyz))) {
    atomic_inc(&counters[WT_COUNTER_NONFINITE]);
    if (blank) {
      s[0] = s[1] = s[2] = s[3] = (float4)(0.0f);
      sample_count[i] = 0u;
    }
    return;
  }
  uint n = (blank ? 0u : sample_count[i]) + 1u;
#if WT_HAS_FP64
  if (frame.accumulate_mode == WT_ACCUMULATE_DOUBLE) {
    __global double4* d = (__global double4*)s;
    double4 mean = blank ? (double4)(0.0) : d[0], m2 = blank ? (double4)(0.0) : d[1];
    accumulate_double(value, (double)n, &mean, &m2);
    d[0] = mean;
    d[1] = m2;
    sample_count[i] = n;
    return;
  }
#endif
  const float4 zero = (float4)(0.0f);
  float4 mean = blank ? zero : s[0], m2 = blank ? zero : s[1];
  if (frame.accumulate_mode == WT_ACCUMULATE_KAHAN) {
    float4 c_mean = blank ? zero : s[2], c_m2 = blank ? zero : s[3];
    accumulate_kahan(value, (float)n, &mean, &m2, &c_mean, &c_m2);
    s[2] = c_mean;
    s[3] = c_m2;
  } else {
    accumulate_single(value, (float)n, &mean, &m2);
    if (blank) s[2] = s[3] = zero;
  }
  s[0] = mean;
  s[1] = m2;
  sample_count[i] = n;
}

/// Float mean and second moment from the accumulation state of any mode.
WT_KERNEL void accumulate_resolve(WtFrameParams frame, __global const float4* state,
                                  __global float4* mean, __global float4* m2) {
  uint i = get_global_id(0);
  if (i >= frame.width * frame.height) return;
  __global const float4* s = state + 4u * i;
#if WT_HAS_FP64
  if (frame.accumulate_mode == WT_ACCUMULATE_DOUBLE) {
    __global const double4* d = (__global const double4*)s;
    mean[i] = convert_float4(d[0]);
    m2[i] = convert_float4(d[1]);
    return;
  }
#endif
  mean[i] = s[0];
  m2[i] = s[1];
}

#endif  // WT_ACCUMULATE_CL
