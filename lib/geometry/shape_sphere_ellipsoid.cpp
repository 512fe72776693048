// Spheres and ellipsoids (README: classification, crossings, volumes, distances).
#include "geometry/shape_sphere_ellipsoid.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "geometry/box_tests.hpp"
#include "geometry/predicates3.hpp"

namespace cisamr::geometry {
namespace {

// Distance from body-frame point y to the ellipsoid surface with semi-axes a (inside or
// outside), by bisection on the Lagrange parameter; also the closest point.
double ellipsoid_surface_distance(const Vec3& a, Vec3 y, Vec3* closest = nullptr) {
  const double amax = std::max({a[0], a[1], a[2]}), amin = std::min({a[0], a[1], a[2]});
  Vec3 sg{};
  for (int i = 0; i < 3; ++i) {
    sg[i] = y[i] < 0 ? -1 : 1;
    // A 1e-15 nudge off the symmetry planes removes the degenerate branches; the
    // distance is 1-Lipschitz, so the error is at most 2e-15·amax.
    y[i] = std::abs(y[i]) + 1e-15 * amax;
  }
  auto F = [&](double t) {
    double s = 0;
    for (int i = 0; i < 3; ++i) {
      const double v = a[i] * y[i] / (t + a[i] * a[i]);
      s += v * v;
    }
    return s - 1;
  };
  double lo = -amin * amin, hi = amax * norm(y) + amax * amax;
  for (int it = 0; it < 2000; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    if (F(mid) > 0) lo = mid;
    else hi = mid;
  }
  const double t = 0.5 * (lo + hi);
  Vec3 x{};
  for (int i = 0; i < 3; ++i) x[i] = a[i] * a[i] * y[i] / (t + a[i] * a[i]);
  if (closest)
    for (int i = 0; i < 3; ++i) (*closest)[i] = sg[i] * x[i];
  return norm(sub(x, y));
}

}  // namespace

namespace {

class SphereModel final : public SurfaceModel {
 public:
  SphereModel(const Shape& shape, const std::string& src, const std::string& field) : SurfaceModel(shape) {
    const Sphere& sp = std::get<Sphere>(shape);
    if (!finite(sp.center)) throw InputError(src, field + ".center", "must be finite");
    if (!(sp.radius > 0) || !std::isfinite(sp.radius)) throw InputError(src, field + ".radius", "must be positive");
    c_ = sp.center;
    r_ = sp.radius;
    const double r = sp.radius * (1 + 4 * kUnitRoundoff);
    for (int d = 0; d < 3; ++d) box_.min[d] = sp.center[d] - r, box_.max[d] = sp.center[d] + r;
  }

  int side(const Vec3& p) const override { return exact::sphere_side(p, c_, r_); }

  bool segment_events(const Vec3& a, const Vec3& b, const Box3&, EventSink& sink, std::vector<double>&) const override {
    return sink.push_hits(exact::sphere_segment_hits(a, b, c_, r_));
  }

  double boundary_distance(const Vec3& p) const override { return std::abs(norm(sub(p, c_)) - r_); }
  bool boundary_touches(const Box3& box) const override { return detail::sphere_meets_box<3>(c_, r_, box); }
  double measure() const override { return 4.0 / 3.0 * M_PI * std::pow(r_, 3); }

  bool outward_normal(const Vec3& p, Vec3& n) const override {
    n = sub(p, c_);
    return true;
  }

  void x_breakpoints(std::vector<double>& out) const override {
    out.push_back(c_[0] - r_);
    out.push_back(c_[0] + r_);
  }

  std::optional<bool> regions_intersect(const ShapeModel<3>& other, bool interiors, double depth_tol) const override {
    const auto* q = dynamic_cast<const SphereModel*>(&other);
    if (!q) return std::nullopt;
    if (!interiors) return exact::balls_side(c_, r_, q->c_, q->r_) >= 0;
    return norm(sub(q->c_, c_)) < r_ + q->r_ - depth_tol;
  }

  void nearest_boundary_points(const Vec3& p, std::vector<Vec3>& out) const override {
    const Vec3 d = sub(p, c_);
    const double n = norm(d);
    out.push_back(n == 0 ? Vec3{c_[0] + r_, c_[1], c_[2]}
                         : Vec3{c_[0] + r_ * d[0] / n, c_[1] + r_ * d[1] / n, c_[2] + r_ * d[2] / n});
  }

  // The intersection circle (center o, radius h, normal n); its nearest point to p is
  // o + h·(projection of p − o on the circle's plane, normalised).
  void boundary_meetings(const ShapeModel<3>& other, const Vec3& p, std::vector<Vec3>& out) const override {
    const auto* s2 = dynamic_cast<const SphereModel*>(&other);
    Vec3 o, n;
    double h;
    if (!s2 || !meeting_circle(*s2, o, n, h)) return;
    const Vec3 w = sub(p, o);
    Vec3 t = sub(w, Vec3{dot(w, n) * n[0], dot(w, n) * n[1], dot(w, n) * n[2]});
    double tn = norm(t);
    if (tn == 0) {
      t = std::abs(n[0]) < 0.9 ? cross(n, Vec3{1, 0, 0}) : cross(n, Vec3{0, 1, 0});
      tn = norm(t);
    }
    out.push_back({o[0] + h * t[0] / tn, o[1] + h * t[1] / tn, o[2] + h * t[2] / tn});
  }

  bool convex() const override { return true; }

  void y_breakpoints_at(double x, std::vector<double>& out) const override {
    const double h = std::sqrt(std::max(0.0, r_ * r_ - (x - c_[0]) * (x - c_[0])));
    out.push_back(c_[1] - h);
    out.push_back(c_[1] + h);
  }

  // Overlapping sphere pairs: their section circles start/stop meeting at the x-extent
  // of the spheres' intersection circle (a kink of the section area).
  void pair_x_breakpoints(const SurfaceModel& other, std::vector<double>& out) const override {
    const auto* s2 = dynamic_cast<const SphereModel*>(&other);
    if (!s2) return;
    const Vec3 d = sub(s2->c_, c_);
    const double dist = norm(d);
    if (dist == 0 || dist >= r_ + s2->r_ || dist <= std::abs(r_ - s2->r_)) return;
    const double along = (r_ * r_ - s2->r_ * s2->r_ + dist * dist) / (2 * dist);
    const double h = std::sqrt(std::max(0.0, r_ * r_ - along * along));
    const double ox = c_[0] + along * d[0] / dist, nx = d[0] / dist;
    const double ext = h * std::sqrt(std::max(0.0, 1 - nx * nx));
    out.push_back(ox - ext);
    out.push_back(ox + ext);
  }

  // Sphere pairs: where their section circles cross, the z-length has a kink in y.
  void pair_y_breakpoints_at(const SurfaceModel& other, double x, std::vector<double>& out) const override {
    const auto* s2 = dynamic_cast<const SphereModel*>(&other);
    if (!s2) return;
    const double q1 = r_ * r_ - (x - c_[0]) * (x - c_[0]);
    const double q2 = s2->r_ * s2->r_ - (x - s2->c_[0]) * (x - s2->c_[0]);
    if (q1 <= 0 || q2 <= 0) return;
    const double r1 = std::sqrt(q1), r2 = std::sqrt(q2);
    const double dy = s2->c_[1] - c_[1], dz = s2->c_[2] - c_[2], dist = std::hypot(dy, dz);
    if (dist == 0 || dist > r1 + r2 || dist < std::abs(r1 - r2)) return;
    const double along = (r1 * r1 - r2 * r2 + dist * dist) / (2 * dist);
    const double h = std::sqrt(std::max(0.0, r1 * r1 - along * along));
    out.push_back(c_[1] + along * dy / dist - h * dz / dist);
    out.push_back(c_[1] + along * dy / dist + h * dz / dist);
  }

  // The circle of this sphere and b meets c in up to two points.
  void triple_meetings(const SurfaceModel& b, const SurfaceModel& c, std::vector<Vec3>& out) const override {
    const auto* s2 = dynamic_cast<const SphereModel*>(&b);
    const auto* s3 = dynamic_cast<const SphereModel*>(&c);
    Vec3 o, n;
    double h;
    if (!s2 || !s3 || !meeting_circle(*s2, o, n, h)) return;
    // Points o + h(cos φ e1 + sin φ e2) with |· − c3|² = r3²: α cos φ + β sin φ = γ.
    const Vec3 e1 = std::abs(n[0]) < 0.9 ? cross(n, Vec3{1, 0, 0}) : cross(n, Vec3{0, 1, 0});
    const double n1 = norm(e1);
    const Vec3 u1{e1[0] / n1, e1[1] / n1, e1[2] / n1};
    const Vec3 u2 = cross(n, u1);
    const Vec3 oc = sub(o, s3->c_);
    const double alpha = 2 * h * dot(oc, u1), beta = 2 * h * dot(oc, u2);
    const double gamma = s3->r_ * s3->r_ - dot(oc, oc) - h * h;
    const double rr = std::hypot(alpha, beta);
    if (rr == 0 || std::abs(gamma) > rr) return;
    const double phi0 = std::atan2(beta, alpha), dphi = std::acos(std::clamp(gamma / rr, -1.0, 1.0));
    for (double phi : {phi0 - dphi, phi0 + dphi})
      out.push_back({o[0] + h * (std::cos(phi) * u1[0] + std::sin(phi) * u2[0]),
                     o[1] + h * (std::cos(phi) * u1[1] + std::sin(phi) * u2[1]),
                     o[2] + h * (std::cos(phi) * u1[2] + std::sin(phi) * u2[2])});
  }

 private:
  // The circle where this sphere meets `other` (center o, unit normal n, radius h), if any.
  bool meeting_circle(const SphereModel& s2, Vec3& o, Vec3& n, double& h) const {
    const Vec3 d = sub(s2.c_, c_);
    const double dist = norm(d);
    if (dist == 0 || dist > r_ + s2.r_ || dist < std::abs(r_ - s2.r_)) return false;
    n = {d[0] / dist, d[1] / dist, d[2] / dist};
    const double along = (r_ * r_ - s2.r_ * s2.r_ + dist * dist) / (2 * dist);
    h = std::sqrt(std::max(0.0, r_ * r_ - along * along));
    o = {c_[0] + along * n[0], c_[1] + along * n[1], c_[2] + along * n[2]};
    return true;
  }

  Vec3 c_;
  double r_;
};

// Body coordinate j of p is Σ_i rot[i][j]·(p − c)_i; divided by axis[j] it lands on the
// unit sphere.
class EllipsoidModel final : public SurfaceModel {
 public:
  EllipsoidModel(const Shape& shape, const std::string& src, const std::string& field) : SurfaceModel(shape) {
    const Ellipsoid& e = std::get<Ellipsoid>(shape);
    if (!finite(e.center)) throw InputError(src, field + ".center", "must be finite");
    if (!(e.semi_axes[0] > 0) || !(e.semi_axes[1] > 0) || !(e.semi_axes[2] > 0) || !finite(e.semi_axes))
      throw InputError(src, field + ".semi_axes", "must be positive");
    if (!orthonormal(e.rotation)) throw InputError(src, field + ".rotation", "must be orthonormal");
    c_ = e.center;
    axis_ = e.semi_axes;
    rot_ = e.rotation;
    // Loose by rounding so that the box test never rejects a point ON the ellipsoid.
    for (int d = 0; d < 3; ++d) {
      const double h = ellipsoid_half_extent(e, d) * (1 + 1e-12) + 1e-300;
      box_.min[d] = e.center[d] - h, box_.max[d] = e.center[d] + h;
    }
  }

  int side(const Vec3& p) const override { return tolerant_side(p); }

  bool segment_events(const Vec3& a, const Vec3& b, const Box3&, EventSink& sink, std::vector<double>&) const override {
    double f0, f1;
    const int s0 = tolerant_side(a, &f0), s1 = tolerant_side(b, &f1);
    const Vec3 ua = unit_frame(a), ub = unit_frame(b);
    const Vec3 d = sub(ub, ua);
    const double dd = dot(d, d);
    if (dd == 0) return s0 > 0;
    const double ed = dot(ua, d), fd = dot(ub, d);
    const double disc = ed * ed + dd * f0;
    auto sgn = [](double x) { return x > 0 ? 1 : (x < 0 ? -1 : 0); };
    return sink.push_hits(exact::circle_hits_from_signs(s0, s1, sgn(ed), sgn(fd), sgn(disc), ed, dd, f0, disc));
  }

  double boundary_distance(const Vec3& p) const override { return ellipsoid_surface_distance(axis_, to_body(p)); }

  bool boundary_touches(const Box3& box) const override {
    // q = |u|² is convex: max over the box at a corner; min bounded below by the
    // tangent plane at an approximate minimiser y (q(x) ≥ q(y) + ∇q(y)·(x − y)).
    auto q = [&](const Vec3& p) {
      const Vec3 u = unit_frame(p);
      return dot(u, u);
    };
    double qmax = 0;
    for (int c = 0; c < 8; ++c)
      qmax = std::max(
          qmax, q({c & 1 ? box.max[0] : box.min[0], c & 2 ? box.max[1] : box.min[1], c & 4 ? box.max[2] : box.min[2]}));
    if (qmax < 1 - 1e-9) return false;  // the box is inside
    // Gradient of q in world coordinates: 2·R·diag(1/a²)·body.
    auto grad = [&](const Vec3& p) {
      const Vec3 bd = to_body(p);
      Vec3 g{};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) g[i] += 2 * rot_[i][j] * bd[j] / (axis_[j] * axis_[j]);
      return g;
    };
    Vec3 y{};
    for (int d = 0; d < 3; ++d) y[d] = std::clamp(c_[d], box.min[d], box.max[d]);
    // Projected coordinate descent (exact 1D minimisation of the quadratic per axis).
    for (int iter = 0; iter < 60; ++iter)
      for (int d = 0; d < 3; ++d) {
        double h = 0;
        for (int j = 0; j < 3; ++j) h += 2 * (rot_[d][j] / axis_[j]) * (rot_[d][j] / axis_[j]);
        y[d] = std::clamp(y[d] - grad(y)[d] / h, box.min[d], box.max[d]);
      }
    const Vec3 g = grad(y);
    double lower = q(y);
    for (int d = 0; d < 3; ++d) lower += std::min(g[d] * (box.min[d] - y[d]), g[d] * (box.max[d] - y[d]));
    return lower <= 1 + 1e-9;
  }

  double measure() const override { return 4.0 / 3.0 * M_PI * axis_[0] * axis_[1] * axis_[2]; }

  bool outward_normal(const Vec3& p, Vec3& n) const override {
    const Vec3 u = unit_frame(p);
    n = {};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) n[i] += rot_[i][j] * u[j] / axis_[j];
    return true;
  }

  void nearest_boundary_points(const Vec3& p, std::vector<Vec3>& out) const override {
    Vec3 xb{};
    ellipsoid_surface_distance(axis_, to_body(p), &xb);
    Vec3 q = c_;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) q[i] += rot_[i][j] * xb[j];
    out.push_back(q);
    const std::vector<Vec3> samples = boundary_points(256);
    out.insert(out.end(), samples.begin(), samples.end());
  }

  bool convex() const override { return true; }

  void y_breakpoints_at(double x, std::vector<double>& out) const override {
    // y-extent of the quadric section at x: (p−c)ᵀM(p−c) ≤ 1 minimised over z.
    double M[3][3] = {};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int l = 0; l < 3; ++l) M[i][j] += rot_[i][l] * rot_[j][l] / (axis_[l] * axis_[l]);
    quadric_y_extent(M, c_, 1, x, out);
  }

 private:
  Vec3 to_body(const Vec3& p) const {
    const Vec3 d = sub(p, c_);
    Vec3 b{};
    for (int j = 0; j < 3; ++j) b[j] = rot_[0][j] * d[0] + rot_[1][j] * d[1] + rot_[2][j] * d[2];
    return b;
  }

  Vec3 unit_frame(const Vec3& p) const {
    const Vec3 b = to_body(p);
    return {b[0] / axis_[0], b[1] / axis_[1], b[2] / axis_[2]};
  }

  // Tolerant side: F = 1 − |u|², ON within the rounding bound of its evaluation.
  int tolerant_side(const Vec3& p, double* f_out = nullptr) const {
    const Vec3 d = sub(p, c_);
    const Vec3 u = unit_frame(p);
    const double q = dot(u, u), f = 1 - q;
    const double s = std::abs(d[0]) + std::abs(d[1]) + std::abs(d[2]);
    double inv = 0;
    for (int j = 0; j < 3; ++j) inv += 1 / (axis_[j] * axis_[j]);
    const double bound = 48 * kUnitRoundoff * (1 + q + s * s * inv);
    if (f_out) *f_out = std::abs(f) <= bound ? 0.0 : f;
    if (f > bound) return 1;
    if (f < -bound) return -1;
    return 0;
  }

  Vec3 c_;
  Vec3 axis_;
  Rotation3 rot_;
};

}  // namespace

double ellipsoid_half_extent(const Ellipsoid& e, int d) {
  double h2 = 0;
  for (int j = 0; j < 3; ++j) h2 += (e.rotation[d][j] * e.semi_axes[j]) * (e.rotation[d][j] * e.semi_axes[j]);
  return std::sqrt(h2);
}

std::unique_ptr<SurfaceModel> make_sphere_model(const Shape& shape, const std::string& source,
                                                const std::string& field) {
  return std::make_unique<SphereModel>(shape, source, field);
}

std::unique_ptr<SurfaceModel> make_ellipsoid_model(const Shape& shape, const std::string& source,
                                                   const std::string& field) {
  return std::make_unique<EllipsoidModel>(shape, source, field);
}

}  // namespace cisamr::geometry
