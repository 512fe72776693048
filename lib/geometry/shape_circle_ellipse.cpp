// Circles and ellipses (README: classification, crossings, distances of each).
#include "geometry/shape_circle_ellipse.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "geometry/box_tests.hpp"
#include "geometry/shape_fields.hpp"
#include "geometry/shape_model.hpp"
#include "geometry/shapes.hpp"

namespace cisamr::geometry {
namespace {

std::vector<Vec2> polyline_of(const Shape& sh) {
  std::vector<Vec2> pts;
  const double len = shape_boundary_measure(sh);
  for (const Vec3& q : shape_boundary_samples(sh, len / 4096)) pts.push_back({q[0], q[1]});
  return pts;
}

// Closest distance from p to an axis-aligned ellipse x²/a² + y²/b² = 1 (Eberly's robust
// bisection on the quadrant-reduced problem).
double ellipse_boundary_distance_local(double a, double b, double x, double y) {
  x = std::abs(x);
  y = std::abs(y);
  if (a < b) {
    std::swap(a, b);
    std::swap(x, y);
  }
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

namespace {

class CircleModel final : public CurveModel {
 public:
  CircleModel(const Circle& c, const std::string& src, const std::string& field) {
    if (!finite(c.center)) throw InputError(src, field + ".center", "must be finite");
    if (!(c.radius > 0) || !std::isfinite(c.radius)) throw InputError(src, field + ".radius", "must be positive");
    c_ = c.center;
    r_ = c.radius;
    // Slightly loose so that the box test never rejects a point on the circle.
    const double r = r_ * (1 + 4 * kUnitRoundoff);
    box_ = {{c_[0] - r, c_[1] - r}, {c_[0] + r, c_[1] + r}};
  }

  int side(const Vec2& p) const override { return exact::circle_side(p, c_, r_); }

  bool segment_events(const Vec2& a, const Vec2& b, const Box2&, EventSink& sink, std::vector<double>&) const override {
    return sink.push_hits(exact::circle_segment_hits(a, b, c_, r_));
  }

  double boundary_distance(const Vec2& p) const override {
    return std::abs(std::hypot(p[0] - c_[0], p[1] - c_[1]) - r_);
  }
  bool boundary_touches(const Box2& box) const override { return detail::sphere_meets_box<2>(c_, r_, box); }
  double measure() const override { return M_PI * r_ * r_; }

  bool outward_normal(const Vec2& p, Vec2& n) const override {
    n = {p[0] - c_[0], p[1] - c_[1]};
    return true;
  }

  std::optional<bool> regions_intersect(const ShapeModel<2>& other, bool interiors, double depth_tol) const override {
    const auto* q = dynamic_cast<const CircleModel*>(&other);
    if (!q) return std::nullopt;
    if (!interiors) return exact::disks_side(c_, r_, q->c_, q->r_) >= 0;
    return std::hypot(q->c_[0] - c_[0], q->c_[1] - c_[1]) < r_ + q->r_ - depth_tol;
  }

  void nearest_boundary_points(const Vec2& p, std::vector<Vec2>& out) const override {
    // The distance along a circle is unimodal: one minimum.
    const double dx = p[0] - c_[0], dy = p[1] - c_[1], n = std::hypot(dx, dy);
    if (n == 0) out.push_back({c_[0] + r_, c_[1]});
    else out.push_back({c_[0] + r_ * (dx / n), c_[1] + r_ * (dy / n)});
  }

  void boundary_meetings(const ShapeModel<2>& other, const Vec2& p, std::vector<Vec2>& out) const override {
    if (const auto* q = dynamic_cast<const CircleModel*>(&other)) {
      const double dx = q->c_[0] - c_[0], dy = q->c_[1] - c_[1], d = std::hypot(dx, dy);
      if (d == 0 || d > r_ + q->r_ || d < std::abs(r_ - q->r_)) return;
      const double along = (r_ * r_ - q->r_ * q->r_ + d * d) / (2 * d);
      const double h = std::sqrt(std::max(0.0, r_ * r_ - along * along));
      const double ex = dx / d, ey = dy / d;
      out.push_back({c_[0] + along * ex - h * ey, c_[1] + along * ey + h * ex});
      out.push_back({c_[0] + along * ex + h * ey, c_[1] + along * ey - h * ex});
      return;
    }
    if (const auto poly = static_cast<const CurveModel&>(other).polygon_vertices(); !poly.empty()) {
      polygon_meetings(poly, out);
      return;
    }
    CurveModel::boundary_meetings(other, p, out);
  }

  bool polygon_meetings(std::span<const Vec2> poly, std::vector<Vec2>& out) const override {
    for (std::size_t i = 0, i0 = poly.size() - 1; i < poly.size(); i0 = i++) {
      const Vec2& u = poly[i0];
      const Vec2& v = poly[i];
      // |u + t(v−u) − c|² = r²: A t² + 2B t + C = 0.
      const double ex = v[0] - u[0], ey = v[1] - u[1], fx = u[0] - c_[0], fy = u[1] - c_[1];
      const double A = ex * ex + ey * ey, B = fx * ex + fy * ey, C = fx * fx + fy * fy - r_ * r_;
      const double disc = B * B - A * C;
      if (disc < 0) continue;
      const double sq = std::sqrt(disc);
      for (double t : {(-B - sq) / A, (-B + sq) / A})
        if (t >= 0 && t <= 1) out.push_back({u[0] + t * ex, u[1] + t * ey});
    }
    return true;
  }

  Vec2 curve_point(int, double s) const override {
    const double th = 2 * M_PI * s;
    return {c_[0] + r_ * std::cos(th), c_[1] + r_ * std::sin(th)};
  }

  std::vector<Vec2> boundary_polyline() const override { return polyline_of(Circle{c_, r_}); }

 private:
  Vec2 c_;
  double r_;
};

// The ellipse as the unit circle in the frame u = ((x−c)·e1)/a, v = ((x−c)·e2)/b.
class EllipseModel final : public CurveModel {
 public:
  EllipseModel(const Ellipse& e, const std::string& src, const std::string& field) {
    if (!finite(e.center)) throw InputError(src, field + ".center", "must be finite");
    if (!(e.semi_axes[0] > 0) || !(e.semi_axes[1] > 0) || !finite(e.semi_axes))
      throw InputError(src, field + ".semi_axes", "must be positive");
    if (!std::isfinite(e.angle)) throw InputError(src, field + ".angle", "must be finite");
    c_ = e.center;
    a_ = e.semi_axes[0];
    b_ = e.semi_axes[1];
    cs_ = std::cos(e.angle);
    sn_ = std::sin(e.angle);
    const double hx = std::hypot(a_ * cs_, b_ * sn_) * (1 + 1e-12) + 1e-300;
    const double hy = std::hypot(a_ * sn_, b_ * cs_) * (1 + 1e-12) + 1e-300;
    box_ = {{c_[0] - hx, c_[1] - hy}, {c_[0] + hx, c_[1] + hy}};
  }

  int side(const Vec2& p) const override { return tolerant_side(p); }

  bool segment_events(const Vec2& a, const Vec2& b, const Box2&, EventSink& sink, std::vector<double>&) const override {
    // The unit-circle decision with the endpoint signs of the tolerant classification,
    // so that nodes classified ON never get a crossing at t ≈ 0 or 1.
    double f0, f1;
    const int s0 = tolerant_side(a, &f0), s1 = tolerant_side(b, &f1);
    const Vec2 ua = to_unit_frame(a), ub = to_unit_frame(b);
    const double dx = ub[0] - ua[0], dy = ub[1] - ua[1];
    const double dd = dx * dx + dy * dy;
    if (dd == 0) return s0 > 0;
    const double ed = ua[0] * dx + ua[1] * dy, fd = ub[0] * dx + ub[1] * dy;
    const double disc = ed * ed + dd * f0;
    auto sgn = [](double x) { return x > 0 ? 1 : (x < 0 ? -1 : 0); };
    return sink.push_hits(exact::circle_hits_from_signs(s0, s1, sgn(ed), sgn(fd), sgn(disc), ed, dd, f0, disc));
  }

  double boundary_distance(const Vec2& p) const override {
    const double dx = p[0] - c_[0], dy = p[1] - c_[1];
    return ellipse_boundary_distance_local(a_, b_, dx * cs_ + dy * sn_, -dx * sn_ + dy * cs_);
  }

  bool boundary_touches(const Box2& box) const override {
    // F(x) = u² + v² is convex: its max over the box is at a corner; its min is at the
    // center when inside, else on one of the four edges (1D quadratic minimum).
    auto q = [&](const Vec2& p) {
      const Vec2 u = to_unit_frame(p);
      return u[0] * u[0] + u[1] * u[1];
    };
    const Vec2 corners[4] = {
        {box.min[0], box.min[1]}, {box.max[0], box.min[1]}, {box.max[0], box.max[1]}, {box.min[0], box.max[1]}};
    double qmax = 0, qmin = std::numeric_limits<double>::infinity();
    for (const Vec2& c : corners) qmax = std::max(qmax, q(c));
    if (point_in_box(c_, box)) qmin = 0;
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

  double measure() const override { return M_PI * a_ * b_; }

  bool outward_normal(const Vec2& p, Vec2& n) const override {
    const Vec2 u = to_unit_frame(p);
    const double gx = u[0] / a_, gy = u[1] / b_;  // gradient in the body frame
    n = {cs_ * gx - sn_ * gy, sn_ * gx + cs_ * gy};
    return true;
  }

  void nearest_boundary_points(const Vec2& p, std::vector<Vec2>& out) const override {
    sampled_nearest_points(p, 512, out);
  }

  Vec2 curve_point(int, double s) const override {
    const double th = 2 * M_PI * s, x = a_ * std::cos(th), y = b_ * std::sin(th);
    return {c_[0] + x * cs_ - y * sn_, c_[1] + x * sn_ + y * cs_};
  }

  std::vector<Vec2> boundary_polyline() const override {
    return polyline_of(Ellipse{c_, {a_, b_}, std::atan2(sn_, cs_)});
  }

  int meeting_samples() const override { return 1024; }

 private:
  Vec2 to_unit_frame(const Vec2& p) const {
    const double dx = p[0] - c_[0], dy = p[1] - c_[1];
    return {(dx * cs_ + dy * sn_) / a_, (-dx * sn_ + dy * cs_) / b_};
  }

  // Tolerant side: F = 1 − u² − v², |F| below the rounding bound is ON (f_out: F or 0).
  int tolerant_side(const Vec2& p, double* f_out = nullptr) const {
    const double dx = p[0] - c_[0], dy = p[1] - c_[1];
    const double u = (dx * cs_ + dy * sn_) / a_, v = (-dx * sn_ + dy * cs_) / b_;
    const double q = u * u + v * v;
    const double f = 1 - q;
    // Each of u, v carries ≲ 6u relative error of (|dx|+|dy|)/axis; squares double it.
    const double s = (std::abs(dx) + std::abs(dy));
    const double bound = 32 * kUnitRoundoff * (1 + q + s * s / (a_ * a_) + s * s / (b_ * b_));
    if (f_out) *f_out = std::abs(f) <= bound ? 0.0 : f;
    if (f > bound) return 1;
    if (f < -bound) return -1;
    return 0;
  }

  Vec2 c_;
  double a_, b_, cs_, sn_;
};

}  // namespace

// ---------------------------------------------------------------- scene descriptors

namespace {

// Closed boundary polyline: n points at equal parameter steps.
std::vector<Vec3> ellipse_polyline(const Ellipse& e, int n) {
  std::vector<Vec3> out;
  out.reserve(static_cast<std::size_t>(n));
  const double cs = std::cos(e.angle), sn = std::sin(e.angle);
  // The points of equal parameter steps by rotation (a partition's load field samples
  // millions of them), re-anchored on the exact angle every 64 steps so that rounding does
  // not drift.
  const double step = 2 * M_PI / n, cos_step = std::cos(step), sin_step = std::sin(step);
  double c = 1, s = 0;
  for (int i = 0; i < n; ++i) {
    if (i % 64 == 0) c = std::cos(step * i), s = std::sin(step * i);
    const double x = e.semi_axes[0] * c, y = e.semi_axes[1] * s;
    out.push_back({e.center[0] + cs * x - sn * y, e.center[1] + sn * x + cs * y, 0});
    const double next_c = c * cos_step - s * sin_step;
    s = s * cos_step + c * sin_step;
    c = next_c;
  }
  return out;
}

double ellipse_perimeter(double a, double b) {
  // Gauss–Kummer through the arithmetic-geometric mean: exact for every ratio of the axes,
  // converged to the last bit in a handful of steps (it replaced a 4,096-point trapezoid rule
  // that made the partitioner's load field of 11,200 ellipses take seconds).
  double an = std::max(a, b), gn = std::min(a, b);
  double sum = 0.5 * (an * an - gn * gn), power = 1;
  for (int i = 0; i < 64 && an - gn > 1e-15 * an; ++i) {  // then the next term is below 1e-28
    const double c = 0.5 * (an - gn);
    const double next_g = std::sqrt(an * gn);
    an = 0.5 * (an + gn);
    gn = next_g;
    power *= 2;
    sum += 0.5 * power * c * c;
  }
  return 2 * M_PI * (std::max(a, b) * std::max(a, b) - sum) / (0.5 * (an + gn));
}

class CircleFamily final : public FamilyOf<Circle> {
 public:
  std::string_view name() const override { return "circle"; }
  int dimension() const override { return 2; }
  Shape read(const FieldReader& f) const override {
    f.allow_keys({"center", "radius"});
    Circle c;
    c.center = f.vec<2>("center");
    c.radius = f.positive("radius");
    return c;
  }
  void write(const Shape& s, FieldWriter& f) const override {
    f.vec("center", of(s).center);
    f.number("radius", of(s).radius);
  }
  Box3 bounding_box(const Shape& s) const override {
    const Circle& c = of(s);
    return {{c.center[0] - c.radius, c.center[1] - c.radius, 0}, {c.center[0] + c.radius, c.center[1] + c.radius, 0}};
  }
  double measure(const Shape& s) const override { return M_PI * of(s).radius * of(s).radius; }
  double boundary_measure(const Shape& s) const override { return 2 * M_PI * of(s).radius; }
  std::vector<Vec3> boundary_samples(const Shape& s, double spacing) const override {
    const Circle& c = of(s);
    std::vector<Vec3> out;
    const int n = std::max(8, static_cast<int>(std::ceil(2 * M_PI * c.radius / spacing)));
    for (int i = 0; i < n; ++i)
      out.push_back({c.center[0] + c.radius * std::cos(2 * M_PI * i / n), c.center[1] + c.radius * std::sin(2 * M_PI * i / n), 0});
    return out;
  }
  bool contains(const Shape& s, const Vec3& p) const override {
    return exact::circle_side({p[0], p[1]}, of(s).center, of(s).radius) >= 0;
  }
  void translate(Shape& s, const Vec3& o) const override { of(s).center[0] += o[0], of(s).center[1] += o[1]; }
  bool convex(const Shape&) const override { return true; }
  double support(const Shape& s, const Vec3& d) const override {
    const Circle& c = of(s);
    return c.center[0] * d[0] + c.center[1] * d[1] + c.radius * std::hypot(d[0], d[1]);
  }
  std::optional<bool> overlap_same_family(const Shape& a, const Shape& b, double gap) const override {
    const Circle &ca = of(a), &cb = of(b);
    if (gap == 0) return exact::disks_side(ca.center, ca.radius, cb.center, cb.radius) >= 0;
    return std::hypot(ca.center[0] - cb.center[0], ca.center[1] - cb.center[1]) <= ca.radius + cb.radius + gap;
  }
  std::unique_ptr<CurveModel> curve_model(const Shape& s, const std::string& source,
                                          const std::string& field) const override {
    return std::make_unique<CircleModel>(of(s), source, field);
  }
};

class EllipseFamily final : public FamilyOf<Ellipse> {
 public:
  std::string_view name() const override { return "ellipse"; }
  int dimension() const override { return 2; }
  Shape read(const FieldReader& f) const override {
    f.allow_keys({"center", "semi_axes", "angle"});
    Ellipse e;
    e.center = f.vec<2>("center");
    e.semi_axes = f.positive_vec<2>("semi_axes");
    if (f.has("angle")) e.angle = f.number("angle");
    return e;
  }
  void write(const Shape& s, FieldWriter& f) const override {
    f.vec("center", of(s).center);
    f.vec("semi_axes", of(s).semi_axes);
    f.number("angle", of(s).angle);
  }
  Box3 bounding_box(const Shape& s) const override {
    const Ellipse& e = of(s);
    const double cs = std::cos(e.angle), sn = std::sin(e.angle);
    const double hx = std::hypot(e.semi_axes[0] * cs, e.semi_axes[1] * sn);
    const double hy = std::hypot(e.semi_axes[0] * sn, e.semi_axes[1] * cs);
    return {{e.center[0] - hx, e.center[1] - hy, 0}, {e.center[0] + hx, e.center[1] + hy, 0}};
  }
  double measure(const Shape& s) const override { return M_PI * of(s).semi_axes[0] * of(s).semi_axes[1]; }
  double boundary_measure(const Shape& s) const override {
    return ellipse_perimeter(of(s).semi_axes[0], of(s).semi_axes[1]);
  }
  std::vector<Vec3> boundary_samples(const Shape& s, double spacing) const override {
    // Parameter steps bounded by spacing / max axis keep chords below spacing.
    const Ellipse& e = of(s);
    const double amax = std::max(e.semi_axes[0], e.semi_axes[1]);
    return ellipse_polyline(e, std::max(8, static_cast<int>(std::ceil(2 * M_PI * amax / spacing))));
  }
  bool contains(const Shape& s, const Vec3& q) const override {
    const Ellipse& e = of(s);
    const double cs = std::cos(e.angle), sn = std::sin(e.angle);
    const double dx = q[0] - e.center[0], dy = q[1] - e.center[1];
    const double u = (dx * cs + dy * sn) / e.semi_axes[0], v = (-dx * sn + dy * cs) / e.semi_axes[1];
    return u * u + v * v <= 1 + 1e-14;
  }
  void translate(Shape& s, const Vec3& o) const override { of(s).center[0] += o[0], of(s).center[1] += o[1]; }
  bool convex(const Shape&) const override { return true; }
  double support(const Shape& s, const Vec3& d) const override {
    const Ellipse& e = of(s);
    const double cs = std::cos(e.angle), sn = std::sin(e.angle);
    const double d1 = d[0] * cs + d[1] * sn, d2 = -d[0] * sn + d[1] * cs;
    return e.center[0] * d[0] + e.center[1] * d[1] + std::hypot(e.semi_axes[0] * d1, e.semi_axes[1] * d2);
  }
  std::unique_ptr<CurveModel> curve_model(const Shape& s, const std::string& source,
                                          const std::string& field) const override {
    return std::make_unique<EllipseModel>(of(s), source, field);
  }
};

}  // namespace

const ShapeFamily& circle_family() {
  static const CircleFamily family;
  return family;
}

const ShapeFamily& ellipse_family() {
  static const EllipseFamily family;
  return family;
}

}  // namespace cisamr::geometry
