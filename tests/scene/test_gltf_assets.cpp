// The glTF loader on Khronos sample models (../shared/assets/gltf). The
// expected numbers were computed from the models' own JSON and .bin files
// with python3 (json + struct), as each comment says; they are not whatever
// the loader produced.
#include "scene/gltf_loader.h"

#include "test_util.h"

#include <gtest/gtest.h>

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace wt {
namespace {

/// World position of vertex v (the loader stores positions relative to Scene::origin).
glm::vec3 pos(const Scene& s, std::uint32_t v) {
  return glm::vec3(s.origin + glm::dvec3(s.positions[v].x, s.positions[v].y, s.positions[v].z));
}
/// World position of the camera.
glm::vec3 cameraPosition(const Scene& s) { return glm::vec3(s.origin + glm::dvec3(s.camera->cameraToWorld[3])); }
glm::vec3 nrm(const Scene& s, std::uint32_t v) {
  return {s.normals[v].x, s.normals[v].y, s.normals[v].z};
}

void expectNear(const glm::vec3& actual, const glm::vec3& expected, float eps = 1e-5f) {
  EXPECT_NEAR(actual.x, expected.x, eps);
  EXPECT_NEAR(actual.y, expected.y, eps);
  EXPECT_NEAR(actual.z, expected.z, eps);
}

bool hasWarning(const Scene& s, const std::string& part) {
  return std::any_of(s.warnings.begin(), s.warnings.end(),
                     [&](const std::string& w) { return w.find(part) != std::string::npos; });
}

void expectConsistent(const Scene& s) {
  ASSERT_EQ(s.normals.size(), s.positions.size());
  ASSERT_EQ(s.texcoords.size(), s.positions.size());
  ASSERT_FALSE(s.materials.empty());
  ASSERT_EQ(s.materialNames.size(), s.materials.size());
  for (const WtTriangle& t : s.triangles) {
    ASSERT_LT(std::max({t.v0, t.v1, t.v2}), s.positions.size());
    ASSERT_LT(t.material, s.materials.size());
  }
}

/// Of the triangles with vertex normals and non-zero area, the fraction whose
/// winding (counter-clockwise = front) agrees with their vertex normals. A
/// mirrored node without the winding flip, or normals transformed by the
/// matrix instead of its inverse transpose, pulls this down.
double fractionFacingTheirNormals(const Scene& s) {
  std::size_t counted = 0, agreeing = 0;
  for (const WtTriangle& t : s.triangles) {
    glm::vec3 n = nrm(s, t.v0) + nrm(s, t.v1) + nrm(s, t.v2);
    glm::vec3 g = glm::cross(pos(s, t.v1) - pos(s, t.v0), pos(s, t.v2) - pos(s, t.v0));
    if (glm::length(n) < 1e-3f || glm::length(g) < 1e-12f) continue;
    ++counted;
    if (glm::dot(n, g) > 0.0f) ++agreeing;
  }
  return counted == 0 ? 0.0 : double(agreeing) / double(counted);
}

TEST(GltfAssets, Triangle) {
  WT_REQUIRE_ASSET(path, "gltf/Triangle/glTF/Triangle.gltf");
  Scene s = loadGltf(path.string());
  expectConsistent(s);
  // Triangle.gltf: indices accessor count 3, data URI buffer
  ASSERT_EQ(s.triangles.size(), 1u);
  expectNear(pos(s, s.triangles[0].v1), {1, 0, 0});
  expectNear(pos(s, s.triangles[0].v2), {0, 1, 0});
  EXPECT_EQ(s.materialNames, std::vector<std::string>{"default"});
}

TEST(GltfAssets, TriangleWithoutIndices) {
  WT_REQUIRE_ASSET(path, "gltf/TriangleWithoutIndices/glTF/TriangleWithoutIndices.gltf");
  Scene s = loadGltf(path.string());
  expectConsistent(s);
  // POSITION accessor count 3, no indices
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_GT(glm::cross(pos(s, 1) - pos(s, 0), pos(s, 2) - pos(s, 0)).z, 0.0f);
}

TEST(GltfAssets, SimpleSparseAccessor) {
  WT_REQUIRE_ASSET(path, "gltf/SimpleSparseAccessor/glTF/SimpleSparseAccessor.gltf");
  Scene s = loadGltf(path.string());
  expectConsistent(s);
  // indices accessor count 36 -> 12 triangles over 14 vertices
  ASSERT_EQ(s.triangles.size(), 12u);
  ASSERT_EQ(s.positions.size(), 14u);
  // SimpleSparseAccessor.bin: the base grid has vertex i at (i % 7, i / 7, 0);
  // the sparse indices (UNSIGNED_SHORT at byte 240) are 8, 10, 12 and the
  // values (FLOAT VEC3 at byte 248) move them to (1,2,0), (3,3,0), (5,4,0).
  // One node, one primitive: scene vertex i is accessor element i.
  expectNear(pos(s, 8), {1, 2, 0});
  expectNear(pos(s, 10), {3, 3, 0});
  expectNear(pos(s, 12), {5, 4, 0});
  expectNear(pos(s, 9), {2, 1, 0});  // not in the sparse set
  expectNear(pos(s, 7), {0, 1, 0});
  // the accessor's max [6, 4, 0] holds only with the sparse values applied
  EXPECT_FLOAT_EQ(float(s.bounds().hi.y + s.origin.y), 4.0f);
}

TEST(GltfAssets, MultipleScenes) {
  WT_REQUIRE_ASSET(path, "gltf/MultipleScenes/glTF/MultipleScenes.gltf");
  // "scene": 1 is the default; scene 0 holds node 0 (mesh 0: 3 indices),
  // scene 1 holds node 1 (mesh 1: 6 indices)
  Scene byDefault = loadGltf(path.string());
  EXPECT_EQ(byDefault.triangles.size(), 2u);
  GltfLoadOptions options;
  options.sceneIndex = 0;
  EXPECT_EQ(loadGltf(path.string(), options).triangles.size(), 1u);
  options.sceneIndex = 1;
  EXPECT_EQ(loadGltf(path.string(), options).triangles.size(), 2u);
  options.sceneIndex = 2;
  try {
    loadGltf(path.string(), options);
    ADD_FAILURE() << "scene 2 does not exist";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("MultipleScenes.gltf: scene 2 out of range (2 scenes)"),
              std::string::npos)
        << e.what();
  }
}

TEST(GltfAssets, Cameras) {
  WT_REQUIRE_ASSET(path, "gltf/Cameras/glTF/Cameras.gltf");
  // nodes 1 and 2 carry camera 0 (perspective: yfov 0.7, aspectRatio 1,
  // znear 0.01) and camera 1 (orthographic: xmag 1, ymag 1, znear 0.01),
  // both translated to (0.5, 0.5, 3)
  Scene s = loadGltf(path.string());
  expectConsistent(s);
  EXPECT_EQ(s.triangles.size(), 2u);  // indices accessor count 6
  ASSERT_TRUE(s.camera.has_value());
  EXPECT_FALSE(s.camera->orthographic);
  EXPECT_FLOAT_EQ(s.camera->yfov, 0.7f);
  EXPECT_FLOAT_EQ(s.camera->aspectRatio, 1.0f);
  EXPECT_FLOAT_EQ(s.camera->znear, 0.01f);
  expectNear(cameraPosition(s), {0.5f, 0.5f, 3.0f});

  GltfLoadOptions options;
  options.cameraIndex = 1;
  Scene ortho = loadGltf(path.string(), options);
  ASSERT_TRUE(ortho.camera.has_value());
  EXPECT_TRUE(ortho.camera->orthographic);
  EXPECT_FLOAT_EQ(ortho.camera->xmag, 1.0f);
  EXPECT_FLOAT_EQ(ortho.camera->ymag, 1.0f);

  options.cameraIndex = 2;
  EXPECT_THROW(loadGltf(path.string(), options), SceneError);
}

TEST(GltfAssets, NegativeScaleTest) {
  WT_REQUIRE_ASSET(path, "gltf/NegativeScaleTest/glTF/NegativeScaleTest.gltf");
  Scene s = loadGltf(path.string());
  expectConsistent(s);
  // sum over the scene's mesh instances of indices count / 3
  EXPECT_EQ(s.triangles.size(), 7724u);
  // Several nodes mirror their meshes (scale -1 on one or three axes); with
  // the winding flipped, front faces still agree with the vertex normals.
  EXPECT_EQ(fractionFacingTheirNormals(s), 1.0);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
  EXPECT_GT(s.textures.textures.size(), 0u);
}

TEST(GltfAssets, Box) {
  for (const char* rel : {"gltf/Box/glTF/Box.gltf", "gltf/Box/glTF-Binary/Box.glb"}) {
    SCOPED_TRACE(rel);
    WT_REQUIRE_ASSET(path, rel);
    Scene s = loadGltf(path.string());
    expectConsistent(s);
    // indices accessor count 36
    ASSERT_EQ(s.triangles.size(), 12u);
    // POSITION min/max is +-0.5; the root's matrix only swaps axes
    expectNear(s.bounds().lo, glm::vec3(-0.5f));
    expectNear(s.bounds().hi, glm::vec3(0.5f));
    // outward winding and outward normals
    for (std::size_t t = 0; t < s.triangles.size(); ++t) {
      const WtTriangle& tri = s.triangles[t];
      glm::vec3 centroid = (pos(s, tri.v0) + pos(s, tri.v1) + pos(s, tri.v2)) / 3.0f;
      glm::vec3 g = glm::cross(pos(s, tri.v1) - pos(s, tri.v0), pos(s, tri.v2) - pos(s, tri.v0));
      EXPECT_GT(glm::dot(g, centroid), 0.0f) << "triangle " << t;
    }
    EXPECT_EQ(fractionFacingTheirNormals(s), 1.0);
    // material "Red": baseColorFactor [0.8, 0, 0, 1]
    ASSERT_EQ(s.materials.size(), 1u);
    EXPECT_EQ(s.materialNames[0], "Red");
    EXPECT_FLOAT_EQ(s.materials[0].base_color.x, 0.8f);
    EXPECT_FLOAT_EQ(s.materials[0].base_color.y, 0.0f);
  }
}

TEST(GltfAssets, BoxInterleaved) {
  WT_REQUIRE_ASSET(path, "gltf/BoxInterleaved/glTF/BoxInterleaved.gltf");
  Scene s = loadGltf(path.string());
  expectConsistent(s);
  // indices accessor count 36; POSITION and NORMAL share one bufferView
  // with byteStride 24
  ASSERT_EQ(s.triangles.size(), 12u);
  expectNear(s.bounds().lo, glm::vec3(-0.5f));
  expectNear(s.bounds().hi, glm::vec3(0.5f));
  EXPECT_EQ(fractionFacingTheirNormals(s), 1.0);
  for (std::size_t v = 0; v < s.positions.size(); ++v)
    EXPECT_NEAR(glm::length(nrm(s, std::uint32_t(v))), 1.0f, 1e-5f);
}

TEST(GltfAssets, SimpleInstancing) {
  // EXT_mesh_gpu_instancing: 125 instances of a 12-triangle cube
  WT_REQUIRE_ASSET(path, "gltf/SimpleInstancing/glTF/SimpleInstancing.gltf");
  Scene s = loadGltf(path.string());
  expectConsistent(s);
  EXPECT_EQ(s.triangles.size(), 125u * 12u);
  ASSERT_EQ(s.instances.size(), 125u);
  EXPECT_FALSE(hasWarning(s, "EXT_mesh_gpu_instancing"));
  // spread over space, not stacked at one place
  EXPECT_GT(glm::length(s.bounds().extent()), 5.0f);
}

TEST(GltfAssets, SimpleMeshes) {
  WT_REQUIRE_ASSET(path, "gltf/SimpleMeshes/glTF/SimpleMeshes.gltf");
  Scene s = loadGltf(path.string());
  expectConsistent(s);
  // one 3-index mesh, instanced by node 0 and by node 1 at translation (1,0,0)
  ASSERT_EQ(s.triangles.size(), 2u);
  expectNear(pos(s, s.triangles[1].v0) - pos(s, s.triangles[0].v0), {1, 0, 0});
}

TEST(GltfAssets, MeshPrimitiveModes) {
  WT_REQUIRE_ASSET(path, "gltf/MeshPrimitiveModes/glTF/MeshPrimitiveModes.gltf");
  Scene s = loadGltf(path.string());
  expectConsistent(s);
  // TRIANGLES: 18 indices -> 6; TRIANGLE_STRIP: 6 indices -> 4;
  // TRIANGLE_FAN: 8 indices -> 6; POINTS, LINES, LINE_LOOP, LINE_STRIP skipped
  EXPECT_EQ(s.triangles.size(), 16u);
  for (const char* mode : {"POINTS", "LINES", "LINE_LOOP", "LINE_STRIP"})
    EXPECT_TRUE(hasWarning(s, std::string(mode) + " primitives are not supported")) << mode;
  // all modes draw the same flat shape facing +z
  for (std::size_t t = 0; t < s.triangles.size(); ++t) {
    const WtTriangle& tri = s.triangles[t];
    glm::vec3 g = glm::cross(pos(s, tri.v1) - pos(s, tri.v0), pos(s, tri.v2) - pos(s, tri.v0));
    EXPECT_GT(g.z, 0.0f) << "triangle " << t;
  }
}

TEST(GltfAssets, TextureCoordinateTest) {
  for (const char* rel : {"gltf/TextureCoordinateTest/glTF/TextureCoordinateTest.gltf",
                          "gltf/TextureCoordinateTest/glTF-Binary/TextureCoordinateTest.glb"}) {
    SCOPED_TRACE(rel);
    WT_REQUIRE_ASSET(path, rel);
    Scene s = loadGltf(path.string());
    expectConsistent(s);
    // five meshes of 6 indices each -> 10 triangles
    EXPECT_EQ(s.triangles.size(), 10u);
    EXPECT_EQ(s.materials.size(), 5u);
    EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
    // one image, the base colour of the four quadrants' materials (not the back plane's)
    EXPECT_EQ(s.textures.imageCount(), 1u);
    EXPECT_EQ(std::count_if(s.materials.begin(), s.materials.end(),
                            [](const WtMaterial& m) { return m.texture_mask == 1u << WT_TEXTURE_SLOT_BASE_COLOR; }),
              4);
    // every TEXCOORD_0 min/max lies in [0, 1]; some are not zero
    bool anyNonZero = false;
    for (const glm::vec2& uv : s.texcoords) {
      EXPECT_GE(uv.x, -1e-6f);
      EXPECT_LE(uv.x, 1.0f + 1e-6f);
      EXPECT_GE(uv.y, -1e-6f);
      EXPECT_LE(uv.y, 1.0f + 1e-6f);
      anyNonZero = anyNonZero || uv != glm::vec2(0.0f);
    }
    EXPECT_TRUE(anyNonZero);
  }
}

TEST(GltfAssets, OrientationTest) {
  WT_REQUIRE_ASSET(gltf, "gltf/OrientationTest/glTF/OrientationTest.gltf");
  WT_REQUIRE_ASSET(glb, "gltf/OrientationTest/glTF-Binary/OrientationTest.glb");
  Scene a = loadGltf(gltf.string());
  Scene b = loadGltf(glb.string());
  expectConsistent(a);
  // sum over the 13 mesh nodes of indices count / 3
  EXPECT_EQ(a.triangles.size(), 524u);
  // TRS and matrix nodes both place the arrows; normals agree with windings
  EXPECT_EQ(fractionFacingTheirNormals(a), 1.0);
  // the .glb holds the same scene
  ASSERT_EQ(b.triangles.size(), a.triangles.size());
  ASSERT_EQ(b.positions.size(), a.positions.size());
  for (std::size_t v = 0; v < a.positions.size(); ++v)
    expectNear(pos(b, std::uint32_t(v)), pos(a, std::uint32_t(v)), 1e-4f);
}

TEST(GltfAssets, DamagedHelmet) {
  // Only the .gltf of DamagedHelmet is in the assets (no glTF-Binary folder).
  WT_REQUIRE_ASSET(path, "gltf/DamagedHelmet/glTF/DamagedHelmet.gltf");
  Scene s = loadGltf(path.string());
  expectConsistent(s);
  // indices accessor count 46356 -> 15452 triangles over 14556 vertices
  EXPECT_EQ(s.triangles.size(), 15452u);
  // the normal map's tangents are generated (the file has none); vertices on
  // mirrored UV seams are split, one copy per handedness
  EXPECT_GE(s.positions.size(), 14556u);
  EXPECT_LT(s.positions.size(), 14556u + 100u);
  ASSERT_EQ(s.tangents.size(), s.positions.size());
  for (std::size_t v = 0; v < s.tangents.size(); ++v) {
    glm::vec3 t(s.tangents[v]), n(s.normals[v].x, s.normals[v].y, s.normals[v].z);
    ASSERT_NEAR(glm::length(t), 1.0f, 1e-4f) << v;
    ASSERT_NEAR(glm::dot(t, n), 0.0f, 1e-3f) << v;
    ASSERT_EQ(std::fabs(s.tangents[v].w), 1.0f) << v;
  }
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
  // base colour, metallic-roughness, normal and emissive: four slots of five images (occlusion is not read)
  EXPECT_EQ(s.materials[0].texture_mask, 0b1111u);
  EXPECT_EQ(s.textures.imageCount(), 4u);
  // Material_MR: emissiveFactor [1, 1, 1] (the emissive texture is ignored)
  EXPECT_FLOAT_EQ(s.materials[0].emission.x, 1.0f);
  EXPECT_EQ(fractionFacingTheirNormals(s), 1.0);
}

// KHR_materials_transmission, _ior and _volume as two sample models write
// them (values from their JSON): AttenuationTest's first material has
// attenuationColor [0.1, 0.5, 0.9] over attenuationDistance 1 (sigma =
// -ln(colour)), thicknessFactor 1; TransmissionRoughnessTest's
// "Mat_IOR_1.33" has ior 1.33, base colour [0.5, 0.7, 0.9], thickness
// 0.005 and no attenuation.
TEST(GltfAssets, TransmissionMaterials) {
  WT_REQUIRE_ASSET(attenuation, "gltf/AttenuationTest/glTF/AttenuationTest.gltf");
  WT_REQUIRE_ASSET(roughness, "gltf/TransmissionRoughnessTest/glTF/TransmissionRoughnessTest.gltf");
  Scene a = loadGltf(attenuation.string());
  auto named = [](const Scene& s, const std::string& name) -> const WtMaterial& {
    auto it = std::find(s.materialNames.begin(), s.materialNames.end(), name);
    EXPECT_NE(it, s.materialNames.end()) << name;
    return s.materials[std::size_t(it - s.materialNames.begin())];
  };
  const WtMaterial& r2 = named(a, "R2_and_R4_ThicknessFac_1.0");
  EXPECT_EQ(r2.transmission, 1.0f);
  EXPECT_EQ(r2.volume.w, 1.0f);
  EXPECT_NEAR(r2.volume.x, 2.3025851f, 1e-5f);
  EXPECT_NEAR(r2.volume.y, 0.6931472f, 1e-5f);
  EXPECT_NEAR(r2.volume.z, 0.1053605f, 1e-5f);
  EXPECT_FALSE(hasWarning(a, "KHR_materials_transmission is not supported"));
  // the thickness texture is a rasteriser's stand-in for the traced distance: read past, not warned about
  EXPECT_FALSE(hasWarning(a, "thicknessTexture"));
  EXPECT_TRUE(named(a, "R3_ThicknessTex_Mat").volume.w == 1.0f);
  EXPECT_GT(a.textures.textures.size(), 0u);  // the labels' base colour
  Scene r = loadGltf(roughness.string());
  const WtMaterial& water = named(r, "Mat_IOR_1.33");
  EXPECT_FLOAT_EQ(water.ior, 1.33f);
  EXPECT_EQ(water.transmission, 1.0f);
  EXPECT_EQ(water.volume.w, 1.0f);
  EXPECT_EQ(water.volume.x, 0.0f);
  EXPECT_FLOAT_EQ(water.base_color.y, 0.7f);
  EXPECT_EQ(named(r, "Mat_IOR_1.50").ior, 1.5f);  // no KHR_materials_ior: the default
}

// The layer extensions' factors on the Khronos test models (values from
// their JSON): ClearCoatTest's "Simple_Coated" (clearcoat 1, roughness
// 0.03) and "RoughVariations_Coated" (roughness 1); SpecularTest's specular
// factors and colours, up to the "HDR" colour 25 (F0 0.04 x 25, capped at 1
// by the BSDF); UnlitTest's orange [1, 0.2176, 0] as emission; and
// IridescenceSuzanne, whose iridescence is not drawn and said so once, while
// its opaque ior 2.0 now sets the dielectric's F0. ClearCoatTest's coat
// normal maps are read, with tangents generated for them.
TEST(GltfAssets, LayerMaterials) {
  WT_REQUIRE_ASSET(coat, "gltf/ClearCoatTest/glTF/ClearCoatTest.gltf");
  WT_REQUIRE_ASSET(specular, "gltf/SpecularTest/glTF/SpecularTest.gltf");
  WT_REQUIRE_ASSET(unlit, "gltf/UnlitTest/glTF/UnlitTest.gltf");
  WT_REQUIRE_ASSET(iridescence, "gltf/IridescenceSuzanne/glTF/IridescenceSuzanne.gltf");
  auto named = [](const Scene& s, const std::string& name) -> const WtMaterial& {
    auto it = std::find(s.materialNames.begin(), s.materialNames.end(), name);
    EXPECT_NE(it, s.materialNames.end()) << name;
    return s.materials[std::size_t(it - s.materialNames.begin())];
  };
  Scene c = loadGltf(coat.string());
  EXPECT_EQ(named(c, "Simple_Coated").clearcoat, 1.0f);
  EXPECT_FLOAT_EQ(named(c, "Simple_Coated").clearcoat_roughness, 0.03f);
  EXPECT_EQ(named(c, "RoughVariations_Coated").clearcoat_roughness, 1.0f);
  EXPECT_EQ(named(c, "Simple_Base").clearcoat, 0.0f);
  EXPECT_FALSE(hasWarning(c, "KHR_materials_clearcoat is not supported"));
  // the coat's normal maps are read: alone, and beside the base's own
  EXPECT_FALSE(hasWarning(c, "clearcoatNormalTexture"));
  EXPECT_EQ(named(c, "CoatNorm_Coated").texture_mask, 1u << WT_TEXTURE_SLOT_CLEARCOAT_NORMAL);
  EXPECT_EQ(named(c, "SharedNorm_Coated").texture_mask,
            (1u << WT_TEXTURE_SLOT_CLEARCOAT_NORMAL) | (1u << WT_TEXTURE_SLOT_NORMAL));
  EXPECT_EQ(c.tangents.size(), c.positions.size());
  // the coat's factor and roughness textures are read
  EXPECT_EQ(named(c, "Partial_Coated").texture_mask, 1u << WT_TEXTURE_SLOT_CLEARCOAT);
  EXPECT_EQ(named(c, "RoughVariations_Coated").texture_mask, 1u << WT_TEXTURE_SLOT_CLEARCOAT_ROUGHNESS);
  Scene sp = loadGltf(specular.string());
  EXPECT_EQ(named(sp, "M1.1_specFac").specular.w, 0.0f);
  EXPECT_FLOAT_EQ(named(sp, "M1.4_specFac").specular.w, 0.520996f);
  const WtMaterial& yellow = named(sp, "M5.4_yellowFac");
  EXPECT_FLOAT_EQ(yellow.specular.x, 0.520996f);
  EXPECT_EQ(yellow.specular.z, 0.0f);
  EXPECT_EQ(yellow.specular.w, 1.0f);
  EXPECT_EQ(named(sp, "M7.5_HDR").specular.y, 25.0f);
  EXPECT_FALSE(hasWarning(sp, "KHR_materials_specular is not supported"));
  EXPECT_FALSE(hasWarning(sp, "clamped"));
  Scene u = loadGltf(unlit.string());
  const WtMaterial& orange = named(u, "Orange");
  EXPECT_EQ(orange.model, WT_MATERIAL_DIFFUSE);
  EXPECT_EQ(orange.base_color.x, 0.0f);
  EXPECT_EQ(orange.emission.x, 1.0f);
  EXPECT_NEAR(orange.emission.y, 0.217637640824031, 1e-7);
  EXPECT_EQ(orange.emission.z, 0.0f);
  EXPECT_FALSE(hasWarning(u, "KHR_materials_unlit is not supported"));
  Scene i = loadGltf(iridescence.string());
  EXPECT_FALSE(hasWarning(i, "KHR_materials_iridescence"));
  EXPECT_FALSE(hasWarning(i, "applies to transmission only"));
  EXPECT_EQ(i.materials[0].ior, 2.0f);
  // KHR_materials_iridescence as the model's JSON gives it (python3 json):
  // factor 1, ior 1.33, maximum 400 (minimum the default 100) on materials
  // 0 and 1; ior 1.8, 200 to 600 nm by the thickness texture (index 0) on 2
  ASSERT_EQ(i.materials.size(), 3u);
  for (std::size_t m : {0u, 1u}) {
    EXPECT_EQ(i.materials[m].iridescence.x, 1.0f);
    EXPECT_FLOAT_EQ(i.materials[m].iridescence.y, 1.33f);
    EXPECT_EQ(i.materials[m].iridescence.z, 100.0f);
    EXPECT_EQ(i.materials[m].iridescence.w, 400.0f);
  }
  EXPECT_FLOAT_EQ(i.materials[2].iridescence.y, 1.8f);
  EXPECT_EQ(i.materials[2].iridescence.z, 200.0f);
  EXPECT_EQ(i.materials[2].iridescence.w, 600.0f);
  EXPECT_TRUE(i.materials[2].texture_mask & (1u << WT_TEXTURE_SLOT_IRIDESCENCE_THICKNESS));
  EXPECT_FALSE(i.materials[2].texture_mask & (1u << WT_TEXTURE_SLOT_IRIDESCENCE));
}

}  // namespace
}  // namespace wt
