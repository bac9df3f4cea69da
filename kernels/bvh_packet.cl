// Packet traversal: one work-item traces WT_PACKET_WIDTH rays (8 or 16, the
// device's native float vector width: packetWidthFor in host/device/program.h)
// through the 4-wide BVH together, one ray per lane of a float8 or float16.
// A node's child box is tested against all the rays at once, and a leaf
// triangle with the watertight test on all the lanes. Each lane makes the
// same decisions, with the same arithmetic,
// as bvh_closest / bvh_occluded would for its ray alone (only the order in
// which nodes are visited differs, so of two hits at exactly the same
// distance another may win). PoCL vectorises inside a work-item, never
// across the work-items of a loop like this one, so lanes are where coherent
// rays (camera rays, shadow rays from neighbouring pixels) share the cost of
// fetching and testing a node.
//
// Lanes are the watertight test's, whose axis permutation needs only each
// ray's dominant axis kz: swapping the other two (triangle_ray_shear's flip
// where d[kz] < 0) negates u, v, w, det and the scaled t alike, so t, b1 and
// b2 come out bit for bit the same without it. A packet whose lanes agree on
// kz loads each corner's coordinates by its row; one whose lanes do not
// picks each lane's own in one pass (packet_triangle), so incoherent rays
// (every bounce's extend, shadow rays) trace in one pass, not one per
// permutation.
#ifndef WT_BVH_PACKET_CL
#define WT_BVH_PACKET_CL

#include "bvh.cl"

#ifdef __clang__
// float16 builtins (vload16, shuffle2) on an AVX2 CPU: clang warns that the
// 16-wide vector ABI differs without AVX-512, which no caller here depends on
#pragma clang diagnostic ignored "-Wpsabi"
#endif

#define WT_PACKET WT_PACKET_WIDTH
#if WT_PACKET == 8
#define pfloat float8
#define pint int8
#define puint uint8
#define as_pfloat as_float8
#define as_pint as_int8
#define as_puint as_uint8
#define packet_vload(a) vload8(0, a)
#define packet_vstore(v, a) vstore8(v, 0, a)
#elif WT_PACKET == 16
#define pfloat float16
#define pint int16
#define puint uint16
#define as_pfloat as_float16
#define as_pint as_int16
#define as_puint as_uint16
#define packet_vload(a) vload16(0, a)
#define packet_vstore(v, a) vstore16(v, 0, a)
#else
#error "WT_PACKET_WIDTH must be 8 or 16 (packetWidthFor, host/device/program.h)"
#endif
// A leaf that at most this many lanes enter is tested lane by lane, four
// triangles at a time (bvh_closest's and bvh_occluded's leaf test), instead
// of one triangle at a time on every lane (WT_PACKET_LEAF_LANES, declared in
// switches.h). Packets of 8 only: they are the width of large scenes and of
// 8-wide devices (packetWidthFor), so leaves are small against a packet's
// footprint; with packets of 16 it did not pay
// (docs/lab/2026-12-04-performance-log.md, "Leaves that few lanes enter").

/// Lane masks normalised to all ones or zero. Comparisons are folded with
/// this before any select or ~, never trusted for their sign bit:
/// Oclgrind's optimised build makes some vector comparisons 1 instead of -1.
inline pint packet_mask(pint c) { return (c | -c) >> 31; }
// Reductions over the lanes: halves folded down to one float8 / int8 first.
// Minima and maxima compare and pick instead of calling fmin / fmax: no lane
// reduced holds a NaN (the lanes left out carry +-inf), and fmin's NaN rules
// cost extra compares in every reduction of the traversal
// (docs/lab/2026-12-04-performance-log.md, "The cheap rays' overhead").
// Under Oclgrind (WT_FOLD_THROUGH_MEMORY, set by the host) the 16 lanes go
// through private memory instead of .hi: Oclgrind 21.10 loses the upper
// half's initialisation on .hi of a 16-wide vector in an unoptimised build
// (tests/oclgrind/upper_half.cl). On PoCL .hi is the faster of the two
// (docs/lab/2026-12-01-performance-log.md, "Sixteen lanes").
#if WT_PACKET == 16 && defined(WT_FOLD_THROUGH_MEMORY) && WT_FOLD_THROUGH_MEMORY
inline int8 packet_fold8_i(int16 m) {
  int t[16];
  vstore16(m, 0, t);
  return vload8(0, t) | vload8(1, t);
}
inline float8 packet_fold8_min(float16 v) {
  float t[16];
  vstore16(v, 0, t);
  float8 a = vload8(0, t), b = vload8(1, t);
  return a < b ? a : b;
}
inline float8 packet_fold8_max(float16 v) {
  float t[16];
  vstore16(v, 0, t);
  float8 a = vload8(0, t), b = vload8(1, t);
  return a > b ? a : b;
}
#elif WT_PACKET == 16
#define packet_fold8_i(m) ((m).lo | (m).hi)
#define packet_fold8_min(v) ((v).lo < (v).hi ? (v).lo : (v).hi)
#define packet_fold8_max(v) ((v).lo > (v).hi ? (v).lo : (v).hi)
#else
#define packet_fold8_i(m) (m)
#define packet_fold8_min(v) (v)
#define packet_fold8_max(v) (v)
#endif
inline bool packet_any(pint m) {
  int8 m8 = packet_fold8_i(m);
  int4 a = m8.lo | m8.hi;
  int2 b = a.lo | a.hi;
  return (b.x | b.y) != 0;
}
/// How many lanes a normalised mask holds.
inline int packet_count(pint m) {
  pint ones = -m;
#if WT_PACKET == 16
  int8 m8 = ones.lo + ones.hi;
#else
  int8 m8 = ones;
#endif
  int4 a = m8.lo + m8.hi;
  int2 b = a.lo + a.hi;
  return b.x + b.y;
}
inline float packet_min(pfloat v) {
  float8 v8 = packet_fold8_min(v);
  float4 a = v8.lo < v8.hi ? v8.lo : v8.hi;
  float2 b = a.lo < a.hi ? a.lo : a.hi;
  return b.x < b.y ? b.x : b.y;
}
inline float packet_max(pfloat v) {
  float8 v8 = packet_fold8_max(v);
  float4 a = v8.lo > v8.hi ? v8.lo : v8.hi;
  float2 b = a.lo > a.hi ? a.lo : a.hi;
  return b.x > b.y ? b.x : b.y;
}
inline pfloat packet_vmax(pfloat a, pfloat b) { return a > b ? a : b; }
inline pfloat packet_vmin(pfloat a, pfloat b) { return a < b ? a : b; }
inline pfloat packet_pick(pint m, pfloat yes, pfloat no) { return as_pfloat((as_pint(yes) & m) | (as_pint(no) & ~m)); }
inline puint packet_pick_u(pint m, puint yes, puint no) { return (yes & as_puint(m)) | (no & ~as_puint(m)); }

/// The rays of one packet, lane by lane: origins and reciprocal directions
/// per axis, the shared axis permutation with each lane's shear, and the
/// interval each lane searches.
typedef struct RayPacket {
  pfloat o[3];       ///< origin per world axis
  pfloat inv_d[3];   ///< bvh_safe_rcp of the direction per world axis
  pfloat o_kx, o_ky, o_kz;  ///< the origin along the permuted axes
  pfloat sx, sy, sz; ///< each lane's shear (RayShear, never flipped)
  pint kz_is_x, kz_is_y;  ///< each lane's dominant axis kz (z where neither)
  int per_lane;      ///< the valid lanes disagree on kz: each picks its own corners
  int kx, ky, kz;    ///< the permutation every lane shares (unless per_lane)
  pfloat tmin;
  puint skip_a, skip_b;  ///< leaf-order triangles a lane never hits
#if WT_HAS_ALPHA
  puint alpha_ray;  ///< each lane's stream for the alpha test (AlphaScene::ray)
#endif
} RayPacket;

/// Slab test of child k's box against every lane: a mask of the lanes whose
/// (tmin, tmax) interval overlaps it, with their entry distances. The same
/// products as bvh4_box_hit: min/max of the two planes' distances equal its
/// sign-picked near and far distances (an empty slot is never tested).
inline pint packet_box_hit(__global const WtBvh4Node* n, int k, const RayPacket* p, pfloat tmax, pfloat* enter) {
  pfloat t0x = (n->lo_x[k] - p->o[0]) * p->inv_d[0], t1x = (n->hi_x[k] - p->o[0]) * p->inv_d[0];
  pfloat t0y = (n->lo_y[k] - p->o[1]) * p->inv_d[1], t1y = (n->hi_y[k] - p->o[1]) * p->inv_d[1];
  pfloat t0z = (n->lo_z[k] - p->o[2]) * p->inv_d[2], t1z = (n->hi_z[k] - p->o[2]) * p->inv_d[2];
  // no NaN in a valid lane (see bvh_max); the others are masked out below
  pfloat tn = packet_vmax(packet_vmax(packet_vmin(t0x, t1x), packet_vmin(t0y, t1y)), packet_vmax(packet_vmin(t0z, t1z), p->tmin));
  pfloat tf = packet_vmin(packet_vmin(packet_vmax(t0x, t1x), packet_vmax(t0y, t1y)), packet_vmax(t0z, t1z)) * 1.00000036f;
  tf = packet_vmin(tf, tmax);
  *enter = tn;
  return packet_mask(tn <= tf);
}

/// Slab test of the box around the root's four children against every lane:
/// a lane that misses it misses each of them (the planes' distances are
/// monotonic in the plane, so the union's interval holds each child's).
inline pint packet_scene_hit(__global const WtBvh4Node* root, const RayPacket* p, pfloat tmax) {
  float4 lx = vload4(0, root->lo_x), hx = vload4(0, root->hi_x);
  float4 ly = vload4(0, root->lo_y), hy = vload4(0, root->hi_y);
  float4 lz = vload4(0, root->lo_z), hz = vload4(0, root->hi_z);
  // an empty slot's inverted box (lo +inf, hi -inf) drops out of both
  float lo_x = min(min(lx.s0, lx.s1), min(lx.s2, lx.s3)), hi_x = max(max(hx.s0, hx.s1), max(hx.s2, hx.s3));
  float lo_y = min(min(ly.s0, ly.s1), min(ly.s2, ly.s3)), hi_y = max(max(hy.s0, hy.s1), max(hy.s2, hy.s3));
  float lo_z = min(min(lz.s0, lz.s1), min(lz.s2, lz.s3)), hi_z = max(max(hz.s0, hz.s1), max(hz.s2, hz.s3));
  pfloat t0x = (lo_x - p->o[0]) * p->inv_d[0], t1x = (hi_x - p->o[0]) * p->inv_d[0];
  pfloat t0y = (lo_y - p->o[1]) * p->inv_d[1], t1y = (hi_y - p->o[1]) * p->inv_d[1];
  pfloat t0z = (lo_z - p->o[2]) * p->inv_d[2], t1z = (hi_z - p->o[2]) * p->inv_d[2];
  pfloat tn = packet_vmax(packet_vmax(packet_vmin(t0x, t1x), packet_vmin(t0y, t1y)), packet_vmax(packet_vmin(t0z, t1z), p->tmin));
  pfloat tf = packet_vmin(packet_vmin(packet_vmax(t0x, t1x), packet_vmax(t0y, t1y)), packet_vmax(t0z, t1z)) * 1.00000036f;
  tf = packet_vmin(tf, tmax);
  return packet_mask(tn <= tf);
}

/// The watertight test of triangle `prim` on every lane in `lanes`: the mask
/// of lanes that hit it in (tmin, tmax), with distance and barycentrics.
/// triangle_intersect's operations in its order, lane by lane.
__attribute__((always_inline)) inline pint packet_triangle(const RayPacket* p, __global const float4* tri_verts, uint prim, pint lanes,
                            pfloat tmax, pfloat* t_hit, pfloat* b1, pfloat* b2) {
  // the block layout (WT_TRIANGLE_BLOCK) gives each corner's coordinate on
  // the packet's permuted axes by one load: row 3 k + axis of the block
  __global const float* f = triangle_block_lane(tri_verts, prim);
  pfloat ax0, ay0, az, bx0, by0, bz, cx0, cy0, cz;
  if (p->per_lane) {
    // each lane's own permutation: two blends per coordinate (coherent
    // packets keep the row loads below, which cost less)
    const pint zx = p->kz_is_x, zy = p->kz_is_y;
#define WT_CORNER(c, X, Y, Z)                                                          \
  {                                                                                    \
    pfloat vx = (pfloat)(f[c]), vy = (pfloat)(f[c + 4]), vz = (pfloat)(f[c + 8]);      \
    Z = packet_pick(zx, vx, packet_pick(zy, vy, vz)) - p->o_kz;                        \
    X = packet_pick(zx, vy, packet_pick(zy, vz, vx)) - p->o_kx;                        \
    Y = packet_pick(zx, vz, packet_pick(zy, vx, vy)) - p->o_ky;                        \
  }
    WT_CORNER(0, ax0, ay0, az) WT_CORNER(12, bx0, by0, bz) WT_CORNER(24, cx0, cy0, cz)
#undef WT_CORNER
  } else {
    const int ox = 4 * p->kx, oy = 4 * p->ky, oz = 4 * p->kz;
    az = f[oz] - p->o_kz, bz = f[12 + oz] - p->o_kz, cz = f[24 + oz] - p->o_kz;
    ax0 = f[ox] - p->o_kx, ay0 = f[oy] - p->o_ky;
    bx0 = f[12 + ox] - p->o_kx, by0 = f[12 + oy] - p->o_ky;
    cx0 = f[24 + ox] - p->o_kx, cy0 = f[24 + oy] - p->o_ky;
  }
  pfloat ax = ax0 - p->sx * az;
  pfloat ay = ay0 - p->sy * az;
  pfloat bx = bx0 - p->sx * bz;
  pfloat by = by0 - p->sy * bz;
  pfloat cx = cx0 - p->sx * cz;
  pfloat cy = cy0 - p->sy * cz;

  pfloat u = cx * by - cy * bx;
  pfloat v = ax * cy - ay * cx;
  pfloat w = bx * ay - by * ax;
#if WT_HAS_FP64
  pint zero = packet_mask((u == 0.0f) | (v == 0.0f) | (w == 0.0f)) & lanes;
  if (packet_any(zero)) {
    // exactly-zero edge functions decided in double, lane by lane (rare)
    float lu[WT_PACKET], lv[WT_PACKET], lw[WT_PACKET], lax[WT_PACKET], lay[WT_PACKET], lbx[WT_PACKET], lby[WT_PACKET], lcx[WT_PACKET], lcy[WT_PACKET];
    packet_vstore(u, lu), packet_vstore(v, lv), packet_vstore(w, lw);
    packet_vstore(ax, lax), packet_vstore(ay, lay), packet_vstore(bx, lbx);
    packet_vstore(by, lby), packet_vstore(cx, lcx), packet_vstore(cy, lcy);
    for (int l = 0; l < WT_PACKET; ++l) {
      if (lu[l] == 0.0f || lv[l] == 0.0f || lw[l] == 0.0f) {
        lu[l] = (float)((double)lcx[l] * (double)lby[l] - (double)lcy[l] * (double)lbx[l]);
        lv[l] = (float)((double)lax[l] * (double)lcy[l] - (double)lay[l] * (double)lcx[l]);
        lw[l] = (float)((double)lbx[l] * (double)lay[l] - (double)lby[l] * (double)lax[l]);
      }
    }
    u = packet_vload(lu), v = packet_vload(lv), w = packet_vload(lw);
  }
#endif
  pint inside = packet_mask(((u >= 0.0f) & (v >= 0.0f) & (w >= 0.0f)) | ((u <= 0.0f) & (v <= 0.0f) & (w <= 0.0f)));
  pfloat det = u + v + w;
  pfloat t_scaled = u * p->sz * az + v * p->sz * bz + w * p->sz * cz;
  pfloat inv_det = 1.0f / det;
  pfloat t = t_scaled * inv_det;
  pint ok = lanes & inside & packet_mask((det != 0.0f) & (t > p->tmin) & (t < tmax)) &
            packet_mask(((puint)(prim) != p->skip_a) & ((puint)(prim) != p->skip_b));
  *t_hit = t;
  *b1 = v * inv_det;
  *b2 = w * inv_det;
  return ok;
}

/// What packet_load found: a packet to trace, or (where the caller asks)
/// rays that all miss the scene.
#define WT_PACKET_TRACE 0
#define WT_PACKET_MISSES 2

/// Whether a packet's lanes are rays index[0], index[0] + 1, ... of a batch,
/// every lane real: their rays and skip triangles are loaded as whole
/// vectors then.
inline bool packet_contiguous(const uint* index, uint lanes) {
  bool contiguous = lanes == WT_PACKET;
  for (uint l = 1; l < WT_PACKET; ++l) contiguous = contiguous && index[l] == index[0] + l;
  return contiguous;
}

/// The axis permutation every lane's triangle test uses: dominant axis kz,
/// kx = kz + 1 and ky = kz + 2 (mod 3), never flipped (a negative kz, no
/// lane, takes z).
inline void packet_permute(RayPacket* p, int pkz) {
  if (pkz < 0) pkz = 2;
  int pkx = pkz == 2 ? 0 : pkz + 1;
  int pky = pkx == 2 ? 0 : pkx + 1;
  p->kx = pkx, p->ky = pky, p->kz = pkz;
  p->o_kx = pkx == 0 ? p->o[0] : (pkx == 1 ? p->o[1] : p->o[2]);
  p->o_ky = pky == 0 ? p->o[0] : (pky == 1 ? p->o[1] : p->o[2]);
  p->o_kz = pkz == 0 ? p->o[0] : (pkz == 1 ? p->o[1] : p->o[2]);
}

__attribute__((always_inline)) inline int packet_load_lanes(RayPacket* p, pint* valid, pfloat* tmax,
                                                           pfloat vox, pfloat voy, pfloat voz, pfloat vtn, pfloat vdx,
                                                           pfloat vdy, pfloat vdz, pfloat vtx, pint in_v,
                                                           const BvhScene* root);

/// Loads a packet: lane l takes ray index[l] of a batch (o.w = tmin,
/// d.w = tmax) for l < lanes; the other lanes, and lanes whose ray is not
/// finite, are left out of `valid`. Each lane's shear is its own ray's
/// (triangle_ray_shear without the flip), with its dominant axis; where the
/// valid lanes share one, the packet's permutation is set to it, else
/// per_lane. Returns WT_PACKET_TRACE; with `root` (the scene; closest hits),
/// first WT_PACKET_MISSES when no valid lane enters the box around the
/// root's children, with only the rays' origins, intervals (tmax the misses'
/// distances) and reciprocal directions set.
__attribute__((always_inline)) inline int packet_load(RayPacket* p, pint* valid, pfloat* tmax,
                                                     const uint* index, uint lanes, bool contiguous,
                                                     __global const float4* ray_o, __global const float4* ray_d,
                                                     const BvhScene* root) {
  // The rays in lanes: origin, tmin, direction, tmax, and whether each lane
  // is in (a real lane with a finite ray)
  pfloat vox, voy, voz, vtn, vdx, vdy, vdz, vtx;
  pint in_v;
  if (contiguous) {
    // consecutive rays: whole vectors loaded and transposed
    __global const float* fo = (__global const float*)(ray_o + index[0]);
    __global const float* fd = (__global const float*)(ray_d + index[0]);
    // each row of four floats one ray: component c of the rays is every
    // fourth float from c
#if WT_PACKET == 8
    const float16 o0 = vload16(0, fo), o1 = vload16(1, fo), d0 = vload16(0, fd), d1 = vload16(1, fd);
#define WT_TRANSPOSE(v0, v1, c, out) out = shuffle2(v0, v1, (uint8)(c, c + 4, c + 8, c + 12, c + 16, c + 20, c + 24, c + 28));
    WT_TRANSPOSE(o0, o1, 0u, vox) WT_TRANSPOSE(o0, o1, 1u, voy) WT_TRANSPOSE(o0, o1, 2u, voz) WT_TRANSPOSE(o0, o1, 3u, vtn)
    WT_TRANSPOSE(d0, d1, 0u, vdx) WT_TRANSPOSE(d0, d1, 1u, vdy) WT_TRANSPOSE(d0, d1, 2u, vdz) WT_TRANSPOSE(d0, d1, 3u, vtx)
#else
    // two halves blended rather than joined as (float16)(lo, hi): the join
    // crashes Oclgrind's unoptimised build (tests/oclgrind/join_halves.cl)
    const float16 o0 = vload16(0, fo), o1 = vload16(1, fo), o2 = vload16(2, fo), o3 = vload16(3, fo);
    const float16 d0 = vload16(0, fd), d1 = vload16(1, fd), d2 = vload16(2, fd), d3 = vload16(3, fd);
    const pint kLowHalf = (pint)(-1, -1, -1, -1, -1, -1, -1, -1, 0, 0, 0, 0, 0, 0, 0, 0);
#define WT_TRANSPOSE(v0, v1, v2, v3, c, out)                                                                    \
  {                                                                                                             \
    const uint16 m = (uint16)(c, c + 4, c + 8, c + 12, c + 16, c + 20, c + 24, c + 28, c, c + 4, c + 8, c + 12, \
                              c + 16, c + 20, c + 24, c + 28);                                                  \
    out = packet_pick(kLowHalf, shuffle2(v0, v1, m), shuffle2(v2, v3, m));                                      \
  }
    WT_TRANSPOSE(o0, o1, o2, o3, 0u, vox) WT_TRANSPOSE(o0, o1, o2, o3, 1u, voy)
    WT_TRANSPOSE(o0, o1, o2, o3, 2u, voz) WT_TRANSPOSE(o0, o1, o2, o3, 3u, vtn)
    WT_TRANSPOSE(d0, d1, d2, d3, 0u, vdx) WT_TRANSPOSE(d0, d1, d2, d3, 1u, vdy)
    WT_TRANSPOSE(d0, d1, d2, d3, 2u, vdz) WT_TRANSPOSE(d0, d1, d2, d3, 3u, vtx)
#endif
#undef WT_TRANSPOSE
    in_v = packet_mask(isfinite(vox)) & packet_mask(isfinite(voy)) & packet_mask(isfinite(voz)) &
           packet_mask(isfinite(vdx)) & packet_mask(isfinite(vdy)) & packet_mask(isfinite(vdz));
  } else {
    int in[WT_PACKET];
    float ox[WT_PACKET], oy[WT_PACKET], oz[WT_PACKET], tn[WT_PACKET];
    float dx[WT_PACKET], dy[WT_PACKET], dz[WT_PACKET], tx[WT_PACKET];
    for (uint l = 0; l < WT_PACKET; ++l) {
      uint i = index[min(l, lanes - 1u)];
      float4 o = ray_o[i], d = ray_d[i];
      ox[l] = o.x, oy[l] = o.y, oz[l] = o.z, tn[l] = o.w;
      dx[l] = d.x, dy[l] = d.y, dz[l] = d.z, tx[l] = d.w;
      // bvh_ray_is_finite without its branches
      int4 finite = isfinite(o) & isfinite(d);
      in[l] = l < lanes && (finite.x & finite.y & finite.z) != 0 ? -1 : 0;
    }
    vox = packet_vload(ox), voy = packet_vload(oy), voz = packet_vload(oz), vtn = packet_vload(tn);
    vdx = packet_vload(dx), vdy = packet_vload(dy), vdz = packet_vload(dz), vtx = packet_vload(tx);
    in_v = packet_vload(in);
  }
  return packet_load_lanes(p, valid, tmax, vox, voy, voz, vtn, vdx, vdy, vdz, vtx, in_v, root);
}

/// packet_load from the rays already in lanes (origin, tmin, direction,
/// tmax per axis; in_v the lanes to trace, whose rays are finite): also the
/// entry for rays moved into an instance's object space
/// (kernels/bvh_prims_packet.cl), with no `root`.
__attribute__((always_inline)) inline int packet_load_lanes(RayPacket* p, pint* valid, pfloat* tmax,
                                                           pfloat vox, pfloat voy, pfloat voz, pfloat vtn, pfloat vdx,
                                                           pfloat vdy, pfloat vdz, pfloat vtx, pint in_v,
                                                           const BvhScene* root) {
  // Each lane's dominant axis kz, in lanes: triangle_ray_shear's (x over y
  // over z on ties, as there); a lane left out traces (0, 0, 1), as
  // bvh_closest would never see it
  pfloat ux = packet_pick(in_v, vdx, (pfloat)(0.0f));
  pfloat uy = packet_pick(in_v, vdy, (pfloat)(0.0f));
  pfloat uz = packet_pick(in_v, vdz, (pfloat)(1.0f));
  pfloat adx = fabs(ux), ady = fabs(uy), adz = fabs(uz);
  pint kz_is_x = packet_mask(adx > ady) & packet_mask(adx > adz);
  pint kz_is_y = packet_mask(adx <= ady) & packet_mask(ady > adz);
  pfloat codef = packet_pick(kz_is_x, (pfloat)(0.0f), packet_pick(kz_is_y, (pfloat)(1.0f), (pfloat)(2.0f)));
  p->o[0] = vox, p->o[1] = voy, p->o[2] = voz;
  p->tmin = vtn;
  *tmax = vtx;
  *valid = in_v;
  // bvh_safe_rcp, lane by lane
  const float kTiny = 1e-30f;
  pfloat d[3] = {ux, uy, uz};
  for (int k = 0; k < 3; ++k)
    p->inv_d[k] = 1.0f / packet_pick(packet_mask(fabs(d[k]) < kTiny), copysign((pfloat)(kTiny), d[k]), d[k]);
  if (root) {
    // Camera rays that miss the scene's box (most of the view of a small
    // object) end here, before the triangle test's set-up.
    if (root->node_count == 0) return WT_PACKET_MISSES;
    if (!packet_any(packet_scene_hit((__global const WtBvh4Node*)root->nodes, p, *tmax) & in_v))
      return WT_PACKET_MISSES;
  }

  // triangle_ray_shear, lane by lane, with each lane's permutation
  // (the axis masks used as they are: integer arithmetic on them came out
  // wrong under Oclgrind's optimised build, tests/oclgrind/mask_arithmetic.cl)
  pfloat dk_z = packet_pick(kz_is_x, d[0], packet_pick(kz_is_y, d[1], d[2]));
  // kx = kz + 1 and ky = kz + 2 (mod 3), never swapped (see the top)
  pfloat d_next = packet_pick(kz_is_x, d[1], packet_pick(kz_is_y, d[2], d[0]));
  pfloat d_after = packet_pick(kz_is_x, d[2], packet_pick(kz_is_y, d[0], d[1]));
  p->sx = d_next / dk_z;
  p->sy = d_after / dk_z;
  p->sz = 1.0f / dk_z;
  p->skip_a = p->skip_b = (puint)(WT_NO_HIT);
  p->kz_is_x = kz_is_x, p->kz_is_y = kz_is_y;

  float code_lo = packet_min(packet_pick(in_v, codef, (pfloat)(99.0f)));
  float code_hi = packet_max(packet_pick(in_v, codef, (pfloat)(-1.0f)));
  p->per_lane = code_hi >= 0.0f && code_lo != code_hi;
  if (!p->per_lane) {
    packet_permute(p, (int)code_hi);
  } else {
    p->o_kz = packet_pick(kz_is_x, vox, packet_pick(kz_is_y, voy, voz));
    p->o_kx = packet_pick(kz_is_x, voy, packet_pick(kz_is_y, voz, vox));
    p->o_ky = packet_pick(kz_is_x, voz, packet_pick(kz_is_y, vox, voy));
  }
  return WT_PACKET_TRACE;
}

/// The triangles each lane never hits (the surface its ray leaves, the
/// emitter a shadow ray aims at), lane l from skip[index[l]].
inline void packet_set_skip(RayPacket* p, const uint* index, uint lanes, bool contiguous,
                            __global const uint* skip_a, __global const uint2* skip_ab) {
  if (contiguous && !skip_ab) {
    p->skip_a = packet_vload(skip_a + index[0]);
    p->skip_b = (puint)(WT_NO_HIT);
    return;
  }
  uint a[WT_PACKET], b[WT_PACKET];
  for (uint l = 0; l < WT_PACKET; ++l) {
    uint i = index[min(l, lanes - 1u)];
    uint2 ab = skip_ab ? skip_ab[i] : (uint2)(skip_a[i], WT_NO_HIT);
    a[l] = ab.x, b[l] = ab.y;
  }
  p->skip_a = packet_vload(a);
  p->skip_b = packet_vload(b);
}

#if WT_HAS_ALPHA
/// Each lane's stream for the alpha test: the one its ray has traced alone
/// (WT_ALPHA_RAY of its index), so that both decide the same.
inline void packet_set_alpha(RayPacket* p, BvhScene scene, const uint* index) {
  uint ray[WT_PACKET];
  for (uint l = 0; l < WT_PACKET; ++l) ray[l] = rng_alpha_ray(scene.alpha.key, index[l]);
  p->alpha_ray = packet_vload(ray);
}

/// The lanes of `won` (hits on triangle `prim` at barycentrics b1, b2) that
/// the alpha test keeps: all of them unless the triangle is flagged. A lane
/// dropped goes on as if the triangle were not there, as alone (each
/// triangle of a leaf is tested on its own here, so no other candidate is
/// lost with it).
inline pint packet_alpha_keep(BvhScene scene, const RayPacket* p, uint prim, pint won, pfloat b1, pfloat b2) {
  if (!alpha_flagged(scene.alpha, prim)) return won;
  // the triangle's part once; a uniform coverage (the factor alone) is the same for every lane
  AlphaTriangle tri = alpha_triangle(scene.alpha, prim);
  const bool uniform = alpha_uniform(tri);
  const float uniform_coverage = tri.m.factor;
  if (uniform && tri.m.mode == WT_ALPHA_MASK) return uniform_coverage >= tri.m.cutoff ? won : (pint)(0);
  int lane_won[WT_PACKET];
  float lane_b1[WT_PACKET], lane_b2[WT_PACKET];
  uint ray[WT_PACKET];
  packet_vstore(won, lane_won), packet_vstore(b1, lane_b1), packet_vstore(b2, lane_b2);
  packet_vstore(p->alpha_ray, ray);
  for (int l = 0; l < WT_PACKET; ++l) {
    if (!lane_won[l]) continue;
    scene.alpha.ray = ray[l];
    float coverage = uniform ? uniform_coverage : alpha_coverage(scene.alpha, tri, lane_b1[l], lane_b2[l]);
    if (!alpha_covered(scene.alpha, tri, prim, coverage)) lane_won[l] = 0;
  }
  return packet_vload(lane_won);
}
#endif

#if WT_PACKET_LEAF_LANES > 0
/// Each lane's ray as scalars, for the leaves that few lanes enter.
typedef struct PacketLanes {
  float ox[WT_PACKET], oy[WT_PACKET], oz[WT_PACKET];
  float sx[WT_PACKET], sy[WT_PACKET], sz[WT_PACKET];
  float tmin[WT_PACKET];
  uint skip_a[WT_PACKET], skip_b[WT_PACKET];
  int kz_is_x[WT_PACKET], kz_is_y[WT_PACKET];
#if WT_HAS_ALPHA
  AlphaScene alpha;  ///< the scene's alpha test (the lanes' streams in alpha_ray)
  uint alpha_ray[WT_PACKET];
#endif
} PacketLanes;

inline void packet_lanes(const RayPacket* p, PacketLanes* lanes) {
  packet_vstore(p->o[0], lanes->ox), packet_vstore(p->o[1], lanes->oy), packet_vstore(p->o[2], lanes->oz);
  packet_vstore(p->sx, lanes->sx), packet_vstore(p->sy, lanes->sy), packet_vstore(p->sz, lanes->sz);
  packet_vstore(p->tmin, lanes->tmin);
  packet_vstore(p->skip_a, lanes->skip_a), packet_vstore(p->skip_b, lanes->skip_b);
  packet_vstore(p->kz_is_x, lanes->kz_is_x), packet_vstore(p->kz_is_y, lanes->kz_is_y);
#if WT_HAS_ALPHA
  packet_vstore(p->alpha_ray, lanes->alpha_ray);
#endif
}

/// Lane l's ray against the leaf [first, first + count), four triangles at a
/// time, as bvh_closest and bvh_occluded test a leaf (the same operations,
/// so the same answers): the nearest hit in (tmin, tmax), or with `any` the
/// first found; WT_NO_HIT when none, t, b1 and b2 set only on a hit.
inline uint packet_lane_leaf(__global const float4* tri_verts, const RayPacket* p, const PacketLanes* lanes, int l,
                             uint first, uint count, float tmax, bool any, float* t, float* b1, float* b2) {
  // the lane's own permutation, unflipped as its shear (packet_load_lanes)
  const int kz = lanes->kz_is_x[l] ? 0 : (lanes->kz_is_y[l] ? 1 : 2);
  RayShear shear = {kz == 2 ? 0 : kz + 1, kz == 0 ? 2 : kz - 1, kz, lanes->sx[l], lanes->sy[l], lanes->sz[l]};
  float3 org = (float3)(lanes->ox[l], lanes->oy[l], lanes->oz[l]);
  // the lane's view of the scene: the triangles, and the alpha test with the lane's stream
  BvhScene scene = {0, 0u, tri_verts};
#if WT_HAS_ALPHA
  scene.alpha = lanes->alpha;
  scene.alpha.ray = lanes->alpha_ray[l];
#endif
  uint last = first + count - 1u, found = WT_NO_HIT;
  for (uint b = first >> 2; b <= last >> 2; ++b) {
    uint prim = bvh_block_hit(scene, org, shear, lanes->tmin[l], tmax, b, b == first >> 2 ? first & 3u : 0u,
                              b == last >> 2 ? (last & 3u) + 1u : 4u, lanes->skip_a[l], lanes->skip_b[l], t, b1, b2);
    if (prim == WT_NO_HIT) continue;
    found = prim;
    tmax = *t;
    if (any) break;
  }
  return found;
}
#endif

/// Closest hits of a packet's valid lanes: per lane the nearest t in
/// (tmin, t_best) with its barycentrics and leaf-order triangle, which
/// replace t_best, b1_best, b2_best and prim_best where one is found (the
/// other lanes keep theirs).
/// packet_closest_root starts at node `root` instead of node 0: the root of
/// an instanced geometry's tree (bvh_closest_root), the packet in its object space.
__attribute__((always_inline)) inline void packet_closest_root(BvhScene scene, uint root, const RayPacket* p, pint valid,
                                                               pfloat* t_best, pfloat* b1_best, pfloat* b2_best,
                                                               puint* prim_best) {
  if (scene.node_count == 0 || !packet_any(valid)) return;
  __global const WtBvh4Node* nodes = (__global const WtBvh4Node*)scene.nodes;
  pfloat tmax = *t_best;
  // the farthest any lane still searches: a box entered beyond it is skipped
  float reach = packet_max(packet_pick(valid, tmax, (pfloat)(-INFINITY)));
#if WT_PACKET_LEAF_LANES > 0
  PacketLanes lanes;
  packet_lanes(p, &lanes);
#if WT_HAS_ALPHA
  lanes.alpha = scene.alpha;
#endif
#endif
  uint stack_node[WT_BVH_STACK_SIZE];
  float stack_t[WT_BVH_STACK_SIZE];
  int sp = 0;
  uint node = root;
  for (;;) {
    __global const WtBvh4Node* n = &nodes[node];
    uint inner[4];
    float inner_t[4];
    int inner_count = 0;
    for (int k = 0; k < 4; ++k) {
      uint first = n->child[k], count = n->count[k];
      if (first == WT_BVH4_EMPTY) continue;
      pfloat enter;
      pint hit = packet_box_hit(n, k, p, tmax, &enter) & valid;
      if (!packet_any(hit)) continue;
#if WT_PACKET_LEAF_LANES > 0
      if (count > 0 && packet_count(hit) <= WT_PACKET_LEAF_LANES) {
        // few lanes entered: each tests the leaf alone
        int lane_hit[WT_PACKET];
        float lane_t[WT_PACKET], lane_b1[WT_PACKET], lane_b2[WT_PACKET];
        uint lane_prim[WT_PACKET];
        packet_vstore(hit, lane_hit), packet_vstore(tmax, lane_t);
        packet_vstore(*b1_best, lane_b1), packet_vstore(*b2_best, lane_b2), packet_vstore(*prim_best, lane_prim);
        bool won = false;
        for (int l = 0; l < WT_PACKET; ++l) {
          if (!lane_hit[l]) continue;
          float t, b1, b2;
          uint prim = packet_lane_leaf(scene.tri_verts, p, &lanes, l, first, count, lane_t[l], false, &t, &b1, &b2);
          if (prim == WT_NO_HIT) continue;
          lane_t[l] = t, lane_b1[l] = b1, lane_b2[l] = b2, lane_prim[l] = prim;
          won = true;
        }
        if (won) {
          tmax = packet_vload(lane_t);
          *b1_best = packet_vload(lane_b1), *b2_best = packet_vload(lane_b2), *prim_best = packet_vload(lane_prim);
          reach = packet_max(packet_pick(valid, tmax, (pfloat)(-INFINITY)));
        }
        continue;
      }
#endif
      if (count > 0) {
        bool won_any = false;
        for (uint prim = first; prim < first + count; ++prim) {
          pfloat t, b1, b2;
          pint won = packet_triangle(p, scene.tri_verts, prim, hit, tmax, &t, &b1, &b2);
          if (!packet_any(won)) continue;
#if WT_HAS_ALPHA
          won = packet_alpha_keep(scene, p, prim, won, b1, b2);
          if (!packet_any(won)) continue;
#endif
          tmax = packet_pick(won, t, tmax);
          *b1_best = packet_pick(won, b1, *b1_best);
          *b2_best = packet_pick(won, b2, *b2_best);
          *prim_best = packet_pick_u(won, (puint)(prim), *prim_best);
          won_any = true;
        }
        // the leaf's closer hits pull in how far the packet searches
        if (won_any) reach = packet_max(packet_pick(valid, tmax, (pfloat)(-INFINITY)));
      } else {
        // ordered by the nearest entry among the lanes that enter it
        float key = packet_min(packet_pick(hit, enter, (pfloat)(INFINITY)));
        int j = inner_count++;
        for (; j > 0 && inner_t[j - 1] > key; --j) {
          inner[j] = inner[j - 1];
          inner_t[j] = inner_t[j - 1];
        }
        inner[j] = first;
        inner_t[j] = key;
      }
    }
    if (inner_count > 0 && inner_t[0] <= reach) {
      for (int k = inner_count - 1; k >= 1; --k) {
        if (inner_t[k] > reach) continue;
        stack_node[sp] = inner[k];
        stack_t[sp] = inner_t[k];
        ++sp;
      }
      node = inner[0];
      continue;
    }
    for (;;) {
      if (sp == 0) {
        *t_best = tmax;
        return;
      }
      --sp;
      if (stack_t[sp] <= reach) break;
    }
    node = stack_node[sp];
  }
}

__attribute__((always_inline)) inline void packet_closest(BvhScene scene, const RayPacket* p, pint valid, pfloat* t_best,
                                                          pfloat* b1_best, pfloat* b2_best, puint* prim_best) {
  packet_closest_root(scene, 0u, p, valid, t_best, b1_best, b2_best, prim_best);
}

/// Occlusion of a packet's valid lanes: all ones in a lane whose segment
/// (tmin, tmax) is blocked; from node `root` (packet_closest_root).
__attribute__((always_inline)) inline pint packet_occluded_root(BvhScene scene, uint root, const RayPacket* p, pint valid,
                                                                pfloat tmax) {
  pint blocked = (pint)(0);
  if (scene.node_count == 0 || !packet_any(valid)) return blocked;
  __global const WtBvh4Node* nodes = (__global const WtBvh4Node*)scene.nodes;
  pint open = valid;
#if WT_PACKET_LEAF_LANES > 0
  PacketLanes lanes;
  packet_lanes(p, &lanes);
#if WT_HAS_ALPHA
  lanes.alpha = scene.alpha;
#endif
  float lane_tmax[WT_PACKET];
  packet_vstore(tmax, lane_tmax);
#endif
  uint stack_node[WT_BVH_STACK_SIZE];
  int sp = 0;
  uint node = root;
  for (;;) {
    __global const WtBvh4Node* n = &nodes[node];
    int next = -1;
    for (int k = 0; k < 4; ++k) {
      uint first = n->child[k], count = n->count[k];
      if (first == WT_BVH4_EMPTY) continue;
      pfloat enter;
      pint hit = packet_box_hit(n, k, p, tmax, &enter) & open;
      if (!packet_any(hit)) continue;
#if WT_PACKET_LEAF_LANES > 0
      if (count > 0 && packet_count(hit) <= WT_PACKET_LEAF_LANES) {
        // few lanes entered: each tests the leaf alone
        int lane_hit[WT_PACKET], lane_won[WT_PACKET];
        packet_vstore(hit, lane_hit);
        bool won = false;
        for (int l = 0; l < WT_PACKET; ++l) {
          float t, b1, b2;
          lane_won[l] = lane_hit[l] && packet_lane_leaf(scene.tri_verts, p, &lanes, l, first, count, lane_tmax[l], true,
                                                        &t, &b1, &b2) != WT_NO_HIT
                            ? -1
                            : 0;
          won = won || lane_won[l];
        }
        if (won) {
          pint blocked_now = packet_vload(lane_won);
          blocked |= blocked_now;
          open &= ~blocked_now;
          if (!packet_any(open)) return blocked;
        }
        continue;
      }
#endif
      if (count > 0) {
        for (uint prim = first; prim < first + count; ++prim) {
          pfloat t, b1, b2;
          pint won = packet_triangle(p, scene.tri_verts, prim, hit & open, tmax, &t, &b1, &b2);
#if WT_HAS_ALPHA
          if (packet_any(won)) won = packet_alpha_keep(scene, p, prim, won, b1, b2);
#endif
          blocked |= won;
          open &= ~won;
        }
        if (!packet_any(open)) return blocked;
      } else if (next < 0) {
        next = (int)first;
      } else {
        stack_node[sp++] = first;
      }
    }
    if (next >= 0) {
      node = (uint)next;
      continue;
    }
    if (sp == 0) return blocked;
    node = stack_node[--sp];
  }
}

__attribute__((always_inline)) inline pint packet_occluded(BvhScene scene, const RayPacket* p, pint valid, pfloat tmax) {
  return packet_occluded_root(scene, 0u, p, valid, tmax);
}

/// Lanes of the packet at entries [first, first + WT_PACKET) of a queue of
/// `count`: index[l] the queued ray of lane l (the last one repeated past the
/// end); returns how many lanes are real.
inline uint packet_from_queue(__global const uint* queue, uint first, uint count, uint* index) {
  uint lanes = min(count - first, (uint)WT_PACKET);
  for (uint l = 0; l < WT_PACKET; ++l) index[l] = queue[first + min(l, lanes - 1u)];
  return lanes;
}

/// Closest hits written to hits[index[l]] as (t, b1, b2, prim), lane l
/// for l < lanes.
inline void packet_store_hits(__global float4* hits, const uint* index, uint lanes, pfloat t, pfloat b1, pfloat b2,
                              puint prim) {
  float lt[WT_PACKET], lb1[WT_PACKET], lb2[WT_PACKET];
  uint lp[WT_PACKET];
  packet_vstore(t, lt), packet_vstore(b1, lb1), packet_vstore(b2, lb2), packet_vstore(prim, lp);
  for (uint l = 0; l < lanes; ++l) hits[index[l]] = (float4)(lt[l], lb1[l], lb2[l], as_float(lp[l]));
}

/// Closest hits of rays index[0], ..., index[lanes - 1] of a batch, written
/// to hits[index[l]] as (t, b1, b2, leaf-order triangle or WT_NO_HIT);
/// skip[i] is the triangle ray i leaves.
inline void packet_trace_closest(BvhScene scene, const uint* index, uint lanes, __global const float4* ray_o,
                                 __global const float4* ray_d, __global const uint* skip, __global float4* hits) {
  RayPacket p;
  pint valid;
  pfloat tmax;
  const bool contiguous = packet_contiguous(index, lanes);
  int loaded = packet_load(&p, &valid, &tmax, index, lanes, contiguous, ray_o, ray_d, &scene);
  pfloat b1 = (pfloat)(0.0f), b2 = (pfloat)(0.0f);
  puint prim = (puint)(WT_NO_HIT);
  if (loaded != WT_PACKET_MISSES) {
    packet_set_skip(&p, index, lanes, contiguous, skip, 0);
#if WT_HAS_ALPHA
    packet_set_alpha(&p, scene, index);
#endif
    packet_closest(scene, &p, valid, &tmax, &b1, &b2, &prim);
  }
  packet_store_hits(hits, index, lanes, tmax, b1, b2, prim);
}

/// Occlusion of rays index[0], ..., index[lanes - 1]: all ones in lane l
/// when ray index[l]'s segment is blocked or the ray is not finite (as
/// bvh_occluded). skip[i] (skip_ab == 0) or skip_ab[i] are the triangles
/// ray i never hits.
inline pint packet_trace_occluded(BvhScene scene, const uint* index, uint lanes, __global const float4* ray_o,
                                  __global const float4* ray_d, __global const uint* skip,
                                  __global const uint2* skip_ab) {
  RayPacket p;
  pint valid;
  pfloat tmax;
  const bool contiguous = packet_contiguous(index, lanes);
  packet_load(&p, &valid, &tmax, index, lanes, contiguous, ray_o, ray_d, 0);
  packet_set_skip(&p, index, lanes, contiguous, skip, skip_ab);
#if WT_HAS_ALPHA
  packet_set_alpha(&p, scene, index);
#endif
  // a lane whose ray is not finite counts as blocked, as in bvh_occluded
  return ~valid | packet_occluded(scene, &p, valid, tmax);
}

#endif  // WT_BVH_PACKET_CL
