// libFuzzer harness: binary glTF through loadGlbFromMemory (the path loadGltf
// takes for a .glb file). Every input must load into a consistent scene or
// throw a SceneError naming the file.
#include "fuzz_checks.h"
#include "scene/gltf_loader.h"

extern "C" int LLVMFuzzerTestOneInput(const unsigned char* data, std::size_t size) {
  const std::string name = "fuzz.glb";
  try {
    wt::fuzz::checkScene(wt::loadGlbFromMemory({data, size}, name, wt::fuzz::emptyBaseDir()));
  } catch (const wt::SceneError& e) {
    wt::fuzz::checkMessage(e.what(), name);
  }
  return 0;
}
