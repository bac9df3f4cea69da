#include "render/light_tree.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace wt {
namespace {

constexpr double kPi = std::numbers::pi;

/// A cone of directions: unit axis and half-angle (pi: every direction).
struct Cone {
  glm::dvec3 axis{0.0, 0.0, 1.0};
  double theta = -1.0;  ///< < 0: empty
  bool empty() const { return theta < 0.0; }
};

double angleBetween(glm::dvec3 a, glm::dvec3 b) {
  // robust for nearly parallel and antiparallel vectors
  return 2.0 * std::atan2(glm::length(a - b), glm::length(a + b));
}

/// The smallest cone holding both (pbrt-v4's DirectionCone union).
Cone merge(const Cone& a, const Cone& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  if (a.theta >= kPi || b.theta >= kPi) return {a.axis, kPi};
  double d = angleBetween(a.axis, b.axis);
  if (std::min(d + b.theta, kPi) <= a.theta) return a;
  if (std::min(d + a.theta, kPi) <= b.theta) return b;
  double theta = 0.5 * (a.theta + d + b.theta);
  if (theta >= kPi) return {a.axis, kPi};
  glm::dvec3 w = glm::cross(a.axis, b.axis);
  if (glm::length(w) < 1e-12) return {a.axis, kPi};
  // turn a's axis towards b's by theta - a.theta (Rodrigues)
  w = glm::normalize(w);
  double r = theta - a.theta;
  glm::dvec3 axis = a.axis * std::cos(r) + glm::cross(w, a.axis) * std::sin(r) + w * glm::dot(w, a.axis) * (1.0 - std::cos(r));
  return {glm::normalize(axis), theta};
}

struct Box {
  glm::dvec3 lo{INFINITY}, hi{-INFINITY};
  void extend(glm::dvec3 p) { lo = glm::min(lo, p), hi = glm::max(hi, p); }
  void extend(const Box& b) { lo = glm::min(lo, b.lo), hi = glm::max(hi, b.hi); }
  double area() const {
    if (lo.x > hi.x) return 0.0;
    glm::dvec3 e = hi - lo;
    return 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
  }
};

struct Item {
  Box box;
  glm::dvec3 centroid;
  Cone cone;
  double power;
  std::size_t emitter;
};

/// Conty Estevez and Kulla's orientation measure of a cone of normals
/// (theta_o) spreading Lambertian emission (theta_e = pi/2).
double orientationMeasure(const Cone& c) {
  double to = std::clamp(c.theta, 0.0, kPi), tw = std::min(to + 0.5 * kPi, kPi);
  return 2.0 * kPi * (1.0 - std::cos(to)) +
         0.5 * kPi * (2.0 * tw * std::sin(to) - std::cos(to - 2.0 * tw) - 2.0 * to * std::sin(to) + std::cos(to));
}

class Builder {
 public:
  explicit Builder(std::vector<Item>& items) : m_items(items) {}

  std::vector<WtLightNode> nodes;

  /// Fill node `index` with items [begin, end); children go to the end.
  void build(std::uint32_t index, std::size_t begin, std::size_t end, std::uint32_t parent) {
    Box box;
    Cone cone;
    double power = 0.0;
    for (std::size_t i = begin; i < end; ++i) box.extend(m_items[i].box), cone = merge(cone, m_items[i].cone), power += m_items[i].power;
    WtLightNode& n = nodes[index];
    n = WtLightNode{};
    n.lo_x = float(box.lo.x), n.lo_y = float(box.lo.y), n.lo_z = float(box.lo.z);
    n.hi_x = float(box.hi.x), n.hi_y = float(box.hi.y), n.hi_z = float(box.hi.z);
    n.power = float(power);
    n.axis_x = float(cone.axis.x), n.axis_y = float(cone.axis.y), n.axis_z = float(cone.axis.z);
    // rounding to float may only widen the cone
    n.cos_theta_o = cone.theta >= kPi ? -1.0f : std::nextafter(float(std::cos(cone.theta)), -1.0f);
    n.sin_theta_o = float(std::sqrt(std::max(0.0, 1.0 - double(n.cos_theta_o) * double(n.cos_theta_o))));
    // of the bounds as stored, as the importance's r^2 is
    const glm::dvec3 diagonal(double(n.hi_x) - n.lo_x, double(n.hi_y) - n.lo_y, double(n.hi_z) - n.lo_z);
    n.radius = float(0.5 * glm::length(diagonal));
    n.parent = parent;
    if (end - begin == 1) {
      n.leaf = 1;
      n.child = std::uint32_t(m_items[begin].emitter);
      return;
    }
    std::size_t mid = split(begin, end, box);
    std::uint32_t child = std::uint32_t(nodes.size());
    nodes.resize(nodes.size() + 2);
    nodes[index].child = child;
    build(child, begin, mid, index);
    build(child + 1, mid, end, index);
  }

 private:
  /// The binned surface-area-orientation heuristic (12 buckets per axis);
  /// the middle when every centroid is the same.
  std::size_t split(std::size_t begin, std::size_t end, const Box& box) {
    Box centroids;
    for (std::size_t i = begin; i < end; ++i) centroids.extend(m_items[i].centroid);
    glm::dvec3 extent = centroids.hi - centroids.lo;
    const double boxMax = std::max({box.hi.x - box.lo.x, box.hi.y - box.lo.y, box.hi.z - box.lo.z});
    constexpr int kBuckets = 12;
    double best = INFINITY;
    int bestAxis = -1, bestBucket = 0;
    for (int axis = 0; axis < 3; ++axis) {
      if (!(extent[axis] > 0.0)) continue;
      struct Bucket {
        Box box;
        Cone cone;
        double power = 0.0;
        std::size_t count = 0;
      };
      std::array<Bucket, kBuckets> buckets;
      auto bucketOf = [&](const Item& it) {
        int b = int(kBuckets * (it.centroid[axis] - centroids.lo[axis]) / extent[axis]);
        return std::clamp(b, 0, kBuckets - 1);
      };
      for (std::size_t i = begin; i < end; ++i) {
        Bucket& b = buckets[std::size_t(bucketOf(m_items[i]))];
        b.box.extend(m_items[i].box), b.cone = merge(b.cone, m_items[i].cone), b.power += m_items[i].power, ++b.count;
      }
      // a long, thin box is a poor bound: regularise by its aspect along the axis
      const double regular = boxMax / std::max(box.hi[axis] - box.lo[axis], 1e-300);
      for (int s = 1; s < kBuckets; ++s) {
        Bucket left, right;
        for (int b = 0; b < s; ++b)
          left.box.extend(buckets[b].box), left.cone = merge(left.cone, buckets[b].cone), left.power += buckets[b].power, left.count += buckets[b].count;
        for (int b = s; b < kBuckets; ++b)
          right.box.extend(buckets[b].box), right.cone = merge(right.cone, buckets[b].cone), right.power += buckets[b].power, right.count += buckets[b].count;
        if (left.count == 0 || right.count == 0) continue;
        double cost = regular * (left.power * orientationMeasure(left.cone) * left.box.area() +
                                 right.power * orientationMeasure(right.cone) * right.box.area());
        if (cost < best) best = cost, bestAxis = axis, bestBucket = s;
      }
    }
    if (bestAxis < 0) return begin + (end - begin) / 2;
    auto first = m_items.begin() + std::ptrdiff_t(begin), last = m_items.begin() + std::ptrdiff_t(end);
    auto mid = std::partition(first, last, [&](const Item& it) {
      int b = int(kBuckets * (it.centroid[bestAxis] - centroids.lo[bestAxis]) / extent[bestAxis]);
      return std::clamp(b, 0, kBuckets - 1) < bestBucket;
    });
    std::size_t m = std::size_t(mid - m_items.begin());
    return (m == begin || m == end) ? begin + (end - begin) / 2 : m;
  }

  std::vector<Item>& m_items;
};

}  // namespace

LightTree buildLightTree(std::span<const LightTreeEmitter> emitters) {
  LightTree tree;
  tree.leafOfEmitter.assign(emitters.size(), WT_LIGHT_NODE_NONE);
  std::vector<Item> items;
  for (std::size_t i = 0; i < emitters.size(); ++i) {
    const LightTreeEmitter& e = emitters[i];
    if (!(e.power > 0.0)) continue;
    Item it;
    for (glm::vec3 p : {e.p0, e.p1, e.p2}) it.box.extend(glm::dvec3(p));
    it.centroid = (glm::dvec3(e.p0) + glm::dvec3(e.p1) + glm::dvec3(e.p2)) / 3.0;
    if (e.quad) {
      it.box.extend(glm::dvec3(e.p3));
      it.centroid = 0.25 * (glm::dvec3(e.p0) + glm::dvec3(e.p1) + glm::dvec3(e.p2) + glm::dvec3(e.p3));
    }
    glm::dvec3 n = glm::cross(glm::dvec3(e.p1) - glm::dvec3(e.p0), glm::dvec3(e.p2) - glm::dvec3(e.p0));
    if (!(glm::length(n) > 0.0)) continue;
    it.cone = {glm::normalize(n), e.twoSided ? kPi : 0.0};
    it.power = e.power;
    it.emitter = i;
    items.push_back(it);
  }
  if (items.empty()) return tree;
  Builder builder(items);
  builder.nodes.resize(1);
  builder.nodes.reserve(2 * items.size());
  builder.build(0, 0, items.size(), WT_LIGHT_NODE_NONE);
  tree.nodes = std::move(builder.nodes);
  // leaves hold emitter indices while building; map them back, then to light indices
  for (std::uint32_t k = 0; k < tree.nodes.size(); ++k)
    if (tree.nodes[k].leaf) {
      std::size_t emitter = tree.nodes[k].child;
      tree.leafOfEmitter[emitter] = k;
      tree.nodes[k].child = emitters[emitter].light;
    }
  return tree;
}

}  // namespace wt
