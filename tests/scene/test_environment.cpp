// Environment maps on the host: reading .hdr and .exr (and refusing what
// cannot be read, naming the file), repairing bad texels, the constant
// environment, and the sampling distribution's invariants.
#include "scene/environment.h"
#include "test_util.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfPreviewImageAttribute.h>
#include <ImfRgbaFile.h>
#include <ImfStringVectorAttribute.h>
#include <ImfTiledOutputFile.h>
#include <stb_image_write.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <cstddef>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>

namespace wt {
namespace {

constexpr double kPi = std::numbers::pi;

static_assert(sizeof(WtEnvironment) == 48);
static_assert(offsetof(WtEnvironment, intensity) == 16);
static_assert(offsetof(WtEnvironment, mode) == 32);
static_assert(offsetof(WtEnvironment, height) == 40);

/// The call throws EnvironmentError whose message starts with `path` and contains `part`.
void expectError(const std::filesystem::path& path, const std::string& part, const std::function<void()>& call) {
  try {
    call();
    ADD_FAILURE() << path << ": no error (expected one mentioning '" << part << "')";
  } catch (const EnvironmentError& e) {
    std::string what = e.what();
    EXPECT_EQ(what.rfind(path.string(), 0), 0u) << "message does not start with the path: " << what;
    EXPECT_NE(what.find(part), std::string::npos) << "message lacks '" << part << "': " << what;
  }
}

/// A w x h test image, distinct per pixel and channel.
std::vector<float> testPixels(int w, int h) {
  std::vector<float> rgb(std::size_t(w) * h * 3);
  for (int k = 0; k < w * h; ++k) {
    rgb[3 * k] = 0.25f + float(k % w);
    rgb[3 * k + 1] = 0.5f + 0.1f * float(k / w);
    rgb[3 * k + 2] = 1000.0f + float(k);
  }
  return rgb;
}

std::filesystem::path writeHdr(const std::string& name, int w, int h, const std::vector<float>& rgb) {
  std::filesystem::path path = test::scratchDir("environment") / name;
  EXPECT_TRUE(stbi_write_hdr(path.c_str(), w, h, 3, rgb.data()));
  return path;
}

using test::readAll;

void writeBytes(const std::filesystem::path& path, const std::vector<char>& bytes, std::size_t count) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(count));
}

/// A scanline EXR with the named FLOAT channels, channel c of pixel k = value(k, c).
std::filesystem::path writeExr(const std::string& name, int w, int h, const std::vector<std::string>& channels,
                               const std::function<float(int, int)>& value, Imath::V2i origin = {0, 0}) {
  std::filesystem::path path = test::scratchDir("environment") / name;
  Imath::Box2i window(origin, origin + Imath::V2i(w - 1, h - 1));
  Imf::Header header(window, window);
  std::vector<std::vector<float>> planes(channels.size(), std::vector<float>(std::size_t(w) * h));
  Imf::FrameBuffer fb;
  for (std::size_t c = 0; c < channels.size(); ++c) {
    header.channels().insert(channels[c], Imf::Channel(Imf::FLOAT));
    for (int k = 0; k < w * h; ++k) planes[c][k] = value(k, int(c));
    fb.insert(channels[c], Imf::Slice::Make(Imf::FLOAT, planes[c].data(), window));
  }
  Imf::OutputFile out(path.c_str(), header);
  out.setFrameBuffer(fb);
  out.writePixels(h);
  return path;
}

// ---------------------------------------------------------------------------
// errors

TEST(EnvironmentLoader, MissingFileIsNamed) {
  for (const char* name : {"no_such_map.hdr", "no_such_map.exr"}) {
    std::filesystem::path path = test::scratchDir("environment") / name;
    expectError(path, "no such file", [&] { loadEnvironmentMap(path); });
  }
}

TEST(EnvironmentLoader, UnsupportedFormatIsNamed) {
  std::filesystem::path png = test::scratchDir("environment") / "map.png";
  unsigned char pixels[12] = {};
  ASSERT_TRUE(stbi_write_png(png.c_str(), 2, 2, 3, pixels, 6));
  expectError(png, "unsupported environment map format '.png'", [&] { loadEnvironmentMap(png); });
  // a PNG under a .hdr name is refused by its content
  std::filesystem::path disguised = test::scratchDir("environment") / "png_inside.hdr";
  std::vector<char> bytes = readAll(png);
  writeBytes(disguised, bytes, bytes.size());
  expectError(disguised, "not a Radiance HDR file", [&] { loadEnvironmentMap(disguised); });
  // and a .hdr under an .exr name by OpenEXR
  std::filesystem::path hdr = writeHdr("real.hdr", 16, 8, testPixels(16, 8));
  std::filesystem::path wrongExr = test::scratchDir("environment") / "hdr_inside.exr";
  bytes = readAll(hdr);
  writeBytes(wrongExr, bytes, bytes.size());
  expectError(wrongExr, "cannot read OpenEXR file", [&] { loadEnvironmentMap(wrongExr); });
}

TEST(EnvironmentLoader, TruncatedHdrIsRefused) {
  // 64 wide: run-length encoded scanlines, where stb_image 2.27 would read zeros or hang
  std::filesystem::path full = writeHdr("full.hdr", 64, 32, testPixels(64, 32));
  std::vector<char> bytes = readAll(full);
  ASSERT_GT(bytes.size(), 200u);
  std::size_t headerEnd = std::string(bytes.begin(), bytes.end()).find("+X 64\n") + 6;
  ASSERT_GT(headerEnd, 6u);
  struct Cut {
    std::size_t size;
    const char* part;
  };
  for (Cut cut : {Cut{10, "truncated"}, Cut{headerEnd - 3, "resolution"}, Cut{headerEnd, "truncated"},
                  Cut{headerEnd + 3, "truncated"}, Cut{headerEnd + 50, "truncated"},
                  Cut{bytes.size() / 2, "truncated"}, Cut{bytes.size() - 1, "truncated"}}) {
    std::filesystem::path cutPath = test::scratchDir("environment") / ("cut_" + std::to_string(cut.size) + ".hdr");
    writeBytes(cutPath, bytes, cut.size);
    expectError(cutPath, cut.part, [&] { loadEnvironmentMap(cutPath); });
  }
  EXPECT_NO_THROW(loadEnvironmentMap(full));
}

TEST(EnvironmentLoader, CorruptRunLengthDataIsRefused) {
  std::filesystem::path full = writeHdr("rle.hdr", 64, 4, testPixels(64, 4));
  std::vector<char> bytes = readAll(full);
  std::size_t data = std::string(bytes.begin(), bytes.end()).find("+X 64\n") + 6;
  // a zero run count right after the first scanline header
  std::vector<char> zero = bytes;
  zero[data + 4] = 0;
  std::filesystem::path path = test::scratchDir("environment") / "zero_run.hdr";
  writeBytes(path, zero, zero.size());
  expectError(path, "zero-length run", [&] { loadEnvironmentMap(path); });
  // a scanline length that is not the width
  std::vector<char> length = bytes;
  length[data + 3] = 63;
  path = test::scratchDir("environment") / "bad_length.hdr";
  writeBytes(path, length, length.size());
  expectError(path, "expected 64", [&] { loadEnvironmentMap(path); });
}

TEST(EnvironmentLoader, HdrHeaderIsReadAsStbReadsIt) {
  // stb ends the header at a line that starts with NUL; a check that did not
  // walked a harmless 4 x 1 image further down while stb decoded 64-wide
  // run-length data the check had never seen (here with a zero run count)
  using namespace std::string_literals;
  const std::string text = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n"s + '\0' + "\n-Y 1 +X 64\n" +
                           "\x02\x02\x00\x40\x00 run of zero\n\n-Y 1 +X 4\n"s + std::string(16, '\x80');
  std::filesystem::path path = test::scratchDir("environment") / "nul_line.hdr";
  writeBytes(path, std::vector<char>(text.begin(), text.end()), text.size());
  expectError(path, "scanline 0: zero-length run", [&] { loadEnvironmentMap(path); });
  // the same without the zero run: stb's 64 x 1 reading is what is checked
  std::string flat = text.substr(0, text.find("\x02\x02")) + std::string(256, '\x80');
  writeBytes(path, std::vector<char>(flat.begin(), flat.end()), flat.size());
  EXPECT_EQ(loadEnvironmentMap(path).header.width, 64u);
  // and lines longer than stb's 1023-character buffer are cut where stb cuts them
  std::string longLine = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X " + std::string(1100, ' ') + "4\n" +
                         std::string(16, '\x80');
  writeBytes(path, std::vector<char>(longLine.begin(), longLine.end()), longLine.size());
  expectError(path, "unsupported resolution line", [&] { loadEnvironmentMap(path); });
}

TEST(EnvironmentLoader, TruncatedExrIsRefused) {
  std::filesystem::path full = writeExr("full.exr", 32, 16, {"R", "G", "B"}, [](int k, int c) { return float(k + c); });
  std::vector<char> bytes = readAll(full);
  std::filesystem::path cut = test::scratchDir("environment") / "cut.exr";
  writeBytes(cut, bytes, bytes.size() / 2);
  expectError(cut, "cannot read OpenEXR file", [&] { loadEnvironmentMap(cut); });
}

TEST(EnvironmentLoader, ExrWithMissingChunksIsRefusedBeforeAllocating) {
  // one scanline per chunk (no compression), half the chunk offsets zero:
  // OpenEXR marks such a file incomplete, and it is refused before the
  // texels are allocated
  const int w = 8, h = 512;
  Imath::Box2i window(Imath::V2i(0, 0), Imath::V2i(w - 1, h - 1));
  Imf::Header header(window, window);
  header.compression() = Imf::NO_COMPRESSION;
  std::vector<float> px(std::size_t(w) * h, 1.0f);
  Imf::FrameBuffer fb;
  for (const char* c : {"R", "G", "B"}) {
    header.channels().insert(c, Imf::Channel(Imf::FLOAT));
    fb.insert(c, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(px.data()), sizeof(float), sizeof(float) * w));
  }
  std::filesystem::path full = test::scratchDir("environment") / "one_line_chunks.exr";
  {
    Imf::OutputFile out(full.c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(h);
  }
  std::vector<char> bytes = readAll(full);
  ASSERT_EQ(loadEnvironmentMap(full).header.height, wt_uint(h));
  // the header ends after screenWindowWidth (the last attribute: 4 bytes of
  // size, 4 of value) and a NUL; the offset table follows, 8 bytes a chunk
  const std::string last = std::string("screenWindowWidth\0float\0", 24);
  const std::size_t attribute = std::string(bytes.begin(), bytes.end()).find(last);
  ASSERT_NE(attribute, std::string::npos);
  const std::size_t table = attribute + last.size() + 4 + 4 + 1;
  std::fill(bytes.begin() + std::ptrdiff_t(table + 8 * (h / 2)), bytes.begin() + std::ptrdiff_t(table + 8 * h), 0);
  std::filesystem::path holes = test::scratchDir("environment") / "zero_offsets.exr";
  writeBytes(holes, bytes, bytes.size());
  expectError(holes, "truncated: some scanlines or tiles are missing", [&] { loadEnvironmentMap(holes); });
}

TEST(EnvironmentLoader, ExrTilesMuchLargerThanTheWindowAreRefused) {
  const int w = 40, h = 20;
  std::filesystem::path path = test::scratchDir("environment") / "tiles.exr";
  {
    Imf::Header header(w, h);
    for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::HALF));
    header.setTileDescription(Imf::TileDescription(64, 64, Imf::ONE_LEVEL));  // larger than the window: fine
    Imf::TiledOutputFile out(path.c_str(), header);
    std::vector<half> px(std::size_t(w) * h * 3, half(0.25f));
    Imf::FrameBuffer fb;
    for (int c = 0; c < 3; ++c)
      fb.insert(c == 0 ? "R" : c == 1 ? "G" : "B",
                Imf::Slice(Imf::HALF, reinterpret_cast<char*>(&px[std::size_t(c)]), 3 * sizeof(half),
                           3 * sizeof(half) * w));
    out.setFrameBuffer(fb);
    out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
  }
  EXPECT_EQ(loadEnvironmentMap(path).header.width, wt_uint(w));
  // the tile height patched to 2^24: OpenEXR would allocate gigabytes for it
  std::vector<char> bytes = readAll(path);
  const std::string marker = std::string("tiles\0tiledesc\0", 15);
  const std::size_t at = std::string(bytes.begin(), bytes.end()).find(marker);
  ASSERT_NE(at, std::string::npos);
  const std::uint32_t tall = 1u << 24;
  std::memcpy(bytes.data() + at + marker.size() + 4 + 4, &tall, 4);  // after the size and the tile width
  std::filesystem::path bad = test::scratchDir("environment") / "tall_tiles.exr";
  writeBytes(bad, bytes, bytes.size());
  expectError(bad, "corrupt header: 64 x 16777216 tiles for a 40 x 20 data window", [&] { loadEnvironmentMap(bad); });
}

TEST(EnvironmentLoader, ConstantDwaMapIsNotTakenForCorrupt) {
  // DWA stores a constant 8 x 8 block as one deflated value, so a constant
  // map packs far more texels per byte than deflate alone could
  const int w = 2048, h = 1024;
  std::filesystem::path path = test::scratchDir("environment") / "constant_dwab.exr";
  {
    Imath::Box2i window(Imath::V2i(0, 0), Imath::V2i(w - 1, h - 1));
    Imf::Header header(window, window);
    header.compression() = Imf::DWAB_COMPRESSION;
    std::vector<half> px(std::size_t(w) * h, half(0.5f));
    Imf::FrameBuffer fb;
    for (const char* c : {"R", "G", "B"}) {
      header.channels().insert(c, Imf::Channel(Imf::HALF));
      fb.insert(c, Imf::Slice(Imf::HALF, reinterpret_cast<char*>(px.data()), sizeof(half), sizeof(half) * w));
    }
    Imf::OutputFile out(path.c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(h);
  }
  const std::size_t fileSize = std::filesystem::file_size(path);
  EXPECT_GT(std::size_t(w) * h / fileSize, 1024u) << "the file is not denser than deflate alone: " << fileSize << " bytes";
  Environment env = loadEnvironmentMap(path);
  ASSERT_EQ(env.header.width, wt_uint(w));
  EXPECT_NEAR(env.texels[12345].y, 0.5f, 0.01f);  // DWA is lossy
}

TEST(EnvironmentLoader, ExrHeaderStructureIsCheckedFirst) {
  // OpenEXR 3.1 reads each attribute at its type's own size and allocates by
  // whatever size it then finds, so a value whose size disagrees with its
  // type must be refused before OpenEXR sees it (see test_fuzz_regressions)
  const int w = 8, h = 4;
  std::filesystem::path path = test::scratchDir("environment") / "attributes.exr";
  {
    Imf::Header header(w, h);
    header.setPreviewImage(Imf::PreviewImage(2, 1));
    header.insert("names", Imf::StringVectorAttribute({"sky", "ground"}));
    std::vector<float> px(std::size_t(w) * h * 3, 0.5f);
    Imf::FrameBuffer fb;
    for (int c = 0; c < 3; ++c) {
      const char* channel = c == 0 ? "R" : c == 1 ? "G" : "B";
      header.channels().insert(channel, Imf::Channel(Imf::FLOAT));
      fb.insert(channel, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(&px[c]), 3 * sizeof(float),
                                    3 * sizeof(float) * w));
    }
    Imf::OutputFile out(path.c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(h);
  }
  const std::vector<char> original = readAll(path);
  ASSERT_EQ(loadEnvironmentMap(path).header.width, wt_uint(w));  // the unpatched file loads

  // the 4 bytes `offset` bytes after the end of "name\0type\0", set to `value`
  auto patched = [&](const std::string& attribute, std::size_t offset, std::uint32_t value) {
    const std::string marker = attribute + '\0';
    auto at = std::search(original.begin(), original.end(), marker.begin(), marker.end());
    EXPECT_NE(at, original.end()) << attribute;
    std::vector<char> bytes = original;
    std::memcpy(bytes.data() + (at - original.begin()) + std::ptrdiff_t(marker.size() + offset), &value, 4);
    std::filesystem::path out = test::scratchDir("environment") / ("patched_" + std::to_string(value) + ".exr");
    writeBytes(out, bytes, bytes.size());
    return out;
  };
  struct Case {
    std::string attribute;  ///< "name\0type"
    std::size_t offset;     ///< 0: the size field
    std::uint32_t value;
    std::string error;
  };
  const std::uint32_t chlistSize = 3 * 18 + 1;  // "R\0" + 16 bytes per channel, then a NUL
  const Case cases[] = {
      {std::string("pixelAspectRatio\0float", 22), 0, 3, "'pixelAspectRatio' of type 'float' has 3 bytes, expected 4"},
      {std::string("channels\0chlist", 15), 0, chlistSize - 1, "'channels' of type 'chlist' is not terminated within its 54 bytes"},
      {std::string("channels\0chlist", 15), 0, chlistSize + 1, "ends after 55 of its 56 bytes"},
      {std::string("channels\0chlist", 15), 0, 0x7fffff00, "claims 2147483392 bytes"},
      {std::string("preview\0preview", 15), 4, 100000, "has 16 bytes for a preview of 100000 pixels"},
      {std::string("names\0stringvector", 18), 4, 0x7fffffff, "has a string of 2147483647 bytes where 13 remain"},
  };
  for (const Case& c : cases) {
    std::filesystem::path bad = patched(c.attribute, c.offset, c.value);
    expectError(bad, c.error, [&] { loadEnvironmentMap(bad); });
  }
}

TEST(EnvironmentLoader, UnsupportedExrChannelsAreNamed) {
  std::filesystem::path g = writeExr("only_g.exr", 8, 4, {"G"}, [](int k, int) { return float(k); });
  expectError(g, "unsupported channel layout (G)", [&] { loadEnvironmentMap(g); });
  std::filesystem::path z = writeExr("depth.exr", 8, 4, {"Z"}, [](int k, int) { return float(k); });
  expectError(z, "unsupported channel layout (Z)", [&] { loadEnvironmentMap(z); });
}

TEST(EnvironmentLoader, BadParametersAreNamed) {
  std::filesystem::path hdr = writeHdr("params.hdr", 16, 8, testPixels(16, 8));
  expectError(hdr, "intensity", [&] { loadEnvironmentMap(hdr, -1.0f); });
  expectError(hdr, "intensity", [&] { loadEnvironmentMap(hdr, std::numeric_limits<float>::quiet_NaN()); });
  expectError(hdr, "rotation", [&] { loadEnvironmentMap(hdr, 1.0f, std::numeric_limits<float>::infinity()); });
}

// ---------------------------------------------------------------------------
// reading

TEST(EnvironmentLoader, HdrRoundTrip) {
  const int w = 16, h = 8;
  std::vector<float> rgb = testPixels(w, h);
  Environment env = loadEnvironmentMap(writeHdr("round.hdr", w, h, rgb), 2.0f, 90.0f);
  ASSERT_EQ(env.header.width, wt_uint(w));
  ASSERT_EQ(env.header.height, wt_uint(h));
  ASSERT_EQ(env.texels.size(), std::size_t(w * h));
  for (int k = 0; k < w * h; ++k) {
    // RGBE keeps 8 bits of mantissa per channel, shared exponent
    float scale = std::max({rgb[3 * k], rgb[3 * k + 1], rgb[3 * k + 2]}) / 128.0f;
    EXPECT_NEAR(env.texels[k].x, rgb[3 * k], scale) << "texel " << k;
    EXPECT_NEAR(env.texels[k].y, rgb[3 * k + 1], scale) << "texel " << k;
    EXPECT_NEAR(env.texels[k].z, rgb[3 * k + 2], scale) << "texel " << k;
  }
  EXPECT_EQ(env.header.mode, wt_uint(WT_ENV_MAP));
  EXPECT_FLOAT_EQ(env.header.intensity, 2.0f);
  EXPECT_FLOAT_EQ(env.header.rotation, float(kPi / 2));
  EXPECT_NEAR(env.header.cos_rotation, 0.0f, 1e-7f);
  EXPECT_FLOAT_EQ(env.header.sin_rotation, 1.0f);
  EXPECT_TRUE(env.warnings.empty());
}

TEST(EnvironmentLoader, FromMemoryReadsWhatTheFileGives) {
  const int w = 16, h = 8;
  const std::filesystem::path files[] = {
      writeHdr("memory.hdr", w, h, testPixels(w, h)),
      writeExr("memory.exr", w, h, {"B", "G", "R"}, [](int k, int c) { return float(k) + 0.25f * float(c); })};
  for (const std::filesystem::path& path : files) {
    const std::vector<char> chars = readAll(path);
    const std::vector<unsigned char> bytes(chars.begin(), chars.end());
    Environment fromFile = loadEnvironmentMap(path, 1.5f, 30.0f);
    Environment fromMemory = loadEnvironmentMapFromMemory(bytes, "sky" + path.extension().string(), 1.5f, 30.0f);
    ASSERT_EQ(fromMemory.header.width, wt_uint(w)) << path;
    ASSERT_EQ(fromMemory.texels.size(), fromFile.texels.size()) << path;
    for (std::size_t k = 0; k < fromFile.texels.size(); ++k) {
      ASSERT_EQ(fromMemory.texels[k].x, fromFile.texels[k].x) << path << " texel " << k;
      ASSERT_EQ(fromMemory.texels[k].z, fromFile.texels[k].z) << path << " texel " << k;
    }
    EXPECT_EQ(fromMemory.conditionalCdf, fromFile.conditionalCdf) << path;
    EXPECT_EQ(fromMemory.sourceName, "sky" + path.extension().string());
    // truncated bytes are refused under the given name
    const std::span<const unsigned char> cut(bytes.data(), bytes.size() / 2);
    expectError("cut" + path.extension().string(), "", [&] {
      loadEnvironmentMapFromMemory(cut, "cut" + path.extension().string());
    });
  }
  expectError("sky.png", "unsupported environment map format '.png'",
              [&] { loadEnvironmentMapFromMemory({}, "sky.png"); });
}

TEST(EnvironmentLoader, ExrFloatRgbExactWithAnyDataWindow) {
  const int w = 12, h = 6;
  auto value = [](int k, int c) { return 1e5f * float(c + 1) + float(k) * 0.125f; };  // beyond half's range
  for (Imath::V2i origin : {Imath::V2i(0, 0), Imath::V2i(-7, 30)}) {
    Environment env = loadEnvironmentMap(
        writeExr("rgba_" + std::to_string(origin.y) + ".exr", w, h, {"A", "B", "G", "R"}, value, origin));
    ASSERT_EQ(env.header.width, wt_uint(w));
    ASSERT_EQ(env.header.height, wt_uint(h));
    // channels are stored alphabetically (A, B, G, R): c = 3 is R
    for (int k = 0; k < w * h; ++k) {
      ASSERT_EQ(env.texels[k].x, value(k, 3)) << "texel " << k;
      ASSERT_EQ(env.texels[k].y, value(k, 2)) << "texel " << k;
      ASSERT_EQ(env.texels[k].z, value(k, 1)) << "texel " << k;
    }
  }
}

TEST(EnvironmentLoader, ExrLuminanceOnlyIsGrey) {
  Environment env = loadEnvironmentMap(writeExr("y.exr", 8, 4, {"Y"}, [](int k, int) { return 0.5f + float(k); }));
  for (int k = 0; k < 32; ++k) {
    EXPECT_EQ(env.texels[k].x, 0.5f + float(k));
    EXPECT_EQ(env.texels[k].y, 0.5f + float(k));
    EXPECT_EQ(env.texels[k].z, 0.5f + float(k));
  }
}

TEST(EnvironmentLoader, ExrLuminanceChromaIsConvertedToRgb) {
  // Y at full resolution, RY and BY sub-sampled 2 x 2 (OpenEXR's YC layout);
  // these were refused as "sub-sampled" before the fuzz seeds covered them
  const int w = 16, h = 8;
  const Imf::Rgba colour(0.8f, 0.4f, 0.2f, 1.0f);
  std::filesystem::path path = test::scratchDir("environment") / "yc.exr";
  {
    std::vector<Imf::Rgba> px(std::size_t(w) * h, colour);
    Imf::RgbaOutputFile out(path.c_str(), w, h, Imf::WRITE_YC);
    out.setFrameBuffer(px.data(), 1, w);
    out.writePixels(h);
  }
  {
    Imf::InputFile probe(path.c_str());
    const Imf::Channel* ry = probe.header().channels().findChannel("RY");
    ASSERT_NE(ry, nullptr);
    ASSERT_EQ(ry->xSampling, 2);  // the file really is sub-sampled
  }
  Environment env = loadEnvironmentMap(path);
  ASSERT_EQ(env.header.width, wt_uint(w));
  for (int k = 0; k < w * h; ++k) {
    ASSERT_NEAR(env.texels[k].x, 0.8f, 0.01f) << "texel " << k;
    ASSERT_NEAR(env.texels[k].y, 0.4f, 0.01f) << "texel " << k;
    ASSERT_NEAR(env.texels[k].z, 0.2f, 0.01f) << "texel " << k;
  }
}

TEST(EnvironmentLoader, TiledMipmappedExrGivesLevelZero) {
  const int w = 40, h = 20;
  std::filesystem::path path = test::scratchDir("environment") / "mip.exr";
  {
    Imath::Box2i window(Imath::V2i(0, 0), Imath::V2i(w - 1, h - 1));
    Imf::Header header(window, window);
    for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::HALF));
    header.setTileDescription(Imf::TileDescription(16, 16, Imf::MIPMAP_LEVELS, Imf::ROUND_DOWN));
    Imf::TiledOutputFile out(path.c_str(), header);
    for (int level = 0; level < out.numLevels(); ++level) {
      Imath::Box2i lw = out.dataWindowForLevel(level);
      int lwidth = lw.max.x - lw.min.x + 1, lheight = lw.max.y - lw.min.y + 1;
      // level 0 distinct per pixel, coarser levels a constant that must not show up
      std::vector<half> px(std::size_t(lwidth) * lheight * 3);
      for (int k = 0; k < lwidth * lheight; ++k)
        for (int c = 0; c < 3; ++c) px[3 * k + c] = level == 0 ? half(float(k % 97) + 0.25f * c) : half(777.0f);
      Imf::FrameBuffer fb;
      const std::size_t xs = 3 * sizeof(half), ys = xs * lwidth;
      fb.insert("R", Imf::Slice(Imf::HALF, reinterpret_cast<char*>(&px[0]), xs, ys));
      fb.insert("G", Imf::Slice(Imf::HALF, reinterpret_cast<char*>(&px[1]), xs, ys));
      fb.insert("B", Imf::Slice(Imf::HALF, reinterpret_cast<char*>(&px[2]), xs, ys));
      out.setFrameBuffer(fb);
      out.writeTiles(0, out.numXTiles(level) - 1, 0, out.numYTiles(level) - 1, level);
    }
  }
  Environment env = loadEnvironmentMap(path);
  ASSERT_EQ(env.header.width, wt_uint(w));
  ASSERT_EQ(env.header.height, wt_uint(h));
  for (int k = 0; k < w * h; ++k) {
    ASSERT_EQ(env.texels[k].x, float(k % 97)) << "texel " << k;
    ASSERT_EQ(env.texels[k].z, float(k % 97) + 0.5f) << "texel " << k;
  }
}

TEST(EnvironmentLoader, BadTexelsBecomeZeroWithOneWarning) {
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<glm::vec3> rgb(8, glm::vec3(1.0f));
  rgb[1] = {nan, 1.0f, 1.0f};
  rgb[2] = {1.0f, -3.0f, 1.0f};
  rgb[5] = {inf, -inf, 2.0f};
  Environment env = makeEnvironmentMap(4, 2, rgb, 1.0f, 0.0f, "bad.exr");
  ASSERT_EQ(env.warnings.size(), 1u);
  EXPECT_NE(env.warnings[0].find("bad.exr: 4 texel values"), std::string::npos) << env.warnings[0];
  EXPECT_EQ(env.texels[1].x, 0.0f);
  EXPECT_EQ(env.texels[1].y, 1.0f);
  EXPECT_EQ(env.texels[2].y, 0.0f);
  EXPECT_EQ(env.texels[5].x, 0.0f);
  EXPECT_EQ(env.texels[5].y, 0.0f);
  EXPECT_EQ(env.texels[5].z, 2.0f);
  for (float c : env.marginalCdf) EXPECT_TRUE(std::isfinite(c));
  for (float c : env.conditionalCdf) EXPECT_TRUE(std::isfinite(c));
}

// ---------------------------------------------------------------------------
// distribution

/// Sizes, end points, monotone cdfs; row probabilities proportional to the
/// row's luminance x sin(theta of its centre).
void expectDistributionValid(const Environment& env) {
  const std::size_t w = env.header.width, h = env.header.height;
  ASSERT_EQ(env.texels.size(), w * h);
  ASSERT_EQ(env.marginalCdf.size(), h + 1);
  ASSERT_EQ(env.conditionalCdf.size(), h * (w + 1));
  EXPECT_EQ(env.marginalCdf.front(), 0.0f);
  EXPECT_EQ(env.marginalCdf.back(), 1.0f);
  for (std::size_t j = 0; j < h; ++j) {
    EXPECT_LE(env.marginalCdf[j], env.marginalCdf[j + 1]);
    const float* row = &env.conditionalCdf[j * (w + 1)];
    EXPECT_EQ(row[0], 0.0f);
    EXPECT_EQ(row[w], 1.0f);
    for (std::size_t i = 0; i < w; ++i) ASSERT_LE(row[i], row[i + 1]) << "row " << j;
  }
  std::vector<double> rows(h, 0.0);
  double total = 0.0;
  for (std::size_t j = 0; j < h; ++j) {
    for (std::size_t i = 0; i < w; ++i) {
      const WtVec4& t = env.texels[j * w + i];
      rows[j] += (0.2126 * t.x + 0.7152 * t.y + 0.0722 * t.z) * std::sin(kPi * (j + 0.5) / h);
    }
    total += rows[j];
  }
  if (total == 0.0) return;
  for (std::size_t j = 0; j < h; ++j)
    EXPECT_NEAR(env.marginalCdf[j + 1] - env.marginalCdf[j], rows[j] / total, 1e-6) << "row " << j;
}

TEST(EnvironmentDistribution, InvariantsHold) {
  std::vector<glm::vec3> rgb(32 * 16);
  for (std::size_t k = 0; k < rgb.size(); ++k) rgb[k] = glm::vec3(float(k % 5), float(k % 3), 0.5f);
  for (int i = 0; i < 32; ++i) rgb[3 * 32 + i] = glm::vec3(0.0f);  // a black row
  rgb[0] = glm::vec3(1e6f);                                          // a bright texel at the pole row
  Environment env = makeEnvironmentMap(32, 16, rgb, 1.0f, 0.0f, "grid");
  EXPECT_EQ(env.header.mode, wt_uint(WT_ENV_MAP));
  expectDistributionValid(env);
  // the black row is never chosen, its columns stay finite
  EXPECT_EQ(env.marginalCdf[3], env.marginalCdf[4]);
  EXPECT_GT(env.meanLuminance, 0.0);
}

TEST(EnvironmentDistribution, AllBlackFallsBackToUniform) {
  Environment env = makeEnvironmentMap(8, 4, std::vector<glm::vec3>(32, glm::vec3(0.0f)), 1.0f, 0.0f, "black");
  EXPECT_EQ(env.header.mode, wt_uint(WT_ENV_MAP_UNIFORM));
  expectDistributionValid(env);
  for (float c : env.conditionalCdf) EXPECT_TRUE(std::isfinite(c));
  EXPECT_EQ(env.meanLuminance, 0.0);
}

TEST(EnvironmentDistribution, MeanLuminanceOfAUniformMap) {
  // a uniform map of luminance 1 x intensity 3 has mean luminance 3
  Environment env = makeEnvironmentMap(64, 32, std::vector<glm::vec3>(64 * 32, glm::vec3(1.0f)), 3.0f, 0.0f, "grey");
  EXPECT_NEAR(env.meanLuminance, 3.0, 1e-9);
  // rows by sin(theta) only
  expectDistributionValid(env);
}

TEST(EnvironmentDistribution, ConstantEnvironment) {
  Environment env = constantEnvironment({0.5f, 1.0f, 2.0f});
  EXPECT_EQ(env.header.mode, wt_uint(WT_ENV_CONSTANT));
  EXPECT_EQ(env.header.color.x, 0.5f);
  EXPECT_EQ(env.header.color.z, 2.0f);
  EXPECT_EQ(env.header.intensity, 1.0f);
  EnvironmentUpload up = environmentUpload(env);
  EXPECT_FALSE(up.texels.empty());
  EXPECT_FALSE(up.marginalCdf.empty());
  EXPECT_FALSE(up.conditionalCdf.empty());
  EXPECT_NEAR(env.meanLuminance, 0.2126 * 0.5 + 0.7152 + 0.0722 * 2.0, 1e-6);
}

TEST(EnvironmentDistribution, UploadSpansTheArrays) {
  Environment env = makeEnvironmentMap(4, 2, std::vector<glm::vec3>(8, glm::vec3(1.0f)), 1.0f, 0.0f, "tiny");
  EnvironmentUpload up = environmentUpload(env);
  EXPECT_EQ(up.texels.size(), 8u);
  EXPECT_EQ(up.marginalCdf.size(), 3u);
  EXPECT_EQ(up.conditionalCdf.size(), 10u);
  EXPECT_EQ(up.texels.data(), env.texels.data());
  // not 2:1: loads, with a warning
  Environment wide = makeEnvironmentMap(4, 4, std::vector<glm::vec3>(16, glm::vec3(1.0f)), 1.0f, 0.0f, "square");
  ASSERT_EQ(wide.warnings.size(), 1u);
  EXPECT_NE(wide.warnings[0].find("not 2:1"), std::string::npos);
}

// ---------------------------------------------------------------------------
// real files

TEST(EnvironmentAssets, RealHdrMapsLoad) {
  for (const char* name : {"royal_esplanade_1k.hdr", "chinese_garden_1k.hdr", "studio.hdr", "spot1Lux.hdr"}) {
    WT_REQUIRE_ASSET(file, std::string("envmaps/") + name);
    Environment env = loadEnvironmentMap(file);
    EXPECT_EQ(env.header.width, 2 * env.header.height) << name;
    EXPECT_EQ(env.header.mode, wt_uint(WT_ENV_MAP)) << name;
    EXPECT_GT(env.meanLuminance, 0.0) << name;
    expectDistributionValid(env);
  }
}

TEST(EnvironmentAssets, TiledMipmappedOrientationMapLoads) {
  WT_REQUIRE_ASSET(file, "envmaps/openexr-images/OrientationLatLong.exr");
  Environment env = loadEnvironmentMap(file);
  EXPECT_EQ(env.header.width, 1024u);
  EXPECT_EQ(env.header.height, 512u);
  EXPECT_TRUE(env.warnings.empty());
}

TEST(EnvironmentAssets, WideFloatRangeIsRefusedClearly) {
  // PXR24, a single G channel: not an environment map's layout
  WT_REQUIRE_ASSET(file, "envmaps/openexr-images/WideFloatRange.exr");
  expectError(file, "unsupported channel layout (G)", [&] { loadEnvironmentMap(file); });
}

}  // namespace
}  // namespace wt
