// Oclgrind 21.10 defect (optimised build): integer arithmetic on lane masks
// made by comparisons comes out wrong. Each lane's dominant axis of a
// direction (0 x, 1 y, 2 z, as triangle_ray_shear picks it) is computed as
// 2 - ((x & 2) | (y & 1)) from two normalised masks and used again to pick
// the dominant component. PoCL and Oclgrind's unoptimised build give axes
// 0 0 1 2 0 2 0 0 and components 1 -3 -2 -0.9 -0.5 1 2 -1; the optimised
// build a garbage axis in the third lane (-253) and 0.3 for its component.
// packet_load (kernels/bvh_packet.cl) uses the masks as they are
// (-D MASKS_ONLY here), which both builds get right.
//   oclgrind-kernel mask_arithmetic.sim                                   # third lane wrong
//   oclgrind-kernel --build-options -cl-opt-disable mask_arithmetic.sim   # right
//   oclgrind-kernel --build-options "-D MASKS_ONLY" mask_arithmetic.sim   # right
inline int8 mask8(int8 c) { return (c | -c) >> 31; }
inline float8 pick8(int8 m, float8 yes, float8 no) { return as_float8((as_int8(yes) & m) | (as_int8(no) & ~m)); }
__kernel void axis(__global const float* dx, __global const float* dy, __global const float* dz,
                   __global float* out) {
  float8 ux = vload8(0, dx), uy = vload8(0, dy), uz = vload8(0, dz);
  float8 adx = fabs(ux), ady = fabs(uy), adz = fabs(uz);
  int8 is_x = mask8(adx > ady) & mask8(adx > adz);
  int8 is_y = mask8(adx <= ady) & mask8(ady > adz);
#ifdef MASKS_ONLY
  float8 axis = pick8(is_x, (float8)(0.0f), pick8(is_y, (float8)(1.0f), (float8)(2.0f)));
  int8 z_is_x = is_x, z_is_y = is_y;
#else
  int8 kz = (int8)(2) - ((is_x & (int8)(2)) | (is_y & (int8)(1)));
  float8 axis = convert_float8(kz);
  int8 z_is_x = mask8(kz == 0), z_is_y = mask8(kz == 1);
#endif
  // the dominant component, picked by the axis again (as the shear is)
  float8 dominant = pick8(z_is_x, ux, pick8(z_is_y, uy, uz));
  vstore8(axis, 0, out);
  vstore8(dominant, 1, out);
}
