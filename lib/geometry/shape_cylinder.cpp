// Cylinders (README: classification, crossings, volumes, distances).
#include "geometry/shape_cylinder.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "geometry/predicates3.hpp"
#include "geometry/shape_fields.hpp"
#include "geometry/shape_model.hpp"

namespace cisamr::geometry {

namespace {

class CylinderModel final : public SurfaceModel {
 public:
  CylinderModel(const Shape& shape, const std::string& src, const std::string& field) : SurfaceModel(shape) {
    const Cylinder& c = std::get<Cylinder>(shape);
    if (!finite(c.start)) throw InputError(src, field + ".start", "must be finite");
    if (!finite(c.end)) throw InputError(src, field + ".end", "must be finite");
    if (!(c.radius > 0) || !std::isfinite(c.radius)) throw InputError(src, field + ".radius", "must be positive");
    const Vec3 ax = sub(c.end, c.start);
    const double len = norm(ax);
    if (!(len > 0)) throw InputError(src, field + ".end", "zero-length cylinder (end equals start)");
    s_ = c.start;
    e_ = c.end;
    r_ = c.radius;
    u_ = {ax[0] / len, ax[1] / len, ax[2] / len};
    len_ = len;
    for (int d = 0; d < 3; ++d) {
      const double h = c.radius * std::sqrt(std::max(0.0, 1 - u_[d] * u_[d])) * (1 + 1e-12) + 1e-12 * (len + c.radius);
      box_.min[d] = std::min(c.start[d], c.end[d]) - h;
      box_.max[d] = std::max(c.start[d], c.end[d]) + h;
    }
  }

  int side(const Vec3& p) const override { return exact::cylinder_side(p, s_, e_, r_); }

  bool segment_events(const Vec3& a, const Vec3& b, const Box3&, EventSink& sink, std::vector<double>&) const override {
    // Convex: the closed inside set along the line is one interval [tl, th] (rounded),
    // the topology is decided by the exact endpoint sides and exact mid-point tests.
    const double lo_t = std::numeric_limits<double>::denorm_min(), hi_t = 1 - kUnitRoundoff;
    auto push = [&](double t, bool after) { sink.push(t, after); };
    const int sa = classify(a), sb = classify(b);
    const Vec3 d = sub(b, a), w = sub(a, s_);
    double tl = -std::numeric_limits<double>::infinity(), th = std::numeric_limits<double>::infinity();
    auto clip_linear = [&](double g0, double g1) {  // g0 + t·g1 ≥ 0
      if (g1 == 0) {
        if (g0 < 0) tl = 1, th = 0;
        return;
      }
      const double t = -g0 / g1;
      if (g1 > 0) tl = std::max(tl, t);
      else th = std::min(th, t);
    };
    const double wu = dot(w, u_), du = dot(d, u_);
    clip_linear(wu, du);
    clip_linear(len_ - wu, -du);
    // Radial: |w⊥ + t d⊥|² ≤ r².
    const Vec3 wp = sub(w, Vec3{wu * u_[0], wu * u_[1], wu * u_[2]});
    const Vec3 dp = sub(d, Vec3{du * u_[0], du * u_[1], du * u_[2]});
    const double A = dot(dp, dp), B = dot(wp, dp), C = dot(wp, wp) - r_ * r_;
    if (A == 0) {
      if (C > 0) tl = 1, th = 0;
    } else {
      const double disc = B * B - A * C;
      if (disc < 0) {
        tl = 1, th = 0;
      } else {
        const double sq = std::sqrt(disc), q = B <= 0 ? -B + sq : -B - sq;
        double r1 = q / A, r2 = q != 0 ? C / q : r1;
        if (r1 > r2) std::swap(r1, r2);
        tl = std::max(tl, r1);
        th = std::min(th, r2);
      }
    }
    auto inside_at = [&](double t) { return classify(Vec3{a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]}) >= 0; };
    if (sa > 0) {
      if (sb < 0) push(std::clamp(th, lo_t, hi_t), false);
      return true;
    }
    if (sa == 0) {
      if (sb >= 0) return true;  // convex: the open segment stays in the closed body
      if (th > kMergeT && th < 1 && inside_at(0.5 * th)) {
        push(std::clamp(th, lo_t, hi_t), false);
        return true;
      }
      return false;
    }
    if (sb > 0) {
      push(std::clamp(tl, lo_t, hi_t), true);
      return false;
    }
    if (sb == 0) {
      if (tl > 0 && tl < 1 - kMergeT && inside_at(0.5 * (tl + 1))) push(std::clamp(tl, lo_t, hi_t), true);
      return false;
    }
    if (tl > 0 && th < 1 && th - tl > kMergeT && inside_at(0.5 * (tl + th))) {
      push(std::clamp(tl, lo_t, hi_t), true);
      push(std::clamp(th, lo_t, hi_t), false);
    }
    return false;
  }

  // Distance from p to the surface (axial and radial coordinates).
  double boundary_distance(const Vec3& p) const override {
    const Vec3 w = sub(p, s_);
    const double t = dot(w, u_);
    const double rho = norm(sub(w, Vec3{t * u_[0], t * u_[1], t * u_[2]}));
    const bool inside = t >= 0 && t <= len_ && rho <= r_;
    if (inside) return std::min({t, len_ - t, r_ - rho});
    const double dt = t < 0 ? -t : (t > len_ ? t - len_ : 0.0);
    const double dr = rho > r_ ? rho - r_ : 0.0;
    return std::hypot(dt, dr);
  }

  bool boundary_touches(const Box3& box) const override {
    // Box inside (all corners strictly inside the convex body) → no surface.
    bool all_inside = true;
    for (int cn = 0; cn < 8 && all_inside; ++cn)
      all_inside = exact::cylinder_side({cn & 1 ? box.max[0] : box.min[0], cn & 2 ? box.max[1] : box.min[1],
                                         cn & 4 ? box.max[2] : box.min[2]},
                                        s_, e_, r_) > 0;
    if (all_inside) return false;
    // Far apart: the ball around the box misses the capsule around the cylinder.
    Vec3 mid{};
    for (int d = 0; d < 3; ++d) mid[d] = 0.5 * (box.min[d] + box.max[d]);
    const double half = 0.5 * box_diagonal(box);
    const Vec3 w = sub(mid, s_);
    const double t = std::clamp(dot(w, u_), 0.0, len_);
    const double dist = norm(sub(w, Vec3{t * u_[0], t * u_[1], t * u_[2]}));
    return dist <= r_ + half + 1e-12 * (r_ + half);
  }

  double measure() const override { return M_PI * r_ * r_ * len_; }

  void nearest_boundary_points(const Vec3&, std::vector<Vec3>& out) const override {
    const std::vector<Vec3> samples = boundary_points(256);
    out.insert(out.end(), samples.begin(), samples.end());
  }

  bool convex() const override { return true; }

  void y_breakpoints_at(double x, std::vector<double>& out) const override {
    double M[3][3] = {};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) M[i][j] = (i == j ? 1.0 : 0.0) - u_[i] * u_[j];
    quadric_y_extent(M, s_, r_ * r_, x, out);
  }

 private:
  Vec3 s_, e_;
  double r_;
  Vec3 u_;      // unit axis
  double len_;  // |e − s|
};

}  // namespace

// ---------------------------------------------------------------- scene descriptors

namespace {

class CylinderFamily final : public FamilyOf<Cylinder> {
 public:
  std::string_view name() const override { return "cylinder"; }
  int dimension() const override { return 3; }
  Shape read(const FieldReader& f) const override {
    f.allow_keys({"start", "end", "radius"});
    Cylinder c;
    c.start = f.vec<3>("start");
    c.end = f.vec<3>("end");
    if (c.start == c.end) f.fail("end", "equals start (a cylinder of length 0)");
    c.radius = f.positive("radius");
    return c;
  }
  void write(const Shape& s, FieldWriter& f) const override {
    f.vec("start", of(s).start);
    f.vec("end", of(s).end);
    f.number("radius", of(s).radius);
  }
  Box3 bounding_box(const Shape& s) const override {
    Box3 b{};
    for (int i = 0; i < 3; ++i) {
      Vec3 d{0, 0, 0};
      d[i] = 1;
      b.max[i] = support(s, d);
      d[i] = -1;
      b.min[i] = -support(s, d);
    }
    return b;
  }
  double measure(const Shape& s) const override {
    const Cylinder& c = of(s);
    const Vec3 ax{c.end[0] - c.start[0], c.end[1] - c.start[1], c.end[2] - c.start[2]};
    return M_PI * c.radius * c.radius * norm(ax);
  }
  double boundary_measure(const Shape& s) const override {
    const Cylinder& c = of(s);
    const Vec3 ax{c.end[0] - c.start[0], c.end[1] - c.start[1], c.end[2] - c.start[2]};
    return 2 * M_PI * c.radius * norm(ax) + 2 * M_PI * c.radius * c.radius;
  }
  std::vector<Vec3> boundary_samples(const Shape& s, double spacing) const override {
    const Cylinder& c = of(s);
    std::vector<Vec3> out;
    const Vec3 ax{c.end[0] - c.start[0], c.end[1] - c.start[1], c.end[2] - c.start[2]};
    const double l = norm(ax);
    const Vec3 u{ax[0] / l, ax[1] / l, ax[2] / l};
    // Two unit vectors orthogonal to the axis.
    Vec3 v = std::abs(u[0]) < 0.9 ? Vec3{0, -u[2], u[1]} : Vec3{-u[2], 0, u[0]};
    const double nv = norm(v);
    v = {v[0] / nv, v[1] / nv, v[2] / nv};
    const Vec3 w{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const int nring = std::max(8, static_cast<int>(std::ceil(2 * M_PI * c.radius / spacing)));
    const int nlen = std::max(1, static_cast<int>(std::ceil(l / spacing)));
    auto at = [&](double t, double rad, double ang) {
      Vec3 p{};
      for (int k = 0; k < 3; ++k) p[k] = c.start[k] + t * ax[k] + rad * (std::cos(ang) * v[k] + std::sin(ang) * w[k]);
      return p;
    };
    for (int i = 0; i <= nlen; ++i)
      for (int j = 0; j < nring; ++j) out.push_back(at(double(i) / nlen, c.radius, 2 * M_PI * j / nring));
    const int nrad = std::max(1, static_cast<int>(std::ceil(c.radius / spacing)));
    for (int cap = 0; cap < 2; ++cap)
      for (int i = 0; i < nrad; ++i) {
        const double rad = c.radius * i / nrad;
        const int n = std::max(1, static_cast<int>(std::ceil(2 * M_PI * rad / spacing)));
        for (int j = 0; j < n; ++j) out.push_back(at(cap, rad, 2 * M_PI * j / n));
      }
    return out;
  }
  bool contains(const Shape& s, const Vec3& p) const override {
    const Cylinder& c = of(s);
    const Vec3 ax{c.end[0] - c.start[0], c.end[1] - c.start[1], c.end[2] - c.start[2]};
    const Vec3 d{p[0] - c.start[0], p[1] - c.start[1], p[2] - c.start[2]};
    const double ll = dot(ax, ax), t = dot(d, ax);
    if (t < 0 || t > ll) return false;
    return dot(d, d) - t * t / ll <= c.radius * c.radius;
  }
  void translate(Shape& s, const Vec3& o) const override {
    for (int k = 0; k < 3; ++k) of(s).start[k] += o[k], of(s).end[k] += o[k];
  }
  bool convex(const Shape&) const override { return true; }
  double support(const Shape& s, const Vec3& d) const override {
    const Cylinder& c = of(s);
    const Vec3 ax{c.end[0] - c.start[0], c.end[1] - c.start[1], c.end[2] - c.start[2]};
    const double l = norm(ax);
    const double du = dot(d, ax) / l;
    return std::max(dot(c.start, d), dot(c.end, d)) + c.radius * std::sqrt(std::max(0.0, dot(d, d) - du * du));
  }
  std::unique_ptr<SurfaceModel> surface_model(const Shape& s, const std::string& source,
                                              const std::string& field) const override {
    return std::make_unique<CylinderModel>(s, source, field);
  }
};

}  // namespace

const ShapeFamily& cylinder_family() {
  static const CylinderFamily family;
  return family;
}

}  // namespace cisamr::geometry
