// Stress rows for textures: an emissive quad filling an orthographic view
// shows its emissive texture exactly (emission 1, black base, nothing else
// lit), under texture coordinates far from [0, 1], not a number, and images
// of one texel, odd sizes and 16 bits.
#include "stress/stress.h"

#include "render/renderer.h"
#include "scene/generators.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>

namespace wt {
namespace {

constexpr int kRepeat = 10497, kClampToEdge = 33071, kMirroredRepeat = 33648;  // glTF's wrap modes
constexpr int kNearest = 9728, kLinear = 9729, kLinearMipmapLinear = 9987;     // glTF's filters

/// What a row's image must show.
enum class Expect {
  kEveryPixel,  ///< every pixel the value, within 1e-6 relative (no noise: one texel everywhere)
  kMean,        ///< the image's mean the value (full periods of the texture), within 5 standard errors + half a step of the image's bit depth (mip levels are stored at it) + 1e-5
  kTexelRange,  ///< every pixel within the texels' range per channel (which texel is the sampler's choice)
};

struct TextureCase {
  std::string name;
  DecodedImage image;
  int wrap = kRepeat, mag = kLinear, min = kLinearMipmapLinear;
  glm::vec2 uv0{0.0f}, uvSpan{1.0f};  ///< the quad's corners: uv0 + (0|1, 0|1) * uvSpan
  bool nanUv = false;                 ///< every corner's uv NaN (uv0 and uvSpan unused)
  Expect expect = Expect::kMean;
};

/// An image of w x h texels from f(x, y) in [0, 1] per channel, 8 or 16 bits.
DecodedImage makeImage(std::uint32_t w, std::uint32_t h, bool sixteen, const std::string& name,
                       const std::function<glm::vec3(std::uint32_t, std::uint32_t)>& f) {
  DecodedImage image;
  image.width = w, image.height = h, image.sixteenBit = sixteen, image.name = name;
  for (std::uint32_t y = 0; y < h; ++y)
    for (std::uint32_t x = 0; x < w; ++x) {
      glm::vec3 c = f(x, y);
      for (int ch = 0; ch < 4; ++ch) {
        float v = ch < 3 ? c[ch] : 1.0f;
        if (sixteen) image.rgba16.push_back(std::uint16_t(std::lround(v * 65535.0f)));
        else image.rgba8.push_back(std::uint8_t(std::lround(v * 255.0f)));
      }
    }
  return image;
}

/// The texel's value as the kernels decode it (linear images).
glm::dvec3 texel(const DecodedImage& image, std::uint32_t i) {
  glm::dvec3 c;
  for (int ch = 0; ch < 3; ++ch)
    c[ch] = image.sixteenBit ? image.rgba16[4 * i + ch] / 65535.0 : image.rgba8[4 * i + ch] / 255.0;
  return c;
}

/// The quad y = 0 over [-1, 1]^2 emitting 1 times the texture (linear) from
/// both faces, seen straight down by an orthographic camera that frames it.
Scene textureStage(const TextureCase& c) {
  Scene scene;
  const glm::vec3 corners[4] = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
  const glm::vec2 unit[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < 4; ++v) {
    scene.positions.push_back({corners[v].x, corners[v].y, corners[v].z, 0});
    scene.normals.push_back({0, 0, 0, 0});
    scene.texcoords.push_back(c.nanUv ? glm::vec2(nan) : c.uv0 + unit[v] * c.uvSpan);
  }
  scene.triangles.push_back({0, 2, 1, 0});
  scene.triangles.push_back({0, 3, 2, 0});
  scene.materials.push_back(makeMaterial(glm::vec3(0.0f), glm::vec3(1.0f), /*twoSided=*/true));
  scene.materialNames.push_back("screen");
  const std::uint32_t texture = scene.textures.addTexture(scene.textures.addImage(c.image, false), c.wrap, c.wrap, c.mag, c.min);
  scene.materialTextures.resize(WT_TEXTURE_SLOTS);
  WtTextureRef ref{};
  ref.texture = texture;
  ref.scale = 1.0f;
  ref.transform_u = {1.0f, 0.0f, 0.0f, 0.0f};
  ref.transform_v = {0.0f, 1.0f, 0.0f, 0.0f};
  scene.materialTextures[WT_TEXTURE_SLOT_EMISSIVE] = ref;
  scene.materials[0].texture_mask |= 1u << WT_TEXTURE_SLOT_EMISSIVE;
  CameraDesc camera;
  camera.orthographic = true;
  camera.xmag = camera.ymag = 1.0f;
  camera.cameraToWorld = glm::mat4(glm::vec4(1, 0, 0, 0), glm::vec4(0, 0, -1, 0), glm::vec4(0, 1, 0, 0),
                                   glm::vec4(0, 2, 0, 1));
  scene.camera = camera;
  return scene;
}

}  // namespace

std::vector<StressRow> stressTextures(Context& context, const StressOptions& options) {
  auto ramp = [](std::uint32_t w, std::uint32_t h) {
    return [w, h](std::uint32_t x, std::uint32_t y) {
      return glm::vec3((x + 0.5f) / w, (y + 0.5f) / h, ((x + y) % 3) / 2.0f);
    };
  };
  std::vector<TextureCase> cases;
  auto add = [&](std::string name, DecodedImage image, Expect expect) -> TextureCase& {
    TextureCase c;
    c.name = std::move(name);
    c.image = std::move(image);
    c.expect = expect;
    cases.push_back(std::move(c));
    return cases.back();
  };
  add("a 1 x 1 texture (mipmapped, linear)", makeImage(1, 1, false, "one texel", [](auto, auto) {
        return glm::vec3(200 / 255.0f, 100 / 255.0f, 50 / 255.0f);
      }), Expect::kEveryPixel);
  add("a 3 x 5 texture (not a power of two), trilinear, repeat", makeImage(3, 5, false, "3x5", ramp(3, 5)), Expect::kMean);
  {
    TextureCase& c = add("a 7 x 1 texture, nearest, clamped", makeImage(7, 1, false, "7x1", ramp(7, 1)), Expect::kMean);
    c.wrap = kClampToEdge, c.mag = kNearest, c.min = kNearest;
  }
  {
    TextureCase& c = add("a 5 x 3 texture repeated 1000 times across the quad (minified to its 1 x 1 level)",
                         makeImage(5, 3, false, "5x3", ramp(5, 3)), Expect::kMean);
    c.uvSpan = glm::vec2(1000.0f);
  }
  add("16 bits: one value, 1000 / 65535, that 8 bits cannot hold (4 / 255 is 4e-4 away)",
      makeImage(2, 3, true, "16-bit", [](auto, auto) { return glm::vec3(1000.0f / 65535.0f); }), Expect::kEveryPixel);
  add("16 bits: a 3 x 3 ramp, trilinear, repeat", makeImage(3, 3, true, "16-bit ramp", ramp(3, 3)), Expect::kMean);
  // coordinates where float has no fraction left, or no integer either
  for (float at : {1e7f, -3e7f, 1e30f, -1e38f})
    for (int wrap : {kRepeat, kMirroredRepeat, kClampToEdge}) {
      const char* mode = wrap == kRepeat ? "repeat" : wrap == kMirroredRepeat ? "mirrored repeat" : "clamp";
      TextureCase& c = add("uv around " + stressFormat("%g", at) + ", " + mode, makeImage(4, 3, false, "4x3", ramp(4, 3)),
                           Expect::kTexelRange);
      c.wrap = wrap, c.uv0 = glm::vec2(at), c.uvSpan = glm::vec2(std::abs(at) * 1e-7f);
    }
  for (bool linear : {false, true}) {
    TextureCase& c = add(std::string("NaN uvs, ") + (linear ? "trilinear" : "nearest"),
                         makeImage(4, 3, false, "4x3", ramp(4, 3)), Expect::kTexelRange);
    c.nanUv = true;
    if (!linear) c.mag = c.min = kNearest;
  }
  {
    TextureCase& c = add("infinite uvs", makeImage(4, 3, false, "4x3", ramp(4, 3)), Expect::kTexelRange);
    c.uv0 = glm::vec2(std::numeric_limits<float>::infinity());
  }

  RenderSettings settings;
  settings.width = settings.height = options.quick ? 16 : 48;
  settings.samplesPerPixel = options.quick ? 16 : 128;
  settings.maxBounces = 1;
  settings.background = glm::vec3(0.0f);
  std::vector<StressRow> rows;
  for (const TextureCase& c : cases) {
    auto start = std::chrono::steady_clock::now();
    StressRow row;
    row.group = "textures";
    row.name = c.name;
    const std::uint32_t texels = c.image.width * c.image.height;
    glm::dvec3 lo(INFINITY), hi(-INFINITY), mean(0.0);
    for (std::uint32_t i = 0; i < texels; ++i) {
      glm::dvec3 t = texel(c.image, i);
      lo = glm::min(lo, t), hi = glm::max(hi, t), mean += t / double(texels);
    }
    switch (c.expect) {
      case Expect::kEveryPixel: row.criterion = "0 NaN/Inf; every pixel the texel's value within 1e-6 relative"; break;
      case Expect::kMean:
        row.criterion = "0 NaN/Inf; the image's mean the texels' mean within 5 standard errors + half a step of " +
                        std::string(c.image.sixteenBit ? "16" : "8") + " bits (the mip levels' storage) + 1e-5";
        break;
      case Expect::kTexelRange: row.criterion = "0 NaN/Inf; every pixel within the texels' range"; break;
    }
    try {
      Renderer renderer(context, textureStage(c), settings);
      for (int s = 0; s < settings.samplesPerPixel; ++s) renderer.renderSample();
      Image img = renderer.readImage();
      const std::uint64_t nonFinite = renderer.stats().nonFiniteSamples;
      std::size_t bad = 0, outside = 0;
      double worst = 0.0;  // the largest deviation: relative (every pixel), in standard errors (mean), absolute (range)
      glm::dvec3 sum(0.0), variance(0.0);
      const std::size_t pixels = std::size_t(img.width) * img.height;
      for (std::size_t p = 0; p < pixels; ++p)
        for (int ch = 0; ch < 3; ++ch) {
          double v = img.rgb[3 * p + ch];
          if (!std::isfinite(v) || !std::isfinite(img.rgbVariance[3 * p + ch])) {
            ++bad;
            continue;
          }
          sum[ch] += v, variance[ch] += img.rgbVariance[3 * p + ch] / std::max<std::uint32_t>(img.samples[p], 1);
          if (c.expect == Expect::kEveryPixel) {
            double rel = std::abs(v - lo[ch]) / std::max(lo[ch], 1e-30);
            worst = std::max(worst, rel), outside += rel > 1e-6;
          } else if (c.expect == Expect::kTexelRange) {
            double off = std::max(lo[ch] - v, v - hi[ch]);
            worst = std::max(worst, off), outside += off > 1e-6;
          }
        }
      std::string figure = std::to_string(nonFinite) + " NaN/Inf samples, " + std::to_string(bad) + " non-finite pixels; ";
      bool pass = nonFinite == 0 && bad == 0;
      if (c.expect == Expect::kMean) {
        for (int ch = 0; ch < 3; ++ch) {
          double m = sum[ch] / double(pixels), se = std::sqrt(variance[ch]) / double(pixels);
          double tolerance = 5.0 * se + 0.5 / (c.image.sixteenBit ? 65535.0 : 255.0) + 1e-5;
          worst = std::max(worst, std::abs(m - mean[ch]));
          pass = pass && std::abs(m - mean[ch]) <= tolerance;
          figure += std::string(ch ? ", " : "mean ") + stressFormat("%.5f", m) + " vs " + stressFormat("%.5f", mean[ch]) +
                    " (+- " + stressFormat("%.1e", se) + ")";
        }
      } else {
        figure += std::to_string(outside) + " pixel channels off, worst by " + stressFormat("%.2g", worst) +
                  (c.expect == Expect::kEveryPixel ? " relative" : "");
        pass = pass && outside == 0;
      }
      row.figure = figure;
      row.pass = pass;
    } catch (const std::exception& e) {
      row.figure = std::string("failed: ") + e.what();
    }
    row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    rows.push_back(row);
  }
  return rows;
}

}  // namespace wt
