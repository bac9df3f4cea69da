// Writes the fuzzers' seed corpus: small valid files that between them
// reach every branch of the loaders (glTF node graphs, every accessor
// component type, strides, sparse accessors, strips and fans, cameras,
// lights, materials; .hdr flat and run-length encoded; .exr of every
// compression, tiled and mip-mapped, Y-only and luminance/chroma; scene
// files with every object type, transform form and setting).
// Usage: wt_fuzz_seeds OUTDIR   (writes OUTDIR/{gltf,glb,hdr,exr,scene_file,ply}/...)
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfRgbaFile.h>
#include <ImfTiledOutputFile.h>
#include <ImfTiledRgbaFile.h>
#include <stb_image_write.h>

#include "scene/gltf_doc.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

using wt::gltf_doc::kFloat;
using wt::gltf_doc::kUByte;
using wt::gltf_doc::kUInt;
using wt::gltf_doc::kUShort;

void writeFile(const fs::path& path, const void* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(static_cast<const char*>(data), std::streamsize(size));
  if (!out) {
    std::fprintf(stderr, "wt_fuzz_seeds: cannot write %s\n", path.c_str());
    std::exit(1);
  }
}
void writeFile(const fs::path& path, const std::string& text) { writeFile(path, text.data(), text.size()); }

using wt::gltf_doc::base64;

// ---------------------------------------------------------------------------
// glTF

/// A glTF document built from JSON fragments and one binary buffer.
struct Doc {
  std::vector<std::string> accessors, bufferViews, meshes, nodes, materials, cameras, scenes, lights;
  std::string extras;  ///< more top-level members, each starting with ','
  std::vector<unsigned char> bin;

  int view(const void* data, std::size_t bytes, std::size_t stride = 0) {
    while (bin.size() % 4 != 0) bin.push_back(0);
    const std::size_t offset = bin.size();
    bin.resize(offset + bytes);
    std::memcpy(bin.data() + offset, data, bytes);
    std::string v = "{\"buffer\":0,\"byteOffset\":" + std::to_string(offset) +
                    ",\"byteLength\":" + std::to_string(bytes);
    if (stride != 0) v += ",\"byteStride\":" + std::to_string(stride);
    bufferViews.push_back(v + "}");
    return int(bufferViews.size()) - 1;
  }
  template <typename T>
  int view(const std::vector<T>& values, std::size_t stride = 0) {
    return view(values.data(), values.size() * sizeof(T), stride);
  }
  int accessor(int bufferView, int componentType, std::size_t count, const char* type,
               const std::string& extra = "") {
    std::string a = "{";
    if (bufferView >= 0) a += "\"bufferView\":" + std::to_string(bufferView) + ",";
    a += "\"componentType\":" + std::to_string(componentType) + ",\"count\":" + std::to_string(count) +
         ",\"type\":\"" + type + "\"" + extra + "}";
    accessors.push_back(a);
    return int(accessors.size()) - 1;
  }
  int floats(const std::vector<float>& values, const char* type, std::size_t components) {
    return accessor(view(values), kFloat, values.size() / components, type);
  }

  std::string json(bool glb) const {
    std::string out = "{\"asset\":{\"version\":\"2.0\",\"generator\":\"wt_fuzz_seeds\"}";
    auto list = [&](const char* key, const std::vector<std::string>& items) {
      if (items.empty()) return;
      out += std::string(",\"") + key + "\":[";
      for (std::size_t i = 0; i < items.size(); ++i) out += (i ? "," : "") + items[i];
      out += "]";
    };
    list("scenes", scenes);
    list("nodes", nodes);
    list("meshes", meshes);
    list("materials", materials);
    list("cameras", cameras);
    list("accessors", accessors);
    list("bufferViews", bufferViews);
    if (!bin.empty()) {
      out += ",\"buffers\":[{\"byteLength\":" + std::to_string(bin.size());
      if (!glb) out += ",\"uri\":\"data:application/octet-stream;base64," + base64(bin) + "\"";
      out += "}]";
    }
    if (!lights.empty()) {
      out += ",\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[";
      for (std::size_t i = 0; i < lights.size(); ++i) out += (i ? "," : "") + lights[i];
      out += "]}}";
    }
    return out + extras + "}";
  }

  std::vector<unsigned char> glb() const {
    std::string text = json(true);
    while (text.size() % 4 != 0) text += ' ';
    std::vector<unsigned char> payload = bin;
    while (payload.size() % 4 != 0) payload.push_back(0);
    std::vector<unsigned char> out;
    auto u32 = [&](std::uint32_t v) {
      for (int i = 0; i < 4; ++i) out.push_back(static_cast<unsigned char>(v >> (8 * i)));
    };
    const std::size_t total = 12 + 8 + text.size() + (payload.empty() ? 0 : 8 + payload.size());
    u32(0x46546C67);  // "glTF"
    u32(2);
    u32(std::uint32_t(total));
    u32(std::uint32_t(text.size()));
    u32(0x4E4F534A);  // "JSON"
    out.insert(out.end(), text.begin(), text.end());
    if (!payload.empty()) {
      u32(std::uint32_t(payload.size()));
      u32(0x004E4942);  // "BIN\0"
      out.insert(out.end(), payload.begin(), payload.end());
    }
    return out;
  }
};

/// One indexed triangle under one node.
Doc triangle() {
  Doc d;
  int pos = d.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, "VEC3", 3);
  int idx = d.accessor(d.view(std::vector<std::uint16_t>{0, 1, 2}), kUShort, 3, "SCALAR");
  d.meshes.push_back("{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
                     "},\"indices\":" + std::to_string(idx) + "}]}");
  d.nodes.push_back("{\"mesh\":0}");
  d.scenes.push_back("{\"nodes\":[0]}");
  return d;
}

/// Hierarchy (TRS and matrix), interleaved normals with a stride, normalized
/// texcoords, a sparse accessor, strip and fan, materials, cameras, lights.
Doc rich() {
  Doc d;
  // interleaved position + normal, stride 24
  std::vector<float> interleaved = {0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 1, 1, 0, 0, 0, 1, 0, 1, 0, 0, 0, 1};
  int inter = d.view(interleaved, 24);
  int pos = d.accessor(inter, kFloat, 4, "VEC3", ",\"min\":[0,0,0],\"max\":[1,1,0]");
  int nrm = d.accessor(inter, kFloat, 4, "VEC3", ",\"byteOffset\":12");
  int uv = d.accessor(d.view(std::vector<std::uint16_t>{0, 0, 65535, 0, 65535, 65535, 0, 65535}), kUShort, 4,
                      "VEC2", ",\"normalized\":true");
  int uvBytes = d.accessor(d.view(std::vector<std::uint8_t>{0, 0, 255, 0, 255, 255, 0, 255}), kUByte, 4, "VEC2",
                           ",\"normalized\":true");
  int idx8 = d.accessor(d.view(std::vector<std::uint8_t>{0, 1, 2, 0, 2, 3}), kUByte, 6, "SCALAR");
  int idx32 = d.accessor(d.view(std::vector<std::uint32_t>{0, 1, 2, 3}), kUInt, 4, "SCALAR");
  int sparseIdx = d.view(std::vector<std::uint16_t>{1, 3});
  int sparseVal = d.view(std::vector<float>{2, 0, 0, 0, 2, 0});
  int sparse = d.accessor(d.view(std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}), kFloat, 4, "VEC3",
                          ",\"sparse\":{\"count\":2,\"indices\":{\"bufferView\":" + std::to_string(sparseIdx) +
                              ",\"componentType\":5123},\"values\":{\"bufferView\":" + std::to_string(sparseVal) +
                              "}}");
  int zeros = d.accessor(-1, kFloat, 3, "VEC3",
                         ",\"sparse\":{\"count\":1,\"indices\":{\"bufferView\":" + std::to_string(sparseIdx) +
                             ",\"componentType\":5123},\"values\":{\"bufferView\":" + std::to_string(sparseVal) +
                             "}}");
  auto s = [](int v) { return std::to_string(v); };
  d.meshes.push_back("{\"name\":\"quad\",\"primitives\":[{\"attributes\":{\"POSITION\":" + s(pos) +
                     ",\"NORMAL\":" + s(nrm) + ",\"TEXCOORD_0\":" + s(uv) + "},\"indices\":" + s(idx8) +
                     ",\"material\":0},{\"attributes\":{\"POSITION\":" + s(sparse) + ",\"TEXCOORD_0\":" +
                     s(uvBytes) + "},\"indices\":" + s(idx32) + ",\"mode\":5,\"material\":1}]}");
  d.meshes.push_back("{\"primitives\":[{\"attributes\":{\"POSITION\":" + s(sparse) + "},\"mode\":6},"
                     "{\"attributes\":{\"POSITION\":" + s(zeros) + "}},"
                     "{\"attributes\":{\"POSITION\":" + s(pos) + "},\"mode\":1}]}");
  d.materials.push_back(
      "{\"name\":\"lamp\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.6,0.7,1],\"metallicFactor\":0,"
      "\"roughnessFactor\":1},\"emissiveFactor\":[1,0.5,0.25],\"doubleSided\":true,"
      "\"extensions\":{\"KHR_materials_emissive_strength\":{\"emissiveStrength\":4}}}");
  d.materials.push_back("{\"alphaMode\":\"MASK\",\"alphaCutoff\":0.5}");
  d.materials.push_back(
      "{\"name\":\"glass\",\"pbrMetallicRoughness\":{\"metallicFactor\":0,\"roughnessFactor\":0.2},"
      "\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":0.9},"
      "\"KHR_materials_ior\":{\"ior\":1.45},\"KHR_materials_volume\":{\"thicknessFactor\":1,"
      "\"attenuationDistance\":0.5,\"attenuationColor\":[0.9,0.5,0.1]}}}");
  d.cameras.push_back(
      "{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.7,\"znear\":0.1,\"zfar\":100,\"aspectRatio\":1.5}}");
  d.cameras.push_back("{\"type\":\"orthographic\",\"orthographic\":{\"xmag\":2,\"ymag\":1,\"znear\":0,\"zfar\":10}}");
  d.lights.push_back("{\"type\":\"point\",\"color\":[1,0.9,0.8],\"intensity\":50}");
  d.lights.push_back("{\"type\":\"spot\",\"intensity\":20,\"spot\":{\"innerConeAngle\":0.2,\"outerConeAngle\":0.6}}");
  d.lights.push_back("{\"type\":\"directional\",\"intensity\":3}");
  d.nodes.push_back("{\"name\":\"root\",\"translation\":[1,2,3],\"rotation\":[0,0.3826834,0,0.9238795],"
                    "\"scale\":[1,-1,1],\"children\":[1,2,3,4]}");
  d.nodes.push_back("{\"mesh\":0,\"children\":[5]}");
  d.nodes.push_back("{\"camera\":0,\"matrix\":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,9,1]}");
  d.nodes.push_back("{\"camera\":1,\"translation\":[0,0,5]}");
  d.nodes.push_back("{\"extensions\":{\"KHR_lights_punctual\":{\"light\":1}},\"rotation\":[-0.7071068,0,0,0.7071068]}");
  d.nodes.push_back("{\"mesh\":1,\"scale\":[2,2,2],\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}");
  d.nodes.push_back("{\"extensions\":{\"KHR_lights_punctual\":{\"light\":2}}}");
  d.scenes.push_back("{\"nodes\":[0,6]}");
  d.scenes.push_back("{\"nodes\":[1]}");
  d.extras = ",\"scene\":0,\"extensionsUsed\":[\"KHR_lights_punctual\",\"KHR_materials_emissive_strength\","
             "\"KHR_texture_transform\",\"KHR_materials_transmission\",\"KHR_materials_ior\",\"KHR_materials_volume\"]";
  return d;
}

/// Float normals and texcoords, 16-bit indices, a mesh shared by two nodes, no scenes.
Doc components() {
  Doc d;
  int pos = d.floats({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0}, "VEC3", 3);
  int nrm = d.floats({0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}, "VEC3", 3);
  int uv = d.floats({0, 0, 1, 0, 0, 1, 1, 1}, "VEC2", 2);
  int idx = d.accessor(d.view(std::vector<std::uint16_t>{0, 1, 2, 2, 1, 3}), kUShort, 6, "SCALAR");
  auto s = [](int v) { return std::to_string(v); };
  d.meshes.push_back("{\"primitives\":[{\"attributes\":{\"POSITION\":" + s(pos) + ",\"NORMAL\":" + s(nrm) +
                     ",\"TEXCOORD_0\":" + s(uv) + "},\"indices\":" + s(idx) + "}]}");
  d.nodes.push_back("{\"mesh\":0}");
  d.nodes.push_back("{\"mesh\":0,\"translation\":[0,0,-1]}");
  // no scenes: the loader draws every root node
  return d;
}

void writeGltfSeeds(const fs::path& dir) {
  fs::create_directories(dir / "gltf");
  fs::create_directories(dir / "glb");
  const std::pair<const char*, Doc> docs[] = {{"triangle", triangle()}, {"rich", rich()}, {"components", components()}};
  for (const auto& [name, doc] : docs) {
    writeFile(dir / "gltf" / (std::string(name) + ".gltf"), doc.json(false));
    const std::vector<unsigned char> glb = doc.glb();
    writeFile(dir / "glb" / (std::string(name) + ".glb"), glb.data(), glb.size());
  }
  // an external buffer (absent, so loading fails cleanly) and an empty scene
  writeFile(dir / "gltf" / "external.gltf",
            "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":12,\"uri\":\"missing.bin\"}],"
            "\"bufferViews\":[{\"buffer\":0,\"byteLength\":12}],"
            "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":1,\"type\":\"VEC3\"}],"
            "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],\"nodes\":[{\"mesh\":0}]}");
  writeFile(dir / "gltf" / "empty.gltf", "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{}],\"scene\":0}");
}

// ---------------------------------------------------------------------------
// scene files (.json): fuzz_scene_file resolves "triangle.gltf" and "sky.hdr"
// in a folder of its own

void writeSceneFileSeeds(const fs::path& dir) {
  fs::create_directories(dir / "scene_file");
  const std::pair<const char*, const char*> seeds[] = {
      {"minimal", R"({"version": 1})"},
      {"spheres", R"({"version": 1,
  "camera": {"from": [0, 1.6, 8], "to": [0, 1, 0], "up": [0, 1, 0], "fov": 40},
  "environment": {"color": [0.05, 0.07, 0.1], "hidden": false},
  "render": {"width": 64, "height": 36, "spp": 4, "max_bounces": 8, "seed": 3, "exposure": -0.5, "integrator": "path"},
  "materials": {
    "ground": {"base_color": [0.5, 0.5, 0.45], "roughness": 0.9},
    "gold": {"base_color": [1.0, 0.77, 0.34], "metallic": 1, "roughness": 0.15, "double_sided": true},
    "glass": {"roughness": 0, "transmission": 1, "ior": 1.5, "thin_walled": false,
              "attenuation_color": [0.7, 0.9, 0.8], "attenuation_distance": 2},
    "lamp": {"type": "lambert", "base_color": [0, 0, 0], "emission": [1, 0.85, 0.6], "emission_strength": 40}
  },
  "objects": [
    {"type": "sphere", "center": [0, -1000, 0], "radius": 1000, "material": "ground"},
    {"type": "sphere", "center": [-1.6, 1, 0], "radius": 1, "material": "glass"},
    {"type": "sphere", "center": [1.6, 1, 0], "radius": 1, "material": "gold"},
    {"type": "sphere", "center": [0, 0.01, 2.6], "radius": 0.01},
    {"type": "spheres", "centers": [[-3, 0.1, 3], [-2.5, 0.2, 3]], "radii": [0.1, 0.2], "material": "lamp"},
    {"type": "spheres", "centers": [[3, 0.1, 3], [2.5, 0.1, 3]], "radius": 0.1}
  ]})"},
      {"gltf", R"({"version": 1,
  "environment": {"map": "sky.hdr", "intensity": 2, "rotation": 90, "hidden": true},
  "objects": [
    {"type": "gltf", "file": "triangle.gltf"},
    {"type": "gltf", "file": "triangle.gltf", "transform": {"translate": [1000000, 0, -5], "rotate": [0, 1, 0, 30], "scale": 2}},
    {"type": "gltf", "file": "triangle.gltf", "transform": {"quaternion": [0, 0.2588190451, 0, 0.9659258263], "scale": [1, -1, 2]}},
    {"type": "gltf", "file": "triangle.gltf", "transform": {"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 4,5,6,1]}},
    {"type": "sphere", "center": [0, 0, 0], "radius": 0.5}
  ]})"},
      {"instances", R"({"version": 1,
  "objects": [
    {"type": "sphere", "center": [0, 1, 0], "radius": 0.5, "instances": [{"translate": [2, 0, 0]}, {"scale": -2}]},
    {"type": "spheres", "centers": [[0, 0, 0], [1, 0, 0]], "radii": [0.1, 0.2],
     "instances": [{"rotate": [0, 1, 0, 30], "scale": 3}, {"matrix": [0,1,0,0, -1,0,0,0, 0,0,1,0, 4,5,6,1]}]},
    {"type": "curves", "basis": "bspline", "children": 2, "child_radius": 0.1,
     "strands": [[[0, 0, 0, 0.1], [0, 1, 0, 0.1], [0, 2, 1, 0.05], [1, 3, 1, 0]]],
     "instances": [{"translate": [0, 0, 5]}, {"quaternion": [0, 0.2588190451, 0, 0.9659258263], "scale": 0.5}]}
  ]})"},
      {"gltf_with_camera", R"({"version": 1,
  "camera": {"from": [1e6, 2, 10], "to": [1e6, 0, 0], "fov": 30},
  "objects": [{"type": "gltf", "file": "triangle.gltf", "transform": {"translate": [1e6, 0, 0]}}]})"},
  };
  for (const auto& [name, text] : seeds) writeFile(dir / "scene_file" / (std::string(name) + ".json"), text);
}

// ---------------------------------------------------------------------------
// Radiance .hdr

std::vector<float> gradient(int w, int h, int channels) {
  std::vector<float> px(std::size_t(w) * std::size_t(h) * std::size_t(channels));
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = std::ldexp(float(1 + i % 7), int(i % 11) - 5);
  return px;
}

void writeHdrSeeds(const fs::path& dir) {
  fs::create_directories(dir / "hdr");
  auto write = [](void* context, void* data, int size) {
    auto* out = static_cast<std::string*>(context);
    out->append(static_cast<const char*>(data), std::size_t(size));
  };
  // stb writes run-length encoded scanlines for widths 8..32767, flat ones otherwise
  for (auto [w, h] : {std::pair{16, 8}, std::pair{4, 2}, std::pair{9, 3}}) {
    std::string bytes;
    std::vector<float> px = gradient(w, h, 3);
    stbi_write_hdr_to_func(write, &bytes, w, h, 3, px.data());
    writeFile(dir / "hdr" / ("stb_" + std::to_string(w) + "x" + std::to_string(h) + ".hdr"), bytes);
  }
  // flat RGBE pixels at a width that allows run-length encoding, #?RGBE magic,
  // extra header lines and a run of identical pixels
  std::string flat = "#?RGBE\n# made by wt_fuzz_seeds\nEXPOSURE=1.0\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 8\n";
  for (int i = 0; i < 16; ++i) flat += std::string{char(64 + i), char(128), char(32), char(129)};
  writeFile(dir / "hdr" / "flat_8x2.hdr", flat);
  // hand-made run-length data: per channel one run of 8 equal bytes
  std::string rle = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 8\n";
  rle += std::string{2, 2, 0, 8};
  for (char value : {char(200), char(100), char(50), char(129)}) rle += std::string{char(128 + 8), value};
  writeFile(dir / "hdr" / "runs_8x1.hdr", rle);
}

// ---------------------------------------------------------------------------
// OpenEXR

/// A scanline file with FLOAT or HALF planes named `channels`.
void writeScanline(const fs::path& path, int w, int h, const std::vector<std::string>& channels,
                   Imf::PixelType type, Imf::Compression compression, Imath::V2i origin = {0, 0}) {
  const Imath::Box2i window(origin, origin + Imath::V2i(w - 1, h - 1));
  Imf::Header header(window, window);
  header.compression() = compression;
  const std::vector<float> values = gradient(w, h, int(channels.size()));
  std::vector<half> halves(values.begin(), values.end());
  Imf::FrameBuffer fb;
  const std::size_t n = channels.size();
  for (std::size_t c = 0; c < n; ++c) {
    header.channels().insert(channels[c], Imf::Channel(type));
    const std::size_t size = type == Imf::HALF ? sizeof(half) : sizeof(float);
    char* base = type == Imf::HALF ? reinterpret_cast<char*>(halves.data() + c)
                                   : reinterpret_cast<char*>(const_cast<float*>(values.data() + c));
    base -= (std::ptrdiff_t(origin.x) + std::ptrdiff_t(origin.y) * w) * std::ptrdiff_t(n * size);
    fb.insert(channels[c], Imf::Slice(type, base, n * size, n * size * std::size_t(w)));
  }
  Imf::OutputFile file(path.c_str(), header);
  file.setFrameBuffer(fb);
  file.writePixels(h);
}

void writeExrSeeds(const fs::path& dir) {
  fs::create_directories(dir / "exr");
  const fs::path out = dir / "exr";
  const std::vector<std::string> rgb = {"R", "G", "B"};
  const std::pair<const char*, Imf::Compression> compressions[] = {
      {"none", Imf::NO_COMPRESSION}, {"rle", Imf::RLE_COMPRESSION},     {"zips", Imf::ZIPS_COMPRESSION},
      {"zip", Imf::ZIP_COMPRESSION}, {"piz", Imf::PIZ_COMPRESSION},     {"pxr24", Imf::PXR24_COMPRESSION},
      {"b44", Imf::B44_COMPRESSION}, {"b44a", Imf::B44A_COMPRESSION},   {"dwaa", Imf::DWAA_COMPRESSION},
      {"dwab", Imf::DWAB_COMPRESSION}};
  for (const auto& [name, compression] : compressions)
    writeScanline(out / (std::string("half_") + name + ".exr"), 8, 4, rgb, Imf::HALF, compression);
  writeScanline(out / "float_none.exr", 4, 2, rgb, Imf::FLOAT, Imf::NO_COMPRESSION);
  writeScanline(out / "float_zip_window.exr", 6, 3, {"A", "B", "G", "R"}, Imf::FLOAT, Imf::ZIP_COMPRESSION,
                {-3, 5});
  writeScanline(out / "y_only.exr", 8, 4, {"Y"}, Imf::HALF, Imf::PIZ_COMPRESSION);

  // luminance/chroma (sub-sampled RY, BY and full-resolution Y) through the RGBA interface
  {
    const int w = 8, h = 4;
    std::vector<Imf::Rgba> px(std::size_t(w) * h);
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = Imf::Rgba(float(i % 5), 0.5f, float(i % 3), 1.0f);
    Imf::RgbaOutputFile file((out / "luminance_chroma.exr").c_str(), w, h, Imf::WRITE_YCA, 1,
                             Imath::V2f(0, 0), 1, Imf::INCREASING_Y, Imf::ZIP_COMPRESSION);
    file.setFrameBuffer(px.data(), 1, w);
    file.writePixels(h);
  }
  // tiled, single level and mip-mapped
  for (auto [name, mode] : {std::pair{"tiled.exr", Imf::ONE_LEVEL}, std::pair{"tiled_mipmap.exr", Imf::MIPMAP_LEVELS}}) {
    const int w = 8, h = 4;
    Imf::Header header(w, h);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const std::string& c : rgb) header.channels().insert(c, Imf::Channel(Imf::HALF));
    header.setTileDescription(Imf::TileDescription(4, 4, mode, Imf::ROUND_DOWN));
    Imf::TiledOutputFile file((out / name).c_str(), header);
    std::vector<half> planes(std::size_t(w) * h * 3);
    for (std::size_t i = 0; i < planes.size(); ++i) planes[i] = half(float(i % 9) * 0.25f);
    for (int level = 0; level < file.numLevels(); ++level) {
      Imf::FrameBuffer fb;
      for (std::size_t c = 0; c < 3; ++c)
        fb.insert(rgb[c], Imf::Slice(Imf::HALF, reinterpret_cast<char*>(planes.data() + c), 3 * sizeof(half),
                                     3 * sizeof(half) * std::size_t(w)));
      file.setFrameBuffer(fb);
      file.writeTiles(0, file.numXTiles(level) - 1, 0, file.numYTiles(level) - 1, level);
    }
  }
}

// PLY: a mesh in each format (with normals and texture coordinates in one),
// and strands with an element to skip
void writePlySeeds(const fs::path& dir) {
  fs::create_directories(dir / "ply");
  const std::string header = "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                             "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
  writeFile(dir / "ply" / "quad_ascii.ply",
            "ply\nformat ascii 1.0\n" + header + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n4 0 2 3 1\n");
  for (const char* format : {"binary_little_endian", "binary_big_endian"}) {
    const bool big = std::string(format) == "binary_big_endian";
    std::string body;
    auto put = [&](const void* p, std::size_t n) {
      std::string b(static_cast<const char*>(p), n);
      if (big) b.assign(b.rbegin(), b.rend());
      body += b;
    };
    for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 1.f, 0.f, 0.f, 1.f, 0.f}) put(&v, 4);
    for (const std::vector<int>& f : {std::vector<int>{0, 1, 2}, std::vector<int>{0, 2, 3}}) {
      const auto n = std::uint8_t(f.size());
      put(&n, 1);
      for (int i : f) put(&i, 4);
    }
    writeFile(dir / "ply" / (std::string("quad_") + format + ".ply"), "ply\nformat " + std::string(format) + " 1.0\n" + header + body);
  }
  writeFile(dir / "ply" / "attributes.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
            "property float nx\nproperty float ny\nproperty float nz\nproperty float s\nproperty float t\n"
            "element face 1\nproperty list uchar uint vertex_index\nend_header\n"
            "0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n0 1 0 0 0 1 0 1\n3 0 1 2\n");
  writeFile(dir / "ply" / "strands.ply",
            "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
            "property float radius\nelement strand 2\nproperty ushort nsegs\nelement edge 1\nproperty int vertex1\n"
            "property int vertex2\nend_header\n0 0 0 0.1\n0 1 0 0.1\n0 2 0 0.1\n1 0 0 0.1\n1 1 0 0.1\n2\n1\n0 1\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUTDIR\n", argv[0]);
    return 2;
  }
  const fs::path dir = argv[1];
  try {
    writeGltfSeeds(dir);
    writeSceneFileSeeds(dir);
    writeHdrSeeds(dir);
    writeExrSeeds(dir);
    writePlySeeds(dir);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "wt_fuzz_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
