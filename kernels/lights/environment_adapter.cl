// The environment as the integrator sees it: radiance for escaping rays,
// a sampled direction for NEE, and its pdf for MIS. Today a constant colour
// (uniform sphere sampling).
#ifndef WT_LIGHTS_ENVIRONMENT_ADAPTER_CL
#define WT_LIGHTS_ENVIRONMENT_ADAPTER_CL

#include "common.h"

typedef struct EnvScene {
  float3 color;  ///< constant radiance
} EnvScene;

inline float3 env_eval(EnvScene env, float3 dir) { return env.color; }

inline float env_pdf(EnvScene env, float3 dir) { return 1.0f / (4.0f * WT_PI); }

inline float3 env_sample(EnvScene env, float u1, float u2, float3* dir, float* pdf) {
  float z = 1.0f - 2.0f * u1;
  float r = sqrt(fmax(0.0f, 1.0f - z * z));
  float phi = 2.0f * WT_PI * u2;
  *dir = (float3)(r * cos(phi), z, r * sin(phi));
  *pdf = 1.0f / (4.0f * WT_PI);
  return env.color;
}

#endif  // WT_LIGHTS_ENVIRONMENT_ADAPTER_CL
