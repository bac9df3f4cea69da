// Oclgrind 21.10 defect: an OpenCL object released after main returns (from
// an atexit handler, or a C++ static destructor) writes to freed memory.
// exit() runs thread_local destructors before atexit handlers and static
// destructors, and every entry point of Oclgrind's runtime pushes its name on
// a thread_local std::stack that is gone by then. In the device tests the
// heap corruption aborted the binary at exit ("corrupted double-linked
// list"); they now release their shared objects before main returns
// (tests/device_fixture.h). valgrind shows the invalid writes:
//   cc release_at_exit.c -lOpenCL -o release_at_exit
//   LD_PRELOAD=/usr/lib/oclgrind/liboclgrind-rt.so valgrind ./release_at_exit
//     -> "Invalid write of size 8 ... clReleaseContext", freed by
//        "std::stack<char const*, ...>::~stack() ... __call_tls_dtors"
//   LD_PRELOAD=/usr/lib/oclgrind/liboclgrind-rt.so valgrind ./release_at_exit in-main
//     -> no error
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>

#include <stdlib.h>
#include <string.h>

static cl_context g_context;

static void releaseContext(void) { clReleaseContext(g_context); }

int main(int argc, char** argv) {
  cl_platform_id platform;
  cl_device_id device;
  cl_int err;
  if (clGetPlatformIDs(1, &platform, NULL) != CL_SUCCESS ||
      clGetDeviceIDs(platform, CL_DEVICE_TYPE_ALL, 1, &device, NULL) != CL_SUCCESS)
    return 2;
  g_context = clCreateContext(NULL, 1, &device, NULL, NULL, &err);
  if (err != CL_SUCCESS) return 2;
  if (argc > 1 && strcmp(argv[1], "in-main") == 0)
    releaseContext();
  else
    atexit(releaseContext);
  return 0;
}
