// The 3D geometry oracle (contract in oracle3.hpp, schemes in README.md). Exact
// predicates live in predicates3.cpp, the STL machinery in stl_mesh.cpp and the CGAL
// search trees in box_index.cpp; this file holds the shape evaluators, crossings,
// validation, volumes and distances. No CGAL header here.
#include "geometry/oracle3.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.hpp"
#include "core/vec_math.hpp"
#include "geometry/box_index.hpp"
#include "geometry/box_tests.hpp"
#include "geometry/overlap_groups.hpp"
#include "geometry/predicates3.hpp"
#include "geometry/shapes.hpp"
#include "geometry/shapes_detail.hpp"
#include "geometry/stl_mesh.hpp"

namespace cisamr::geometry {
namespace {

constexpr double kUnitRoundoff = std::numeric_limits<double>::epsilon() * 0.5;
constexpr double kMergeT = 64 * std::numeric_limits<double>::epsilon();

enum class Kind : std::uint8_t { sphere, ellipsoid, cylinder, stl };

struct SphereData {
  Vec3 c;
  double r;
};
// Ellipsoid: body coordinate j of p is Σ_i rot[i][j]·(p − c)_i, divided by axis[j] it
// lands on the unit sphere.
struct EllipsoidData {
  Vec3 c;
  Vec3 axis;
  Rotation3 rot;
};
struct CylinderData {
  Vec3 s, e;
  double r;
  Vec3 u;      // unit axis
  double len;  // |e − s|
};

struct Item {
  Kind kind;
  std::int32_t data;
  std::int32_t phase;
  std::int32_t levels;
  std::int32_t group = -1;
  Box3 box;
};

double box_size(const Box3& b) { return norm(sub(b.max, b.min)); }
bool point_in_box(const Vec3& p, const Box3& b) {
  return p[0] >= b.min[0] && p[0] <= b.max[0] && p[1] >= b.min[1] && p[1] <= b.max[1] &&
         p[2] >= b.min[2] && p[2] <= b.max[2];
}
double box_distance(const Box3& b, const Vec3& p) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double e = std::max({b.min[k] - p[k], 0.0, p[k] - b.max[k]});
    d2 += e * e;
  }
  return std::sqrt(d2);
}

Vec3 to_body(const EllipsoidData& e, const Vec3& p) {
  const Vec3 d = sub(p, e.c);
  Vec3 b{};
  for (int j = 0; j < 3; ++j) b[j] = e.rot[0][j] * d[0] + e.rot[1][j] * d[1] + e.rot[2][j] * d[2];
  return b;
}
Vec3 unit_frame(const EllipsoidData& e, const Vec3& p) {
  const Vec3 b = to_body(e, p);
  return {b[0] / e.axis[0], b[1] / e.axis[1], b[2] / e.axis[2]};
}

// Tolerant side of an ellipsoid, like the 2D ellipse: F = 1 − |u|², ON within the
// rounding bound of its evaluation.
int ellipsoid_side(const EllipsoidData& e, const Vec3& p, double* f_out = nullptr) {
  const Vec3 d = sub(p, e.c);
  const Vec3 u = unit_frame(e, p);
  const double q = dot(u, u), f = 1 - q;
  const double s = std::abs(d[0]) + std::abs(d[1]) + std::abs(d[2]);
  double inv = 0;
  for (int j = 0; j < 3; ++j) inv += 1 / (e.axis[j] * e.axis[j]);
  const double bound = 48 * kUnitRoundoff * (1 + q + s * s * inv);
  if (f_out) *f_out = std::abs(f) <= bound ? 0.0 : f;
  if (f > bound) return 1;
  if (f < -bound) return -1;
  return 0;
}

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

// Distance from p to the closed cylinder (0 inside) or, with `surface`, to its boundary.
double cylinder_distance(const CylinderData& c, const Vec3& p, bool surface) {
  const Vec3 w = sub(p, c.s);
  const double t = dot(w, c.u);
  const double rho = norm(sub(w, Vec3{t * c.u[0], t * c.u[1], t * c.u[2]}));
  const bool inside = t >= 0 && t <= c.len && rho <= c.r;
  if (inside) return surface ? std::min({t, c.len - t, c.r - rho}) : 0.0;
  const double dt = t < 0 ? -t : (t > c.len ? t - c.len : 0.0);
  const double dr = rho > c.r ? rho - c.r : 0.0;
  return std::hypot(dt, dr);
}

// Gauss–Legendre 10 points on [-1, 1].
constexpr double kGx[5] = {0.1488743389816312, 0.4333953941292472, 0.6794095682990244,
                           0.8650633666889845, 0.9739065285171717};
constexpr double kGw[5] = {0.2955242247147529, 0.2692667193099963, 0.2190863625159820,
                           0.1494513491505806, 0.0666713443086881};

// ∫_{x0}^{x1} f (vector valued, np entries) with x = x0 + (x1−x0)(1 − cos πs)/2 (smooths
// square-root ends) and adaptive halving in s until |left + right − whole| ≤ tol·Δs.
template <class F>
void integrate(double x0, double x1, std::size_t np, double tol, F&& f, std::vector<double>& acc) {
  if (!(x1 > x0)) return;
  std::vector<double> val;
  auto panel = [&](double s0, double s1, std::vector<double>& sum) {
    sum.assign(np, 0.0);
    const double hm = 0.5 * (s1 - s0), cm = 0.5 * (s1 + s0);
    for (int i = 0; i < 10; ++i) {
      const double s = cm + hm * (i < 5 ? -kGx[i] : kGx[i - 5]);
      const double w = kGw[i < 5 ? i : i - 5] * hm;
      const double x = x0 + (x1 - x0) * 0.5 * (1 - std::cos(M_PI * s));
      const double jac = (x1 - x0) * 0.5 * M_PI * std::sin(M_PI * s);
      f(x, val);
      for (std::size_t p = 0; p < np; ++p) sum[p] += w * jac * val[p];
    }
  };
  struct Task {
    double s0, s1;
    int depth;
    std::vector<double> whole;
  };
  std::vector<Task> stack;
  stack.push_back({0, 1, 0, {}});
  panel(0, 1, stack.back().whole);
  std::vector<double> left, right;
  while (!stack.empty()) {
    Task tk = std::move(stack.back());
    stack.pop_back();
    const double sm = 0.5 * (tk.s0 + tk.s1);
    panel(tk.s0, sm, left);
    panel(sm, tk.s1, right);
    double diff = 0;
    for (std::size_t p = 0; p < np; ++p) diff += std::abs(left[p] + right[p] - tk.whole[p]);
    if (diff <= tol * (tk.s1 - tk.s0) || tk.depth >= 30) {
      for (std::size_t p = 0; p < np; ++p) acc[p] += left[p] + right[p];
    } else {
      stack.push_back({tk.s0, sm, tk.depth + 1, left});
      stack.push_back({sm, tk.s1, tk.depth + 1, right});
    }
  }
}

bool orthonormal(const Rotation3& r) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += r[k][i] * r[k][j];
      if (!std::isfinite(s) || std::abs(s - (i == j ? 1.0 : 0.0)) > 1e-9) return false;
    }
  return true;
}

bool finite3(const Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

}  // namespace

struct Oracle3::Impl {
  SceneDesc scene;
  int matrix = 0;
  std::vector<Item> items;
  std::vector<SphereData> spheres;
  std::vector<EllipsoidData> ellipsoids;
  std::vector<CylinderData> cylinders;
  std::vector<stl::Mesh> meshes;
  std::vector<Box3> boxes;
  std::unique_ptr<BoxIndex3> index;

  int side(std::int32_t k, const Vec3& p) const {
    const Item& it = items[k];
    if (!point_in_box(p, it.box)) return -1;
    switch (it.kind) {
      case Kind::sphere: return exact::sphere_side(p, spheres[it.data].c, spheres[it.data].r);
      case Kind::ellipsoid: return ellipsoid_side(ellipsoids[it.data], p);
      case Kind::cylinder: {
        const CylinderData& c = cylinders[it.data];
        return exact::cylinder_side(p, c.s, c.e, c.r);
      }
      case Kind::stl: return stl::side(meshes[it.data], p);
    }
    return -1;
  }

  double boundary_distance(std::int32_t k, const Vec3& p) const {
    const Item& it = items[k];
    switch (it.kind) {
      case Kind::sphere: return std::abs(norm(sub(p, spheres[it.data].c)) - spheres[it.data].r);
      case Kind::ellipsoid: {
        const EllipsoidData& e = ellipsoids[it.data];
        return ellipsoid_surface_distance(e.axis, to_body(e, p));
      }
      case Kind::cylinder: return cylinder_distance(cylinders[it.data], p, true);
      case Kind::stl: return stl::distance_to_surface(meshes[it.data], p);
    }
    return 0;
  }

  // Distance from p to the closed region of k (0 inside).
  double region_distance(std::int32_t k, const Vec3& p) const {
    if (side(k, p) >= 0) return 0;
    return boundary_distance(k, p);
  }

  struct Event {
    double t;
    std::int32_t inclusion;
    std::int32_t slot;
    std::int32_t order;
    bool inside_after;
  };
  bool segment_events(std::int32_t k, std::int32_t slot, const Vec3& a, const Vec3& b,
                      std::vector<Event>& events, std::vector<double>& ts) const;

  int phase_of_states(std::span<const std::int32_t> cands, const std::vector<std::uint8_t>& state) const {
    std::int32_t best = std::numeric_limits<std::int32_t>::max();
    for (std::size_t i = 0; i < cands.size(); ++i)
      if (state[i] && cands[i] < best) best = cands[i];
    return best == std::numeric_limits<std::int32_t>::max() ? matrix : items[best].phase;
  }

  PhaseMask closure_mask(const Vec3& p, std::span<const std::int32_t> cands) const;
  void crossings(const Vec3& a, const Vec3& b, std::span<const std::int32_t> cands,
                 std::vector<Crossing>& out) const;
  void validate_and_build(const SceneDesc& s);
  bool regions_intersect(std::int32_t i, std::int32_t j, bool interiors) const;
  std::vector<Vec3> boundary_points(std::int32_t k, int per_axis) const;
  double matrix_distance(const Vec3& p) const;
};

// ---------------------------------------------------------------- segment events
bool Oracle3::Impl::segment_events(std::int32_t k, std::int32_t slot, const Vec3& a, const Vec3& b,
                                   std::vector<Event>& events, std::vector<double>& ts) const {
  const Item& it = items[k];
  Box3 seg{};
  for (int d = 0; d < 3; ++d) seg.min[d] = std::min(a[d], b[d]), seg.max[d] = std::max(a[d], b[d]);
  if (!boxes_overlap(seg, it.box)) return false;
  std::int32_t order = 0;
  auto push_hits = [&](const exact::CircleSegmentHits& h) {
    bool state = h.start_inside;
    for (int i = 0; i < h.count; ++i) {
      state = !state;
      events.push_back({h.t[i], k, slot, order++, state});
    }
    return h.start_inside;
  };
  auto push = [&](double t, bool after) { events.push_back({t, k, slot, order++, after}); };
  const double lo_t = std::numeric_limits<double>::denorm_min(), hi_t = 1 - kUnitRoundoff;
  switch (it.kind) {
    case Kind::sphere: {
      const SphereData& s = spheres[it.data];
      return push_hits(exact::sphere_segment_hits(a, b, s.c, s.r));
    }
    case Kind::ellipsoid: {
      const EllipsoidData& e = ellipsoids[it.data];
      double f0, f1;
      const int s0 = ellipsoid_side(e, a, &f0), s1 = ellipsoid_side(e, b, &f1);
      const Vec3 ua = unit_frame(e, a), ub = unit_frame(e, b);
      const Vec3 d = sub(ub, ua);
      const double dd = dot(d, d);
      if (dd == 0) return s0 > 0;
      const double ed = dot(ua, d), fd = dot(ub, d);
      const double disc = ed * ed + dd * f0;
      auto sgn = [](double x) { return x > 0 ? 1 : (x < 0 ? -1 : 0); };
      return push_hits(exact::circle_hits_from_signs(s0, s1, sgn(ed), sgn(fd), sgn(disc), ed, dd, f0, disc));
    }
    case Kind::cylinder: {
      // Convex: the closed inside set along the line is one interval [tl, th] (rounded),
      // the topology is decided by the exact endpoint sides and exact mid-point tests.
      const CylinderData& c = cylinders[it.data];
      const int sa = side(k, a), sb = side(k, b);
      const Vec3 d = sub(b, a), w = sub(a, c.s);
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
      const double wu = dot(w, c.u), du = dot(d, c.u);
      clip_linear(wu, du);
      clip_linear(c.len - wu, -du);
      // Radial: |w⊥ + t d⊥|² ≤ r².
      const Vec3 wp = sub(w, Vec3{wu * c.u[0], wu * c.u[1], wu * c.u[2]});
      const Vec3 dp = sub(d, Vec3{du * c.u[0], du * c.u[1], du * c.u[2]});
      const double A = dot(dp, dp), B = dot(wp, dp), C = dot(wp, wp) - c.r * c.r;
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
      auto inside_at = [&](double t) {
        return side(k, Vec3{a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]}) >= 0;
      };
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
    case Kind::stl: {
      ts.clear();
      stl::segment_hits(meshes[it.data], a, b, ts);
      std::sort(ts.begin(), ts.end());
      ts.erase(std::unique(ts.begin(), ts.end()), ts.end());
      const Vec3 d = sub(b, a);
      auto state_at = [&](double t0, double t1) {
        const double tm = 0.5 * (t0 + t1);
        return stl::side(meshes[it.data], Vec3{a[0] + tm * d[0], a[1] + tm * d[1], a[2] + tm * d[2]}) >= 0;
      };
      const bool start = state_at(0, ts.empty() ? 1.0 : ts[0]);
      bool state = start;
      for (std::size_t i = 0; i < ts.size(); ++i) {
        const double next = i + 1 < ts.size() ? ts[i + 1] : 1.0;
        const bool after = state_at(ts[i], next);
        if (after != state) push(ts[i], after);
        state = after;
      }
      return start;
    }
  }
  return false;
}

// ---------------------------------------------------------------- build and validation
void Oracle3::Impl::validate_and_build(const SceneDesc& s) {
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
    if (it.phase < 0) throw InputError(src, field + ".phase", "no phase has id " + std::to_string(inc.phase));
    it.levels = inc.levels;
    if (const auto* sp = std::get_if<Sphere>(&inc.shape)) {
      if (!finite3(sp->center)) throw InputError(src, field + ".center", "must be finite");
      if (!(sp->radius > 0) || !std::isfinite(sp->radius)) throw InputError(src, field + ".radius", "must be positive");
      it.kind = Kind::sphere;
      it.data = static_cast<std::int32_t>(spheres.size());
      spheres.push_back({sp->center, sp->radius});
      const double r = sp->radius * (1 + 4 * kUnitRoundoff);
      for (int d = 0; d < 3; ++d) it.box.min[d] = sp->center[d] - r, it.box.max[d] = sp->center[d] + r;
    } else if (const auto* e = std::get_if<Ellipsoid>(&inc.shape)) {
      if (!finite3(e->center)) throw InputError(src, field + ".center", "must be finite");
      if (!(e->semi_axes[0] > 0) || !(e->semi_axes[1] > 0) || !(e->semi_axes[2] > 0) || !finite3(e->semi_axes))
        throw InputError(src, field + ".semi_axes", "must be positive");
      if (!orthonormal(e->rotation)) throw InputError(src, field + ".rotation", "must be orthonormal");
      it.kind = Kind::ellipsoid;
      it.data = static_cast<std::int32_t>(ellipsoids.size());
      ellipsoids.push_back({e->center, e->semi_axes, e->rotation});
      for (int d = 0; d < 3; ++d) {
        double h2 = 0;
        for (int j = 0; j < 3; ++j) h2 += (e->rotation[d][j] * e->semi_axes[j]) * (e->rotation[d][j] * e->semi_axes[j]);
        const double h = std::sqrt(h2) * (1 + 1e-12) + 1e-300;
        it.box.min[d] = e->center[d] - h, it.box.max[d] = e->center[d] + h;
      }
    } else if (const auto* c = std::get_if<Cylinder>(&inc.shape)) {
      if (!finite3(c->start)) throw InputError(src, field + ".start", "must be finite");
      if (!finite3(c->end)) throw InputError(src, field + ".end", "must be finite");
      if (!(c->radius > 0) || !std::isfinite(c->radius)) throw InputError(src, field + ".radius", "must be positive");
      const Vec3 ax = sub(c->end, c->start);
      const double len = norm(ax);
      if (!(len > 0)) throw InputError(src, field + ".end", "zero-length cylinder (end equals start)");
      it.kind = Kind::cylinder;
      it.data = static_cast<std::int32_t>(cylinders.size());
      cylinders.push_back({c->start, c->end, c->radius, {ax[0] / len, ax[1] / len, ax[2] / len}, len});
      const CylinderData& cd = cylinders.back();
      for (int d = 0; d < 3; ++d) {
        const double h = c->radius * std::sqrt(std::max(0.0, 1 - cd.u[d] * cd.u[d])) * (1 + 1e-12) +
                         1e-12 * (len + c->radius);
        it.box.min[d] = std::min(c->start[d], c->end[d]) - h;
        it.box.max[d] = std::max(c->start[d], c->end[d]) + h;
      }
    } else if (const auto* st = std::get_if<StlSurface>(&inc.shape)) {
      if (!(st->scale > 0) || !std::isfinite(st->scale)) throw InputError(src, field + ".scale", "must be positive");
      if (!orthonormal(st->rotation)) throw InputError(src, field + ".rotation", "must be orthonormal");
      if (!finite3(st->translate)) throw InputError(src, field + ".translate", "must be finite");
      stl::Mesh mesh;
      const std::string problem = stl::build(*st, mesh, true);
      if (!problem.empty()) throw InputError(src, field + ".file", st->file + ": " + problem);
      it.kind = Kind::stl;
      it.data = static_cast<std::int32_t>(meshes.size());
      it.box = mesh.box;
      meshes.push_back(std::move(mesh));
    } else if (std::get_if<NurbsSurface>(&inc.shape)) {
      throw InputError(src, field + ".shape", "nurbs_surface: not supported yet");
    } else {
      throw InputError(src, field + ".shape", "a 2D shape in a 3D scene");
    }
    items.push_back(it);
  }
  boxes.reserve(items.size());
  for (const Item& it : items) boxes.push_back(it.box);
  index = std::make_unique<BoxIndex3>(boxes);
  detail::group_overlapping_inclusions(*this);
}

// Boundary points of k for overlap tests: STL vertices and face centroids; analytic
// surfaces sampled at about size/per_axis.
std::vector<Vec3> Oracle3::Impl::boundary_points(std::int32_t k, int per_axis) const {
  const Item& it = items[k];
  std::vector<Vec3> pts;
  if (it.kind == Kind::stl) {
    const stl::Mesh& m = meshes[it.data];
    pts = m.vertices;
    for (const auto& f : m.faces) {
      Vec3 c{};
      for (int d = 0; d < 3; ++d) c[d] = (m.vertices[f[0]][d] + m.vertices[f[1]][d] + m.vertices[f[2]][d]) / 3;
      pts.push_back(c);
    }
    return pts;
  }
  return shape_boundary_samples(scene.inclusions[k].shape, box_size(it.box) / per_axis);
}

bool Oracle3::Impl::regions_intersect(std::int32_t i, std::int32_t j, bool interiors) const {
  const Item& a = items[i];
  const Item& b = items[j];
  const double depth_tol = 1e-10 * std::min(box_size(a.box), box_size(b.box));
  if (a.kind == Kind::sphere && b.kind == Kind::sphere) {
    const SphereData& p = spheres[a.data];
    const SphereData& q = spheres[b.data];
    if (!interiors) return exact::balls_side(p.c, p.r, q.c, q.r) >= 0;
    return norm(sub(q.c, p.c)) < p.r + q.r - depth_tol;
  }
  if (a.kind != Kind::stl && b.kind != Kind::stl) {
    // Convex pair: min over directions of h_a(d) + h_b(−d) is the penetration depth.
    return detail::overlap3(scene.inclusions[i].shape, scene.inclusions[j].shape, interiors ? -depth_tol : 0.0);
  }
  // With an STL surface: boundary points of each inside the other (README: conservative
  // to the sampling), and for two meshes, edges of one piercing faces of the other.
  const std::int32_t ks[2] = {i, j};
  for (int w = 0; w < 2; ++w) {
    const std::int32_t self = ks[w], other = ks[1 - w];
    for (const Vec3& q : boundary_points(self, 96)) {
      const int s = side(other, q);
      if (interiors ? (s > 0 && boundary_distance(other, q) > depth_tol) : s >= 0) return true;
    }
  }
  if (a.kind == Kind::stl && b.kind == Kind::stl) {
    std::vector<double> ts;
    for (int w = 0; w < 2; ++w) {
      const stl::Mesh& m = meshes[items[ks[w]].data];
      const stl::Mesh& other = meshes[items[ks[1 - w]].data];
      for (const auto& f : m.faces)
        for (int e = 0; e < 3; ++e) {
          ts.clear();
          stl::segment_hits(other, m.vertices[f[e]], m.vertices[f[(e + 1) % 3]], ts);
          if (!ts.empty()) return true;
        }
    }
  }
  return false;
}

// ---------------------------------------------------------------- classification
PhaseMask Oracle3::Impl::closure_mask(const Vec3& p, std::span<const std::int32_t> cands) const {
  PhaseMask inside = 0, on = 0;
  int on_count = 0;
  for (std::int32_t k : cands) {
    const int s = side(k, p);
    if (s > 0) inside |= PhaseMask(1) << items[k].phase;
    else if (s == 0) {
      on |= PhaseMask(1) << items[k].phase;
      ++on_count;
    }
  }
  if (inside) return inside | (on & ~inside);
  const PhaseMask matrix_bit = PhaseMask(1) << matrix;
  if (!on) return matrix_bit;
  if (on_count == 1) return on | matrix_bit;
  // ON several boundaries and inside none: the matrix reaches p iff some nearby direction
  // leaves every inclusion. Probe the tangent planes of the curved surfaces holding p
  // (the cusp between touching spheres) and a fan of directions.
  double scale = std::numeric_limits<double>::infinity();
  for (std::int32_t k : cands) scale = std::min(scale, box_size(items[k].box));
  auto outside_all = [&](const Vec3& q) {
    for (std::int32_t k : cands)
      if (side(k, q) >= 0) return false;
    return true;
  };
  for (std::int32_t k : cands) {
    const Item& it = items[k];
    Vec3 n{};
    if (it.kind == Kind::sphere) n = sub(p, spheres[it.data].c);
    else if (it.kind == Kind::ellipsoid) {
      const EllipsoidData& e = ellipsoids[it.data];
      const Vec3 u = unit_frame(e, p);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) n[i] += e.rot[i][j] * u[j] / e.axis[j];
    } else {
      continue;
    }
    if (side(k, p) != 0) continue;
    const double nn = norm(n);
    if (!(nn > 0)) continue;
    const Vec3 t1 = std::abs(n[0]) < 0.9 * nn ? cross(n, Vec3{1, 0, 0}) : cross(n, Vec3{0, 1, 0});
    const Vec3 t2 = cross(n, t1);
    for (const Vec3& t : {t1, t2}) {
      const double rho = 1e-6 * scale / norm(t);
      for (double sgn : {1.0, -1.0})
        if (outside_all({p[0] + sgn * rho * t[0], p[1] + sgn * rho * t[1], p[2] + sgn * rho * t[2]}))
          return on | matrix_bit;
    }
  }
  const double rho = 1e-9 * scale;
  const int n = 128;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(std::max(0.0, 1 - z * z));
    if (outside_all({p[0] + rho * r * std::cos(golden * i), p[1] + rho * r * std::sin(golden * i), p[2] + rho * z}))
      return on | matrix_bit;
  }
  return on;
}

void Oracle3::Impl::crossings(const Vec3& a, const Vec3& b, std::span<const std::int32_t> cands,
                              std::vector<Crossing>& out) const {
  out.clear();
  if (a == b || cands.empty()) return;
  thread_local std::vector<Event> events;
  thread_local std::vector<std::uint8_t> state;
  thread_local std::vector<double> scratch;
  events.clear();
  state.assign(cands.size(), 0);
  for (std::size_t i = 0; i < cands.size(); ++i)
    state[i] = segment_events(cands[i], static_cast<std::int32_t>(i), a, b, events, scratch);
  if (events.empty()) return;
  std::sort(events.begin(), events.end(), [](const Event& x, const Event& y) {
    if (x.t != y.t) return x.t < y.t;
    if (x.inclusion != y.inclusion) return x.inclusion < y.inclusion;
    return x.order < y.order;
  });
  int before = phase_of_states(cands, state);
  for (std::size_t i = 0; i < events.size();) {
    const double t = events[i].t;
    const std::int32_t first = events[i].inclusion;
    std::size_t j = i;
    for (; j < events.size() && events[j].t == t; ++j) state[events[j].slot] = events[j].inside_after;
    const int after = phase_of_states(cands, state);
    if (after != before) out.push_back({t, first, before, after});
    before = after;
    i = j;
  }
  std::size_t w = 0;
  for (std::size_t r = 0; r < out.size(); ++r) {
    if (w > 0 && out[r].t - out[w - 1].t < kMergeT) {
      Crossing& prev = out[w - 1];
      if (prev.from_phase == out[r].to_phase) {
        --w;
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

// ---------------------------------------------------------------- public API
Oracle3::Oracle3(const SceneDesc& scene) : impl_(std::make_unique<Impl>()) { impl_->validate_and_build(scene); }
Oracle3::~Oracle3() = default;
Oracle3::Oracle3(Oracle3&&) noexcept = default;
Oracle3& Oracle3::operator=(Oracle3&&) noexcept = default;

const SceneDesc& Oracle3::scene() const { return impl_->scene; }
int Oracle3::inclusion_count() const { return static_cast<int>(impl_->items.size()); }
int Oracle3::phase_count() const { return static_cast<int>(impl_->scene.phases.size()); }
int Oracle3::matrix_phase() const { return impl_->matrix; }
int Oracle3::phase_of(std::int32_t k) const { return impl_->items[k].phase; }
int Oracle3::levels_of(std::int32_t k) const { return impl_->items[k].levels; }
int Oracle3::interface_group(std::int32_t k) const { return impl_->items[k].group; }
Box3 Oracle3::bounding_box(std::int32_t k) const { return impl_->items[k].box; }

void Oracle3::candidates(const Box3& box, std::vector<std::int32_t>& out) const { impl_->index->query(box, out); }

bool Oracle3::boundary_touches(std::int32_t k, const Box3& box_in) const {
  const Impl& m = *impl_;
  const Item& it = m.items[k];
  const double slack = 1e-12 * std::max(box_size(box_in), box_size(it.box)) + 1e-300;
  Box3 box = box_in;
  for (int d = 0; d < 3; ++d) box.min[d] -= slack, box.max[d] += slack;
  if (!boxes_overlap(box, it.box)) return false;
  switch (it.kind) {
    case Kind::sphere: {
      const SphereData& c = m.spheres[it.data];
      return detail::sphere_meets_box(c.c, c.r, box);
    }
    case Kind::ellipsoid: {
      // q = |u|² is convex: max over the box at a corner; min bounded below by the
      // tangent plane at an approximate minimiser y (q(x) ≥ q(y) + ∇q(y)·(x − y)).
      const EllipsoidData& e = m.ellipsoids[it.data];
      auto q = [&](const Vec3& p) {
        const Vec3 u = unit_frame(e, p);
        return dot(u, u);
      };
      double qmax = 0;
      for (int c = 0; c < 8; ++c)
        qmax = std::max(qmax, q({c & 1 ? box.max[0] : box.min[0], c & 2 ? box.max[1] : box.min[1],
                                 c & 4 ? box.max[2] : box.min[2]}));
      if (qmax < 1 - 1e-9) return false;  // the box is inside
      // Gradient of q in world coordinates: 2·R·diag(1/a²)·body.
      auto grad = [&](const Vec3& p) {
        const Vec3 bd = to_body(e, p);
        Vec3 g{};
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) g[i] += 2 * e.rot[i][j] * bd[j] / (e.axis[j] * e.axis[j]);
        return g;
      };
      Vec3 y{};
      for (int d = 0; d < 3; ++d) y[d] = std::clamp(e.c[d], box.min[d], box.max[d]);
      // Projected coordinate descent (exact 1D minimisation of the quadratic per axis).
      for (int iter = 0; iter < 60; ++iter)
        for (int d = 0; d < 3; ++d) {
          Vec3 ed{};
          ed[d] = 1;
          double h = 0;
          for (int j = 0; j < 3; ++j) h += 2 * (e.rot[d][j] / e.axis[j]) * (e.rot[d][j] / e.axis[j]);
          y[d] = std::clamp(y[d] - grad(y)[d] / h, box.min[d], box.max[d]);
        }
      const Vec3 g = grad(y);
      double lower = q(y);
      for (int d = 0; d < 3; ++d) lower += std::min(g[d] * (box.min[d] - y[d]), g[d] * (box.max[d] - y[d]));
      return lower <= 1 + 1e-9;
    }
    case Kind::cylinder: {
      const CylinderData& c = m.cylinders[it.data];
      // Box inside (all corners strictly inside the convex body) → no surface.
      bool all_inside = true;
      for (int cn = 0; cn < 8 && all_inside; ++cn)
        all_inside = exact::cylinder_side({cn & 1 ? box.max[0] : box.min[0], cn & 2 ? box.max[1] : box.min[1],
                                           cn & 4 ? box.max[2] : box.min[2]},
                                          c.s, c.e, c.r) > 0;
      if (all_inside) return false;
      // Far apart: the ball around the box misses the capsule around the cylinder.
      Vec3 mid{};
      for (int d = 0; d < 3; ++d) mid[d] = 0.5 * (box.min[d] + box.max[d]);
      const double half = 0.5 * box_size(box);
      const Vec3 w = sub(mid, c.s);
      const double t = std::clamp(dot(w, c.u), 0.0, c.len);
      const double dist = norm(sub(w, Vec3{t * c.u[0], t * c.u[1], t * c.u[2]}));
      return dist <= c.r + half + 1e-12 * (c.r + half);
    }
    case Kind::stl: return stl::touches_box(m.meshes[it.data], box);
  }
  return true;
}

PhaseMask Oracle3::closure_phases(const Vec3& p, std::span<const std::int32_t> cands) const {
  return impl_->closure_mask(p, cands);
}

int Oracle3::phase_at(const Vec3& p, std::span<const std::int32_t> cands) const {
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

void Oracle3::crossings(const Vec3& a, const Vec3& b, std::span<const std::int32_t> cands,
                        std::vector<Crossing>& out) const {
  impl_->crossings(a, b, cands, out);
}

// ---------------------------------------------------------------- volumes
std::vector<double> Oracle3::phase_volumes() const {
  const Impl& m = *impl_;
  const SceneDesc& sc = m.scene;
  Box3 dom{};
  for (int d = 0; d < 3; ++d) dom.min[d] = sc.domain_min[d], dom.max[d] = sc.domain_max[d];
  const double dom_volume = (dom.max[0] - dom.min[0]) * (dom.max[1] - dom.min[1]) * (dom.max[2] - dom.min[2]);
  const std::size_t np = sc.phases.size();
  std::vector<double> vol(np, 0.0);
  std::vector<int> group_size(m.items.size(), 0);
  for (const Item& it : m.items) ++group_size[it.group];
  std::vector<std::int32_t> integrated;
  for (std::size_t k = 0; k < m.items.size(); ++k) {
    const Item& it = m.items[k];
    bool inside_domain = true;
    for (int d = 0; d < 3; ++d) inside_domain = inside_domain && it.box.min[d] >= dom.min[d] && it.box.max[d] <= dom.max[d];
    if (inside_domain && group_size[it.group] == 1) {
      double v = 0;
      switch (it.kind) {
        case Kind::sphere: v = 4.0 / 3.0 * M_PI * std::pow(m.spheres[it.data].r, 3); break;
        case Kind::ellipsoid: {
          const Vec3& a = m.ellipsoids[it.data].axis;
          v = 4.0 / 3.0 * M_PI * a[0] * a[1] * a[2];
          break;
        }
        case Kind::cylinder: v = M_PI * m.cylinders[it.data].r * m.cylinders[it.data].r * m.cylinders[it.data].len; break;
        case Kind::stl: v = stl::volume(m.meshes[it.data]); break;
      }
      vol[it.phase] += v;
      continue;
    }
    if (boxes_overlap(it.box, dom)) integrated.push_back(static_cast<std::int32_t>(k));
  }
  if (!integrated.empty()) {
    // ∫∫ (length of each phase on the z-line at (x, y)) dy dx, nested adaptive
    // Gauss–Legendre with breakpoints at the kinks we know (README: volumes).
    std::vector<double> xb{dom.min[0], dom.max[0]};
    for (std::int32_t k : integrated) {
      const Item& it = m.items[k];
      xb.push_back(it.box.min[0]);
      xb.push_back(it.box.max[0]);
      if (it.kind == Kind::sphere) {
        xb.push_back(m.spheres[it.data].c[0] - m.spheres[it.data].r);
        xb.push_back(m.spheres[it.data].c[0] + m.spheres[it.data].r);
      }
      if (it.kind == Kind::stl && m.meshes[it.data].vertices.size() <= 512)
        for (const Vec3& v : m.meshes[it.data].vertices) xb.push_back(v[0]);
    }
    // Overlapping sphere pairs: their section circles start/stop meeting at the x-extent
    // of the spheres' intersection circle (a kink of the section area).
    for (std::size_t i = 0; i < integrated.size(); ++i)
      for (std::size_t j = i + 1; j < integrated.size(); ++j) {
        const Item &a = m.items[integrated[i]], &b = m.items[integrated[j]];
        if (a.kind != Kind::sphere || b.kind != Kind::sphere || !boxes_overlap(a.box, b.box)) continue;
        const SphereData &s1 = m.spheres[a.data], &s2 = m.spheres[b.data];
        const Vec3 d = sub(s2.c, s1.c);
        const double dist = norm(d);
        if (dist == 0 || dist >= s1.r + s2.r || dist <= std::abs(s1.r - s2.r)) continue;
        const double along = (s1.r * s1.r - s2.r * s2.r + dist * dist) / (2 * dist);
        const double h = std::sqrt(std::max(0.0, s1.r * s1.r - along * along));
        const double ox = s1.c[0] + along * d[0] / dist, nx = d[0] / dist;
        const double ext = h * std::sqrt(std::max(0.0, 1 - nx * nx));
        xb.push_back(ox - ext);
        xb.push_back(ox + ext);
      }
    for (double& x : xb) x = std::clamp(x, dom.min[0], dom.max[0]);
    std::sort(xb.begin(), xb.end());
    xb.erase(std::unique(xb.begin(), xb.end()), xb.end());
    std::vector<std::int32_t> cands, col;
    std::vector<Crossing> cr;
    const double zspan = dom.max[2] - dom.min[2];
    auto line = [&](double x, double y, std::vector<double>& len) {
      len.assign(np, 0.0);
      cands.clear();
      for (std::int32_t k : col)
        if (m.items[k].box.min[1] <= y && y <= m.items[k].box.max[1]) cands.push_back(k);
      if (cands.empty()) return;
      const Vec3 a{x, y, dom.min[2]}, b{x, y, dom.max[2]};
      m.crossings(a, b, cands, cr);
      double t0 = 0;
      int ph = cr.empty() ? phase_at(Vec3{x, y, 0.5 * (a[2] + b[2])}, cands) : cr[0].from_phase;
      for (const Crossing& c : cr) {
        len[ph] += (c.t - t0) * zspan;
        t0 = c.t;
        ph = c.to_phase;
      }
      len[ph] += (1 - t0) * zspan;
    };
    const double tol_inner = 1e-13 * (dom.max[1] - dom.min[1]) * zspan;
    const double tol_outer = 1e-12 * dom_volume;
    std::vector<double> yb;
    auto section = [&](double x, std::vector<double>& area) {
      area.assign(np, 0.0);
      col.clear();
      for (std::int32_t k : integrated)
        if (m.items[k].box.min[0] <= x && x <= m.items[k].box.max[0]) col.push_back(k);
      if (col.empty()) return;
      yb.assign({dom.min[1], dom.max[1]});
      for (std::int32_t k : col) {
        const Item& it = m.items[k];
        yb.push_back(it.box.min[1]);
        yb.push_back(it.box.max[1]);
        if (it.kind == Kind::sphere) {
          const SphereData& s = m.spheres[it.data];
          const double h = std::sqrt(std::max(0.0, s.r * s.r - (x - s.c[0]) * (x - s.c[0])));
          yb.push_back(s.c[1] - h);
          yb.push_back(s.c[1] + h);
        } else if (it.kind == Kind::ellipsoid || it.kind == Kind::cylinder) {
          // y-extent of the quadric section at x: (p−c)ᵀM(p−c) ≤ rhs minimised over z.
          double M[3][3] = {}, rhs = 1;
          Vec3 c{};
          if (it.kind == Kind::ellipsoid) {
            const EllipsoidData& e = m.ellipsoids[it.data];
            c = e.c;
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j)
                for (int l = 0; l < 3; ++l) M[i][j] += e.rot[i][l] * e.rot[j][l] / (e.axis[l] * e.axis[l]);
          } else {
            const CylinderData& cy = m.cylinders[it.data];
            c = cy.s;
            rhs = cy.r * cy.r;
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j) M[i][j] = (i == j ? 1.0 : 0.0) - cy.u[i] * cy.u[j];
          }
          const double dx = x - c[0];
          double A, B, C;
          if (M[2][2] > 1e-12) {
            A = M[1][1] - M[1][2] * M[1][2] / M[2][2];
            B = M[0][1] * dx - M[0][2] * M[1][2] * dx / M[2][2];
            C = M[0][0] * dx * dx - M[0][2] * M[0][2] * dx * dx / M[2][2];
          } else {
            A = M[1][1], B = M[0][1] * dx, C = M[0][0] * dx * dx;
          }
          const double disc = B * B - A * (C - rhs);
          if (A > 1e-12 && disc > 0) {
            yb.push_back(c[1] + (-B - std::sqrt(disc)) / A);
            yb.push_back(c[1] + (-B + std::sqrt(disc)) / A);
          }
        } else if (m.meshes[it.data].faces.size() <= 4096) {
          stl::edge_crossings_at_x(m.meshes[it.data], x, yb);
        }
      }
      // Sphere pairs: where their section circles cross, the z-length has a kink in y.
      for (std::size_t i = 0; i < col.size(); ++i)
        for (std::size_t j = i + 1; j < col.size(); ++j) {
          const Item &a = m.items[col[i]], &b = m.items[col[j]];
          if (a.kind != Kind::sphere || b.kind != Kind::sphere || !boxes_overlap(a.box, b.box)) continue;
          const SphereData &s1 = m.spheres[a.data], &s2 = m.spheres[b.data];
          const double q1 = s1.r * s1.r - (x - s1.c[0]) * (x - s1.c[0]);
          const double q2 = s2.r * s2.r - (x - s2.c[0]) * (x - s2.c[0]);
          if (q1 <= 0 || q2 <= 0) continue;
          const double r1 = std::sqrt(q1), r2 = std::sqrt(q2);
          const double dy = s2.c[1] - s1.c[1], dz = s2.c[2] - s1.c[2], dist = std::hypot(dy, dz);
          if (dist == 0 || dist > r1 + r2 || dist < std::abs(r1 - r2)) continue;
          const double along = (r1 * r1 - r2 * r2 + dist * dist) / (2 * dist);
          const double h = std::sqrt(std::max(0.0, r1 * r1 - along * along));
          yb.push_back(s1.c[1] + along * dy / dist - h * dz / dist);
          yb.push_back(s1.c[1] + along * dy / dist + h * dz / dist);
        }
      for (double& y : yb) y = std::clamp(y, dom.min[1], dom.max[1]);
      std::sort(yb.begin(), yb.end());
      yb.erase(std::unique(yb.begin(), yb.end()), yb.end());
      const std::vector<double> ys = yb;  // `line` is re-entered below; keep a copy
      for (std::size_t i = 0; i + 1 < ys.size(); ++i)
        integrate(ys[i], ys[i + 1], np, tol_inner, [&](double y, std::vector<double>& len) { line(x, y, len); }, area);
    };
    for (std::size_t i = 0; i + 1 < xb.size(); ++i) integrate(xb[i], xb[i + 1], np, tol_outer, section, vol);
  }
  double total = 0;
  for (std::size_t p = 0; p < np; ++p)
    if (static_cast<int>(p) != m.matrix) total += vol[p];
  vol[m.matrix] = dom_volume - total;
  return vol;
}

// ---------------------------------------------------------------- distances
double Oracle3::distance_to_phase(const Vec3& p, int phase_index) const {
  const Impl& m = *impl_;
  if (phase_index != m.matrix) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < m.items.size(); ++k) {
      const std::int32_t kk = static_cast<std::int32_t>(k);
      if (m.items[k].phase != phase_index || box_distance(m.items[k].box, p) >= best) continue;
      best = std::min(best, m.region_distance(kk, p));
      if (best == 0) return 0;
    }
    return best;
  }
  // Inside exactly one inclusion with no other box nearer than its surface: that surface.
  std::vector<std::int32_t> here;
  m.index->query(Box3{p, p}, here);
  std::int32_t inside = -1;
  int inside_count = 0;
  for (std::int32_t k : here)
    if (m.side(k, p) > 0) inside = k, ++inside_count;
  if (inside_count == 1) {
    const double d = m.boundary_distance(inside, p);
    const double r = d * (1 + 1e-9);
    m.index->query(Box3{{p[0] - r, p[1] - r, p[2] - r}, {p[0] + r, p[1] + r, p[2] + r}}, here);
    if (here.size() == 1) return d;
  }
  return m.matrix_distance(p);
}

// Distance to the matrix: 0 outside all inclusions; else to ∂U (U the union). Candidates
// not interior to another inclusion: the nearest point of each surface (sphere radial,
// ellipsoid by bisection), for sphere pairs the nearest point of their intersection
// circle, for sphere triples their common points — exact for sphere clusters; other
// shapes in clusters add surface samples (README: distances).
double Oracle3::Impl::matrix_distance(const Vec3& p) const {
  std::vector<std::int32_t> near;
  index->query(Box3{p, p}, near);
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
  if (!inside_any && (!on_any || (closure_mask(p, near) & matrix_bit))) return 0;
  double reach = std::max(lower, 1e-300);
  std::vector<Vec3> pts;
  for (;;) {
    const double r = reach * (1 + 1e-9);
    index->query(Box3{{p[0] - r, p[1] - r, p[2] - r}, {p[0] + r, p[1] + r, p[2] + r}}, near);
    double best = std::numeric_limits<double>::infinity();
    auto consider = [&](const Vec3& q, std::int32_t k, std::int32_t j, std::int32_t l) {
      const double d = norm(sub(q, p));
      if (d >= best) return;
      bool on_other = false;
      for (std::int32_t i : near) {
        if (i == k || i == j || i == l) continue;
        const int s = side(i, q);
        if (s > 0) return;
        if (s == 0) on_other = true;
      }
      if (on_other && !(closure_mask(q, near) & matrix_bit)) return;
      best = d;
    };
    bool all_spheres = true;
    for (std::int32_t k : near) {
      const Item& it = items[k];
      if (it.kind == Kind::sphere) {
        const SphereData& s = spheres[it.data];
        const Vec3 d = sub(p, s.c);
        const double n = norm(d);
        const Vec3 q = n == 0 ? Vec3{s.c[0] + s.r, s.c[1], s.c[2]}
                              : Vec3{s.c[0] + s.r * d[0] / n, s.c[1] + s.r * d[1] / n, s.c[2] + s.r * d[2] / n};
        consider(q, k, -1, -1);
      } else if (it.kind == Kind::ellipsoid) {
        all_spheres = false;
        const EllipsoidData& e = ellipsoids[it.data];
        Vec3 xb{};
        ellipsoid_surface_distance(e.axis, to_body(e, p), &xb);
        Vec3 q = e.c;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) q[i] += e.rot[i][j] * xb[j];
        consider(q, k, -1, -1);
      } else {
        all_spheres = false;
      }
      if (it.kind != Kind::sphere) {
        pts = boundary_points(k, 256);
        for (const Vec3& q : pts) consider(q, k, -1, -1);
      }
    }
    // Sphere pairs: the intersection circle (center o, radius h, normal n); its nearest
    // point to p is o + h·(projection of p − o on the circle's plane, normalised).
    for (std::size_t x = 0; x < near.size(); ++x)
      for (std::size_t y = x + 1; y < near.size(); ++y) {
        const Item &a = items[near[x]], &b = items[near[y]];
        if (a.kind != Kind::sphere || b.kind != Kind::sphere) continue;
        const SphereData &s1 = spheres[a.data], &s2 = spheres[b.data];
        const Vec3 d = sub(s2.c, s1.c);
        const double dist = norm(d);
        if (dist == 0 || dist > s1.r + s2.r || dist < std::abs(s1.r - s2.r)) continue;
        const Vec3 n{d[0] / dist, d[1] / dist, d[2] / dist};
        const double along = (s1.r * s1.r - s2.r * s2.r + dist * dist) / (2 * dist);
        const double h = std::sqrt(std::max(0.0, s1.r * s1.r - along * along));
        const Vec3 o{s1.c[0] + along * n[0], s1.c[1] + along * n[1], s1.c[2] + along * n[2]};
        const Vec3 w = sub(p, o);
        Vec3 t = sub(w, Vec3{dot(w, n) * n[0], dot(w, n) * n[1], dot(w, n) * n[2]});
        double tn = norm(t);
        if (tn == 0) {
          t = std::abs(n[0]) < 0.9 ? cross(n, Vec3{1, 0, 0}) : cross(n, Vec3{0, 1, 0});
          tn = norm(t);
        }
        consider({o[0] + h * t[0] / tn, o[1] + h * t[1] / tn, o[2] + h * t[2] / tn}, near[x], near[y], -1);
        // Triples: the circle meets a third sphere in up to two points.
        for (std::size_t z = y + 1; z < near.size(); ++z) {
          const Item& c3 = items[near[z]];
          if (c3.kind != Kind::sphere) continue;
          const SphereData& s3 = spheres[c3.data];
          // Points o + h(cos φ e1 + sin φ e2) with |· − c3|² = r3²: α cos φ + β sin φ = γ.
          const Vec3 e1 = std::abs(n[0]) < 0.9 ? cross(n, Vec3{1, 0, 0}) : cross(n, Vec3{0, 1, 0});
          const double n1 = norm(e1);
          const Vec3 u1{e1[0] / n1, e1[1] / n1, e1[2] / n1};
          const Vec3 u2 = cross(n, u1);
          const Vec3 oc = sub(o, s3.c);
          const double alpha = 2 * h * dot(oc, u1), beta = 2 * h * dot(oc, u2);
          const double gamma = s3.r * s3.r - dot(oc, oc) - h * h;
          const double rr = std::hypot(alpha, beta);
          if (rr == 0 || std::abs(gamma) > rr) continue;
          const double phi0 = std::atan2(beta, alpha), dphi = std::acos(std::clamp(gamma / rr, -1.0, 1.0));
          for (double phi : {phi0 - dphi, phi0 + dphi})
            consider({o[0] + h * (std::cos(phi) * u1[0] + std::sin(phi) * u2[0]),
                      o[1] + h * (std::cos(phi) * u1[1] + std::sin(phi) * u2[1]),
                      o[2] + h * (std::cos(phi) * u1[2] + std::sin(phi) * u2[2])},
                     near[x], near[y], near[z]);
        }
      }
    (void)all_spheres;
    if (best <= reach || near.size() == items.size()) return best;
    reach = std::isfinite(best) ? best : 2 * reach;
  }
}

}  // namespace cisamr::geometry
