// Oclgrind 21.10 defect (--uninitialized, unoptimised build): the upper half
// (.hi) of a 16-wide vector is reported uninitialised although every lane is
// set, so a branch or a builtin on it is reported ("Controlflow depends on
// uninitialized value"); .lo, and .hi of an 8-wide vector, are fine. The
// 16-lane packets (kernels/bvh_packet.cl, WT_PACKET_WIDTH 16) fold their
// lanes through private memory instead (-D VIA_PRIVATE here).
//   oclgrind-kernel --uninitialized --build-options -cl-opt-disable upper_half.sim     # 2 reports
//   oclgrind-kernel --uninitialized --build-options "-cl-opt-disable -D VIA_PRIVATE" upper_half.sim
__kernel void fold(__global const float* in, __global int* out) {
  uint i = get_global_id(0);
  float16 v = vload16(0, in) + (float)i;
#ifdef VIA_PRIVATE
  float t[16];
  vstore16(v, 0, t);
  float8 h = fmax(vload8(0, t), vload8(1, t));
#else
  float8 h = fmax(v.lo, v.hi);
#endif
  float4 q = fmax(h.lo, h.hi);
  out[i] = q.x > 3.0f ? 1 : 0;
}
