// Free functions on one 2D shape (shapes.hpp); the 3D ones are in shapes3.cpp.
#include "geometry/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "geometry/nurbs2.hpp"
#include "geometry/predicates2.hpp"
#include "geometry/shapes_detail.hpp"

namespace cisamr::geometry {
namespace {

nurbs::Region region_of(const NurbsCurve& n) {
  nurbs::Region r;
  const std::string problem = nurbs::build_region(n, r);
  if (!problem.empty()) throw std::invalid_argument("invalid NURBS curve" + problem);
  return r;
}

double polygon_area(const std::vector<Vec2>& v) {
  double s = 0;
  for (std::size_t i = 0, j = v.size() - 1; i < v.size(); j = i++) s += v[j][0] * v[i][1] - v[i][0] * v[j][1];
  return 0.5 * std::abs(s);
}

double ellipse_perimeter(double a, double b) {
  // The trapezoid rule is spectrally accurate for this smooth periodic integrand.
  const int n = 4096;
  double s = 0;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * M_PI * (i + 0.5) / n;
    s += std::hypot(a * std::sin(t), b * std::cos(t));
  }
  return s * 2 * M_PI / n;
}

Vec2 ellipse_point(const Ellipse& e, double t) {
  const double x = e.semi_axes[0] * std::cos(t), y = e.semi_axes[1] * std::sin(t);
  const double cs = std::cos(e.angle), sn = std::sin(e.angle);
  return {e.center[0] + cs * x - sn * y, e.center[1] + sn * x + cs * y};
}

// Closed boundary polyline of a 2D shape with points at most `spacing` apart.
std::vector<Vec2> boundary_polyline(const Shape& s, double spacing) {
  std::vector<Vec2> out;
  if (const auto* c = std::get_if<Circle>(&s)) {
    const int n = std::max(8, static_cast<int>(std::ceil(2 * M_PI * c->radius / spacing)));
    for (int i = 0; i < n; ++i)
      out.push_back({c->center[0] + c->radius * std::cos(2 * M_PI * i / n), c->center[1] + c->radius * std::sin(2 * M_PI * i / n)});
  } else if (const auto* e = std::get_if<Ellipse>(&s)) {
    // Parameter steps bounded by spacing / max axis keep chords below spacing.
    const double amax = std::max(e->semi_axes[0], e->semi_axes[1]);
    const int n = std::max(8, static_cast<int>(std::ceil(2 * M_PI * amax / spacing)));
    for (int i = 0; i < n; ++i) out.push_back(ellipse_point(*e, 2 * M_PI * i / n));
  } else if (const auto* p = std::get_if<Polygon>(&s)) {
    const auto& v = p->vertices;
    for (std::size_t i = 0; i < v.size(); ++i) {
      const Vec2& a = v[i];
      const Vec2& b = v[(i + 1) % v.size()];
      const int n = std::max(1, static_cast<int>(std::ceil(std::hypot(b[0] - a[0], b[1] - a[1]) / spacing)));
      for (int k = 0; k < n; ++k) out.push_back({a[0] + (b[0] - a[0]) * k / n, a[1] + (b[1] - a[1]) * k / n});
    }
  } else if (const auto* nc = std::get_if<NurbsCurve>(&s)) {
    const nurbs::Region r = region_of(*nc);
    const std::vector<Vec2> fine = nurbs::flatten(r, 1e-6 * r.size);
    for (std::size_t i = 0; i < fine.size(); ++i) {
      const Vec2& a = fine[i];
      const Vec2& b = fine[(i + 1) % fine.size()];
      const int n = std::max(1, static_cast<int>(std::ceil(std::hypot(b[0] - a[0], b[1] - a[1]) / spacing)));
      for (int k = 0; k < n; ++k) out.push_back({a[0] + (b[0] - a[0]) * k / n, a[1] + (b[1] - a[1]) * k / n});
    }
  }
  return out;
}

bool is_convex_polygon(const std::vector<Vec2>& v) {
  int sign = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const int o = exact::orientation(v[i], v[(i + 1) % v.size()], v[(i + 2) % v.size()]);
    if (o == 0) continue;
    if (sign == 0) sign = o;
    else if (o != sign) return false;
  }
  return true;
}

double segment_distance(const Vec2& p, const Vec2& u, const Vec2& v) {
  const double dx = v[0] - u[0], dy = v[1] - u[1], dd = dx * dx + dy * dy;
  const double t = dd > 0 ? std::clamp(((p[0] - u[0]) * dx + (p[1] - u[1]) * dy) / dd, 0.0, 1.0) : 0.0;
  return std::hypot(p[0] - u[0] - t * dx, p[1] - u[1] - t * dy);
}

}  // namespace

namespace detail {
// Support function h(d) = max over the shape of x·d (2D convex shapes), for the
// separating-direction search of shapes_overlap.
bool support2(const Shape& s, const Vec2& d, double& h) {
  if (const auto* c = std::get_if<Circle>(&s)) {
    h = c->center[0] * d[0] + c->center[1] * d[1] + c->radius * std::hypot(d[0], d[1]);
    return true;
  }
  if (const auto* e = std::get_if<Ellipse>(&s)) {
    const double cs = std::cos(e->angle), sn = std::sin(e->angle);
    const double d1 = d[0] * cs + d[1] * sn, d2 = -d[0] * sn + d[1] * cs;
    h = e->center[0] * d[0] + e->center[1] * d[1] + std::hypot(e->semi_axes[0] * d1, e->semi_axes[1] * d2);
    return true;
  }
  if (const auto* p = std::get_if<Polygon>(&s)) {
    h = -std::numeric_limits<double>::infinity();
    for (const Vec2& v : p->vertices) h = std::max(h, v[0] * d[0] + v[1] * d[1]);
    return true;
  }
  return false;
}
}  // namespace detail

int shape_dimension(const Shape& s) { return s.index() < 4 ? 2 : 3; }

Box3 shape_bounding_box(const Shape& s) {
  if (shape_dimension(s) == 3) return detail::bounding_box3(s);
  if (const auto* c = std::get_if<Circle>(&s))
    return {{c->center[0] - c->radius, c->center[1] - c->radius, 0}, {c->center[0] + c->radius, c->center[1] + c->radius, 0}};
  if (const auto* e = std::get_if<Ellipse>(&s)) {
    const double cs = std::cos(e->angle), sn = std::sin(e->angle);
    const double hx = std::hypot(e->semi_axes[0] * cs, e->semi_axes[1] * sn);
    const double hy = std::hypot(e->semi_axes[0] * sn, e->semi_axes[1] * cs);
    return {{e->center[0] - hx, e->center[1] - hy, 0}, {e->center[0] + hx, e->center[1] + hy, 0}};
  }
  std::vector<Vec2> pts;
  if (const auto* p = std::get_if<Polygon>(&s)) pts = p->vertices;
  else {
    const nurbs::Region r = region_of(std::get<NurbsCurve>(s));
    pts = nurbs::flatten(r, 1e-12 * r.size);
  }
  Box3 b{{pts[0][0], pts[0][1], 0}, {pts[0][0], pts[0][1], 0}};
  for (const Vec2& q : pts)
    for (int k = 0; k < 2; ++k) {
      b.min[k] = std::min(b.min[k], q[k]);
      b.max[k] = std::max(b.max[k], q[k]);
    }
  return b;
}

double shape_measure(const Shape& s) {
  if (shape_dimension(s) == 3) return detail::measure3(s);
  if (const auto* c = std::get_if<Circle>(&s)) return M_PI * c->radius * c->radius;
  if (const auto* e = std::get_if<Ellipse>(&s)) return M_PI * e->semi_axes[0] * e->semi_axes[1];
  if (const auto* p = std::get_if<Polygon>(&s)) return polygon_area(p->vertices);
  return nurbs::area(region_of(std::get<NurbsCurve>(s)));
}

double shape_boundary_measure(const Shape& s) {
  if (shape_dimension(s) == 3) return detail::boundary_measure3(s);
  if (const auto* c = std::get_if<Circle>(&s)) return 2 * M_PI * c->radius;
  if (const auto* e = std::get_if<Ellipse>(&s)) return ellipse_perimeter(e->semi_axes[0], e->semi_axes[1]);
  if (const auto* p = std::get_if<Polygon>(&s)) {
    double l = 0;
    for (std::size_t i = 0; i < p->vertices.size(); ++i) {
      const Vec2& a = p->vertices[i];
      const Vec2& b = p->vertices[(i + 1) % p->vertices.size()];
      l += std::hypot(b[0] - a[0], b[1] - a[1]);
    }
    return l;
  }
  return nurbs::length(region_of(std::get<NurbsCurve>(s)));
}

void shape_boundary_samples_within(const Shape& s, double spacing, const Box3& clip, std::vector<Vec3>& points,
                                   std::vector<double>& areas) {
  if (!(spacing > 0)) throw std::invalid_argument("shape_boundary_samples_within: spacing must be positive");
  if (shape_dimension(s) != 3) throw std::invalid_argument("shape_boundary_samples_within: a 2D shape");
  detail::boundary_samples_within3(s, spacing, clip, points, areas);
}

std::vector<Vec3> shape_boundary_samples(const Shape& s, double spacing) {
  if (!(spacing > 0)) throw std::invalid_argument("shape_boundary_samples: spacing must be positive");
  if (shape_dimension(s) == 3) return detail::boundary_samples3(s, spacing);
  std::vector<Vec3> out;
  for (const Vec2& q : boundary_polyline(s, spacing)) out.push_back({q[0], q[1], 0});
  return out;
}

bool shape_contains(const Shape& s, const Vec3& p) {
  if (shape_dimension(s) == 3) return detail::contains3(s, p);
  const Vec2 q{p[0], p[1]};
  if (const auto* c = std::get_if<Circle>(&s)) return exact::circle_side(q, c->center, c->radius) >= 0;
  if (const auto* e = std::get_if<Ellipse>(&s)) {
    const double cs = std::cos(e->angle), sn = std::sin(e->angle);
    const double dx = q[0] - e->center[0], dy = q[1] - e->center[1];
    const double u = (dx * cs + dy * sn) / e->semi_axes[0], v = (-dx * sn + dy * cs) / e->semi_axes[1];
    return u * u + v * v <= 1 + 1e-14;
  }
  if (const auto* p2 = std::get_if<Polygon>(&s)) return exact::polygon_side(p2->vertices, q) >= 0;
  return nurbs::side(region_of(std::get<NurbsCurve>(s)), q) >= 0;
}

bool shapes_overlap(const Shape& a, const Shape& b, double gap) {
  if (shape_dimension(a) != shape_dimension(b)) throw std::invalid_argument("shapes_overlap: mixed dimensions");
  if (shape_dimension(a) == 3) return detail::overlap3(a, b, gap);
  const Box3 ba = shape_bounding_box(a), bb = shape_bounding_box(b);
  for (int k = 0; k < 2; ++k)
    if (ba.max[k] + gap < bb.min[k] || bb.max[k] + gap < ba.min[k]) return false;
  const auto* ca = std::get_if<Circle>(&a);
  const auto* cb = std::get_if<Circle>(&b);
  if (ca && cb) {
    if (gap == 0) return exact::disks_side(ca->center, ca->radius, cb->center, cb->radius) >= 0;
    return std::hypot(ca->center[0] - cb->center[0], ca->center[1] - cb->center[1]) <= ca->radius + cb->radius + gap;
  }
  const auto* pa = std::get_if<Polygon>(&a);
  const auto* pb = std::get_if<Polygon>(&b);
  if (pa && pb) {
    const auto& u = pa->vertices;
    const auto& v = pb->vertices;
    if (exact::polygon_side(v, u[0]) >= 0 || exact::polygon_side(u, v[0]) >= 0) return true;
    for (std::size_t i = 0; i < u.size(); ++i)
      for (std::size_t j = 0; j < v.size(); ++j) {
        const Vec2 &p0 = u[i], &p1 = u[(i + 1) % u.size()], &q0 = v[j], &q1 = v[(j + 1) % v.size()];
        if (exact::segments_intersect(p0, p1, q0, q1)) return true;
        if (gap > 0 && std::min({segment_distance(p0, q0, q1), segment_distance(p1, q0, q1),
                                 segment_distance(q0, p0, p1), segment_distance(q1, p0, p1)}) <= gap)
          return true;
      }
    return false;
  }
  // Convex pairs: they are apart by more than gap iff some direction d separates them,
  // h_a(d) + h_b(−d) < −gap. Search d on the circle: sampling, then golden section.
  const bool convex_a = !std::get_if<NurbsCurve>(&a) && (!pa || is_convex_polygon(pa->vertices));
  const bool convex_b = !std::get_if<NurbsCurve>(&b) && (!pb || is_convex_polygon(pb->vertices));
  if (convex_a && convex_b) {
    auto g = [&](double ang) {
      const Vec2 d{std::cos(ang), std::sin(ang)};
      double ha = 0, hb = 0;
      detail::support2(a, d, ha);
      detail::support2(b, Vec2{-d[0], -d[1]}, hb);
      return ha + hb;
    };
    const int n = 720;
    double best = std::numeric_limits<double>::infinity();
    int arg = 0;
    for (int i = 0; i < n; ++i) {
      const double v = g(2 * M_PI * i / n);
      if (v < best) best = v, arg = i;
    }
    double lo = 2 * M_PI * (arg - 1) / n, hi = 2 * M_PI * (arg + 1) / n;
    const double phi = 0.5 * (std::sqrt(5.0) - 1);
    double x1 = hi - phi * (hi - lo), x2 = lo + phi * (hi - lo), f1 = g(x1), f2 = g(x2);
    for (int it = 0; it < 80; ++it) {
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
      if (std::min({segment_distance(p0, q0, q1), segment_distance(p1, q0, q1), segment_distance(q0, p0, p1),
                    segment_distance(q1, p0, p1)}) <= slack)
        return true;
    }
  return false;
}

Shape translated(const Shape& s, const Vec3& o) {
  Shape r = s;
  std::visit(
      [&](auto& x) {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, Circle> || std::is_same_v<T, Ellipse>) {
          x.center[0] += o[0];
          x.center[1] += o[1];
        } else if constexpr (std::is_same_v<T, Polygon>) {
          for (Vec2& v : x.vertices) v[0] += o[0], v[1] += o[1];
        } else if constexpr (std::is_same_v<T, NurbsCurve>) {
          for (Vec2& v : x.control_points) v[0] += o[0], v[1] += o[1];
        } else if constexpr (std::is_same_v<T, Sphere> || std::is_same_v<T, Ellipsoid>) {
          for (int k = 0; k < 3; ++k) x.center[k] += o[k];
        } else if constexpr (std::is_same_v<T, Cylinder>) {
          for (int k = 0; k < 3; ++k) x.start[k] += o[k], x.end[k] += o[k];
        } else if constexpr (std::is_same_v<T, StlSurface>) {
          for (int k = 0; k < 3; ++k) x.translate[k] += o[k];
        } else {
          for (NurbsPatch& p : x.patches)
            for (Vec3& v : p.control_points)
              for (int k = 0; k < 3; ++k) v[k] += o[k];
        }
      },
      r);
  return r;
}

}  // namespace cisamr::geometry
