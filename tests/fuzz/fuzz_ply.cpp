// libFuzzer harness: PLY bytes through both PLY readers, the mesh reader
// (readPlyMesh) and the strand reader (loadPlyStrandsFromMemory). Every input
// must give an indexable mesh / consistent strands or throw a SceneError
// naming the file.
#include "fuzz_checks.h"

#include "scene/hair_loader.h"
#include "scene/ply.h"

extern "C" int LLVMFuzzerTestOneInput(const unsigned char* data, std::size_t size) {
  const std::string name = "fuzz.ply";
  try {
    const wt::PlyMesh mesh = wt::readPlyMesh({data, size}, name);
    WT_FUZZ_CHECK(mesh.normals.size() == mesh.positions.size(), "");
    WT_FUZZ_CHECK(mesh.texcoords.empty() || mesh.texcoords.size() == mesh.positions.size(), "");
    for (const auto& t : mesh.triangles)
      for (std::uint32_t v : t) WT_FUZZ_CHECK(v < mesh.positions.size(), "");
  } catch (const wt::SceneError& e) {
    wt::fuzz::checkMessage(e.what(), name);
  }
  try {
    const wt::StrandSet strands = wt::loadPlyStrandsFromMemory({data, size}, name);
    std::size_t points = 0;
    for (std::uint32_t c : strands.counts) points += c;
    WT_FUZZ_CHECK(points == strands.points.size(), "");
  } catch (const wt::SceneError& e) {
    wt::fuzz::checkMessage(e.what(), name);
  }
  return 0;
}
