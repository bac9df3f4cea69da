// Stage 3: emission at the hit, then (below the bounce limit) a new direction
// from the material; surviving paths are appended to the output queue.
#include "common.h"
#include "geometry/triangle.cl"
#include "materials/lambert.cl"

__kernel void shade(WtFrameParams frame, __global uint* counters, uint in_slot, uint out_slot,
                    __global const uint* queue_in, __global uint* queue_out,
                    __global float4* ray_o, __global float4* ray_d,
                    __global const float4* hits, __global float4* throughput,
                    __global float4* radiance, __global const WtTriangle* triangles,
                    __global const float4* tri_verts, __global const float4* normals,
                    __global const WtMaterial* materials) {
  uint i = get_global_id(0);
  if (i >= counters[in_slot]) return;
  uint path = queue_in[i];
  float4 hit = hits[path];
  uint prim = as_uint(hit.w);
  float3 beta = throughput[path].xyz;

  // miss: the constant environment (black by default)
  if (prim == WT_NO_HIT) {
    radiance[path] += (float4)(beta * vec4_xyz(frame.background), 0.0f);
    return;
  }

  WtTriangle tri = triangles[prim];
  WtMaterial material = materials[tri.material];

  // emission (two-sided); the minimal integrator counts it at every vertex
  radiance[path] += (float4)(beta * vec4_xyz(material.emission), 0.0f);
  if (frame.bounce >= frame.max_bounces) return;

  // surface
  float3 p, ng, ns;
  triangle_surface(tri_verts[3 * prim].xyz, tri_verts[3 * prim + 1].xyz,
                   tri_verts[3 * prim + 2].xyz, normals[tri.v0].xyz, normals[tri.v1].xyz,
                   normals[tri.v2].xyz, hit.y, hit.z, &p, &ng, &ns);
  if (dot(ng, ng) == 0.0f) return;  // degenerate triangle: absorb
  float3 wo = -ray_d[path].xyz;
  if (dot(ng, wo) < 0.0f) ng = -ng;
  if (dot(ns, ng) < 0.0f) ns = -ns;

  // Lambertian bounce; a direction below the geometric surface is absorbed
  float u1 = rng_uniform(path, frame.sample, frame.bounce, 2u, frame.seed);
  float u2 = rng_uniform(path, frame.sample, frame.bounce, 3u, frame.seed);
  float3 wi = lambert_sample(ns, u1, u2);
  if (dot(wi, ng) <= 0.0f) return;
  beta *= vec4_xyz(material.base_color);
  if (beta.x <= 0.0f && beta.y <= 0.0f && beta.z <= 0.0f) return;

  throughput[path] = (float4)(beta, 0.0f);
  ray_o[path] = (float4)(ray_offset_origin(p, ng), 0.0f);
  ray_d[path] = (float4)(wi, INFINITY);
  uint slot = atomic_inc(&counters[out_slot]);
  queue_out[slot] = path;
}
