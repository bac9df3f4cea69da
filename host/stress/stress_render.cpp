// Stress rows that render: scenes translated and scaled far from unit size
// and the world origin, degenerate files, material extremes in a furnace, and
// the NaN guard.
#include "stress/stress.h"

#include "core/embedded.h"
#include "render/image_error.h"
#include "render/renderer.h"
#include "scene/default_scene.h"
#include "scene/generators.h"
#include "scene/gltf_doc.h"
#include "scene/gltf_loader.h"

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <optional>

namespace wt {
namespace {

using gltf_doc::GltfDoc;
using gltf_doc::num;
using gltf_doc::str;

/// A false alarm in one row of statistical comparisons is this rare.
constexpr double kFamilyAlpha = 1e-3;

std::string format(const char* fmt, double v) { return stressFormat(fmt, v); }

struct Rendered {
  Image image;
  std::uint64_t nonFinite = 0;
};

Rendered render(Context& context, const Scene& scene, const RenderSettings& settings) {
  Renderer renderer(context, scene, settings);
  for (int s = 0; s < settings.samplesPerPixel; ++s) renderer.renderSample();
  Rendered r;
  r.image = renderer.readImage();
  r.nonFinite = renderer.stats().nonFiniteSamples;
  return r;
}

/// Pixels whose mean or variance is NaN or infinite.
std::size_t nonFinitePixels(const Image& image) {
  std::size_t count = 0;
  for (std::size_t i = 0; i < image.rgb.size(); ++i)
    count += !std::isfinite(image.rgb[i]) || !std::isfinite(image.rgbVariance[i]);
  return count;
}

// ---------------------------------------------------------------------------
// transforms

/// A built-in scene under one more root node that translates (by d on every
/// axis) or scales it, the camera with it (the loader scales the near plane
/// with the camera's node).
std::string transformedScene(std::string_view gltf, double translate, double scale) {
  nlohmann::json d = nlohmann::json::parse(gltf);
  nlohmann::json root = {{"name", "stress root"}, {"children", d["scenes"][0]["nodes"]}};
  if (translate != 0.0) root["translation"] = {translate, translate, translate};
  if (scale != 1.0) root["scale"] = {scale, scale, scale};
  d["nodes"].push_back(root);
  d["scenes"][0]["nodes"] = {d["nodes"].size() - 1};
  return d.dump();
}

struct TransformCase {
  std::string name;
  double translate = 0.0, scale = 1.0;
  bool recenter = true;
};

}  // namespace

// Each case renders with the reference's seed, so wherever the transformed
// scene gives the same paths the two images agree to rounding, and where
// float differences send a path elsewhere the pair is no worse correlated
// than two seeds: the unpaired standard error of a block difference is then
// an upper bound on the paired one, and |z| over it stays below the
// Bonferroni limit unless the transform changed what is rendered (light
// leaking through offset walls, shadows lost to self-intersection).
std::vector<StressRow> stressTransforms(Context& context, const StressOptions& options) {
  std::vector<StressRow> rows;
  const int size = options.quick ? 32 : 48, spp = options.quick ? 64 : 256, blocks = options.quick ? 4 : 6;
  const double zLimit = bonferroniZ(blocks * blocks * 3, kFamilyAlpha);
  std::vector<std::string> scenes = {"cornell"};
  if (!options.quick) scenes.push_back("cornell_small_light");

  for (const std::string& sceneName : scenes) {
    std::string_view text = *embedded::find("scenes/" + sceneName + ".gltf");
    RenderSettings settings;
    settings.width = settings.height = size;
    settings.samplesPerPixel = spp;
    auto renderCase = [&](const TransformCase& c, std::uint32_t seed) {
      GltfLoadOptions load;
      load.recenter = c.recenter;
      Scene scene = loadGltfFromMemory(transformedScene(text, c.translate, c.scale), sceneName + " (stress)", ".", load);
      RenderSettings s = settings;
      s.seed = seed;
      return render(context, scene, s);
    };
    auto start = std::chrono::steady_clock::now();
    Rendered reference = renderCase({"reference"}, 1);
    // the noise scale: what two seeds of the untransformed scene differ by
    ImageError noise = imageError(renderCase({"another seed"}, 2).image, reference.image);
    Rendered again = renderCase({"again"}, 1);
    StressRow control;
    control.group = "transform";
    control.name = sceneName + ": untransformed, rendered twice with one seed";
    control.figure = std::string(again.image.rgb == reference.image.rgb ? "bit-identical" : "different") +
                     "; two seeds differ by relMSE " + format("%.3g", noise.relMse);
    control.criterion = "bit-identical (what the transformed cases are compared with)";
    control.pass = again.image.rgb == reference.image.rgb;
    control.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    rows.push_back(control);

    // one case: the same image within the noise of both renders
    auto compare = [&](const TransformCase& c, StressRow* row) {
      auto start = std::chrono::steady_clock::now();
      Rendered r = renderCase(c, 1);
      ImageAgreement a = compareImages(r.image, reference.image, blocks);
      ImageError e = imageError(r.image, reference.image);
      row->group = "transform";
      row->name = sceneName + ": " + c.name;
      row->figure = "max |z| " + format("%.2f", a.maxAbsZ) + " over " + std::to_string(a.tests) + " blocks, relMSE " +
                    format("%.3g", e.relMseRaw) + " (two seeds: " + format("%.3g", noise.relMse) + "), mean ratio " +
                    format("%.4f", e.meanRatio);
      if (r.nonFinite) row->figure += ", " + std::to_string(r.nonFinite) + " NaN/Inf samples";
      row->criterion = "max |z| < " + format("%.2f", zLimit) + " (block means within the noise of both renders)";
      row->pass = a.maxAbsZ < zLimit && a.exactMismatches == 0 && r.nonFinite == 0;
      row->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      return row->pass;
    };

    std::vector<TransformCase> cases;
    for (double t : options.quick ? std::vector<double>{1e6} : std::vector<double>{1e3, 1e5, 1e6})
      cases.push_back({"translated by " + format("%.0e", t) + " (recentred, the default)", t, 1.0, true});
    for (double s : {1e-4, 1e4}) cases.push_back({"scaled by " + format("%.0e", s) + " (recentred)", 0.0, s, true});
    cases.push_back({"translated by 1e+03 (world coordinates, --no-recenter)", 1e3, 1.0, false});
    for (double s : options.quick ? std::vector<double>{1e-4} : std::vector<double>{1e-4, 1e4})
      cases.push_back({"scaled by " + format("%.0e", s) + " (world coordinates)", 0.0, s, false});
    for (const TransformCase& c : cases) {
      StressRow row;
      compare(c, &row);
      rows.push_back(row);
    }
    if (options.quick) continue;

    // how far float world coordinates carry the scene without recentring
    start = std::chrono::steady_clock::now();
    double largest = 0.0;
    std::string firstFailure = "none up to 1e+06";
    for (double t : {1e2, 1e3, 3e3, 1e4, 3e4, 1e5, 3e5, 1e6}) {
      StressRow probe;
      if (!compare({"", t, 1.0, false}, &probe)) {
        firstFailure = format("%.0e", t) + " (" + probe.figure + ")";
        break;
      }
      largest = t;
    }
    StressRow row;
    row.group = "transform";
    row.name = sceneName + ": largest translation that matches in world coordinates (--no-recenter)";
    row.figure = format("%.0e", largest) + "; first failure at " + firstFailure;
    row.criterion = ">= 1e+03 (from 1e4 on, float spacing exceeds 0.1 mm and the light quad rounds onto the "
                    "ceiling's plane: the input itself is lost, which recentring avoids)";
    row.pass = largest >= 1e3;
    row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    rows.push_back(row);
  }
  return rows;
}

// ---------------------------------------------------------------------------
// degenerate input

namespace {

/// What a degenerate file must give: a clean error naming the element, or a
/// scene (with a warning when `message` is set) that renders without NaN.
struct DegenerateCase {
  std::string name;
  std::function<void(GltfDoc&)> edit;  ///< breaks one element of the base document
  bool expectError = false;
  std::string message;  ///< must appear in the error, or in a warning
};

/// A floor seen from above at an angle, with a camera: every case adds to it.
GltfDoc degenerateBase() {
  GltfDoc doc;
  int pos = doc.addVec3({{-2, 0, -2}, {2, 0, -2}, {2, 0, 2}, {-2, 0, 2}});
  int idx = doc.addIndices<std::uint16_t>({0, 2, 1, 0, 3, 2});
  doc.addMesh("{\"attributes\":{\"POSITION\":" + str(std::size_t(pos)) + "},\"indices\":" + str(std::size_t(idx)) + "}");
  doc.addNode("{\"mesh\":0}");
  doc.cameras.push_back("{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.9,\"znear\":0.01}}");
  // at (0, 2, 3) looking at the origin: rotated -33.7 degrees about +x
  doc.addNode("{\"camera\":0,\"translation\":[0,2,3],\"rotation\":[-0.2897841,0,0,0.9570920]}");
  doc.scenes.push_back("{\"nodes\":[0,1]}");
  return doc;
}

/// Add a mesh of one triangle list (and optional normals) on its own node.
void addMeshNode(GltfDoc& doc, const std::vector<glm::vec3>& positions, const std::vector<std::uint16_t>& indices,
                 const std::vector<glm::vec3>& normals = {}, const std::string& nodeExtra = "") {
  int pos = doc.addVec3(positions);
  std::string attributes = "\"POSITION\":" + str(std::size_t(pos));
  if (!normals.empty()) attributes += ",\"NORMAL\":" + str(std::size_t(doc.addVec3(normals)));
  std::string prim = "{\"attributes\":{" + attributes + "}";
  if (!indices.empty()) prim += ",\"indices\":" + str(std::size_t(doc.addIndices(indices)));
  int mesh = doc.addMesh(prim + "}");
  int node = doc.addNode("{\"mesh\":" + str(std::size_t(mesh)) + nodeExtra + "}");
  std::string& scene = doc.scenes[0];
  scene.insert(scene.size() - 2, "," + str(std::size_t(node)));
}

const std::vector<glm::vec3> kTriangle = {{-0.5f, 0.5f, 0.0f}, {0.5f, 0.5f, 0.0f}, {0.0f, 1.2f, 0.3f}};

std::vector<DegenerateCase> degenerateCases() {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<DegenerateCase> cases;
  cases.push_back({"zero-area triangle (a repeated corner)", [](GltfDoc& d) {
                     addMeshNode(d, kTriangle, {0, 1, 2, 0, 0, 1});
                   }, false, "1 of 4 triangles have zero area"});
  cases.push_back({"collinear triangle", [](GltfDoc& d) {
                     addMeshNode(d, {{0, 0.5f, 0}, {1, 0.5f, 0}, {2, 0.5f, 0}}, {0, 1, 2});
                   }, false, "have zero area"});
  cases.push_back({"every triangle of a mesh degenerate", [](GltfDoc& d) {
                     addMeshNode(d, {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}}, {0, 1, 2, 2, 1, 0});
                   }, false, "have zero area"});
  cases.push_back({"duplicate vertices and coincident triangles", [](GltfDoc& d) {
                     std::vector<glm::vec3> p = kTriangle;
                     p.insert(p.end(), kTriangle.begin(), kTriangle.end());
                     addMeshNode(d, p, {0, 1, 2, 3, 4, 5, 5, 4, 3});
                   }, false, ""});
  cases.push_back({"zero-length normals", [](GltfDoc& d) {
                     addMeshNode(d, kTriangle, {0, 1, 2}, {glm::vec3(0.0f), glm::vec3(0.0f), glm::vec3(0.0f)});
                   }, false, ""});
  cases.push_back({"NaN normals", [nan](GltfDoc& d) {
                     addMeshNode(d, kTriangle, {0, 1, 2}, {glm::vec3(nan), glm::vec3(0, nan, 1), glm::vec3(0, 0, 1)});
                   }, false, ""});
  cases.push_back({"zero-scale node", [](GltfDoc& d) {
                     addMeshNode(d, kTriangle, {0, 1, 2}, {}, ",\"scale\":[0,0,0]");
                   }, false, "its transform is singular"});
  cases.push_back({"singular matrix (rank 2: projects onto a plane)", [](GltfDoc& d) {
                     addMeshNode(d, kTriangle, {0, 1, 2}, {}, ",\"matrix\":[1,0,0,0, 0,0,0,0, 0,0,1,0, 0,0.5,0,1]");
                   }, false, "its transform is singular"});
  cases.push_back({"tiny triangle (1e-20 across)", [](GltfDoc& d) {
                     addMeshNode(d, {{0, 1, 0}, {1e-20f, 1, 0}, {0, 1 + 1e-20f, 1e-20f}}, {0, 1, 2});
                   }, false, ""});
  cases.push_back({"huge triangle (1e19 across, its cross product overflows)", [](GltfDoc& d) {
                     addMeshNode(d, {{-1e19f, 3, -1e19f}, {1e19f, 3, -1e19f}, {0, 3, 1e19f}}, {0, 1, 2});
                   }, false, ""});
  cases.push_back({"no geometry but the floor's camera", [](GltfDoc& d) { d.scenes[0] = "{\"nodes\":[1]}"; }, false, ""});
  cases.push_back({"point light under a zero-scale node", [](GltfDoc& d) {
                     d.extensionsUsed = "[\"KHR_lights_punctual\"]";
                     d.extensions = "{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"point\",\"intensity\":2}]}}";
                     d.addNode("{\"scale\":[0,0,0],\"translation\":[0,1,0],\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}");
                     d.scenes[0] = "{\"nodes\":[0,1,2]}";
                   }, false, ""});
  cases.push_back({"NaN position", [nan](GltfDoc& d) { addMeshNode(d, {{0, 1, 0}, {nan, 1, 0}, {0, 2, 0}}, {0, 1, 2}); },
                   true, "mesh 1, primitive 0 (node 2): vertex 1 has a non-finite position"});
  cases.push_back({"position overflowing float once placed (1e30 x scale 1e30)", [](GltfDoc& d) {
                     addMeshNode(d, {{0, 1, 0}, {1e30f, 1, 0}, {0, 2, 0}}, {0, 1, 2}, {}, ",\"scale\":[1e30,1,1]");
                   }, true, "vertex 1 has a non-finite position"});
  cases.push_back({"infinite node translation (1e999 in the file)", [](GltfDoc& d) {
                     d.nodes[0] = "{\"mesh\":0,\"translation\":[0,1e999,0]}";
                   }, true, "number overflow parsing '1e999'"});
  cases.push_back({"zero quaternion", [](GltfDoc& d) { d.nodes[0] = "{\"mesh\":0,\"rotation\":[0,0,0,0]}"; },
                   true, "node 0: rotation is not a valid quaternion"});
  cases.push_back({"camera under a zero-scale node", [](GltfDoc& d) {
                     d.nodes[1] = "{\"camera\":0,\"translation\":[0,2,3],\"scale\":[0,0,0]}";
                   }, true, "camera 0"});
  cases.push_back({"camera with yfov 0", [](GltfDoc& d) {
                     d.cameras[0] = "{\"type\":\"perspective\",\"perspective\":{\"yfov\":0,\"znear\":0.01}}";
                   }, true, "camera 0: yfov must be positive"});
  cases.push_back({"index out of range", [](GltfDoc& d) { addMeshNode(d, kTriangle, {0, 1, 7}); },
                   true, "mesh 1, primitive 0"});
  return cases;
}

}  // namespace

std::vector<StressRow> stressDegenerate(Context& context, const StressOptions& options) {
  std::vector<StressRow> rows;
  RenderSettings settings;
  settings.width = settings.height = options.quick ? 16 : 32;
  settings.samplesPerPixel = options.quick ? 4 : 16;
  settings.maxBounces = 4;
  settings.background = glm::vec3(0.5f);
  for (const DegenerateCase& c : degenerateCases()) {
    auto start = std::chrono::steady_clock::now();
    StressRow row;
    row.group = "degenerate";
    row.name = c.name;
    row.criterion = c.expectError ? "a clear error naming '" + c.message + "'"
                                  : std::string("loads") + (c.message.empty() ? "" : " with a warning '" + c.message + "'") +
                                        "; renders with 0 NaN/Inf samples and pixels";
    GltfDoc doc = degenerateBase();
    c.edit(doc);
    std::string text = doc.embedded();
    std::optional<Scene> scene;
    try {
      scene = loadGltfFromMemory(text, "degenerate.gltf", ".");
    } catch (const SceneError& e) {
      row.figure = std::string("error: ") + e.what();
      row.pass = c.expectError && row.figure.find(c.message) != std::string::npos;
    }
    if (scene) {
      std::string warnings;
      for (const std::string& w : scene->warnings) warnings += (warnings.empty() ? "" : "; ") + w;
      try {
        Rendered r = render(context, *scene, settings);
        std::size_t bad = nonFinitePixels(r.image);
        row.figure = "loaded, " + std::to_string(scene->triangles.size()) + " triangles; " +
                     std::to_string(r.nonFinite) + " NaN/Inf samples, " + std::to_string(bad) + " non-finite pixels" +
                     (warnings.empty() ? "" : "; warnings: " + warnings);
        row.pass = !c.expectError && r.nonFinite == 0 && bad == 0 &&
                   (c.message.empty() || warnings.find(c.message) != std::string::npos);
      } catch (const std::exception& e) {
        row.figure = std::string("render failed: ") + e.what();
      }
    }
    row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    rows.push_back(row);
  }
  return rows;
}

// ---------------------------------------------------------------------------
// material extremes

namespace {

struct MaterialCase {
  std::string name;
  std::string material;  ///< glTF material JSON of the sphere
  enum Normals { kFile, kBackFacing, kTangent } normals = kFile;
  bool grazing = false;     ///< camera skimming the floor instead of looking at the sphere
  std::string warning;      ///< must be among the warnings
  std::string extensions;   ///< extensionsUsed
};

/// A sphere resting on a floor, both white unless the case says otherwise,
/// under a uniform white sky (radiance 1, set by the renderer's background).
GltfDoc furnaceDoc(const MaterialCase& c) {
  GltfDoc doc;
  int floorPos = doc.addVec3({{-20, 0, -20}, {20, 0, -20}, {20, 0, 20}, {-20, 0, 20}});
  int floorIdx = doc.addIndices<std::uint16_t>({0, 2, 1, 0, 3, 2});
  Scene sphere = makeIcosphere(3, glm::vec3(0, 1, 0), 1.0f, makeMaterial(glm::vec3(1.0f)));
  std::vector<glm::vec3> p, n;
  std::vector<std::uint16_t> idx;
  for (std::size_t v = 0; v < sphere.positions.size(); ++v) {
    glm::vec3 pos(sphere.positions[v].x, sphere.positions[v].y, sphere.positions[v].z);
    glm::vec3 out = glm::normalize(pos - glm::vec3(0, 1, 0));
    p.push_back(pos);
    if (c.normals == MaterialCase::kBackFacing) n.push_back(-out);
    else if (c.normals == MaterialCase::kTangent) n.push_back(glm::normalize(glm::cross(out, glm::vec3(0.3f, 0.9f, 0.1f))));
    else n.push_back(out);
  }
  for (const WtTriangle& t : sphere.triangles)
    idx.insert(idx.end(), {std::uint16_t(t.v0), std::uint16_t(t.v1), std::uint16_t(t.v2)});
  int spherePos = doc.addVec3(p), sphereNrm = doc.addVec3(n), sphereIdx = doc.addIndices(idx);
  // the floor: white and rough, or the sphere's own material for the grazing view
  doc.materials.push_back(c.grazing ? c.material
                                    : "{\"name\":\"white floor\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,1,1,1],"
                                      "\"metallicFactor\":0,\"roughnessFactor\":1}}");
  doc.materials.push_back(c.material);
  doc.addMesh("{\"attributes\":{\"POSITION\":" + str(std::size_t(floorPos)) + "},\"indices\":" +
              str(std::size_t(floorIdx)) + ",\"material\":0}");
  doc.addMesh("{\"attributes\":{\"POSITION\":" + str(std::size_t(spherePos)) + ",\"NORMAL\":" +
              str(std::size_t(sphereNrm)) + "},\"indices\":" + str(std::size_t(sphereIdx)) + ",\"material\":1}");
  doc.addNode("{\"mesh\":0}");
  doc.addNode("{\"mesh\":1}");
  doc.cameras.push_back("{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.8,\"znear\":0.01}}");
  if (c.grazing)  // 0.02 above the floor, looking along it (tilted 0.1 degrees down)
    doc.addNode("{\"camera\":0,\"translation\":[0,0.02,6],\"rotation\":[-0.00087266,0,0,0.99999962]}");
  else  // at (0, 2, 4.5) looking at the sphere
    doc.addNode("{\"camera\":0,\"translation\":[0,2,4.5],\"rotation\":[-0.1045285,0,0,0.9945219]}");
  doc.scenes.push_back("{\"nodes\":[0,1,2]}");
  doc.extensionsUsed = c.extensions;
  return doc;
}

std::string pbr(const std::string& baseColor, double metallic, double roughness, const std::string& extra = "") {
  return "{\"name\":\"sphere\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[" + baseColor + "],\"metallicFactor\":" +
         num(float(metallic)) + ",\"roughnessFactor\":" + num(float(roughness)) + "}" + extra + "}";
}

}  // namespace

std::vector<StressRow> stressMaterials(Context& context, const StressOptions& options) {
  const std::string white = "1,1,1,1";
  auto make = [](std::string name, std::string material, std::string warning = "") {
    MaterialCase c;
    c.name = std::move(name);
    c.material = std::move(material);
    c.warning = std::move(warning);
    return c;
  };
  std::vector<MaterialCase> cases = {
      make("white dielectric, roughness 1", pbr(white, 0, 1)),
      make("white dielectric, roughness 0 (a mirror coat)", pbr(white, 0, 0)),
      make("white metal, roughness 1 (multiple-scattering compensation at its largest)", pbr(white, 1, 1)),
      make("white metal, roughness 0 (a perfect mirror)", pbr(white, 1, 0)),
      make("white metal, roughness 1e-7", pbr(white, 1, 1e-7)),
      make("white metal, roughness 0.0317 (the smoothest GGX: alpha 1e-3)", pbr(white, 1, 0.0317)),
      make("black (base colour 0)", pbr("0,0,0,1", 0, 0.5)),
      make("base colour 1.5 in the file", pbr("1.5,1.5,1.5,1", 0, 1), "clamped"),
      make("metallic 1.5 and roughness -0.2 in the file", pbr(white, 1.5, -0.2), "metallicFactor 1.500000 is outside [0,1]; clamped"),
      make("ior 1 on an opaque dielectric (KHR_materials_ior: F0 0)",
           pbr(white, 0, 0.5, ",\"extensions\":{\"KHR_materials_ior\":{\"ior\":1.0}}")),
      make("ior 3 on an opaque dielectric (KHR_materials_ior: F0 0.25)",
           pbr(white, 0, 0.5, ",\"extensions\":{\"KHR_materials_ior\":{\"ior\":3.0}}")),
  };
  cases[9].extensions = cases[10].extensions = "[\"KHR_materials_ior\"]";
  // the layers (KHR_materials_specular, _clearcoat, _sheen) and unlit
  auto layer = [&](std::string name, std::string material, std::string extension) {
    MaterialCase c = make(std::move(name), std::move(material));
    c.extensions = "[\"" + extension + "\"]";
    return c;
  };
  const std::string allLayers =
      ",\"extensions\":{\"KHR_materials_clearcoat\":{\"clearcoatFactor\":1,\"clearcoatRoughnessFactor\":0.3},"
      "\"KHR_materials_sheen\":{\"sheenColorFactor\":[1,1,1],\"sheenRoughnessFactor\":0.5},"
      "\"KHR_materials_specular\":{\"specularFactor\":0.5,\"specularColorFactor\":[25,1,0]}}";
  cases.insert(cases.end(),
               {layer("specular 0 (a Lambertian dielectric)",
                      pbr(white, 0, 0.5, ",\"extensions\":{\"KHR_materials_specular\":{\"specularFactor\":0}}"),
                      "KHR_materials_specular"),
                layer("specular colour 25 (F0 capped at 1), roughness 0.3",
                      pbr(white, 0, 0.3, ",\"extensions\":{\"KHR_materials_specular\":{\"specularColorFactor\":[25,25,25]}}"),
                      "KHR_materials_specular"),
                layer("mirror clear coat over a white metal, roughness 1",
                      pbr(white, 1, 1, ",\"extensions\":{\"KHR_materials_clearcoat\":{\"clearcoatFactor\":1}}"),
                      "KHR_materials_clearcoat"),
                layer("clear coat roughness 1 over a mirror dielectric",
                      pbr(white, 0, 0, ",\"extensions\":{\"KHR_materials_clearcoat\":{\"clearcoatFactor\":1,"
                                       "\"clearcoatRoughnessFactor\":1}}"),
                      "KHR_materials_clearcoat"),
                layer("white sheen of roughness 0 (clamped to 0.2646)",
                      pbr(white, 0, 1, ",\"extensions\":{\"KHR_materials_sheen\":{\"sheenColorFactor\":[1,1,1]}}"),
                      "KHR_materials_sheen"),
                layer("white sheen of roughness 1 over a white metal",
                      pbr(white, 1, 0.2, ",\"extensions\":{\"KHR_materials_sheen\":{\"sheenColorFactor\":[1,1,1],"
                                         "\"sheenRoughnessFactor\":1}}"),
                      "KHR_materials_sheen"),
                layer("coat, sheen and a specular colour (25, 1, 0) at once", pbr(white, 0, 0.6, allLayers),
                      "KHR_materials_clearcoat\",\"KHR_materials_sheen\",\"KHR_materials_specular"),
                layer("unlit white (an emitter of radiance 1 that reflects nothing)",
                      pbr(white, 0, 0.5, ",\"extensions\":{\"KHR_materials_unlit\":{}}"), "KHR_materials_unlit")});
  // transmitting spheres (KHR_materials_transmission, a volume of KHR_materials_volume, KHR_materials_ior)
  auto glass = [&](std::string name, double roughness, double ior, bool thin) {
    MaterialCase c = make(std::move(name),
                          pbr(white, 0, roughness,
                              ",\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":1},"
                              "\"KHR_materials_ior\":{\"ior\":" + num(float(ior)) + "}" +
                                  (thin ? "" : ",\"KHR_materials_volume\":{\"thicknessFactor\":1}") + "}"));
    c.extensions = "[\"KHR_materials_transmission\",\"KHR_materials_ior\",\"KHR_materials_volume\"]";
    return c;
  };
  cases.insert(cases.end(), {glass("smooth glass sphere (ior 1.5, roughness 0)", 0, 1.5, false),
                             glass("rough glass sphere (ior 1.5, roughness 0.5)", 0.5, 1.5, false),
                             glass("rough glass sphere (ior 1.5, roughness 1)", 1, 1.5, false),
                             glass("glass of ior 1 (an interface that bends nothing), roughness 0.5", 0.5, 1.0, false),
                             glass("glass of ior 3, roughness 0.2", 0.2, 3.0, false),
                             glass("glass of ior 1.0001 (bends almost nothing), roughness 0.5", 0.5, 1.0001, false),
                             glass("thin-walled transmission (ior 1.5, roughness 0.3)", 0.3, 1.5, true),
                             // shadow rays cross it, and paths through it go on from their last vertex
                             glass("smooth thin-walled transmission (ior 1.5, roughness 0)", 0, 1.5, true)});
  MaterialCase backFacing = make("back-facing shading normals (glossy metal)", pbr(white, 1, 0.3));
  backFacing.normals = MaterialCase::kBackFacing;
  MaterialCase tangent = make("shading normals tangent to the surface (glossy metal)", pbr(white, 1, 0.3));
  tangent.normals = MaterialCase::kTangent;
  MaterialCase grazing = make("grazing view along the floor (glossy metal floor and sphere)", pbr(white, 1, 0.2));
  grazing.grazing = true;
  cases.insert(cases.end(), {backFacing, tangent, grazing});
  RenderSettings settings;
  settings.width = settings.height = options.quick ? 24 : 48;
  settings.samplesPerPixel = options.quick ? 32 : 256;
  settings.maxBounces = 32;
  settings.background = glm::vec3(1.0f);
  const int blocks = options.quick ? 4 : 8;
  // one-sided test per block and channel: the mean may not exceed 1
  const double zLimit = bonferroniZ(blocks * blocks * 3, 2.0 * kFamilyAlpha);

  std::vector<StressRow> rows;
  for (const MaterialCase& c : cases) {
    auto start = std::chrono::steady_clock::now();
    StressRow row;
    row.group = "materials";
    row.name = c.name;
    row.criterion = "0 NaN/Inf; no block brighter than the sky: (mean - 1) / standard error < " + format("%.2f", zLimit) +
                    (c.warning.empty() ? "" : "; warns '" + c.warning + "'");
    try {
      Scene scene = loadGltfFromMemory(furnaceDoc(c).embedded(), "furnace.gltf", ".");
      std::string warnings;
      for (const std::string& w : scene.warnings) warnings += (warnings.empty() ? "" : "; ") + w;
      Rendered r = render(context, scene, settings);
      // the largest excess over 1 of any block mean, in standard errors
      double worst = -INFINITY, brightest = 0.0;
      const Image& img = r.image;
      for (int by = 0; by < blocks; ++by)
        for (int bx = 0; bx < blocks; ++bx)
          for (int ch = 0; ch < 3; ++ch) {
            double sum = 0.0, var = 0.0;
            int n = 0;
            for (int y = by * img.height / blocks; y < (by + 1) * img.height / blocks; ++y)
              for (int x = bx * img.width / blocks; x < (bx + 1) * img.width / blocks; ++x, ++n) {
                std::size_t px = std::size_t(y) * img.width + x;
                sum += img.rgb[3 * px + ch];
                var += img.rgbVariance[3 * px + ch] / std::max<std::uint32_t>(img.samples[px], 1);
              }
            double mean = sum / n, se = std::sqrt(var) / n;
            brightest = std::max(brightest, mean);
            // a block with no variance (pure sky) must not exceed 1 at all
            double z = se > 0.0 ? (mean - 1.0) / se : (mean > 1.0 + 1e-6 ? INFINITY : -INFINITY);
            worst = std::max(worst, z);
          }
      std::size_t bad = nonFinitePixels(img);
      row.figure = std::to_string(r.nonFinite) + " NaN/Inf samples, " + std::to_string(bad) +
                   " non-finite pixels; brightest block " + format("%.4f", brightest) + ", worst excess " +
                   format("%.2f", worst) + " SE" + (warnings.empty() ? "" : "; warnings: " + warnings);
      row.pass = r.nonFinite == 0 && bad == 0 && worst < zLimit &&
                 (c.warning.empty() || warnings.find(c.warning) != std::string::npos);
    } catch (const std::exception& e) {
      row.figure = std::string("failed: ") + e.what();
    }
    row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    rows.push_back(row);
  }
  return rows;
}

// ---------------------------------------------------------------------------
// the NaN guard

std::vector<StressRow> stressNonFinite(Context& context, const StressOptions& options) {
  auto start = std::chrono::steady_clock::now();
  // a floor whose albedo is NaN in red (the loader refuses such a file, so
  // the scene is made in code) under the view's lower half: its paths turn NaN
  Scene scene;
  appendScene(scene, makeGrid(1, glm::vec3(0.0f), 50.0f, glm::vec3(0, 0, 1), glm::vec3(1, 0, 0),
                              makeMaterial(glm::vec3(std::nanf(""), 0.5f, 0.5f))));
  CameraDesc camera;
  camera.cameraToWorld = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 1.0f, 0.0f));
  scene.camera = camera;
  RenderSettings settings;
  settings.width = settings.height = options.quick ? 16 : 64;
  settings.samplesPerPixel = options.quick ? 4 : 16;
  settings.maxBounces = 2;
  settings.background = glm::vec3(0.25f);
  settings.stopOnNonFinite = false;
  Rendered r = render(context, scene, settings);
  std::uint64_t discarded = 0;
  for (std::uint32_t n : r.image.samples) discarded += std::uint32_t(settings.samplesPerPixel) - n;
  std::size_t bad = nonFinitePixels(r.image);

  std::vector<StressRow> rows;
  StressRow counted;
  counted.group = "non-finite";
  counted.name = "NaN albedo under half the view: counted, never accumulated";
  counted.figure = std::to_string(r.nonFinite) + " samples counted, " + std::to_string(discarded) +
                   " missing from pixel counts, " + std::to_string(bad) + " non-finite pixels";
  counted.criterion = "counted == missing > 0, 0 non-finite pixels";
  counted.pass = r.nonFinite == discarded && discarded > 0 && bad == 0;
  counted.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  rows.push_back(counted);

  StressRow stop;
  stop.group = "non-finite";
  stop.name = "--stop-on-nan names the first one";
  stop.criterion = "stops at sample 0, bounce 0, in the floor's half of the image";
  settings.stopOnNonFinite = true;
  try {
    Renderer renderer(context, scene, settings);
    renderer.renderSample();
    stop.figure = "did not stop";
  } catch (const NonFiniteSampleError& e) {
    stop.figure = e.what();
    stop.pass = e.sample == 0 && e.bounce == 0 && e.y >= settings.height / 2;
  }
  rows.push_back(stop);
  return rows;
}

}  // namespace wt
