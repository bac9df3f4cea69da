// Textures on the Khronos texture test models (../shared/assets/gltf),
// rendered in-process and read back where the model's reference screenshot
// shows something known. Each model is seen straight down -Z by an
// orthographic camera (they all face +Z), under lighting that makes the
// rendered colour a known function of the texture:
//   - a uniform white environment, one bounce: a surface facing the camera
//     shows about its albedo (plus the dielectric's F0 0.04 specular), so
//     colours are compared by hue class or against another region that
//     must look the same, never against an absolute level;
//   - emission seen directly (no bounce, a black environment): exact;
//   - for normal maps, an environment whose red light comes from above and
//     whose blue light comes from the left: a dome lit that way is redder
//     at the top and bluer on the left, whether it is geometry or a normal map.
// World coordinates of quads, domes and spheres were computed from each
// model's JSON and .bin with python3 (json + struct), as the comments say.
// Alpha modes (MASK, BLEND): AlphaBlendModeTest's panels against its
// OPAQUE one, pixel by pixel.
#include "render/render_helpers.h"
#include "output/image_io.h"
#include "scene/gltf_loader.h"
#include "scene/tangents.h"
#include "test_util.h"

#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <gtest/gtest.h>

#include <stb_image.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace wt {
namespace {

// ---------------------------------------------------------------------------
// views, renders and pixel windows

/// An orthographic view straight down -Z onto the world rectangle [lo, hi]
/// (x right, y up) at `pixelsPerUnit`, square pixels.
struct View {
  glm::vec2 lo, hi;
  float pixelsPerUnit = 64.0f;

  int width() const { return std::max(1, int(std::lround((hi.x - lo.x) * pixelsPerUnit))); }
  int height() const { return std::max(1, int(std::lround((hi.y - lo.y) * pixelsPerUnit))); }
  glm::vec2 centre() const { return 0.5f * (lo + hi); }
  /// World units per pixel (the image's height decides it: makeCamera keeps ymag).
  float unitsPerPixel() const { return (hi.y - lo.y) / float(height()); }
  CameraDesc camera() const {
    CameraDesc c;
    c.orthographic = true;
    c.ymag = c.xmag = 0.5f * (hi.y - lo.y);
    c.cameraToWorld = glm::translate(glm::mat4(1.0f), glm::vec3(centre(), 10.0f));
    return c;
  }
  /// World position of the centre of pixel (x, y), counted from the top left.
  glm::vec2 world(int x, int y) const {
    const float u = unitsPerPixel();
    return centre() + glm::vec2((float(x) + 0.5f - 0.5f * float(width())) * u,
                                (0.5f * float(height()) - float(y) - 0.5f) * u);
  }
};

/// Scratch folder for images of failed checks.
std::filesystem::path scratch() { return test::scratchDir("gltf_texture_assets"); }

/// The render as EXR (radiance) and PNG under the scratch folder, for a
/// failed check to point at.
std::string keepImage(const Image& image, const std::string& name) {
  const std::filesystem::path path = scratch() / (name + ".exr");
  writeImage(path, image);
  writeImage(scratch() / (name + ".png"), image);
  return path.string();
}

/// A model in its own world coordinates (not recentred), as the comments give them.
Scene loadModel(const std::filesystem::path& path) {
  GltfLoadOptions options;
  options.recenter = false;
  return loadGltf(path.string(), options);
}

Image renderView(Scene scene, const View& view, RenderSettings settings, int spp) {
  scene.camera = view.camera();
  settings.width = view.width();
  settings.height = view.height();
  return test::render(scene, settings, spp);
}

/// Lighting that shows a surface facing the camera at about its albedo: a
/// uniform white environment, one bounce; escaping camera rays see black.
RenderSettings whiteFurnace() {
  RenderSettings s;
  s.background = glm::vec3(1.0f);
  s.environmentHidden = true;
  s.maxBounces = 1;
  return s;
}

/// Only emission seen directly: exact, with no noise from lighting.
RenderSettings emissionOnly() {
  RenderSettings s;
  s.background = glm::vec3(0.0f);
  s.maxBounces = 0;
  return s;
}

/// Mean radiance over the pixels whose centres lie in the square of half
/// side `half` (world) around `centre`, and the standard error of that mean
/// (from the pixels' sample variances).
struct Window {
  glm::dvec3 mean{0.0}, standardError{0.0};
  int pixels = 0;
};

Window window(const Image& image, const View& view, glm::vec2 centre, float half) {
  Window w;
  glm::dvec3 variance(0.0);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const glm::vec2 p = view.world(x, y);
      if (std::abs(p.x - centre.x) > half || std::abs(p.y - centre.y) > half) continue;
      const std::size_t i = std::size_t(y) * image.width + x;
      for (int c = 0; c < 3; ++c) {
        w.mean[c] += image.rgb[3 * i + c];
        variance[c] += image.rgbVariance[3 * i + c] / std::max<std::uint32_t>(image.samples[i], 1);
      }
      ++w.pixels;
    }
  EXPECT_GT(w.pixels, 0) << "window at (" << centre.x << ", " << centre.y << ") holds no pixel";
  if (w.pixels == 0) return w;
  w.mean /= double(w.pixels);
  w.standardError = glm::sqrt(variance) / double(w.pixels);
  return w;
}

std::string str(glm::dvec3 c) {
  std::ostringstream s;
  s.precision(4);
  s << "(" << c.x << ", " << c.y << ", " << c.z << ")";
  return s.str();
}

double luminance(glm::dvec3 c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

// ---------------------------------------------------------------------------
// colour classes

/// Coarse hue classes: a channel is on at half the brightest one or more,
/// off at a quarter or less (the 0.04 specular of a dielectric under the
/// white environment stays below that on any albedo of 0.16 or more);
/// anything between is Other. A flat white render is White everywhere, so
/// no coloured class passes by accident.
enum class Hue { Black, Red, Green, Blue, Yellow, Cyan, Magenta, White, Other };

std::ostream& operator<<(std::ostream& o, Hue h) {
  static const char* names[] = {"black", "red", "green", "blue", "yellow", "cyan", "magenta", "white", "other"};
  return o << names[int(h)];
}

Hue hueOf(glm::dvec3 c) {
  const double top = std::max({c.x, c.y, c.z});
  if (top < 0.05) return Hue::Black;
  int on = 0;
  for (int k = 0; k < 3; ++k) {
    if (c[k] >= 0.5 * top) on |= 1 << k;
    else if (c[k] > 0.25 * top) return Hue::Other;
  }
  switch (on) {
    case 1: return Hue::Red;
    case 2: return Hue::Green;
    case 4: return Hue::Blue;
    case 3: return Hue::Yellow;
    case 6: return Hue::Cyan;
    case 5: return Hue::Magenta;
    default: return Hue::White;
  }
}

// ---------------------------------------------------------------------------
// a texture read by the test itself (stb_image, independent of the product's
// decoder), to predict the pattern a quad must show

struct TestTexture {
  int width = 0, height = 0;
  std::vector<float> linearLuminance;  ///< row-major from the file's first row (glTF's v = 0)

  /// Luminance at (u, v), nearest texel, clamped to the edge.
  float at(glm::vec2 uv) const {
    const int x = std::clamp(int(std::floor(uv.x * float(width))), 0, width - 1);
    const int y = std::clamp(int(std::floor(uv.y * float(height))), 0, height - 1);
    return linearLuminance[std::size_t(y) * width + x];
  }
};

float srgbToLinear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

TestTexture readTexture(const std::filesystem::path& path) {
  TestTexture t;
  int channels = 0;
  // stb's flip is one flag for the whole process: whatever the product's
  // decoder left it at, read the file's first row first
  stbi_set_flip_vertically_on_load(0);
  unsigned char* pixels = stbi_load(path.c_str(), &t.width, &t.height, &channels, 3);
  EXPECT_NE(pixels, nullptr) << path;
  if (!pixels) return t;
  t.linearLuminance.resize(std::size_t(t.width) * t.height);
  for (std::size_t i = 0; i < t.linearLuminance.size(); ++i)
    t.linearLuminance[i] = float(luminance(glm::dvec3(srgbToLinear(pixels[3 * i] / 255.0f),
                                                      srgbToLinear(pixels[3 * i + 1] / 255.0f),
                                                      srgbToLinear(pixels[3 * i + 2] / 255.0f))));
  stbi_image_free(pixels);
  return t;
}

/// Pearson correlation of two equally long series.
double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const double n = double(a.size());
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) ma += a[i], mb += b[i];
  ma /= n, mb /= n;
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return saa > 0 && sbb > 0 ? sab / std::sqrt(saa * sbb) : 0.0;
}

/// A texture read through a mapping from world position to texture uv.
using TextureMapping = std::function<glm::vec2(glm::vec2)>;

/// The rendered luminance of the pixels of a region (those `inside`
/// accepts), and beside each, the luminance each mapping predicts there: the
/// texture averaged over the pixel (4 x 4 points).
struct RegionPrediction {
  std::vector<double> rendered;
  std::vector<std::vector<double>> predicted;  ///< per mapping
};

RegionPrediction predictRegion(const Image& image, const View& view, const TestTexture& texture,
                               const std::function<bool(glm::vec2)>& inside,
                               const std::vector<TextureMapping>& mappings) {
  RegionPrediction r;
  r.predicted.resize(mappings.size());
  const float step = view.unitsPerPixel();
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const glm::vec2 p = view.world(x, y);
      if (!inside(p)) continue;
      const std::size_t k = std::size_t(y) * image.width + x;
      r.rendered.push_back(luminance(glm::dvec3(image.rgb[3 * k], image.rgb[3 * k + 1], image.rgb[3 * k + 2])));
      for (std::size_t m = 0; m < mappings.size(); ++m) {
        double sum = 0.0;
        for (int j = 0; j < 4; ++j)
          for (int i = 0; i < 4; ++i)
            sum += texture.at(mappings[m](p + step * glm::vec2((float(i) + 0.5f) / 4.0f - 0.5f,
                                                               (float(j) + 0.5f) / 4.0f - 0.5f)));
        r.predicted[m].push_back(sum / 16.0);
      }
    }
  EXPECT_GT(r.rendered.size(), 50u) << "too few pixels in the region";
  return r;
}

/// How the render of a region follows texture mapping 0 rather than
/// mapping m: over the pixels where the two predictions differ by 0.1 or
/// more, the correlation of the rendered luminance with each.
struct Preference {
  std::size_t pixels = 0;  ///< where the predictions differ
  double right = 0.0;      ///< correlation with mapping 0's prediction there
  double other = 0.0;      ///< with mapping m's
  double margin() const { return right - other; }
};

/// Under the white environment a diffuse surface's radiance is an affine
/// function of its albedo, so the correlation with the right mapping is near
/// 1 (noise pulls it down) and with a wrong one much lower, often negative.
/// Element 0 compares mapping 0 with itself over the whole region (right ==
/// other: whether the pattern is there at all).
std::vector<Preference> mappingPreferences(const RegionPrediction& r) {
  std::vector<Preference> result(r.predicted.size());
  result[0] = {r.rendered.size(), correlation(r.rendered, r.predicted[0]), correlation(r.rendered, r.predicted[0])};
  for (std::size_t m = 1; m < r.predicted.size(); ++m) {
    std::vector<double> rendered, right, other;
    for (std::size_t i = 0; i < r.rendered.size(); ++i) {
      if (std::abs(r.predicted[0][i] - r.predicted[m][i]) < 0.1) continue;
      rendered.push_back(r.rendered[i]);
      right.push_back(r.predicted[0][i]);
      other.push_back(r.predicted[m][i]);
    }
    EXPECT_GT(rendered.size(), 20u) << "mapping " << m << " hardly differs from mapping 0";
    result[m] = {rendered.size(), correlation(rendered, right), correlation(rendered, other)};
  }
  return result;
}

/// Expect the region to show mapping 0 (correlation `minMatch` or more over
/// the region) and, where the others differ from it, mapping 0 rather than
/// them (correlation higher by `minMargin` or more). Returns a line for the log.
std::string expectMapping(const RegionPrediction& r, const std::vector<std::string>& names, double minMatch,
                          double minMargin) {
  const std::vector<Preference> p = mappingPreferences(r);
  std::ostringstream line;
  line.precision(3);
  line << names[0] << " " << p[0].right;
  EXPECT_GT(p[0].right, minMatch) << "the region does not show " << names[0];
  for (std::size_t m = 1; m < p.size(); ++m) {
    EXPECT_GT(p[m].margin(), minMargin) << "where " << names[0] << " and " << names[m] << " differ ("
                                        << p[m].pixels << " pixels), the render correlates " << p[m].right
                                        << " with the first, " << p[m].other << " with the second";
    line << ", over " << names[m] << " " << p[m].right << " vs " << p[m].other << " (" << p[m].pixels << " px)";
  }
  return line.str();
}

/// Thresholds of expectMapping for 16 samples per pixel at 64-96 pixels
/// per world unit (the noise of the white environment's specular keeps the
/// right mapping's correlation near 0.93).
constexpr double kMinMatch = 0.8, kMinMargin = 0.4;

/// The axis-aligned square of half side `half` around `centre`, less `margin`.
std::function<bool(glm::vec2)> inSquare(glm::vec2 centre, float half, float margin) {
  return [=](glm::vec2 p) {
    return std::abs(p.x - centre.x) <= half - margin && std::abs(p.y - centre.y) <= half - margin;
  };
}

// ---------------------------------------------------------------------------
// TextureCoordinateTest

// Four 1 x 1 quads at z = 0 (x and y in +-[0.2, 1.2]), each showing the
// corner of TextureCoordinateTemplate.png its name says, times its
// baseColorFactor: TopLeft_TEXCOORD_0 is u, v in [0, 0.4] with v = 0 at the
// top (y = 1.2), and so on; a grey back plane at z = -0.05.
struct CoordinateQuad {
  const char* name;
  glm::vec2 topLeft;   ///< world corner where (u, v) = uvTopLeft
  glm::vec2 uvTopLeft; ///< u grows with x, v grows downwards, 0.4 per world unit
  Hue tint;            ///< baseColorFactor's class
};
constexpr CoordinateQuad kCoordinateQuads[] = {
    {"TopLeft", {-1.2f, 1.2f}, {0.0f, 0.0f}, Hue::Yellow},   // factor (0.8, 0.8, 0)
    {"TopRight", {0.2f, 1.2f}, {0.6f, 0.0f}, Hue::Red},      // (0.8, 0.08, 0): orange, red by far the most
    {"BottomLeft", {-1.2f, -0.2f}, {0.0f, 0.6f}, Hue::Blue}, // (0, 0.16, 0.8)
    {"BottomRight", {0.2f, -0.2f}, {0.6f, 0.6f}, Hue::Green},// (0, 0.8, 0)
};

TEST(GltfTextureAssets, TextureCoordinateTestShowsEachCornerUpright) {
  WT_REQUIRE_ASSET(dir, "gltf/TextureCoordinateTest/glTF");
  Scene scene = loadModel(dir / "TextureCoordinateTest.gltf");
  const TestTexture texture = readTexture(dir / "TextureCoordinateTemplate.png");
  const View view{{-1.3f, -1.3f}, {1.3f, 1.3f}, 96.0f};
  const Image image = renderView(scene, view, whiteFurnace(), 16);
  for (const CoordinateQuad& q : kCoordinateQuads) {
    SCOPED_TRACE(q.name);
    const glm::vec2 centre = q.topLeft + glm::vec2(0.5f, -0.5f);
    auto uvAt = [&](glm::vec2 p) { return q.uvTopLeft + 0.4f * glm::vec2(p.x - q.topLeft.x, q.topLeft.y - p.y); };
    // the same corner upside down (rows read bottom-up) and mirrored (u = 1 - u)
    auto flippedV = [&](glm::vec2 p) { glm::vec2 uv = uvAt(p); return glm::vec2(uv.x, 1.0f - uv.y); };
    auto flippedU = [&](glm::vec2 p) { glm::vec2 uv = uvAt(p); return glm::vec2(1.0f - uv.x, uv.y); };
    // the half of the quad at its outer corner: the checks whose squares
    // shrink away from the corner, and the label; the rest is mostly white
    const glm::vec2 outer = centre + 0.25f * glm::sign(centre);
    const auto inside = inSquare(outer, 0.25f, 0.02f);
    const std::string line = expectMapping(predictRegion(image, view, texture, inside, {uvAt, flippedV, flippedU}),
                                           {"its corner", "upside down", "mirrored"}, kMinMatch, kMinMargin);
    // the tint: the quad's middle is plain white in the texture (uv 0.16-0.24 from its corner)
    const Window plain = window(image, view, centre, 0.1f);
    EXPECT_EQ(hueOf(plain.mean), q.tint) << str(plain.mean);
    std::printf("%s: %s; middle %s\n", q.name, line.c_str(), str(plain.mean).c_str());
  }
  if (testing::Test::HasFailure()) ADD_FAILURE() << "render: " << keepImage(image, "TextureCoordinateTest");
}

// ---------------------------------------------------------------------------
// TextureSettingsTest

/// glTF's wrap modes, as the specification defines them.
enum class Wrap { Repeat, Clamp, Mirror };
const char* wrapName(Wrap w) { return w == Wrap::Repeat ? "REPEAT" : w == Wrap::Clamp ? "CLAMP_TO_EDGE" : "MIRRORED_REPEAT"; }

float wrapCoordinate(float t, Wrap w) {
  switch (w) {
    case Wrap::Repeat: return t - std::floor(t);
    case Wrap::Clamp: return std::clamp(t, 0.0f, 1.0f);
    case Wrap::Mirror: {
      const float m = t - 2.0f * std::floor(0.5f * t);  // [0, 2)
      return m > 1.0f ? 2.0f - m : m;
    }
  }
  return t;
}

/// An axis-aligned 0.9 x 0.9 box at z = 0 facing +Z, its left edge at
/// x = left; u changes along x only and v along y only, from these values
/// at its edges.
struct SettingsBox {
  float left;
  float uLeft, uRight, vTop, vBottom;
  /// Texture uv of world point p in a row whose top edge is at y = top.
  glm::vec2 uv(glm::vec2 p, float top) const {
    const float fx = (p.x - left) / 0.9f, fy = (top - p.y) / 0.9f;
    return {uLeft + fx * (uRight - uLeft), vTop + fy * (vBottom - vTop)};
  }
};

// Under the root's matrix (mesh (x, y, z) -> world (x, z, -y)) each row is
// a pair of boxes: "Test" from x = 0.0048, "Sample pass" from x = 2.1508
// (uv from TextureSettingsTest0.bin). The sample reads its texture inside
// [0, 1]; the test box reads outside it along one axis, where its sampler's
// wrap mode on that axis must bring it back to (about) the sample's texels.
// The double-sided row puts a back-facing double-sided quad (a check) at
// z = 0.1 over the quad of its test box (an X). The single-sided row is left
// out: its back-facing single-sided quad must not be drawn, but wavetrace
// draws back faces, so it shows a red X (not a texture matter).
struct SettingsRow {
  const char* name;
  const char* image;  ///< the texture's image
  float top;          ///< world y of the boxes' top edge
  int axis;           ///< 0: s (u), 1: t (v)
  Wrap wrap;          ///< the sampler's mode on that axis
  SettingsBox test, sample;
};
constexpr float kTestBoxLeft = 0.0048f, kSampleBoxLeft = 2.1508f;
const SettingsRow kSettingsRows[] = {
    {"texture clamp s", "CheckAndX.png", 0.9174f, 0, Wrap::Clamp,
     {kTestBoxLeft, 1.39f, 1.6069f, 0.1808f, 0.3978f}, {kSampleBoxLeft, 0.9863f, 0.9922f, 0.1822f, 0.3993f}},
    {"texture clamp t", "CheckAndX_V.png", -0.1196f, 1, Wrap::Clamp,
     {kTestBoxLeft, 0.2236f, 0.4405f, -0.6116f, -0.3946f}, {kSampleBoxLeft, 0.2238f, 0.4389f, 0.0073f, 0.0198f}},
    {"texture repeat s", "CheckAndX.png", -1.1538f, 0, Wrap::Repeat,
     {kTestBoxLeft, 1.2162f, 1.4707f, 0.5632f, 0.8176f}, {kSampleBoxLeft, 0.2122f, 0.4667f, 0.5533f, 0.8078f}},
    {"texture repeat t", "CheckAndX_V.png", -2.1908f, 1, Wrap::Repeat,
     {kTestBoxLeft, 0.5419f, 0.7964f, -0.4594f, -0.2049f}, {kSampleBoxLeft, 0.5419f, 0.7964f, 0.5385f, 0.793f}},
    {"texture mirror s", "CheckAndX.png", -3.2278f, 0, Wrap::Mirror,
     {kTestBoxLeft, 1.7815f, 1.5338f, 0.565f, 0.8195f}, {kSampleBoxLeft, 0.2122f, 0.4667f, 0.5533f, 0.8078f}},
    {"texture mirror t", "CheckAndX_V.png", -4.2648f, 1, Wrap::Mirror,
     {kTestBoxLeft, 0.545f, 0.7995f, -0.5307f, -0.7909f}, {kSampleBoxLeft, 0.5419f, 0.7964f, 0.5385f, 0.793f}},
};

TEST(GltfTextureAssets, TextureSettingsTestWrapModes) {
  WT_REQUIRE_ASSET(dir, "gltf/TextureSettingsTest/glTF");
  Scene scene = loadModel(dir / "TextureSettingsTest.gltf");
  const View view{{-0.05f, -5.25f}, {3.1f, 2.05f}, 64.0f};
  const Image image = renderView(scene, view, whiteFurnace(), 16);
  for (const SettingsRow& row : kSettingsRows) {
    SCOPED_TRACE(row.name);
    const TestTexture texture = readTexture(dir / row.image);
    auto inBox = [&](const SettingsBox& box) { return inSquare({box.left + 0.45f, row.top - 0.45f}, 0.45f, 0.03f); };
    if (row.wrap != Wrap::Clamp) {
      // the sample shows its texels (this checks the method itself)
      auto sampleMapping = [&](glm::vec2 p) { return row.sample.uv(p, row.top); };
      const std::string sampleLine = expectMapping(
          predictRegion(image, view, texture, inBox(row.sample), {sampleMapping}), {"its texels"}, kMinMatch, 0.0);
      // the test box shows its texels wrapped by the sampler's mode, not by
      // either other mode (clamped, they would be the one edge texel: the
      // difference from it is the pattern itself)
      std::vector<TextureMapping> mappings;
      std::vector<Wrap> modes{row.wrap};
      for (Wrap w : {Wrap::Repeat, Wrap::Clamp, Wrap::Mirror})
        if (w != row.wrap) modes.push_back(w);
      for (Wrap w : modes)
        mappings.push_back([&row, w](glm::vec2 p) {
          glm::vec2 uv = row.test.uv(p, row.top);
          uv[row.axis] = wrapCoordinate(uv[row.axis], w);
          return uv;
        });
      const std::string testLine =
          expectMapping(predictRegion(image, view, texture, inBox(row.test), mappings),
                        {wrapName(modes[0]), wrapName(modes[1]), wrapName(modes[2])}, kMinMatch, kMinMargin);
      std::printf("%s: sample: %s; test: %s\n", row.name, sampleLine.c_str(), testLine.c_str());
    }
    // what the screenshot shows: no red X in the test box, and the clamped
    // boxes solid green (their whole pattern: a clamped read of uniform
    // texels has none to correlate with)
    int red = 0, green = 0, windows = 0;
    for (float dy = -0.3f; dy <= 0.31f; dy += 0.15f)
      for (float dx = -0.3f; dx <= 0.31f; dx += 0.15f, ++windows) {
        const Window w = window(image, view, glm::vec2(row.test.left + 0.45f + dx, row.top - 0.45f + dy), 0.05f);
        green += hueOf(w.mean) == Hue::Green;
        if (hueOf(w.mean) == Hue::Red && ++red <= 3) ADD_FAILURE() << "a red window in the test box: " << str(w.mean);
      }
    if (row.wrap == Wrap::Clamp) {
      EXPECT_EQ(green, windows) << "the clamped box is not solid green";
    }
  }
  {
    // double-sided: the back-facing double-sided quad at z = 0.1 (a check)
    // hides the quad behind it (an X); top edge at y = 1.9703
    SCOPED_TRACE("double-sided");
    int red = 0, green = 0;
    for (float dy = -0.3f; dy <= 0.31f; dy += 0.15f)
      for (float dx = -0.3f; dx <= 0.31f; dx += 0.15f) {
        const Window w = window(image, view, glm::vec2(kTestBoxLeft + 0.45f + dx, 1.9703f - 0.45f + dy), 0.05f);
        green += hueOf(w.mean) == Hue::Green;
        red += hueOf(w.mean) == Hue::Red;
      }
    EXPECT_EQ(red, 0);
    EXPECT_GE(green, 2);
  }
  if (testing::Test::HasFailure()) ADD_FAILURE() << "render: " << keepImage(image, "TextureSettingsTest");
}

// ---------------------------------------------------------------------------
// TextureTransformTest

/// KHR_texture_transform as its specification writes it: uv' = T R S uv,
/// R = [cos sin; -sin cos].
glm::vec2 transformUv(glm::vec2 uv, glm::vec2 offset, float rotation, glm::vec2 scale) {
  const float c = std::cos(rotation), s = std::sin(rotation);
  const glm::vec2 q = uv * scale;
  return {c * q.x + s * q.y + offset.x, -s * q.x + c * q.y + offset.y};
}

// Six 1 x 1 quads at z = 0, (u, v) = (0, 0) at the top left, u along +x and
// v down -y: the top row (centres y = 0.55) reads UV.png over uv [0, 0.5]
// with an offset, the bottom row (y = -0.55) reads Arrow.png over [0, 1]
// rotated, scaled and both; small marker quads at z = 0.01 (children of the
// quads, translations and scales from the JSON) show where the arrow's tip
// must land. Both textures clamp.
TEST(GltfTextureAssets, TextureTransformTestOffsetsRotationScale) {
  WT_REQUIRE_ASSET(dir, "gltf/TextureTransformTest/glTF");
  Scene scene = loadModel(dir / "TextureTransformTest.gltf");
  EXPECT_TRUE(std::none_of(scene.warnings.begin(), scene.warnings.end(), [](const std::string& w) {
    return w.find("KHR_texture_transform") != std::string::npos;
  })) << "KHR_texture_transform is warned about";
  const View view{{-1.7f, -1.15f}, {1.7f, 1.15f}, 80.0f};
  const Image image = renderView(scene, view, whiteFurnace(), 16);

  // offsets: UV.png's quadrants are yellow (uv [0, 0.5]^2: "offset not
  // applied"), green (u + 0.5), blue (v + 0.5) and cyan (both); each
  // quadrant's colour is plain near its corners (clear of its white sign)
  const struct {
    const char* name;
    glm::vec2 centre;
    Hue hue;
  } offsets[] = {{"Offset U", {-1.1f, 0.55f}, Hue::Green},
                 {"Offset V", {0.0f, 0.55f}, Hue::Blue},
                 {"Offset UV", {1.1f, 0.55f}, Hue::Cyan}};
  for (const auto& q : offsets)
    for (glm::vec2 corner : {glm::vec2(-0.4f, 0.4f), glm::vec2(0.4f, 0.4f), glm::vec2(-0.4f, -0.4f),
                             glm::vec2(0.4f, -0.4f)}) {
      const Window w = window(image, view, q.centre + corner, 0.03f);
      EXPECT_EQ(hueOf(w.mean), q.hue) << q.name << " near corner (" << corner.x << ", " << corner.y
                                      << "): " << str(w.mean);
    }

  // the arrow: rendered where the transform puts it, not where the
  // untransformed texture (or one rotated the other way) would
  const TestTexture arrow = readTexture(dir / "Arrow.png");
  const struct {
    const char* name;
    glm::vec2 centre;
    glm::vec2 offset;
    float rotation;
    glm::vec2 scale;
    std::vector<std::pair<glm::vec2, float>> markers;  ///< centre relative to the quad's, half side
  } arrows[] = {
      {"Rotation", {-1.1f, -0.55f}, {0.0f, 0.0f}, 0.39269908f, {1.0f, 1.0f},
       {{{-0.0790f, -0.5163f}, 0.075f}, {{0.2778f, -0.2778f}, 0.075f}, {{0.5163f, 0.0790f}, 0.075f}}},
      {"Scale", {0.0f, -0.55f}, {0.0f, 0.0f}, 0.0f, {1.5f, 1.5f},
       {{{0.0185f, -0.0185f}, 0.05f}, {{0.2778f, -0.2778f}, 0.075f}}},
      {"All", {1.1f, -0.55f}, {-0.2f, -0.1f}, 0.3f, {1.5f, 1.5f}, {{{-0.07f, -0.25f}, 0.05f}}},
  };
  for (const auto& q : arrows) {
    SCOPED_TRACE(q.name);
    auto quadUv = [&](glm::vec2 p) { return glm::vec2(p.x - q.centre.x + 0.5f, q.centre.y + 0.5f - p.y); };
    auto inside = [&](glm::vec2 p) {
      if (!inSquare(q.centre, 0.5f, 0.02f)(p)) return false;
      for (const auto& [m, half] : q.markers)
        if (inSquare(q.centre + m, half, -0.02f)(p)) return false;  // under a marker, and a margin
      return true;
    };
    std::vector<TextureMapping> mappings{
        [&](glm::vec2 p) { return transformUv(quadUv(p), q.offset, q.rotation, q.scale); },
        [&](glm::vec2 p) { return quadUv(p); },
    };
    if (q.rotation != 0.0f)
      mappings.push_back([&](glm::vec2 p) { return transformUv(quadUv(p), q.offset, -q.rotation, q.scale); });
    std::vector<std::string> names{"the transformed arrow", "the untransformed arrow", "the arrow rotated back"};
    names.resize(mappings.size());
    const std::string line =
        expectMapping(predictRegion(image, view, arrow, inside, mappings), names, kMinMatch, kMinMargin);
    std::printf("%s: %s\n", q.name, line.c_str());
  }
  if (testing::Test::HasFailure()) ADD_FAILURE() << "render: " << keepImage(image, "TextureTransformTest");
}

// ---------------------------------------------------------------------------
// TextureEncodingTest, TextureLinearInterpolationTest

// TextureEncodingTest: unit spheres at z = 0 in four columns, x = -2.75
// (factors only), 0.25 (a 1 x 1 texture), 3.25 (the same texel with a PNG
// gamma of 0.2, which glTF says to ignore) and 6.25 (with an ICC profile,
// ignored too); rows y = 2 (base colour: factor 0.2462 green = sRGB 136),
// y = -1 (emission: the same) and y = -4 (metallic-roughness: metallic 1,
// roughness 0.5333 = 136 / 255, stored linear in the texture's green; its
// blue is 255, metallic 1). Labels (alphaMode MASK) lie at z = -1 behind.
constexpr float kEncodingColumns[] = {-2.75f, 0.25f, 3.25f, 6.25f};
constexpr const char* kEncodingColumnNames[] = {"factors", "texture", "texture with gamma", "texture with ICC profile"};
constexpr float kSrgb136 = 0.24620133f;  // sRGB 136 / 255 decoded, the models' factor

TEST(GltfTextureAssets, TextureEncodingTestEmissionDecodesSrgb) {
  WT_REQUIRE_ASSET(path, "gltf/TextureEncodingTest/glTF/TextureEncodingTest.gltf");
  Scene scene = loadModel(path);
  const View view{{-4.0f, -2.25f}, {7.5f, 0.25f}, 16.0f};
  const Image image = renderView(scene, view, emissionOnly(), 1);
  for (int c = 0; c < 4; ++c) {
    const Window w = window(image, view, {kEncodingColumns[c], -1.0f}, 0.5f);
    EXPECT_NEAR(w.mean.y, kSrgb136, 2e-3) << kEncodingColumnNames[c] << " " << str(w.mean);
    EXPECT_LT(std::max(w.mean.x, w.mean.z), 1e-4) << kEncodingColumnNames[c] << " " << str(w.mean);
  }
  if (testing::Test::HasFailure()) ADD_FAILURE() << "render: " << keepImage(image, "TextureEncodingTest_emissive");
}

TEST(GltfTextureAssets, TextureEncodingTestBaseColorDecodesSrgb) {
  WT_REQUIRE_ASSET(path, "gltf/TextureEncodingTest/glTF/TextureEncodingTest.gltf");
  Scene scene = loadModel(path);
  const View view{{-4.0f, 0.75f}, {7.5f, 3.25f}, 16.0f};
  const Image image = renderView(scene, view, whiteFurnace(), 64);
  // the sphere's middle faces the camera: a green metal (metallicFactor
  // defaults to 1) under the white environment
  const Window factors = window(image, view, {kEncodingColumns[0], 2.0f}, 0.3f);
  EXPECT_EQ(hueOf(factors.mean), Hue::Green) << str(factors.mean);
  for (int c = 1; c < 4; ++c) {
    const Window w = window(image, view, {kEncodingColumns[c], 2.0f}, 0.3f);
    for (int k = 0; k < 3; ++k) {
      const double se = std::hypot(w.standardError[k], factors.standardError[k]);
      EXPECT_NEAR(w.mean[k], factors.mean[k], 4.0 * se + 0.02 * factors.mean[k])
          << kEncodingColumnNames[c] << " channel " << k << ": " << str(w.mean) << " vs factors " << str(factors.mean);
    }
  }
  if (testing::Test::HasFailure()) ADD_FAILURE() << "render: " << keepImage(image, "TextureEncodingTest_base_color");
}

TEST(GltfTextureAssets, TextureEncodingTestMetallicRoughnessIsLinear) {
  WT_REQUIRE_ASSET(path, "gltf/TextureEncodingTest/glTF/TextureEncodingTest.gltf");
  Scene scene = loadModel(path);
  // a directional light from the upper right, in front, on a black
  // environment: the highlight's size and height follow the roughness
  PunctualLight sun;
  sun.type = WT_LIGHT_DIRECTIONAL;
  sun.direction = glm::normalize(glm::vec3(-1.0f, -1.0f, -2.0f));
  sun.intensity = glm::vec3(3.0f);
  scene.lights.push_back(sun);
  RenderSettings settings;
  settings.maxBounces = 1;
  const View view{{-4.0f, -5.25f}, {7.5f, -2.75f}, 32.0f};
  const Image image = renderView(scene, view, settings, 16);
  // windows over each sphere at the same places: orthographic, every sphere
  // is seen alike; compare with the factor sphere
  int worse = 0;
  double worstZ = 0.0;
  for (int c = 1; c < 4; ++c)
    for (float dy = -0.6f; dy <= 0.61f; dy += 0.2f)
      for (float dx = -0.6f; dx <= 0.61f; dx += 0.2f) {
        if (dx * dx + dy * dy > 0.7f * 0.7f) continue;
        const Window f = window(image, view, {kEncodingColumns[0] + dx, -4.0f + dy}, 0.06f);
        const Window w = window(image, view, {kEncodingColumns[c] + dx, -4.0f + dy}, 0.06f);
        for (int k = 0; k < 3; ++k) {
          const double se = std::hypot(w.standardError[k], f.standardError[k]);
          worstZ = std::max(worstZ, std::abs(w.mean[k] - f.mean[k]) / se);
          if (std::abs(w.mean[k] - f.mean[k]) > 4.0 * se + 0.03 * f.mean[k] && ++worse <= 5)
            ADD_FAILURE() << kEncodingColumnNames[c] << " at (" << dx << ", " << dy << ") channel " << k << ": "
                          << str(w.mean) << " vs factors " << str(f.mean) << " (standard error " << se << ")";
        }
      }
  std::printf("metallic-roughness: worst z %.2f\n", worstZ);
  if (testing::Test::HasFailure()) ADD_FAILURE() << "render: " << keepImage(image, "TextureEncodingTest_metallic_roughness");
}

// TextureLinearInterpolationTest: two unit spheres at y = -1 emitting green,
// x = -1.5 by the factor 0.5, x = 1.5 by a 2 x 1 texture (sRGB 0 and 255)
// read at u = 0.5 by every vertex with LINEAR filtering: filtered after
// decoding it is 0.5, filtered before (the encoded 127.5 decoded) 0.2140.
TEST(GltfTextureAssets, TextureLinearInterpolationTestFiltersLinearValues) {
  WT_REQUIRE_ASSET(path, "gltf/TextureLinearInterpolationTest/glTF/TextureLinearInterpolationTest.gltf");
  Scene scene = loadModel(path);
  const View view{{-2.75f, -2.25f}, {2.75f, 0.25f}, 16.0f};
  const Image image = renderView(scene, view, emissionOnly(), 1);
  for (float x : {-1.5f, 1.5f}) {
    const Window w = window(image, view, {x, -1.0f}, 0.5f);
    EXPECT_NEAR(w.mean.y, 0.5, 0.01) << "sphere at x = " << x << ": " << str(w.mean);
    EXPECT_LT(std::max(w.mean.x, w.mean.z), 1e-4) << "sphere at x = " << x << ": " << str(w.mean);
  }
  if (testing::Test::HasFailure()) ADD_FAILURE() << "render: " << keepImage(image, "TextureLinearInterpolationTest");
}

// ---------------------------------------------------------------------------
// VertexColorTest

// Six quads facing +Z at z = 0.036 (VertexColorTest.bin, node scale z
// 0.0741): the test row (y in [0.109, 0.572]) shows checks with an X of the
// two other channels over them, multiplied by COLOR_0 red, green and blue;
// the sample row (y in [-0.759, -0.297]) the plain checks times white.
// Columns: x centres -0.548, 0, 0.592, half width 0.231.
TEST(GltfTextureAssets, VertexColorTestMultipliesBaseColor) {
  WT_REQUIRE_ASSET(path, "gltf/VertexColorTest/glTF/VertexColorTest.gltf");
  Scene scene = loadModel(path);
  const View view{{-1.05f, -1.05f}, {1.05f, 1.05f}, 96.0f};
  const Image image = renderView(scene, view, whiteFurnace(), 16);
  const struct {
    const char* name;
    float x;
    int channel;
    Hue hue;
  } columns[] = {{"red", -0.548f, 0, Hue::Red}, {"green", 0.0f, 1, Hue::Green}, {"blue", 0.592f, 2, Hue::Blue}};
  for (const auto& col : columns) {
    SCOPED_TRACE(col.name);
    std::vector<double> testMain, sampleMain;
    int leaks = 0;
    double brightest = 0.0;
    Hue brightestHue = Hue::Black;
    for (float dy = -0.175f; dy <= 0.176f; dy += 0.07f)
      for (float dx = -0.175f; dx <= 0.176f; dx += 0.07f) {
        const Window t = window(image, view, {col.x + dx, 0.3405f + dy}, 0.03f);
        const Window s = window(image, view, {col.x + dx, -0.528f + dy}, 0.03f);
        testMain.push_back(t.mean[col.channel]);
        sampleMain.push_back(s.mean[col.channel]);
        if (t.mean[col.channel] > brightest) brightest = t.mean[col.channel], brightestHue = hueOf(t.mean);
        // the other channels: no more than in the sample (the specular's share)
        for (int k = 0; k < 3; ++k) {
          if (k == col.channel) continue;
          const double se = std::hypot(t.standardError[k], s.standardError[k]);
          if (t.mean[k] > s.mean[k] + 4.0 * se + 0.03 && ++leaks <= 3)
            ADD_FAILURE() << "channel " << k << " at (" << dx << ", " << dy << "): test " << str(t.mean)
                          << " vs sample " << str(s.mean);
        }
      }
    // the check itself: the same shape as the sample's, in the right colour
    const double shape = correlation(testMain, sampleMain);
    EXPECT_GT(shape, 0.9) << "the test check's channel " << col.channel << " does not follow the sample's";
    EXPECT_EQ(brightestHue, col.hue);
    std::printf("%s: leaks %d, shape %.3f, brightest %.3f\n", col.name, leaks, shape, brightest);
  }
  if (testing::Test::HasFailure()) ADD_FAILURE() << "render: " << keepImage(image, "VertexColorTest");
}

// ---------------------------------------------------------------------------
// AlphaBlendModeTest

// Five 1.1 x 1.87 panels facing +Z at z = 0 (AlphaBlendModeTest.bin), x
// centres -3 (OPAQUE), -1.5 (BLEND), 0 (MASK, cutoff 0.25), 1.5 (MASK, the
// default cutoff 0.5), 3 (MASK, 0.75), y in [0.1, 1.97], each showing
// AlphaBlendLabels.png at u = 0.125 + (x - centre + 0.55) / 2, v = 0.05 +
// (1.97 - y) / 2. For u in [0.3, 0.65] the texture's alpha rises down the
// panel (0 near v 0.11, 1 near v 0.89) and is the same across it. The bed
// behind the panels and the decals and arrows in front of them are removed,
// so a hole shows the hidden environment: black. The OPAQUE panel's
// radiance L at the same place on the panel predicts the others pixel by
// pixel: a MASK panel shows L where alpha >= its cutoff and 0 below it, the
// BLEND panel alpha L on average.
TEST(GltfTextureAssets, AlphaBlendModeTestCutsAndBlendsAtTheTexturesAlpha) {
  WT_REQUIRE_ASSET(dir, "gltf/AlphaBlendModeTest/glTF");
  Scene scene = loadModel(dir / "AlphaBlendModeTest.gltf");
  std::vector<WtTriangle> panels;
  for (const WtTriangle& t : scene.triangles) {
    bool inPlane = true;
    for (std::uint32_t v : {t.v0, t.v1, t.v2}) inPlane = inPlane && std::abs(scene.positions[v].z) < 1e-4f;
    if (inPlane && scene.materialNames[t.material] != "MatBed") panels.push_back(t);
  }
  ASSERT_EQ(panels.size(), 10u) << "expected the five panels' quads";
  scene.triangles = panels;
  scene.instances.clear();

  // the texture's alpha (linear), read by stb_image
  int tw = 0, th = 0, channels = 0;
  stbi_set_flip_vertically_on_load(0);
  unsigned char* texels = stbi_load((dir / "AlphaBlendLabels.png").c_str(), &tw, &th, &channels, 4);
  ASSERT_NE(texels, nullptr);
  std::vector<float> alphaRow(std::size_t(th), 0.0f);  // at u = 0.475, the gradient's middle
  for (int y = 0; y < th; ++y) alphaRow[y] = texels[4 * (std::size_t(y) * tw + tw * 475 / 1000) + 3] / 255.0f;
  stbi_image_free(texels);

  const float ppu = 48.0f;  // 1.5 world units between panels: 72 whole pixels
  const View view{{-3.625f, 0.0f}, {3.625f, 2.0f}, ppu};  // whole pixels: 348 x 96
  const Image image = renderView(scene, view, whiteFurnace(), 16);
  // alpha averaged over the pixel's rows of texels (8 points down the pixel)
  auto pixelAlpha = [&](float y, float* lo, float* hi) {
    double sum = 0.0;
    *lo = 1.0f, *hi = 0.0f;
    for (int j = 0; j < 8; ++j) {
      const float yy = y + view.unitsPerPixel() * ((float(j) + 0.5f) / 8.0f - 0.5f);
      const float v = 0.05f + (1.97f - yy) * 0.5f;
      const float a = alphaRow[std::clamp(int(std::floor(v * float(th))), 0, th - 1)];
      sum += a, *lo = std::min(*lo, a), *hi = std::max(*hi, a);
    }
    return float(sum / 8.0);
  };
  struct Panel {
    const char* name;
    float centre;
    float cutoff;  ///< < 0: BLEND
  };
  const Panel tested[] = {{"BLEND", -1.5f, -1.0f}, {"MASK 0.25", 0.0f, 0.25f}, {"MASK 0.5", 1.5f, 0.5f},
                          {"MASK 0.75", 3.0f, 0.75f}};
  for (const Panel& panel : tested) {
    SCOPED_TRACE(panel.name);
    const int shift = int(std::lround((panel.centre + 3.0f) * ppu));  // pixels from the OPAQUE panel
    // BLEND: six bands down the gradient; MASK: kept and cut pixels
    const int kBands = 6;
    glm::dvec3 blendSum[kBands] = {}, predictedSum[kBands] = {}, varSum[kBands] = {};
    glm::dvec3 keptDiff(0.0), keptVar(0.0), keptLevel(0.0);
    int kept = 0, cut = 0, cutLit = 0;
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x) {
        const glm::vec2 p = view.world(x, y);
        const float local = p.x - panel.centre;
        if (local < -0.15f || local > 0.45f || p.y < 0.3f || p.y > 1.85f) continue;
        const int xo = x - shift;
        ASSERT_GE(xo, 0);
        ASSERT_NEAR(view.world(xo, y).x + 3.0f, local, 1e-3f);
        const std::size_t k = std::size_t(y) * image.width + x, ko = std::size_t(y) * image.width + xo;
        float lo, hi;
        const float a = pixelAlpha(p.y, &lo, &hi);
        glm::dvec3 L, Lo, var, varo;
        for (int c = 0; c < 3; ++c) {
          L[c] = image.rgb[3 * k + c], Lo[c] = image.rgb[3 * ko + c];
          var[c] = image.rgbVariance[3 * k + c] / std::max<std::uint32_t>(image.samples[k], 1);
          varo[c] = image.rgbVariance[3 * ko + c] / std::max<std::uint32_t>(image.samples[ko], 1);
        }
        if (panel.cutoff < 0.0f) {
          const int band = std::clamp(int((p.y - 0.3f) / (1.55f / kBands)), 0, kBands - 1);
          blendSum[band] += L, predictedSum[band] += double(a) * Lo, varSum[band] += var + double(a) * a * varo;
        } else if (lo >= panel.cutoff + 0.02f) {
          ++kept, keptDiff += L - Lo, keptVar += var + varo, keptLevel += Lo;
        } else if (hi <= panel.cutoff - 0.02f) {
          ++cut;
          if (L.x != 0.0 || L.y != 0.0 || L.z != 0.0) ++cutLit;
        }
      }
    if (panel.cutoff < 0.0f) {
      for (int b = 0; b < kBands; ++b)
        std::printf("BLEND band %d: rendered %.2f, predicted %.2f (green), se %.3f\n", b, blendSum[b].y,
                    predictedSum[b].y, std::sqrt(varSum[b].y));
      for (int b = 0; b < kBands; ++b)
        for (int c = 0; c < 3; ++c) {
          // 5 standard errors, plus 1% for alpha and colour varying together
          // inside a pixel (alpha moves 0.034 across one)
          const double tolerance = 5.0 * std::sqrt(varSum[b][c]) + 0.01 * predictedSum[b][c];
          EXPECT_NEAR(blendSum[b][c], predictedSum[b][c], tolerance)
              << "band " << b << " (from y 0.3 up), channel " << c;
        }
    } else {
      std::printf("%s: %d pixels kept (green differs by %.3f, se %.3f), %d cut (%d of them lit)\n", panel.name, kept,
                  keptDiff.y, std::sqrt(keptVar.y), cut, cutLit);
      EXPECT_GT(kept, 200) << "too few pixels above the cutoff";
      EXPECT_GT(cut, 200) << "too few pixels below the cutoff";
      EXPECT_EQ(cutLit, 0) << "of " << cut << " pixels whose alpha is below the cutoff";
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(keptDiff[c], 0.0, 5.0 * std::sqrt(keptVar[c]) + 1e-4 * keptLevel[c])
            << "channel " << c << ": " << kept << " pixels above the cutoff against the OPAQUE panel's";
    }
  }
  if (testing::Test::HasFailure()) ADD_FAILURE() << "render: " << keepImage(image, "AlphaBlendModeTest");
}

// ---------------------------------------------------------------------------
// NormalTangentTest, NormalTangentMirrorTest

/// An environment whose red light comes from above (+Y) and whose blue
/// light comes from the left (-X), both of radiance 1, green none: written
/// as an equirectangular .hdr (kernels/lights/environment.cl's convention:
/// row 0 at +Y, longitude atan2(x, z) = 2 pi (0.5 - u)).
std::string redAboveBlueLeft() {
  constexpr int kWidth = 64, kHeight = 32;
  std::vector<float> rgb(3 * kWidth * kHeight, 0.0f);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const float theta = (float(y) + 0.5f) / kHeight * glm::pi<float>();
      const float longitude = (0.5f - (float(x) + 0.5f) / kWidth) * glm::two_pi<float>();
      const glm::vec3 d(std::sin(theta) * std::sin(longitude), std::cos(theta), std::sin(theta) * std::cos(longitude));
      float* t = &rgb[3 * (y * kWidth + x)];
      t[0] = d.y > 0.0f ? 1.0f : 0.0f;
      t[2] = d.x < 0.0f ? 1.0f : 0.0f;
    }
  const std::filesystem::path path = scratch() / "red_above_blue_left.hdr";
  EXPECT_TRUE(stbi_write_hdr(path.c_str(), kWidth, kHeight, 3, rgb.data()));
  return path.string();
}

/// How a dome (or its normal-mapped picture) at `centre` turns: red (from
/// above) on its upper side against its lower, blue (from the left) on its
/// left against its right, as (a - b) / (a + b) of windows `offset` from the
/// centre. Positive both for a bump facing the camera.
struct DomeShading {
  double upDown = 0.0, leftRight = 0.0;
};

DomeShading domeShading(const Image& image, const View& view, glm::vec2 centre) {
  constexpr float kOffset = 0.05f, kHalf = 0.02f;
  auto contrast = [](double a, double b) { return a + b > 0.0 ? (a - b) / (a + b) : 0.0; };
  DomeShading d;
  d.upDown = contrast(window(image, view, centre + glm::vec2(0, kOffset), kHalf).mean.x,
                      window(image, view, centre - glm::vec2(0, kOffset), kHalf).mean.x);
  d.leftRight = contrast(window(image, view, centre - glm::vec2(kOffset, 0), kHalf).mean.z,
                         window(image, view, centre + glm::vec2(kOffset, 0), kHalf).mean.z);
  return d;
}

/// Every row of tiles: the geometry dome at `geometryX` turns as a bump
/// should, and each normal-mapped dome in the same row (at `mappedX`) turns
/// the same way, at least half as much.
void expectDomesLikeGeometry(const Image& image, const View& view, float geometryX,
                             const std::vector<std::pair<const char*, float>>& mappedX) {
  for (float y : {0.8f, 0.4f, 0.0f, -0.4f, -0.8f}) {
    std::ostringstream line;
    line.precision(3);
    const DomeShading g = domeShading(image, view, {geometryX, y});
    EXPECT_GT(g.upDown, 0.2) << "geometry dome at (" << geometryX << ", " << y << ")";
    EXPECT_GT(g.leftRight, 0.2) << "geometry dome at (" << geometryX << ", " << y << ")";
    line << "  row y " << y << ": geometry " << g.upDown << " " << g.leftRight;
    for (const auto& [name, x] : mappedX) {
      const DomeShading m = domeShading(image, view, {x, y});
      EXPECT_GT(m.upDown, 0.5 * g.upDown) << name << " dome at (" << x << ", " << y << "): red above "
                                          << m.upDown << " against the geometry's " << g.upDown;
      EXPECT_GT(m.leftRight, 0.5 * g.leftRight) << name << " dome at (" << x << ", " << y << "): blue left "
                                                << m.leftRight << " against the geometry's " << g.leftRight;
      line << ", " << name << " " << m.upDown << " " << m.leftRight;
    }
    std::printf("%s\n", line.str().c_str());
  }
}

// NormalTangentTest (no tangents in the file: they are generated): five rows
// (y = 0.8 ... -0.8) of three pairs, a real dome at x = -0.96, -0.16, 0.64
// and a flat tile normal-mapped as a dome 0.32 to its right (dome centres
// from NormalTangentTest0.bin; the normal map's bumps located through the
// mesh's uv), the map turned a different way on every tile.
TEST(GltfTextureAssets, NormalTangentTestMapsLikeGeometry) {
  WT_REQUIRE_ASSET(path, "gltf/NormalTangentTest/glTF/NormalTangentTest.gltf");
  Scene scene = loadModel(path);
  ASSERT_EQ(scene.tangents.size(), scene.positions.size()) << "no tangents generated";
  RenderSettings settings = whiteFurnace();
  settings.environmentMap = redAboveBlueLeft();
  const View view{{-1.15f, -1.0f}, {1.15f, 1.0f}, 128.0f};
  const Image image = renderView(scene, view, settings, 16);
  for (float x : {-0.96f, -0.16f, 0.64f}) {
    SCOPED_TRACE("column at x = " + std::to_string(x));
    std::printf("column at x = %.2f\n", x);
    expectDomesLikeGeometry(image, view, x, {{"normal-mapped", x + 0.32f}});
  }
  if (testing::Test::HasFailure()) ADD_FAILURE() << "render: " << keepImage(image, "NormalTangentTest");
}

// NormalTangentMirrorTest (tangents in the file): two groups of four columns,
// a real dome at x = -1.275 and 0.3, then the normal map, the normal map with
// v mirrored and with u mirrored (the bumps at x = -0.955, -0.63, -0.29 and
// 0.62, 0.94, 1.264, located through the mesh's uv); rows as above.
void expectMirrorTestDomes(const Image& image, const View& view) {
  const struct {
    float geometry;
    float mapped[3];
  } groups[] = {{-1.275f, {-0.955f, -0.63f, -0.29f}}, {0.3f, {0.62f, 0.94f, 1.264f}}};
  for (const auto& g : groups) {
    SCOPED_TRACE("group at x = " + std::to_string(g.geometry));
    std::printf("group at x = %.3f\n", g.geometry);
    expectDomesLikeGeometry(image, view, g.geometry,
                            {{"normal", g.mapped[0]}, {"v mirror", g.mapped[1]}, {"u mirror", g.mapped[2]}});
  }
}

TEST(GltfTextureAssets, NormalTangentMirrorTestMapsLikeGeometry) {
  WT_REQUIRE_ASSET(path, "gltf/NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf");
  Scene scene = loadModel(path);
  RenderSettings settings = whiteFurnace();
  settings.environmentMap = redAboveBlueLeft();
  const View view{{-1.45f, -1.0f}, {1.45f, 1.0f}, 128.0f};
  const Image image = renderView(scene, view, settings, 16);
  expectMirrorTestDomes(image, view);
  if (testing::Test::HasFailure()) ADD_FAILURE() << "render: " << keepImage(image, "NormalTangentMirrorTest");
}

/// The scene with its tangents made again by generateTangents (as for a
/// file without them) from its positions, normals and TEXCOORD_0, vertices
/// split where it splits them; `sources` gets, per vertex, the vertex it copies.
Scene withGeneratedTangents(const Scene& scene, std::vector<std::uint32_t>& sources) {
  std::vector<glm::vec3> positions, normals;
  for (std::size_t v = 0; v < scene.positions.size(); ++v) {
    positions.emplace_back(scene.positions[v].x, scene.positions[v].y, scene.positions[v].z);
    normals.emplace_back(scene.normals[v].x, scene.normals[v].y, scene.normals[v].z);
  }
  std::vector<std::uint32_t> corners;
  for (const WtTriangle& t : scene.triangles) corners.insert(corners.end(), {t.v0, t.v1, t.v2});
  Scene out = scene;
  sources = generateTangents(positions, normals, scene.texcoords, corners, out.tangents);
  for (std::size_t v = scene.positions.size(); v < sources.size(); ++v) {
    out.positions.push_back(scene.positions[sources[v]]);
    out.normals.push_back(scene.normals[sources[v]]);
    out.texcoords.push_back(scene.texcoords[sources[v]]);
    if (!out.texcoords1.empty()) out.texcoords1.push_back(scene.texcoords1[sources[v]]);
    if (!out.colors.empty()) out.colors.push_back(scene.colors[sources[v]]);
  }
  for (std::size_t t = 0; t < out.triangles.size(); ++t) {
    out.triangles[t].v0 = corners[3 * t];
    out.triangles[t].v1 = corners[3 * t + 1];
    out.triangles[t].v2 = corners[3 * t + 2];
  }
  return out;
}

// glTF asks for MikkTSpace tangents where a file has none: those generated
// for NormalTangentMirrorTest's mesh (one node, no transform) must agree with
// the ones in its file, in direction and handedness, and render the same
// domes.
TEST(GltfTextureAssets, NormalTangentMirrorTestGeneratedTangentsMatchTheFiles) {
  WT_REQUIRE_ASSET(path, "gltf/NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf");
  const Scene scene = loadModel(path);
  ASSERT_EQ(scene.tangents.size(), scene.positions.size());
  std::vector<std::uint32_t> sources;
  const Scene generated = withGeneratedTangents(scene, sources);
  // a vertex the generator split (corners of both handednesses) compares
  // with the file's tangent of the vertex it copies
  std::size_t otherSide = 0, apart = 0;
  double worstCosine = 1.0;
  for (std::size_t v = 0; v < generated.tangents.size(); ++v) {
    const glm::vec4 file = scene.tangents[sources[v]], made = generated.tangents[v];
    const double cosine = glm::dot(glm::vec3(file), glm::vec3(made));
    worstCosine = std::min(worstCosine, cosine);
    if (file.w != made.w && ++otherSide <= 3)
      ADD_FAILURE() << "vertex " << v << ": handedness " << made.w << ", the file's " << file.w;
    // within 11 degrees (MikkTSpace and the file's exporter may weigh corners differently)
    if (cosine < 0.98 && ++apart <= 3)
      ADD_FAILURE() << "vertex " << v << ": tangent " << str(glm::dvec3(glm::vec3(made))) << ", the file's "
                    << str(glm::dvec3(glm::vec3(file)));
  }
  std::printf("%zu vertices (%zu split): %zu on the other side, %zu apart, worst cosine %.4f\n",
              generated.tangents.size(), generated.tangents.size() - scene.positions.size(), otherSide, apart,
              worstCosine);

  RenderSettings settings = whiteFurnace();
  settings.environmentMap = redAboveBlueLeft();
  const View view{{-1.45f, -1.0f}, {1.45f, 1.0f}, 128.0f};
  const Image image = renderView(generated, view, settings, 16);
  expectMirrorTestDomes(image, view);
  if (testing::Test::HasFailure()) ADD_FAILURE() << "render: " << keepImage(image, "NormalTangentMirrorTest_generated");
}

}  // namespace
}  // namespace wt
