// Oclgrind 21.10 defect (--uninitialized): after clEnqueueFillBuffer of more
// than one pattern, all but the last pattern read as uninitialised. The
// checker's Uninitialized::hostMemoryStore replaces the buffer's whole shadow
// with a fresh one the size of each host write, and a fill is executed as one
// write per pattern; any write to part of a buffer does the same to the rest.
//
//   cc fill_buffer.c -lOpenCL -o fill_buffer
//   oclgrind --uninitialized ./fill_buffer 1   # fill one word:  no report
//   oclgrind --uninitialized ./fill_buffer 2   # fill two words: "Controlflow
//                                              # depends on uninitialized value"
// Both runs fill word 0 with 2 and read it back in the kernel. The renderer
// works around it in Context::fill (host/device/context.cpp).
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>

#include <stdio.h>
#include <stdlib.h>

static const char* kSource =
    "__kernel void consume(__global const uint* count, __global uint* out) {\n"
    "  uint i = get_global_id(0);\n"
    "  if (i >= count[0]) return;\n"
    "  out[i] = 1u;\n"
    "}\n";

int main(int argc, char** argv) {
  size_t words = argc > 1 ? (size_t)atoi(argv[1]) : 2;
  cl_platform_id platform;
  cl_device_id device;
  cl_int err;
  if (clGetPlatformIDs(1, &platform, NULL) != CL_SUCCESS ||
      clGetDeviceIDs(platform, CL_DEVICE_TYPE_ALL, 1, &device, NULL) != CL_SUCCESS)
    return 2;
  cl_context ctx = clCreateContext(NULL, 1, &device, NULL, NULL, &err);
  cl_command_queue q = clCreateCommandQueue(ctx, device, 0, &err);
  cl_mem count = clCreateBuffer(ctx, CL_MEM_READ_WRITE, 4 * words, NULL, &err);
  cl_mem out = clCreateBuffer(ctx, CL_MEM_READ_WRITE, 16, NULL, &err);
  cl_uint two = 2;
  clEnqueueFillBuffer(q, count, &two, sizeof two, 0, 4 * words, 0, NULL, NULL);
  cl_program program = clCreateProgramWithSource(ctx, 1, &kSource, NULL, &err);
  if (clBuildProgram(program, 1, &device, "", NULL, NULL) != CL_SUCCESS) return 2;
  cl_kernel k = clCreateKernel(program, "consume", &err);
  clSetKernelArg(k, 0, sizeof(cl_mem), &count);
  clSetKernelArg(k, 1, sizeof(cl_mem), &out);
  size_t global = 4;
  clEnqueueNDRangeKernel(q, k, 1, NULL, &global, &global, 0, NULL, NULL);
  cl_uint host[4] = {0};
  clEnqueueReadBuffer(q, out, CL_TRUE, 0, sizeof host, host, 0, NULL, NULL);
  printf("filled %zu word(s): work-items 0 and 1 wrote %u %u (expected 1 1)\n", words, host[0], host[1]);
  clReleaseKernel(k);
  clReleaseProgram(program);
  clReleaseMemObject(count);
  clReleaseMemObject(out);
  clReleaseCommandQueue(q);
  clReleaseContext(ctx);
  return host[0] == 1 && host[1] == 1 ? 0 : 1;
}
