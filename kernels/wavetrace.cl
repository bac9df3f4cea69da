// The render program: the wavefront stages only, specialised by -D options
// from kernelDefines() (host/device/program.cpp). Accumulation and tone
// mapping (frame.cl), the bench's tracers (trace.cl) and the stress suite's
// kernels (stress.cl) are programs of their own.
#include "generate.cl"
#include "extend.cl"
#include "shade.cl"
#include "connect.cl"
