// Oclgrind 21.10 defect: __builtin_ctzl lowers to llvm.cttz.i64, which
// Oclgrind does not define, and the kernel stops with "fatal: Undefined
// external function: llvm.cttz.i64". The stream traversal
// (kernels/bvh_stream.cl) takes a mask's rays lowest first with it; under
// Oclgrind the host defines WT_NO_CTZ (here -D NO_CTZ) and the position is
// counted with popcount instead.
//   oclgrind-kernel --uninitialized ctz.sim                         # fatal
//   oclgrind-kernel --uninitialized --build-options "-D NO_CTZ" ctz.sim
__kernel void lowest(__global const ulong* in, __global uint* out) {
  uint i = get_global_id(0);
  ulong m = in[i];
#ifdef NO_CTZ
  out[i] = (uint)popcount((m & (0ul - m)) - 1ul);
#else
  out[i] = (uint)__builtin_ctzl(m);
#endif
}
