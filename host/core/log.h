// Diagnostics on stderr. Warnings are printed once per distinct text.
#pragma once

#include <string>

namespace wt::log {

void info(const std::string& message);
/// Only with setVerbose(true) (--verbose): timings and internals.
void debug(const std::string& message);
void setVerbose(bool verbose);
/// Print "warning: <message>" unless the same text was printed before.
void warnOnce(const std::string& message);
void error(const std::string& message);
/// Silence info (tests, --quiet); warnings and errors still print.
void setQuiet(bool quiet);

}  // namespace wt::log
