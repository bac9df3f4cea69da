#include "render/checkpoint.h"

#include "bvh/builders.h"
#include "device/program.h"
#include "output/image_io.h"

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <unistd.h>

namespace wt {
namespace {

constexpr char kMagic[8] = {'W', 'T', 'C', 'K', 'P', 'T', '\r', '\n'};
constexpr std::uint64_t kFnvPrime = 0x100000001b3ull;

std::string hex(std::uint64_t v) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(v));
  return text;
}

std::uint64_t environmentHash(const Environment& env) {
  Fnv64 h;
  h.pod(env.header);
  h.array(env.texels);
  h.array(env.marginalCdf);
  h.array(env.conditionalCdf);
  return h.value();
}

std::uint64_t kernelHash(const KernelFeatures& features) {
  Fnv64 h;
  // the frame program holds the accumulation state's format
  for (const char* root : {"wavetrace.cl", "frame.cl"}) {
    const std::string source = expandKernelSource(root);
    h.bytes(source.data(), source.size());
  }
  for (const std::string& d : kernelDefines(features)) {
    h.bytes(d.data(), d.size());
    h.bytes("\n", 1);
  }
  return h.value();
}

const char* lightSamplerName(LightSampler s) {
  return s == LightSampler::Power ? "power" : s == LightSampler::Tree ? "tree" : "auto";
}

const char* accumulationName(std::uint32_t mode) {
  return mode == WT_ACCUMULATE_SINGLE ? "single" : mode == WT_ACCUMULATE_DOUBLE ? "double" : "kahan";
}

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& what) {
  throw CheckpointError(path.string() + ": " + what);
}

}  // namespace

void Fnv64::word(std::uint64_t w) {
  m_hash ^= w;
  m_hash *= kFnvPrime;
}

void Fnv64::bytes(const void* data, std::size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  while (size > 0 && (m_tailSize > 0 || size < 8)) {
    m_tail[m_tailSize++] = *p++;
    --size;
    if (m_tailSize == 8) {
      std::uint64_t w;
      std::memcpy(&w, m_tail, 8);
      word(w);
      m_tailSize = 0;
    }
  }
  for (; size >= 8; p += 8, size -= 8) {
    std::uint64_t w;
    std::memcpy(&w, p, 8);
    word(w);
  }
  // a rest here means m_tailSize == 0 and size < 8
  if (size > 0) {
    std::memcpy(m_tail, p, size);
    m_tailSize = size;
  }
}

std::uint64_t Fnv64::value() const {
  std::uint64_t h = m_hash;
  for (std::size_t i = 0; i < m_tailSize; ++i) {
    h ^= m_tail[i];
    h *= kFnvPrime;
  }
  return h;
}

std::uint64_t sceneContentHash(const Scene& scene) {
  Fnv64 h;
  // plain-data arrays (shared structs pad explicitly; glm vectors are packed floats)
  h.array(scene.positions);
  h.array(scene.normals);
  h.array(scene.texcoords);
  h.array(scene.texcoords1);
  h.array(scene.colors);
  h.array(scene.tangents);
  h.array(scene.triangles);
  h.array(scene.curvePoints);
  h.array(scene.materials);
  h.array(scene.materialTextures);
  h.array(scene.textures.texels);
  h.array(scene.textures.levels);
  h.array(scene.textures.textures);
  // host structs field by field: their padding is not initialised
  h.pod(std::uint64_t(scene.instances.size()));
  for (const GeometryInstance& g : scene.instances) {
    h.pod(g.firstTriangle), h.pod(g.triangleCount), h.pod(g.geometry);
    h.pod(g.transform);
  }
  h.pod(std::uint64_t(scene.spheres.size()));
  for (const Sphere& s : scene.spheres) h.pod(s.center), h.pod(s.radius), h.pod(s.material);
  h.pod(std::uint64_t(scene.curves.size()));
  for (const Curve& c : scene.curves) h.pod(c.firstPoint), h.pod(c.pointCount), h.pod(c.material), h.pod(c.basis);
  h.pod(std::uint8_t(scene.camera.has_value()));
  if (const auto& c = scene.camera) {
    h.pod(c->cameraToWorld), h.pod(std::uint8_t(c->orthographic)), h.pod(c->yfov), h.pod(c->aspectRatio);
    h.pod(c->xmag), h.pod(c->ymag), h.pod(c->znear);
  }
  h.pod(std::uint64_t(scene.lights.size()));
  for (const PunctualLight& l : scene.lights) {
    h.pod(l.type), h.pod(l.position), h.pod(l.direction), h.pod(l.intensity);
    h.pod(l.innerConeAngle), h.pod(l.outerConeAngle);
  }
  h.pod(scene.origin);
  return h.value();
}

std::vector<CheckpointField> checkpointIdentity(const Scene& scene, const Renderer& renderer) {
  const RenderSettings& s = renderer.settings();
  const KernelFeatures& k = renderer.kernelFeatures();
  auto lobe = [&](int limit) { return std::to_string(limit < 0 ? s.maxBounces : std::min(limit, s.maxBounces)); };
  const bool path = s.integrator == Integrator::Path;
  return {
      {"scene", hex(sceneContentHash(scene))},
      {"environment", hex(environmentHash(renderer.environment()))},
      {"environment_hidden", s.environmentHidden ? "yes" : "no"},
      {"kernels", hex(kernelHash(k))},
      {"width", std::to_string(s.width)},
      {"height", std::to_string(s.height)},
      {"seed", std::to_string(s.seed)},
      {"max_bounces", std::to_string(s.maxBounces)},
      {"max_diffuse_bounces", lobe(s.maxDiffuseBounces)},
      {"max_specular_bounces", lobe(s.maxSpecularBounces)},
      {"max_transmission_bounces", lobe(s.maxTransmissionBounces)},
      {"integrator", path ? "path" : "minimal"},
      {"nee", path && s.useNee ? "yes" : "no"},
      {"mis", path && s.useMis ? "yes" : "no"},
      {"mis_heuristic", s.powerHeuristic ? "power" : s.powerAtLambertian ? "auto" : "balance"},
      {"russian_roulette", path && s.useRussianRoulette ? "yes" : "no"},
      {"rr_depth", std::to_string(s.rrMinDepth)},
      {"sampler", s.sobol ? "sobol" : "independent"},
      {"texture_filter", s.textureFootprint ? "footprint" : "finest"},
      {"light_sampler", lightSamplerName(s.lightSampler)},
      {"accumulation", accumulationName(s.accumulation)},
      {"bvh", bvhBuilderName(s.bvhBuilder)},
      {"instancing", s.instancing == Instancing::On ? "on" : s.instancing == Instancing::Off ? "off" : "auto"},
      {"traversal", s.packets ? "auto" : "single"},
      {"packet_width", std::to_string(k.packetWidth)},
  };
}

std::filesystem::path checkpointPathFor(const std::filesystem::path& output) {
  return std::filesystem::path(output.string() + ".wtckpt");
}

void writeCheckpoint(const std::filesystem::path& path, const Checkpoint& c) {
  const Accumulation& a = c.accumulation;
  const std::size_t aovBytesPerPixel = a.aovs.empty() ? 0 : kAovSumBytes + kAovIdBytes;
  if (a.state.size() != c.pixels * kAccumulationStateBytes || a.samples.size() != c.pixels ||
      a.aovs.size() != c.pixels * aovBytesPerPixel)
    fail(path, "internal: accumulation of " + std::to_string(a.samples.size()) + " pixels, header says " +
                   std::to_string(c.pixels));
  std::string header;
  auto line = [&](const std::string& key, const std::string& value) { header += key + " " + value + "\n"; };
  line("samples_done", std::to_string(a.samplesDone));
  line("nonfinite_samples", std::to_string(a.nonFiniteSamples));
  line("pixels", std::to_string(c.pixels));
  line("state_bytes", std::to_string(kAccumulationStateBytes));
  line("aov_bytes", std::to_string(aovBytesPerPixel));
  line("device", c.device);
  for (const CheckpointField& f : c.identity) line(f.key, f.value);

  const std::uint32_t version = kCheckpointVersion, headerBytes = std::uint32_t(header.size());
  const std::uint64_t payloadBytes = a.state.size() + a.samples.size() * sizeof(std::uint32_t) + a.aovs.size();
  Fnv64 sum;
  const std::filesystem::path temp = temporaryPathFor(path);
  std::FILE* f = std::fopen(temp.c_str(), "wb");
  if (!f) fail(path, std::string("cannot write the checkpoint: ") + std::strerror(errno));
  bool ok = true;
  auto put = [&](const void* data, std::size_t size) {
    if (size == 0) return;  // an empty vector's data() may be null, which fwrite must not get
    sum.bytes(data, size);
    ok = ok && std::fwrite(data, 1, size, f) == size;
  };
  put(kMagic, sizeof kMagic);
  put(&version, 4);
  put(&headerBytes, 4);
  put(header.data(), header.size());
  put(&payloadBytes, 8);
  put(a.state.data(), a.state.size());
  put(a.samples.data(), a.samples.size() * sizeof(std::uint32_t));
  put(a.aovs.data(), a.aovs.size());
  const std::uint64_t checksum = sum.value();
  ok = ok && std::fwrite(&checksum, 1, 8, f) == 8;
  // on disk before the rename, so a power cut cannot leave a renamed empty file
  ok = ok && std::fflush(f) == 0 && fsync(fileno(f)) == 0;
  const int err = errno;
  ok = std::fclose(f) == 0 && ok;
  if (!ok) {
    std::filesystem::remove(temp);
    fail(path, std::string("cannot write the checkpoint: ") + std::strerror(err));
  }
  std::error_code ec;
  std::filesystem::rename(temp, path, ec);
  if (ec) {
    std::filesystem::remove(temp);
    fail(path, "cannot rename the checkpoint into place: " + ec.message());
  }
  removeStaleTemporaries(path);
}

Checkpoint readCheckpoint(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot read the checkpoint: ") + std::strerror(errno));
  std::vector<char> file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) fail(path, "cannot read the checkpoint: read error");

  const std::size_t kFixed = sizeof kMagic + 4 + 4 + 8 + 8;  // magic, version, header size, payload size, checksum
  if (file.size() >= sizeof kMagic && std::memcmp(file.data(), kMagic, sizeof kMagic) != 0)
    fail(path, "not a wavetrace checkpoint (no WTCKPT magic)");
  if (file.size() < kFixed)
    fail(path, "truncated checkpoint (" + std::to_string(file.size()) + " bytes, less than its fixed fields)");
  std::uint32_t version = 0, headerBytes = 0;
  std::memcpy(&version, file.data() + 8, 4);
  std::memcpy(&headerBytes, file.data() + 12, 4);
  // version 1 is version 2 without AOVs (no aov_bytes line)
  if (version != kCheckpointVersion && version != 1)
    fail(path, "checkpoint format version " + std::to_string(version) + "; this build reads version " +
                   std::to_string(kCheckpointVersion));
  if (std::uint64_t(headerBytes) + kFixed > file.size())
    fail(path, "truncated checkpoint (" + std::to_string(file.size()) + " bytes; its header alone is " +
                   std::to_string(headerBytes) + ")");
  std::uint64_t payloadBytes = 0;
  std::memcpy(&payloadBytes, file.data() + 16 + headerBytes, 8);
  const std::uint64_t expected = kFixed + std::uint64_t(headerBytes) + payloadBytes;
  if (payloadBytes > file.size() || file.size() < expected)
    fail(path, "truncated checkpoint (" + std::to_string(file.size()) + " bytes of the " +
                   (payloadBytes > file.size() ? std::string("more than ") + std::to_string(file.size())
                                               : std::to_string(expected)) +
                   " its header names)");
  if (file.size() > expected)
    fail(path, "corrupt checkpoint (" + std::to_string(file.size() - expected) + " bytes past its end)");
  Fnv64 sum;
  sum.bytes(file.data(), file.size() - 8);
  std::uint64_t checksum = 0;
  std::memcpy(&checksum, file.data() + file.size() - 8, 8);
  if (checksum != sum.value())
    fail(path, "corrupt checkpoint (checksum " + hex(checksum) + " stored, " + hex(sum.value()) +
                   " computed): not used");

  // header: "key value" lines
  Checkpoint c;
  std::map<std::string, std::string> meta;
  const std::string header(file.data() + 16, headerBytes);
  std::size_t at = 0;
  while (at < header.size()) {
    std::size_t end = header.find('\n', at);
    if (end == std::string::npos) fail(path, "corrupt checkpoint header (unterminated line)");
    const std::string text = header.substr(at, end - at);
    const std::size_t space = text.find(' ');
    if (space == std::string::npos || space == 0) fail(path, "corrupt checkpoint header line '" + text + "'");
    const std::string key = text.substr(0, space), value = text.substr(space + 1);
    if (key == "samples_done" || key == "nonfinite_samples" || key == "pixels" || key == "state_bytes" ||
        key == "aov_bytes" || key == "device")
      meta[key] = value;
    else
      c.identity.push_back({key, value});
    at = end + 1;
  }
  auto integer = [&](const char* key) -> std::uint64_t {
    auto it = meta.find(key);
    if (it == meta.end()) fail(path, std::string("checkpoint header lacks '") + key + "'");
    try {
      std::size_t used = 0;
      const unsigned long long v = std::stoull(it->second, &used);
      if (used != it->second.size()) throw std::invalid_argument(key);
      return v;
    } catch (const std::exception&) {
      fail(path, std::string("checkpoint header: '") + key + "' is not a number: " + it->second);
    }
  };
  c.pixels = integer("pixels");
  const std::uint64_t samplesDone = integer("samples_done");
  c.accumulation.nonFiniteSamples = integer("nonfinite_samples");
  if (integer("state_bytes") != kAccumulationStateBytes)
    fail(path, "checkpoint of " + meta["state_bytes"] + " state bytes per pixel; this build keeps " +
                   std::to_string(kAccumulationStateBytes));
  if (samplesDone > (1u << 30)) fail(path, "checkpoint header: samples_done " + meta["samples_done"] + " out of range");
  c.accumulation.samplesDone = int(samplesDone);
  c.device = meta.count("device") ? meta["device"] : std::string();
  const std::uint64_t aovBytes = meta.count("aov_bytes") ? integer("aov_bytes") : 0;
  if (aovBytes != 0 && aovBytes != kAovSumBytes + kAovIdBytes)
    fail(path, "checkpoint of " + meta["aov_bytes"] + " AOV bytes per pixel; this build keeps " +
                   std::to_string(kAovSumBytes + kAovIdBytes));
  if (c.pixels > payloadBytes ||
      payloadBytes != c.pixels * (kAccumulationStateBytes + sizeof(std::uint32_t) + aovBytes))
    fail(path, "corrupt checkpoint: " + std::to_string(payloadBytes) + " payload bytes for " +
                   std::to_string(c.pixels) + " pixels");
  const char* payload = file.data() + 16 + headerBytes + 8;
  c.accumulation.state.assign(payload, payload + c.pixels * kAccumulationStateBytes);
  c.accumulation.samples.resize(c.pixels);
  std::memcpy(c.accumulation.samples.data(), payload + c.pixels * kAccumulationStateBytes, c.pixels * 4);
  const char* aovs = payload + c.pixels * (kAccumulationStateBytes + 4);
  c.accumulation.aovs.assign(aovs, aovs + c.pixels * aovBytes);
  return c;
}

void requireSameRender(const std::filesystem::path& path, const Checkpoint& found,
                       const std::vector<CheckpointField>& expected) {
  std::string differences;
  auto add = [&](const std::string& text) { differences += (differences.empty() ? "" : "; ") + text; };
  for (const CheckpointField& want : expected) {
    const CheckpointField* have = nullptr;
    for (const CheckpointField& f : found.identity)
      if (f.key == want.key) have = &f;
    if (!have)
      add(want.key + " missing from the checkpoint");
    else if (have->value != want.value && want.key == "scene")
      add("another scene (scene content hash " + have->value + " in the checkpoint, " + want.value + " here)");
    else if (have->value != want.value && (want.key == "environment" || want.key == "kernels"))
      add("other " + want.key + " (hash " + have->value + " in the checkpoint, " + want.value + " here)");
    else if (have->value != want.value)
      add(want.key + " " + have->value + " in the checkpoint, " + want.value + " here");
  }
  for (const CheckpointField& f : found.identity) {
    bool known = false;
    for (const CheckpointField& want : expected) known = known || want.key == f.key;
    if (!known) add("'" + f.key + "' unknown to this build");
  }
  if (!differences.empty())
    throw CheckpointError(path.string() + ": the checkpoint is of another render: " + differences +
                          " (render with the checkpoint's settings, or without --resume to start over)");
}

}  // namespace wt
