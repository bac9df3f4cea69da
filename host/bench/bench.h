// `wavetrace bench`: BVH build figures, and three standard ray sets (camera,
// diffuse, shadow) traced by wavetrace and, when the build has Embree, by
// Embree on the same rays, with throughput ratios and hit agreement. Output
// is a table or JSON. Timings belong here, never in tests.
#pragma once

#include <string>
#include <vector>

namespace wt {

struct BenchOptions {
  std::vector<std::string> scenes;  ///< files; empty: the default set (see runBench)
  std::string device;               ///< --device spec
  std::string assetsDir;            ///< --assets; empty: look for ../shared/assets (source dir, then cwd)
  bool json = false;
  int primaryWidth = 1024;          ///< primary ray set is width x width
  int pathWidth = 256;              ///< path rays: a render of pathWidth^2 pixels
  int pathSamples = 4;
  int repetitions = 5;              ///< median of this many timed runs after a warm-up (at least)
  /// Each tracer's timed runs of a ray set (wavetrace's, each Embree API's)
  /// go on past `repetitions` while they add up to less than this many
  /// seconds (20 runs per repetition at most), so that a stall of a few
  /// tens of milliseconds cannot move the median of a set that traces in a
  /// few milliseconds.
  double minSeconds = 0.5;
  int meshTriangles = 1000000;      ///< size of the generated mesh
  /// > 0: a scene with displaced meshes gains a row, the same meshes
  /// pre-tessellated into this many triangles per base edge (tessellateDisplaced)
  int tessellate = 0;
  int sphereCount = 100000;         ///< spheres of the generated sphere field (makeSphereField); 0: none
  int hairGuides = 100;             ///< guide strands of the generated head of hair (makeHairScene), 100 children each; 0: none
  /// single, packet8, packet16, stream (host/bench/embree_reference.h), or
  /// fastest: every set traced with all four, compared with the fastest
  std::string embreeApi = "fastest";
  int embreeQuality = 2;            ///< RTC_BUILD_QUALITY_: 0 low, 1 medium, 2 high
  bool embreeRobust = false;        ///< RTC_SCENE_FLAG_ROBUST
  std::string bvh = "auto";         ///< the tree compared with Embree and rendering the path figure
  /// --instancing: off, on, auto (Instancing, SceneBuffers). Off by default:
  /// Embree traces the flattened copies, so the ratios compare traversal of
  /// one geometry; `render` defaults to auto.
  std::string instancing = "off";
  /// Builders whose trees are built (median of repetitions) and traced on
  /// the same rays, interleaved, for the tree-quality table; "none" skips it.
  std::vector<std::string> compareBvh{"auto", "lbvh", "ploc", "sah"};
  /// "general": the path figure also renders with the general program (every
  /// switch on), samples interleaved, for the specialisation table; "none" skips it.
  std::string compareProgram = "general";
  /// single, packet, stream or auto: packets (Traversal::kPacket) for the
  /// sets whose packets' rays point nearly the same way (camera rays, shadow
  /// rays to one small light), streams (Traversal::kStream) for the other
  /// any-hit sets on a CPU, one ray per work-item for the rest.
  std::string traversal = "auto";
  int packetWidth = 0;    ///< rays per packet, 8 or 16; 0: by the device (packetWidthFor)
  int maxLeafSize = 0;    ///< the 4-wide leaf limit of every tree (0: kBvh4MaxLeafSize, as the renderer; bvh4Options)
  int plocRadius = 16;    ///< BvhBuildOptions::plocRadius for every ploc tree
  int plocTopPrims = 16;  ///< BvhBuildOptions::plocTopPrims for every ploc tree
  /// Kernel development: one more row in the tree comparison, the --bvh tree
  /// traced by the kernels in this folder (as --kernel-dir), taking turns
  /// with the others in one process; empty: none.
  std::string abKernelDir;
  /// Kernel development: one more row in the tree comparison, the --bvh tree
  /// traced in packets of this many rays (8 or 16) instead of packetWidth,
  /// with --ab-kernel-dir's kernels if given; 0: none.
  int abPacketWidth = 0;
  /// Kernel development: a row in the tree comparison per entry, the --bvh
  /// tree with every set traced this way (single, packet, stream; as
  /// --traversal); empty: none.
  std::vector<std::string> abTraversal;
};

/// Run the benchmark and print the results to stdout. Returns an exit code.
/// Default scenes: the built-in Cornell box; MetalRoughSpheresNoTextures and
/// DamagedHelmet from the asset folder (skipped, saying so, when absent); a
/// generated height field of meshTriangles triangles; a generated field of
/// sphereCount spheres; a generated head of hair of hairGuides x 101 strands.
int runBench(const BenchOptions& options);

}  // namespace wt
