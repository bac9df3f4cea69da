// Kernel parameter lists declared once on the host and bound by name. A
// declaration is a type with the kernel's name and its parameters in order
// (the kernel-side macro groups as kGeometryParams, kSurfaceParams,
// kAlphaParams); KernelArgs<Decl> sets arguments by parameter name, checked
// at compile time against the declaration, and at start-up against the
// built kernel: its argument count always, and its argument names where the
// program keeps them (buildProgram passes -cl-kernel-arg-info;
// tests/contract/test_kernel_contract.cpp checks that it does). A parameter
// never set is an error at its first launch, naming kernel and parameter.
#pragma once

#include "device/context.h"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace wt {

/// Which builds of a kernel have a parameter: all of them, or those with a
/// feature compiled in (the kernel-side group exists only under its #if).
enum class ParamIf : std::uint8_t {
  Always,
  Alpha,  ///< WT_HAS_ALPHA (kernels/materials/alpha.cl, WT_ALPHA_PARAMS)
  ThinShadows,  ///< WT_HAS_THIN_SHADOWS (kernels/connect.cl, WT_THIN_SHADOW_PARAMS)
  QuadLights,   ///< WT_HAS_QUAD_LIGHTS (kernels/shade.cl, WT_QUAD_SHADE_PARAMS)
};

struct KernelParam {
  std::string_view name;  ///< as the kernel source spells it
  ParamIf when = ParamIf::Always;
};

/// The compiled-in features that decide which conditional parameters exist.
struct ParamFeatures {
  bool alpha = false;
  bool thinShadows = false;
  bool quadLights = false;
  bool has(ParamIf when) const {
    return when == ParamIf::Always || (when == ParamIf::Alpha && alpha) || (when == ParamIf::ThinShadows && thinShadows) ||
           (when == ParamIf::QuadLights && quadLights);
  }
};

/// Parameters present in every build, in order.
template <class... Names>
constexpr std::array<KernelParam, sizeof...(Names)> params(Names... names) {
  return {KernelParam{names, ParamIf::Always}...};
}

/// Several parameter lists one after another.
template <std::size_t... N>
constexpr std::array<KernelParam, (N + ...)> concatParams(const std::array<KernelParam, N>&... parts) {
  std::array<KernelParam, (N + ...)> out{};
  std::size_t at = 0;
  ((std::copy(parts.begin(), parts.end(), out.begin() + std::ptrdiff_t(at)), at += N), ...);
  return out;
}

/// The same parameters, present only with `when`.
template <std::size_t N>
constexpr std::array<KernelParam, N> paramsIf(ParamIf when, std::array<KernelParam, N> list) {
  for (KernelParam& p : list) p.when = when;
  return list;
}

/// WT_GEOMETRY_PARAMS (kernels/geometry/geometry.cl): the same names in the same order.
inline constexpr auto kGeometryParams = params("geometry", "prim_nodes", "prim_refs", "prim_data", "prim_info");
/// WT_SURFACE_PARAMS (kernels/materials/textured.cl).
inline constexpr auto kSurfaceParams = params("vertex_uv", "vertex_color", "vertex_tangent", "material_textures",
                                              "textures", "texture_levels", "texels");
/// WT_ALPHA_PARAMS (kernels/materials/alpha.cl): only with WT_HAS_ALPHA.
inline constexpr auto kAlphaParams =
    paramsIf(ParamIf::Alpha, concatParams(params("alpha_key", "alpha_bits", "alpha_tri_info", "alpha_materials"),
                                          kSurfaceParams));

/// The declaration's parameter named `name`, if any.
constexpr std::optional<std::size_t> findParam(std::span<const KernelParam> list, std::string_view name) {
  for (std::size_t i = 0; i < list.size(); ++i)
    if (list[i].name == name) return i;
  return std::nullopt;
}

/// What KernelArgs does without the declaration's type: check the built
/// kernel against the declaration, map parameters to argument positions and
/// remember which have been set.
class KernelBinding {
 public:
  KernelBinding() = default;
  /// Create `kernelName` from `program` and check it against `declared`
  /// (DeviceError naming the kernel and the first argument that differs).
  KernelBinding(const cl::Program& program, std::string_view kernelName, std::span<const KernelParam> declared,
                ParamFeatures features);

  cl::Kernel& kernel() { return m_kernel; }
  const std::string& name() const { return m_name; }
  /// Whether declared parameter `param` exists in this build.
  bool present(std::size_t param) const { return m_position[param] >= 0; }
  /// Throws DeviceError naming the first parameter never set.
  void requireBound() const;

  template <class T>
  void setParam(std::size_t param, const T& value) {
    m_kernel.setArg(cl_uint(position(param)), value);
    m_bound[param] = true;
  }

 private:
  int position(std::size_t param) const;
  cl::Kernel m_kernel;
  std::string m_name;
  std::span<const KernelParam> m_declared;
  std::vector<int> m_position;  ///< per declared parameter: its argument index, -1 if not in this build
  std::vector<bool> m_bound;
};

/// The argument names of a built kernel (empty optional: the program was
/// built without -cl-kernel-arg-info), and their type names (e.g. "float4*").
std::optional<std::vector<std::string>> kernelArgNames(const cl::Kernel& kernel);
std::optional<std::vector<std::string>> kernelArgTypeNames(const cl::Kernel& kernel);

/// One kernel bound through its declaration `Decl` (static kName, kParams).
template <class Decl>
class KernelArgs : public KernelBinding {
 public:
  /// A parameter of Decl: a name the declaration lacks does not compile.
  struct Name {
    consteval Name(const char* name) : index(lookup(name)) {}
    std::size_t index;

   private:
    static consteval std::size_t lookup(std::string_view name) {
      std::optional<std::size_t> i = findParam(Decl::kParams, name);
      if (!i) throw "not a parameter of this kernel's declaration";
      return *i;
    }
  };

  KernelArgs() = default;
  KernelArgs(const cl::Program& program, ParamFeatures features)
      : KernelBinding(program, Decl::kName, Decl::kParams, features) {}

  template <class T>
  KernelArgs& set(Name name, const T& value) {
    setParam(name.index, value);
    return *this;
  }
  /// Set `name` if the declaration has it and this build takes it (for
  /// binding a whole table of buffers by name, e.g. the path state).
  template <class T>
  bool setIfDeclared(std::string_view name, const T& value) {
    std::optional<std::size_t> i = findParam(Decl::kParams, name);
    if (!i || !present(*i)) return false;
    setParam(*i, value);
    return true;
  }
};

}  // namespace wt
