// The checkpoint file: round trip, and every damaged or foreign file refused
// with a message naming what is wrong.
#include "render/checkpoint.h"
#include "scene/default_scene.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

namespace wt {
namespace {

std::filesystem::path scratch(const std::string& name) {
  std::filesystem::path dir = std::filesystem::path(WT_TEST_BINARY_DIR) / "scratch" / "checkpoint";
  const std::filesystem::path path = dir / name;
  std::filesystem::create_directories(path.parent_path());
  return path;
}

Checkpoint sample(std::uint64_t pixels) {
  Checkpoint c;
  c.identity = {{"scene", "0123456789abcdef"}, {"width", std::to_string(pixels)}, {"height", "1"}, {"seed", "7"}};
  c.device = "test device";
  c.pixels = pixels;
  c.accumulation.samplesDone = 33;
  c.accumulation.nonFiniteSamples = 2;
  c.accumulation.state.resize(pixels * kAccumulationStateBytes);
  for (std::size_t i = 0; i < c.accumulation.state.size(); ++i) c.accumulation.state[i] = std::uint8_t(i * 31 + 5);
  for (std::uint64_t p = 0; p < pixels; ++p) c.accumulation.samples.push_back(std::uint32_t(33 - p % 2));
  return c;
}

using test::readAll;

void writeAll(const std::filesystem::path& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

/// The CheckpointError message reading `path` gives ("" when it reads).
std::string readError(const std::filesystem::path& path) {
  try {
    readCheckpoint(path);
  } catch (const CheckpointError& e) {
    return e.what();
  }
  return "";
}

TEST(Checkpoint, RoundTripIsExact) {
  // a folder of its own: other tests' temporary files may sit beside theirs while they write
  const auto path = scratch("round_trip/round_trip.wtckpt");
  const Checkpoint written = sample(5);
  writeCheckpoint(path, written);
  const Checkpoint read = readCheckpoint(path);
  EXPECT_EQ(read.identity, written.identity);
  EXPECT_EQ(read.device, written.device);
  EXPECT_EQ(read.pixels, written.pixels);
  EXPECT_EQ(read.accumulation.samplesDone, 33);
  EXPECT_EQ(read.accumulation.nonFiniteSamples, 2u);
  EXPECT_EQ(read.accumulation.state, written.accumulation.state);
  EXPECT_EQ(read.accumulation.samples, written.accumulation.samples);
  // no temporary file left beside it
  for (const auto& entry : std::filesystem::directory_iterator(path.parent_path()))
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST(Checkpoint, AovsRoundTripAndAVersionOneFileStillReads) {
  const auto path = scratch("aovs.wtckpt");
  Checkpoint written = sample(4);
  written.accumulation.aovs.resize(4 * (kAovSumBytes + kAovIdBytes));
  for (std::size_t i = 0; i < written.accumulation.aovs.size(); ++i)
    written.accumulation.aovs[i] = std::uint8_t(i * 17 + 3);
  writeCheckpoint(path, written);
  EXPECT_EQ(readCheckpoint(path).accumulation.aovs, written.accumulation.aovs);

  // version 1: the same file without AOVs, without the aov_bytes line, checksum recomputed
  const auto plain = scratch("plain.wtckpt");
  writeCheckpoint(plain, sample(4));
  std::vector<char> bytes = readAll(plain);
  const std::string line = "aov_bytes 0\n";
  std::uint32_t headerBytes = 0;
  std::memcpy(&headerBytes, bytes.data() + 12, 4);
  const auto at = std::search(bytes.begin() + 16, bytes.begin() + 16 + headerBytes, line.begin(), line.end());
  ASSERT_NE(at, bytes.begin() + 16 + headerBytes);
  bytes.erase(at, at + std::ptrdiff_t(line.size()));
  headerBytes -= std::uint32_t(line.size());
  const std::uint32_t one = 1;
  std::memcpy(bytes.data() + 8, &one, 4);
  std::memcpy(bytes.data() + 12, &headerBytes, 4);
  Fnv64 sum;
  sum.bytes(bytes.data(), bytes.size() - 8);
  const std::uint64_t checksum = sum.value();
  std::memcpy(bytes.data() + bytes.size() - 8, &checksum, 8);
  const auto v1 = scratch("version1.wtckpt");
  writeAll(v1, bytes);
  const Checkpoint read = readCheckpoint(v1);
  EXPECT_TRUE(read.accumulation.aovs.empty());
  EXPECT_EQ(read.accumulation.state, sample(4).accumulation.state);
}

TEST(Checkpoint, EveryTruncationIsRefused) {
  const auto path = scratch("full.wtckpt");
  writeCheckpoint(path, sample(3));
  const std::vector<char> bytes = readAll(path);
  const auto cut = scratch("truncated.wtckpt");
  for (std::size_t size = 0; size < bytes.size(); ++size) {
    writeAll(cut, std::vector<char>(bytes.begin(), bytes.begin() + std::ptrdiff_t(size)));
    const std::string error = readError(cut);
    EXPECT_NE(error.find("truncated.wtckpt: "), std::string::npos) << size << " bytes: " << error;
    // a cut in the checksum reads as a checksum failure
    EXPECT_TRUE(error.find("truncated checkpoint") != std::string::npos ||
                error.find("corrupt checkpoint") != std::string::npos)
        << size << " bytes: " << error;
  }
}

TEST(Checkpoint, EveryBitFlipIsRefused) {
  const auto path = scratch("flip_source.wtckpt");
  writeCheckpoint(path, sample(2));
  const std::vector<char> bytes = readAll(path);
  const auto flipped = scratch("flipped.wtckpt");
  for (std::size_t byte = 0; byte < bytes.size(); ++byte) {
    std::vector<char> copy = bytes;
    copy[byte] = char(copy[byte] ^ (1 << (byte % 8)));
    writeAll(flipped, copy);
    const std::string error = readError(flipped);
    EXPECT_FALSE(error.empty()) << "flip in byte " << byte << " was accepted";
  }
  // a flip in the payload is named as corruption
  std::vector<char> copy = bytes;
  copy[bytes.size() - 20] ^= 0x10;
  writeAll(flipped, copy);
  EXPECT_NE(readError(flipped).find("corrupt checkpoint (checksum"), std::string::npos) << readError(flipped);
  // and a file that is no checkpoint at all says so
  writeAll(flipped, std::vector<char>(100, 'x'));
  EXPECT_NE(readError(flipped).find("not a wavetrace checkpoint"), std::string::npos);
}

TEST(Checkpoint, AnotherRenderIsRefusedNamingWhatDiffers) {
  const Checkpoint found = sample(1);
  auto message = [&](std::vector<CheckpointField> expected) {
    try {
      requireSameRender("x.wtckpt", found, expected);
    } catch (const CheckpointError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(message(found.identity), "");
  auto other = found.identity;
  other[0].value = "fedcba9876543210";
  EXPECT_NE(message(other).find("another scene (scene content hash 0123456789abcdef in the checkpoint, "
                                "fedcba9876543210 here)"),
            std::string::npos)
      << message(other);
  other = found.identity;
  other[3].value = "8";
  EXPECT_NE(message(other).find("seed 7 in the checkpoint, 8 here"), std::string::npos) << message(other);
  other.push_back({"sampler", "sobol"});
  EXPECT_NE(message(other).find("sampler missing from the checkpoint"), std::string::npos) << message(other);
}

TEST(Checkpoint, SceneHashSeesAnyChangeOfContent) {
  Scene scene = loadDefaultScene();
  const std::uint64_t base = sceneContentHash(scene);
  EXPECT_EQ(sceneContentHash(loadDefaultScene()), base);  // a pure function of the content
  scene.sourceName = "renamed.gltf";
  EXPECT_EQ(sceneContentHash(scene), base);  // not of the path
  Scene moved = loadDefaultScene();
  moved.positions[5].y = std::nextafter(moved.positions[5].y, 1e9f);
  EXPECT_NE(sceneContentHash(moved), base);
  Scene recoloured = loadDefaultScene();
  recoloured.materials[1].base_color.x *= 0.5f;
  EXPECT_NE(sceneContentHash(recoloured), base);
  Scene reframed = loadDefaultScene();
  reframed.camera->yfov *= 1.01f;
  EXPECT_NE(sceneContentHash(reframed), base);
}

TEST(Checkpoint, HashIsTheSameHoweverTheStreamIsSplit) {
  std::vector<unsigned char> data(37);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<unsigned char>(i * 7 + 1);
  Fnv64 whole;
  whole.bytes(data.data(), data.size());
  for (std::size_t a = 0; a <= data.size(); ++a)
    for (std::size_t b = a; b <= data.size(); b += 3) {
      Fnv64 split;
      split.bytes(data.data(), a);
      split.bytes(data.data() + a, b - a);
      split.bytes(data.data() + b, data.size() - b);
      ASSERT_EQ(split.value(), whole.value()) << a << " " << b;
    }
}

}  // namespace
}  // namespace wt
