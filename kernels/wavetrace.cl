// The program the host builds: every stage, specialised by -D options from
// kernelDefines() (host/device/program.cpp).
#include "generate.cl"
#include "extend.cl"
#include "shade.cl"
#include "connect.cl"
#include "accumulate.cl"
#include "tonemap.cl"
#include "trace.cl"
