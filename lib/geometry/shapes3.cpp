// The 3D halves of shapes.hpp: sphere, ellipsoid, cylinder, STL surface (through
// stl_mesh, unvalidated: the oracle validates). NURBS surfaces are not implemented yet
// (std::logic_error).
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/vec_math.hpp"
#include "geometry/shape_sphere_ellipsoid.hpp"
#include "geometry/shapes_detail.hpp"
#include "geometry/stl_mesh.hpp"

namespace cisamr::geometry::detail {
namespace {

[[noreturn]] void not_implemented() { throw std::logic_error("not implemented yet"); }


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

// h(d) = max over the (convex) shape of x·d.
double support(const Shape& s, const Vec3& d) {
  if (const auto* sp = std::get_if<Sphere>(&s)) return dot(sp->center, d) + sp->radius * norm(d);
  if (const auto* e = std::get_if<Ellipsoid>(&s)) {
    Vec3 db{};
    for (int j = 0; j < 3; ++j)
      db[j] = e->semi_axes[j] * (e->rotation[0][j] * d[0] + e->rotation[1][j] * d[1] + e->rotation[2][j] * d[2]);
    return dot(e->center, d) + norm(db);
  }
  if (const auto* c = std::get_if<Cylinder>(&s)) {
    const Vec3 ax{c->end[0] - c->start[0], c->end[1] - c->start[1], c->end[2] - c->start[2]};
    const double l = norm(ax);
    const double du = dot(d, ax) / l;
    return std::max(dot(c->start, d), dot(c->end, d)) + c->radius * std::sqrt(std::max(0.0, dot(d, d) - du * du));
  }
  not_implemented();
}

stl::Mesh mesh_of(const StlSurface& s) {
  stl::Mesh m;
  stl::build(s, m, false);
  return m;
}

Vec3 direction(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

}  // namespace

Box3 bounding_box3(const Shape& s) {
  if (const auto* sp = std::get_if<Sphere>(&s)) {
    const double r = sp->radius;
    return {{sp->center[0] - r, sp->center[1] - r, sp->center[2] - r}, {sp->center[0] + r, sp->center[1] + r, sp->center[2] + r}};
  }
  if (const auto* e = std::get_if<Ellipsoid>(&s)) {
    Box3 b{};
    for (int d = 0; d < 3; ++d) {
      const double h = ellipsoid_half_extent(*e, d);
      b.min[d] = e->center[d] - h, b.max[d] = e->center[d] + h;
    }
    return b;
  }
  if (std::get_if<Cylinder>(&s)) {
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
  if (const auto* st = std::get_if<StlSurface>(&s)) {
    if (st->triangles.empty()) return {};
    return mesh_of(*st).box;
  }
  not_implemented();
}

double measure3(const Shape& s) {
  if (const auto* sp = std::get_if<Sphere>(&s)) return 4.0 / 3.0 * M_PI * std::pow(sp->radius, 3);
  if (const auto* e = std::get_if<Ellipsoid>(&s)) return 4.0 / 3.0 * M_PI * e->semi_axes[0] * e->semi_axes[1] * e->semi_axes[2];
  if (const auto* c = std::get_if<Cylinder>(&s)) {
    const Vec3 ax{c->end[0] - c->start[0], c->end[1] - c->start[1], c->end[2] - c->start[2]};
    return M_PI * c->radius * c->radius * norm(ax);
  }
  if (const auto* st = std::get_if<StlSurface>(&s)) return st->triangles.empty() ? 0.0 : stl::volume(mesh_of(*st));
  not_implemented();
}

double boundary_measure3(const Shape& s) {
  if (const auto* sp = std::get_if<Sphere>(&s)) return 4 * M_PI * sp->radius * sp->radius;
  if (const auto* e = std::get_if<Ellipsoid>(&s)) {
    // ∫∫ |r_θ × r_φ|: Gauss–Legendre in θ (64 panels × 8 points), trapezoid in φ.
    static const double gx[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
    static const double gw[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
    const double a = e->semi_axes[0], b = e->semi_axes[1], c = e->semi_axes[2];
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
  if (const auto* c = std::get_if<Cylinder>(&s)) {
    const Vec3 ax{c->end[0] - c->start[0], c->end[1] - c->start[1], c->end[2] - c->start[2]};
    return 2 * M_PI * c->radius * norm(ax) + 2 * M_PI * c->radius * c->radius;
  }
  if (const auto* st = std::get_if<StlSurface>(&s)) return st->triangles.empty() ? 0.0 : stl::surface_area(mesh_of(*st));
  not_implemented();
}

std::vector<Vec3> boundary_samples3(const Shape& s, double spacing) {
  std::vector<Vec3> out;
  auto fibonacci = [&](int n, auto&& map) {
    const double golden = M_PI * (3 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
      const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(std::max(0.0, 1 - z * z));
      out.push_back(map(Vec3{r * std::cos(golden * i), r * std::sin(golden * i), z}));
    }
  };
  if (const auto* sp = std::get_if<Sphere>(&s)) {
    const int n = std::max(12, static_cast<int>(std::ceil(2 * boundary_measure3(s) / (spacing * spacing))));
    fibonacci(n, [&](const Vec3& u) {
      return Vec3{sp->center[0] + sp->radius * u[0], sp->center[1] + sp->radius * u[1], sp->center[2] + sp->radius * u[2]};
    });
  } else if (const auto* e = std::get_if<Ellipsoid>(&s)) {
    const double amax = std::max({e->semi_axes[0], e->semi_axes[1], e->semi_axes[2]});
    const int n = std::max(12, static_cast<int>(std::ceil(2 * 4 * M_PI * amax * amax / (spacing * spacing))));
    fibonacci(n, [&](const Vec3& u) {
      return from_body(*e, Vec3{e->semi_axes[0] * u[0], e->semi_axes[1] * u[1], e->semi_axes[2] * u[2]});
    });
  } else if (const auto* c = std::get_if<Cylinder>(&s)) {
    const Vec3 ax{c->end[0] - c->start[0], c->end[1] - c->start[1], c->end[2] - c->start[2]};
    const double l = norm(ax);
    const Vec3 u{ax[0] / l, ax[1] / l, ax[2] / l};
    // Two unit vectors orthogonal to the axis.
    Vec3 v = std::abs(u[0]) < 0.9 ? Vec3{0, -u[2], u[1]} : Vec3{-u[2], 0, u[0]};
    const double nv = norm(v);
    v = {v[0] / nv, v[1] / nv, v[2] / nv};
    const Vec3 w{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const int nring = std::max(8, static_cast<int>(std::ceil(2 * M_PI * c->radius / spacing)));
    const int nlen = std::max(1, static_cast<int>(std::ceil(l / spacing)));
    auto at = [&](double t, double rad, double ang) {
      Vec3 p{};
      for (int k = 0; k < 3; ++k) p[k] = c->start[k] + t * ax[k] + rad * (std::cos(ang) * v[k] + std::sin(ang) * w[k]);
      return p;
    };
    for (int i = 0; i <= nlen; ++i)
      for (int j = 0; j < nring; ++j) out.push_back(at(double(i) / nlen, c->radius, 2 * M_PI * j / nring));
    const int nrad = std::max(1, static_cast<int>(std::ceil(c->radius / spacing)));
    for (int cap = 0; cap < 2; ++cap)
      for (int i = 0; i < nrad; ++i) {
        const double rad = c->radius * i / nrad;
        const int n = std::max(1, static_cast<int>(std::ceil(2 * M_PI * rad / spacing)));
        for (int j = 0; j < n; ++j) out.push_back(at(cap, rad, 2 * M_PI * j / n));
      }
  } else if (const auto* st = std::get_if<StlSurface>(&s)) {
    // Vertices, then a barycentric grid on each face fine enough for `spacing`.
    if (st->triangles.empty()) return out;
    const stl::Mesh m = mesh_of(*st);
    out = m.vertices;
    for (const auto& f : m.faces) {
      const Vec3 &a = m.vertices[f[0]], &b = m.vertices[f[1]], &c = m.vertices[f[2]];
      const double longest = std::max({norm(Vec3{b[0] - a[0], b[1] - a[1], b[2] - a[2]}),
                                       norm(Vec3{c[0] - b[0], c[1] - b[1], c[2] - b[2]}),
                                       norm(Vec3{a[0] - c[0], a[1] - c[1], a[2] - c[2]})});
      const int n = std::max(1, static_cast<int>(std::ceil(longest / spacing)));
      for (int i = 0; i <= n; ++i)
        for (int j = 0; i + j <= n; ++j) {
          if ((i == 0 && j == 0) || (i == n) || (j == n)) continue;  // vertices already in
          const double u = double(i) / n, v = double(j) / n, w = 1 - u - v;
          out.push_back({w * a[0] + u * b[0] + v * c[0], w * a[1] + u * b[1] + v * c[1], w * a[2] + u * b[2] + v * c[2]});
        }
    }
  } else {
    not_implemented();
  }
  return out;
}

namespace {

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
      if (point_in(p)) {
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

  bool point_in(const Vec3& p) const {
    for (int d = 0; d < 3; ++d)
      if (!(p[d] >= clip.min[d] && p[d] <= clip.max[d])) return false;
    return true;
  }

  static constexpr int kMaxDepth = 52;  // parameter steps near the double resolution of π
};

}  // namespace

void boundary_samples_within3(const Shape& s, double spacing, const Box3& clip, std::vector<Vec3>& points,
                              std::vector<double>& areas) {
  points.clear();
  areas.clear();
  const auto quadric = [&](const Vec3& center, const Vec3& semi, const Rotation3& frame) {
    const double amax = std::max({semi[0], semi[1], semi[2]});
    QuadricPatches{center, semi, frame, amax, spacing, clip, points, areas}.visit(0, M_PI, 0, 2 * M_PI, 0);
  };
  if (const auto* sp = std::get_if<Sphere>(&s)) {
    quadric(sp->center, {sp->radius, sp->radius, sp->radius}, Rotation3{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}});
    return;
  }
  if (const auto* e = std::get_if<Ellipsoid>(&s)) {
    quadric(e->center, e->semi_axes, e->rotation);
    return;
  }
  // Other families: their evenly spread samples, each standing for an equal share.
  const std::vector<Vec3> all = boundary_samples3(s, spacing);
  const double share = all.empty() ? 0 : boundary_measure3(s) / static_cast<double>(all.size());
  for (const Vec3& p : all)
    if (p[0] >= clip.min[0] && p[0] <= clip.max[0] && p[1] >= clip.min[1] && p[1] <= clip.max[1] &&
        p[2] >= clip.min[2] && p[2] <= clip.max[2])
      points.push_back(p), areas.push_back(share);
}

bool contains3(const Shape& s, const Vec3& p) {
  if (const auto* sp = std::get_if<Sphere>(&s)) {
    const Vec3 d{p[0] - sp->center[0], p[1] - sp->center[1], p[2] - sp->center[2]};
    return dot(d, d) <= sp->radius * sp->radius;
  }
  if (const auto* e = std::get_if<Ellipsoid>(&s)) {
    const Vec3 b = to_body(*e, p);
    double q = 0;
    for (int j = 0; j < 3; ++j) q += (b[j] / e->semi_axes[j]) * (b[j] / e->semi_axes[j]);
    return q <= 1 + 1e-14;
  }
  if (const auto* c = std::get_if<Cylinder>(&s)) {
    const Vec3 ax{c->end[0] - c->start[0], c->end[1] - c->start[1], c->end[2] - c->start[2]};
    const Vec3 d{p[0] - c->start[0], p[1] - c->start[1], p[2] - c->start[2]};
    const double ll = dot(ax, ax), t = dot(d, ax);
    if (t < 0 || t > ll) return false;
    return dot(d, d) - t * t / ll <= c->radius * c->radius;
  }
  if (const auto* st = std::get_if<StlSurface>(&s)) return !st->triangles.empty() && stl::side(mesh_of(*st), p) >= 0;
  not_implemented();
}

bool overlap3(const Shape& a, const Shape& b, double gap) {
  const auto* sa = std::get_if<Sphere>(&a);
  const auto* sb = std::get_if<Sphere>(&b);
  if (sa && sb) {
    const Vec3 d{sa->center[0] - sb->center[0], sa->center[1] - sb->center[1], sa->center[2] - sb->center[2]};
    const double r = sa->radius + sb->radius + gap;
    return dot(d, d) <= r * r;
  }
  const Box3 ba = bounding_box3(a), bb = bounding_box3(b);
  for (int k = 0; k < 3; ++k)
    if (ba.max[k] + gap < bb.min[k] || bb.max[k] + gap < ba.min[k]) return false;
  const auto* ta = std::get_if<StlSurface>(&a);
  const auto* tb = std::get_if<StlSurface>(&b);
  if (ta || tb) {
    // Conservative: with a positive gap, overlapping inflated boxes already count; else
    // points of either boundary inside the other, or mesh edges piercing the other mesh.
    if (gap > 0) return true;
    const double size = std::max(norm(Vec3{ba.max[0] - ba.min[0], ba.max[1] - ba.min[1], ba.max[2] - ba.min[2]}),
                                 norm(Vec3{bb.max[0] - bb.min[0], bb.max[1] - bb.min[1], bb.max[2] - bb.min[2]}));
    for (const Vec3& q : boundary_samples3(a, size / 64))
      if (contains3(b, q)) return true;
    for (const Vec3& q : boundary_samples3(b, size / 64))
      if (contains3(a, q)) return true;
    if (ta && tb) {
      const stl::Mesh ma = mesh_of(*ta), mb = mesh_of(*tb);
      std::vector<double> ts;
      for (const auto& f : ma.faces)
        for (int e = 0; e < 3; ++e) {
          stl::segment_hits(mb, ma.vertices[f[e]], ma.vertices[f[(e + 1) % 3]], ts);
          if (!ts.empty()) return true;
        }
    }
    return false;
  }
  // Convex bodies are apart by more than gap iff some unit d has h_a(d) + h_b(−d) < −gap.
  // Search: Fibonacci directions, then a shrinking pattern search in (θ, φ) from the best.
  auto g = [&](double th, double ph) {
    const Vec3 d = direction(th, ph);
    return support(a, d) + support(b, Vec3{-d[0], -d[1], -d[2]});
  };
  const int n = 1500;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  struct Start {
    double v, th, ph;
  };
  std::vector<Start> starts;
  for (int i = 0; i < n; ++i) {
    const double z = 1 - 2 * (i + 0.5) / n;
    const double th = std::acos(z), ph = std::fmod(golden * i, 2 * M_PI);
    starts.push_back({g(th, ph), th, ph});
  }
  std::partial_sort(starts.begin(), starts.begin() + 4, starts.end(), [](const Start& x, const Start& y) { return x.v < y.v; });
  double best = starts[0].v;
  for (int s = 0; s < 4; ++s) {
    double th = starts[s].th, ph = starts[s].ph, v = starts[s].v, step = 0.1;
    // Rotate the frame so that the start is not near a pole of (θ, φ).
    while (step > 1e-13) {
      bool moved = false;
      const double cand[8][2] = {{step, 0}, {-step, 0}, {0, step}, {0, -step}, {step, step}, {-step, -step}, {step, -step}, {-step, step}};
      for (const auto& c : cand) {
        const double w = g(th + c[0], ph + c[1]);
        if (w < v) {
          v = w, th += c[0], ph += c[1], moved = true;
          break;
        }
      }
      if (!moved) step *= 0.5;
    }
    best = std::min(best, v);
    if (best < -gap) return false;
  }
  return best >= -gap;
}

}  // namespace cisamr::geometry::detail
