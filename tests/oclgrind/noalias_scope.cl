// Oclgrind 21.10 defect: when LLVM inlines a function that returns a struct
// (through a noalias "sret" pointer) and the result stays in memory, it
// marks the copy with llvm.experimental.noalias.scope.decl, which Oclgrind
// does not define: "fatal: Undefined external function:
// llvm.experimental.noalias.scope.decl" and clCreateKernel fails (`restrict`
// parameters do the same). Optimised builds do it where the result is
// indexed by a variable (pbr_view in pbr_eval, kernels/materials/bsdf.cl;
// alpha_triangle in the alpha test, kernels/materials/alpha.cl),
// unoptimised ones for every always_inline function (triangle_test4_lanes and
// triangle_test4_k, kernels/geometry/triangle.cl). Under Oclgrind the host
// defines WT_NO_SRET_INLINE (here -D NO_SRET_INLINE) and they are called.
//   oclgrind-kernel noalias_scope.sim                                         # fatal
//   oclgrind-kernel --build-options -cl-opt-disable noalias_scope.sim         # fatal
//   oclgrind-kernel --build-options "-D NO_SRET_INLINE" noalias_scope.sim
//   oclgrind-kernel --build-options "-cl-opt-disable -D NO_SRET_INLINE" noalias_scope.sim

typedef struct {
  float v[8];
  int n;
} Big;

#ifdef NO_SRET_INLINE
__attribute__((noinline)) inline
#else
__attribute__((always_inline)) inline
#endif
Big make(__global const float* in, int n) {
  Big b;
  for (int k = 0; k < 8; ++k) b.v[k] = k < n ? in[k] : 0.0f;
  b.n = n;
  return b;
}

__kernel void sum(__global float* out, __global const float* in, int n) {
  Big b = make(in, n);  // indexed by a variable below: it stays in memory
  float s = 0.0f;
  for (int k = 0; k < b.n; ++k) s += b.v[k];
  out[get_global_id(0)] = s;
}
