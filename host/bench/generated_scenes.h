// Scenes the bench makes in code that the traversal choice (chooseTraversal,
// host/device/tracer.h) was never tuned on: each stresses a different ray
// property (origin spread against triangle size, direction spread, shadow
// length, instancing). Deterministic: the same scene on every run and host.
#pragma once

#include "scene/scene.h"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace wt {

/// The names `wavetrace bench gen:NAME` takes, in the order `gen:all` runs them.
const std::vector<std::string>& generatedSceneNames();

/// The scene for a name of generatedSceneNames() (without "gen:"); nullopt
/// for any other name. `triangles` sets the size of the large ones (the
/// displaced sphere rounds it to a subdivision level, the soup takes it as is).
std::optional<Scene> makeGeneratedScene(std::string_view name, std::uint32_t triangles);

/// `count` random triangles (edges up to 0.05) in the unit cube, one small
/// emissive quad above it: shadow rays point nearly one way but cross a
/// soup with no surface structure.
Scene makeLitSoup(std::uint32_t count, std::uint32_t seed = 7);

/// An icosphere of 20 4^s triangles (s the smallest level reaching
/// `triangles`, at most 9), its vertices moved along the normal by 4 octaves
/// of value noise (amplitude 0.08 of the radius), lit by one small quad
/// (0.3 x 0.3 at distance 3): neighbouring pixels' shadow rays leave points
/// several triangles apart towards one small target.
Scene makeDisplacedSphere(std::uint32_t triangles, std::uint32_t seed = 3);

/// `trees` copies (placeCopies) of one tree mesh (a displaced crown of 1280
/// triangles on a box trunk), scaled and turned at random on a 40 x 40
/// ground, and one small quad high above as the sun.
Scene makeForest(std::uint32_t trees = 600, std::uint32_t seed = 5);

/// A floor and 300 random boxes under a ceiling of `lights` small emissive
/// quads: each shadow ray goes to a light picked by area, so neighbouring
/// pixels' shadow rays point different ways.
Scene makeManyLights(std::uint32_t lights = 400, std::uint32_t seed = 11);

}  // namespace wt
