// Oclgrind 21.10 defect: __builtin_prefetch lowers to llvm.prefetch, which
// Oclgrind does not define, and the kernel stops with "fatal: Undefined
// external function: llvm.prefetch.p1i8". The stream traversal
// (kernels/bvh_stream.cl) asks for a node's children early with it; under
// Oclgrind the host defines WT_NO_PREFETCH (here -D NO_PREFETCH) and the
// requests are left out.
//   oclgrind-kernel --uninitialized prefetch.sim                                  # fatal
//   oclgrind-kernel --uninitialized --build-options "-D NO_PREFETCH" prefetch.sim
__kernel void twice(__global const float* in, __global float* out) {
  uint i = get_global_id(0);
#ifndef NO_PREFETCH
  __builtin_prefetch(in + i + 4, 0, 3);
#endif
  out[i] = 2.0f * in[i];
}
