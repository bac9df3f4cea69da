// The texture sampler on the device (kernels/materials/texture.cl, run
// through kernels/texture_tests.cl) against values worked out here: texel
// centres, the exact sRGB decoding, bilinear means, each wrap mode per
// axis, nearest against linear, the choice and blend of mip levels, the
// level of a footprint, and finite in-image answers for NaN and huge uv.
#include "device/program.h"
#include "device_fixture.h"
#include "test_util.h"
#include "texture/texture.h"

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

namespace wt {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// glTF sampler codes
constexpr int kRepeat = 10497, kClamp = 33071, kMirror = 33648;
constexpr int kNearest = 9728, kLinear = 9729;
constexpr int kNearestMipNearest = 9984, kLinearMipNearest = 9985, kNearestMipLinear = 9986, kLinearMipLinear = 9987;

/// The three arrays the sampler reads.
struct Arrays {
  std::vector<WtTexture> textures;
  std::vector<WtTextureLevel> levels;
  std::vector<wt_uint> texels;
};

Arrays arraysOf(const TextureSet& set) { return {set.textures, set.levels, set.texels}; }

struct Query {
  float u, v, lod;
  std::uint32_t texture;
};

std::vector<glm::vec4> sample(const Arrays& a, const std::vector<Query>& queries) {
  Context& ctx = test::deviceContext();
  auto upload = [&](const auto& v) {
    using T = typename std::decay_t<decltype(v)>::value_type;
    return cl::Buffer(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, v.size() * sizeof(T),
                      const_cast<T*>(v.data()));
  };
  std::vector<cl_float4> in;
  for (const Query& q : queries) in.push_back({{q.u, q.v, q.lod, std::bit_cast<float>(q.texture)}});
  const cl_uint n = cl_uint(in.size());
  cl::Buffer textures = upload(a.textures), levels = upload(a.levels), texels = upload(a.texels);
  cl::Buffer queryBuffer = upload(in);
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(cl_float4));
  cl::Kernel k(test::testProgram("texture_tests.cl"), "test_texture_sample");
  k.setArg(0, n), k.setArg(1, textures), k.setArg(2, levels), k.setArg(3, texels), k.setArg(4, queryBuffer);
  k.setArg(5, out);
  ctx.launch("test_texture_sample", k, n);
  std::vector<cl_float4> got(n);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * sizeof(cl_float4), got.data());
  std::vector<glm::vec4> result;
  for (const cl_float4& g : got) result.emplace_back(g.s[0], g.s[1], g.s[2], g.s[3]);
  return result;
}

glm::vec4 sampleOne(const Arrays& a, Query q) { return sample(a, {q})[0]; }

std::string str(glm::vec4 v) {
  return "(" + std::to_string(v.x) + ", " + std::to_string(v.y) + ", " + std::to_string(v.z) + ", " +
         std::to_string(v.w) + ")";
}

void expectNear(glm::vec4 got, glm::vec4 expected, float tolerance, const std::string& what) {
  for (int c = 0; c < 4; ++c)
    EXPECT_NEAR(got[c], expected[c], tolerance) << what << ": got " << str(got) << ", expected " << str(expected);
}

DecodedImage image8(std::uint32_t w, std::uint32_t h, std::vector<std::uint8_t> rgba) {
  DecodedImage image;
  image.width = w, image.height = h, image.rgba8 = std::move(rgba), image.name = "synthetic";
  return image;
}

DecodedImage image16(std::uint32_t w, std::uint32_t h, std::vector<std::uint16_t> rgba) {
  DecodedImage image;
  image.width = w, image.height = h, image.sixteenBit = true, image.rgba16 = std::move(rgba), image.name = "synthetic16";
  return image;
}

template <typename T>
std::vector<T> randomValues(std::size_t count, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<T> out(count);
  for (auto& v : out) v = static_cast<T>(rng());
  return out;
}

/// Texel (x, y) of an 8-bit level as stored, linear (no sRGB decoding).
glm::vec4 storedTexel(const TextureSet& set, std::uint32_t level, std::uint32_t x, std::uint32_t y) {
  const WtTextureLevel& l = set.levels[level];
  const wt_uint p = set.texels[l.offset + y * l.width + x];
  return glm::vec4(float(p & 255u), float((p >> 8) & 255u), float((p >> 16) & 255u), float(p >> 24)) / 255.0f;
}

// ---------------------------------------------------------------------------

TEST(TextureSample, TexelCentresGiveTheTexelExactly) {
  const std::uint32_t w = 5, h = 3;
  const auto rgba8 = randomValues<std::uint8_t>(w * h * 4, 1);
  const auto rgba16 = randomValues<std::uint16_t>(w * h * 4, 2);
  TextureSet set;
  const std::uint32_t a = set.addImage(image8(w, h, rgba8), false), b = set.addImage(image16(w, h, rgba16), false);
  for (std::uint32_t image : {a, b})
    for (int mag : {kNearest, kLinear}) set.addTexture(image, kRepeat, kRepeat, mag, kLinearMipLinear);
  std::vector<Query> queries;
  for (std::uint32_t t = 0; t < 4; ++t)
    for (std::uint32_t y = 0; y < h; ++y)
      for (std::uint32_t x = 0; x < w; ++x) queries.push_back({(x + 0.5f) / w, (y + 0.5f) / h, 0.0f, t});
  const auto got = sample(arraysOf(set), queries);
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const std::size_t texel = i % (w * h);
    const bool wide = queries[i].texture >= 2;
    glm::vec4 expected;
    for (int c = 0; c < 4; ++c)
      expected[c] = wide ? float(rgba16[4 * texel + c] / 65535.0) : float(rgba8[4 * texel + c] / 255.0);
    expectNear(got[i], expected, 1e-6f, "texture " + std::to_string(queries[i].texture) + " texel " + std::to_string(texel));
  }
}

TEST(TextureSample, SrgbDecodeIsTheExactTransferFunctionAndSkipsAlpha) {
  // every 8-bit code once per channel, alpha too (which stays linear)
  std::vector<std::uint8_t> rgba8;
  for (int i = 0; i < 256; ++i) rgba8.insert(rgba8.end(), {std::uint8_t(i), std::uint8_t(255 - i), std::uint8_t(i), std::uint8_t(i)});
  std::vector<std::uint16_t> rgba16;
  for (int i = 0; i < 64; ++i) {
    const auto v = std::uint16_t(i * 1040 + i % 7);
    rgba16.insert(rgba16.end(), {v, std::uint16_t(65535 - v), v, v});
  }
  TextureSet set;
  set.addTexture(set.addImage(image8(256, 1, rgba8), true), kRepeat, kRepeat, kNearest, kNearest);
  set.addTexture(set.addImage(image16(64, 1, rgba16), true), kRepeat, kRepeat, kNearest, kNearest);
  std::vector<Query> queries;
  for (int i = 0; i < 256; ++i) queries.push_back({(i + 0.5f) / 256.0f, 0.5f, 0.0f, 0});
  for (int i = 0; i < 64; ++i) queries.push_back({(i + 0.5f) / 64.0f, 0.5f, 0.0f, 1});
  const auto got = sample(arraysOf(set), queries);
  for (std::size_t q = 0; q < queries.size(); ++q) {
    const bool wide = q >= 256;
    const std::size_t i = wide ? q - 256 : q;
    const double scale = wide ? 65535.0 : 255.0;
    for (int c = 0; c < 4; ++c) {
      const double encoded = (wide ? rgba16[4 * i + c] : rgba8[4 * i + c]) / scale;
      const double expected = c < 3 ? srgbToLinear(encoded) : encoded;
      EXPECT_NEAR(got[q][c], expected, 1e-6 * expected + 1e-9)
          << (wide ? "16" : "8") << "-bit texel " << i << " channel " << c << " (encoded " << encoded << ")";
    }
  }
}

TEST(TextureSample, BilinearHalfwayIsTheMeanInLinearLight) {
  const std::uint32_t w = 4, h = 4;
  const auto rgba = randomValues<std::uint8_t>(w * h * 4, 3);
  TextureSet set;
  set.addTexture(set.addImage(image8(w, h, rgba), false), kClamp, kClamp, kLinear, kLinear);
  auto texel = [&](std::uint32_t x, std::uint32_t y) {
    const std::uint8_t* p = &rgba[(y * w + x) * 4];
    return glm::vec4(p[0], p[1], p[2], p[3]) / 255.0f;
  };
  std::vector<Query> queries;
  std::vector<glm::vec4> expected;
  for (std::uint32_t y = 0; y + 1 < h; ++y)
    for (std::uint32_t x = 0; x + 1 < w; ++x) {
      queries.push_back({(x + 1.0f) / w, (y + 0.5f) / h, 0.0f, 0});  // between two in a row
      expected.push_back(0.5f * (texel(x, y) + texel(x + 1, y)));
      queries.push_back({(x + 0.5f) / w, (y + 1.0f) / h, 0.0f, 0});  // between two in a column
      expected.push_back(0.5f * (texel(x, y) + texel(x, y + 1)));
      queries.push_back({(x + 1.0f) / w, (y + 1.0f) / h, 0.0f, 0});  // among four
      expected.push_back(0.25f * (texel(x, y) + texel(x + 1, y) + texel(x, y + 1) + texel(x + 1, y + 1)));
      queries.push_back({(x + 0.75f) / w, (y + 0.5f) / h, 0.0f, 0});  // a quarter of the way
      expected.push_back(0.75f * texel(x, y) + 0.25f * texel(x + 1, y));
    }
  const auto got = sample(arraysOf(set), queries);
  for (std::size_t i = 0; i < queries.size(); ++i)
    expectNear(got[i], expected[i], 2e-6f, "u " + std::to_string(queries[i].u) + ", v " + std::to_string(queries[i].v));

  // sRGB black and white: halfway is linear 0.5, not the decoded 50% grey (0.214)
  TextureSet srgb;
  srgb.addTexture(srgb.addImage(image8(2, 1, {0, 0, 0, 0, 255, 255, 255, 255}), true), kClamp, kClamp, kLinear, kLinear);
  expectNear(sampleOne(arraysOf(srgb), {0.5f, 0.5f, 0.0f, 0}), glm::vec4(0.5f), 1e-6f, "sRGB halfway");
}

/// The texel column a wrap mode gives coordinate u on n texels (nearest),
/// from the continuous definitions: repeat takes u's fraction, clamp clamps
/// it to [0, 1), mirror reflects every other period.
int expectedColumn(double u, int n, int mode) {
  double x = u;
  if (mode == kRepeat) x = u - std::floor(u);
  if (mode == kMirror) {
    x = u - 2.0 * std::floor(u / 2.0);
    if (x > 1.0) x = 2.0 - x;
  }
  return std::clamp(int(std::floor(x * n)), 0, n - 1);
}

TEST(TextureSample, EachWrapModePicksItsTexelOnEachAxis) {
  // 3 x 3: R codes the column, G the row
  const int n = 3;
  std::vector<std::uint8_t> rgba;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) rgba.insert(rgba.end(), {std::uint8_t(80 * x), std::uint8_t(80 * y), 0, 255});
  TextureSet set;
  const std::uint32_t image = set.addImage(image8(n, n, rgba), false);
  const int modes[3] = {kRepeat, kClamp, kMirror};
  for (int s : modes)
    for (int t : modes) set.addTexture(image, s, t, kNearest, kNearest);
  // none of them within 0.05 texels of a texel edge
  const std::vector<float> coordinates = {-0.25f, 1.25f, 2.75f, -1.1f, -2.6f, 3.3f, 0.1f, 0.9f, -0.9f, 1.9f, 5.45f};
  std::vector<Query> queries;
  for (std::uint32_t tex = 0; tex < 9; ++tex)
    for (float u : coordinates)
      for (float v : {0.1f, -0.25f, 1.25f, 2.75f, -2.6f}) queries.push_back({u, v, 0.0f, tex});
  const auto got = sample(arraysOf(set), queries);
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const Query& q = queries[i];
    const int s = modes[q.texture / 3], t = modes[q.texture % 3];
    const int x = expectedColumn(q.u, n, s), y = expectedColumn(q.v, n, t);
    EXPECT_EQ(std::lround(got[i].x * 255.0f), 80 * x) << "wrap S " << s << ", T " << t << ", u " << q.u;
    EXPECT_EQ(std::lround(got[i].y * 255.0f), 80 * y) << "wrap S " << s << ", T " << t << ", v " << q.v;
  }
  // the coordinates tell every pair of modes apart
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b) {
      bool differ = false;
      for (float u : coordinates) differ = differ || expectedColumn(u, n, modes[a]) != expectedColumn(u, n, modes[b]);
      EXPECT_TRUE(differ) << modes[a] << " and " << modes[b];
    }

  // bilinear at the edge: repeat blends in the far column, clamp and mirror do not
  TextureSet edge;
  const std::uint32_t row = edge.addImage(image8(3, 1, {0, 0, 0, 255, 90, 0, 0, 255, 240, 0, 0, 255}), false);
  for (int s : modes) edge.addTexture(row, s, kClamp, kLinear, kLinear);
  const auto atEdges = sample(arraysOf(edge), {{0.0f, 0.5f, 0.0f, 0}, {0.0f, 0.5f, 0.0f, 1}, {0.0f, 0.5f, 0.0f, 2},
                                               {1.0f, 0.5f, 0.0f, 0}, {1.0f, 0.5f, 0.0f, 1}, {1.0f, 0.5f, 0.0f, 2}});
  const float expectedEdges[6] = {120, 0, 0, 120, 240, 240};
  for (int i = 0; i < 6; ++i)
    EXPECT_NEAR(atEdges[i].x * 255.0f, expectedEdges[i], 1e-4f) << "u " << (i < 3 ? 0 : 1) << ", wrap " << modes[i % 3];
}

TEST(TextureSample, NearestAndLinearFiltersApplyToTheirSide) {
  // 4 x 2; level 1 is 2 x 1
  const auto rgba = randomValues<std::uint8_t>(4 * 2 * 4, 4);
  TextureSet set;
  const std::uint32_t image = set.addImage(image8(4, 2, rgba), false);
  set.addTexture(image, kClamp, kClamp, kNearest, kLinearMipNearest);  // 0: magnify nearest, minify linear
  set.addTexture(image, kClamp, kClamp, kLinear, kNearestMipNearest);  // 1: magnify linear, minify nearest
  const float u = 0.4f, v = 0.3f;
  // level 0 at (u, v): s = 1.6, t = 0.6; bilinear from texel centres: s - 0.5 = 1.1, t - 0.5 = 0.1
  const glm::vec4 near0 = storedTexel(set, 0, 1, 0);
  const glm::vec4 lin0 = glm::mix(glm::mix(storedTexel(set, 0, 1, 0), storedTexel(set, 0, 2, 0), 0.1f),
                                  glm::mix(storedTexel(set, 0, 1, 1), storedTexel(set, 0, 2, 1), 0.1f), 0.1f);
  // level 1 (2 x 1): s = 0.8, nearest texel 0; bilinear s - 0.5 = 0.3 (one row, clamped)
  const glm::vec4 near1 = storedTexel(set, 1, 0, 0);
  const glm::vec4 lin1 = glm::mix(storedTexel(set, 1, 0, 0), storedTexel(set, 1, 1, 0), 0.3f);
  const auto got = sample(arraysOf(set), {{u, v, 0.0f, 0}, {u, v, 0.0f, 1}, {u, v, 1.0f, 0}, {u, v, 1.0f, 1}});
  expectNear(got[0], near0, 1e-6f, "magnified, nearest");
  expectNear(got[1], lin0, 2e-6f, "magnified, linear");
  expectNear(got[2], lin1, 2e-6f, "minified, linear");
  expectNear(got[3], near1, 1e-6f, "minified, nearest");
  ASSERT_GT(glm::length(near0 - lin0), 0.01f) << "the texture must tell the filters apart";
  ASSERT_GT(glm::length(near1 - lin1), 0.01f);
}

TEST(TextureSample, LodPicksAndBlendsLevels) {
  // 8 x 8: levels 8, 4, 2, 1 wide; nearest within a level, so a lookup is one texel of its level
  const auto rgba = randomValues<std::uint8_t>(8 * 8 * 4, 5);
  TextureSet set;
  const std::uint32_t image = set.addImage(image8(8, 8, rgba), false);
  set.addTexture(image, kRepeat, kRepeat, kNearest, kNearestMipLinear);   // 0: trilinear between levels
  set.addTexture(image, kRepeat, kRepeat, kNearest, kNearestMipNearest);  // 1: nearest level
  set.addTexture(image, kRepeat, kRepeat, kNearest, kNearest);            // 2: no mips
  set.addTexture(image, kRepeat, kRepeat, kLinear, kLinearMipLinear);     // 3: bilinear, trilinear
  const float u = 0.7f, v = 0.2f;
  glm::vec4 level[4];
  for (std::uint32_t l = 0; l < 4; ++l) {
    const std::uint32_t n = 8u >> l;
    level[l] = storedTexel(set, l, std::uint32_t(u * n), std::uint32_t(v * n));
  }
  ASSERT_GT(glm::length(level[0] - level[1]), 0.01f) << "levels must differ";
  struct Case {
    std::uint32_t texture;
    float lod;
    glm::vec4 expected;
  };
  const std::vector<Case> cases = {
      {0, 0.0f, level[0]}, {0, -3.0f, level[0]}, {0, kNaN, level[0]},
      {0, 1.0f, level[1]}, {0, 2.0f, level[2]}, {0, 3.0f, level[3]}, {0, 7.5f, level[3]}, {0, kInf, level[3]},
      {0, 0.5f, 0.5f * (level[0] + level[1])}, {0, 1.25f, 0.75f * level[1] + 0.25f * level[2]},
      {0, 2.9f, 0.1f * level[2] + 0.9f * level[3]},
      {1, 0.4f, level[0]}, {1, 0.6f, level[1]}, {1, 1.4f, level[1]}, {1, 2.6f, level[3]}, {1, 50.0f, level[3]},
      {2, 3.0f, level[0]}, {2, 0.5f, level[0]}, {2, kInf, level[0]},
  };
  std::vector<Query> queries;
  for (const Case& c : cases) queries.push_back({u, v, c.lod, c.texture});
  // trilinear with bilinear levels: lod 0.5 is the mean of the lod 0 and lod 1 lookups
  for (float lod : {0.0f, 1.0f, 0.5f}) queries.push_back({u, v, lod, 3});
  const auto got = sample(arraysOf(set), queries);
  for (std::size_t i = 0; i < cases.size(); ++i)
    expectNear(got[i], cases[i].expected, 2e-6f,
               "texture " + std::to_string(cases[i].texture) + ", lod " + std::to_string(cases[i].lod));
  const std::size_t k = cases.size();
  expectNear(got[k + 2], 0.5f * (got[k] + got[k + 1]), 2e-6f, "bilinear trilinear, lod 0.5");
  ASSERT_GT(glm::length(got[k] - got[k + 1]), 0.01f);
}

TEST(TextureSample, LodIsLog2OfTheFootprintInTexels) {
  TextureSet set;
  set.addTexture(set.addImage(image8(8, 4, std::vector<std::uint8_t>(8 * 4 * 4, 9)), false));
  set.addTexture(set.addImage(image8(2, 16, std::vector<std::uint8_t>(2 * 16 * 4, 9)), false));
  const std::vector<std::pair<cl_float2, float>> cases = {
      {{{1.0f / 8, 0}}, 0.0f},    {{{1.0f / 4, 0}}, 1.0f},  {{{1.0f / 2, 0}}, 2.0f}, {{{1.0f / 32, 0}}, -2.0f},
      {{{0.0f, 0}}, 0.0f},        {{{-1.0f, 0}}, 0.0f},     {{{kNaN, 0}}, 0.0f},     {{{3.0f / 8, 0}}, std::log2(3.0f)},
      {{{1.0f / 16, 0}}, -1.0f},  {{{1.0f / 16, std::bit_cast<float>(1u)}}, 0.0f},
      {{{1.0f, std::bit_cast<float>(1u)}}, 4.0f},
  };
  Context& ctx = test::deviceContext();
  std::vector<cl_float2> in;
  for (const auto& c : cases) in.push_back(c.first);
  const cl_uint n = cl_uint(in.size());
  cl::Buffer textures(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, set.textures.size() * sizeof(WtTexture),
                      set.textures.data());
  cl::Buffer levels(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, set.levels.size() * sizeof(WtTextureLevel),
                    set.levels.data());
  cl::Buffer queries(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(cl_float2), in.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(float));
  cl::Kernel k(test::testProgram("texture_tests.cl"), "test_texture_lod");
  k.setArg(0, n), k.setArg(1, textures), k.setArg(2, levels), k.setArg(3, queries), k.setArg(4, out);
  ctx.launch("test_texture_lod", k, n);
  std::vector<float> got(n);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * sizeof(float), got.data());
  for (std::size_t i = 0; i < cases.size(); ++i)
    EXPECT_NEAR(got[i], cases[i].second, 1e-6f) << "footprint " << cases[i].first.s[0] << " on texture "
                                                << std::bit_cast<std::uint32_t>(cases[i].first.s[1]);
}

TEST(TextureSample, NonFiniteInputsGiveFiniteAnswers) {
  TextureSet set;
  const std::uint32_t a = set.addImage(image8(5, 3, randomValues<std::uint8_t>(5 * 3 * 4, 6)), true);
  const std::uint32_t b = set.addImage(image16(3, 5, randomValues<std::uint16_t>(3 * 5 * 4, 7)), true);
  for (std::uint32_t image : {a, b})
    for (int wrap : {kRepeat, kClamp, kMirror})
      for (int filter : {kNearest, kLinear}) set.addTexture(image, wrap, wrap, filter, kLinearMipLinear);
  const float bad[] = {kNaN, kInf, -kInf};
  std::vector<Query> queries, asZero;
  for (std::uint32_t t = 0; t < set.textures.size(); ++t)
    for (float x : bad)
      for (float lod : {0.0f, 1.5f}) {
        queries.push_back({x, 0.3f, lod, t}), asZero.push_back({0.0f, 0.3f, lod, t});
        queries.push_back({0.6f, x, lod, t}), asZero.push_back({0.6f, 0.0f, lod, t});
        queries.push_back({x, x, lod, t}), asZero.push_back({0.0f, 0.0f, lod, t});
      }
  const auto got = sample(arraysOf(set), queries), expected = sample(arraysOf(set), asZero);
  for (std::size_t i = 0; i < queries.size(); ++i) {
    for (int c = 0; c < 4; ++c) {
      ASSERT_TRUE(std::isfinite(got[i][c])) << "u " << queries[i].u << ", v " << queries[i].v << ", texture "
                                            << queries[i].texture;
      EXPECT_GE(got[i][c], 0.0f);
      EXPECT_LE(got[i][c], 1.0f);
    }
    expectNear(got[i], expected[i], 0.0f, "a non-finite coordinate reads as 0");
  }
}

TEST(TextureSample, HugeCoordinatesStayInsideTheImage) {
  // one 5 x 3 level between sentinel texels: nearest must give one of its texels, bilinear a blend of them
  const std::uint32_t w = 5, h = 3, guard = 64;
  for (bool wide : {false, true}) {
    Arrays a;
    a.texels.assign(guard, 0xffffffffu);
    std::vector<glm::vec4> inside;
    for (std::uint32_t i = 0; i < w * h; ++i) {
      const std::uint32_t r = 10 * i + 3, g = 7 * i + 1;  // every texel its own (r, g), all below the sentinel's
      if (wide) {
        a.texels.push_back(r * 256 | (g * 256) << 16);
        a.texels.push_back(0xffffu << 16);
        inside.emplace_back(r * 256 / 65535.0f, g * 256 / 65535.0f, 0.0f, 1.0f);
      } else {
        a.texels.push_back(r | g << 8 | 0xffu << 24);
        inside.emplace_back(r / 255.0f, g / 255.0f, 0.0f, 1.0f);
      }
    }
    a.texels.insert(a.texels.end(), guard, 0xffffffffu);
    a.levels.push_back({guard, w, h, 0});
    const wt_uint base = wide ? WT_TEXTURE_16BIT : 0u;
    for (wt_uint mode : {WT_WRAP_REPEAT, WT_WRAP_CLAMP, WT_WRAP_MIRROR})
      for (wt_uint linear : {0u, WT_TEXTURE_MAG_LINEAR})
        a.textures.push_back({0, 1, base | linear | mode << WT_TEXTURE_WRAP_S_SHIFT | mode << WT_TEXTURE_WRAP_T_SHIFT, 0});
    const float huge[] = {1e9f, -1e9f, 3e38f, -3e38f, 16777215.0f, -8388607.5f, 1e-30f, -1e-30f, -0.0f, 1e9f + 0.5f,
                          -1.0f - 1e-7f, 1.0f + 1e-7f, 2.0f - 1e-7f, -3.0f};
    // every (u, v) pair; a fifth of them under a checker (test::testSize)
    const std::size_t stride = test::testSize(1, 5), n = std::size(huge);
    std::vector<Query> queries;
    for (std::uint32_t t = 0; t < a.textures.size(); ++t)
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j)
          if ((i + j) % stride == 0) queries.push_back({huge[i], huge[j], 0.0f, t});
    const auto got = sample(a, queries);
    for (std::size_t i = 0; i < queries.size(); ++i) {
      const Query& q = queries[i];
      const std::string what = std::string(wide ? "16" : "8") + "-bit texture " + std::to_string(q.texture) + ", u " +
                               std::to_string(q.u) + ", v " + std::to_string(q.v) + ": " + str(got[i]);
      if (a.textures[q.texture].flags & WT_TEXTURE_MAG_LINEAR) {
        // a blend of inside texels: within their range, alpha 1
        EXPECT_GE(got[i].x, inside.front().x - 1e-6f) << what;
        EXPECT_LE(got[i].x, inside.back().x + 1e-6f) << what;
        EXPECT_NEAR(got[i].w, 1.0f, 1e-6f) << what;
      } else {
        bool found = false;
        for (const glm::vec4& texel : inside) found = found || glm::length(got[i] - texel) < 1e-6f;
        EXPECT_TRUE(found) << what;
      }
    }
  }
}

}  // namespace
}  // namespace wt
