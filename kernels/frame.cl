// The frame program: accumulation and tone mapping, whose code reads no
// scene switch. Built with WT_AOV only (frameProgramDefines,
// host/device/program.cpp), so every feature set shares one build of it and
// a new scene recompiles the render program (wavetrace.cl) alone.
#ifndef WT_AOV
#error "WT_AOV not set (frameProgramDefines)"
#elif (WT_AOV) != 0 && (WT_AOV) != 1
#error "WT_AOV must be 0 or 1"
#endif

// the shared headers before base.h, in the order common.h has them
#include "shared/types.h"
#include "shared/rng.h"
#include "base.h"
#include "accumulate.cl"
#include "tonemap.cl"
