// Curves on the host: B-splines subdivided into linear segments, and every
// segment's box and rows (kernels/geometry/curve.cl).
#include "geometry/primitives.h"

#include "core/spawn.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>

namespace wt {
namespace {

/// A joint of a linear curve: position and radius, and the curve's parameter there.
struct Joint {
  glm::dvec4 p;
  double u;
};

bool usable(const WtVec4& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(p.w) && p.w >= 0.0f;
}

glm::dvec4 toDouble(const WtVec4& p) { return {p.x, p.y, p.z, p.w}; }

/// Whether the cubic Bezier b (position and radius) is close enough to its
/// chord: each inner control point within `tolerance` of the chord's point
/// at the same parameter, which bounds the curve's distance from the chord
/// (its Bernstein weights sum to 1), radius included.
bool flatEnough(const glm::dvec4 b[4], double tolerance) {
  for (int i = 1; i <= 2; ++i) {
    const glm::dvec4 chord = b[0] + (b[3] - b[0]) * (double(i) / 3.0);
    if (glm::length(b[i] - chord) > tolerance) return false;
  }
  return true;
}

/// Append the end joints of the linear pieces of Bezier b over [u0, u1]
/// (not its start, which the joints before already hold).
void subdivide(const glm::dvec4 b[4], double u0, double u1, double tolerance, int depth, std::vector<Joint>& out) {
  if (depth == 0 || flatEnough(b, tolerance)) {
    out.push_back({b[3], u1});
    return;
  }
  // de Casteljau at the middle
  const glm::dvec4 ab = 0.5 * (b[0] + b[1]), bc = 0.5 * (b[1] + b[2]), cd = 0.5 * (b[2] + b[3]);
  const glm::dvec4 abc = 0.5 * (ab + bc), bcd = 0.5 * (bc + cd), mid = 0.5 * (abc + bcd);
  const glm::dvec4 left[4] = {b[0], ab, abc, mid}, right[4] = {mid, bcd, cd, b[3]};
  const double um = 0.5 * (u0 + u1);
  subdivide(left, u0, um, tolerance, depth - 1, out);
  subdivide(right, um, u1, tolerance, depth - 1, out);
}

/// Writes one curve's runs of joints as segments.
class SegmentWriter {
 public:
  SegmentWriter(PrimitiveRows& rows, std::uint32_t curve, std::uint32_t material)
      : m_rows(rows), m_curve(curve), m_material(material) {}

  /// A segment counted but left out (a point it needs is unusable).
  void skip() {
    ++m_rows.count[WT_PRIM_CURVE];
    ++m_rows.skipped;
  }

  /// The run's joints as segments between consecutive ones: coincident
  /// joints merged, segments of radius 0 at both ends left out, and each
  /// segment told whether its neighbours were kept.
  void write(const std::vector<Joint>& run) {
    m_joints.clear();
    for (const Joint& j : run) {
      const glm::vec4 p(j.p);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !std::isfinite(p.w)) {
        // beyond float range: a break, as an unusable point is
        flush();
        ++m_rows.count[WT_PRIM_CURVE];
        ++m_rows.skipped;
        continue;
      }
      if (!m_joints.empty() && glm::vec3(m_joints.back().p) == glm::vec3(p)) {
        m_joints.back().p.w = std::max(m_joints.back().p.w, p.w);
        continue;
      }
      m_joints.push_back({glm::vec4(glm::vec3(p), std::max(p.w, 0.0f)), float(j.u)});
    }
    flush();
  }

 private:
  struct FloatJoint {
    glm::vec4 p;
    float u;
  };

  void flush() {
    const std::size_t n = m_joints.size();
    auto kept = [&](std::size_t j) { return m_joints[j].p.w > 0.0f || m_joints[j + 1].p.w > 0.0f; };
    for (std::size_t j = 0; j + 1 < n; ++j) {
      ++m_rows.count[WT_PRIM_CURVE];
      if (!kept(j)) {
        ++m_rows.skipped;
        continue;
      }
      const bool left = j > 0 && kept(j - 1), right = j + 2 < n && kept(j + 1);
      const glm::vec4 a = m_joints[j].p, b = m_joints[j + 1].p;
      const auto index = std::uint32_t(m_rows.info.size() - m_rows.infoFirst[WT_PRIM_CURVE]);
      // the sign bit of a radius says the curve ends at that joint (-0 for radius 0)
      m_rows.data.push_back({a.x, a.y, a.z, std::copysign(a.w, left ? 1.0f : -1.0f)});
      m_rows.data.push_back({b.x, b.y, b.z, std::copysign(b.w, right ? 1.0f : -1.0f)});
      m_rows.info.push_back({m_material, m_curve, std::bit_cast<std::uint32_t>(m_joints[j].u),
                             std::bit_cast<std::uint32_t>(m_joints[j + 1].u)});
      Aabb box;
      for (const glm::vec4& s : {a, b}) {
        // the box's float corners may round inside the sphere: widen by an ulp or so
        const glm::vec3 reach = glm::vec3(s.w) + 4.8e-7f * (glm::abs(glm::vec3(s)) + glm::vec3(s.w));
        box.extend(glm::vec3(s) - reach);
        box.extend(glm::vec3(s) + reach);
      }
      m_rows.bounds.push_back(box);
      m_rows.ids.push_back(primId(WT_PRIM_CURVE, index));
    }
    m_joints.clear();
  }

  PrimitiveRows& m_rows;
  std::uint32_t m_curve, m_material;
  std::vector<FloatJoint> m_joints;
};

void gatherLinear(const Scene& scene, const Curve& curve, SegmentWriter& writer) {
  std::vector<Joint> run;
  const double last = std::max<double>(curve.pointCount - 1, 1);
  for (std::uint32_t i = 0; i < curve.pointCount; ++i) {
    const WtVec4& p = scene.curvePoints[curve.firstPoint + i];
    if (usable(p)) {
      run.push_back({toDouble(p), double(i) / last});
      continue;
    }
    // the segments on either side of an unusable point are left out
    if (i > 0) writer.skip();
    if (i + 1 < curve.pointCount && usable(scene.curvePoints[curve.firstPoint + i + 1])) writer.skip();
    writer.write(run);
    run.clear();
  }
  writer.write(run);
}

void gatherBSpline(const Scene& scene, const Curve& curve, SegmentWriter& writer) {
  if (curve.pointCount < 4) return;
  const std::uint32_t segments = curve.pointCount - 3;
  std::vector<Joint> run;
  for (std::uint32_t i = 0; i < segments; ++i) {
    const WtVec4* c = &scene.curvePoints[curve.firstPoint + i];
    if (!usable(c[0]) || !usable(c[1]) || !usable(c[2]) || !usable(c[3])) {
      writer.skip();
      writer.write(run);
      run.clear();
      continue;
    }
    const glm::dvec4 p0 = toDouble(c[0]), p1 = toDouble(c[1]), p2 = toDouble(c[2]), p3 = toDouble(c[3]);
    // the uniform B-spline segment as a Bezier segment
    const glm::dvec4 b[4] = {(p0 + 4.0 * p1 + p2) / 6.0, (2.0 * p1 + p2) / 3.0, (p1 + 2.0 * p2) / 3.0,
                             (p1 + 4.0 * p2 + p3) / 6.0};
    const double u0 = double(i) / segments, u1 = double(i + 1) / segments;
    if (run.empty()) run.push_back({b[0], u0});
    // flat to a fraction of the thinnest radius, and never finer than the
    // spline's own size needs (radius 0)
    double rMin = std::min(std::min(b[0].w, b[1].w), std::min(b[2].w, b[3].w));
    double extent = glm::length(glm::dvec3(b[1] - b[0])) + glm::length(glm::dvec3(b[2] - b[1])) +
                    glm::length(glm::dvec3(b[3] - b[2]));
    subdivide(b, u0, u1, std::max(kCurveFlatness * std::max(rMin, 0.0), 1e-4 * extent), kCurveMaxDepth, run);
  }
  writer.write(run);
}

}  // namespace

void gatherCurves(const Scene& scene, PrimitiveRows& rows) {
  // a segment's two rows in one 32-byte block
  if (!scene.curves.empty() && rows.data.size() % 2 != 0) rows.data.push_back({0.0f, 0.0f, 0.0f, 0.0f});
  rows.dataFirst[WT_PRIM_CURVE] = std::uint32_t(rows.data.size());
  rows.infoFirst[WT_PRIM_CURVE] = std::uint32_t(rows.info.size());
  rows.count[WT_PRIM_CURVE] = 0;
  rows.curveSegments.clear();
  for (std::size_t i = 0; i < scene.curves.size(); ++i) {
    const Curve& curve = scene.curves[i];
    rows.curveSegments.push_back(std::uint32_t(rows.info.size() - rows.infoFirst[WT_PRIM_CURVE]));
    SegmentWriter writer(rows, std::uint32_t(i), curve.material);
    if (curve.basis == CurveBasis::kBSpline)
      gatherBSpline(scene, curve, writer);
    else
      gatherLinear(scene, curve, writer);
  }
  rows.curveSegments.push_back(std::uint32_t(rows.info.size() - rows.infoFirst[WT_PRIM_CURVE]));
}

CurveSegment curveSegment(const PrimitiveRows& rows, std::uint32_t index) {
  const WtVec4& a = rows.data[rows.dataFirst[WT_PRIM_CURVE] + 2 * std::size_t(index)];
  const WtVec4& b = rows.data[rows.dataFirst[WT_PRIM_CURVE] + 2 * std::size_t(index) + 1];
  const auto& info = rows.info[rows.infoFirst[WT_PRIM_CURVE] + index];
  CurveSegment s;
  s.p0 = {a.x, a.y, a.z, std::fabs(a.w)};
  s.p1 = {b.x, b.y, b.z, std::fabs(b.w)};
  s.left = !std::signbit(a.w);
  s.right = !std::signbit(b.w);
  s.material = info[0];
  s.curve = info[1];
  s.u0 = std::bit_cast<float>(info[2]);
  s.u1 = std::bit_cast<float>(info[3]);
  return s;
}

double curveSegmentArea(const Scene&, const PrimitiveRows& rows, std::uint32_t index) {
  const CurveSegment c = curveSegment(rows, index);
  const double r0 = c.p0.w, r1 = c.p1.w;
  const double length = glm::length(glm::dvec3(c.p1) - glm::dvec3(c.p0));
  return std::numbers::pi * (r0 + r1) * std::sqrt(length * length + (r1 - r0) * (r1 - r0));
}

glm::vec3 curvePoint(const CurveSegment& segment, glm::vec3 o, glm::vec3 d, float t, glm::vec3* error,
                     glm::vec3* normal) {
  // curve_sphere_param and curve_surface, operation for operation
  const glm::vec3 a(segment.p0), e = glm::vec3(segment.p1) - a;
  const float dr = segment.p1.w - segment.p0.w;
  const glm::vec3 h = o + t * d - a;
  const float l2 = glm::dot(e, e), g = l2 - dr * dr;
  float s = dr > 0.0f ? 1.0f : 0.0f;
  if (g > 0.0f) {
    const float sg = std::sqrt(g);
    s = std::clamp((glm::dot(h, e) * sg + dr * glm::length(glm::cross(h, e))) / (l2 * sg), 0.0f, 1.0f);
  }
  const glm::vec3 along = s * e, v = h - along;
  const float len = glm::length(v);
  if (len > 0.0f) {
    *normal = v / len;
  } else {
    // on the axis: any direction across it
    const glm::vec3 axis = glm::normalize(e);
    const glm::vec3 other = std::fabs(axis.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    *normal = glm::normalize(glm::cross(axis, other));
  }
  const glm::vec3 rel = (segment.p0.w + s * dr) * *normal;
  const glm::vec3 p = a + (along + rel);
  *error = spawn_gamma(6) * (glm::abs(along) + glm::abs(rel)) + spawn_gamma(3) * (glm::abs(a) + glm::abs(p));
  return p;
}

}  // namespace wt
