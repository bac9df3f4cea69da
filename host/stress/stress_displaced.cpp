// Stress rows for displaced meshes (host/geometry/displaced.cpp): the
// displaced icosphere from a scene file, translated to 1e6 and scaled from
// 1e-4 to 1e4, renders the same image; zero displacement renders the base
// mesh; an extreme scale and NaN in the map never crash or make a NaN; a
// NaN in a map file is refused naming the file and the texel.
#include "stress/stress.h"
#include "stress/stress_rows.h"

#include "geometry/primitives.h"
#include "output/image_io.h"
#include "render/image_error.h"
#include "render/renderer.h"
#include "scene/generators.h"
#include "scene/scene_file.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

namespace wt {
namespace {

using stress_rows::nonFinitePixels;
using stress_rows::Rendered;
using stress_rows::render;
using stress_rows::secondsSince;

/// The displaced icosphere's base mesh as an ASCII PLY (positions, normals, uv) and its map as an EXR, in a temporary folder.
struct DisplacedFiles {
  std::filesystem::path dir, ply, exr;
  explicit DisplacedFiles(const std::string& tag, float nanAt = -1.0f) {
    dir = std::filesystem::temp_directory_path() / ("wt-stress-displaced-" + tag);
    std::filesystem::create_directories(dir);
    ply = dir / "sphere.ply";
    exr = dir / "map.exr";
    const Scene s = makeDisplacedSphere(2, glm::vec3(0.0f), 1.0f, 32, 1.0f, 0.0f, -1, makeMaterial(glm::vec3(0.5f)));
    const DisplacedMesh& m = s.displacedMeshes[0];
    std::ofstream out(ply);
    out.precision(9);
    out << "ply\nformat ascii 1.0\nelement vertex " << m.positions.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
           "property float u\nproperty float v\nelement face "
        << m.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
    // PLY's v runs up (OBJ's convention); the loader flips it back
    for (std::size_t i = 0; i < m.positions.size(); ++i)
      out << m.positions[i].x << ' ' << m.positions[i].y << ' ' << m.positions[i].z << ' ' << m.normals[i].x << ' '
          << m.normals[i].y << ' ' << m.normals[i].z << ' ' << m.texcoords[i].x << ' ' << 1.0f - m.texcoords[i].y << '\n';
    for (const auto& t : m.triangles) out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
    out.close();
    Image image;
    image.width = int(m.mapWidth);
    image.height = int(m.mapHeight);
    for (float h : m.map) image.rgb.insert(image.rgb.end(), {h, h, h});
    if (nanAt >= 0.0f) image.rgb[3 * std::size_t(nanAt)] = std::numeric_limits<float>::quiet_NaN();
    writeImage(exr, image);
  }
  ~DisplacedFiles() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};

/// The displaced sphere (scale 0.15 h - 0.075 about radius 0.6) on a ground sphere under a sphere light,
/// everything scaled by `scale` and moved by `translate` on every axis, as a scene file.
/// `instanced`: placed twice by "instances", the second copy 20 units behind the camera.
std::string displacedSceneJson(const DisplacedFiles& files, double translate, double scale, double mapScale = 0.15,
                               double mapOffset = -0.075, bool instanced = false) {
  const stress_rows::ScaledJson json{translate, scale};
  auto p = [&](double x, double y, double z) { return json.point(x, y, z); };
  auto r = [&](double v) { return json.length(v); };
  const std::string copies =
      instanced ? R"(, "instances": [{"translate": [0, 0, 0]}, {"translate": [0, 0, )" + r(20) + "]}]" : "";
  return json.stage(R"(    "clay": {"base_color": [0.8, 0.5, 0.4], "roughness": 0.5},
)",
                    R"(    {"type": "displaced", "mesh": ")" + files.ply.string() + R"(", "displacement": ")" +
                        files.exr.string() + R"(", "scale": )" + r(mapScale) + R"(, "offset": )" + r(mapOffset) +
                        R"(, "material": "clay",
     "transform": {"translate": )" + p(0, 0.6, 0) + R"(, "scale": )" + r(0.6) + "}" + copies + R"(},
)");
}

}  // namespace

std::vector<StressRow> stressDisplaced(Context& context, const StressOptions& options) {
  const DisplacedFiles files("scene");
  const stress_rows::TransformStudy study = stress_rows::transformStudy(options, 4);
  const RenderSettings& settings = study.settings;
  auto load = [&](const std::string& json) { return loadSceneFileFromMemory(json, "displaced (stress)", ".").scene; };

  // translation and scale: the same image within noise
  std::vector<StressRow> rows = stress_rows::transformRows(
      "displaced icosphere (320 base triangles, 32^2 map)", options, study, [&](double translate, double scale) {
        return render(context, load(displacedSceneJson(files, translate, scale)), settings);
      });
  // as an instance: the full suite only (the quick one's budget; CTest's instancing tests cover the copies)
  if (!options.quick)
    for (StressRow& row : stress_rows::instancedTransformRows(
             context, "displaced icosphere as an instance (two copies, one behind the camera)", options, study, 2,
             [&](double translate, double scale) {
               return load(displacedSceneJson(files, translate, scale, 0.15, -0.075, true));
             }))
      rows.push_back(std::move(row));

  // zero displacement: the base mesh, as a plain triangle mesh
  {
    const auto start = std::chrono::steady_clock::now();
    const Rendered zero = render(context, load(displacedSceneJson(files, 0.0, 1.0, 0.0, 0.0)), settings);
    std::string mesh = displacedSceneJson(files, 0.0, 1.0, 0.0, 0.0);
    const std::size_t at = mesh.find(R"({"type": "displaced")");
    const std::size_t end = mesh.find(R"("material": "clay")", at);
    mesh.replace(at, end - at, R"({"type": "mesh", "file": ")" + files.ply.string() + R"(", )");
    const Rendered base = render(context, load(mesh), settings);
    rows.push_back(stress_rows::agreementRow(
        "displaced icosphere, scale 0 and offset 0, against its base mesh as triangles", zero, base, study, "", start));
  }

  // extreme scales: spikes 1e4 times the mesh's size, and a scale of 1e30
  for (double mapScale : {1e4, 1e30}) {
    const auto start = std::chrono::steady_clock::now();
    // every ray crosses every shell here: a small image is enough to find a NaN
    RenderSettings small = settings;
    small.width = small.height = 16;
    small.samplesPerPixel = options.quick ? 2 : 8;
    const Rendered r = render(context, load(displacedSceneJson(files, 0.0, 1.0, mapScale, -0.5 * mapScale)), small);
    const std::size_t bad = nonFinitePixels(r.image);
    StressRow row;
    row.group = "primitives";
    row.name = "displaced icosphere, displacement scale " + stressFormat("%.0e", mapScale) + " (offset -scale/2)";
    row.figure = std::to_string(r.nonFinite) + " NaN/Inf samples, " + std::to_string(bad) + " non-finite pixels";
    row.criterion = "renders, no NaN";
    row.pass = r.nonFinite == 0 && bad == 0;
    row.seconds = secondsSince(start);
    rows.push_back(row);
  }

  // NaN in a map file: refused naming the file and the texel
  {
    const auto start = std::chrono::steady_clock::now();
    const DisplacedFiles nanFiles("nan", 37.0f);
    std::string error;
    try {
      loadSceneFileFromMemory(displacedSceneJson(nanFiles, 0.0, 1.0), "nan.json", ".");
    } catch (const SceneError& e) {
      error = e.what();
    }
    StressRow row;
    row.group = "primitives";
    row.name = "scene file, a displacement map (EXR) with a NaN texel";
    row.figure = error.empty() ? "loaded" : "error: " + error;
    row.criterion = "an error naming the scene file, objects[1].displacement, the map and the texel";
    row.pass = error.find("nan.json") != std::string::npos && error.find("objects[1].displacement") != std::string::npos &&
               error.find("map.exr") != std::string::npos && error.find("texel (5, 1)") != std::string::npos &&
               error.find("NaN") != std::string::npos;
    row.seconds = secondsSince(start);
    rows.push_back(row);
  }

  // NaN in a map made in code: drawn as 0, never a NaN
  {
    const auto start = std::chrono::steady_clock::now();
    // black and emitting: every pixel that sees it is exactly its radiance
    Scene scene = makeDisplacedSphere(1, glm::vec3(0.0f, 0.0f, -4.0f), 1.0f, 16, 0.3f, -0.1f, -1,
                                      makeMaterial(glm::vec3(0.0f), glm::vec3(1.0f)));
    DisplacedMesh& m = scene.displacedMeshes[0];
    for (std::size_t i = 0; i < m.map.size(); i += 3) m.map[i] = std::numeric_limits<float>::quiet_NaN();
    DisplacedMesh allNan = m;
    for (float& h : allNan.map) h = std::numeric_limits<float>::quiet_NaN();
    for (glm::vec3& p : allNan.positions) p.x += 2.5f;
    scene.displacedMeshes.push_back(allNan);
    scene.camera = CameraDesc{};
    RenderSettings small = settings;
    small.width = small.height = 16;
    small.samplesPerPixel = options.quick ? 4 : 16;
    small.background = glm::vec3(0.0f);
    const Rendered r = render(context, scene, small);
    const std::size_t bad = nonFinitePixels(r.image);
    const float centre = r.image.rgb[3 * (8 * 16 + 8)];
    StressRow row;
    row.group = "primitives";
    row.name = "displaced meshes made in code with NaN texels (a third, and all), emissive";
    row.figure = std::to_string(r.nonFinite) + " NaN/Inf samples, " + std::to_string(bad) +
                 " non-finite pixels; centre pixel " + stressFormat("%.3f", centre);
    row.criterion = "NaN texels drawn as 0: no NaN, the emitter seen (centre pixel 1)";
    row.pass = r.nonFinite == 0 && bad == 0 && std::abs(centre - 1.0f) < 1e-4f;
    row.seconds = secondsSince(start);
    rows.push_back(row);
  }
  return rows;
}

}  // namespace wt
