// Nested dielectrics (Schmidt and Budge 2002, "Simple nested dielectrics in
// ray traced images"), shared by host and kernels. Each path carries the
// closed transmitting volumes it is inside (a small stack of material ids,
// oldest first). The medium the path is in is the entry of highest
// WtMaterial::priority, the latest entered among equals. A hit on a volume
// boundary is a real interface when its medium is (entering) or was
// (leaving) that current medium; otherwise the surface lies inside a medium
// that outranks it and the path passes it unchanged (a false hit). A real
// interface refracts by the indices on its two sides as the stack says: the
// current medium's (1 outside every volume) and the one behind.
#ifndef WT_SHARED_MEDIA_H
#define WT_SHARED_MEDIA_H

#include "shared/types.h"

#ifdef __OPENCL_C_VERSION__
#define WT_MEDIA_INLINE inline
#define WT_MEDIA_GLOBAL __global
#else
#define WT_MEDIA_INLINE static inline
#define WT_MEDIA_GLOBAL
#endif

#define WT_MEDIA_STACK 4          ///< media per path; the path state holds them as one uint4
#define WT_MEDIUM_NONE 0xffffffffu  ///< a free entry

// A false hit is no bounce: it counts neither towards the bounce limit nor
// for Russian roulette (Falcor's rejected hits). A path passes at most
// WT_MAX_FALSE_HITS of them for free, so that overlapping volumes cannot keep
// a path alive forever; beyond that each counts as a bounce. The count shares
// the path state's fourth bounce counter with the dispersion channel: bits
// 0-1 the channel plus 1 (0: all channels), bits 2 and up the false hits.
#define WT_MAX_FALSE_HITS 16u
#define WT_DISPERSION_BITS 3u      ///< the channel's bits in the shared counter
#define WT_FALSE_HIT_STEP 4u       ///< one false hit in the shared counter

/// The false hits a path passed for free, from its shared counter.
WT_MEDIA_INLINE wt_uint media_false_hits(wt_uint shared_counter) { return shared_counter / WT_FALSE_HIT_STEP; }

/// The volumes a path is inside: material ids, oldest first, entries
/// [0, count) used and the rest WT_MEDIUM_NONE.
typedef struct WtMediaStack {
  wt_uint id[WT_MEDIA_STACK];
} WtMediaStack;

/// What a volume boundary's hit is to a path.
typedef struct WtMediaCrossing {
  wt_uint real;     ///< 1: an interface; 0: a false hit, passed unchanged
  float ior_near;   ///< the index on the ray's side (real only)
  float ior_far;    ///< the index behind the surface (real only)
  wt_uint near_id;  ///< the material of the medium on the ray's side (WT_MEDIUM_NONE: air; real only)
  wt_uint far_id;   ///< and behind the surface
} WtMediaCrossing;

/// Whether material `id` bounds a medium: a transmitting PBR material that
/// is not thin-walled (by its factors, not a texel, so that entering and
/// leaving agree).
WT_MEDIA_INLINE int media_is_boundary(WT_MEDIA_GLOBAL const WtMaterial* materials, wt_uint id) {
  return materials[id].model == WT_MATERIAL_PBR && materials[id].transmission > 0.0f && materials[id].volume.w != 0.0f;
}

/// The entry of the medium the path is in (highest priority, the latest
/// among equals); -1 outside every volume.
WT_MEDIA_INLINE int media_current(const WtMediaStack* s, WT_MEDIA_GLOBAL const WtMaterial* materials) {
  int best = -1;
  wt_uint best_priority = 0u;
  for (int k = 0; k < WT_MEDIA_STACK; ++k) {
    if (s->id[k] == WT_MEDIUM_NONE) continue;
    wt_uint p = materials[s->id[k]].priority;
    if (best < 0 || p >= best_priority) best = k, best_priority = p;
  }
  return best;
}

/// The latest entry of material `id`; -1 when the stack lacks it.
WT_MEDIA_INLINE int media_find(const WtMediaStack* s, wt_uint id) {
  int found = -1;
  for (int k = 0; k < WT_MEDIA_STACK; ++k)
    if (s->id[k] == id) found = k;
  return found;
}

/// Entry k out, the later ones moved down.
WT_MEDIA_INLINE void media_remove(WtMediaStack* s, int k) {
  for (int j = k; j + 1 < WT_MEDIA_STACK; ++j) s->id[j] = s->id[j + 1];
  s->id[WT_MEDIA_STACK - 1] = WT_MEDIUM_NONE;
}

/// The index of entry k's medium; 1 (vacuum, air) for -1.
WT_MEDIA_INLINE float media_ior(const WtMediaStack* s, WT_MEDIA_GLOBAL const WtMaterial* materials, int k) {
  return k < 0 ? 1.0f : materials[s->id[k]].ior;
}

/// Entry k's material; WT_MEDIUM_NONE for -1.
WT_MEDIA_INLINE wt_uint media_id(const WtMediaStack* s, int k) { return k < 0 ? WT_MEDIUM_NONE : s->id[k]; }

/// A hit on boundary material `id` from outside it (`entering`, its front
/// face) or from inside.
WT_MEDIA_INLINE WtMediaCrossing media_crossing(const WtMediaStack* s, WT_MEDIA_GLOBAL const WtMaterial* materials,
                                               wt_uint id, int entering) {
  WtMediaCrossing c;
  c.real = 1u;
  c.ior_near = c.ior_far = 1.0f;
  c.near_id = c.far_id = WT_MEDIUM_NONE;
  int current = media_current(s, materials);
  wt_uint priority = materials[id].priority;
  if (entering) {
    // a medium of lower priority than the one the path is in lies inside it
    if (current >= 0 && priority < materials[s->id[current]].priority) {
      c.real = 0u;
      return c;
    }
    c.ior_near = media_ior(s, materials, current);
    c.ior_far = materials[id].ior;
    c.near_id = media_id(s, current);
    c.far_id = id;
    return c;
  }
  int k = media_find(s, id);
  if (k < 0) {
    // leaving a volume the stack lacks (the camera inside it, or an entry
    // lost to overflow): an interface into the current medium, unless that
    // outranks it
    if (current >= 0 && materials[s->id[current]].priority > priority) {
      c.real = 0u;
      return c;
    }
    c.ior_near = materials[id].ior;
    c.ior_far = media_ior(s, materials, current);
    c.near_id = id;
    c.far_id = media_id(s, current);
    return c;
  }
  if (k != current) {
    c.real = 0u;
    return c;
  }
  WtMediaStack behind = *s;
  media_remove(&behind, k);
  int next = media_current(&behind, materials);
  c.ior_near = materials[id].ior;
  c.ior_far = media_ior(&behind, materials, next);
  c.near_id = id;
  c.far_id = media_id(&behind, next);
  return c;
}

/// The stack after the path crossed boundary `id` (an interface it was
/// transmitted through, or a false hit). A full stack forgets its entry of
/// lowest priority (the oldest among equals) to make room, or does not
/// take the new one if that is the lowest: leaving a forgotten volume then
/// counts as the rule in media_crossing says.
WT_MEDIA_INLINE void media_cross(WtMediaStack* s, WT_MEDIA_GLOBAL const WtMaterial* materials, wt_uint id,
                                 int entering) {
  if (!entering) {
    int k = media_find(s, id);
    if (k >= 0) media_remove(s, k);
    return;
  }
  if (s->id[WT_MEDIA_STACK - 1] != WT_MEDIUM_NONE) {
    int lowest = 0;
    for (int k = 1; k < WT_MEDIA_STACK; ++k)
      if (materials[s->id[k]].priority < materials[s->id[lowest]].priority) lowest = k;
    if (materials[id].priority < materials[s->id[lowest]].priority) return;
    media_remove(s, lowest);
  }
  for (int k = 0; k < WT_MEDIA_STACK; ++k)
    if (s->id[k] == WT_MEDIUM_NONE) {
      s->id[k] = id;
      return;
    }
}

// KHR_materials_dispersion in an RGB renderer: a path that meets an
// interface next to a dispersive medium picks one channel (uniformly, once)
// and carries it alone from then on, three times as strong; the channels
// stand for the Fraunhofer lines the Abbe number is defined by: C (656.3 nm,
// red), d (587.6 nm, green: the material's own index) and F (486.1 nm, blue).
#define WT_DISPERSION_CHANNELS 3u

/// The index at channel c (0, 1, 2: red, green, blue) of a medium of index
/// `ior` at the d line and dispersion 20 / V_d: the extension's Cauchy fit
/// n(lambda) = max(n_d + (n_d - 1) / V_d (523655 / lambda^2 - 1.5168), 1)
/// (lambda in nm). Dispersion 0 returns `ior` itself.
WT_MEDIA_INLINE float media_channel_ior(float ior, float dispersion, wt_uint channel) {
  if (!(dispersion > 0.0f)) return ior;
  // 523655 / lambda^2 - 1.5168 at 656.3 and 486.1 nm; at the d line it is
  // below 2e-4 (the constants' rounding): green keeps the index itself
  if (channel == 1u) return ior;
  const float shift = channel == 0u ? -0.30106f : 0.69932f;
  float n = ior + (ior - 1.0f) * (dispersion / 20.0f) * shift;
  return n > 1.0f ? n : 1.0f;
}

#endif  // WT_SHARED_MEDIA_H
