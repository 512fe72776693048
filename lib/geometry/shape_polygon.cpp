// Polygons (README: classification, crossings, distances of each).
#include "geometry/shape_polygon.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "geometry/box_index.hpp"
#include "geometry/box_tests.hpp"
#include "geometry/shape_fields.hpp"
#include "geometry/shape_model.hpp"
#include "geometry/shape_family.hpp"
#include "geometry/shapes_detail.hpp"

namespace cisamr::geometry {
namespace {

// Distance from p to the segment [u, v].
double segment_distance(const Vec2& p, const Vec2& u, const Vec2& v) {
  const double dx = v[0] - u[0], dy = v[1] - u[1];
  const double dd = dx * dx + dy * dy;
  double t = dd > 0 ? ((p[0] - u[0]) * dx + (p[1] - u[1]) * dy) / dd : 0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(p[0] - (u[0] + t * dx), p[1] - (u[1] + t * dy));
}

}  // namespace

namespace {

class PolygonModel final : public CurveModel {
 public:
  // Drops repeated consecutive vertices; throws for < 3 distinct vertices, zero area or
  // self-intersection ("edges x and y").
  PolygonModel(const Polygon& p, const std::string& src, const std::string& field) {
    std::vector<Vec2>& v = v_;
    for (const Vec2& q : p.vertices) {
      if (!finite(q)) throw InputError(src, field + ".vertices", "coordinates must be finite");
      if (v.empty() || v.back() != q) v.push_back(q);
    }
    while (v.size() > 1 && v.front() == v.back()) v.pop_back();
    if (v.size() < 3) throw InputError(src, field + ".vertices", "a polygon needs at least 3 distinct vertices");
    bool all_collinear = true;
    for (std::size_t q = 2; q < v.size() && all_collinear; ++q)
      all_collinear = exact::orientation(v[0], v[1], v[q]) == 0;
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
              ((e0[0] - shared[0]) * (e1[0] - shared[0]) > 0 || (e0[1] - shared[1]) * (e1[1] - shared[1]) > 0);
      } else {
        bad = exact::segments_intersect(p0, p1, q0, q1);
      }
      if (bad)
        throw InputError(
            src, field + ".vertices",
            "polygon is self-intersecting (edges " + std::to_string(x) + " and " + std::to_string(y) + ")");
    }
    Box2 bb{{v[0][0], v[0][1]}, {v[0][0], v[0][1]}};
    for (const Vec2& q : v) {
      bb.min = {std::min(bb.min[0], q[0]), std::min(bb.min[1], q[1])};
      bb.max = {std::max(bb.max[0], q[0]), std::max(bb.max[1], q[1])};
    }
    box_ = bb;
  }

  int side(const Vec2& p) const override { return exact::polygon_side(v_, p); }

  bool segment_events(const Vec2& a, const Vec2& b, const Box2& seg, EventSink& sink,
                      std::vector<double>& ts) const override {
    ts.clear();
    const Vec2 d{b[0] - a[0], b[1] - a[1]};
    const double dd = d[0] * d[0] + d[1] * d[1];
    if (dd == 0) return classify(a) >= 0;
    const auto& poly = v_;
    for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
      const Vec2& u = poly[j];
      const Vec2& v = poly[i];
      if (std::max(u[0], v[0]) < seg.min[0] || std::min(u[0], v[0]) > seg.max[0] || std::max(u[1], v[1]) < seg.min[1] ||
          std::min(u[1], v[1]) > seg.max[1])
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
          ts.push_back(std::clamp(num / den, std::numeric_limits<double>::denorm_min(), 1 - kUnitRoundoff));
        }
      }
    }
    // Classify each open sub-interval at its midpoint (exactly, for that point).
    return events_from_hits<2>(a, d, ts, sink, [&](const Vec2& q) { return classify(q) >= 0; });
  }

  double boundary_distance(const Vec2& p) const override {
    double d = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0, j = v_.size() - 1; i < v_.size(); j = i++)
      d = std::min(d, segment_distance(p, v_[j], v_[i]));
    return d;
  }

  bool boundary_touches(const Box2& box) const override {
    for (std::size_t i = 0, j = v_.size() - 1; i < v_.size(); j = i++)
      if (detail::segment_meets_box(v_[j], v_[i], box)) return true;
    return false;
  }

  double measure() const override {
    double s2 = 0;
    for (std::size_t i = 0, j = v_.size() - 1; i < v_.size(); j = i++) s2 += v_[j][0] * v_[i][1] - v_[i][0] * v_[j][1];
    return 0.5 * std::abs(s2);
  }

  void x_breakpoints(std::vector<double>& out) const override {
    for (const Vec2& v : v_) out.push_back(v[0]);
  }

  void nearest_boundary_points(const Vec2& p, std::vector<Vec2>& out) const override {
    // Per edge: the projection (convex along the edge) and the vertices (arc ends).
    for (std::size_t i = 0, j = v_.size() - 1; i < v_.size(); j = i++) {
      const Vec2& u = v_[j];
      const Vec2& v = v_[i];
      out.push_back(v);
      const double ex = v[0] - u[0], ey = v[1] - u[1];
      const double t = ((p[0] - u[0]) * ex + (p[1] - u[1]) * ey) / (ex * ex + ey * ey);
      if (t > 0 && t < 1) out.push_back({u[0] + t * ex, u[1] + t * ey});
    }
  }

  void boundary_meetings(const ShapeModel<2>& other, const Vec2& p, std::vector<Vec2>& out) const override {
    if (static_cast<const CurveModel&>(other).polygon_meetings(v_, out)) return;
    if (const auto* q = dynamic_cast<const PolygonModel*>(&other)) {
      const auto &pa = v_, &pb = q->v_;
      for (std::size_t i = 0, i0 = pa.size() - 1; i < pa.size(); i0 = i++)
        for (std::size_t l = 0, l0 = pb.size() - 1; l < pb.size(); l0 = l++) {
          const Vec2 &u = pa[i0], &v = pa[i], &w = pb[l0], &z = pb[l];
          if (!exact::segments_intersect(u, v, w, z)) continue;
          const double ex = v[0] - u[0], ey = v[1] - u[1], gx = z[0] - w[0], gy = z[1] - w[1];
          const double den = ex * gy - ey * gx;
          if (exact::orientation(u, v, w) == 0 && exact::orientation(u, v, z) == 0)
            continue;  // collinear: ends are vertices
          const double t = std::clamp(((w[0] - u[0]) * gy - (w[1] - u[1]) * gx) / den, 0.0, 1.0);
          out.push_back({u[0] + t * ex, u[1] + t * ey});
        }
      return;
    }
    CurveModel::boundary_meetings(other, p, out);
  }

  std::span<const Vec2> polygon_vertices() const override { return v_; }
  int piece_count() const override { return static_cast<int>(v_.size()); }

  Vec2 curve_point(int piece, double s) const override {
    const Vec2& u = v_[piece];
    const Vec2& v = v_[(piece + 1) % v_.size()];
    return {u[0] + s * (v[0] - u[0]), u[1] + s * (v[1] - u[1])};
  }

  std::vector<Vec2> boundary_polyline() const override { return v_; }

 private:
  std::vector<Vec2> v_;
};

}  // namespace

// ---------------------------------------------------------------- scene descriptors

namespace {

double polygon_area(const std::vector<Vec2>& v) {
  double s = 0;
  for (std::size_t i = 0, j = v.size() - 1; i < v.size(); j = i++) s += v[j][0] * v[i][1] - v[i][0] * v[j][1];
  return 0.5 * std::abs(s);
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

class PolygonFamily final : public FamilyOf<Polygon> {
 public:
  std::string_view name() const override { return "polygon"; }
  int dimension() const override { return 2; }
  Shape read(const FieldReader& f) const override {
    f.allow_keys({"vertices", "closed"});
    if (f.has("closed") && !f.boolean("closed")) f.fail("closed", "open polygon: an inclusion must be a closed region");
    Polygon p;
    p.vertices = f.points2("vertices");
    // A repeated first vertex at the end (GeoJSON style) closes the ring explicitly.
    if (p.vertices.size() > 1 && p.vertices.front() == p.vertices.back()) p.vertices.pop_back();
    if (p.vertices.size() < 3)
      f.fail("vertices", "open polygon: needs at least 3 distinct vertices, got " + std::to_string(p.vertices.size()));
    return p;
  }
  void write(const Shape& s, FieldWriter& f) const override { f.points("vertices", of(s).vertices); }
  Box3 bounding_box(const Shape& s) const override { return detail::points_box(of(s).vertices); }
  double measure(const Shape& s) const override { return polygon_area(of(s).vertices); }
  double boundary_measure(const Shape& s) const override {
    const auto& v = of(s).vertices;
    double l = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
      const Vec2& a = v[i];
      const Vec2& b = v[(i + 1) % v.size()];
      l += std::hypot(b[0] - a[0], b[1] - a[1]);
    }
    return l;
  }
  std::vector<Vec3> boundary_samples(const Shape& s, double spacing) const override {
    return detail::resampled_ring(of(s).vertices, spacing);
  }
  bool contains(const Shape& s, const Vec3& p) const override {
    return exact::polygon_side(of(s).vertices, {p[0], p[1]}) >= 0;
  }
  void translate(Shape& s, const Vec3& o) const override {
    for (Vec2& v : of(s).vertices) v[0] += o[0], v[1] += o[1];
  }
  bool convex(const Shape& s) const override { return is_convex_polygon(of(s).vertices); }
  double support(const Shape& s, const Vec3& d) const override {
    double h = -std::numeric_limits<double>::infinity();
    for (const Vec2& v : of(s).vertices) h = std::max(h, v[0] * d[0] + v[1] * d[1]);
    return h;
  }
  // Exact: a vertex of one inside the other, or two edges that meet (or come within gap).
  std::optional<bool> overlap_same_family(const Shape& a, const Shape& b, double gap) const override {
    const auto& u = of(a).vertices;
    const auto& v = of(b).vertices;
    if (exact::polygon_side(v, u[0]) >= 0 || exact::polygon_side(u, v[0]) >= 0) return true;
    for (std::size_t i = 0; i < u.size(); ++i)
      for (std::size_t j = 0; j < v.size(); ++j) {
        const Vec2 &p0 = u[i], &p1 = u[(i + 1) % u.size()], &q0 = v[j], &q1 = v[(j + 1) % v.size()];
        if (exact::segments_intersect(p0, p1, q0, q1)) return true;
        if (gap > 0 && detail::segments_distance(p0, p1, q0, q1) <= gap) return true;
      }
    return false;
  }
  std::unique_ptr<CurveModel> curve_model(const Shape& s, const std::string& source,
                                          const std::string& field) const override {
    return std::make_unique<PolygonModel>(of(s), source, field);
  }
};

}  // namespace

const ShapeFamily& polygon_family() {
  static const PolygonFamily family;
  return family;
}

}  // namespace cisamr::geometry
