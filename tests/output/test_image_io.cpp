// Image output: formats by extension, round trips, and writes that never
// destroy an earlier image.
#include "output/image_io.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <stb_image.h>
#include <zlib.h>

#include <fstream>
#include <random>
#include <utility>

#include <sys/wait.h>
#include <unistd.h>

namespace wt {
namespace {

Image gradient(int w, int h) {
  Image image;
  image.width = w;
  image.height = h;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      image.rgb.insert(image.rgb.end(), {float(x) / w, float(y) / h, 1e-3f * float(x * y) + 12.5f});
      image.srgba.insert(image.srgba.end(), {std::uint8_t(x), std::uint8_t(y), 7, 255});
    }
  return image;
}

TEST(ImageIo, ExrRoundTripIsExact) {
  std::filesystem::path path = test::scratchDir("image_io") / "gradient.exr";
  Image image = gradient(37, 21);
  writeImage(path, image);
  Image back = readExr(path);
  EXPECT_EQ(back.width, 37);
  EXPECT_EQ(back.height, 21);
  EXPECT_EQ(back.rgb, image.rgb);
  EXPECT_EQ(back.samplesDone, 0);  // unknown: not recorded
  // the sample count, in the header: what an image that outlived its render holds
  image.samplesDone = 1234567;
  writeImage(path, image);
  EXPECT_EQ(readExr(path).samplesDone, 1234567);
}

TEST(ImageIo, PngHasTheTonemappedPixels) {
  std::filesystem::path path = test::scratchDir("image_io") / "gradient.png";
  Image image = gradient(19, 11);
  writeImage(path, image);
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &n, 4);
  ASSERT_NE(data, nullptr);
  EXPECT_EQ(w, 19);
  EXPECT_EQ(h, 11);
  EXPECT_EQ(std::vector<std::uint8_t>(data, data + 4 * w * h), image.srgba);
  stbi_image_free(data);
}

// Rows filtered against the row above and deflated: any content and any
// shape (one row, one column, odd widths) decodes to the same pixels.
TEST(ImageIo, PngRoundTripsAnyPixels) {
  std::mt19937 rng(7);
  for (auto [w, h] : {std::pair{1, 1}, {1, 9}, {13, 1}, {257, 31}, {64, 64}}) {
    Image image;
    image.width = w;
    image.height = h;
    image.rgb.assign(std::size_t(3 * w * h), 0.0f);
    for (int i = 0; i < 4 * w * h; ++i) image.srgba.push_back(std::uint8_t(rng()));
    std::filesystem::path path = test::scratchDir("image_io") / "noise.png";
    writeImage(path, image);
    int rw = 0, rh = 0, n = 0;
    unsigned char* data = stbi_load(path.c_str(), &rw, &rh, &n, 4);
    ASSERT_NE(data, nullptr) << w << "x" << h << ": " << stbi_failure_reason();
    EXPECT_EQ(rw, w);
    EXPECT_EQ(rh, h);
    EXPECT_EQ(n, 4) << "RGBA in the file";
    EXPECT_EQ(std::vector<std::uint8_t>(data, data + 4 * rw * rh), image.srgba) << w << "x" << h;
    stbi_image_free(data);
  }
}

// An image large enough to be deflated in parts at once (writePng) is still
// one zlib stream whose checksum zlib itself verifies, with the same pixels.
TEST(ImageIo, PngDeflatedInPartsIsOneStream) {
  std::mt19937 rng(11);
  const int w = 300, h = 257;  // 300 KB of rows, an odd row count
  Image image;
  image.width = w;
  image.height = h;
  image.rgb.assign(std::size_t(3 * w * h), 0.0f);
  // noise above, flat below: both halves' data differ in kind
  for (int i = 0; i < 4 * w * h; ++i) image.srgba.push_back(i < 2 * w * h ? std::uint8_t(rng()) : std::uint8_t(i % 4 * 60));
  const std::filesystem::path path = test::scratchDir("image_io") / "large.png";
  writeImage(path, image);
  std::ifstream in(path, std::ios::binary);
  const std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string idat;
  for (std::size_t at = 8; at + 12 <= file.size();) {
    const auto byte = [&](std::size_t k) { return std::uint32_t(std::uint8_t(file[at + k])); };
    const std::size_t length = (byte(0) << 24) | (byte(1) << 16) | (byte(2) << 8) | byte(3);
    if (file.compare(at + 4, 4, "IDAT") == 0) idat += file.substr(at + 8, length);
    at += 12 + length;
  }
  std::vector<Bytef> rows(std::size_t(h) * (4 * w + 1));
  uLongf rowBytes = uLongf(rows.size());
  ASSERT_EQ(uncompress(rows.data(), &rowBytes, reinterpret_cast<const Bytef*>(idat.data()), uLong(idat.size())), Z_OK);
  EXPECT_EQ(rowBytes, rows.size());
  int rw = 0, rh = 0, n = 0;
  unsigned char* data = stbi_load(path.c_str(), &rw, &rh, &n, 4);
  ASSERT_NE(data, nullptr) << stbi_failure_reason();
  EXPECT_EQ(std::vector<std::uint8_t>(data, data + 4 * rw * rh), image.srgba);
  stbi_image_free(data);
}

TEST(ImageIo, FormatFromExtension) {
  EXPECT_EQ(imageFormatFor("a/b.EXR"), ImageFormat::Exr);
  EXPECT_EQ(imageFormatFor("b.png"), ImageFormat::Png);
  EXPECT_THROW(imageFormatFor("b.jpg"), OutputError);
  EXPECT_THROW(imageFormatFor("noextension"), OutputError);
}

TEST(ImageIo, UnwritablePathsAreReportedBeforeRendering) {
  EXPECT_THROW(checkWritable("/nonexistent-folder/x.png"), OutputError);
  EXPECT_THROW(checkWritable(test::scratchDir("image_io") / "x.tiff"), OutputError);
  EXPECT_THROW(checkWritable(test::scratchDir("image_io")), OutputError);
  EXPECT_NO_THROW(checkWritable(test::scratchDir("image_io") / "ok.exr"));
  try {
    checkWritable("/nonexistent-folder/x.png");
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-folder/x.png"), std::string::npos);
  }
}

TEST(ImageIo, FailedWriteKeepsTheEarlierImage) {
  std::filesystem::path path = test::scratchDir("image_io") / "keep.exr";
  Image good = gradient(8, 8);
  writeImage(path, good);
  auto before = std::filesystem::file_size(path);
  Image broken;  // zero-sized: OpenEXR refuses the data window
  broken.width = 0;
  broken.height = 0;
  EXPECT_THROW(writeImage(path, broken), OutputError);
  EXPECT_EQ(std::filesystem::file_size(path), before);
  EXPECT_EQ(readExr(path).rgb, good.rgb);
  // and no temporary file is left behind
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(path.parent_path()))
    files += entry.path().filename().string().find("keep.exr.tmp") != std::string::npos;
  EXPECT_EQ(files, 0);
}

// A PNG of an image that was never tone-mapped is an error naming the file, not a read past the pixels.
TEST(ImageIo, PngWithoutEightBitPixelsIsAnError) {
  const std::filesystem::path path = test::scratchDir("image_io") / "untoned.png";
  Image untoned = gradient(8, 8);
  untoned.srgba.clear();  // linear rgb only
  try {
    writeImage(path, untoned);
    ADD_FAILURE() << "no error";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find("untoned.png"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(path));
}

// A writer killed mid-write leaves its temporary; the next write of that file
// removes it, and leaves a running process's temporary alone.
TEST(ImageIo, NextWriteRemovesADeadWritersTemporary) {
  const std::filesystem::path path = test::scratchDir("image_io") / "killed.exr";
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ::waitpid(child, nullptr, 0);  // a pid that no longer runs
  const std::filesystem::path dead = path.parent_path() / (".killed.exr.tmp" + std::to_string(child) + ".17");
  const std::filesystem::path alive = path.parent_path() / (".killed.exr.tmp" + std::to_string(::getppid()) + ".17");
  const std::filesystem::path other = path.parent_path() / (".killed.exr.other" + std::to_string(child));
  for (const auto& p : {dead, alive, other}) std::ofstream(p) << "partial";
  writeImage(path, gradient(4, 4));
  EXPECT_FALSE(std::filesystem::exists(dead));
  EXPECT_TRUE(std::filesystem::exists(alive));
  EXPECT_TRUE(std::filesystem::exists(other));
  EXPECT_EQ(readExr(path).width, 4);
}

}  // namespace
}  // namespace wt
