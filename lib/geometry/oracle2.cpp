// The 2D geometry oracle (contract in oracle2.hpp, schemes in README.md). The exact
// predicates live in predicates2.cpp and the CGAL search trees in box_index.cpp; this
// file holds the shape evaluators, crossings, validation, areas and distances.
#include "geometry/oracle2.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.hpp"
#include "geometry/box_index.hpp"
#include "geometry/box_tests.hpp"
#include "geometry/overlap_groups.hpp"
#include "geometry/nurbs2.hpp"
#include "geometry/predicates2.hpp"
#include "geometry/shapes.hpp"

namespace cisamr::geometry {
namespace {

constexpr double kUnitRoundoff = std::numeric_limits<double>::epsilon() * 0.5;
// Crossings closer than this (in t) are merged: a sub-interval that short is rounding.
constexpr double kMergeT = 64 * std::numeric_limits<double>::epsilon();

enum class Kind : std::uint8_t { circle, ellipse, polygon, nurbs };

struct CircleData {
  Vec2 c;
  double r;
};
// Ellipse as the unit circle in the frame u = ((x−c)·e1)/a, v = ((x−c)·e2)/b.
struct EllipseData {
  Vec2 c;
  double a, b, cs, sn;
};
struct PolygonData {
  std::uint32_t first, count;
};

struct Item {
  Kind kind;
  std::int32_t data;   // index into the per-kind array
  std::int32_t phase;  // phase index
  std::int32_t levels;
  std::int32_t group = -1;
  Box2 box;
};

Vec2 to_unit_frame(const EllipseData& e, const Vec2& p) {
  const double dx = p[0] - e.c[0], dy = p[1] - e.c[1];
  return {(dx * e.cs + dy * e.sn) / e.a, (-dx * e.sn + dy * e.cs) / e.b};
}

// Tolerant side of an ellipse: F = 1 − u² − v², |F| below the rounding bound is ON.
int ellipse_side(const EllipseData& e, const Vec2& p, double* f_out = nullptr) {
  const double dx = p[0] - e.c[0], dy = p[1] - e.c[1];
  const double u = (dx * e.cs + dy * e.sn) / e.a, v = (-dx * e.sn + dy * e.cs) / e.b;
  const double q = u * u + v * v;
  const double f = 1 - q;
  // Each of u, v carries ≲ 6u relative error of (|dx|+|dy|)/axis; squares double it.
  const double s = (std::abs(dx) + std::abs(dy));
  const double bound = 32 * kUnitRoundoff * (1 + q + s * s / (e.a * e.a) + s * s / (e.b * e.b));
  if (f_out) *f_out = std::abs(f) <= bound ? 0.0 : f;
  if (f > bound) return 1;
  if (f < -bound) return -1;
  return 0;
}

bool point_in_box(const Vec2& p, const Box2& b) {
  return p[0] >= b.min[0] && p[0] <= b.max[0] && p[1] >= b.min[1] && p[1] <= b.max[1];
}

double box_size(const Box2& b) { return std::hypot(b.max[0] - b.min[0], b.max[1] - b.min[1]); }

// Distance from p to the segment [u, v].
double segment_distance(const Vec2& p, const Vec2& u, const Vec2& v) {
  const double dx = v[0] - u[0], dy = v[1] - u[1];
  const double dd = dx * dx + dy * dy;
  double t = dd > 0 ? ((p[0] - u[0]) * dx + (p[1] - u[1]) * dy) / dd : 0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(p[0] - (u[0] + t * dx), p[1] - (u[1] + t * dy));
}

// Closest distance from p to an axis-aligned ellipse x²/a² + y²/b² = 1 (Eberly's robust
// bisection on the quadrant-reduced problem).
double ellipse_boundary_distance_local(double a, double b, double x, double y) {
  x = std::abs(x);
  y = std::abs(y);
  bool swapped = false;
  if (a < b) {
    std::swap(a, b);
    std::swap(x, y);
    swapped = true;
  }
  (void)swapped;
  if (y > 0) {
    if (x > 0) {
      const double z0 = x / a, z1 = y / b;
      const double g = z0 * z0 + z1 * z1 - 1;
      if (g != 0) {
        const double r0 = (a / b) * (a / b);
        // Root of F(s) = (r0 z0/(s+r0))² + (z1/(s+1))² − 1 on [s0, s1].
        double s0 = z1 - 1, s1 = g < 0 ? 0 : std::hypot(r0 * z0, z1) - 1, s = 0;
        for (int i = 0; i < 200; ++i) {
          s = 0.5 * (s0 + s1);
          if (s == s0 || s == s1) break;
          const double n0 = r0 * z0 / (s + r0), n1 = z1 / (s + 1);
          const double f = n0 * n0 + n1 * n1 - 1;
          if (f > 0) s0 = s;
          else if (f < 0) s1 = s;
          else break;
        }
        const double px = r0 * x / (s + r0), py = y / (s + 1);
        return std::hypot(x - px, y - py);
      }
      return 0;
    }
    return std::abs(y - b);
  }
  const double numer = a * x, denom = a * a - b * b;
  if (numer < denom) {
    const double xde = numer / denom;
    const double px = a * xde, py = b * std::sqrt(std::max(0.0, 1 - xde * xde));
    return std::hypot(x - px, py);
  }
  return std::abs(x - a);
}

}  // namespace

struct Oracle2::Impl {
  SceneDesc scene;
  int matrix = 0;
  std::vector<Item> items;
  std::vector<CircleData> circles;
  std::vector<EllipseData> ellipses;
  std::vector<PolygonData> polygons;
  std::vector<Vec2> polygon_vertices;
  std::vector<nurbs::Region> curves;
  std::vector<Box2> boxes;
  std::unique_ptr<BoxIndex2> index;

  std::span<const Vec2> polygon(const Item& it) const {
    const PolygonData& pd = polygons[it.data];
    return {polygon_vertices.data() + pd.first, pd.count};
  }

  // +1 inside, 0 on the boundary, -1 outside inclusion k.
  int side(std::int32_t k, const Vec2& p) const {
    const Item& it = items[k];
    if (!point_in_box(p, it.box)) return -1;
    switch (it.kind) {
      case Kind::circle: {
        const CircleData& c = circles[it.data];
        return exact::circle_side(p, c.c, c.r);
      }
      case Kind::ellipse: return ellipse_side(ellipses[it.data], p);
      case Kind::polygon: return exact::polygon_side(polygon(it), p);
      case Kind::nurbs: return nurbs::side(curves[it.data], p);
    }
    return -1;
  }

  // Distance from p to the boundary curve of inclusion k.
  double boundary_distance(std::int32_t k, const Vec2& p) const {
    const Item& it = items[k];
    switch (it.kind) {
      case Kind::circle: {
        const CircleData& c = circles[it.data];
        return std::abs(std::hypot(p[0] - c.c[0], p[1] - c.c[1]) - c.r);
      }
      case Kind::ellipse: {
        const EllipseData& e = ellipses[it.data];
        const double dx = p[0] - e.c[0], dy = p[1] - e.c[1];
        return ellipse_boundary_distance_local(e.a, e.b, dx * e.cs + dy * e.sn,
                                               -dx * e.sn + dy * e.cs);
      }
      case Kind::polygon: {
        auto poly = polygon(it);
        double d = std::numeric_limits<double>::infinity();
        for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
          d = std::min(d, segment_distance(p, poly[j], poly[i]));
        return d;
      }
      case Kind::nurbs: return nurbs::distance_to_curve(curves[it.data], p);
    }
    return 0;
  }

  // Appends where the open segment a→b enters/leaves inclusion k (state after each t) and
  // returns whether the segment starts inside (on counts as inside).
  struct Event {
    double t;
    std::int32_t inclusion;
    std::int32_t slot;
    std::int32_t order;
    bool inside_after;
  };
  bool segment_events(std::int32_t k, std::int32_t slot, const Vec2& a, const Vec2& b,
                      std::vector<Event>& events, std::vector<double>& ts) const;

  int phase_of_states(std::span<const std::int32_t> cands, const std::vector<std::uint8_t>& state) const {
    std::int32_t best = std::numeric_limits<std::int32_t>::max();
    for (std::size_t i = 0; i < cands.size(); ++i)
      if (state[i] && cands[i] < best) best = cands[i];
    return best == std::numeric_limits<std::int32_t>::max() ? matrix : items[best].phase;
  }

  void validate_and_build(const SceneDesc& s);

  // Distance machinery (README: distances). The boundary of k as pieces s ∈ [0,1].
  int piece_count(std::int32_t k) const;
  Vec2 curve_point(std::int32_t k, int piece, double s) const;
  // Points of ∂k where |q − p| has a local minimum along the curve (plus polygon vertices).
  void nearest_boundary_points(std::int32_t k, const Vec2& p, std::vector<Vec2>& out) const;
  // Points where ∂k and ∂j meet (the C0 corners of their union).
  void boundary_meetings(std::int32_t k, std::int32_t j, std::vector<Vec2>& out) const;
  double matrix_distance(const Vec2& p) const;
  PhaseMask closure_mask(const Vec2& p, std::span<const std::int32_t> cands) const;
  bool regions_intersect(std::int32_t i, std::int32_t j, bool interiors) const;
};

// Events for one inclusion along a→b; `ts` is scratch.
bool Oracle2::Impl::segment_events(std::int32_t k, std::int32_t slot, const Vec2& a,
                                   const Vec2& b, std::vector<Event>& events,
                                   std::vector<double>& ts) const {
  const Item& it = items[k];
  const Box2 seg{{std::min(a[0], b[0]), std::min(a[1], b[1])},
                 {std::max(a[0], b[0]), std::max(a[1], b[1])}};
  if (!boxes_overlap(seg, it.box)) return false;  // a is outside the box, hence outside
  std::int32_t order = 0;
  auto push_hits = [&](const exact::CircleSegmentHits& h) {
    bool state = h.start_inside;
    for (int i = 0; i < h.count; ++i) {
      state = !state;
      events.push_back({h.t[i], k, slot, order++, state});
    }
    return h.start_inside;
  };
  switch (it.kind) {
    case Kind::circle: {
      const CircleData& c = circles[it.data];
      return push_hits(exact::circle_segment_hits(a, b, c.c, c.r));
    }
    case Kind::ellipse: {
      // The unit-circle decision with the endpoint signs of the tolerant classification,
      // so that nodes classified ON never get a crossing at t ≈ 0 or 1.
      const EllipseData& e = ellipses[it.data];
      double f0, f1;
      const int s0 = ellipse_side(e, a, &f0), s1 = ellipse_side(e, b, &f1);
      const Vec2 ua = to_unit_frame(e, a), ub = to_unit_frame(e, b);
      const double dx = ub[0] - ua[0], dy = ub[1] - ua[1];
      const double dd = dx * dx + dy * dy;
      if (dd == 0) return s0 > 0;
      const double ed = ua[0] * dx + ua[1] * dy, fd = ub[0] * dx + ub[1] * dy;
      const double disc = ed * ed + dd * f0;
      auto sgn = [](double x) { return x > 0 ? 1 : (x < 0 ? -1 : 0); };
      return push_hits(
          exact::circle_hits_from_signs(s0, s1, sgn(ed), sgn(fd), sgn(disc), ed, dd, f0, disc));
    }
    case Kind::polygon:
    case Kind::nurbs: {
      ts.clear();
      const Vec2 d{b[0] - a[0], b[1] - a[1]};
      const double dd = d[0] * d[0] + d[1] * d[1];
      if (dd == 0) return side(k, a) >= 0;
      if (it.kind == Kind::polygon) {
        auto poly = polygon(it);
        for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
          const Vec2& u = poly[j];
          const Vec2& v = poly[i];
          if (std::max(u[0], v[0]) < seg.min[0] || std::min(u[0], v[0]) > seg.max[0] ||
              std::max(u[1], v[1]) < seg.min[1] || std::min(u[1], v[1]) > seg.max[1])
            continue;
          const int o1 = exact::orientation(a, b, u), o2 = exact::orientation(a, b, v);
          if (o2 == 0) {
            // Vertex v on the line: a hit when strictly between a and b.
            const double tv = ((v[0] - a[0]) * d[0] + (v[1] - a[1]) * d[1]) / dd;
            const bool between = (d[0] != 0) ? ((v[0] - a[0]) * d[0] > 0 && (b[0] - v[0]) * d[0] > 0)
                                             : ((v[1] - a[1]) * d[1] > 0 && (b[1] - v[1]) * d[1] > 0);
            if (between) ts.push_back(std::clamp(tv, std::numeric_limits<double>::denorm_min(), 1 - kUnitRoundoff));
          }
          if (o1 * o2 < 0) {
            const int o3 = exact::orientation(u, v, a), o4 = exact::orientation(u, v, b);
            if (o3 * o4 < 0) {
              const double ex = v[0] - u[0], ey = v[1] - u[1];
              const double num = (u[0] - a[0]) * ey - (u[1] - a[1]) * ex;
              const double den = d[0] * ey - d[1] * ex;
              ts.push_back(std::clamp(num / den, std::numeric_limits<double>::denorm_min(),
                                      1 - kUnitRoundoff));
            }
          }
        }
      } else {
        const nurbs::Region& reg = curves[it.data];
        nurbs::segment_hits(reg, a, b, ts);
        // Hits within the ON tolerance of an endpoint that is ON belong to that endpoint.
        const double len = std::sqrt(dd);
        const double tol_t = 4 * reg.on_tolerance / len;
        const bool a_on = side(k, a) == 0, b_on = side(k, b) == 0;
        ts.erase(std::remove_if(ts.begin(), ts.end(),
                                [&](double t) { return (a_on && t <= tol_t) || (b_on && t >= 1 - tol_t); }),
                 ts.end());
      }
      std::sort(ts.begin(), ts.end());
      ts.erase(std::unique(ts.begin(), ts.end()), ts.end());
      // Classify each open sub-interval at its midpoint (exactly, for that point).
      auto state_at = [&](double t0, double t1) {
        const double tm = 0.5 * (t0 + t1);
        return side(k, Vec2{a[0] + tm * d[0], a[1] + tm * d[1]}) >= 0;
      };
      double prev_t = 0;
      const bool start = state_at(0, ts.empty() ? 1.0 : ts[0]);
      bool state = start;
      for (std::size_t i = 0; i < ts.size(); ++i) {
        const double next = i + 1 < ts.size() ? ts[i + 1] : 1.0;
        const bool after = state_at(ts[i], next);
        if (after != state) events.push_back({ts[i], k, slot, order++, after});
        state = after;
        prev_t = ts[i];
      }
      (void)prev_t;
      return start;
    }
  }
  return false;
}

void Oracle2::Impl::validate_and_build(const SceneDesc& s) {
  scene = s;
  const std::string& src = scene.source;
  matrix = scene.phase_index(scene.matrix_phase);
  if (matrix < 0) throw InputError(src, "matrix_phase", "no phase has id " + std::to_string(scene.matrix_phase));
  if (scene.phases.size() > 64) throw InputError(src, "phases", "at most 64 phases are supported");
  items.reserve(scene.inclusions.size());
  for (std::size_t i = 0; i < scene.inclusions.size(); ++i) {
    const Inclusion& inc = scene.inclusions[i];
    const std::string field = inclusion_field(i);
    Item it{};
    it.phase = scene.phase_index(inc.phase);
    if (it.phase < 0)
      throw InputError(src, field + ".phase", "no phase has id " + std::to_string(inc.phase));
    it.levels = inc.levels;
    auto finite2 = [](const Vec2& v) { return std::isfinite(v[0]) && std::isfinite(v[1]); };
    if (const auto* c = std::get_if<Circle>(&inc.shape)) {
      if (!finite2(c->center)) throw InputError(src, field + ".center", "must be finite");
      if (!(c->radius > 0) || !std::isfinite(c->radius))
        throw InputError(src, field + ".radius", "must be positive");
      it.kind = Kind::circle;
      it.data = static_cast<std::int32_t>(circles.size());
      circles.push_back({c->center, c->radius});
      // Slightly loose so that the box test never rejects a point on the circle.
      const double r = c->radius * (1 + 4 * kUnitRoundoff);
      it.box = {{c->center[0] - r, c->center[1] - r}, {c->center[0] + r, c->center[1] + r}};
    } else if (const auto* e = std::get_if<Ellipse>(&inc.shape)) {
      if (!finite2(e->center)) throw InputError(src, field + ".center", "must be finite");
      if (!(e->semi_axes[0] > 0) || !(e->semi_axes[1] > 0) || !finite2(e->semi_axes))
        throw InputError(src, field + ".semi_axes", "must be positive");
      if (!std::isfinite(e->angle)) throw InputError(src, field + ".angle", "must be finite");
      it.kind = Kind::ellipse;
      it.data = static_cast<std::int32_t>(ellipses.size());
      EllipseData ed{e->center, e->semi_axes[0], e->semi_axes[1], std::cos(e->angle), std::sin(e->angle)};
      ellipses.push_back(ed);
      const double hx = std::hypot(ed.a * ed.cs, ed.b * ed.sn) * (1 + 1e-12) + 1e-300;
      const double hy = std::hypot(ed.a * ed.sn, ed.b * ed.cs) * (1 + 1e-12) + 1e-300;
      it.box = {{ed.c[0] - hx, ed.c[1] - hy}, {ed.c[0] + hx, ed.c[1] + hy}};
    } else if (const auto* p = std::get_if<Polygon>(&inc.shape)) {
      std::vector<Vec2> v;
      for (const Vec2& q : p->vertices) {
        if (!finite2(q)) throw InputError(src, field + ".vertices", "coordinates must be finite");
        if (v.empty() || v.back() != q) v.push_back(q);
      }
      while (v.size() > 1 && v.front() == v.back()) v.pop_back();
      if (v.size() < 3) throw InputError(src, field + ".vertices", "a polygon needs at least 3 distinct vertices");
      double area2 = 0;
      for (std::size_t a = 0, b = v.size() - 1; a < v.size(); b = a++)
        area2 += v[b][0] * v[a][1] - v[a][0] * v[b][1];
      bool all_collinear = true;
      for (std::size_t q = 2; q < v.size() && all_collinear; ++q)
        all_collinear = exact::orientation(v[0], v[1], v[q]) == 0;
      (void)area2;
      if (all_collinear) throw InputError(src, field + ".vertices", "polygon has zero area");
      // Self-intersection: non-adjacent edges must not meet; adjacent ones only at their
      // shared vertex. Box pairs first (Box_intersection_d), exact tests after.
      const std::size_t n = v.size();
      std::vector<Box2> eb(n);
      for (std::size_t q = 0; q < n; ++q) {
        const Vec2& u = v[q];
        const Vec2& w = v[(q + 1) % n];
        eb[q] = {{std::min(u[0], w[0]), std::min(u[1], w[1])}, {std::max(u[0], w[0]), std::max(u[1], w[1])}};
      }
      for (auto [ea, eb2] : overlapping_box_pairs(eb)) {
        const std::size_t x = static_cast<std::size_t>(ea), y = static_cast<std::size_t>(eb2);
        const Vec2 &p0 = v[x], &p1 = v[(x + 1) % n], &q0 = v[y], &q1 = v[(y + 1) % n];
        bool bad;
        if (y == x + 1 || (x == 0 && y == n - 1)) {
          // Adjacent edges share one vertex; they are bad only when they fold back
          // onto each other (collinear, both far ends on the same side).
          const std::size_t sv = (y == x + 1) ? y : 0;
          const Vec2& shared = v[sv];
          const Vec2& e0 = v[(sv + n - 1) % n];
          const Vec2& e1 = v[(sv + 1) % n];
          bad = exact::orientation(e0, shared, e1) == 0 &&
                ((e0[0] - shared[0]) * (e1[0] - shared[0]) > 0 ||
                 (e0[1] - shared[1]) * (e1[1] - shared[1]) > 0);
        } else {
          bad = exact::segments_intersect(p0, p1, q0, q1);
        }
        if (bad)
          throw InputError(src, field + ".vertices",
                           "polygon is self-intersecting (edges " + std::to_string(x) + " and " +
                               std::to_string(y) + ")");
      }
      it.kind = Kind::polygon;
      it.data = static_cast<std::int32_t>(polygons.size());
      polygons.push_back({static_cast<std::uint32_t>(polygon_vertices.size()), static_cast<std::uint32_t>(n)});
      Box2 bb{{v[0][0], v[0][1]}, {v[0][0], v[0][1]}};
      for (const Vec2& q : v) {
        bb.min = {std::min(bb.min[0], q[0]), std::min(bb.min[1], q[1])};
        bb.max = {std::max(bb.max[0], q[0]), std::max(bb.max[1], q[1])};
      }
      polygon_vertices.insert(polygon_vertices.end(), v.begin(), v.end());
      it.box = bb;
    } else if (const auto* nc = std::get_if<NurbsCurve>(&inc.shape)) {
      nurbs::Region reg;
      const std::string problem = nurbs::build_region(*nc, reg);
      if (!problem.empty()) {
        const auto colon = problem.find(": ");
        throw InputError(src, field + problem.substr(0, colon), problem.substr(colon + 2));
      }
      it.kind = Kind::nurbs;
      it.data = static_cast<std::int32_t>(curves.size());
      it.box = reg.box;
      curves.push_back(std::move(reg));
    } else {
      throw InputError(src, field + ".shape", "a 3D shape in a 2D scene");
    }
    items.push_back(it);
  }
  boxes.reserve(items.size());
  for (const Item& it : items) boxes.push_back(it.box);
  index = std::make_unique<BoxIndex2>(boxes);
  detail::group_overlapping_inclusions(*this);
}

// Do the closed regions of i and j meet (interiors == false) or do their interiors meet
// (interiors == true)? Boundary against boundary with the segment machinery: sample
// i's boundary chain and test it against j, plus containment of one in the other.
bool Oracle2::Impl::regions_intersect(std::int32_t i, std::int32_t j, bool interiors) const {
  // Interiors must overlap by more than rounding-level depth to count: decimal input
  // cannot express an exact tangency (README: overlap tolerance).
  const Item& a = items[i];
  const Item& b = items[j];
  const double depth_tol = 1e-10 * std::min(box_size(a.box), box_size(b.box));
  if (a.kind == Kind::circle && b.kind == Kind::circle) {
    const CircleData& p = circles[a.data];
    const CircleData& q = circles[b.data];
    if (!interiors) return exact::disks_side(p.c, p.r, q.c, q.r) >= 0;
    return std::hypot(q.c[0] - p.c[0], q.c[1] - p.c[1]) < p.r + q.r - depth_tol;
  }
  // General: walk a fine polyline of each boundary through the other's classifier.
  auto boundary_poly = [&](const Item& it) {
    Shape sh;
    std::vector<Vec2> pts;
    switch (it.kind) {
      case Kind::polygon: {
        auto poly = polygon(it);
        pts.assign(poly.begin(), poly.end());
        return pts;
      }
      case Kind::circle: {
        const CircleData& c = circles[it.data];
        sh = Circle{c.c, c.r};
        break;
      }
      case Kind::ellipse: {
        const EllipseData& e = ellipses[it.data];
        sh = Ellipse{e.c, {e.a, e.b}, std::atan2(e.sn, e.cs)};
        break;
      }
      case Kind::nurbs:
        return nurbs::flatten(curves[it.data], 1e-9 * curves[it.data].size);
    }
    const double len = shape_boundary_measure(sh);
    for (const Vec3& q : shape_boundary_samples(sh, len / 4096)) pts.push_back({q[0], q[1]});
    return pts;
  };
  const std::int32_t ks[2] = {i, j};
  for (int w = 0; w < 2; ++w) {
    const std::int32_t self = ks[w], other = ks[1 - w];
    const std::vector<Vec2> pts = boundary_poly(items[self]);
    for (const Vec2& q : pts) {
      const int s = side(other, q);
      if (interiors ? (s > 0 && boundary_distance(other, q) > depth_tol) : s >= 0) return true;
    }
  }
  if (interiors) {
    // Boundaries crossing each other without a sample inside: test chord midpoints.
    const std::vector<Vec2> pts = boundary_poly(items[i]);
    for (std::size_t q = 0; q < pts.size(); ++q) {
      const Vec2& u = pts[q];
      const Vec2& v = pts[(q + 1) % pts.size()];
      const Vec2 mid{0.5 * (u[0] + v[0]), 0.5 * (u[1] + v[1])};
      if (side(j, mid) > 0 && boundary_distance(j, mid) > depth_tol) return true;
    }
  }
  return false;
}

// ---------------------------------------------------------------- public API
Oracle2::Oracle2(const SceneDesc& scene) : impl_(std::make_unique<Impl>()) {
  impl_->validate_and_build(scene);
}
Oracle2::~Oracle2() = default;
Oracle2::Oracle2(Oracle2&&) noexcept = default;
Oracle2& Oracle2::operator=(Oracle2&&) noexcept = default;

const SceneDesc& Oracle2::scene() const { return impl_->scene; }
int Oracle2::inclusion_count() const { return static_cast<int>(impl_->items.size()); }
int Oracle2::phase_count() const { return static_cast<int>(impl_->scene.phases.size()); }
int Oracle2::matrix_phase() const { return impl_->matrix; }
int Oracle2::phase_of(std::int32_t k) const { return impl_->items[k].phase; }
int Oracle2::levels_of(std::int32_t k) const { return impl_->items[k].levels; }
int Oracle2::interface_group(std::int32_t k) const { return impl_->items[k].group; }
Box2 Oracle2::bounding_box(std::int32_t k) const { return impl_->items[k].box; }

void Oracle2::candidates(const Box2& box, std::vector<std::int32_t>& out) const {
  impl_->index->query(box, out);
}

bool Oracle2::boundary_touches(std::int32_t k, const Box2& box_in) const {
  const Impl& m = *impl_;
  const Item& it = m.items[k];
  const double slack = 1e-12 * std::max(box_size(box_in), box_size(it.box)) + 1e-300;
  const Box2 box{{box_in.min[0] - slack, box_in.min[1] - slack}, {box_in.max[0] + slack, box_in.max[1] + slack}};
  if (!boxes_overlap(box, it.box)) return false;
  switch (it.kind) {
    case Kind::circle: {
      const CircleData& c = m.circles[it.data];
      return detail::sphere_meets_box(c.c, c.r, box);
    }
    case Kind::ellipse: {
      // F(x) = u² + v² is convex: its max over the box is at a corner; its min is at the
      // center when inside, else on one of the four edges (1D quadratic minimum).
      const EllipseData& e = m.ellipses[it.data];
      auto q = [&](const Vec2& p) {
        const Vec2 u = to_unit_frame(e, p);
        return u[0] * u[0] + u[1] * u[1];
      };
      const Vec2 corners[4] = {{box.min[0], box.min[1]}, {box.max[0], box.min[1]},
                               {box.max[0], box.max[1]}, {box.min[0], box.max[1]}};
      double qmax = 0, qmin = std::numeric_limits<double>::infinity();
      for (const Vec2& c : corners) qmax = std::max(qmax, q(c));
      if (point_in_box(e.c, box)) qmin = 0;
      else {
        for (int s = 0; s < 4; ++s) {
          const Vec2& u = corners[s];
          const Vec2& v = corners[(s + 1) % 4];
          // q along the edge is a convex quadratic in t: minimise on [0,1].
          const double q0 = q(u), q1 = q(v), qm = q(Vec2{0.5 * (u[0] + v[0]), 0.5 * (u[1] + v[1])});
          const double A = 2 * q0 - 4 * qm + 2 * q1, B = -3 * q0 + 4 * qm - q1;
          double best = std::min(q0, q1);
          if (A > 0) {
            const double t = -B / (2 * A);
            if (t > 0 && t < 1) best = std::min(best, q0 + B * t + A * t * t);
          }
          qmin = std::min(qmin, best);
        }
      }
      return qmin <= 1 + 1e-9 && qmax >= 1 - 1e-9;
    }
    case Kind::polygon: {
      auto poly = m.polygon(it);
      for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
        if (detail::segment_meets_box(poly[j], poly[i], box)) return true;
      return false;
    }
    case Kind::nurbs: return nurbs::touches_box(m.curves[it.data], box);
  }
  return true;
}

PhaseMask Oracle2::closure_phases(const Vec2& p, std::span<const std::int32_t> cands) const {
  return impl_->closure_mask(p, cands);
}

PhaseMask Oracle2::Impl::closure_mask(const Vec2& p, std::span<const std::int32_t> cands) const {
  const Impl& m = *this;
  PhaseMask inside = 0, on = 0;
  int on_count = 0;
  for (std::int32_t k : cands) {
    const int s = m.side(k, p);
    if (s > 0) inside |= PhaseMask(1) << m.items[k].phase;
    else if (s == 0) {
      on |= PhaseMask(1) << m.items[k].phase;
      ++on_count;
    }
  }
  if (inside) return inside | (on & ~inside);
  const PhaseMask matrix_bit = PhaseMask(1) << m.matrix;
  if (!on) return matrix_bit;
  if (on_count == 1) return on | matrix_bit;
  // On several boundaries and inside none (touching inclusions, shared polygon edges):
  // the matrix reaches p iff some nearby direction leaves every inclusion. Probe the
  // tangent directions of the curves at p (where tangent shapes leave a cusp of matrix)
  // and a fan of directions.
  double scale = std::numeric_limits<double>::infinity();
  for (std::int32_t k : cands) scale = std::min(scale, box_size(m.items[k].box));
  auto outside_all = [&](const Vec2& q) {
    for (std::int32_t k : cands)
      if (m.side(k, q) >= 0) return false;
    return true;
  };
  for (std::int32_t k : cands) {
    Vec2 tan{0, 0};
    const Item& it = m.items[k];
    if (it.kind == Kind::circle) {
      const Vec2& c = m.circles[it.data].c;
      tan = {-(p[1] - c[1]), p[0] - c[0]};
    } else if (it.kind == Kind::ellipse) {
      const EllipseData& e = m.ellipses[it.data];
      const Vec2 u = to_unit_frame(e, p);
      const double gx = u[0] / e.a, gy = u[1] / e.b;  // gradient in the body frame
      tan = {e.cs * (-gy) - e.sn * gx, e.sn * (-gy) + e.cs * gx};
    } else {
      continue;
    }
    const double n = std::hypot(tan[0], tan[1]);
    if (!(n > 0)) continue;
    const double rho = 1e-6 * scale / n;
    if (outside_all({p[0] + rho * tan[0], p[1] + rho * tan[1]}) ||
        outside_all({p[0] - rho * tan[0], p[1] - rho * tan[1]}))
      return on | matrix_bit;
  }
  const double rho = 1e-9 * scale;
  for (int dir = 0; dir < 32; ++dir) {
    const double ang = (dir + 0.5) * (2 * M_PI / 32);
    if (outside_all({p[0] + rho * std::cos(ang), p[1] + rho * std::sin(ang)})) return on | matrix_bit;
  }
  return on;
}

int Oracle2::phase_at(const Vec2& p, std::span<const std::int32_t> cands) const {
  const Impl& m = *impl_;
  constexpr std::int32_t none = std::numeric_limits<std::int32_t>::max();
  std::int32_t best_in = none, best_on = none;
  for (std::int32_t k : cands) {
    if (k >= best_in) continue;
    const int s = m.side(k, p);
    if (s > 0) best_in = k;
    else if (s == 0 && k < best_on) best_on = k;
  }
  if (best_in != none) return m.items[best_in].phase;
  if (best_on != none) return m.items[best_on].phase;
  return m.matrix;
}

void Oracle2::crossings(const Vec2& a, const Vec2& b, std::span<const std::int32_t> cands,
                        std::vector<Crossing>& out) const {
  const Impl& m = *impl_;
  out.clear();
  if (a == b || cands.empty()) return;
  thread_local std::vector<Impl::Event> events;
  thread_local std::vector<std::uint8_t> state;
  thread_local std::vector<double> scratch;
  events.clear();
  state.assign(cands.size(), 0);
  for (std::size_t i = 0; i < cands.size(); ++i)
    state[i] = m.segment_events(cands[i], static_cast<std::int32_t>(i), a, b, events, scratch);
  if (events.empty()) return;
  std::sort(events.begin(), events.end(), [](const Impl::Event& x, const Impl::Event& y) {
    if (x.t != y.t) return x.t < y.t;
    if (x.inclusion != y.inclusion) return x.inclusion < y.inclusion;
    return x.order < y.order;
  });
  int before = m.phase_of_states(cands, state);
  for (std::size_t i = 0; i < events.size();) {
    const double t = events[i].t;
    std::int32_t first = events[i].inclusion;
    std::size_t j = i;
    for (; j < events.size() && events[j].t == t; ++j) state[events[j].slot] = events[j].inside_after;
    const int after = m.phase_of_states(cands, state);
    if (after != before) out.push_back({t, first, before, after});
    before = after;
    i = j;
  }
  // Sub-intervals shorter than rounding are not phases: merge or drop their ends.
  std::size_t w = 0;
  for (std::size_t r = 0; r < out.size(); ++r) {
    if (w > 0 && out[r].t - out[w - 1].t < kMergeT) {
      Crossing& prev = out[w - 1];
      if (prev.from_phase == out[r].to_phase) {
        --w;  // a vanishing excursion: no crossing at all
      } else {
        prev.to_phase = out[r].to_phase;
        prev.inclusion = std::min(prev.inclusion, out[r].inclusion);
      }
      continue;
    }
    out[w++] = out[r];
  }
  out.resize(w);
}


// ---------------------------------------------------------------- areas
std::vector<double> Oracle2::phase_areas() const {
  const Impl& m = *impl_;
  const SceneDesc& sc = m.scene;
  const Box2 dom{{sc.domain_min[0], sc.domain_min[1]}, {sc.domain_max[0], sc.domain_max[1]}};
  std::vector<double> areas(sc.phases.size(), 0.0);
  std::vector<int> group_size(m.items.size(), 0);
  for (const Item& it : m.items) ++group_size[it.group];
  // Inclusions alone in their group and fully inside the domain: analytic measure.
  std::vector<std::int32_t> integrated;
  std::vector<double> breaks{dom.min[0], dom.max[0]};
  for (std::size_t k = 0; k < m.items.size(); ++k) {
    const Item& it = m.items[k];
    const bool inside_domain = it.box.min[0] >= dom.min[0] && it.box.max[0] <= dom.max[0] &&
                               it.box.min[1] >= dom.min[1] && it.box.max[1] <= dom.max[1];
    if (inside_domain && group_size[it.group] == 1) {
      double a = 0;
      switch (it.kind) {
        case Kind::circle: a = M_PI * m.circles[it.data].r * m.circles[it.data].r; break;
        case Kind::ellipse: a = M_PI * m.ellipses[it.data].a * m.ellipses[it.data].b; break;
        case Kind::polygon: {
          auto poly = m.polygon(it);
          double s2 = 0;
          for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
            s2 += poly[j][0] * poly[i][1] - poly[i][0] * poly[j][1];
          a = 0.5 * std::abs(s2);
          break;
        }
        case Kind::nurbs: a = nurbs::area(m.curves[it.data]); break;
      }
      areas[it.phase] += a;
      continue;
    }
    if (!boxes_overlap(it.box, dom)) continue;
    integrated.push_back(static_cast<std::int32_t>(k));
    breaks.push_back(std::clamp(it.box.min[0], dom.min[0], dom.max[0]));
    breaks.push_back(std::clamp(it.box.max[0], dom.min[0], dom.max[0]));
    if (it.kind == Kind::polygon)
      for (const Vec2& v : m.polygon(it)) breaks.push_back(std::clamp(v[0], dom.min[0], dom.max[0]));
    if (it.kind == Kind::nurbs) {
      std::vector<double> xs;
      nurbs::x_breakpoints(m.curves[it.data], xs);
      for (double x : xs) breaks.push_back(std::clamp(x, dom.min[0], dom.max[0]));
    }
  }
  if (!integrated.empty()) {
    std::sort(breaks.begin(), breaks.end());
    breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());
    const std::size_t np = areas.size();
    std::vector<std::int32_t> cands;
    std::vector<Crossing> cr;
    // Length of each inclusion phase on the vertical line at x (matrix left out).
    auto line = [&](double x, std::vector<double>& len) {
      len.assign(np, 0.0);
      cands.clear();
      for (std::int32_t k : integrated)
        if (m.items[k].box.min[0] <= x && x <= m.items[k].box.max[0]) cands.push_back(k);
      if (cands.empty()) return;
      const Vec2 a{x, dom.min[1]}, b{x, dom.max[1]};
      crossings(a, b, cands, cr);
      const double span = dom.max[1] - dom.min[1];
      double t0 = 0;
      int ph = cr.empty() ? phase_at(Vec2{x, 0.5 * (a[1] + b[1])}, cands) : cr[0].from_phase;
      for (const Crossing& c : cr) {
        len[ph] += (c.t - t0) * span;
        t0 = c.t;
        ph = c.to_phase;
      }
      len[ph] += (1 - t0) * span;
    };
    // Gauss–Legendre (10 points) after x = x0 + (x1−x0)(1−cos πs)/2, which smooths the
    // square-root behaviour of chord lengths at vertical tangents; adaptive halving.
    static const double gx[5] = {0.1488743389816312, 0.4333953941292472, 0.6794095682990244,
                                 0.8650633666889845, 0.9739065285171717};
    static const double gw[5] = {0.2955242247147529, 0.2692667193099963, 0.2190863625159820,
                                 0.1494513491505806, 0.0666713443086881};
    std::vector<double> len;
    auto panel = [&](double x0, double x1, double s0, double s1, std::vector<double>& sum) {
      sum.assign(np, 0.0);
      const double hm = 0.5 * (s1 - s0), cm = 0.5 * (s1 + s0);
      for (int i = 0; i < 10; ++i) {
        const double s = cm + hm * (i < 5 ? -gx[i] : gx[i - 5]);
        const double w = gw[i < 5 ? i : i - 5] * hm;
        const double x = x0 + (x1 - x0) * 0.5 * (1 - std::cos(M_PI * s));
        const double jac = (x1 - x0) * 0.5 * M_PI * std::sin(M_PI * s);
        line(x, len);
        for (std::size_t p = 0; p < np; ++p) sum[p] += w * jac * len[p];
      }
    };
    const double tol = 1e-13 * (dom.max[0] - dom.min[0]) * (dom.max[1] - dom.min[1]);
    struct Task {
      double s0, s1;
      int depth;
    };
    std::vector<double> whole, left, right;
    for (std::size_t bi = 0; bi + 1 < breaks.size(); ++bi) {
      const double x0 = breaks[bi], x1 = breaks[bi + 1];
      if (!(x1 > x0)) continue;
      std::vector<Task> stack{{0, 1, 0}};
      std::vector<std::vector<double>> est{{}};
      panel(x0, x1, 0, 1, est[0]);
      while (!stack.empty()) {
        const Task tk = stack.back();
        whole = est.back();
        stack.pop_back();
        est.pop_back();
        const double sm = 0.5 * (tk.s0 + tk.s1);
        panel(x0, x1, tk.s0, sm, left);
        panel(x0, x1, sm, tk.s1, right);
        double diff = 0;
        for (std::size_t p = 0; p < np; ++p) diff += std::abs(left[p] + right[p] - whole[p]);
        if (diff <= tol * (tk.s1 - tk.s0) || tk.depth >= 40) {
          for (std::size_t p = 0; p < np; ++p) areas[p] += left[p] + right[p];
        } else {
          stack.push_back({tk.s0, sm, tk.depth + 1});
          est.push_back(left);
          stack.push_back({sm, tk.s1, tk.depth + 1});
          est.push_back(right);
        }
      }
    }
  }
  double total = 0;
  for (std::size_t p = 0; p < areas.size(); ++p)
    if (static_cast<int>(p) != m.matrix) total += areas[p];
  areas[m.matrix] = (dom.max[0] - dom.min[0]) * (dom.max[1] - dom.min[1]) - total;
  return areas;
}

// ---------------------------------------------------------------- distances
double Oracle2::distance_to_phase(const Vec2& p, int phase_index) const {
  const Impl& m = *impl_;
  auto box_distance = [&](const Box2& b) {
    const double dx = std::max({b.min[0] - p[0], 0.0, p[0] - b.max[0]});
    const double dy = std::max({b.min[1] - p[1], 0.0, p[1] - b.max[1]});
    return std::hypot(dx, dy);
  };
  const std::int32_t n = static_cast<std::int32_t>(m.items.size());
  if (phase_index != m.matrix) {
    // Distance to a union is the minimum over its members.
    double best = std::numeric_limits<double>::infinity();
    for (std::int32_t k = 0; k < n; ++k) {
      if (m.items[k].phase != phase_index || box_distance(m.items[k].box) >= best) continue;
      if (m.side(k, p) >= 0) return 0;
      best = std::min(best, m.boundary_distance(k, p));
    }
    return best;
  }
  // Matrix: 0 unless p is interior to some inclusion; then the distance to the
  // complement of the union, i.e. to the nearest boundary point not inside another one.
  std::vector<std::int32_t> inside;
  for (std::int32_t k = 0; k < n; ++k)
    if (point_in_box(p, m.items[k].box) && m.side(k, p) > 0) inside.push_back(k);
  if (inside.empty()) return m.matrix_distance(p);
  double best = std::numeric_limits<double>::infinity();
  if (inside.size() == 1) {
    best = m.boundary_distance(inside[0], p);
    bool alone = true;
    for (std::int32_t k = 0; k < n && alone; ++k)
      if (k != inside[0] && box_distance(m.items[k].box) <= best * (1 + 1e-9)) alone = false;
    if (alone) return best;
  }
  return m.matrix_distance(p);
}

int Oracle2::Impl::piece_count(std::int32_t k) const {
  const Item& it = items[k];
  if (it.kind == Kind::polygon) return static_cast<int>(polygons[it.data].count);
  if (it.kind == Kind::nurbs) return static_cast<int>(curves[it.data].pieces.size());
  return 1;
}

Vec2 Oracle2::Impl::curve_point(std::int32_t k, int piece, double s) const {
  const Item& it = items[k];
  switch (it.kind) {
    case Kind::circle: {
      const CircleData& c = circles[it.data];
      const double th = 2 * M_PI * s;
      return {c.c[0] + c.r * std::cos(th), c.c[1] + c.r * std::sin(th)};
    }
    case Kind::ellipse: {
      const EllipseData& e = ellipses[it.data];
      const double th = 2 * M_PI * s, x = e.a * std::cos(th), y = e.b * std::sin(th);
      return {e.c[0] + x * e.cs - y * e.sn, e.c[1] + x * e.sn + y * e.cs};
    }
    case Kind::polygon: {
      auto poly = polygon(it);
      const Vec2& u = poly[piece];
      const Vec2& v = poly[(piece + 1) % poly.size()];
      return {u[0] + s * (v[0] - u[0]), u[1] + s * (v[1] - u[1])};
    }
    case Kind::nurbs: {
      const nurbs::Region& r = curves[it.data];
      return nurbs::point(r.pieces[piece], r.degree, s);
    }
  }
  return {0, 0};
}

void Oracle2::Impl::nearest_boundary_points(std::int32_t k, const Vec2& p,
                                            std::vector<Vec2>& out) const {
  const Item& it = items[k];
  if (it.kind == Kind::circle) {
    // The distance along a circle is unimodal: one minimum.
    const CircleData& c = circles[it.data];
    const double dx = p[0] - c.c[0], dy = p[1] - c.c[1], n = std::hypot(dx, dy);
    if (n == 0) out.push_back({c.c[0] + c.r, c.c[1]});
    else out.push_back({c.c[0] + c.r * (dx / n), c.c[1] + c.r * (dy / n)});
    return;
  }
  if (it.kind == Kind::polygon) {
    // Per edge: the projection (convex along the edge) and the vertices (arc ends).
    auto poly = polygon(it);
    for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
      const Vec2& u = poly[j];
      const Vec2& v = poly[i];
      out.push_back(v);
      const double ex = v[0] - u[0], ey = v[1] - u[1];
      const double t = ((p[0] - u[0]) * ex + (p[1] - u[1]) * ey) / (ex * ex + ey * ey);
      if (t > 0 && t < 1) out.push_back({u[0] + t * ex, u[1] + t * ey});
    }
    return;
  }
  // Ellipse / NURBS: every discrete local minimum of a dense sampling, refined by golden
  // section inside its bracket (piece ends included as candidates).
  const int samples = it.kind == Kind::ellipse ? 512 : 32;
  std::vector<double> d2(samples + 1);
  auto dist2 = [&](int piece, double s) {
    const Vec2 q = curve_point(k, piece, s);
    return (q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]);
  };
  for (int piece = 0; piece < piece_count(k); ++piece) {
    for (int i = 0; i <= samples; ++i) d2[i] = dist2(piece, double(i) / samples);
    for (int i = 0; i <= samples; ++i) {
      if ((i > 0 && d2[i] > d2[i - 1]) || (i < samples && d2[i] > d2[i + 1])) continue;
      double lo = double(std::max(i - 1, 0)) / samples, hi = double(std::min(i + 1, samples)) / samples;
      constexpr double g = 0.6180339887498949;
      double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
      double f1 = dist2(piece, x1), f2 = dist2(piece, x2);
      for (int iter = 0; iter < 80 && hi - lo > 1e-17; ++iter) {
        if (f1 <= f2) {
          hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = dist2(piece, x1);
        } else {
          lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = dist2(piece, x2);
        }
      }
      out.push_back(curve_point(k, piece, f1 <= f2 ? x1 : x2));
      out.push_back(curve_point(k, piece, double(i) / samples));
    }
  }
}

void Oracle2::Impl::boundary_meetings(std::int32_t k, std::int32_t j, std::vector<Vec2>& out) const {
  const Item* a = &items[k];
  const Item* b = &items[j];
  if (a->kind == Kind::polygon && b->kind == Kind::circle) std::swap(a, b), std::swap(k, j);
  if (a->kind == Kind::circle && b->kind == Kind::circle) {
    const CircleData& p = circles[a->data];
    const CircleData& q = circles[b->data];
    const double dx = q.c[0] - p.c[0], dy = q.c[1] - p.c[1], d = std::hypot(dx, dy);
    if (d == 0 || d > p.r + q.r || d < std::abs(p.r - q.r)) return;
    const double along = (p.r * p.r - q.r * q.r + d * d) / (2 * d);
    const double h = std::sqrt(std::max(0.0, p.r * p.r - along * along));
    const double ex = dx / d, ey = dy / d;
    out.push_back({p.c[0] + along * ex - h * ey, p.c[1] + along * ey + h * ex});
    out.push_back({p.c[0] + along * ex + h * ey, p.c[1] + along * ey - h * ex});
    return;
  }
  if (a->kind == Kind::circle && b->kind == Kind::polygon) {
    const CircleData& c = circles[a->data];
    auto poly = polygon(*b);
    for (std::size_t i = 0, i0 = poly.size() - 1; i < poly.size(); i0 = i++) {
      const Vec2& u = poly[i0];
      const Vec2& v = poly[i];
      // |u + t(v−u) − c|² = r²: A t² + 2B t + C = 0.
      const double ex = v[0] - u[0], ey = v[1] - u[1], fx = u[0] - c.c[0], fy = u[1] - c.c[1];
      const double A = ex * ex + ey * ey, B = fx * ex + fy * ey, C = fx * fx + fy * fy - c.r * c.r;
      const double disc = B * B - A * C;
      if (disc < 0) continue;
      const double sq = std::sqrt(disc);
      for (double t : {(-B - sq) / A, (-B + sq) / A})
        if (t >= 0 && t <= 1) out.push_back({u[0] + t * ex, u[1] + t * ey});
    }
    return;
  }
  if (a->kind == Kind::polygon && b->kind == Kind::polygon) {
    auto pa = polygon(*a), pb = polygon(*b);
    for (std::size_t i = 0, i0 = pa.size() - 1; i < pa.size(); i0 = i++)
      for (std::size_t l = 0, l0 = pb.size() - 1; l < pb.size(); l0 = l++) {
        const Vec2 &u = pa[i0], &v = pa[i], &w = pb[l0], &z = pb[l];
        if (!exact::segments_intersect(u, v, w, z)) continue;
        const double ex = v[0] - u[0], ey = v[1] - u[1], gx = z[0] - w[0], gy = z[1] - w[1];
        const double den = ex * gy - ey * gx;
        if (exact::orientation(u, v, w) == 0 && exact::orientation(u, v, z) == 0) continue;  // collinear: ends are vertices
        const double t = std::clamp(((w[0] - u[0]) * gy - (w[1] - u[1]) * gx) / den, 0.0, 1.0);
        out.push_back({u[0] + t * ex, u[1] + t * ey});
      }
    return;
  }
  // Ellipses and NURBS: walk ∂k, bisect every sign change of j's classifier.
  const int samples = a->kind == Kind::ellipse ? 1024 : 64;
  for (int piece = 0; piece < piece_count(k); ++piece) {
    Vec2 prev = curve_point(k, piece, 0);
    int prev_side = side(j, prev);
    if (prev_side == 0) out.push_back(prev);
    for (int i = 1; i <= samples; ++i) {
      double s1 = double(i) / samples;
      const Vec2 cur = curve_point(k, piece, s1);
      const int cur_side = side(j, cur);
      if (cur_side == 0) out.push_back(cur);
      else if (prev_side != 0 && cur_side != prev_side) {
        double s0 = double(i - 1) / samples;
        Vec2 mid = cur;
        for (int iter = 0; iter < 64; ++iter) {
          const double sm = 0.5 * (s0 + s1);
          if (sm <= s0 || sm >= s1) break;
          mid = curve_point(k, piece, sm);
          const int ms = side(j, mid);
          if (ms == 0) break;
          if (ms == prev_side) s0 = sm;
          else s1 = sm;
        }
        out.push_back(mid);
      }
      prev = cur;
      prev_side = cur_side;
    }
  }
}

// Distance from p to the matrix: 0 unless p is interior to an inclusion; then the
// distance to ∂U (U = union of the inclusions), minimal over the candidates of README
// (local minima of each boundary, pairwise corners, vertices) that no other inclusion
// covers. Exact for circles and polygons (the restricted distance along an arc is
// minimal at an unconstrained minimum or at an arc end).
double Oracle2::Impl::matrix_distance(const Vec2& p) const {
  std::vector<std::int32_t> near;
  index->query(Box2{p, p}, near);
  double lower = 0;
  bool inside_any = false, on_any = false;
  for (std::int32_t k : near) {
    const int s = side(k, p);
    if (s > 0) {
      inside_any = true;
      lower = std::max(lower, boundary_distance(k, p));
    }
    on_any |= s == 0;
  }
  const PhaseMask matrix_bit = PhaseMask(1) << matrix;
  // ON boundaries only: 0 unless the matrix does not reach p (a shared polygon edge).
  if (!inside_any && (!on_any || (closure_mask(p, near) & matrix_bit))) return 0;
  std::vector<Vec2> pts;
  double reach = std::max(lower, 1e-300);
  for (;;) {
    // Slightly inflated: a candidate at distance ≤ reach must see every box holding it.
    const double r = reach * (1 + 1e-9);
    index->query(Box2{{p[0] - r, p[1] - r}, {p[0] + r, p[1] + r}}, near);
    double best = std::numeric_limits<double>::infinity();
    // Keep q when no inclusion other than its owners holds it; a q ON another one (shared
    // polygon edges, tangencies) is kept only if the matrix reaches it.
    auto consider = [&](const Vec2& q, std::int32_t k, std::int32_t j) {
      const double d = std::hypot(q[0] - p[0], q[1] - p[1]);
      if (d >= best) return;
      bool on_other = false;
      for (std::int32_t i : near) {
        if (i == k || i == j) continue;
        const int s = side(i, q);
        if (s > 0) return;
        if (s == 0) on_other = true;
      }
      if (on_other && !(closure_mask(q, near) & matrix_bit)) return;
      best = d;
    };
    for (std::int32_t k : near) {
      pts.clear();
      nearest_boundary_points(k, p, pts);
      for (const Vec2& q : pts) consider(q, k, -1);
    }
    for (std::size_t x = 0; x < near.size(); ++x)
      for (std::size_t y = x + 1; y < near.size(); ++y) {
        if (!boxes_overlap(items[near[x]].box, items[near[y]].box)) continue;
        pts.clear();
        boundary_meetings(near[x], near[y], pts);
        for (const Vec2& q : pts) consider(q, near[x], near[y]);
      }
    if (best <= reach || near.size() == items.size()) return best;
    reach = std::isfinite(best) ? best : 2 * reach;
  }
}

}  // namespace cisamr::geometry
