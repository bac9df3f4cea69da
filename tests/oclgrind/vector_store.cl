// Oclgrind 21.10 defect (--uninitialized, optimised build): a vector stored
// to global memory from scalars is reported as "Uninitialized value written
// to global memory" although every lane is written. Oclgrind rewrites the
// store of an insertelement chain (Program::scalarizeAggregateStore) into a
// store of the chain's undef base followed by one store per lane, and the
// checker reports the undef store: once per work-item of test_mis
// (unit_tests.cl) and test_env_sample (env_tests.cl) in an optimised build.
// -cl-opt-disable (scripts/oclgrind) keeps the value in private memory until
// it is complete.
//   oclgrind-kernel --uninitialized vector_store.sim              # 2 reports
//   oclgrind-kernel --uninitialized --build-options -cl-opt-disable vector_store.sim
__kernel void pair(__global const float* in, __global float2* out) {
  uint i = get_global_id(0);
  out[i] = (float2)(in[i] + 1.0f, in[i] * 2.0f);
}
