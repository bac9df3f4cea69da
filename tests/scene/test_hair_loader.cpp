// Strand files (host/scene/hair_loader.cpp): .hair and PLY polylines made in
// memory, every error naming the file and the element, truncations and
// flipped bytes that must fail cleanly; and the hairutil test files from
// ../shared/assets (HairLoaderAssets).
#include "scene/hair_loader.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <random>
#include <string>

namespace wt {
namespace {

void put32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(std::uint8_t(v >> (8 * k)));
}
void putF(std::vector<std::uint8_t>& out, float v) { put32(out, std::bit_cast<std::uint32_t>(v)); }

/// A .hair file: strands of `segments[i]` segments (or the default when
/// `segments` is empty), points from `points`, optional thickness per point.
std::vector<std::uint8_t> makeHair(const std::vector<std::uint16_t>& segments, std::uint32_t strands,
                                   std::uint32_t defaultSegments, const std::vector<glm::vec3>& points,
                                   const std::vector<float>& thickness, float defaultThickness = 1.0f) {
  std::vector<std::uint8_t> out = {'H', 'A', 'I', 'R'};
  put32(out, strands);
  put32(out, std::uint32_t(points.size()));
  put32(out, (segments.empty() ? 0u : 1u) | 2u | (thickness.empty() ? 0u : 4u));
  put32(out, defaultSegments);
  putF(out, defaultThickness);
  putF(out, 0.0f);
  for (int k = 0; k < 3; ++k) putF(out, 1.0f);
  out.resize(128, 0);
  for (std::uint16_t s : segments) out.push_back(std::uint8_t(s)), out.push_back(std::uint8_t(s >> 8));
  for (const glm::vec3& p : points) putF(out, p.x), putF(out, p.y), putF(out, p.z);
  for (float t : thickness) putF(out, t);
  return out;
}

std::vector<glm::vec3> somePoints(int n) {
  std::vector<glm::vec3> p;
  for (int i = 0; i < n; ++i) p.push_back({float(i), 0.5f * float(i), -float(i)});
  return p;
}

/// The error message of loading `bytes`, or "" when it loads.
template <class Load>
std::string errorOf(Load load, const std::vector<std::uint8_t>& bytes, const std::string& name) {
  try {
    load(bytes, name);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

StrandSet hair(const std::vector<std::uint8_t>& bytes, const std::string& name) { return loadHairFromMemory(bytes, name); }
StrandSet ply(const std::vector<std::uint8_t>& bytes, const std::string& name) {
  return loadPlyStrandsFromMemory(bytes, name);
}

TEST(HairLoader, ReadsStrandsAndThickness) {
  const std::vector<glm::vec3> points = somePoints(7);
  const StrandSet set = loadHairFromMemory(makeHair({2, 3}, 2, 0, points, {1, 2, 3, 4, 5, 6, 7}), "a.hair");
  ASSERT_EQ(set.counts, (std::vector<std::uint32_t>{3, 4}));
  ASSERT_EQ(set.points.size(), 7u);
  EXPECT_TRUE(set.hasRadius);
  for (int i = 0; i < 7; ++i) {
    EXPECT_EQ(glm::vec3(set.points[i]), points[i]);
    EXPECT_FLOAT_EQ(set.points[i].w, 0.5f * float(i + 1));  // half the thickness
  }
}

TEST(HairLoader, DefaultSegmentsAndThickness) {
  const StrandSet set = loadHairFromMemory(makeHair({}, 3, 1, somePoints(6), {}, 0.25f), "b.hair");
  EXPECT_EQ(set.counts, (std::vector<std::uint32_t>{2, 2, 2}));
  for (const glm::vec4& p : set.points) EXPECT_FLOAT_EQ(p.w, 0.125f);
}

TEST(HairLoader, ErrorsNameTheFileAndTheElement) {
  const std::vector<glm::vec3> points = somePoints(7);
  struct Case {
    std::vector<std::uint8_t> bytes;
    const char* expect;
  };
  std::vector<Case> cases;
  cases.push_back({{'H', 'A', 'I'}, "x.hair: header: the file has 3 bytes"});
  std::vector<std::uint8_t> notHair = makeHair({2, 3}, 2, 0, points, {});
  notHair[0] = 'X';
  cases.push_back({notHair, "x.hair: header: not a .hair file"});
  cases.push_back({makeHair({2, 2}, 2, 0, points, {}), "x.hair: header: the strands' segments need 6 points, the header says 7"});
  cases.push_back({makeHair({}, 2, 2, points, {}), "x.hair: header: the strands' segments need 6 points, the header says 7"});
  std::vector<glm::vec3> nan = points;
  nan[5].y = NAN;
  cases.push_back({makeHair({2, 3}, 2, 0, nan, {}), "x.hair: strand 1, point 2: coordinate is not finite (nan)"});
  cases.push_back({makeHair({2, 3}, 2, 0, points, {1, 1, 1, -2, 1, 1, 1}),
                   "x.hair: strand 1, point 0: thickness must be finite and >= 0, got -2"});
  cases.push_back({makeHair({2, 3}, 2, 0, points, {}, NAN), "x.hair: header: the default thickness must be finite"});
  std::vector<std::uint8_t> truncated = makeHair({2, 3}, 2, 0, points, {1, 1, 1, 1, 1, 1, 1});
  truncated.resize(truncated.size() - 3);
  cases.push_back({truncated, "x.hair: the file ends at byte 241, inside the thickness array"});
  std::vector<std::uint8_t> noPoints = makeHair({2, 3}, 2, 0, points, {});
  noPoints[12] = 1;  // segments only
  cases.push_back({noPoints, "x.hair: header: the file has no points array"});
  std::vector<std::uint8_t> huge = makeHair({2, 3}, 2, 0, points, {});
  huge[8] = 0xff, huge[9] = 0xff, huge[10] = 0xff, huge[11] = 0x7f;  // 2^31 points
  cases.push_back({huge, "x.hair: header: 2147483647 points, more than the 268435456 supported"});
  for (const Case& c : cases) EXPECT_EQ(errorOf(hair, c.bytes, "x.hair").rfind(c.expect, 0), 0u) << errorOf(hair, c.bytes, "x.hair");
}

/// A PLY file of two strands (2 and 1 segments) in `format`, with colours,
/// an edge element and a face list to skip; `radius` adds a radius property.
std::vector<std::uint8_t> makePly(const std::string& format, bool radius, float y1 = 0.5f) {
  const float xyz[5][3] = {{0, 0, 0}, {1, y1, 0}, {2, 1, 0}, {5, 5, 5}, {6, 5, 5}};
  std::string header = "ply\nformat " + format + " 1.0\ncomment made by a test\nelement vertex 5\n"
                       "property float x\nproperty float y\nproperty float z\n" +
                       std::string(radius ? "property double radius\n" : "") +
                       "property uchar red\nelement face 1\nproperty list uchar int vertex_indices\n"
                       "element strand 2\nproperty ushort nsegs\nelement edge 3\nproperty int vertex1\n"
                       "property int vertex2\nend_header\n";
  std::vector<std::uint8_t> out(header.begin(), header.end());
  const bool big = format == "binary_big_endian";
  auto raw = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    for (std::size_t k = 0; k < n; ++k) out.push_back(big ? b[n - 1 - k] : b[k]);
  };
  auto text = [&](const std::string& s) { out.insert(out.end(), s.begin(), s.end()); };
  if (format == "ascii") {
    for (int i = 0; i < 5; ++i) {
      char line[128];
      std::snprintf(line, sizeof line, "%g %g %g%s 200\n", double(xyz[i][0]), double(xyz[i][1]), double(xyz[i][2]),
                    radius ? " 0.25" : "");
      text(line);
    }
    text("3 0 1 2\n2\n1\n0 1\n1 2\n3 4\n");
    return out;
  }
  for (int i = 0; i < 5; ++i) {
    for (int k = 0; k < 3; ++k) raw(&xyz[i][k], 4);
    if (radius) {
      const double r = 0.25;
      raw(&r, 8);
    }
    out.push_back(200);
  }
  out.push_back(3);
  for (std::int32_t v : {0, 1, 2}) raw(&v, 4);
  for (std::uint16_t s : {2, 1}) raw(&s, 2);
  for (std::int32_t v : {0, 1, 1, 2, 3, 4}) raw(&v, 4);
  return out;
}

TEST(HairLoader, ReadsPlyPolylinesInEveryFormat) {
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"})
    for (bool radius : {false, true}) {
      const StrandSet set = loadPlyStrandsFromMemory(makePly(format, radius), "s.ply");
      ASSERT_EQ(set.counts, (std::vector<std::uint32_t>{3, 2})) << format;
      ASSERT_EQ(set.points.size(), 5u);
      EXPECT_EQ(set.hasRadius, radius);
      EXPECT_EQ(set.points[1], glm::vec4(1, 0.5f, 0, radius ? 0.25f : 0.0f)) << format;
      EXPECT_EQ(set.points[4], glm::vec4(6, 5, 5, radius ? 0.25f : 0.0f)) << format;
    }
}

TEST(HairLoader, PlyErrorsNameTheFileAndTheElement) {
  auto edited = [](std::string text, const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    return std::vector<std::uint8_t>(text.begin(), text.end());
  };
  const std::vector<std::uint8_t> ascii = makePly("ascii", false);
  const std::string text(ascii.begin(), ascii.end());
  struct Case {
    std::vector<std::uint8_t> bytes;
    const char* expect;
  };
  std::vector<Case> cases = {
      {edited(text, "ply\n", "plx\n"), "s.ply: line 1: not a PLY file"},
      {edited(text, "ascii", "binary_middle_endian"), "s.ply: line 2: unknown format"},
      {edited(text, "end_header\n", "end_headr\n"), "s.ply: line 16: unknown header keyword"},
      {edited(text, "property float y\n", ""), "s.ply: line 4: vertex needs scalar x, y and z"},
      {edited(text, "element strand 2\nproperty ushort nsegs\n", ""), "s.ply: no \"strand\" element"},
      {edited(text, "element vertex 5", "element vertex 6"), "s.ply: edge 1, vertex2: the file ends before this value"},
      {edited(text, "2\n1\n0 1", "2\n2\n0 1"), "s.ply: strand: the strands' segments need 6 points, there are 5 vertices"},
      {edited(text, "1 0.5 0", "1 nan 0"), "s.ply: vertex 1 (strand 0, point 1): coordinate is not finite (nan)"},
      {edited(text, "1 0.5 0", "1 0.5q 0"), "s.ply: vertex 1, y: not a number: \"0.5q\""},
      {edited(text, "property float z\n", "property float z\nproperty quad w\n"), "s.ply: line 8: unknown property type"},
      {edited(text, "element vertex 5", "element vertex 5x"), "s.ply: line 4: expected \"element <name> <count>\""},
  };
  std::vector<std::uint8_t> binary = makePly("binary_little_endian", false);
  binary.resize(binary.size() - 5);
  cases.push_back({binary, "s.ply: edge: 3 items do not fit in the 19 bytes left"});
  std::vector<std::uint8_t> lying = makePly("binary_little_endian", false);
  const std::string lyingText(lying.begin(), lying.end());
  cases.push_back({edited(lyingText, "element vertex 5", "element vertex 500000000"),
                   "s.ply: vertex: 500000000 points, more than the"});
  cases.push_back({edited(lyingText, "element vertex 5", "element vertex 5000000"),
                   "s.ply: vertex: 5000000 items do not fit"});
  const std::vector<std::uint8_t> nanBinary = makePly("binary_little_endian", true, NAN);
  cases.push_back({nanBinary, "s.ply: vertex 1 (strand 0, point 1): coordinate is not finite (nan)"});
  for (const Case& c : cases)
    EXPECT_EQ(errorOf(ply, c.bytes, "s.ply").rfind(c.expect, 0), 0u) << errorOf(ply, c.bytes, "s.ply");
}

TEST(HairLoader, DamagedFilesFailCleanly) {
  // every truncation and a few thousand flipped bytes: loaded or refused with
  // a SceneError naming the file, never a crash
  std::mt19937 rng(3);
  const std::vector<std::vector<std::uint8_t>> files = {
      makeHair({2, 3}, 2, 0, somePoints(7), {1, 2, 3, 4, 5, 6, 7}), makePly("ascii", true),
      makePly("binary_little_endian", true), makePly("binary_big_endian", false)};
  for (std::size_t f = 0; f < files.size(); ++f) {
    auto load = f == 0 ? hair : ply;
    const std::string name = f == 0 ? "d.hair" : "d.ply";
    for (std::size_t n = 0; n < files[f].size(); ++n) {
      const std::vector<std::uint8_t> cut(files[f].begin(), files[f].begin() + std::ptrdiff_t(n));
      const std::string error = errorOf(load, cut, name);
      // (an ASCII file may lose its last line break and stay whole)
      const bool whole = std::all_of(files[f].begin() + std::ptrdiff_t(n), files[f].end(),
                                     [](std::uint8_t c) { return std::isspace(c); });
      if (!whole) {
        EXPECT_EQ(error.rfind(name + ": ", 0), 0u) << "cut at " << n << ": " << error;
      }
    }
    for (int k = 0; k < 3000; ++k) {
      std::vector<std::uint8_t> bytes = files[f];
      bytes[std::uniform_int_distribution<std::size_t>(0, bytes.size() - 1)(rng)] ^= std::uint8_t(1 + rng() % 255);
      const std::string error = errorOf(load, bytes, name);
      EXPECT_TRUE(error.empty() || error.rfind(name + ": ", 0) == 0) << error;
    }
  }
}

TEST(HairLoader, ChoosesTheReaderByExtension) {
  try {
    loadStrands("/nonexistent/strands.obj");
    FAIL() << "no error";
  } catch (const SceneError& e) {
    EXPECT_STREQ(e.what(), "strands.obj: not a strand file (expected .hair or .ply)");
  }
  try {
    loadStrands("/nonexistent/strands.hair");
    FAIL() << "no error";
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("strands.hair: cannot open /nonexistent/strands.hair (no such file)", 0), 0u);
  }
}

TEST(HairLoaderAssets, BangsAsHairAndAsPlyAgree) {
  WT_REQUIRE_ASSET(hairPath, "curves/hairutil_testdata/Bangs_100.hair");
  WT_REQUIRE_ASSET(plyPath, "curves/hairutil_testdata/Bangs_100_binary.ply");
  const StrandSet h = loadStrands(hairPath.string()), p = loadStrands(plyPath.string());
  ASSERT_EQ(h.counts.size(), 100u);
  ASSERT_EQ(h.points.size(), 1165u);
  EXPECT_EQ(h.counts, p.counts);
  ASSERT_EQ(h.points.size(), p.points.size());
  for (std::size_t i = 0; i < h.points.size(); ++i) EXPECT_EQ(glm::vec3(h.points[i]), glm::vec3(p.points[i])) << i;
  for (const glm::vec4& v : h.points) EXPECT_FLOAT_EQ(v.w, 0.5f);  // the header's default thickness 1
  EXPECT_FALSE(p.hasRadius);
}

TEST(HairLoaderAssets, CurlyPly) {
  WT_REQUIRE_ASSET(path, "curves/hairutil_testdata/Curly_100.ply");
  const StrandSet s = loadStrands(path.string());
  EXPECT_EQ(s.counts.size(), 100u);
  EXPECT_EQ(s.points.size(), 2528u);
}

}  // namespace
}  // namespace wt
