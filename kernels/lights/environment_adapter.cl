// The environment as the integrator sees it: radiance for escaping rays, a
// sampled direction for NEE and its pdf for MIS, over the model and the
// importance sampling of lights/environment.cl.
#ifndef WT_LIGHTS_ENVIRONMENT_ADAPTER_CL
#define WT_LIGHTS_ENVIRONMENT_ADAPTER_CL

#include "common.h"
#include "lights/environment.cl"

typedef struct EnvScene {
  WtEnvironment header;
  __global const float4* texels;
  __global const float* marginal_cdf;
  __global const float* conditional_cdf;
} EnvScene;

inline float3 env_eval(EnvScene e, float3 dir) {
  return environment_eval(e.header, e.texels, e.marginal_cdf, e.conditional_cdf, dir);
}

inline float env_pdf(EnvScene e, float3 dir) {
  return environment_pdf(e.header, e.texels, e.marginal_cdf, e.conditional_cdf, dir);
}

inline float3 env_sample(EnvScene e, float u1, float u2, float3* dir, float* pdf) {
  return environment_sample(e.header, e.texels, e.marginal_cdf, e.conditional_cdf, u1, u2, dir, pdf);
}

#endif  // WT_LIGHTS_ENVIRONMENT_ADAPTER_CL
