// Oclgrind 21.10 defect (unoptimised build): a float16 joined from two
// float8 halves, (float16)(lo, hi), crashes the checker (segmentation
// fault) when the halves come from shuffle2; the optimised build is right.
// packet_load (kernels/bvh_packet.cl) transposes 16 consecutive rays into
// lanes by two shuffle2 of 16 lanes each, blended by a mask of the low
// half (-D BLEND here), which both builds run. Not shuffle2's doing: any
// vector after the first component of a vector literal crashes the
// unoptimised checker (vector_literal.cl).
//   oclgrind-kernel --uninitialized --build-options -cl-opt-disable join_halves.sim              # crashes
//   oclgrind-kernel --uninitialized --build-options "-cl-opt-disable -D BLEND" join_halves.sim   # 0 4 8 ... 60
__kernel void transpose(__global const float* in, __global float* out) {
#ifdef BLEND
  const uint16 m = (uint16)(0, 4, 8, 12, 16, 20, 24, 28, 0, 4, 8, 12, 16, 20, 24, 28);
  float16 a = shuffle2(vload16(0, in), vload16(1, in), m);
  float16 b = shuffle2(vload16(2, in), vload16(3, in), m);
  const int16 low = (int16)(-1, -1, -1, -1, -1, -1, -1, -1, 0, 0, 0, 0, 0, 0, 0, 0);
  float16 x = as_float16((as_int16(a) & low) | (as_int16(b) & ~low));
#else
  const uint8 m = (uint8)(0, 4, 8, 12, 16, 20, 24, 28);
  float8 lo = shuffle2(vload16(0, in), vload16(1, in), m);
  float8 hi = shuffle2(vload16(2, in), vload16(3, in), m);
  float16 x = (float16)(lo, hi);
#endif
  vstore16(x, 0, out);
}
