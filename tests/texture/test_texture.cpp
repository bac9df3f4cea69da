// Textures on the host (host/texture/texture.cpp): PNG and JPEG decoding
// made in the test, refusal of truncated, corrupt, huge and unsupported
// files by name, the mip pyramid's sizes and box weights (sRGB averaged in
// linear light), and the packing of texels and sampler flags.
#include "texture/texture.h"

#include <stb_image_write.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace wt {
namespace {

using Bytes = std::vector<unsigned char>;

// ---------------------------------------------------------------------------
// files made here

void appendBytes(void* context, void* data, int size) {
  auto* out = static_cast<Bytes*>(context);
  out->insert(out->end(), static_cast<unsigned char*>(data), static_cast<unsigned char*>(data) + size);
}

Bytes writePng(int width, int height, int channels, const std::vector<std::uint8_t>& pixels) {
  Bytes out;
  EXPECT_NE(stbi_write_png_to_func(appendBytes, &out, width, height, channels, pixels.data(), width * channels), 0);
  return out;
}

Bytes writeJpeg(int width, int height, int channels, const std::vector<std::uint8_t>& pixels, int quality) {
  Bytes out;
  EXPECT_NE(stbi_write_jpg_to_func(appendBytes, &out, width, height, channels, pixels.data(), quality), 0);
  return out;
}

void putBe32(Bytes& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<unsigned char>(v >> shift));
}

std::uint32_t crc32(const unsigned char* data, std::size_t size) {
  std::uint32_t crc = 0xffffffffu;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

void putChunk(Bytes& png, const char* type, const Bytes& data) {
  putBe32(png, std::uint32_t(data.size()));
  Bytes body(type, type + 4);
  body.insert(body.end(), data.begin(), data.end());
  png.insert(png.end(), body.begin(), body.end());
  putBe32(png, crc32(body.data(), body.size()));
}

/// A PNG of `samples` (big-endian on write), bit depth 16 when `sixteen`:
/// colour type 0 (grey), 2 (RGB) or 6 (RGBA), deflate's stored blocks. With
/// no samples, the header alone (a file cut after IHDR).
Bytes handMadePng(std::uint32_t width, std::uint32_t height, int colourType, const std::vector<std::uint16_t>& samples) {
  Bytes png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  Bytes ihdr;
  putBe32(ihdr, width), putBe32(ihdr, height);
  ihdr.insert(ihdr.end(), {16, static_cast<unsigned char>(colourType), 0, 0, 0});
  putChunk(png, "IHDR", ihdr);
  if (samples.empty()) return png;
  // scanlines: filter type 0, then the row's samples
  const std::size_t perRow = samples.size() / height;
  Bytes raw;
  for (std::uint32_t y = 0; y < height; ++y) {
    raw.push_back(0);
    for (std::size_t i = 0; i < perRow; ++i) {
      raw.push_back(static_cast<unsigned char>(samples[y * perRow + i] >> 8));
      raw.push_back(static_cast<unsigned char>(samples[y * perRow + i]));
    }
  }
  EXPECT_LT(raw.size(), 65536u) << "one stored block only";
  Bytes zlib = {0x78, 0x01, 0x01};  // header; final stored block
  const auto len = static_cast<std::uint16_t>(raw.size());
  zlib.insert(zlib.end(), {static_cast<unsigned char>(len), static_cast<unsigned char>(len >> 8),
                           static_cast<unsigned char>(~len), static_cast<unsigned char>(~len >> 8)});
  zlib.insert(zlib.end(), raw.begin(), raw.end());
  std::uint32_t a = 1, b = 0;
  for (unsigned char c : raw) a = (a + c) % 65521, b = (b + a) % 65521;
  putBe32(zlib, b << 16 | a);
  putChunk(png, "IDAT", zlib);
  putChunk(png, "IEND", {});
  return png;
}

std::vector<std::uint8_t> randomBytes(std::size_t count, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<std::uint8_t> out(count);
  for (auto& v : out) v = static_cast<std::uint8_t>(rng() & 255u);
  return out;
}

/// decodeImage's message for bytes it must refuse (fails the test when it decodes).
std::string refusal(const Bytes& bytes, const std::string& name = "img.bin") {
  try {
    decodeImage(bytes.data(), bytes.size(), name);
  } catch (const TextureError& e) {
    return e.what();
  }
  ADD_FAILURE() << name << ": " << bytes.size() << " bytes decoded, expected a TextureError";
  return {};
}

// ---------------------------------------------------------------------------
// decoding

TEST(TextureDecode, PngRgbaIsExactTopRowFirst) {
  const auto pixels = randomBytes(5 * 3 * 4, 1);
  const Bytes png = writePng(5, 3, 4, pixels);
  DecodedImage image = decodeImage(png.data(), png.size(), "rgba.png");
  EXPECT_EQ(image.width, 5u);
  EXPECT_EQ(image.height, 3u);
  EXPECT_FALSE(image.sixteenBit);
  EXPECT_TRUE(image.rgba16.empty());
  EXPECT_EQ(image.rgba8, pixels);  // row 0 of the file first
  EXPECT_EQ(image.name, "rgba.png");
}

TEST(TextureDecode, GreyReplicatesAndMissingAlphaIsOpaque) {
  const auto grey = randomBytes(4 * 2, 2), greyAlpha = randomBytes(4 * 2 * 2, 3), rgb = randomBytes(4 * 2 * 3, 4);
  const Bytes greyPng = writePng(4, 2, 1, grey), gaPng = writePng(4, 2, 2, greyAlpha), rgbPng = writePng(4, 2, 3, rgb);
  DecodedImage g = decodeImage(greyPng.data(), greyPng.size(), "grey.png");
  DecodedImage ga = decodeImage(gaPng.data(), gaPng.size(), "grey_alpha.png");
  DecodedImage c = decodeImage(rgbPng.data(), rgbPng.size(), "rgb.png");
  for (std::size_t i = 0; i < 8; ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(g.rgba8[4 * i + k], grey[i]);
      EXPECT_EQ(ga.rgba8[4 * i + k], greyAlpha[2 * i]);
      EXPECT_EQ(c.rgba8[4 * i + k], rgb[3 * i + k]);
    }
    EXPECT_EQ(g.rgba8[4 * i + 3], 255);
    EXPECT_EQ(ga.rgba8[4 * i + 3], greyAlpha[2 * i + 1]);
    EXPECT_EQ(c.rgba8[4 * i + 3], 255);
  }
}

TEST(TextureDecode, SixteenBitPngKeepsSixteenBits) {
  std::vector<std::uint16_t> rgba = {0x0102, 0xfffe, 0x8001, 0x7fff, 0, 1, 65535, 0x1234,
                                     0xabcd, 0x00ff, 0xff00, 0x4242, 9, 99, 999, 9999};  // 2 x 2
  const Bytes png = handMadePng(2, 2, 6, rgba);
  DecodedImage image = decodeImage(png.data(), png.size(), "rgba16.png");
  EXPECT_TRUE(image.sixteenBit);
  EXPECT_TRUE(image.rgba8.empty());
  EXPECT_EQ(image.rgba16, rgba);

  const std::vector<std::uint16_t> grey = {0x0101, 0xfeed, 0x8000};  // 3 x 1
  const Bytes greyPng = handMadePng(3, 1, 0, grey);
  DecodedImage g = decodeImage(greyPng.data(), greyPng.size(), "grey16.png");
  ASSERT_TRUE(g.sixteenBit);
  ASSERT_EQ(g.rgba16.size(), 12u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(g.rgba16[4 * i], grey[i]);
    EXPECT_EQ(g.rgba16[4 * i + 1], grey[i]);
    EXPECT_EQ(g.rgba16[4 * i + 2], grey[i]);
    EXPECT_EQ(g.rgba16[4 * i + 3], 65535);
  }
}

TEST(TextureDecode, JpegGivesItsColoursInPlace) {
  // four flat 8 x 8 quadrants: each block's colour survives quality 100
  const std::uint8_t colours[4][3] = {{200, 30, 30}, {30, 200, 30}, {30, 30, 200}, {220, 220, 40}};
  std::vector<std::uint8_t> pixels(16 * 16 * 3);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      for (int c = 0; c < 3; ++c) pixels[(y * 16 + x) * 3 + c] = colours[(y / 8) * 2 + x / 8][c];
  const Bytes jpeg = writeJpeg(16, 16, 3, pixels, 100);
  DecodedImage image = decodeImage(jpeg.data(), jpeg.size(), "quadrants.jpg");
  ASSERT_EQ(image.width, 16u);
  ASSERT_EQ(image.height, 16u);
  EXPECT_FALSE(image.sixteenBit);
  for (int q = 0; q < 4; ++q) {
    const int x = (q % 2) * 8 + 4, y = (q / 2) * 8 + 4;
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(image.rgba8[(y * 16 + x) * 4 + c], colours[q][c], 6) << "quadrant " << q << " channel " << c;
    EXPECT_EQ(image.rgba8[(y * 16 + x) * 4 + 3], 255);
  }
}

TEST(TextureDecode, TruncatedFilesAreRefusedByName) {
  const Bytes png = writePng(7, 5, 4, randomBytes(7 * 5 * 4, 5));
  const Bytes jpeg = writeJpeg(16, 8, 3, randomBytes(16 * 8 * 3, 6), 90);
  // a PNG cut anywhere before its IEND chunk (12 bytes) lacks pixels
  for (std::size_t n = 1; n + 12 < png.size(); ++n) {
    const std::string what = refusal(Bytes(png.begin(), png.begin() + std::ptrdiff_t(n)), "cut.png");
    ASSERT_EQ(what.rfind("cut.png: ", 0), 0u) << n << " bytes: " << what;
  }
  for (std::size_t n = 1; n + 2 < jpeg.size(); ++n) {  // before the EOI marker
    const std::string what = refusal(Bytes(jpeg.begin(), jpeg.begin() + std::ptrdiff_t(n)), "cut.jpg");
    ASSERT_EQ(what.rfind("cut.jpg: ", 0), 0u) << n << " bytes: " << what;
  }
  EXPECT_NE(refusal(Bytes(png.begin(), png.begin() + 40), "cut.png").find("cannot decode the PNG data"),
            std::string::npos);
  EXPECT_NE(refusal(Bytes(png.begin(), png.begin() + 12), "cut.png").find("cannot read the PNG header"),
            std::string::npos);
}

TEST(TextureDecode, GarbageIsRefusedByName) {
  EXPECT_EQ(refusal({}, "empty.png"), "empty.png: no image data (0 bytes)");
  EXPECT_THROW(decodeImage(nullptr, 10, "null.png"), TextureError);
  const auto noise = randomBytes(3000, 7);
  EXPECT_EQ(refusal(Bytes(noise.begin(), noise.end()), "noise.bin").rfind("noise.bin: not a PNG or JPEG file (starts with ", 0),
            0u);
  // the right magic followed by noise, and files with bytes overwritten
  for (const Bytes& magic : {Bytes{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'}, Bytes{0xff, 0xd8, 0xff}}) {
    Bytes file = magic;
    file.insert(file.end(), noise.begin(), noise.end());
    EXPECT_EQ(refusal(file, "noisy").rfind("noisy: cannot ", 0), 0u);
  }
  const Bytes png = writePng(9, 9, 3, randomBytes(9 * 9 * 3, 8));
  const Bytes jpeg = writeJpeg(9, 9, 3, randomBytes(9 * 9 * 3, 9), 75);
  std::mt19937 rng(10);
  int refused = 0;
  for (int i = 0; i < 400; ++i) {
    Bytes file = i % 2 ? png : jpeg;
    for (int k = 0; k < 4; ++k) file[8 + rng() % (file.size() - 8)] = static_cast<unsigned char>(rng());
    try {
      DecodedImage image = decodeImage(file.data(), file.size(), "mutated");
      EXPECT_EQ(image.rgba8.size(), std::size_t(image.width) * image.height * 4);  // some changes decode
    } catch (const TextureError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("mutated: ", 0), 0u) << e.what();
      ++refused;
    }
  }
  EXPECT_GT(refused, 0);
}

// stb_image 2.27 writes past a Huffman table whose code counts sum past 256;
// texture.cpp refuses such tables before stb reads them.
TEST(TextureDecode, JpegHuffmanTableWithTooManyCodesIsRefused) {
  Bytes jpeg = writeJpeg(8, 8, 3, randomBytes(8 * 8 * 3, 11), 90);
  std::size_t dht = 0;
  for (std::size_t i = 2; i + 1 < jpeg.size() && !dht; ++i)
    if (jpeg[i] == 0xff && jpeg[i + 1] == 0xc4) dht = i;
  ASSERT_NE(dht, 0u);
  // the first table's counts of 15- and 16-bit codes: 255 each
  jpeg[dht + 5 + 14] = 255, jpeg[dht + 5 + 15] = 255;
  const std::string what = refusal(jpeg, "huffman.jpg");
  EXPECT_NE(what.find("huffman.jpg: cannot decode the JPEG data: a Huffman table has "), std::string::npos) << what;
}

TEST(TextureDecode, HugeImagesAreRefusedFromTheHeader) {
  EXPECT_NE(refusal(handMadePng(kMaxTextureSide + 1, 1, 6, {}), "wide.png")
                .find("wide.png: image too large (32769 x 1; at most 32768 per side and 256 M texels)"),
            std::string::npos);
  EXPECT_NE(refusal(handMadePng(20000, 20000, 6, {}), "big.png").find("big.png: image too large (20000 x 20000"),
            std::string::npos);
  // within the limits, the same cut file fails on its missing data instead
  EXPECT_NE(refusal(handMadePng(16, 16, 6, {}), "cut.png").find("cut.png: cannot decode the PNG data"),
            std::string::npos);
}

TEST(TextureDecode, UnsupportedFormatsAreSniffedAndNamed) {
  const Bytes webp = {'R', 'I', 'F', 'F', 0x10, 0, 0, 0, 'W', 'E', 'B', 'P', 'V', 'P', '8', ' '};
  const Bytes ktx2 = {0xab, 'K', 'T', 'X', ' ', '2', '0', 0xbb, '\r', '\n', 0x1a, '\n', 0, 0, 0, 0};
  const Bytes png = writePng(1, 1, 3, {1, 2, 3}), jpeg = writeJpeg(1, 1, 3, {1, 2, 3}, 90);
  EXPECT_EQ(sniffImageFormat(webp.data(), webp.size()), ImageFileFormat::WebP);
  EXPECT_EQ(sniffImageFormat(ktx2.data(), ktx2.size()), ImageFileFormat::Ktx2);
  EXPECT_EQ(sniffImageFormat(png.data(), png.size()), ImageFileFormat::Png);
  EXPECT_EQ(sniffImageFormat(jpeg.data(), jpeg.size()), ImageFileFormat::Jpeg);
  EXPECT_EQ(sniffImageFormat(png.data(), 4), ImageFileFormat::Unknown);
  EXPECT_EQ(sniffImageFormat(nullptr, 0), ImageFileFormat::Unknown);
  EXPECT_TRUE(isDecodableFormat(ImageFileFormat::Png));
  EXPECT_TRUE(isDecodableFormat(ImageFileFormat::Jpeg));
  EXPECT_FALSE(isDecodableFormat(ImageFileFormat::WebP));
  EXPECT_FALSE(isDecodableFormat(ImageFileFormat::Ktx2));
  EXPECT_FALSE(isDecodableFormat(ImageFileFormat::Unknown));
  EXPECT_TRUE(isDecodableMimeType("image/png"));
  EXPECT_TRUE(isDecodableMimeType("image/jpeg"));
  EXPECT_FALSE(isDecodableMimeType("image/webp"));
  EXPECT_FALSE(isDecodableMimeType("image/ktx2"));
  EXPECT_EQ(refusal(webp, "a.webp"), "a.webp: WebP images are not supported (only PNG and JPEG)");
  EXPECT_EQ(refusal(ktx2, "b.ktx2"), "b.ktx2: KTX2 images are not supported (only PNG and JPEG)");
}

// ---------------------------------------------------------------------------
// mip pyramid

DecodedImage image8(std::uint32_t w, std::uint32_t h, std::vector<std::uint8_t> rgba) {
  DecodedImage image;
  image.width = w, image.height = h, image.rgba8 = std::move(rgba), image.name = "synthetic";
  return image;
}

/// Channel c of texel (x, y) of level `level` (absolute index) of an 8-bit image.
int channel8(const TextureSet& set, std::uint32_t level, std::uint32_t x, std::uint32_t y, int c) {
  const WtTextureLevel& l = set.levels[level];
  return int((set.texels[l.offset + y * l.width + x] >> (8 * c)) & 255u);
}

TEST(TextureMips, LevelsHalveDownToOneByOne) {
  struct Case {
    std::uint32_t w, h;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> sizes;
  };
  const std::vector<Case> cases = {
      {5, 3, {{5, 3}, {2, 1}, {1, 1}}},
      {8, 8, {{8, 8}, {4, 4}, {2, 2}, {1, 1}}},
      {1, 7, {{1, 7}, {1, 3}, {1, 1}}},
      {1, 1, {{1, 1}}},
      {16, 4, {{16, 4}, {8, 2}, {4, 1}, {2, 1}, {1, 1}}},
      {7, 6, {{7, 6}, {3, 3}, {1, 1}}},
  };
  TextureSet set;
  std::size_t texels = 0;
  for (const Case& c : cases) {
    const std::uint32_t image = set.addImage(image8(c.w, c.h, randomBytes(c.w * c.h * 4, c.w * 10 + c.h)), false);
    const WtTexture t = set.textures[set.addTexture(image)];
    ASSERT_EQ(t.level_count, c.sizes.size()) << c.w << " x " << c.h;
    for (std::size_t i = 0; i < c.sizes.size(); ++i) {
      const WtTextureLevel& l = set.levels[t.first_level + i];
      EXPECT_EQ(l.width, c.sizes[i].first) << c.w << " x " << c.h << " level " << i;
      EXPECT_EQ(l.height, c.sizes[i].second) << c.w << " x " << c.h << " level " << i;
      EXPECT_EQ(l.offset, texels) << "levels are packed back to back";
      texels += std::size_t(l.width) * l.height;
    }
  }
  EXPECT_EQ(set.texels.size(), texels);
  EXPECT_EQ(set.bytes(), texels * 4 + set.levels.size() * 16 + set.textures.size() * 16);
}

TEST(TextureMips, OddAxesUseThreeTapBoxWeights) {
  // 5 texels -> 2: weights (2, 2, 1) / 5 and (1, 2, 2) / 5
  std::vector<std::uint8_t> row;
  // (element by element: GCC 12 warns falsely about inserting an initializer list here)
  for (int v : {0, 50, 100, 150, 200})
    for (int c : {v, v, 0, 255}) row.push_back(std::uint8_t(c));
  TextureSet set;
  set.addImage(image8(5, 1, row), false);
  EXPECT_EQ(channel8(set, 1, 0, 0, 0), 40);   // (0 * 2 + 50 * 2 + 100) / 5
  EXPECT_EQ(channel8(set, 1, 1, 0, 0), 160);  // (100 + 150 * 2 + 200 * 2) / 5
  EXPECT_EQ(channel8(set, 2, 0, 0, 0), 100);
  EXPECT_EQ(channel8(set, 1, 0, 0, 3), 255);
  // 3 x 3 -> 1 x 1: the mean of all nine, each weight 1/9
  std::vector<std::uint8_t> square;
  for (int v : {9, 18, 27, 36, 45, 54, 63, 72, 90}) square.insert(square.end(), {std::uint8_t(v), 0, 0, 0});
  set.addImage(image8(3, 3, square), false);
  EXPECT_EQ(channel8(set, 4, 0, 0, 0), 46);  // 414 / 9
}

TEST(TextureMips, BoxFilterKeepsTheMean) {
  for (auto [w, h] : {std::pair{7u, 5u}, std::pair{6u, 9u}, std::pair{13u, 2u}}) {
    TextureSet set;
    set.addImage(image8(w, h, randomBytes(w * h * 4, w * h)), false);
    for (int c = 0; c < 4; ++c) {
      double mean0 = 0.0, mean1 = 0.0;
      const WtTextureLevel &l0 = set.levels[0], &l1 = set.levels[1];
      for (std::uint32_t y = 0; y < l0.height; ++y)
        for (std::uint32_t x = 0; x < l0.width; ++x) mean0 += channel8(set, 0, x, y, c);
      for (std::uint32_t y = 0; y < l1.height; ++y)
        for (std::uint32_t x = 0; x < l1.width; ++x) mean1 += channel8(set, 1, x, y, c);
      mean0 /= l0.width * l0.height, mean1 /= l1.width * l1.height;
      EXPECT_NEAR(mean1, mean0, 0.5) << w << " x " << h << " channel " << c;  // rounding only
    }
  }
}

TEST(TextureMips, SrgbIsAveragedInLinearLight) {
  // a black and white checker with a transparent/opaque alpha checker
  std::vector<std::uint8_t> checker;
  for (int i = 0; i < 16; ++i) {
    const std::uint8_t v = ((i % 4) + (i / 4)) % 2 ? 255 : 0;
    checker.insert(checker.end(), {v, v, v, std::uint8_t(255 - v)});
  }
  TextureSet set;
  const std::uint32_t srgb = set.addImage(image8(4, 4, checker), true);
  const std::uint32_t linear = set.addImage(image8(4, 4, checker), false);
  const WtTexture s = set.textures[set.addTexture(srgb)];
  const WtTexture l = set.textures[set.addTexture(linear)];
  EXPECT_NE(s.first_level, l.first_level);
  EXPECT_EQ(s.flags & WT_TEXTURE_SRGB, WT_TEXTURE_SRGB);
  EXPECT_EQ(l.flags & WT_TEXTURE_SRGB, 0u);
  // round(255 x linearToSrgb(0.5)) = round(187.5...) = 188, not 128
  EXPECT_EQ(std::lround(255.0 * linearToSrgb(0.5)), 188);
  for (std::uint32_t level = 1; level < 3; ++level) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(channel8(set, s.first_level + level, 0, 0, c), 188) << "sRGB level " << level;
      EXPECT_EQ(channel8(set, l.first_level + level, 0, 0, c), 128) << "linear level " << level;
    }
    EXPECT_EQ(channel8(set, s.first_level + level, 0, 0, 3), 128) << "alpha is never sRGB";
    EXPECT_EQ(channel8(set, l.first_level + level, 0, 0, 3), 128);
  }
  // 16-bit sRGB: the same, to 16 bits
  DecodedImage wide;
  wide.width = 2, wide.height = 1, wide.sixteenBit = true, wide.rgba16 = {0, 0, 0, 0, 65535, 65535, 65535, 65535};
  TextureSet set16;
  set16.addImage(wide, true);
  const wt_uint rg = set16.texels[set16.levels[1].offset], ba = set16.texels[set16.levels[1].offset + 1];
  const wt_uint expected = wt_uint(std::lround(65535.0 * linearToSrgb(0.5)));
  EXPECT_EQ(rg & 0xffffu, expected);
  EXPECT_EQ(rg >> 16, expected);
  EXPECT_EQ(ba & 0xffffu, expected);
  EXPECT_EQ(ba >> 16, 32768u);  // alpha linear: round(65535 / 2)
}

TEST(TextureMips, SrgbMeansRoundToTheNearestCode) {
  // level 1 of a 512 x 1 image is the mean of each pair of texels: pairs of
  // neighbouring, scattered and opposite codes
  auto linear = [](int code) { return float(srgbToLinear(code / 255.0)); };
  for (int pairing = 0; pairing < 3; ++pairing) {
    std::vector<std::uint8_t> rgba;
    std::vector<int> second(256);
    for (int a = 0; a < 256; ++a) {
      second[a] = pairing == 0 ? std::min(a + 1, 255) : pairing == 1 ? (a * 37 + 11) % 256 : 255 - a;
      rgba.insert(rgba.end(), {std::uint8_t(a), std::uint8_t(a), std::uint8_t(a), 255});
      rgba.insert(rgba.end(), {std::uint8_t(second[a]), std::uint8_t(second[a]), std::uint8_t(second[a]), 255});
    }
    TextureSet set;
    set.addImage(image8(512, 1, rgba), true);
    for (int a = 0; a < 256; ++a) {
      const float mean = 0.5f * linear(a) + 0.5f * linear(second[a]);
      const long expected = std::lround(255.0 * linearToSrgb(double(mean)));
      ASSERT_EQ(channel8(set, 1, std::uint32_t(a), 0, 0), expected) << "codes " << a << " and " << second[a];
    }
  }
}

TEST(TextureMips, SrgbTransferFunctionsAreExactAndInverse) {
  EXPECT_DOUBLE_EQ(srgbToLinear(0.04045), 0.04045 / 12.92);
  EXPECT_DOUBLE_EQ(srgbToLinear(0.5), std::pow((0.5 + 0.055) / 1.055, 2.4));
  EXPECT_DOUBLE_EQ(srgbToLinear(1.0), 1.0);
  for (int i = 0; i <= 255; ++i) EXPECT_NEAR(linearToSrgb(srgbToLinear(i / 255.0)), i / 255.0, 1e-12);
}

// ---------------------------------------------------------------------------
// packing

TEST(TextureSetPacking, TexelsPackAsTheKernelsReadThem) {
  TextureSet set;
  set.addImage(image8(1, 1, {0x11, 0x22, 0x33, 0x44}), false);
  DecodedImage wide;
  wide.width = 1, wide.height = 1, wide.sixteenBit = true, wide.rgba16 = {0x1111, 0x2222, 0x3333, 0x4444};
  const std::uint32_t second = set.addImage(wide, false);
  EXPECT_EQ(second, 1u);
  ASSERT_EQ(set.texels.size(), 3u);
  EXPECT_EQ(set.texels[0], 0x44332211u);  // R in the low byte
  EXPECT_EQ(set.levels[1].offset, 1u);
  EXPECT_EQ(set.texels[1], 0x22221111u);  // R | G << 16
  EXPECT_EQ(set.texels[2], 0x44443333u);  // B | A << 16
  EXPECT_EQ(set.textures[set.addTexture(second)].flags & WT_TEXTURE_16BIT, WT_TEXTURE_16BIT);
  EXPECT_EQ(set.textures[set.addTexture(0)].flags & WT_TEXTURE_16BIT, 0u);
}

TEST(TextureSetPacking, GltfSamplerCodesMapToFlags) {
  TextureSet set;
  set.addImage(image8(2, 2, std::vector<std::uint8_t>(16, 7)), false);
  auto flags = [&](int wrapS, int wrapT, int mag, int min) {
    return set.textures[set.addTexture(0, wrapS, wrapT, mag, min)].flags;
  };
  // wrap: undefined and unknown are REPEAT
  for (auto [code, mode] : {std::pair{10497, WT_WRAP_REPEAT}, std::pair{33071, WT_WRAP_CLAMP},
                            std::pair{33648, WT_WRAP_MIRROR}, std::pair{-1, WT_WRAP_REPEAT}, std::pair{12345, WT_WRAP_REPEAT}}) {
    EXPECT_EQ(WT_TEXTURE_WRAP_S(flags(code, 33071, -1, -1)), mode) << code;
    EXPECT_EQ(WT_TEXTURE_WRAP_T(flags(33648, code, -1, -1)), mode) << code;
  }
  EXPECT_EQ(WT_TEXTURE_WRAP_T(flags(33071, 33648, -1, -1)), WT_WRAP_MIRROR);
  // magnification: only NEAREST drops the linear bit
  EXPECT_EQ(flags(-1, -1, 9728, -1) & WT_TEXTURE_MAG_LINEAR, 0u);
  for (int code : {9729, -1, 9987})
    EXPECT_EQ(flags(-1, -1, code, -1) & WT_TEXTURE_MAG_LINEAR, WT_TEXTURE_MAG_LINEAR);
  // minification: within a level, between levels
  struct Min {
    int code;
    bool linear;
    unsigned mip;
  };
  for (Min m : {Min{9728, false, WT_MIP_NONE}, Min{9729, true, WT_MIP_NONE}, Min{9984, false, WT_MIP_NEAREST},
                Min{9985, true, WT_MIP_NEAREST}, Min{9986, false, WT_MIP_LINEAR}, Min{9987, true, WT_MIP_LINEAR},
                Min{-1, true, WT_MIP_LINEAR}, Min{4242, true, WT_MIP_LINEAR}}) {
    const wt_uint f = flags(-1, -1, -1, m.code);
    EXPECT_EQ((f & WT_TEXTURE_MIN_LINEAR) != 0, m.linear) << m.code;
    EXPECT_EQ(WT_TEXTURE_MIP(f), m.mip) << m.code;
  }
  // a texture carries its image's levels
  const WtTexture& t = set.textures.back();
  EXPECT_EQ(t.first_level, 0u);
  EXPECT_EQ(t.level_count, 2u);
}

TEST(TextureSetPacking, AppendingASetGivenUpMovesItsTexelsAndMatchesACopy) {
  auto file = [] {
    TextureSet set;
    set.addImage(image8(2, 2, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16}), true);
    set.addTexture(0, 33071, -1, 9728, -1);
    return set;
  };
  auto same = [](const TextureSet& a, const TextureSet& b) {
    EXPECT_EQ(a.texels, b.texels);
    ASSERT_EQ(a.levels.size(), b.levels.size());
    for (std::size_t i = 0; i < a.levels.size(); ++i)
      EXPECT_EQ(std::memcmp(&a.levels[i], &b.levels[i], sizeof(WtTextureLevel)), 0) << "level " << i;
    ASSERT_EQ(a.textures.size(), b.textures.size());
    for (std::size_t i = 0; i < a.textures.size(); ++i)
      EXPECT_EQ(std::memcmp(&a.textures[i], &b.textures[i], sizeof(WtTexture)), 0) << "texture " << i;
    EXPECT_EQ(a.imageCount(), b.imageCount());
  };
  TextureSet copied, moved;
  // the first file into a scene without texels: its array itself, not a copy
  TextureSet first = file(), firstCopy = file();
  const wt_uint* storage = first.texels.data();
  EXPECT_EQ(copied.append(firstCopy), 0u);
  EXPECT_EQ(moved.append(std::move(first)), 0u);
  EXPECT_EQ(moved.texels.data(), storage);
  EXPECT_TRUE(first.texels.empty());
  // a second file: copied behind the first, renumbered alike
  TextureSet second = file(), secondCopy = file();
  EXPECT_EQ(copied.append(secondCopy), 1u);
  EXPECT_EQ(moved.append(std::move(second)), 1u);
  EXPECT_TRUE(second.texels.empty());
  same(moved, copied);
  EXPECT_EQ(moved.levels.back().offset, copied.levels.back().offset);
  EXPECT_GT(moved.textures[1].first_level, 0u);
}

TEST(TextureSetPacking, BadInputIsRefused) {
  TextureSet set;
  EXPECT_THROW(set.addTexture(0), TextureError);
  try {
    set.addImage(image8(3, 3, std::vector<std::uint8_t>(30)), false);
    FAIL() << "expected TextureError";
  } catch (const TextureError& e) {
    EXPECT_EQ(std::string(e.what()), "synthetic: has 30 channel values, not width x height x 4 = 36");
  }
  EXPECT_THROW(set.addImage(image8(0, 3, {}), false), TextureError);
  EXPECT_TRUE(set.texels.empty());
  EXPECT_EQ(set.imageCount(), 0u);
}

}  // namespace
}  // namespace wt
