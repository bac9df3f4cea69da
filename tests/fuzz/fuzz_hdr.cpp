// libFuzzer harness: Radiance .hdr (RGBE) bytes through loadEnvironmentMapFromMemory.
// Every input must give a usable map (finite texels, valid cdfs) or throw an
// EnvironmentError naming the file.
#include "fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const unsigned char* data, std::size_t size) {
  const std::string name = "fuzz.hdr";
  try {
    wt::fuzz::checkEnvironment(wt::loadEnvironmentMapFromMemory({data, size}, name));
  } catch (const wt::EnvironmentError& e) {
    wt::fuzz::checkMessage(e.what(), name);
  }
  return 0;
}
