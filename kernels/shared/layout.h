// Every struct host and kernels share (kernels/shared/*.h), field by field,
// as an X-macro: S(type) opens a struct, F(type, field) names a field. The
// layout test (tests/contract/test_layout.cpp, kernels/layout_tests.cl)
// compares sizeof and offsetof of each on both compilers, and checks that
// this list names every field the headers declare.
#ifndef WT_SHARED_LAYOUT_H
#define WT_SHARED_LAYOUT_H

#include "shared/alpha.h"
#include "shared/environment.h"
#include "shared/lights.h"
#include "shared/media.h"
#include "shared/textures.h"
#include "shared/tonemap.h"
#include "shared/types.h"

#define WT_SHARED_LAYOUT(S, F) \
  S(WtAlphaMaterial) F(WtAlphaMaterial, mode) F(WtAlphaMaterial, cutoff) F(WtAlphaMaterial, factor) \
  F(WtAlphaMaterial, texture) \
  S(WtEnvironment) F(WtEnvironment, color) F(WtEnvironment, intensity) F(WtEnvironment, rotation) \
  F(WtEnvironment, cos_rotation) F(WtEnvironment, sin_rotation) F(WtEnvironment, mode) F(WtEnvironment, width) \
  F(WtEnvironment, height) F(WtEnvironment, pad0) \
  S(WtLight) F(WtLight, position) F(WtLight, direction) F(WtLight, intensity) F(WtLight, type) \
  F(WtLight, triangle) F(WtLight, cos_inner) F(WtLight, cos_outer) \
  S(WtAliasSlot) F(WtAliasSlot, threshold) F(WtAliasSlot, alias) F(WtAliasSlot, pmf) F(WtAliasSlot, pad0) \
  S(WtLightNode) F(WtLightNode, lo_x) F(WtLightNode, lo_y) F(WtLightNode, lo_z) F(WtLightNode, power) \
  F(WtLightNode, hi_x) F(WtLightNode, hi_y) F(WtLightNode, hi_z) F(WtLightNode, child) F(WtLightNode, axis_x) \
  F(WtLightNode, axis_y) F(WtLightNode, axis_z) F(WtLightNode, cos_theta_o) F(WtLightNode, leaf) \
  F(WtLightNode, parent) F(WtLightNode, sin_theta_o) F(WtLightNode, radius) \
  S(WtTexture) F(WtTexture, first_level) F(WtTexture, level_count) F(WtTexture, flags) F(WtTexture, pad) \
  S(WtTextureLevel) F(WtTextureLevel, offset) F(WtTextureLevel, width) F(WtTextureLevel, height) \
  F(WtTextureLevel, pad) \
  S(WtVec4) F(WtVec4, x) F(WtVec4, y) F(WtVec4, z) F(WtVec4, w) \
  S(WtTriangle) F(WtTriangle, v0) F(WtTriangle, v1) F(WtTriangle, v2) F(WtTriangle, material) \
  S(WtBvhNode) F(WtBvhNode, lo_x) F(WtBvhNode, lo_y) F(WtBvhNode, lo_z) F(WtBvhNode, first) F(WtBvhNode, hi_x) \
  F(WtBvhNode, hi_y) F(WtBvhNode, hi_z) F(WtBvhNode, count) \
  S(WtBvh4Node) F(WtBvh4Node, lo_x) F(WtBvh4Node, hi_x) F(WtBvh4Node, lo_y) F(WtBvh4Node, hi_y) \
  F(WtBvh4Node, lo_z) F(WtBvh4Node, hi_z) F(WtBvh4Node, child) F(WtBvh4Node, count) \
  S(WtBvh4Oriented) F(WtBvh4Oriented, rows) F(WtBvh4Oriented, origin) F(WtBvh4Oriented, step) F(WtBvh4Oriented, grid) \
  F(WtBvh4Oriented, child) F(WtBvh4Oriented, count) \
  S(WtGeometry) F(WtGeometry, node_count) F(WtGeometry, triangle_count) F(WtGeometry, leaf_joints) F(WtGeometry, pad1) \
  F(WtGeometry, data_first) F(WtGeometry, info_first) F(WtGeometry, emitter_first) \
  S(WtMaterial) F(WtMaterial, base_color) F(WtMaterial, emission) F(WtMaterial, roughness) F(WtMaterial, model) \
  F(WtMaterial, transmission) F(WtMaterial, ior) F(WtMaterial, volume) F(WtMaterial, alpha) \
  F(WtMaterial, alpha_mode) F(WtMaterial, alpha_cutoff) F(WtMaterial, texture_mask) F(WtMaterial, specular) \
  F(WtMaterial, sheen) F(WtMaterial, clearcoat) F(WtMaterial, clearcoat_roughness) F(WtMaterial, anisotropy) \
  F(WtMaterial, anisotropy_rotation) F(WtMaterial, iridescence) F(WtMaterial, priority) F(WtMaterial, dispersion) \
  F(WtMaterial, shadow_pass) F(WtMaterial, pad1) \
  S(WtMediaStack) F(WtMediaStack, id) \
  S(WtMediaCrossing) F(WtMediaCrossing, real) F(WtMediaCrossing, ior_near) F(WtMediaCrossing, ior_far) \
  F(WtMediaCrossing, near_id) F(WtMediaCrossing, far_id) \
  S(WtTextureRef) F(WtTextureRef, texture) F(WtTextureRef, texcoord) F(WtTextureRef, scale) F(WtTextureRef, pad) \
  F(WtTextureRef, transform_u) F(WtTextureRef, transform_v) \
  S(WtCamera) F(WtCamera, origin) F(WtCamera, right) F(WtCamera, up) F(WtCamera, forward) \
  S(WtFrameParams) F(WtFrameParams, width) F(WtFrameParams, height) F(WtFrameParams, sample) \
  F(WtFrameParams, bounce) F(WtFrameParams, max_bounces) F(WtFrameParams, seed) F(WtFrameParams, exposure) \
  F(WtFrameParams, max_diffuse_bounces) F(WtFrameParams, light_count) F(WtFrameParams, analytic_count) \
  F(WtFrameParams, flags) F(WtFrameParams, rr_min_depth) F(WtFrameParams, env_pmf) \
  F(WtFrameParams, accumulate_mode) F(WtFrameParams, max_specular_bounces) \
  F(WtFrameParams, max_transmission_bounces) \
  S(WtTonemapParams) F(WtTonemapParams, op) F(WtTonemapParams, flags) F(WtTonemapParams, white) \
  F(WtTonemapParams, pad0) F(WtTonemapParams, balance_r) F(WtTonemapParams, balance_g) F(WtTonemapParams, balance_b)

#endif  // WT_SHARED_LAYOUT_H
