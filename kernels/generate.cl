// Stage 1: one camera ray per pixel, jittered within the pixel; every path
// starts with unit throughput and no radiance, and enters queue A.
#include "common.h"
#include "sampler.cl"

WT_KERNEL void generate(WtFrameParams frame, WtCamera camera, uint4 camera_media, __global float4* ray_o,
                        __global float4* ray_d, __global float4* throughput,
                        __global float4* radiance, __global uint* queue,
                        __global uint* counters, __global ushort4* bounce_counts, __global uint* ray_skip,
                        __global float2* ray_cone, __global uint4* media) {
  uint i = get_global_id(0);
  uint pixel_count = frame.width * frame.height;
  if (i >= pixel_count) return;
  if (i == 0) counters[WT_COUNTER_QUEUE_A] = pixel_count;

  // image plane in [-1,1]^2, y up
  uint px = i % frame.width;
  uint py = i / frame.width;
  float2 jitter = sampler_get2(frame, i, WT_DIM_PIXEL_X);  // (PIXEL_X, PIXEL_Y)
  float jx = jitter.x, jy = jitter.y;
  float sx = 2.0f * ((float)px + jx) / (float)frame.width - 1.0f;
  float sy = 1.0f - 2.0f * ((float)py + jy) / (float)frame.height;

  float3 forward = vec4_xyz(camera.forward);
  float3 offset = sx * vec4_xyz(camera.right) + sy * vec4_xyz(camera.up);
  float3 origin = vec4_xyz(camera.origin);
  float3 dir;
  if (camera.origin.w == (float)WT_CAMERA_ORTHOGRAPHIC) {
    origin += offset;
    dir = forward;
  } else {
    dir = normalize(forward + offset);
  }
  // The near plane is a distance along the view axis; convert it to this ray's t.
  float tmin = camera.forward.w / fmax(dot(dir, forward), 1e-6f);

  ray_o[i] = (float4)(origin, tmin);
  ray_d[i] = (float4)(dir, INFINITY);
  throughput[i] = (float4)(1.0f, 1.0f, 1.0f, 0.0f);
  radiance[i] = (float4)(0.0f);
  queue[i] = i;
  bounce_counts[i] = (ushort4)(0);
  ray_skip[i] = WT_NO_HIT;
#if WT_HAS_TEXTURES
  // the pixel's cone (materials/textured.cl): a perspective ray's angle, an
  // orthographic ray's width. Sample k takes 1/sqrt(k + 1) of the pixel (a
  // pixel's k samples each stand for a k-th of it): the first samples read
  // blurred texels, where they cut the most noise, and the running mean
  // converges to the pixel's box integral of the finest level.
  float pixel = 2.0f * length(vec4_xyz(camera.up)) / (float)frame.height * rsqrt((float)frame.sample + 1.0f);
  ray_cone[i] = camera.origin.w == (float)WT_CAMERA_ORTHOGRAPHIC ? (float2)(pixel, 0.0f) : (float2)(0.0f, pixel);
#endif
#if WT_HAS_TRANSMISSION
  // the volumes the camera is inside (shared/media.h; host/render/camera_media.h)
  media[i] = camera_media;
#endif
}
