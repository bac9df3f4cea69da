// Every struct host and kernels share has the same size and field offsets
// on both compilers (kernels/shared/layout.h lists them; kernels/layout_tests.cl
// reports the device's), and that list names every field the headers declare.
#include "device/program.h"
#include "device_fixture.h"
#include "shared/layout.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace wt {
namespace {

struct LayoutEntry {
  std::string what;  ///< "WtMaterial" (its size) or "WtMaterial.emission" (that field's offset)
  std::size_t host;
};

std::vector<LayoutEntry> hostLayout() {
  std::vector<LayoutEntry> out;
#define WT_LAYOUT_SIZE(T) out.push_back({#T, sizeof(T)});
#define WT_LAYOUT_OFFSET(T, field) out.push_back({#T "." #field, offsetof(T, field)});
  WT_SHARED_LAYOUT(WT_LAYOUT_SIZE, WT_LAYOUT_OFFSET)
#undef WT_LAYOUT_SIZE
#undef WT_LAYOUT_OFFSET
  return out;
}

TEST(SharedLayout, SizesAndOffsetsMatchTheDevice) {
  Context& ctx = test::deviceContext();
  const std::vector<LayoutEntry> host = hostLayout();
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, host.size() * sizeof(cl_uint));
  cl::Kernel k(test::testProgram("layout_tests.cl"), "layout_table");
  k.setArg(0, out);
  ctx.launch("layout_table", k, 1);
  std::vector<cl_uint> device(host.size());
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, device.size() * sizeof(cl_uint), device.data());
  for (std::size_t i = 0; i < host.size(); ++i)
    EXPECT_EQ(host[i].host, device[i]) << host[i].what << (host[i].what.find('.') == std::string::npos
                                                                ? ": size differs between host and device"
                                                                : ": offset differs between host and device");
}

/// The fields of every `typedef struct Wt... { ... } Wt...;` in `source`.
std::map<std::string, std::vector<std::string>> declaredFields(const std::string& source) {
  std::map<std::string, std::vector<std::string>> out;
  const std::regex structRe(R"(typedef struct (Wt\w+) \{([^}]*)\} \1;)");
  const std::regex fieldRe(R"(^\s*[A-Za-z_][\w ]*?\s+([\w\[\], ]+);)");
  for (auto it = std::sregex_iterator(source.begin(), source.end(), structRe); it != std::sregex_iterator(); ++it) {
    std::vector<std::string>& fields = out[(*it)[1]];
    std::istringstream body((*it)[2].str());
    for (std::string line; std::getline(body, line);) {
      line = line.substr(0, line.find("//"));
      std::smatch m;
      if (!std::regex_search(line, m, fieldRe)) continue;
      std::istringstream names(m[1].str());
      for (std::string name; std::getline(names, name, ',');) {
        name = std::regex_replace(name, std::regex(R"(\[.*\]|\s)"), "");
        fields.push_back(name);
      }
    }
  }
  return out;
}

TEST(SharedLayout, TheListNamesEveryFieldOfEverySharedStruct) {
  // layout_tests.cl includes shared/layout.h, which includes every header
  // with shared structs: its expanded source holds them all (the test
  // kernels are read from the source tree, which the device fixture names)
  test::deviceContext();
  const auto declared = declaredFields(expandKernelSource("layout_tests.cl"));
  ASSERT_GE(declared.size(), 10u) << "the struct parser found too few shared structs";
  std::map<std::string, std::vector<std::string>> listed;
#define WT_LAYOUT_SIZE(T) listed[#T];
#define WT_LAYOUT_OFFSET(T, field) listed[#T].push_back(#field);
  WT_SHARED_LAYOUT(WT_LAYOUT_SIZE, WT_LAYOUT_OFFSET)
#undef WT_LAYOUT_SIZE
#undef WT_LAYOUT_OFFSET
  for (const auto& [name, fields] : declared) {
    ASSERT_TRUE(listed.count(name)) << name << " is shared but missing from WT_SHARED_LAYOUT (kernels/shared/layout.h)";
    EXPECT_EQ(listed[name], fields) << name << ": WT_SHARED_LAYOUT must list its fields as declared";
  }
}

}  // namespace
}  // namespace wt
