// Oclgrind 21.10 defect (--uninitialized): a buffer made with
// CL_MEM_USE_HOST_PTR reads as uninitialised in kernels, though it holds the
// host array (CL_MEM_COPY_HOST_PTR, or a write, is seen as initialised).
//
//   cc use_host_ptr.c -lOpenCL -o use_host_ptr
//   oclgrind --uninitialized ./use_host_ptr copy   # no report
//   oclgrind --uninitialized ./use_host_ptr use    # "Controlflow depends on
//                                                  # uninitialized value"
// readOnlyBuffer (host/device/scene_buffers.cpp) reads arrays in place on CPU
// devices, but not under Oclgrind.
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>

#include <stdio.h>
#include <string.h>

static const char* kSource =
    "__kernel void consume(__global const uint* count, __global uint* out) {\n"
    "  uint i = get_global_id(0);\n"
    "  if (i >= count[0]) return;\n"
    "  out[i] = 1u;\n"
    "}\n";

int main(int argc, char** argv) {
  int use = argc > 1 && strcmp(argv[1], "use") == 0;
  cl_platform_id platform;
  cl_device_id device;
  cl_int err;
  if (clGetPlatformIDs(1, &platform, NULL) != CL_SUCCESS ||
      clGetDeviceIDs(platform, CL_DEVICE_TYPE_ALL, 1, &device, NULL) != CL_SUCCESS)
    return 2;
  cl_context ctx = clCreateContext(NULL, 1, &device, NULL, NULL, &err);
  cl_command_queue q = clCreateCommandQueue(ctx, device, 0, &err);
  static cl_uint counts[4] = {2, 2, 2, 2};
  cl_mem count = clCreateBuffer(ctx, CL_MEM_READ_ONLY | (use ? CL_MEM_USE_HOST_PTR : CL_MEM_COPY_HOST_PTR),
                                sizeof counts, counts, &err);
  cl_mem out = clCreateBuffer(ctx, CL_MEM_READ_WRITE, 16, NULL, &err);
  cl_program program = clCreateProgramWithSource(ctx, 1, &kSource, NULL, &err);
  if (clBuildProgram(program, 1, &device, "", NULL, NULL) != CL_SUCCESS) return 2;
  cl_kernel k = clCreateKernel(program, "consume", &err);
  clSetKernelArg(k, 0, sizeof(cl_mem), &count);
  clSetKernelArg(k, 1, sizeof(cl_mem), &out);
  size_t global = 4;
  clEnqueueNDRangeKernel(q, k, 1, NULL, &global, &global, 0, NULL, NULL);
  cl_uint host[4] = {0};
  clEnqueueReadBuffer(q, out, CL_TRUE, 0, sizeof host, host, 0, NULL, NULL);
  printf("%s host pointer: work-items 0 and 1 wrote %u %u (expected 1 1)\n", use ? "used" : "copied", host[0], host[1]);
  clReleaseKernel(k);
  clReleaseProgram(program);
  clReleaseMemObject(count);
  clReleaseMemObject(out);
  clReleaseCommandQueue(q);
  clReleaseContext(ctx);
  return host[0] == 1 && host[1] == 1 ? 0 : 1;
}
