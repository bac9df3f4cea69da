// The device's side of the layout test (tests/contract/test_layout.cpp): the
// size of every shared struct and the offset of each of its fields, in the
// order of WT_SHARED_LAYOUT.
#include "common.h"
#include "shared/layout.h"

#define WT_LAYOUT_SIZE(T) out[n++] = (uint)sizeof(T);
#define WT_LAYOUT_OFFSET(T, field) out[n++] = (uint)__builtin_offsetof(T, field);

__kernel void layout_table(__global uint* out) {
  if (get_global_id(0) != 0) return;
  uint n = 0;
  WT_SHARED_LAYOUT(WT_LAYOUT_SIZE, WT_LAYOUT_OFFSET)
}
