// Stream traversal of any-hit queries: many incoherent shadow rays walk the
// tree together. One work-item holds up to WT_STREAM_RAYS rays as bits of a
// mask; a node is fetched once for all the rays that entered it, and each of
// them tests the node's four boxes in a loop with no branch per ray, so the
// slot branches that single-ray traversal mispredicts are paid per node
// rather than per ray. A ray leaves the stream when blocked. Each ray
// enters the boxes it enters in bvh_occluded and tests their triangles with
// the same test, in another order (slot order), until one blocks it: the
// order only decides which blocker is found first, so the answers are the
// same.
#ifndef WT_BVH_STREAM_CL
#define WT_BVH_STREAM_CL

#include "bvh.cl"

#if WT_STREAM_RAYS > 64
#error "WT_STREAM_RAYS: a stream's rays are the bits of one ulong"
#endif

// Whether a node's children are asked for as it arrives (below): where the
// host asks for it (WT_STREAM_PREFETCH: the scene does not fit in the
// device's cache, streamPrefetchFor), never under Oclgrind, which lacks the
// intrinsic (WT_NO_PREFETCH, tests/oclgrind/prefetch.cl).
#if WT_STREAM_PREFETCH && !(defined(WT_NO_PREFETCH) && WT_NO_PREFETCH)
#define WT_STREAM_REQUESTS 1
#else
#define WT_STREAM_REQUESTS 0
#endif

/// The lowest set bit's position (m != 0): one instruction from the
/// builtin, three from popcount where it is missing (Oclgrind,
/// WT_NO_CTZ). Rays are taken from a mask this way because it is the
/// cheapest loop over them (docs/lab/2026-12-05-performance-log.md, "Streams, 2026-12-05").
#if defined(WT_NO_CTZ) && WT_NO_CTZ
inline uint stream_lowest(ulong m) { return (uint)popcount((m & (0ul - m)) - 1ul); }
#else
inline uint stream_lowest(ulong m) { return (uint)__builtin_ctzl(m); }
#endif

/// Occlusion of rays index[0 .. n) of a batch (n <= WT_STREAM_RAYS): bit r
/// of the result is set where ray index[r]'s (tmin, tmax) is blocked by a
/// triangle other than the ray's skipped ones (skip_stride 1: skip[i];
/// 2: skip[2 i] and skip[2 i + 1], the uint2 of the renderer's shadow
/// rays), or where the ray is not finite
/// (bvh_occluded's answers; with WT_HAS_ALPHA each ray draws from its own
/// stream, that of ray index[r] alone, so the holes are the same too).
inline ulong bvh_occluded_stream(BvhScene scene, const uint* index, uint n, __global const float4* ray_o,
                                 __global const float4* ray_d, __global const uint* skip, uint skip_stride) {
  __global const WtBvh4Node* nodes = (__global const WtBvh4Node*)scene.nodes;
  // per-ray constants, set up once (bvh_occluded's)
  float3 org[WT_STREAM_RAYS], inv_d[WT_STREAM_RAYS], org_k[WT_STREAM_RAYS];
  float tmin[WT_STREAM_RAYS], tmax[WT_STREAM_RAYS];
  RayPlanes planes[WT_STREAM_RAYS];
  RayShear shear[WT_STREAM_RAYS];
  uint skip_prim[WT_STREAM_RAYS], skip_other[WT_STREAM_RAYS];
#if WT_HAS_ALPHA
  uint alpha_ray[WT_STREAM_RAYS];  // each ray's stream for the alpha test (WT_ALPHA_RAY)
#endif
  ulong blocked = 0ul;
  ulong open = 0ul;  // rays still searching
  for (uint r = 0; r < n; ++r) {
    float4 o = ray_o[index[r]], d = ray_d[index[r]];
    if (!bvh_ray_is_finite(o.xyz, d.xyz)) {
      blocked |= 1ul << r;
      continue;
    }
    if (scene.node_count == 0) continue;
    org[r] = o.xyz;
    tmin[r] = o.w;
    tmax[r] = d.w;
    inv_d[r] = bvh_safe_rcp(d.xyz);
    planes[r] = bvh_ray_planes(inv_d[r]);
    shear[r] = triangle_ray_shear(d.xyz);
    org_k[r] = (float3)(vec3_component(o.xyz, shear[r].kx), vec3_component(o.xyz, shear[r].ky),
                        vec3_component(o.xyz, shear[r].kz));
    skip_prim[r] = skip[skip_stride * index[r]];
    skip_other[r] = skip_stride == 2u ? skip[2u * index[r] + 1u] : WT_NO_HIT;
#if WT_HAS_ALPHA
    WT_ALPHA_RAY(scene, index[r]);
    alpha_ray[r] = scene.alpha.ray;
#endif
    open |= 1ul << r;
  }

  // a node and the rays that entered its box; at most three pushes per level left
  uint stack_node[WT_BVH_STACK_SIZE];
  ulong stack_rays[WT_BVH_STACK_SIZE];
  int sp = 0;
  uint node = 0;
  ulong rays = open;
  for (;;) {
    rays &= open;  // rays blocked since the push are done
    if (rays != 0ul) {
      __global const WtBvh4Node* n = &nodes[node];
#if WT_STREAM_REQUESTS
      // Every child's data is asked for as the node arrives (a leaf's first
      // block, 144 bytes on at most three cache lines, an inner node's two
      // lines): the box tests of all the
      // stream's rays come first, and the misses overlap. On the 1 M-triangle
      // scenes half the stream's time was spent waiting on the first load of
      // a node or of a leaf block; a tree that fits in the caches gains nothing
      // (docs/lab/2026-12-04-performance-log.md, "Streams: the children's data asked for early").
      for (int k = 0; k < 4; ++k) {
        uint child = n->child[k];
        if (child == WT_BVH4_EMPTY) continue;
        if (n->count[k] > 0u) {
          __global const float4* block = scene.tri_verts + WT_TRIANGLE_BLOCK_ROWS * (child >> 2);
          __builtin_prefetch(block, 0, 3);
          __builtin_prefetch(block + 4, 0, 3);
          __builtin_prefetch(block + 8, 0, 3);
        } else {
          __builtin_prefetch(&nodes[child], 0, 3);
          __builtin_prefetch((__global const char*)&nodes[child] + 64, 0, 3);
        }
      }
#endif
      // which rays enter which child
      ulong enter0 = 0ul, enter1 = 0ul, enter2 = 0ul, enter3 = 0ul;
      for (ulong m = rays; m != 0ul; m &= m - 1ul) {
        uint r = stream_lowest(m);
        float4 t4;
        int4 hit4 = bvh4_box_hit(n, planes[r], org[r], inv_d[r], tmin[r], tmax[r], &t4);
        ulong bit = 1ul << r;
        enter0 |= hit4.s0 ? bit : 0ul;
        enter1 |= hit4.s1 ? bit : 0ul;
        enter2 |= hit4.s2 ? bit : 0ul;
        enter3 |= hit4.s3 ? bit : 0ul;
      }
      ulong enter[4] = {enter0, enter1, enter2, enter3};
      // leaves now, by every ray that entered them (leaves come first in
      // slot order), taken from a mask of the leaf slots some ray entered
      // rather than by a branch or two per slot, which the predictor cannot
      // learn (docs/lab/2026-12-05-performance-log.md, "Streams, 2026-12-05")
      uint4 counts = vload4(0, n->count);
      int4 is_leaf = counts != (uint4)(0u);
      ulong leaves = ((is_leaf.s0 && enter0 != 0ul) ? 1ul : 0ul) | ((is_leaf.s1 && enter1 != 0ul) ? 2ul : 0ul) |
                     ((is_leaf.s2 && enter2 != 0ul) ? 4ul : 0ul) | ((is_leaf.s3 && enter3 != 0ul) ? 8ul : 0ul);
      for (; leaves != 0ul; leaves &= leaves - 1ul) {
        uint k = stream_lowest(leaves);
        uint count = n->count[k];
        uint first = n->child[k], last = first + count - 1u;
#if WT_STREAM_REQUESTS
        // ray by ray, each through the leaf's blocks until one blocks it
        for (ulong m = enter[k] & open; m != 0ul; m &= m - 1ul) {
          uint r = stream_lowest(m);
#if WT_HAS_ALPHA
          scene.alpha.ray = alpha_ray[r];
#endif
          for (uint b = first >> 2; b <= last >> 2; ++b) {
            float t, b1, b2;
            if (bvh_block_hit_k(scene, org_k[r], shear[r], tmin[r], tmax[r], b, b == first >> 2 ? first & 3u : 0u,
                                b == last >> 2 ? (last & 3u) + 1u : 4u, skip_prim[r], skip_other[r], &t, &b1,
                                &b2) != WT_NO_HIT) {
              open &= ~(1ul << r);
              blocked |= 1ul << r;
              break;
            }
          }
        }
#else
        // block by block, each tested by every ray still open, the blocked
        // ones gathered in a mask rather than branched on: one branch per
        // block instead of one per ray, which pays only where the blocks are
        // in cache (docs/lab/2026-12-05-performance-log.md, "Streams, 2026-12-05")
        for (uint b = first >> 2; b <= last >> 2; ++b) {
          uint lo = b == first >> 2 ? first & 3u : 0u, hi = b == last >> 2 ? (last & 3u) + 1u : 4u;
          ulong hits = 0ul;
          for (ulong m = enter[k] & open; m != 0ul; m &= m - 1ul) {
            uint r = stream_lowest(m);
            float t, b1, b2;
#if WT_HAS_ALPHA
            scene.alpha.ray = alpha_ray[r];
#endif
            uint prim = bvh_block_hit_k(scene, org_k[r], shear[r], tmin[r], tmax[r], b, lo, hi, skip_prim[r],
                                        skip_other[r], &t, &b1, &b2);
            hits |= prim != WT_NO_HIT ? 1ul << r : 0ul;
          }
          open &= ~hits;
          blocked |= hits;
        }
#endif
      }
      // Every inner child entered is pushed, the last slot first, with no
      // branch per slot, and the pop below takes the first: the rays visit
      // the children in slot order (largest box first). Against the first
      // child taken at once and the others pushed behind a branch each, this
      // saves the branches (docs/lab/2026-12-05-performance-log.md, "Streams,
      // 2026-12-05"). The fourth push, popped at once, is the one entry
      // bvh4StackEntries adds to three per level.
      for (int k = 3; k >= 0; --k) {
        stack_node[sp] = n->child[k];
        stack_rays[sp] = enter[k];
        sp += (n->count[k] == 0u && enter[k] != 0ul) ? 1 : 0;
      }
    }
    if (sp == 0 || open == 0ul) return blocked;
    --sp;
    node = stack_node[sp];
    rays = stack_rays[sp];
  }
}

/// Order rays[0 .. n) (batch indices, n <= WT_STREAM_WINDOW) by the octant
/// of their direction into sorted: rays that leave neighbouring points the
/// same way share more of the tree.
inline void stream_sort_by_octant(const uint* rays, uint n, __global const float4* ray_d, uint* sorted) {
  uchar octant[WT_STREAM_WINDOW];
  uint start[8] = {0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u};
  for (uint i = 0; i < n; ++i) {
    float4 d = ray_d[rays[i]];
    uint o = (d.x < 0.0f ? 1u : 0u) | (d.y < 0.0f ? 2u : 0u) | (d.z < 0.0f ? 4u : 0u);
    octant[i] = (uchar)o;
    ++start[o];
  }
  // counts to starts
  uint at = 0u;
  for (int o = 0; o < 8; ++o) {
    uint count = start[o];
    start[o] = at;
    at += count;
  }
  for (uint i = 0; i < n; ++i) sorted[start[octant[i]]++] = rays[i];
}

/// Occlusion of rays [first, end) of a batch (at most WT_STREAM_WINDOW),
/// written to occluded[]: grouped by octant where the scene fits in the
/// device's cache, in their order where it does not (WT_STREAM_PREFETCH),
/// then traced as streams of WT_STREAM_RAYS. Consecutive rays leave
/// neighbouring points (the bench's and the renderer's shadow rays follow
/// their pixels), and where every node and leaf block is a trip to memory,
/// rays that start together share the leaves around their origins, which
/// matters only where the scene outgrows the cache
/// (docs/lab/2026-12-04-performance-log.md, "Streams keep the rays' order on large scenes").
inline void bvh_occluded_window(BvhScene scene, uint first, uint end, __global const float4* ray_o,
                                __global const float4* ray_d, __global const uint* skip,
                                __global uint* occluded) {
  uint n = end - first;
  uint rays[WT_STREAM_WINDOW], order[WT_STREAM_WINDOW];
  for (uint i = 0; i < n; ++i) rays[i] = first + i;
#if WT_STREAM_PREFETCH
  for (uint i = 0; i < n; ++i) order[i] = rays[i];
#else
  stream_sort_by_octant(rays, n, ray_d, order);
#endif
  for (uint s = 0; s < n; s += WT_STREAM_RAYS) {
    uint m = min(n - s, (uint)WT_STREAM_RAYS);
    ulong blocked = bvh_occluded_stream(scene, order + s, m, ray_o, ray_d, skip, 1u);
    for (uint r = 0; r < m; ++r) occluded[order[s + r]] = (uint)((blocked >> r) & 1ul);
  }
}

#endif  // WT_BVH_STREAM_CL
