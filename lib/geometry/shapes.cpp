// The free functions of shapes.hpp: each asks the shape's family (shape_family.hpp);
// overlap tests combine what the two families answer (3D: shapes3.cpp).
#include "geometry/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "geometry/predicates2.hpp"
#include "geometry/shape_family.hpp"
#include "geometry/shapes_detail.hpp"

namespace cisamr::geometry {
namespace detail {

Box3 points_box(const std::vector<Vec2>& pts) {
  Box3 b{{pts[0][0], pts[0][1], 0}, {pts[0][0], pts[0][1], 0}};
  for (const Vec2& q : pts)
    for (int k = 0; k < 2; ++k) {
      b.min[k] = std::min(b.min[k], q[k]);
      b.max[k] = std::max(b.max[k], q[k]);
    }
  return b;
}

std::vector<Vec3> resampled_ring(const std::vector<Vec2>& v, double spacing) {
  std::vector<Vec3> out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const Vec2& a = v[i];
    const Vec2& b = v[(i + 1) % v.size()];
    const int n = std::max(1, static_cast<int>(std::ceil(std::hypot(b[0] - a[0], b[1] - a[1]) / spacing)));
    for (int k = 0; k < n; ++k) out.push_back({a[0] + (b[0] - a[0]) * k / n, a[1] + (b[1] - a[1]) * k / n, 0});
  }
  return out;
}

namespace {
double segment_distance(const Vec2& p, const Vec2& u, const Vec2& v) {
  const double dx = v[0] - u[0], dy = v[1] - u[1], dd = dx * dx + dy * dy;
  const double t = dd > 0 ? std::clamp(((p[0] - u[0]) * dx + (p[1] - u[1]) * dy) / dd, 0.0, 1.0) : 0.0;
  return std::hypot(p[0] - u[0] - t * dx, p[1] - u[1] - t * dy);
}
}  // namespace

double segments_distance(const Vec2& p0, const Vec2& p1, const Vec2& q0, const Vec2& q1) {
  return std::min({segment_distance(p0, q0, q1), segment_distance(p1, q0, q1), segment_distance(q0, p0, p1),
                   segment_distance(q1, p0, p1)});
}

}  // namespace detail

namespace {

std::vector<Vec2> boundary_polyline(const Shape& s, double spacing) {
  std::vector<Vec2> out;
  for (const Vec3& q : shape_family(s).boundary_samples(s, spacing)) out.push_back({q[0], q[1]});
  return out;
}

}  // namespace

int shape_dimension(const Shape& s) { return shape_family(s).dimension(); }

Box3 shape_bounding_box(const Shape& s) { return shape_family(s).bounding_box(s); }

Box3 shape_holding_box(const Shape& s) { return shape_family(s).holding_box(s); }

bool shape_judged_by_box(const Shape& s) { return shape_family(s).judged_by_box(); }

double shape_measure(const Shape& s) { return shape_family(s).measure(s); }

double shape_boundary_measure(const Shape& s) { return shape_family(s).boundary_measure(s); }

void shape_boundary_samples_within(const Shape& s, double spacing, const Box3& clip, std::vector<Vec3>& points,
                                   std::vector<double>& areas) {
  if (!(spacing > 0)) throw std::invalid_argument("shape_boundary_samples_within: spacing must be positive");
  if (shape_dimension(s) != 3) throw std::invalid_argument("shape_boundary_samples_within: a 2D shape");
  shape_family(s).boundary_samples_within(s, spacing, clip, points, areas);
}

std::vector<Vec3> shape_boundary_samples(const Shape& s, double spacing) {
  if (!(spacing > 0)) throw std::invalid_argument("shape_boundary_samples: spacing must be positive");
  return shape_family(s).boundary_samples(s, spacing);
}

bool shape_contains(const Shape& s, const Vec3& p) { return shape_family(s).contains(s, p); }

bool shapes_overlap(const Shape& a, const Shape& b, double gap) {
  if (shape_dimension(a) != shape_dimension(b)) throw std::invalid_argument("shapes_overlap: mixed dimensions");
  if (shape_dimension(a) == 3) return detail::overlap3(a, b, gap);
  const Box3 ba = shape_bounding_box(a), bb = shape_bounding_box(b);
  for (int k = 0; k < 2; ++k)
    if (ba.max[k] + gap < bb.min[k] || bb.max[k] + gap < ba.min[k]) return false;
  const ShapeFamily& fa = shape_family(a);
  const ShapeFamily& fb = shape_family(b);
  if (&fa == &fb)
    if (const std::optional<bool> exact = fa.overlap_same_family(a, b, gap)) return *exact;
  // Convex pairs: they are apart by more than gap iff some direction d separates them,
  // h_a(d) + h_b(−d) < −gap. Search d on the circle: sampling, then golden section. The
  // answer is whether the least value found is ≥ −gap, so the first value below −gap
  // settles it: most apart pairs stop within the samples.
  if (fa.convex(a) && fb.convex(b)) {
    auto g = [&](double ang) {
      const Vec3 d{std::cos(ang), std::sin(ang), 0};
      return fa.support(a, d) + fb.support(b, Vec3{-d[0], -d[1], 0});
    };
    const int n = 720;
    double best = std::numeric_limits<double>::infinity();
    int arg = 0;
    for (int i = 0; i < n; ++i) {
      const double v = g(2 * M_PI * i / n);
      if (v < -gap) return false;
      if (v < best) best = v, arg = i;
    }
    double lo = 2 * M_PI * (arg - 1) / n, hi = 2 * M_PI * (arg + 1) / n;
    const double phi = 0.5 * (std::sqrt(5.0) - 1);
    double x1 = hi - phi * (hi - lo), x2 = lo + phi * (hi - lo), f1 = g(x1), f2 = g(x2);
    for (int it = 0; it < 80; ++it) {
      if (f1 < -gap || f2 < -gap) return false;
      if (f1 < f2) hi = x2, x2 = x1, f2 = f1, x1 = hi - phi * (hi - lo), f1 = g(x1);
      else lo = x1, x1 = x2, f1 = f2, x2 = lo + phi * (hi - lo), f2 = g(x2);
    }
    best = std::min({best, f1, f2});
    return best >= -gap;
  }
  // General (non-convex polygon, NURBS): containment of a sample point, or boundary
  // polylines within gap of each other (conservative by the flattening error).
  const double size = std::max(std::hypot(ba.max[0] - ba.min[0], ba.max[1] - ba.min[1]),
                               std::hypot(bb.max[0] - bb.min[0], bb.max[1] - bb.min[1]));
  const std::vector<Vec2> la = boundary_polyline(a, 1e-3 * size), lb = boundary_polyline(b, 1e-3 * size);
  if (shape_contains(b, {la[0][0], la[0][1], 0}) || shape_contains(a, {lb[0][0], lb[0][1], 0})) return true;
  const double slack = gap + 1e-6 * size;
  for (std::size_t i = 0; i < la.size(); ++i)
    for (std::size_t j = 0; j < lb.size(); ++j) {
      const Vec2 &p0 = la[i], &p1 = la[(i + 1) % la.size()], &q0 = lb[j], &q1 = lb[(j + 1) % lb.size()];
      if (std::max(p0[0], p1[0]) + slack < std::min(q0[0], q1[0]) || std::max(q0[0], q1[0]) + slack < std::min(p0[0], p1[0]) ||
          std::max(p0[1], p1[1]) + slack < std::min(q0[1], q1[1]) || std::max(q0[1], q1[1]) + slack < std::min(p0[1], p1[1]))
        continue;
      if (exact::segments_intersect(p0, p1, q0, q1)) return true;
      if (detail::segments_distance(p0, p1, q0, q1) <= slack)
        return true;
    }
  return false;
}

Shape translated(const Shape& s, const Vec3& offset) {
  Shape r = s;
  shape_family(r).translate(r, offset);
  return r;
}

}  // namespace cisamr::geometry
