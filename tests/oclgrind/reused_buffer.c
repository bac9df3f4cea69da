// Oclgrind 21.10 defect (--uninitialized): a buffer can inherit the shadow
// of a released one. The checker keeps a shadow per buffer index, sized by
// the last host write to the buffer, or by the buffer itself when a kernel
// first sees it unwritten; shadows are never dropped when a buffer is
// released, and Oclgrind gives a new buffer the index of a released one. A
// bigger new buffer then has a shadow too small for it: stores past its end
// are dropped and loads there read as uninitialised. Here a 4-byte buffer is
// written by the host and released, a 16-byte buffer takes its index, a
// kernel writes all four words and another reads them:
//   cc reused_buffer.c -lOpenCL -o reused_buffer
//   oclgrind --uninitialized ./reused_buffer write    # 3 reports, words 1-3
//   oclgrind --uninitialized ./reused_buffer no-write # no report
// The second renderer in a process (two renders in one test) saw every ray
// but the first as uninitialised. scripts/oclgrind runs each device test in a
// process of its own, and the renderer through the command line.
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>

#include <stdio.h>
#include <string.h>

static const char* kSource =
    "__kernel void produce(__global uint* data) { data[get_global_id(0)] = 1u; }\n"
    "__kernel void consume(__global const uint* data, __global uint* out) {\n"
    "  uint i = get_global_id(0);\n"
    "  if (data[i] == 1u) out[i] = 1u;\n"
    "}\n";

int main(int argc, char** argv) {
  int hostWrite = !(argc > 1 && strcmp(argv[1], "no-write") == 0);
  cl_platform_id platform;
  cl_device_id device;
  cl_int err;
  if (clGetPlatformIDs(1, &platform, NULL) != CL_SUCCESS ||
      clGetDeviceIDs(platform, CL_DEVICE_TYPE_ALL, 1, &device, NULL) != CL_SUCCESS)
    return 2;
  cl_context ctx = clCreateContext(NULL, 1, &device, NULL, NULL, &err);
  cl_command_queue q = clCreateCommandQueue(ctx, device, 0, &err);
  cl_program program = clCreateProgramWithSource(ctx, 1, &kSource, NULL, &err);
  if (clBuildProgram(program, 1, &device, "", NULL, NULL) != CL_SUCCESS) return 2;
  cl_kernel produce = clCreateKernel(program, "produce", &err);
  cl_kernel consume = clCreateKernel(program, "consume", &err);

  // a small buffer, written by the host, then released
  cl_uint one = 1;
  cl_mem small = clCreateBuffer(ctx, CL_MEM_READ_WRITE, sizeof one, NULL, &err);
  if (hostWrite) clEnqueueWriteBuffer(q, small, CL_TRUE, 0, sizeof one, &one, 0, NULL, NULL);
  clReleaseMemObject(small);

  // a bigger one takes its index: written in full by a kernel, then read
  cl_mem data = clCreateBuffer(ctx, CL_MEM_READ_WRITE, 4 * sizeof one, NULL, &err);
  cl_mem out = clCreateBuffer(ctx, CL_MEM_READ_WRITE, 4 * sizeof one, NULL, &err);
  clSetKernelArg(produce, 0, sizeof(cl_mem), &data);
  clSetKernelArg(consume, 0, sizeof(cl_mem), &data);
  clSetKernelArg(consume, 1, sizeof(cl_mem), &out);
  size_t global = 4;
  clEnqueueNDRangeKernel(q, produce, 1, NULL, &global, &global, 0, NULL, NULL);
  clEnqueueNDRangeKernel(q, consume, 1, NULL, &global, &global, 0, NULL, NULL);
  cl_uint host[4] = {0};
  clEnqueueReadBuffer(q, out, CL_TRUE, 0, sizeof host, host, 0, NULL, NULL);
  printf("%s: out = %u %u %u %u (expected 1 1 1 1)\n", hostWrite ? "write" : "no-write", host[0], host[1],
         host[2], host[3]);
  clReleaseKernel(produce);
  clReleaseKernel(consume);
  clReleaseProgram(program);
  clReleaseMemObject(data);
  clReleaseMemObject(out);
  clReleaseCommandQueue(q);
  clReleaseContext(ctx);
  return host[0] == 1 && host[1] == 1 && host[2] == 1 && host[3] == 1 ? 0 : 1;
}
