// Oclgrind 21.10 defect (--uninitialized, unoptimised build; the optimised
// one crashes as well, undef_shuffle.cl): a vector literal with a vector
// after its first component, (float4)(t, n) with n a float3, crashes the
// checker (segmentation fault in Uninitialized::instructionExecuted). Clang builds such a literal with a
// shufflevector that takes the vector's lanes from its second operand;
// a vector first, (float4)(n, t), and a literal of scalars, (float4)(t,
// n.x, n.y, n.z) (-D COMPONENTS here), both run. join_halves.cl is the same
// defect. The test-only kernels (sdf_tests.cl, displaced_tests.cl) write
// their (t, normal) results component by component.
//   oclgrind-kernel --uninitialized --build-options -cl-opt-disable vector_literal.sim                  # crashes
//   oclgrind-kernel --uninitialized --build-options "-cl-opt-disable -D COMPONENTS" vector_literal.sim  # 4 2 4 6 8 ...
__kernel void hit_record(__global const float4* in, __global float4* out) {
  uint i = get_global_id(0);
  float t = in[i].w;
  float3 n = in[i].xyz * 2.0f;
#ifdef COMPONENTS
  out[i] = (float4)(t, n.x, n.y, n.z);
#else
  out[i] = (float4)(t, n);
#endif
}
