// Packets through the primitive BVH (kernels/bvh_prims.cl) and into its
// instances: one work-item walks the tree of spheres, curves and instances
// with the WT_PACKET_WIDTH rays of its packet, a node's child boxes tested
// against every lane at once (packet_box_hit), a leaf's primitives a lane
// at a time (each entering lane through the whole leaf, so a blocked one
// stops there) with the very calls bvh_prims_closest and bvh_prims_occluded
// make; closest and any hits are one walk (`any`, a constant where it is
// called, so each compiles to its own). A
// packet that enters an instance goes on inside it as a packet: its lanes'
// rays are moved into the copy's object space once per visit (each lane by
// instance_point / instance_vector, the single ray's own arithmetic, so the
// object-space rays are the same floats), the geometry's tree walked as a
// packet, and the scene-space packet taken up again after it. Each lane gets
// the answers its ray gets alone; only the order in which nodes are visited
// differs (nearest entry among the lanes), so of two hits at exactly the
// same distance another may win. Inside an instance of triangles the packet
// is the triangles' own (kernels/bvh_packet.cl: packet_load_lanes, then
// packet_closest_root / packet_occluded_root from the geometry's root), each
// lane with its own axis permutation as in the scene's tree.
#ifndef WT_BVH_PRIMS_PACKET_CL
#define WT_BVH_PRIMS_PACKET_CL

#include "bvh_packet.cl"
#include "bvh_prims.cl"

#if WT_HAS_PRIMITIVES

/// A packet's rays in one space (the scene's, or an instance's object
/// space): each lane's ray as scalars, for the primitives' own tests, and
/// origins, reciprocal directions and tmin as vectors in `box` (only those
/// fields of it are set), for packet_box_hit.
typedef struct PrimPacket {
  RayPacket box;
  float ox[WT_PACKET], oy[WT_PACKET], oz[WT_PACKET];
  float dx[WT_PACKET], dy[WT_PACKET], dz[WT_PACKET];
  float tmin[WT_PACKET];
  uint skip[WT_PACKET];  ///< the primitive the lane's ray leaves, in this space (WT_NO_HIT: none)
} PrimPacket;

/// Lane l's ray (o, d) from tmin, leaving `skip`.
inline void prims_packet_set(PrimPacket* p, int l, float3 o, float3 d, float tmin, uint skip) {
  p->ox[l] = o.x, p->oy[l] = o.y, p->oz[l] = o.z;
  p->dx[l] = d.x, p->dy[l] = d.y, p->dz[l] = d.z;
  p->tmin[l] = tmin;
  p->skip[l] = skip;
}

/// The vectors of `box` from the lanes' scalars; the reciprocal directions
/// by bvh_safe_rcp lane by lane, as the single ray computes its own.
inline void prims_packet_finish(PrimPacket* p) {
  float ix[WT_PACKET], iy[WT_PACKET], iz[WT_PACKET];
  for (int l = 0; l < WT_PACKET; ++l) {
    float3 inv_d = bvh_safe_rcp((float3)(p->dx[l], p->dy[l], p->dz[l]));
    ix[l] = inv_d.x, iy[l] = inv_d.y, iz[l] = inv_d.z;
  }
  p->box.o[0] = packet_vload(p->ox), p->box.o[1] = packet_vload(p->oy), p->box.o[2] = packet_vload(p->oz);
  p->box.inv_d[0] = packet_vload(ix), p->box.inv_d[1] = packet_vload(iy), p->box.inv_d[2] = packet_vload(iz);
  p->box.tmin = packet_vload(p->tmin);
}

inline float3 prims_packet_org(const PrimPacket* p, int l) { return (float3)(p->ox[l], p->oy[l], p->oz[l]); }
inline float3 prims_packet_dir(const PrimPacket* p, int l) { return (float3)(p->dx[l], p->dy[l], p->dz[l]); }

#if WT_HAS_INSTANCES
/// The lanes of `lanes` moved into instance `prim`'s object space: the
/// packet q, and in *valid those whose object-space ray is finite (a lane
/// whose ray is not is dropped by the closest walk and blocked by the
/// occlusion walk, as alone: *not_finite). Lane l leaves its primitive on
/// this copy only when the copy is the one it leaves (skip_instance[l]).
inline void prims_packet_into_instance(GeometryScene g, uint prim, const PrimPacket* p, const int* lanes,
                                       const uint* skip_instance, PrimPacket* q, pint* valid, pint* not_finite) {
  __global const float4* rows = geometry_instance_rows(g, prim);
  int in[WT_PACKET], bad[WT_PACKET];
  for (int l = 0; l < WT_PACKET; ++l) {
    in[l] = 0, bad[l] = 0;
    if (!lanes[l]) {
      // a lane left out: any finite ray, masked out of every test
      prims_packet_set(q, l, (float3)(0.0f), (float3)(0.0f, 0.0f, 1.0f), 0.0f, WT_NO_HIT);
      continue;
    }
    float3 o = instance_point(rows, prims_packet_org(p, l)), d = instance_vector(rows, prims_packet_dir(p, l));
    bool finite = bvh_ray_is_finite(o, d);
    if (!finite) o = (float3)(0.0f), d = (float3)(0.0f, 0.0f, 1.0f);
    prims_packet_set(q, l, o, d, p->tmin[l], prim == skip_instance[l] ? p->skip[l] : WT_NO_HIT);
    in[l] = finite ? -1 : 0;
    bad[l] = finite ? 0 : -1;
  }
  prims_packet_finish(q);
  *valid = packet_vload(in);
  *not_finite = packet_vload(bad);
}

/// The lanes of `lanes` moved into instance `prim`'s object space as a
/// triangle packet (packet_load_lanes: each lane's permutation and shear),
/// tmax[l] their interval's end; lane l skips its geometry's triangle on
/// this copy only, and tests alpha with the stream its ray uses on this copy
/// alone (rng_alpha_instance). *not_finite: the lanes whose object-space
/// ray is not finite (left out of *valid).
inline void prims_packet_triangles_into(BvhScene scene, GeometryScene g, uint prim, const PrimPacket* p,
                                       const int* lanes, const uint* index, const uint* skip_instance,
                                       const float* tmax, RayPacket* q, pint* valid, pfloat* q_tmax,
                                       pint* not_finite) {
  __global const float4* rows = geometry_instance_rows(g, prim);
  float ox[WT_PACKET], oy[WT_PACKET], oz[WT_PACKET], dx[WT_PACKET], dy[WT_PACKET], dz[WT_PACKET];
  int in[WT_PACKET], bad[WT_PACKET];
  uint skip[WT_PACKET];
#if WT_HAS_ALPHA
  uint alpha[WT_PACKET];
#endif
  for (int l = 0; l < WT_PACKET; ++l) {
    float3 o = (float3)(0.0f), d = (float3)(0.0f, 0.0f, 1.0f);
    bool finite = false;
    if (lanes[l]) {
      o = instance_point(rows, prims_packet_org(p, l)), d = instance_vector(rows, prims_packet_dir(p, l));
      finite = bvh_ray_is_finite(o, d);
      if (!finite) o = (float3)(0.0f), d = (float3)(0.0f, 0.0f, 1.0f);
    }
    ox[l] = o.x, oy[l] = o.y, oz[l] = o.z, dx[l] = d.x, dy[l] = d.y, dz[l] = d.z;
    in[l] = finite ? -1 : 0;
    bad[l] = lanes[l] && !finite ? -1 : 0;
    skip[l] = prim == skip_instance[l] ? p->skip[l] : WT_NO_HIT;
#if WT_HAS_ALPHA
    alpha[l] = rng_alpha_instance(rng_alpha_ray(scene.alpha.key, index[l]), prim);
#endif
  }
  packet_load_lanes(q, valid, q_tmax, packet_vload(ox), packet_vload(oy), packet_vload(oz), packet_vload(p->tmin),
                    packet_vload(dx), packet_vload(dy), packet_vload(dz), packet_vload(tmax), packet_vload(in), 0);
  q->skip_a = packet_vload(skip);
  q->skip_b = (puint)(WT_NO_HIT);
#if WT_HAS_ALPHA
  q->alpha_ray = packet_vload(alpha);
#endif
  *not_finite = packet_vload(bad);
}

/// Closest hits narrowed by instance `prim`'s triangles, the lanes of
/// `lanes` traced as a packet in its object space (geometry_instance_closest
/// lane by lane). The mask of the lanes it narrowed.
inline pint prims_packet_triangles_closest(BvhScene scene, GeometryScene g, uint prim, const PrimPacket* p,
                                           const int* lanes, const uint* index, const uint* skip_instance, float* t,
                                           float* u, float* v, uint* hit) {
  RayPacket q;
  pint valid, not_finite;
  pfloat tmax;
  prims_packet_triangles_into(scene, g, prim, p, lanes, index, skip_instance, t, &q, &valid, &tmax, &not_finite);
  if (!packet_any(valid)) return (pint)(0);
  const pfloat before = tmax;
  pfloat b1 = packet_vload(u), b2 = packet_vload(v);
  puint h = packet_vload(hit);
  uint root = geometry_instance_info(g, prim).x;
  packet_closest_root(scene, root, &q, valid, &tmax, &b1, &b2, &h);
  // a hit is nearer than where the lane searched to (bvh_closest_root's t < tmax)
  pint won = valid & packet_mask(tmax < before);
  packet_vstore(tmax, t), packet_vstore(b1, u), packet_vstore(b2, v), packet_vstore(h, hit);
  return won;
}

/// The lanes of `lanes` that instance `prim`'s triangles block in (tmin,
/// tmax[l]), traced as a packet in its object space, or whose object-space
/// ray is not finite (geometry_instance_occluded lane by lane).
inline pint prims_packet_triangles_occluded(BvhScene scene, GeometryScene g, uint prim, const PrimPacket* p,
                                            const int* lanes, const uint* index, const uint* skip_instance,
                                            const float* tmax) {
  RayPacket q;
  pint valid, not_finite;
  pfloat q_tmax;
  prims_packet_triangles_into(scene, g, prim, p, lanes, index, skip_instance, tmax, &q, &valid, &q_tmax, &not_finite);
  pint blocked = not_finite;
  if (!packet_any(valid)) return blocked;
  uint root = geometry_instance_info(g, prim).x;
  return blocked | packet_occluded_root(scene, root, &q, valid, q_tmax);
}
#endif

/// A walk's stack: nodes, and (closest hits) the nearest entry among the
/// lanes that entered each.
/// A packet's rays in an oriented node's frame (bvh4_frame_hit lane by
/// lane): origins, reciprocal directions, and the boxes' widening for the
/// rounding as a distance along each axis's ray (m |1 / d|).
typedef struct FramePacket {
  pfloat o[3], inv_d[3], m[3];
  float q0[3], qs[3];  ///< the node's grid (WtBvh4Oriented origin, step)
} FramePacket;

inline void prims_packet_frame(__global const WtBvh4Node* node, const PrimPacket* p, FramePacket* f) {
  __global const float* fr = (__global const float*)node;
  float4 r[3] = {vload4(0, fr), vload4(1, fr), vload4(2, fr)};
  float3 q0 = vload3(0, fr + 12), qs = vload3(0, fr + 15);
  float3 reach = fmax(fabs(q0), fabs(q0 + 255.0f * qs));
  f->q0[0] = q0.x, f->q0[1] = q0.y, f->q0[2] = q0.z;
  f->qs[0] = qs.x, f->qs[1] = qs.y, f->qs[2] = qs.z;
  pfloat wx = p->box.o[0] - r[0].w, wy = p->box.o[1] - r[1].w, wz = p->box.o[2] - r[2].w;
  pfloat dx = packet_vload(p->dx), dy = packet_vload(p->dy), dz = packet_vload(p->dz);
  pfloat m = 2e-6f * (fabs(wx) + fabs(wy) + fabs(wz) + (reach.x + reach.y + reach.z));
  for (int i = 0; i < 3; ++i) {
    f->o[i] = r[i].x * wx + r[i].y * wy + r[i].z * wz;
    pfloat d = r[i].x * dx + r[i].y * dy + r[i].z * dz;
    d = select(d, copysign((pfloat)(1e-30f), d), fabs(d) < 1e-30f);  // as bvh_safe_rcp
    f->inv_d[i] = 1.0f / d;
    f->m[i] = m * fabs(f->inv_d[i]);
  }
}

/// packet_box_hit for child k of an oriented node, the lanes in its frame.
inline pint packet_frame_box_hit(__global const WtBvh4Node* node, int k, const FramePacket* f, pfloat tmin,
                                 pfloat tmax, pfloat* enter) {
  __global const uchar* g = (__global const uchar*)((__global const WtBvh4Oriented*)node)->grid;
  pfloat t[6];
  for (int j = 0; j < 6; ++j) {
    float plane = f->q0[j / 2] + (float)g[4 * j + k] * f->qs[j / 2];
    t[j] = (plane - f->o[j / 2]) * f->inv_d[j / 2];
  }
  pfloat tn = packet_vmax(packet_vmax(packet_vmin(t[0], t[1]) - f->m[0], packet_vmin(t[2], t[3]) - f->m[1]),
                          packet_vmax(packet_vmin(t[4], t[5]) - f->m[2], tmin));
  pfloat tf = packet_vmin(packet_vmin(packet_vmax(t[0], t[1]) + f->m[0], packet_vmax(t[2], t[3]) + f->m[1]),
                          packet_vmax(t[4], t[5]) + f->m[2]) * 1.00000036f;
  tf = packet_vmin(tf, tmax);
  *enter = tn;
  return packet_mask(tn <= tf);
}

typedef struct PrimWalk {
  uint node[WT_BVH_STACK_SIZE];
  float t[WT_BVH_STACK_SIZE];
  int sp;
  uint inner[4];  ///< this node's inner children that lanes enter (closest: nearest entry first)
  float inner_t[4];
  int inner_count;
} PrimWalk;

/// Inner child `first`, which the lanes of `hit` enter at `enter`, for the
/// walk: stacked as it comes (any hit), or put in order among this node's
/// (closest hit).
__attribute__((always_inline)) inline void prims_walk_push(PrimWalk* w, bool any, uint first, pint hit, pfloat enter) {
  if (any) {
    w->node[w->sp++] = first;
    return;
  }
  float key = packet_min(packet_pick(hit, enter, (pfloat)(INFINITY)));
  int j = w->inner_count++;
  for (; j > 0 && w->inner_t[j - 1] > key; --j) {
    w->inner[j] = w->inner[j - 1];
    w->inner_t[j] = w->inner_t[j - 1];
  }
  w->inner[j] = first;
  w->inner_t[j] = key;
}

/// The walk's next node into *node, false when it is done: the last
/// stacked (any hit); the nearest inner child of this node that a lane may
/// reach before `reach` (the farthest lane's end), the others stacked, else
/// the last stacked within reach (closest hit).
__attribute__((always_inline)) inline bool prims_walk_next(PrimWalk* w, bool any, float reach, uint* node) {
  int count = w->inner_count;
  w->inner_count = 0;
  if (any) {
    if (w->sp == 0) return false;
    *node = w->node[--w->sp];
    return true;
  }
  if (count > 0 && w->inner_t[0] <= reach) {
    for (int k = count - 1; k >= 1; --k) {
      if (w->inner_t[k] > reach) continue;
      w->node[w->sp] = w->inner[k];
      w->t[w->sp] = w->inner_t[k];
      ++w->sp;
    }
    *node = w->inner[0];
    return true;
  }
  for (;;) {
    if (w->sp == 0) return false;
    --w->sp;
    if (w->t[w->sp] <= reach) break;
  }
  *node = w->node[w->sp];
  return true;
}

/// The primitives refs[first, first + count) (no instances) against the
/// lanes of lane_hit, each lane's ray alone (geometry_intersect_entry in (tmin,
/// t[l]), leaving skip and skip_b[l]; no skip_b: none), a lane at a time
/// (so one the leaf blocks stops at once): where one hits, found[l] set,
/// and the lane narrowed to it (closest hit: t, u, v, prim; instance[l]
/// none where `instance` is given) or left out of lane_hit (any hit).
/// Whether any hit.
__attribute__((always_inline)) inline bool prims_packet_leaf(GeometryScene g, uint first, uint count,
                                                             const PrimPacket* p, bool any, const uint* skip_b,
                                                             int* lane_hit, int* found, float* t, float* u, float* v,
                                                             uint* prim, uint* instance) {
  bool won = false;
  for (int l = 0; l < WT_PACKET; ++l) {
    if (!lane_hit[l]) continue;
    float3 o = prims_packet_org(p, l), d = prims_packet_dir(p, l), dn = prims_ray_unit(d);
    uint missed = prims_leaf_missed(g, first, count, o, dn);
    for (uint i = first; i < first + count; ++i) {
      if (i - first < 4u && (missed >> (i - first) & 1u)) continue;
      uint id = g.refs[i];
      float th, uh, vh;
      if (!geometry_intersect_entry(g, i, id, o, d, p->tmin[l], t[l], p->skip[l], skip_b ? skip_b[l] : WT_NO_HIT,
                                    any, &th, &uh, &vh))
        continue;
      found[l] = -1;
      won = true;
      // a blocked lane is done; a narrowed one goes on with the nearer end
      if (any) {
        lane_hit[l] = 0;
        break;
      }
      t[l] = th, u[l] = uh, v[l] = vh, prim[l] = id;
      if (instance) instance[l] = WT_NO_HIT;
    }
  }
  return won;
}

/// The primitives of the tree whose root is `root`, which holds no
/// instances (an instance's geometry), for the lanes of `valid`:
/// bvh_prims_closest_root lane by lane, or with `any`
/// bvh_prims_occluded_root. Closest: lane arrays t, u, v, prim narrowed,
/// and the mask of the lanes narrowed returned. Any: the lanes blocked in
/// (tmin, t[l]) returned, the arrays untouched.
__attribute__((always_inline)) inline pint prims_packet_tree(GeometryScene g, uint root, const PrimPacket* p,
                                                             pint valid, bool any, float* t, float* u, float* v,
                                                             uint* prim) {
  pfloat tmax = packet_vload(t);
  pint open = valid;  // any: the lanes not blocked yet
  float reach = packet_max(packet_pick(valid, tmax, (pfloat)(-INFINITY)));
  int found[WT_PACKET];
  for (int l = 0; l < WT_PACKET; ++l) found[l] = 0;
  PrimWalk w;
  w.sp = 0, w.inner_count = 0;
  uint node = root;
  do {
    __global const WtBvh4Node* n = &g.nodes[node & ~WT_BVH4_ORIENTED];
    bool framed = (node & WT_BVH4_ORIENTED) != 0;
    // most children are entered by some lane: ask for them all while the boxes are tested
    for (int k = 0; k < 4; ++k)
      if (n->child[k] != WT_BVH4_EMPTY) prims_prefetch_child(g, n->child[k], n->count[k]);
    FramePacket f;
    if (framed) prims_packet_frame(n, p, &f);
    for (int k = 0; k < 4; ++k) {
      uint first = n->child[k], count = n->count[k];
      if (first == WT_BVH4_EMPTY) continue;
      pfloat enter;
      pint hit = (framed ? packet_frame_box_hit(n, k, &f, p->box.tmin, tmax, &enter)
                         : packet_box_hit(n, k, &p->box, tmax, &enter)) & open;
      if (!packet_any(hit)) continue;
      if (count == 0) {
        prims_walk_push(&w, any, first, hit, enter);
        continue;
      }
      int lane_hit[WT_PACKET];
      packet_vstore(hit, lane_hit);
      bool won = prims_packet_leaf(g, first, count, p, any, 0, lane_hit, found, t, u, v, prim, 0);
      if (won && any) {
        open = valid & ~packet_vload(found);
        if (!packet_any(open)) return valid;
      } else if (won) {
        tmax = packet_vload(t);
        reach = packet_max(packet_pick(valid, tmax, (pfloat)(-INFINITY)));
      }
    }
  } while (prims_walk_next(&w, any, reach, &node));
  return packet_vload(found);
}

/// The primitive tree with its instances for the lanes of `valid`:
/// bvh_prims_closest lane by lane, or with `any` bvh_prims_occluded. In:
/// lane arrays t (closest: the triangles' hits' distance or tmax, with u,
/// v, prim their hits; any: tmax), `index` the lanes' ray indices (the
/// alpha test's streams, for instanced triangles), skip_instance the
/// instance each lane's ray leaves, skip_b[l] (any; or none) a second
/// primitive lane l never meets at its start (the emitter it aims at).
/// Closest: narrowed hits, instance[l] the instance hit or WT_NO_HIT.
/// Returns the lanes narrowed, or blocked.
__attribute__((always_inline)) inline pint prims_packet_walk(BvhScene scene, GeometryScene g, const PrimPacket* p,
                                                             pint valid, bool any, const uint* index,
                                                             const uint* skip_b, const uint* skip_instance, float* t,
                                                             float* u, float* v, uint* prim, uint* instance) {
  if (g.header.node_count == 0 || !packet_any(valid)) return (pint)(0);
  pfloat tmax = packet_vload(t);
  pint open = valid;  // any: the lanes not blocked yet
  float reach = packet_max(packet_pick(valid, tmax, (pfloat)(-INFINITY)));
  int found[WT_PACKET];
  for (int l = 0; l < WT_PACKET; ++l) found[l] = 0;
  PrimWalk w;
  w.sp = 0, w.inner_count = 0;
  uint node = 0;
  do {
    __global const WtBvh4Node* n = &g.nodes[node & ~WT_BVH4_ORIENTED];
    bool framed = (node & WT_BVH4_ORIENTED) != 0;
    // most children are entered by some lane: ask for them all while the boxes are tested
    for (int k = 0; k < 4; ++k)
      if (n->child[k] != WT_BVH4_EMPTY) prims_prefetch_child(g, n->child[k], n->count[k]);
    FramePacket f;
    if (framed) prims_packet_frame(n, p, &f);
    for (int k = 0; k < 4; ++k) {
      uint first = n->child[k], count = n->count[k];
      if (first == WT_BVH4_EMPTY) continue;
      pfloat enter;
      pint hit = (framed ? packet_frame_box_hit(n, k, &f, p->box.tmin, tmax, &enter)
                         : packet_box_hit(n, k, &p->box, tmax, &enter)) & open;
      if (!packet_any(hit)) continue;
      if (count == 0) {
        prims_walk_push(&w, any, first, hit, enter);
        continue;
      }
      // lane_hit: the lanes that entered the leaf (any hit: and are not blocked yet)
      int lane_hit[WT_PACKET];
      packet_vstore(hit, lane_hit);
#if !WT_HAS_INSTANCES
      bool won = prims_packet_leaf(g, first, count, p, any, skip_b, lane_hit, found, t, u, v, prim, instance);
#else
      bool won = false;
      for (uint i = first; i < first + count; ++i) {
        uint id = g.refs[i];
        if (prim_type(id) == WT_PRIM_INSTANCE) {
          pint now;
          if (geometry_instance_info(g, id).y & WT_INSTANCE_PRIMITIVES) {
            // the packet goes on inside, in the copy's object space; a lane whose ray is not finite there is
            // dropped (closest) or blocked (any), as alone
            PrimPacket q;
            pint inside, not_finite;
            prims_packet_into_instance(g, id, p, lane_hit, skip_instance, &q, &inside, &not_finite);
            now = any ? not_finite : (pint)(0);
            if (packet_any(inside))
              now |= prims_packet_tree(g, geometry_instance_info(g, id).x, &q, inside, any, t, u, v, prim);
          } else {
            // a copy of triangles: the triangle packet in its object space
            now = any ? prims_packet_triangles_occluded(scene, g, id, p, lane_hit, index, skip_instance, t)
                      : prims_packet_triangles_closest(scene, g, id, p, lane_hit, index, skip_instance, t, u, v, prim);
          }
          if (!packet_any(now)) continue;
          int lane_now[WT_PACKET];
          packet_vstore(now, lane_now);
          for (int l = 0; l < WT_PACKET; ++l) {
            if (!lane_now[l]) continue;
            found[l] = -1;
            if (any) lane_hit[l] = 0;
            else instance[l] = id;
          }
          won = true;
          continue;
        }
        won |= prims_packet_leaf(g, i, 1u, p, any, skip_b, lane_hit, found, t, u, v, prim, instance);
      }
#endif
      if (won && any) {
        open = valid & ~packet_vload(found);
        if (!packet_any(open)) return valid;
      } else if (won) {
        tmax = packet_vload(t);
        reach = packet_max(packet_pick(valid, tmax, (pfloat)(-INFINITY)));
      }
    }
  } while (prims_walk_next(&w, any, reach, &node));
  return packet_vload(found);
}

/// The rays index[0..lanes) of ray_o / ray_d as a scene-space PrimPacket
/// leaving skip_a[index[l]] (or skip_ab[..].x), and the mask of the real
/// lanes whose rays are finite (bvh_prims_closest's and _occluded's first test).
inline pint prims_packet_load(PrimPacket* p, const uint* index, uint lanes, __global const float4* ray_o,
                              __global const float4* ray_d, __global const uint* skip_a,
                              __global const uint2* skip_ab, float* tmax, uint* skip_b) {
  int in[WT_PACKET];
  for (uint l = 0; l < WT_PACKET; ++l) {
    uint i = index[min(l, lanes - 1u)];
    float4 o = ray_o[i], d = ray_d[i];
    uint2 ab = skip_ab ? skip_ab[i] : (uint2)(skip_a[i], WT_NO_HIT);
    bool finite = l < lanes && bvh_ray_is_finite(o.xyz, d.xyz);
    if (finite) {
      prims_packet_set(p, l, o.xyz, d.xyz, o.w, ab.x);
    } else {
      prims_packet_set(p, l, (float3)(0.0f), (float3)(0.0f, 0.0f, 1.0f), 0.0f, WT_NO_HIT);
    }
    tmax[l] = d.w;
    skip_b[l] = ab.y;
    in[l] = finite ? -1 : 0;
  }
  prims_packet_finish(p);
  return packet_vload(in);
}

/// After the triangles' packet (packet_trace_closest wrote hits[index[l]]):
/// those hits narrowed by the other primitives, lane l's ray index[l]
/// leaving skip[index[l]] on instance hit_instance[index[l]] (WT_NO_HIT, or
/// no buffer: none, and none written), which then names the instance hit. A hit is rewritten
/// only where it changed or an instance was hit (the same stores as
/// extend's lane-by-lane loop made).
inline void prims_packet_trace_closest(BvhScene scene, GeometryScene g, const uint* index, uint lanes,
                                       __global const float4* ray_o, __global const float4* ray_d,
                                       __global const uint* skip, __global uint* hit_instance,
                                       __global float4* hits) {
  PrimPacket p;
  float t[WT_PACKET], u[WT_PACKET], v[WT_PACKET], tmax[WT_PACKET];
  uint prim[WT_PACKET], instance[WT_PACKET], skip_instance[WT_PACKET], before[WT_PACKET], unused[WT_PACKET];
  pint valid = prims_packet_load(&p, index, lanes, ray_o, ray_d, skip, 0, tmax, unused);
  for (uint l = 0; l < WT_PACKET; ++l) {
    uint i = index[min(l, lanes - 1u)];
    float4 h = hits[i];
    t[l] = h.x, u[l] = h.y, v[l] = h.z, prim[l] = before[l] = as_uint(h.w);
    instance[l] = WT_NO_HIT;
    skip_instance[l] = hit_instance ? hit_instance[i] : WT_NO_HIT;
  }
  prims_packet_walk(scene, g, &p, valid, false, index, 0, skip_instance, t, u, v, prim, instance);
  for (uint l = 0; l < lanes; ++l) {
    uint i = index[l];
    if (hit_instance) hit_instance[i] = instance[l];
    if (prim[l] != before[l] || instance[l] != WT_NO_HIT) hits[i] = (float4)(t[l], u[l], v[l], as_float(prim[l]));
  }
}

/// After the triangles' packet: blocked[l] (non-zero where a triangle
/// blocks ray index[l]) set for the lanes a primitive blocks, lane l
/// leaving skip_a[index[l]] or skip_ab[index[l]] on instance
/// hit_instance[index[l]].
inline void prims_packet_trace_occluded(BvhScene scene, GeometryScene g, const uint* index, uint lanes,
                                        __global const float4* ray_o, __global const float4* ray_d,
                                        __global const uint* skip_a, __global const uint2* skip_ab,
                                        __global const uint* hit_instance, int* blocked) {
  bool any_open = false;
  for (uint l = 0; l < lanes; ++l) any_open = any_open || !blocked[l];
  if (!any_open || g.header.node_count == 0) return;
#if WT_HAS_CURVES && !WT_HAS_INSTANCES
  // flat curves: each ray alone, as bvh_prims_occluded (shadow rays through
  // dense hair part at once; the packet's box tests then cost more than the
  // lanes share)
  for (uint l = 0; l < lanes; ++l) {
    if (blocked[l]) continue;
    uint i = index[l];
    float4 o = ray_o[i], d = ray_d[i];
    uint2 ab = skip_ab ? skip_ab[i] : (uint2)(skip_a[i], WT_NO_HIT);
    if (bvh_prims_occluded(scene, g, o.xyz, d.xyz, o.w, d.w, ab.x, ab.y, WT_NO_HIT)) blocked[l] = -1;
  }
  return;
#endif
  PrimPacket p;
  float tmax[WT_PACKET];
  uint skip_b[WT_PACKET], skip_instance[WT_PACKET];
  int open[WT_PACKET];
  pint finite = prims_packet_load(&p, index, lanes, ray_o, ray_d, skip_a, skip_ab, tmax, skip_b);
  for (uint l = 0; l < WT_PACKET; ++l) {
    uint i = index[min(l, lanes - 1u)];
    skip_instance[l] = hit_instance ? hit_instance[i] : WT_NO_HIT;
    open[l] = l < lanes && !blocked[l] ? -1 : 0;
  }
  pint todo = packet_vload(open);
  // a lane whose ray is not finite counts as blocked, as in bvh_prims_occluded
  pint now = (todo & ~finite) |
             prims_packet_walk(scene, g, &p, todo & finite, true, index, skip_b, skip_instance, tmax, 0, 0, 0, 0);
  int lane_now[WT_PACKET];
  packet_vstore(now, lane_now);
  for (uint l = 0; l < lanes; ++l)
    if (lane_now[l]) blocked[l] = -1;
}

#endif  // WT_HAS_PRIMITIVES

#endif  // WT_BVH_PRIMS_PACKET_CL
