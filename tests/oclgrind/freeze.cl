// Oclgrind 21.10 defect (--uninitialized, optimised build): the checker does
// not implement LLVM's `freeze` instruction and stops the kernel with
// "OCLGRIND FATAL ERROR ... Unsupported instruction: freeze". LLVM inserts a
// freeze when it computes a quotient and remainder of the same operands
// together (DivRemPairs), as generate.cl does for the pixel coordinates;
// the kernel then writes nothing and every later kernel reads uninitialised
// rays. No freeze appears with -cl-opt-disable, which scripts/oclgrind uses.
//   oclgrind-kernel --uninitialized freeze.sim                    # fatal error
//   oclgrind-kernel --uninitialized --build-options -cl-opt-disable freeze.sim
__kernel void pixel_coordinates(uint width, __global uint* out) {
  uint i = get_global_id(0);
  out[i] = (i % width) * 100u + i / width;
}
