// What every kernel file needs and no compile-time switch decides: exact
// products, fp64 where the device has it, and WT_KERNEL. The frame program
// (frame.cl) includes this without common.h, so it reads no scene switch.
#ifndef WT_BASE_H
#define WT_BASE_H

// Products must round separately: a fused multiply-add in the edge functions
// of the watertight triangle test breaks its exactness on shared edges.
#pragma OPENCL FP_CONTRACT OFF

#ifdef cl_khr_fp64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#define WT_HAS_FP64 1
#else
#define WT_HAS_FP64 0
#endif

// Every kernel is declared WT_KERNEL: vec_type_hint(float4) says the
// kernel's own float4 and float8 code is its vector width. Intel's CPU
// runtime then compiles each work-item as written instead of vectorising
// across work-items, which slowed single-ray traversal (rays in lock step)
// and got shading wrong: bsdf_sample's answers were right in the first of
// every eight work-items only, and renders with next-event estimation
// changed from run to run (docs/lab/2026-12-02-performance-log.md, "A
// second OpenCL implementation"). PoCL's code
// is the same with or without the hint. Embedded.EveryKernelIsWtKernel
// keeps a plain __kernel from coming back.
#define WT_KERNEL __kernel __attribute__((vec_type_hint(float4)))

#endif  // WT_BASE_H
