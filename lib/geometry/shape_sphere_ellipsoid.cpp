// Spheres and ellipsoids (README: classification, crossings, volumes, distances).
#include "geometry/shape_sphere_ellipsoid.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "geometry/box_tests.hpp"
#include "geometry/predicates3.hpp"
#include "geometry/shape_fields.hpp"
#include "geometry/shape_model.hpp"

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

// ---------------------------------------------------------------- scene descriptors

namespace {

// Fibonacci points of the unit sphere, mapped.
template <class Map>
std::vector<Vec3> fibonacci(int n, Map&& map) {
  std::vector<Vec3> out;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(std::max(0.0, 1 - z * z));
    out.push_back(map(Vec3{r * std::cos(golden * i), r * std::sin(golden * i), z}));
  }
  return out;
}

// Body coordinates of an ellipsoid: columns of `rotation` are the body axes.
Vec3 to_body(const Ellipsoid& e, const Vec3& p) {
  const Vec3 d{p[0] - e.center[0], p[1] - e.center[1], p[2] - e.center[2]};
  Vec3 b{};
  for (int j = 0; j < 3; ++j) b[j] = e.rotation[0][j] * d[0] + e.rotation[1][j] * d[1] + e.rotation[2][j] * d[2];
  return b;
}
Vec3 from_body(const Ellipsoid& e, const Vec3& b) {
  Vec3 p = e.center;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) p[i] += e.rotation[i][j] * b[j];
  return p;
}

// Midpoint-rule samples of the quadric surface centre + frame·(a sinθ cosφ, b sinθ sinφ,
// c cosθ) over the parameter rectangle [t0, t1] × [f0, f1], recursively halved; a piece
// whose points all lie farther than its reach from `clip` is skipped.
struct QuadricPatches {
  Vec3 center, semi;
  Rotation3 frame;  // columns: the body axes in the world
  double reach_scale, spacing;
  const Box3& clip;
  std::vector<Vec3>& points;
  std::vector<double>& areas;

  Vec3 at(double t, double f, Vec3* dt, Vec3* df) const {
    const Vec3 body{semi[0] * std::sin(t) * std::cos(f), semi[1] * std::sin(t) * std::sin(f), semi[2] * std::cos(t)};
    const Vec3 body_t{semi[0] * std::cos(t) * std::cos(f), semi[1] * std::cos(t) * std::sin(f), -semi[2] * std::sin(t)};
    const Vec3 body_f{-semi[0] * std::sin(t) * std::sin(f), semi[1] * std::sin(t) * std::cos(f), 0};
    Vec3 p = center;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        p[i] += frame[i][j] * body[j];
        (*dt)[i] += frame[i][j] * body_t[j];
        (*df)[i] += frame[i][j] * body_f[j];
      }
    return p;
  }

  void visit(double t0, double t1, double f0, double f1, int depth) {
    const double tm = 0.5 * (t0 + t1), fm = 0.5 * (f0 + f1);
    Vec3 dt{}, df{};
    const Vec3 p = at(tm, fm, &dt, &df);
    // Every point of the piece is within `reach` of p (arc lengths along both parameters).
    const double reach = reach_scale * ((t1 - t0) + (f1 - f0));
    for (int d = 0; d < 3; ++d)
      if (!(p[d] + reach >= clip.min[d] && p[d] - reach <= clip.max[d])) return;
    if (reach <= 2 * spacing || depth >= kMaxDepth) {
      if (point_in_box<3>(p, clip)) {
        points.push_back(p);
        areas.push_back(norm(cross(dt, df)) * (t1 - t0) * (f1 - f0));
      }
      return;
    }
    visit(t0, tm, f0, fm, depth + 1);
    visit(t0, tm, fm, f1, depth + 1);
    visit(tm, t1, f0, fm, depth + 1);
    visit(tm, t1, fm, f1, depth + 1);
  }

  static constexpr int kMaxDepth = 52;  // parameter steps near the double resolution of π
};

void quadric_samples_within(const Vec3& center, const Vec3& semi, const Rotation3& frame, double spacing,
                            const Box3& clip, std::vector<Vec3>& points, std::vector<double>& areas) {
  points.clear();
  areas.clear();
  const double amax = std::max({semi[0], semi[1], semi[2]});
  QuadricPatches{center, semi, frame, amax, spacing, clip, points, areas}.visit(0, M_PI, 0, 2 * M_PI, 0);
}

class SphereFamily final : public FamilyOf<Sphere> {
 public:
  std::string_view name() const override { return "sphere"; }
  int dimension() const override { return 3; }
  Shape read(const FieldReader& f) const override {
    f.allow_keys({"center", "radius"});
    Sphere s;
    s.center = f.vec<3>("center");
    s.radius = f.positive("radius");
    return s;
  }
  void write(const Shape& s, FieldWriter& f) const override {
    f.vec("center", of(s).center);
    f.number("radius", of(s).radius);
  }
  Box3 bounding_box(const Shape& s) const override {
    const Sphere& sp = of(s);
    const double r = sp.radius;
    return {{sp.center[0] - r, sp.center[1] - r, sp.center[2] - r}, {sp.center[0] + r, sp.center[1] + r, sp.center[2] + r}};
  }
  double measure(const Shape& s) const override { return 4.0 / 3.0 * M_PI * std::pow(of(s).radius, 3); }
  double boundary_measure(const Shape& s) const override { return 4 * M_PI * of(s).radius * of(s).radius; }
  std::vector<Vec3> boundary_samples(const Shape& s, double spacing) const override {
    const Sphere& sp = of(s);
    const int n = std::max(12, static_cast<int>(std::ceil(2 * boundary_measure(s) / (spacing * spacing))));
    return fibonacci(n, [&](const Vec3& u) {
      return Vec3{sp.center[0] + sp.radius * u[0], sp.center[1] + sp.radius * u[1], sp.center[2] + sp.radius * u[2]};
    });
  }
  void boundary_samples_within(const Shape& s, double spacing, const Box3& clip, std::vector<Vec3>& points,
                               std::vector<double>& areas) const override {
    const Sphere& sp = of(s);
    quadric_samples_within(sp.center, {sp.radius, sp.radius, sp.radius}, Rotation3{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}},
                           spacing, clip, points, areas);
  }
  bool contains(const Shape& s, const Vec3& p) const override {
    const Sphere& sp = of(s);
    const Vec3 d{p[0] - sp.center[0], p[1] - sp.center[1], p[2] - sp.center[2]};
    return dot(d, d) <= sp.radius * sp.radius;
  }
  void translate(Shape& s, const Vec3& o) const override {
    for (int k = 0; k < 3; ++k) of(s).center[k] += o[k];
  }
  bool convex(const Shape&) const override { return true; }
  double support(const Shape& s, const Vec3& d) const override { return dot(of(s).center, d) + of(s).radius * norm(d); }
  std::optional<bool> overlap_same_family(const Shape& a, const Shape& b, double gap) const override {
    const Sphere &sa = of(a), &sb = of(b);
    const Vec3 d{sa.center[0] - sb.center[0], sa.center[1] - sb.center[1], sa.center[2] - sb.center[2]};
    const double r = sa.radius + sb.radius + gap;
    return dot(d, d) <= r * r;
  }
  std::unique_ptr<SurfaceModel> surface_model(const Shape& s, const std::string& source,
                                              const std::string& field) const override {
    return std::make_unique<SphereModel>(s, source, field);
  }
};

class EllipsoidFamily final : public FamilyOf<Ellipsoid> {
 public:
  std::string_view name() const override { return "ellipsoid"; }
  int dimension() const override { return 3; }
  Shape read(const FieldReader& f) const override {
    f.allow_keys({"center", "semi_axes", "rotation"});
    Ellipsoid e;
    e.center = f.vec<3>("center");
    e.semi_axes = f.positive_vec<3>("semi_axes");
    if (f.has("rotation")) e.rotation = f.rotation("rotation");
    return e;
  }
  void write(const Shape& s, FieldWriter& f) const override {
    const Ellipsoid& e = of(s);
    f.vec("center", e.center);
    f.vec("semi_axes", e.semi_axes);
    if (!is_identity(e.rotation)) f.rotation("rotation", e.rotation);
  }
  Box3 bounding_box(const Shape& s) const override {
    const Ellipsoid& e = of(s);
    Box3 b{};
    for (int d = 0; d < 3; ++d) {
      const double h = ellipsoid_half_extent(e, d);
      b.min[d] = e.center[d] - h, b.max[d] = e.center[d] + h;
    }
    return b;
  }
  double measure(const Shape& s) const override {
    return 4.0 / 3.0 * M_PI * of(s).semi_axes[0] * of(s).semi_axes[1] * of(s).semi_axes[2];
  }
  double boundary_measure(const Shape& s) const override {
    // ∫∫ |r_θ × r_φ|: Gauss–Legendre in θ (64 panels × 8 points), trapezoid in φ.
    static const double gx[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
    static const double gw[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
    const Ellipsoid& e = of(s);
    const double a = e.semi_axes[0], b = e.semi_axes[1], c = e.semi_axes[2];
    const int panels = 64, nphi = 256;
    double total = 0;
    for (int pn = 0; pn < panels; ++pn) {
      const double t0 = M_PI * pn / panels, h = M_PI / panels;
      for (int g = 0; g < 8; ++g) {
        const double x = g < 4 ? -gx[g] : gx[g - 4], w = gw[g < 4 ? g : g - 4];
        const double th = t0 + 0.5 * h * (1 + x), st = std::sin(th), ct = std::cos(th);
        double ring = 0;
        for (int k = 0; k < nphi; ++k) {
          const double ph = 2 * M_PI * (k + 0.5) / nphi, cp = std::cos(ph), sp = std::sin(ph);
          ring += st * std::sqrt(b * b * c * c * st * st * cp * cp + a * a * c * c * st * st * sp * sp + a * a * b * b * ct * ct);
        }
        total += 0.5 * h * w * ring * 2 * M_PI / nphi;
      }
    }
    return total;
  }
  std::vector<Vec3> boundary_samples(const Shape& s, double spacing) const override {
    const Ellipsoid& e = of(s);
    const double amax = std::max({e.semi_axes[0], e.semi_axes[1], e.semi_axes[2]});
    const int n = std::max(12, static_cast<int>(std::ceil(2 * 4 * M_PI * amax * amax / (spacing * spacing))));
    return fibonacci(n, [&](const Vec3& u) {
      return from_body(e, Vec3{e.semi_axes[0] * u[0], e.semi_axes[1] * u[1], e.semi_axes[2] * u[2]});
    });
  }
  void boundary_samples_within(const Shape& s, double spacing, const Box3& clip, std::vector<Vec3>& points,
                               std::vector<double>& areas) const override {
    const Ellipsoid& e = of(s);
    quadric_samples_within(e.center, e.semi_axes, e.rotation, spacing, clip, points, areas);
  }
  bool contains(const Shape& s, const Vec3& p) const override {
    const Ellipsoid& e = of(s);
    const Vec3 b = to_body(e, p);
    double q = 0;
    for (int j = 0; j < 3; ++j) q += (b[j] / e.semi_axes[j]) * (b[j] / e.semi_axes[j]);
    return q <= 1 + 1e-14;
  }
  void translate(Shape& s, const Vec3& o) const override {
    for (int k = 0; k < 3; ++k) of(s).center[k] += o[k];
  }
  bool convex(const Shape&) const override { return true; }
  double support(const Shape& s, const Vec3& d) const override {
    const Ellipsoid& e = of(s);
    Vec3 db{};
    for (int j = 0; j < 3; ++j)
      db[j] = e.semi_axes[j] * (e.rotation[0][j] * d[0] + e.rotation[1][j] * d[1] + e.rotation[2][j] * d[2]);
    return dot(e.center, d) + norm(db);
  }
  std::unique_ptr<SurfaceModel> surface_model(const Shape& s, const std::string& source,
                                              const std::string& field) const override {
    return std::make_unique<EllipsoidModel>(s, source, field);
  }
};

}  // namespace

const ShapeFamily& sphere_family() {
  static const SphereFamily family;
  return family;
}

const ShapeFamily& ellipsoid_family() {
  static const EllipsoidFamily family;
  return family;
}

}  // namespace cisamr::geometry
