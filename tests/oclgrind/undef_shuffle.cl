// Oclgrind 21.10 defect (--uninitialized, optimised build): a shufflevector
// whose mask has undef lanes crashes the checker (segmentation fault). Its
// handler compares the mask value with llvm::Value::UndefValueVal (a value
// kind) instead of -1, so an undef lane indexes the source vector at -1 and
// memcpy reads from a wild address. The optimiser builds a float3 from scalars
// with such a mask (common.h, vec4_xyz), and widens float3 to float4 with
// one; -cl-opt-disable (scripts/oclgrind) leaves none in our kernels.
//   oclgrind-kernel --uninitialized undef_shuffle.sim             # crashes
//   oclgrind-kernel --uninitialized --build-options -cl-opt-disable undef_shuffle.sim
typedef struct Vec4 {
  float x, y, z, w;
} Vec4;

__kernel void length_squared(Vec4 v, __global float* out) {
  float3 a = (float3)(v.x, v.y, v.z);
  out[get_global_id(0)] = dot(a, a);
}
