#include "core/log.h"

#include <cstdio>
#include <mutex>
#include <set>

namespace wt::log {
namespace {
std::mutex g_mutex;
std::set<std::string> g_warned;
bool g_quiet = false;
bool g_verbose = false;
}  // namespace

void info(const std::string& message) {
  if (g_quiet) return;
  std::fprintf(stderr, "%s\n", message.c_str());
}

void debug(const std::string& message) {
  if (g_verbose) std::fprintf(stderr, "%s\n", message.c_str());
}

void setVerbose(bool verbose) { g_verbose = verbose; }

void warnOnce(const std::string& message) {
  std::lock_guard lock(g_mutex);
  if (!g_warned.insert(message).second) return;
  std::fprintf(stderr, "warning: %s\n", message.c_str());
}

void error(const std::string& message) { std::fprintf(stderr, "error: %s\n", message.c_str()); }

void setQuiet(bool quiet) { g_quiet = quiet; }

}  // namespace wt::log
