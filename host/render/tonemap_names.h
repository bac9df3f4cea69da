// The tone mapping operators by name (--tonemap, scene files' "tonemap"),
// in WT_TONEMAP_* order; header-only so the scene-file reader needs no device code.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace wt {

inline constexpr std::array<std::string_view, 8> kTonemapOperatorNames = {
    "linear", "reinhard", "reinhard-modified", "hable", "aces", "aces-narkowicz", "agx", "pbr-neutral"};

/// WT_TONEMAP_* for a name, none if unknown.
inline std::optional<std::uint32_t> parseTonemapOperator(std::string_view name) {
  for (std::size_t i = 0; i < kTonemapOperatorNames.size(); ++i)
    if (kTonemapOperatorNames[i] == name) return std::uint32_t(i);
  return std::nullopt;
}

inline std::string tonemapOperatorName(std::uint32_t op) {
  return op < kTonemapOperatorNames.size() ? std::string(kTonemapOperatorNames[op]) : "?";
}

/// "linear, reinhard, ..." for help texts and errors.
inline std::string tonemapOperatorList() {
  std::string list;
  for (std::string_view n : kTonemapOperatorNames) list += (list.empty() ? "" : ", ") + std::string(n);
  return list;
}

}  // namespace wt
