#include "device/tracer.h"

#include "device/program.h"

#include <cstring>

namespace wt {

Tracer::Tracer(Context& context, const Scene& scene, const BvhBuildOptions& options)
    : m_context(context), m_scene(std::make_unique<SceneBuffers>(context, scene, options)) {
  KernelFeatures features;
  features.bvhStackSize = m_scene->stackSize();
  m_program = buildProgram(context, features);
  m_closest = cl::Kernel(m_program, "trace_closest");
  m_occluded = cl::Kernel(m_program, "trace_occluded");
}

Tracer::~Tracer() = default;

void Tracer::uploadRays(std::span<const Ray> rays) {
  std::size_t n = std::max<std::size_t>(rays.size(), 1);
  if (n > m_capacity) {
    m_rayO = cl::Buffer(m_context.context(), CL_MEM_READ_ONLY, n * 16);
    m_rayD = cl::Buffer(m_context.context(), CL_MEM_READ_ONLY, n * 16);
    m_skip = cl::Buffer(m_context.context(), CL_MEM_READ_ONLY, n * 4);
    m_out = cl::Buffer(m_context.context(), CL_MEM_READ_WRITE, n * 16);
    m_capacity = n;
  }
  // Split the interleaved rays into the two float4 streams the kernels read.
  std::vector<float> o(4 * rays.size()), d(4 * rays.size());
  std::vector<cl_uint> skip(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    o[4 * i + 0] = r.origin.x, o[4 * i + 1] = r.origin.y, o[4 * i + 2] = r.origin.z, o[4 * i + 3] = r.tmin;
    d[4 * i + 0] = r.direction.x, d[4 * i + 1] = r.direction.y, d[4 * i + 2] = r.direction.z,
              d[4 * i + 3] = r.tmax;
    skip[i] = m_scene->leafTriangle(r.skip);
  }
  if (!rays.empty()) {
    m_context.queue().enqueueWriteBuffer(m_rayO, CL_TRUE, 0, o.size() * 4, o.data());
    m_context.queue().enqueueWriteBuffer(m_rayD, CL_TRUE, 0, d.size() * 4, d.data());
    m_context.queue().enqueueWriteBuffer(m_skip, CL_TRUE, 0, skip.size() * 4, skip.data());
  }
}

std::vector<RayHit> Tracer::traceClosest(std::span<const Ray> rays) {
  uploadRays(rays);
  cl_uint count = cl_uint(rays.size());
  int a = 0;
  m_closest.setArg(a++, count);
  m_closest.setArg(a++, m_rayO);
  m_closest.setArg(a++, m_rayD);
  m_closest.setArg(a++, m_scene->nodes);
  m_closest.setArg(a++, m_scene->nodeCount);
  m_closest.setArg(a++, m_scene->triVerts);
  m_closest.setArg(a++, m_out);
  m_closest.setArg(a++, m_skip);
  m_context.resetStageTimes();
  m_context.launch("trace_closest", m_closest, rays.size());
  m_context.finish();
  m_lastKernelSeconds = m_context.stageTimes().seconds.count("trace_closest")
                            ? m_context.stageTimes().seconds.at("trace_closest")
                            : 0.0;
  std::vector<float> raw(4 * rays.size());
  if (!rays.empty())
    m_context.queue().enqueueReadBuffer(m_out, CL_TRUE, 0, raw.size() * 4, raw.data());
  std::vector<RayHit> hits(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    std::uint32_t prim;
    std::memcpy(&prim, &raw[4 * i + 3], 4);
    hits[i].t = raw[4 * i + 0];
    hits[i].b1 = raw[4 * i + 1];
    hits[i].b2 = raw[4 * i + 2];
    hits[i].triangle = prim == RayHit::kNoHit ? RayHit::kNoHit : m_scene->sceneTriangle(prim);
  }
  return hits;
}

std::vector<std::uint8_t> Tracer::traceOccluded(std::span<const Ray> rays) {
  uploadRays(rays);
  cl_uint count = cl_uint(rays.size());
  int a = 0;
  m_occluded.setArg(a++, count);
  m_occluded.setArg(a++, m_rayO);
  m_occluded.setArg(a++, m_rayD);
  m_occluded.setArg(a++, m_scene->nodes);
  m_occluded.setArg(a++, m_scene->nodeCount);
  m_occluded.setArg(a++, m_scene->triVerts);
  m_occluded.setArg(a++, m_out);
  m_occluded.setArg(a++, m_skip);
  m_context.resetStageTimes();
  m_context.launch("trace_occluded", m_occluded, rays.size());
  m_context.finish();
  m_lastKernelSeconds = m_context.stageTimes().seconds.count("trace_occluded")
                            ? m_context.stageTimes().seconds.at("trace_occluded")
                            : 0.0;
  std::vector<cl_uint> raw(rays.size());
  if (!rays.empty())
    m_context.queue().enqueueReadBuffer(m_out, CL_TRUE, 0, raw.size() * 4, raw.data());
  return std::vector<std::uint8_t>(raw.begin(), raw.end());
}

}  // namespace wt
