// Packet traversal (kernels/bvh_packet.cl) against one ray per work-item:
// every lane must make its ray's decisions, so both give the same closest
// hits (distance, barycentrics, triangle) and the same occlusion, on coherent
// rays that really go through the packet path, for every builder and leaf
// size and both packet widths (8 and 16 rays); and against brute force
// through the shared checks.
#include "brute_force.h"
#include "bvh/builders.h"
#include "device/program.h"
#include "device_fixture.h"
#include "scene/generators.h"
#include "test_util.h"
#include "tree_param.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <tuple>

namespace wt {
namespace {

/// Camera-like fans: from each eye, a grid of directions through a small
/// window around the scene's centre, in scanline order (neighbouring rays
/// are neighbouring pixels). Some rays get a finite segment, a later tmin or
/// a triangle to skip, so lanes of one packet differ in what they search.
std::vector<Ray> cameraFans(const Scene& scene, int width, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> t01(0.0f, 1.0f);
  std::uniform_int_distribution<std::uint32_t> tri(0, std::uint32_t(scene.triangles.size() - 1));
  std::vector<Ray> rays;
  const glm::vec3 target(0.5f);
  for (glm::vec3 eye : {glm::vec3(0.4f, 0.6f, 3.0f), glm::vec3(-2.0f, 1.5f, -1.0f), glm::vec3(2.5f, -1.2f, 0.7f)}) {
    glm::vec3 w = glm::normalize(target - eye);
    glm::vec3 u = glm::normalize(glm::cross(w, glm::vec3(0.0f, 1.0f, 0.0f)));
    glm::vec3 v = glm::cross(u, w);
    for (int y = 0; y < width; ++y)
      for (int x = 0; x < width; ++x) {
        Ray r;
        r.origin = eye;
        float sx = (x + 0.5f) / width - 0.5f, sy = (y + 0.5f) / width - 0.5f;
        r.direction = glm::normalize(w + 0.6f * sx * u + 0.6f * sy * v);
        std::size_t i = rays.size();
        if (i % 7 == 3) r.tmax = 2.0f + 2.0f * t01(rng);
        if (i % 11 == 5) r.tmin = 2.5f * t01(rng);
        if (i % 13 == 2) r.skip = tri(rng);
        rays.push_back(r);
      }
  }
  return rays;
}

/// Whether the watertight test's axis permutation of two directions is the
/// same (the dominant axis, and the swap for a negative dominant component),
/// as triangle_ray_shear picks it.
int permutation(glm::vec3 d) {
  glm::vec3 a = glm::abs(d);
  int kz = (a.x > a.y) ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
  return 2 * kz + (d[kz] < 0.0f ? 1 : 0);
}

/// Both packet widths a device may be given (packetWidthFor).
constexpr int kPacketWidths[] = {8, 16};

/// The least share of whole packets a test's fans must have at `width`, so
/// the packet path is what is tested. Measured: 0.82 (8) and 0.65 (16) on
/// the small fans Oclgrind runs (rows of 16), above 0.9 and 0.88 at full size.
double minPacketShare(int width) { return width == 8 ? 0.8 : 0.6; }

/// The share of full packets (`width` consecutive rays) whose rays share one
/// permutation, and so go through the packet path.
double packetShare(const std::vector<Ray>& rays, std::size_t width) {
  std::size_t packets = 0, uniform = 0;
  for (std::size_t i = 0; i + width <= rays.size(); i += width) {
    ++packets;
    bool same = true;
    for (std::size_t l = 1; l < width; ++l)
      same = same && permutation(rays[i + l].direction) == permutation(rays[i].direction);
    uniform += same;
  }
  return packets ? double(uniform) / packets : 0.0;
}

using test::sameBits;

/// Packets against single rays on the same tree: identical answers, except
/// that of two hits at exactly the same distance either may win.
/// `coherent`: most packets' lanes must share one permutation (the shared
/// test, not each lane's own).
void expectPacketsMatchSingleRays(const Scene& scene, const std::vector<Ray>& rays, const BvhBuildOptions& options,
                                  int width, bool coherent = true) {
  SCOPED_TRACE("packets of " + std::to_string(width));
  // the rays must really go through the path under test
  if (coherent) {
    ASSERT_GT(packetShare(rays, std::size_t(width)), minPacketShare(width));
  }
  Tracer tracer(test::deviceContext(), scene, options, width);
  ASSERT_EQ(tracer.packetWidth(), width);
  std::vector<RayHit> single = tracer.traceClosest(rays, Traversal::kSingle);
  std::vector<RayHit> packet = tracer.traceClosest(rays, Traversal::kPacket);
  std::vector<std::uint8_t> singleBlocked = tracer.traceOccluded(rays, Traversal::kSingle);
  std::vector<std::uint8_t> packetBlocked = tracer.traceOccluded(rays, Traversal::kPacket);
  ASSERT_EQ(packet.size(), rays.size());
  int differ = 0, ties = 0, hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const RayHit &a = single[i], &b = packet[i];
    hits += a.triangle != RayHit::kNoHit;
    if (a.triangle != b.triangle && a.triangle != RayHit::kNoHit && b.triangle != RayHit::kNoHit &&
        sameBits(a.t, b.t)) {
      ++ties;
      continue;
    }
    bool same = a.triangle == b.triangle && sameBits(a.t, b.t) && sameBits(a.b1, b.b1) && sameBits(a.b2, b.b2);
    if (!same && ++differ <= 5)
      ADD_FAILURE() << "ray " << i << ": single triangle " << a.triangle << " t=" << a.t << " (" << a.b1 << ", "
                    << a.b2 << "), packet triangle " << b.triangle << " t=" << b.t << " (" << b.b1 << ", " << b.b2
                    << ")";
    if (singleBlocked[i] != packetBlocked[i] && ++differ <= 5)
      ADD_FAILURE() << "ray " << i << ": occluded " << int(singleBlocked[i]) << " alone, " << int(packetBlocked[i])
                    << " in a packet";
  }
  EXPECT_EQ(differ, 0);
  // ties are rays through a shared edge at exactly the same distance: rare
  EXPECT_LE(ties, int(rays.size() / 1000) + 1);
  EXPECT_GT(hits, int(rays.size() / 10));
  EXPECT_LT(hits, int(rays.size()));
}

class PacketTraversal : public test::TreeParamTest {};

TEST_P(PacketTraversal, CoherentRaysMatchSingleRaysOnASoup) {
  Scene scene = makeTriangleSoup(3000, 3, 0.15f);
  std::vector<Ray> rays = cameraFans(scene, int(test::testSize(48, 16)), 1);
  for (int width : kPacketWidths) expectPacketsMatchSingleRays(scene, rays, options(), width);
}

TEST_P(PacketTraversal, CoherentRaysMatchSingleRaysOnAClosedSphere) {
  Scene scene = makeIcosphere(3, glm::vec3(0.5f), 0.6f, makeMaterial(glm::vec3(0.5f)));
  std::vector<Ray> rays = cameraFans(scene, int(test::testSize(48, 16)), 2);
  for (int width : kPacketWidths) expectPacketsMatchSingleRays(scene, rays, options(), width);
}

INSTANTIATE_TEST_SUITE_P(Trees, PacketTraversal,
                         ::testing::Combine(::testing::Values(BvhBuilder::Lbvh, BvhBuilder::Ploc, BvhBuilder::Sah),
                                            ::testing::Values(1, 4, 8)),
                         test::treeParamName);

TEST(PacketTraversalEdges, CoherentRaysMatchBruteForce) {
  Scene scene = makeTriangleSoup(2000, 9, 0.2f);
  std::vector<Ray> rays = cameraFans(scene, int(test::testSize(48, 16)), 3);
  std::vector<test::BruteHit> want(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) want[i] = test::bruteClosest(scene, rays[i]);
  for (int width : kPacketWidths) {
    SCOPED_TRACE("packets of " + std::to_string(width));
    ASSERT_GT(packetShare(rays, std::size_t(width)), minPacketShare(width));
    Tracer tracer(test::deviceContext(), scene, {}, width);
    std::vector<RayHit> hits = tracer.traceClosest(rays, Traversal::kPacket);
    std::vector<std::uint8_t> blocked = tracer.traceOccluded(rays, Traversal::kPacket);
    int disagreements = 0, occlusionErrors = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      if (!test::agrees(scene, rays[i], hits[i], want[i]) && ++disagreements <= 5)
        ADD_FAILURE() << "ray " << i << ": packet triangle " << hits[i].triangle << " t=" << hits[i].t
                      << ", brute force triangle " << want[i].triangle << " t=" << want[i].t;
      bool wantBlocked = want[i].triangle != RayHit::kNoHit;
      if (bool(blocked[i]) != wantBlocked && !(wantBlocked && want[i].minBarycentric < 1e-5) &&
          !(bool(blocked[i]) && hits[i].triangle != RayHit::kNoHit))
        ++occlusionErrors;
    }
    EXPECT_EQ(disagreements, 0);
    EXPECT_EQ(occlusionErrors, 0);
  }
}

TEST(PacketTraversalEdges, PartialPacketsMixedLanesAndEmptyScenes) {
  // batches that end inside a packet; packets holding rays that are not
  // finite next to ordinary ones (those lanes miss and count as blocked, as
  // alone); a packet whose rays disagree on the permutation (one pass per
  // permutation)
  Scene scene = makeTriangleSoup(500, 4, 0.2f);
  std::vector<Ray> fan = cameraFans(scene, 8, 4);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (std::size_t i = 5; i < fan.size(); i += 29) fan[i].direction.y = (i % 2) ? nan : inf;
  for (std::size_t i = 17; i < fan.size(); i += 37) fan[i].origin.x = nan;
  for (int l = 0; l < 8; ++l) {  // one packet pointing along all six axis directions
    Ray r;
    r.origin = glm::vec3(0.5f);
    r.direction = glm::vec3(0.0f);
    r.direction[l % 3] = (l & 1) ? -1.0f : 1.0f;
    fan.push_back(r);
  }
  for (int width : kPacketWidths) {
    SCOPED_TRACE("packets of " + std::to_string(width));
    Tracer tracer(test::deviceContext(), scene, {}, width);
    for (std::size_t count : {std::size_t(1), std::size_t(7), std::size_t(9), std::size_t(15), std::size_t(17),
                              std::size_t(100), fan.size()}) {
      std::vector<Ray> rays(fan.end() - std::ptrdiff_t(count), fan.end());
      std::vector<RayHit> single = tracer.traceClosest(rays, Traversal::kSingle);
      std::vector<RayHit> packet = tracer.traceClosest(rays, Traversal::kPacket);
      std::vector<std::uint8_t> singleBlocked = tracer.traceOccluded(rays, Traversal::kSingle);
      std::vector<std::uint8_t> packetBlocked = tracer.traceOccluded(rays, Traversal::kPacket);
      ASSERT_EQ(packet.size(), count);
      for (std::size_t i = 0; i < count; ++i) {
        EXPECT_TRUE(single[i].triangle == packet[i].triangle && sameBits(single[i].t, packet[i].t))
            << count << " rays, ray " << i << ": single " << single[i].triangle << ", packet " << packet[i].triangle;
        EXPECT_EQ(singleBlocked[i], packetBlocked[i]) << count << " rays, ray " << i;
        const Ray& r = rays[i];
        if (!std::isfinite(r.origin.x) || !std::isfinite(r.direction.y)) {
          EXPECT_EQ(packet[i].triangle, RayHit::kNoHit);
          EXPECT_EQ(packetBlocked[i], 1);
        }
      }
    }
    Scene empty;
    empty.materials.push_back(makeMaterial(glm::vec3(0.5f)));
    Tracer none(test::deviceContext(), empty, {}, width);
    std::vector<Ray> rays(fan.begin(), fan.begin() + 20);
    for (const RayHit& h : none.traceClosest(rays, Traversal::kPacket)) EXPECT_EQ(h.triangle, RayHit::kNoHit);
    // nothing blocks, but a ray that is not finite carries no light
    EXPECT_EQ(none.traceOccluded(rays, Traversal::kPacket), none.traceOccluded(rays, Traversal::kSingle));
  }
}

TEST(PacketTraversalEdges, MixedPacketsMatchSingleRays) {
  // Every packet holds a few rays of another axis permutation: both queries
  // trace the packet in two passes, each the lanes of one permutation. The
  // same answers as single rays.
  Scene scene = makeTriangleSoup(2000, 6, 0.15f);
  std::vector<Ray> fan = cameraFans(scene, 32, 9);
  for (int width : kPacketWidths) {
    SCOPED_TRACE("packets of " + std::to_string(width));
    std::vector<Ray> rays = fan;
    std::size_t mixed = 0, packets = 0;
    for (std::size_t i = 0; i + std::size_t(width) <= rays.size(); i += std::size_t(width), ++packets) {
      // lanes 3 and, in packets of 16, 11 aimed from their origin at the scene's
      // centre along another dominant axis
      for (std::size_t l : {std::size_t(3), std::size_t(11)}) {
        if (l >= std::size_t(width)) continue;
        Ray& r = rays[i + l];
        const glm::vec3 d = r.direction;
        r.origin = glm::vec3(0.5f) - 2.0f * glm::vec3(d.y, d.z, d.x);
        r.direction = glm::vec3(d.y, d.z, d.x);
      }
      bool same = true;
      for (std::size_t l = 1; l < std::size_t(width); ++l)
        same = same && permutation(rays[i + l].direction) == permutation(rays[i].direction);
      mixed += !same;
    }
    ASSERT_GT(mixed, packets * 9 / 10);
    Tracer tracer(test::deviceContext(), scene, {}, width);
    std::vector<RayHit> single = tracer.traceClosest(rays, Traversal::kSingle);
    std::vector<RayHit> packet = tracer.traceClosest(rays, Traversal::kPacket);
    std::vector<std::uint8_t> singleBlocked = tracer.traceOccluded(rays, Traversal::kSingle);
    std::vector<std::uint8_t> packetBlocked = tracer.traceOccluded(rays, Traversal::kPacket);
    int differ = 0, blocked = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      blocked += singleBlocked[i] != 0;
      if ((single[i].triangle != packet[i].triangle || !sameBits(single[i].t, packet[i].t) ||
           singleBlocked[i] != packetBlocked[i]) &&
          ++differ <= 5)
        ADD_FAILURE() << "ray " << i << ": single " << single[i].triangle << " blocked " << int(singleBlocked[i])
                      << ", packet " << packet[i].triangle << " blocked " << int(packetBlocked[i]);
    }
    EXPECT_EQ(differ, 0);
    EXPECT_GT(blocked, int(rays.size() / 10));
    EXPECT_LT(blocked, int(rays.size()));
  }
}

TEST(PacketTraversalEdges, LanesOfEveryAxisMatchSingleRays) {
  // Bounce-like rays: random origins in the soup, and lane l of every packet
  // dominant along axis l mod 3 with sign by (l / 3) mod 2, so each packet
  // holds all three dominant axes and both signs (each lane's own
  // permutation in one pass). Distance, barycentrics, triangle and
  // occlusion bit for bit as single rays', at both widths.
  Scene scene = makeTriangleSoup(2000, 11, 0.15f);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), side(-0.6f, 0.6f);
  for (int width : kPacketWidths) {
    std::vector<Ray> rays(std::size_t(test::testSize(8192, 1024)));
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const std::size_t l = i % std::size_t(width);
      glm::vec3 d(side(rng), side(rng), side(rng));
      d[int(l % 3)] = ((l / 3) % 2 ? -1.0f : 1.0f) * (0.7f + 0.3f * unit(rng));
      rays[i].origin = glm::vec3(unit(rng), unit(rng), unit(rng));
      rays[i].direction = d;
      if (i % 7 == 3) rays[i].tmax = 0.3f;  // segments that end short, as shadow rays do
    }
    ASSERT_EQ(packetShare(rays, std::size_t(width)), 0.0);
    expectPacketsMatchSingleRays(scene, rays, {}, width, false);
  }
}

TEST(PacketTraversalEdges, WidthByDevice) {
  // 16 lanes where the device's float vector is 16 wide, 8 elsewhere; an
  // explicit 8 or 16 wins; anything else is refused
  DeviceInfo device = test::deviceContext().info();
  device.nativeFloatWidth = 16;
  EXPECT_EQ(packetWidthFor(device), 16);
  EXPECT_EQ(packetWidthFor(device, 8), 8);
  device.nativeFloatWidth = 8;
  EXPECT_EQ(packetWidthFor(device), 8);
  device.nativeFloatWidth = 4;
  EXPECT_EQ(packetWidthFor(device), 8);
  EXPECT_EQ(packetWidthFor(device, 16), 16);
  EXPECT_THROW(packetWidthFor(device, 4), DeviceError);
  EXPECT_THROW(packetWidthFor(device, 32), DeviceError);
}

TEST(PacketTraversalEdges, WidthByTheDeviceAndTheSceneOnly) {
  // a 16-wide device gets packets of 8 on scenes of more than
  // kWidePacketMaxTriangles triangles, whatever the image size; an explicit
  // width and a narrower device are not affected; no triangle count, no rule
  DeviceInfo device = test::deviceContext().info();
  device.nativeFloatWidth = 16;
  EXPECT_EQ(packetWidthFor(device, 0, 1040409), 8);   // MetalRoughSpheresNoTextures
  EXPECT_EQ(packetWidthFor(device, 0, 15452), 16);    // DamagedHelmet
  EXPECT_EQ(packetWidthFor(device, 0, kWidePacketMaxTriangles), 16);
  EXPECT_EQ(packetWidthFor(device, 0, kWidePacketMaxTriangles + 1), 8);
  EXPECT_EQ(packetWidthFor(device, 0, 0), 16);
  EXPECT_EQ(packetWidthFor(device, 16, 1040409), 16);
  device.nativeFloatWidth = 8;
  EXPECT_EQ(packetWidthFor(device, 0, 1000), 8);
}



TEST(PacketCoherence, ParallelRandomOpposedAndDegenerateDirections) {
  // packets of parallel rays measure 1, and packets of four opposed pairs 0;
  // a camera fan is close to 1; uniform directions on the sphere measure
  // E|sum of 8 unit vectors| / 8, about sqrt(8 / (3 pi 8)) = 0.33 (the
  // length of a sum of random unit vectors is near Maxwell-distributed)
  EXPECT_EQ(packetCoherence({}), 0.0);
  std::vector<Ray> rays(64);
  for (Ray& r : rays) r.direction = glm::vec3(0.0f, 3.0f, 4.0f);
  EXPECT_NEAR(packetCoherence(rays), 1.0, 1e-12);
  for (std::size_t i = 0; i < rays.size(); ++i) rays[i].direction *= (i % 2) ? -1.0f : 2.0f;
  EXPECT_NEAR(packetCoherence(rays), 0.0, 1e-12);
  // zero, infinite and NaN directions have no say; a packet of none, none at all
  for (std::size_t i = 0; i < rays.size(); ++i)
    if (i % 2) rays[i].direction = i % 3 ? glm::vec3(0.0f) : glm::vec3(std::numeric_limits<float>::quiet_NaN());
  for (std::size_t i = 0; i < 8; ++i) rays[i].direction = glm::vec3(0.0f);
  EXPECT_NEAR(packetCoherence(rays), 1.0, 1e-12);

  Scene scene = makeTriangleSoup(10, 1, 0.2f);
  EXPECT_GT(packetCoherence(cameraFans(scene, 32, 1)), 0.99);

  std::mt19937 rng(7);
  std::normal_distribution<float> gauss;
  std::vector<Ray> random(80000);
  for (Ray& r : random) r.direction = glm::vec3(gauss(rng), gauss(rng), gauss(rng));
  // 10 000 packets: the mean's standard error is about 0.0015
  const double expected = std::sqrt(8.0 / (3.0 * M_PI * 8.0));
  EXPECT_NEAR(packetCoherence(random), expected, 0.02);
  // packets of 16: sqrt(8 / (3 pi 16)) = 0.23, 5 000 packets
  EXPECT_NEAR(packetCoherence(random, 16), std::sqrt(8.0 / (3.0 * M_PI * 16.0)), 0.02);
  EXPECT_GT(packetCoherence(cameraFans(scene, 32, 1), 16), 0.99);
}

}  // namespace
}  // namespace wt
