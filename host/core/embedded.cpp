#include "core/embedded.h"

namespace wt::embedded {

std::optional<std::string_view> find(std::string_view path) {
  for (const File& f : files())
    if (f.path == path) return f.contents;
  return std::nullopt;
}

std::filesystem::path sourceDirectory() { return WT_SOURCE_DIR; }

}  // namespace wt::embedded
