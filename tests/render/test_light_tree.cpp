// The light tree (host/render/light_tree.cpp, kernels/lights/light_tree.cl):
// its build keeps the bounds, cones and powers of its nodes, its importance
// is zero only where no emitter below can send light, the device's picks
// follow the pmf it reports for MIS, and path tracing with it converges to
// what minimal and the power-only light choice converge to.
#include "device_fixture.h"
#include "render/light_tree.h"
#include "render/render_helpers.h"
#include "test_util.h"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace wt {
namespace {

/// Small triangles scattered over [-1,1]^3 facing every way, a few of them
/// two-sided, powers over three decades.
std::vector<LightTreeEmitter> randomEmitters(std::size_t count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), u01(0.0f, 1.0f);
  std::vector<LightTreeEmitter> out;
  for (std::size_t i = 0; i < count; ++i) {
    glm::vec3 c(u(rng), u(rng), u(rng));
    LightTreeEmitter e;
    e.p0 = c + 0.05f * glm::vec3(u(rng), u(rng), u(rng));
    e.p1 = c + 0.05f * glm::vec3(u(rng), u(rng), u(rng));
    e.p2 = c + 0.05f * glm::vec3(u(rng), u(rng), u(rng));
    e.power = std::pow(10.0, 3.0 * u01(rng));
    e.twoSided = i % 7 == 3;
    e.light = std::uint32_t(100 + i);
    out.push_back(e);
  }
  return out;
}

glm::dvec3 frontNormal(const LightTreeEmitter& e) {
  return glm::normalize(glm::cross(glm::dvec3(e.p1) - glm::dvec3(e.p0), glm::dvec3(e.p2) - glm::dvec3(e.p0)));
}

TEST(LightTree, BuildKeepsBoundsConesAndPower) {
  std::vector<LightTreeEmitter> emitters = randomEmitters(500, 3);
  LightTree tree = buildLightTree(emitters);
  ASSERT_EQ(tree.nodes.size(), 2 * emitters.size() - 1);
  double total = 0.0;
  for (const LightTreeEmitter& e : emitters) total += e.power;
  EXPECT_NEAR(tree.nodes[0].power, total, 1e-5 * total);
  EXPECT_EQ(tree.nodes[0].parent, WT_LIGHT_NODE_NONE);
  std::vector<int> seen(emitters.size(), 0);
  for (std::size_t i = 0; i < emitters.size(); ++i) {
    std::uint32_t leaf = tree.leafOfEmitter[i];
    ASSERT_LT(leaf, tree.nodes.size());
    EXPECT_EQ(tree.nodes[leaf].leaf, 1u);
    EXPECT_EQ(tree.nodes[leaf].child, emitters[i].light);
    ++seen[i];
    // every ancestor bounds the triangle and holds its normal in its cone
    glm::dvec3 n = frontNormal(emitters[i]);
    for (std::uint32_t k = leaf; k != WT_LIGHT_NODE_NONE; k = tree.nodes[k].parent) {
      const WtLightNode& node = tree.nodes[k];
      for (glm::vec3 p : {emitters[i].p0, emitters[i].p1, emitters[i].p2}) {
        EXPECT_TRUE(p.x >= node.lo_x && p.y >= node.lo_y && p.z >= node.lo_z && p.x <= node.hi_x &&
                    p.y <= node.hi_y && p.z <= node.hi_z) << "node " << k;
      }
      if (node.cos_theta_o > -1.0f) {
        EXPECT_FALSE(emitters[i].twoSided) << "a two-sided emitter needs a cone of every direction, node " << k;
        glm::dvec3 axis(node.axis_x, node.axis_y, node.axis_z);
        EXPECT_GE(glm::dot(axis, n), double(node.cos_theta_o) - 1e-6) << "node " << k;
      }
    }
  }
  for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
    const WtLightNode& node = tree.nodes[k];
    if (node.leaf) continue;
    EXPECT_EQ(tree.nodes[node.child].parent, k);
    EXPECT_EQ(tree.nodes[node.child + 1].parent, k);
    double sum = double(tree.nodes[node.child].power) + tree.nodes[node.child + 1].power;
    EXPECT_NEAR(node.power, sum, 1e-5 * sum);
  }
}

// The importance bounds what a node's emitters can send: zero means no point
// of any emitter below lies on the receiver's side of its plane facing it.
TEST(LightTree, ImportanceIsZeroOnlyWhereNoEmitterCanReach) {
  std::vector<LightTreeEmitter> emitters = randomEmitters(200, 5);
  LightTree tree = buildLightTree(emitters);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.5f, 1.5f), u01(0.0f, 1.0f);
  int zeros = 0;
  for (int trial = 0; trial < 300; ++trial) {
    glm::vec3 p(u(rng), u(rng), u(rng));
    glm::vec3 n = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
    for (std::size_t i = 0; i < emitters.size(); ++i) {
      const WtLightNode& leaf = tree.nodes[tree.leafOfEmitter[i]];
      if (light_tree_importance(&leaf, p.x, p.y, p.z, n.x, n.y, n.z) > 0.0f) continue;
      ++zeros;
      glm::dvec3 ne = frontNormal(emitters[i]);
      for (int k = 0; k < 64; ++k) {
        float a = std::sqrt(u01(rng)), b = u01(rng);
        glm::dvec3 q = glm::dvec3((1.0f - a) * emitters[i].p0 + a * (1.0f - b) * emitters[i].p1 + a * b * emitters[i].p2);
        glm::dvec3 toQ = q - glm::dvec3(p);
        bool receiverSees = glm::dot(glm::dvec3(n), toQ) > 0.0;
        bool emitterFaces = emitters[i].twoSided || glm::dot(ne, -toQ) > 0.0;
        ASSERT_FALSE(receiverSees && emitterFaces) << "trial " << trial << ", emitter " << i;
      }
    }
  }
  EXPECT_GT(zeros, 1000) << "the test must see zero importances to check them";
}

/// The importance's bound in double from the node's bounds, cone axis and
/// cone cosine alone (the definition, before the node stored its sphere's
/// radius and its cone's sine).
double importanceInDouble(const WtLightNode& node, glm::dvec3 p, glm::dvec3 n) {
  const glm::dvec3 lo(node.lo_x, node.lo_y, node.lo_z), hi(node.hi_x, node.hi_y, node.hi_z);
  const double r2 = 0.25 * glm::dot(hi - lo, hi - lo);
  const glm::dvec3 t = 0.5 * (lo + hi) - p;
  const double d2 = glm::dot(t, t);
  if (d2 <= r2) return node.power / std::max(r2, 1e-30);
  const glm::dvec3 w = t / std::sqrt(d2);
  const double theta_u = std::asin(std::sqrt(r2 / d2));
  auto cosMinus = [](double a, double b) { return std::cos(std::max(0.0, a - b)); };
  const double cos_i = n == glm::dvec3(0.0) ? 1.0 : cosMinus(std::acos(std::clamp(glm::dot(n, w), -1.0, 1.0)), theta_u);
  if (!(cos_i > 0.0)) return 0.0;
  double cos_e = 1.0;
  const double theta_o = std::acos(double(node.cos_theta_o));
  if (theta_o + theta_u < std::numbers::pi) {
    const double theta = std::acos(std::clamp(-glm::dot(glm::dvec3(node.axis_x, node.axis_y, node.axis_z), w), -1.0, 1.0));
    cos_e = cosMinus(theta, theta_o + theta_u);
    if (!(cos_e > 0.0)) return 0.0;
  }
  return node.power * cos_i * cos_e / d2;
}

// The float importance, from the radius and cone sine the build stores,
// is its bound computed from the definition in double: over every node of
// a tree at points near and far, up to float rounding where it is not zero
// (the angles' cosines near 0 cancel, so the tolerance is on the bound's
// scale, power / d^2); a wrong stored radius or sine moves it by far more.
TEST(LightTree, ImportanceMatchesItsDefinitionInDouble) {
  std::vector<LightTreeEmitter> emitters = randomEmitters(300, 11);
  LightTree tree = buildLightTree(emitters);
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), logd(-1.0f, 1.0f);
  int compared = 0, inside = 0;
  for (int trial = 0; trial < 400; ++trial) {
    glm::vec3 p = std::pow(10.0f, logd(rng)) * glm::vec3(u(rng), u(rng), u(rng));
    glm::vec3 n = trial % 5 == 0 ? glm::vec3(0.0f) : glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
    for (const WtLightNode& node : tree.nodes) {
      const float got = light_tree_importance(&node, p.x, p.y, p.z, n.x, n.y, n.z);
      const double want = importanceInDouble(node, glm::dvec3(p), glm::dvec3(n));
      const glm::dvec3 c = 0.5 * (glm::dvec3(node.lo_x, node.lo_y, node.lo_z) + glm::dvec3(node.hi_x, node.hi_y, node.hi_z));
      const double scale = node.power / glm::dot(c - glm::dvec3(p), c - glm::dvec3(p));
      ASSERT_NEAR(got, want, 1e-4 * want + 2e-3 * scale)
          << "trial " << trial << ", bound scale " << scale;
      ++compared;
      inside += want > 0.0 && want < scale;
    }
  }
  EXPECT_GT(inside, compared / 10) << "the cosines must bound some nodes below their scale";
}

// The device takes both children's importance in one go (two lanes, the
// early returns as selects): each lane is the shared scalar importance
// above, on every pair of siblings of a tree at points near and far, with
// and without a receiver normal, up to float rounding.
TEST(LightTree, DeviceImportanceOfSiblingsIsTheScalarOne) {
  std::vector<LightTreeEmitter> emitters = randomEmitters(120, 17);
  LightTree tree = buildLightTree(emitters);
  std::vector<cl_uint> first;
  for (const WtLightNode& node : tree.nodes)
    if (!node.leaf) first.push_back(node.child);
  std::mt19937 rng(19);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), logd(-1.0f, 1.0f);
  std::vector<cl_uint> pairs;
  std::vector<cl_float4> ps, ns;
  for (int trial = 0; trial < 60; ++trial) {
    glm::vec3 p = std::pow(10.0f, logd(rng)) * glm::vec3(u(rng), u(rng), u(rng));
    glm::vec3 n = trial % 4 == 0 ? glm::vec3(0.0f) : glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
    for (cl_uint c : first) {
      pairs.push_back(c);
      ps.push_back({{p.x, p.y, p.z, 0.0f}});
      ns.push_back({{n.x, n.y, n.z, 0.0f}});
    }
  }
  Context& ctx = test::deviceContext();
  const cl_uint count = cl_uint(pairs.size());
  cl::Buffer nodes(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, tree.nodes.size() * sizeof(WtLightNode),
                   tree.nodes.data());
  cl::Buffer pairBuffer(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, count * 4, pairs.data());
  cl::Buffer pBuffer(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, count * sizeof(cl_float4), ps.data());
  cl::Buffer nBuffer(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, count * sizeof(cl_float4), ns.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, count * sizeof(cl_float2));
  cl::Kernel k(test::unitTestProgram(), "test_light_tree_importance2");
  k.setArg(0, count), k.setArg(1, nodes), k.setArg(2, pairBuffer), k.setArg(3, pBuffer), k.setArg(4, nBuffer),
      k.setArg(5, out);
  ctx.launch("test_light_tree_importance2", k, count);
  std::vector<cl_float2> got(count);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, count * sizeof(cl_float2), got.data());
  int zeros = 0, nonzero = 0;
  for (cl_uint i = 0; i < count; ++i)
    for (cl_uint lane = 0; lane < 2; ++lane) {
      const WtLightNode& node = tree.nodes[pairs[i] + lane];
      const cl_float4& p = ps[i];
      const cl_float4& n = ns[i];
      const float want = light_tree_importance(&node, p.s[0], p.s[1], p.s[2], n.s[0], n.s[1], n.s[2]);
      const glm::dvec3 c = 0.5 * (glm::dvec3(node.lo_x, node.lo_y, node.lo_z) + glm::dvec3(node.hi_x, node.hi_y, node.hi_z));
      const glm::dvec3 t = c - glm::dvec3(p.s[0], p.s[1], p.s[2]);
      const double scale = node.power / glm::dot(t, t);
      ASSERT_NEAR(got[i].s[lane], want, 1e-5 * want + 1e-5 * scale) << "pair " << i << ", lane " << lane;
      (want > 0.0f ? nonzero : zeros)++;
    }
  EXPECT_GT(zeros, int(count) / 20) << "the test must see zero importances";
  EXPECT_GT(nonzero, int(count) / 2);
}

TEST(LightTree, DevicePicksFollowThePmfItReports) {
  std::vector<LightTreeEmitter> emitters = randomEmitters(40, 9);
  LightTree tree = buildLightTree(emitters);
  Context& ctx = test::deviceContext();
  cl::Buffer nodes(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, tree.nodes.size() * sizeof(WtLightNode),
                   tree.nodes.data());
  std::vector<cl_uint> leaves(tree.leafOfEmitter.begin(), tree.leafOfEmitter.end());
  cl::Buffer leafBuffer(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, leaves.size() * 4, leaves.data());
  const cl_uint n = test::testSize(1u << 18, 1u << 12);
  std::vector<float> us(n);
  for (cl_uint i = 0; i < n; ++i) us[i] = (float(i) + 0.5f) / float(n);  // stratified: the histogram converges fast
  cl::Buffer ub(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * 4, us.data());
  cl::Buffer chosen(ctx.context(), CL_MEM_WRITE_ONLY, n * 4), pickPmf(ctx.context(), CL_MEM_WRITE_ONLY, n * 4);
  cl::Buffer leafPmf(ctx.context(), CL_MEM_WRITE_ONLY, leaves.size() * 4);
  for (auto [p, nrm] : {std::pair{glm::vec3(0.0f), glm::vec3(0, 1, 0)}, std::pair{glm::vec3(0.7f, -1.2f, 0.3f), glm::normalize(glm::vec3(0.2f, 1, -0.3f))},
                        std::pair{glm::vec3(3.0f, 0.5f, -2.0f), glm::normalize(glm::vec3(-1, 0.1f, 0.5f))}}) {
    cl_float4 pc{{p.x, p.y, p.z, 0}}, nc{{nrm.x, nrm.y, nrm.z, 0}};
    cl::Kernel pick(test::unitTestProgram(), "test_light_tree_pick");
    pick.setArg(0, n), pick.setArg(1, nodes), pick.setArg(2, pc), pick.setArg(3, nc), pick.setArg(4, ub),
        pick.setArg(5, chosen), pick.setArg(6, pickPmf);
    ctx.launch("test_light_tree_pick", pick, n);
    cl::Kernel pmf(test::unitTestProgram(), "test_light_tree_pmf");
    cl_uint count = cl_uint(leaves.size());
    pmf.setArg(0, count), pmf.setArg(1, nodes), pmf.setArg(2, leafBuffer), pmf.setArg(3, pc), pmf.setArg(4, nc),
        pmf.setArg(5, leafPmf);
    ctx.launch("test_light_tree_pmf", pmf, count);
    std::vector<cl_uint> got(n);
    std::vector<float> gotPmf(n), expected(leaves.size());
    ctx.queue().enqueueReadBuffer(chosen, CL_TRUE, 0, n * 4, got.data());
    ctx.queue().enqueueReadBuffer(pickPmf, CL_TRUE, 0, n * 4, gotPmf.data());
    ctx.queue().enqueueReadBuffer(leafPmf, CL_TRUE, 0, leaves.size() * 4, expected.data());
    // A descent can end where both children's importance is 0 although their
    // parent's was not (its bound was looser): that probability is lost, a
    // pick that returns nothing. The pmf over the emitters sums to the rest.
    double sum = 0.0;
    for (float e : expected) sum += e;
    EXPECT_LE(sum, 1.0 + 1e-5);
    EXPECT_GT(sum, 0.5);
    std::vector<double> histogram(leaves.size() + 1, 0.0);
    expected.push_back(float(std::max(0.0, 1.0 - sum)));  // the last bin: picks that found nothing
    for (cl_uint i = 0; i < n; ++i) {
      if (got[i] == 0xffffffffu) {
        EXPECT_EQ(gotPmf[i], 0.0f);
        histogram.back() += 1.0;
        continue;
      }
      std::uint32_t emitter = got[i] - 100;  // light indices were 100 + i
      ASSERT_LT(emitter, leaves.size());
      histogram[emitter] += 1.0;
      ASSERT_NEAR(gotPmf[i], expected[emitter], 1e-5 * expected[emitter]) << "the pick's pmf is the one MIS computes";
    }
    double chi2 = 0.0;
    int dof = -1;
    for (std::size_t e = 0; e < expected.size(); ++e) {
      double want = expected[e] * n;
      if (want < 5.0) {
        EXPECT_LE(histogram[e], want + 6.0 * std::sqrt(want + 1.0));
        continue;
      }
      chi2 += (histogram[e] - want) * (histogram[e] - want) / want;
      ++dof;
    }
    EXPECT_LT(chi2, dof + 4.5 * std::sqrt(2.0 * dof)) << "chi2 " << chi2 << " over " << dof << " dof";
  }
}

// 72 small emitters of different colours and powers over a floor, with a
// glossy sphere: path with the tree, path choosing by power alone, and
// minimal (which finds emitters by BSDF sampling only) agree.
TEST(LightTree, PathWithTheTreeMatchesPowerSamplingAndMinimal) {
  Scene scene = test::makeFloor(3.0f, 0.0f, makePbrMaterial(glm::vec3(0.6f), 0.0f, 0.6f));
  appendScene(scene, makeIcosphere(2, glm::vec3(0.0f, 0.5f, 0.0f), 0.5f, makePbrMaterial(glm::vec3(0.9f, 0.7f, 0.4f), 1.0f, 0.4f)));
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  for (int i = 0; i < 72; ++i) {
    glm::vec3 colour(u01(rng), u01(rng), u01(rng));
    float radiance = 2.0f * std::pow(10.0f, 1.5f * u01(rng));
    Scene quad = test::makeFloor(0.1f, 0.0f, makeMaterial(glm::vec3(0.0f), radiance * colour, i % 5 == 0), /*faceDown=*/true);
    glm::vec3 at(2.6f * (u01(rng) - 0.5f) * 2.0f, 0.4f + 1.4f * u01(rng), 2.6f * (u01(rng) - 0.5f) * 2.0f);
    for (WtVec4& p : quad.positions) p.x += at.x, p.y += at.y, p.z += at.z;
    appendScene(scene, quad);
  }
  CameraDesc cam;
  cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 2.5f, 4.0f), glm::vec3(0.0f, 0.3f, 0.0f), glm::vec3(0, 1, 0)));
  scene.camera = cam;
  RenderSettings s;
  s.width = s.height = 16;
  s.seed = 5;
  s.maxBounces = 2;
  s.integrator = Integrator::Minimal;
  Image reference = test::render(scene, s, 4096);
  s.integrator = Integrator::Path;
  s.lightSampler = LightSampler::Tree;
  Image tree = test::render(scene, s, 512);
  s.lightSampler = LightSampler::Power;
  s.seed = 6;
  Image power = test::render(scene, s, 512);
  test::expectSameImage(reference, tree, 4, 5.0, "tree vs minimal");
  test::expectSameImage(power, tree, 4, 5.0, "tree vs power");
  // power: a 5% bias over the image would be many standard errors
  for (const Image* i : {&reference, &tree}) {
    test::BlockStat all = test::blockStat(*i, 0, 0, i->width, i->height, 1);
    EXPECT_LT(std::sqrt(all.varianceOfMean), 0.01 * all.mean);
  }
}

}  // namespace
}  // namespace wt
