#include "device/program.h"

#include "core/embedded.h"
#include "core/log.h"
#include "device/program_cache.h"
#include "geometry/primitives.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

namespace wt {
namespace {

std::optional<std::filesystem::path> g_kernelDir;
bool g_kernelDirFromEnv = false;
std::optional<std::filesystem::path> g_fallbackDir;

}  // namespace

std::optional<std::filesystem::path> kernelDirectory() {
  if (!g_kernelDirFromEnv) {
    g_kernelDirFromEnv = true;
    if (!g_kernelDir) {
      if (const char* env = std::getenv("WT_KERNEL_DIR"); env && *env) g_kernelDir = env;
    }
  }
  return g_kernelDir;
}

namespace {

/// The whole file, or nothing where it cannot be read.
std::optional<std::string> readFrom(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A kernel file by its path relative to kernels/: from the kernel folder
/// when one is set, else embedded, else from the fallback folder.
std::optional<std::string> readKernelFile(const std::string& rel) {
  if (auto dir = kernelDirectory()) return readFrom(*dir / rel);
  if (auto contents = embedded::find("kernels/" + rel)) return std::string(*contents);
  if (g_fallbackDir) return readFrom(*g_fallbackDir / rel);
  return std::nullopt;
}

std::string normalise(const std::filesystem::path& p) { return p.lexically_normal().generic_string(); }

void expandInto(const std::string& rel, std::set<std::string>& seen, std::ostringstream& out,
                const std::string& includedFrom) {
  if (!seen.insert(rel).second) return;
  std::optional<std::string> text = readKernelFile(rel);
  if (!text)
    throw DeviceError("kernel source '" + rel + "' not found" +
                      (includedFrom.empty() ? "" : " (included from " + includedFrom + ")") +
                      (kernelDirectory() ? " in " + kernelDirectory()->string() : ""));
  std::istringstream in(*text);
  std::string line;
  int lineNo = 0;
  out << "#line 1 \"" << rel << "\"\n";
  while (std::getline(in, line)) {
    ++lineNo;
    std::size_t hash = line.find_first_not_of(" \t");
    if (hash != std::string::npos && line.compare(hash, 8, "#include") == 0) {
      std::size_t open = line.find('"', hash);
      std::size_t close = open == std::string::npos ? open : line.find('"', open + 1);
      // <system> headers only appear in the host branches of shared headers:
      // leave them for the device preprocessor, which skips those branches.
      if (open == std::string::npos || close == std::string::npos) {
        out << line << '\n';
        continue;
      }
      std::string name = line.substr(open + 1, close - open - 1);
      std::string sibling = normalise(std::filesystem::path(rel).parent_path() / name);
      std::string target = readKernelFile(sibling) ? sibling : normalise(name);
      expandInto(target, seen, out, rel + ":" + std::to_string(lineNo));
      out << "#line " << lineNo + 1 << " \"" << rel << "\"\n";
      continue;
    }
    out << line << '\n';
  }
}

}  // namespace

void setKernelDirectory(const std::optional<std::filesystem::path>& dir) {
  g_kernelDir = dir;
  g_kernelDirFromEnv = true;
}

void setKernelFallbackDirectory(const std::optional<std::filesystem::path>& dir) { g_fallbackDir = dir; }

std::string expandKernelSource(const std::string& file) {
  std::set<std::string> seen;
  std::ostringstream out;
  expandInto(file, seen, out, "");
  return out.str();
}

void setMaterialFeatures(KernelFeatures& features, std::span<const WtMaterial> materials) {
  auto any = [&](auto&& pred) {
    return std::any_of(materials.begin(), materials.end(),
                       [&](const WtMaterial& m) { return m.model == WT_MATERIAL_PBR && pred(m); });
  };
  // the dielectric share is reachable where metallic is below 1 somewhere:
  // its factor, or a metallic-roughness texture that multiplies it
  auto dielectric = [](const WtMaterial& m) {
    return m.base_color.w < 1.0f || (m.texture_mask & (1u << WT_TEXTURE_SLOT_METALLIC_ROUGHNESS)) != 0u;
  };
  features.pbr = any([](const WtMaterial&) { return true; });
  features.transmission = any([&](const WtMaterial& m) { return m.transmission > 0.0f && dielectric(m); });
  // the opaque dielectric's F0 departs from 0.04 (ior on its opaque share), or the specular extension weighs or tints it
  features.specular = any([&](const WtMaterial& m) {
    bool tinted = m.specular.x != 1.0f || m.specular.y != 1.0f || m.specular.z != 1.0f;
    const bool textured = m.texture_mask & ((1u << WT_TEXTURE_SLOT_SPECULAR) | (1u << WT_TEXTURE_SLOT_SPECULAR_COLOR));
    return dielectric(m) && (m.specular.w != 1.0f || tinted || textured || (m.ior != 1.5f && m.transmission < 1.0f));
  });
  features.clearcoat = any([](const WtMaterial& m) { return m.clearcoat > 0.0f; });
  features.sheen = any([](const WtMaterial& m) { return m.sheen.x > 0.0f || m.sheen.y > 0.0f || m.sheen.z > 0.0f; });
  features.anisotropy = any([](const WtMaterial& m) { return m.anisotropy > 0.0f; });
  features.iridescence = any([](const WtMaterial& m) { return m.iridescence.x > 0.0f; });
  features.thinShadows = any([](const WtMaterial& m) { return m.shadow_pass != 0u; });
}

std::vector<std::string> kernelDefines(const KernelFeatures& features) {
  std::vector<std::string> defines = {
      "-D WT_INTEGRATOR_MINIMAL=" + std::string(features.integratorMinimal ? "1" : "0"),
      "-D WT_BVH_STACK_SIZE=" + std::to_string(features.bvhStackSize),
      "-D WT_HAS_PBR=" + std::string(features.pbr ? "1" : "0"),
      "-D WT_HAS_TRANSMISSION=" + std::string(features.pbr && features.transmission ? "1" : "0"),
      "-D WT_HAS_THIN_SHADOWS=" + std::string(features.pbr && features.transmission && features.thinShadows ? "1" : "0"),
      "-D WT_HAS_QUAD_LIGHTS=" + std::string(features.quadLights ? "1" : "0"),
      "-D WT_HAS_LIGHT_TREE=" + std::string(features.lightTree ? "1" : "0"),
      "-D WT_HAS_OTHER_LIGHTS=" + std::string(features.otherLights ? "1" : "0"),
      "-D WT_HAS_TEXTURES=" + std::string(features.textures ? "1" : "0"),
      "-D WT_HAS_VERTEX_COLORS=" + std::string(features.vertexColors ? "1" : "0"),
      "-D WT_HAS_SPECULAR=" + std::string(features.pbr && features.specular ? "1" : "0"),
      "-D WT_HAS_CLEARCOAT=" + std::string(features.pbr && features.clearcoat ? "1" : "0"),
      "-D WT_HAS_SHEEN=" + std::string(features.pbr && features.sheen ? "1" : "0"),
      "-D WT_HAS_ANISOTROPY=" + std::string(features.pbr && features.anisotropy ? "1" : "0"),
      "-D WT_HAS_IRIDESCENCE=" + std::string(features.pbr && features.iridescence ? "1" : "0"),
      "-D WT_HAS_ALPHA=" + std::string(features.alpha ? "1" : "0"),
      "-D WT_PACKET_WIDTH=" + std::to_string(features.packetWidth),
      "-D WT_STREAM_PREFETCH=" + std::string(features.streamPrefetch ? "1" : "0"),
      "-D WT_AOV=" + std::string(features.aov ? "1" : "0"),
      "-D WT_BVH_COST=" + std::string(features.aov && features.bvhCost ? "1" : "0"),
      "-D WT_SHADE_LANES=" + std::string(features.shadeLanes ? "1" : "0"),
  };
  if (features.shadeLanes) defines.push_back("-D WT_SHADE_LANES_WIDTH=" + std::to_string(features.shadeLanesWidth));
  for (const PrimitiveType& type : primitiveTypes())
    defines.push_back("-D " + std::string(type.define) + "=" + (features.primitives[type.id] ? "1" : "0"));
  return defines;
}

bool streamPrefetchFor(const DeviceInfo& device, std::size_t sceneBytes) {
  return device.globalCacheBytes == 0 || sceneBytes > device.globalCacheBytes;
}

namespace {

/// `requested` (8 or 16) when non-zero, else 16 where the device's native
/// float vector is 16 wide, else 8; `what` names the width in the error.
int vectorWidthFor(const DeviceInfo& device, int requested, const char* what) {
  if (requested == 8 || requested == 16) return requested;
  if (requested != 0)
    throw DeviceError(std::string(what) + " " + std::to_string(requested) + " is not supported (8 or 16)");
  return device.nativeFloatWidth < 16 ? 8 : 16;
}

}  // namespace

int packetWidthFor(const DeviceInfo& device, int requested, std::size_t triangles) {
  const int width = vectorWidthFor(device, requested, "packet width");
  return requested == 0 && triangles > kWidePacketMaxTriangles ? 8 : width;
}

int shadeLanesWidthFor(const DeviceInfo& device, int requested) {
  return vectorWidthFor(device, requested, "shade lanes width");
}

namespace {

/// kernels/<root> built with `options` (after the common ones), once per context and through the program cache.
cl::Program buildRoot(Context& context, const std::string& root, const std::string& extraOptions) {
  std::string source = expandKernelSource(root);
  // argument names let KernelBinding check each kernel against its host declaration at start-up
  const std::string options = "-cl-std=CL1.2 -cl-kernel-arg-info" + extraOptions;
  const std::string key = toHex(programCacheKey(context.info(), source, options));
  if (std::optional<cl::Program> built = context.builtProgram(key)) {
    log::debug("program " + root + ": built in this context already");
    return *built;
  }
  cl::Program program = buildCachedProgram(context, source, options, root).program;
  context.keepProgram(key, program);
  return program;
}

}  // namespace

cl::Program buildProgram(Context& context, const KernelFeatures& features, const std::string& root) {
  std::string options;
  for (const std::string& d : kernelDefines(features)) options += " " + d;
  // Oclgrind (the kernel checker) lacks the llvm.bitreverse, llvm.prefetch,
  // llvm.cttz and llvm.experimental.noalias.scope.decl intrinsics
  // (tests/oclgrind/prefetch.cl, ctz.cl, noalias_scope.cl), and loses the
  // initialisation of .hi of 16-wide vectors (tests/oclgrind/upper_half.cl).
  if (context.underOclgrind())
    options +=
        " -D WT_AVOID_BITREVERSE=1 -D WT_FOLD_THROUGH_MEMORY=1 -D WT_NO_PREFETCH=1 -D WT_NO_CTZ=1"
        " -D WT_NO_SRET_INLINE=1";
  return buildRoot(context, root, options);
}

std::vector<std::string> frameProgramDefines(bool aov) { return {"-D WT_AOV=" + std::string(aov ? "1" : "0")}; }

cl::Program buildFrameProgram(Context& context, bool aov) {
  std::string options;
  for (const std::string& d : frameProgramDefines(aov)) options += " " + d;
  return buildRoot(context, "frame.cl", options);
}

}  // namespace wt
