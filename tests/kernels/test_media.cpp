// The nested-dielectric stack (kernels/shared/media.h) run on the device:
// walks through glasses of water, ice in water, overlapping volumes, a
// volume the path never entered and a full stack, step by step against what
// the priority rule says; random walks against the host build bit for bit.
#include "device_fixture.h"
#include "scene/generators.h"
#include "shared/media.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <random>
#include <vector>

namespace wt {
namespace {

constexpr cl_uint kNone = WT_MEDIUM_NONE;

/// A closed transmitting volume of index `ior` and `priority`.
WtMaterial medium(float ior, std::uint32_t priority) {
  return withPriority(withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.0f), 1.0f, ior), priority);
}

enum : cl_uint { G, W, I, A, B, P5, P4, P3, P2, P1, Q3, kMaterials };

std::vector<WtMaterial> materials() {
  std::vector<WtMaterial> m(kMaterials);
  m[G] = medium(1.5f, 2);    // a glass
  m[W] = medium(1.33f, 1);   // the water in it, overlapping its wall
  m[I] = medium(1.31f, 1);   // ice in the water: equal priority
  m[A] = medium(1.5f, 0);    // two overlapping volumes of equal priority
  m[B] = medium(1.4f, 0);
  m[P5] = medium(1.1f, 5);   // five nested volumes, more than the stack holds
  m[P4] = medium(1.2f, 4);
  m[P3] = medium(1.3f, 3);
  m[P2] = medium(1.4f, 2);
  m[P1] = medium(1.45f, 1);
  m[Q3] = medium(1.6f, 3);
  return m;
}

struct Step {
  cl_uint material;
  bool entering;
  bool real;                   ///< expected: an interface (else a false hit)
  float nearIor, farIor;       ///< expected where real
  cl_uint current;             ///< expected current medium after the step
  std::vector<cl_uint> stack;  ///< expected entries after the step, oldest first
};

struct StepResult {
  cl_float4 crossing;
  cl_uint4 stack;
};

/// Walks run on the device: walk w's steps are `steps[w]`, all of one length.
std::vector<std::vector<StepResult>> runWalks(const std::vector<WtMaterial>& mats,
                                              const std::vector<std::vector<cl_uint2>>& steps) {
  Context& ctx = test::deviceContext();
  const cl_uint count = cl_uint(steps.size()), length = cl_uint(steps[0].size());
  std::vector<cl_uint2> flat;
  for (const auto& walk : steps) flat.insert(flat.end(), walk.begin(), walk.end());
  cl::Buffer m(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, mats.size() * sizeof(WtMaterial),
               const_cast<WtMaterial*>(mats.data()));
  cl::Buffer in(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, flat.size() * sizeof(cl_uint2), flat.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, flat.size() * sizeof(cl_float4));
  cl::Buffer stacks(ctx.context(), CL_MEM_WRITE_ONLY, flat.size() * sizeof(cl_uint4));
  cl::Kernel k(test::unitTestProgram(), "test_media_walk");
  k.setArg(0, count), k.setArg(1, length), k.setArg(2, m), k.setArg(3, in), k.setArg(4, out), k.setArg(5, stacks);
  ctx.launch("test_media_walk", k, count);
  std::vector<cl_float4> crossings(flat.size());
  std::vector<cl_uint4> after(flat.size());
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, crossings.size() * sizeof(cl_float4), crossings.data());
  ctx.queue().enqueueReadBuffer(stacks, CL_TRUE, 0, after.size() * sizeof(cl_uint4), after.data());
  std::vector<std::vector<StepResult>> result(count);
  for (cl_uint w = 0; w < count; ++w)
    for (cl_uint j = 0; j < length; ++j) result[w].push_back({crossings[w * length + j], after[w * length + j]});
  return result;
}

cl_uint bits(float f) {
  cl_uint u;
  std::memcpy(&u, &f, 4);
  return u;
}

void expectWalk(const char* what, const std::vector<Step>& walk) {
  const std::vector<WtMaterial> mats = materials();
  std::vector<cl_uint2> steps;
  for (const Step& s : walk) steps.push_back({{s.material, s.entering ? 1u : 0u}});
  const std::vector<StepResult> got = runWalks(mats, {steps})[0];
  for (std::size_t j = 0; j < walk.size(); ++j) {
    const Step& s = walk[j];
    const StepResult& r = got[j];
    SCOPED_TRACE(std::string(what) + ", step " + std::to_string(j));
    EXPECT_EQ(bits(r.crossing.s[0]), s.real ? 1u : 0u) << "real interface";
    if (s.real) {
      EXPECT_EQ(r.crossing.s[1], s.nearIor);
      EXPECT_EQ(r.crossing.s[2], s.farIor);
    }
    EXPECT_EQ(bits(r.crossing.s[3]), s.current) << "current medium";
    for (std::size_t k = 0; k < WT_MEDIA_STACK; ++k)
      EXPECT_EQ(r.stack.s[k], k < s.stack.size() ? s.stack[k] : kNone) << "stack entry " << k;
  }
}

TEST(Media, GlassOfWaterWhoseWaterOverlapsTheWall) {
  // the water's surface inside the glass wall is no interface; the wall's inner face is glass to water
  expectWalk("glass of water", {{G, true, true, 1.0f, 1.5f, G, {G}},
                                {W, true, false, 0, 0, G, {G, W}},
                                {G, false, true, 1.5f, 1.33f, W, {W}},
                                {W, false, true, 1.33f, 1.0f, kNone, {}}});
  // and back up: water, into the wall from below, out through the water's surface in it, out of the glass
  expectWalk("glass of water, upwards", {{W, true, true, 1.0f, 1.33f, W, {W}},
                                         {G, true, true, 1.33f, 1.5f, G, {W, G}},
                                         {W, false, false, 0, 0, G, {G}},
                                         {G, false, true, 1.5f, 1.0f, kNone, {}}});
}

TEST(Media, EqualPrioritiesMakeEveryBoundaryAnInterface) {
  expectWalk("ice in water", {{W, true, true, 1.0f, 1.33f, W, {W}},
                              {I, true, true, 1.33f, 1.31f, I, {W, I}},
                              {I, false, true, 1.31f, 1.33f, W, {W}},
                              {W, false, true, 1.33f, 1.0f, kNone, {}}});
  // the overlap belongs to the volume entered last; the other's surface in it is passed
  expectWalk("overlapping volumes", {{A, true, true, 1.0f, 1.5f, A, {A}},
                                     {B, true, true, 1.5f, 1.4f, B, {A, B}},
                                     {A, false, false, 0, 0, B, {B}},
                                     {B, false, true, 1.4f, 1.0f, kNone, {}}});
}

TEST(Media, LeavingAVolumeNeverEnteredIsAnInterfaceIntoTheCurrentMedium) {
  expectWalk("camera inside", {{G, false, true, 1.5f, 1.0f, kNone, {}},
                               {A, true, true, 1.0f, 1.5f, A, {A}},
                               {W, false, true, 1.33f, 1.5f, A, {A}},
                               {A, false, true, 1.5f, 1.0f, kNone, {}}});
}

TEST(Media, AFullStackForgetsItsLowestPriority) {
  expectWalk("five nested volumes", {{P5, true, true, 1.0f, 1.1f, P5, {P5}},
                                     {P4, true, false, 0, 0, P5, {P5, P4}},
                                     {P3, true, false, 0, 0, P5, {P5, P4, P3}},
                                     {P2, true, false, 0, 0, P5, {P5, P4, P3, P2}},
                                     {P1, true, false, 0, 0, P5, {P5, P4, P3, P2}},  // the lowest: not taken
                                     {Q3, true, false, 0, 0, P5, {P5, P4, P3, Q3}},  // P2 forgotten
                                     {P1, false, false, 0, 0, P5, {P5, P4, P3, Q3}},  // outranked: still false
                                     {P2, false, false, 0, 0, P5, {P5, P4, P3, Q3}},
                                     {Q3, false, false, 0, 0, P5, {P5, P4, P3}},
                                     {P5, false, true, 1.1f, 1.2f, P4, {P4, P3}}});
}

TEST(Media, RandomWalksMatchTheHostBuildBitForBit) {
  const std::vector<WtMaterial> mats = materials();
  const cl_uint walks = 512, length = 24;
  std::mt19937 rng(31);
  std::vector<std::vector<cl_uint2>> steps(walks);
  for (auto& walk : steps)
    for (cl_uint j = 0; j < length; ++j) walk.push_back({{cl_uint(rng() % kMaterials), cl_uint(rng() % 2)}});
  const auto got = runWalks(mats, steps);
  int falseHits = 0, overflows = 0;
  for (cl_uint w = 0; w < walks; ++w) {
    WtMediaStack s{{kNone, kNone, kNone, kNone}};
    for (cl_uint j = 0; j < length; ++j) {
      const cl_uint2 step = steps[w][j];
      if (step.s[1] && s.id[WT_MEDIA_STACK - 1] != kNone) ++overflows;
      const WtMediaCrossing c = media_crossing(&s, mats.data(), step.s[0], int(step.s[1]));
      media_cross(&s, mats.data(), step.s[0], int(step.s[1]));
      const int current = media_current(&s, mats.data());
      const StepResult& r = got[w][j];
      ASSERT_EQ(bits(r.crossing.s[0]), c.real) << "walk " << w << " step " << j;
      ASSERT_EQ(bits(r.crossing.s[1]), bits(c.ior_near)) << "walk " << w << " step " << j;
      ASSERT_EQ(bits(r.crossing.s[2]), bits(c.ior_far)) << "walk " << w << " step " << j;
      ASSERT_EQ(bits(r.crossing.s[3]), current < 0 ? kNone : s.id[current]) << "walk " << w << " step " << j;
      for (int k = 0; k < WT_MEDIA_STACK; ++k) ASSERT_EQ(r.stack.s[k], s.id[k]) << "walk " << w << " step " << j;
      falseHits += c.real ? 0 : 1;
    }
  }
  // the walks reach the cases that matter
  EXPECT_GT(falseHits, 100);
  EXPECT_GT(overflows, 100);
}

// The dispersive index per channel: the Cauchy fit at the C, d and F lines
// (in double, from the extension's formula), the host build's bits, and the
// index itself, bit for bit, at dispersion 0 in every channel.
TEST(Media, ChannelIndicesFollowTheAbbeNumber) {
  Context& ctx = test::deviceContext();
  std::vector<cl_float2> pairs;
  for (float ior : {1.0f, 1.1f, 1.33f, 1.5f, 2.4f, 9.0f})
    for (float dispersion : {0.0f, 0.33f, 1.0f, 2.04f, 20.0f}) pairs.push_back({{ior, dispersion}});
  const cl_uint n = cl_uint(pairs.size());
  cl::Buffer in(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(cl_float2), pairs.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, 3 * n * sizeof(float));
  cl::Kernel k(test::unitTestProgram(), "test_media_channel_ior");
  k.setArg(0, n), k.setArg(1, in), k.setArg(2, out);
  ctx.launch("test_media_channel_ior", k, n);
  std::vector<float> got(3 * n);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, got.size() * sizeof(float), got.data());
  const double lambda[3] = {656.3, 587.6, 486.1};
  for (cl_uint i = 0; i < n; ++i) {
    const float ior = pairs[i].s[0], dispersion = pairs[i].s[1];
    for (cl_uint c = 0; c < 3; ++c) {
      SCOPED_TRACE("ior " + std::to_string(ior) + ", dispersion " + std::to_string(dispersion) + ", channel " +
                   std::to_string(c));
      const float value = got[3 * i + c];
      EXPECT_EQ(bits(value), bits(media_channel_ior(ior, dispersion, c)));
      if (dispersion == 0.0f) {
        EXPECT_EQ(bits(value), bits(ior));
        continue;
      }
      const double vd = 20.0 / dispersion;
      const double cauchy = std::max(ior + (ior - 1.0) / vd * (523655.0 / (lambda[c] * lambda[c]) - 1.5168), 1.0);
      EXPECT_NEAR(value, cauchy, 2e-4 * (ior - 1.0) * dispersion + 2e-6 * ior);
    }
    // n_F - n_C = (n_d - 1) / V_d: the Abbe number's definition
    if (dispersion > 0.0f && got[3 * i] > 1.0f) {
      EXPECT_NEAR(got[3 * i + 2] - got[3 * i], (ior - 1.0) * dispersion / 20.0,
                  5e-4 * (ior - 1.0) * dispersion / 20.0 + 1e-5 * ior);
    }
  }
}

}  // namespace
}  // namespace wt
