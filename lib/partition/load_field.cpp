#include "partition/load_field.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "geometry/shapes.hpp"

namespace cisamr::partition {
namespace {

using namespace geometry;

template <class... F>
struct Overloaded : F... { using F::operator()...; };
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

double sq(double x) { return x * x; }

// Point on a NURBS curve (de Boor on homogeneous coordinates).
Vec2 nurbs_point(const NurbsCurve& c, double u) {
  const int p = c.degree;
  const int ncp = static_cast<int>(c.control_points.size());
  int k = p;
  while (k < ncp - 1 && u >= c.knots[k + 1]) ++k;
  double d[32][3];
  for (int j = 0; j <= p; ++j) {
    const int idx = k - p + j;
    const double w = c.weights.empty() ? 1.0 : c.weights[idx];
    d[j][0] = w * c.control_points[idx][0];
    d[j][1] = w * c.control_points[idx][1];
    d[j][2] = w;
  }
  for (int r = 1; r <= p; ++r)
    for (int j = p; j >= r; --j) {
      const int i = k - p + j;
      const double den = c.knots[i + p - r + 1] - c.knots[i];
      const double a = den > 0 ? (u - c.knots[i]) / den : 0;
      for (int q = 0; q < 3; ++q) d[j][q] = (1 - a) * d[j - 1][q] + a * d[j][q];
    }
  return {d[p][0] / d[p][2], d[p][1] / d[p][2]};
}

class Accumulator {
 public:
  explicit Accumulator(LoadField& f) : f_(f) {}

  // Adds `value` at point x (wrapped when periodic, dropped outside the domain otherwise).
  void add_point(Vec3 x, double value) {
    std::int64_t idx[3] = {0, 0, 0};
    for (int d = 0; d < f_.dim; ++d) {
      const double L = f_.domain.max[d] - f_.domain.min[d];
      double t = x[d] - f_.domain.min[d];
      if (f_.periodic) {
        t = std::fmod(t, L);
        if (t < 0) t += L;
      } else if (t < 0 || t > L) {
        return;
      }
      idx[d] = std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor(t / (f_.coarsen * f_.h))), 0, f_.n[d] - 1);
    }
    f_.cells[idx[0] + f_.n[0] * (idx[1] + f_.n[1] * idx[2])] += value;
  }

  // A 2D closed polyline carrying `weight` per unit length; pieces shorter than `spacing`
  // go to the cell of their midpoint. `scale` corrects the polyline length to the exact one.
  void add_polyline(const std::vector<Vec2>& pts, double weight, double spacing, double scale) {
    for (std::size_t i = 0, n = pts.size(); i < n; ++i) {
      const Vec2& a = pts[i];
      const Vec2& b = pts[(i + 1) % n];
      const double len = std::hypot(b[0] - a[0], b[1] - a[1]);
      const int pieces = std::max(1, static_cast<int>(std::ceil(len / spacing)));
      for (int k = 0; k < pieces; ++k) {
        const double t = (k + 0.5) / pieces;
        add_point({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), 0}, weight * scale * len / pieces);
      }
    }
  }

  // Exact: the circle is cut at every raster line (and its periodic copies) it crosses, and
  // each arc between consecutive cuts lies in one cell.
  void add_circle(const Circle& c, double weight) {
    std::vector<double> angles{0.0};
    const double r = c.radius;
    for (int d = 0; d < 2; ++d) {
      const double L = f_.domain.max[d] - f_.domain.min[d];
      const int copies = f_.periodic ? 1 : 0;
      for (int m = -copies; m <= copies; ++m)
        for (std::int64_t i = 0; i <= f_.n[d]; ++i) {
          const double line = f_.coordinate(d, i) + m * L;
          const double s = (line - c.center[d]) / r;
          if (s <= -1 || s >= 1) continue;
          if (d == 0) {
            const double a = std::acos(s);
            angles.push_back(a);
            angles.push_back(2 * M_PI - a);
          } else {
            const double a = std::asin(s);
            angles.push_back(a < 0 ? a + 2 * M_PI : a);
            angles.push_back(M_PI - a);
          }
        }
    }
    std::sort(angles.begin(), angles.end());
    angles.push_back(2 * M_PI);
    for (std::size_t i = 0; i + 1 < angles.size(); ++i) {
      const double d = angles[i + 1] - angles[i];
      if (d <= 0) continue;
      const double mid = 0.5 * (angles[i] + angles[i + 1]);
      add_point({c.center[0] + r * std::cos(mid), c.center[1] + r * std::sin(mid), 0}, weight * r * d);
    }
  }

 private:
  LoadField& f_;
};

void add_inclusion(Accumulator& acc, const Inclusion& inc, double weight, double spacing) {
  std::visit(
      Overloaded{
          [&](const Circle& c) { acc.add_circle(c, weight); },
          [&](const Ellipse& e) {
            const double a = e.semi_axes[0], b = e.semi_axes[1];
            const double per = ellipse_perimeter(a, b);
            const int n = std::max(256, static_cast<int>(std::ceil(per / spacing)));
            std::vector<Vec2> pts;
            const double co = std::cos(e.angle), si = std::sin(e.angle);
            for (int i = 0; i < n; ++i) {
              const double t = 2 * M_PI * i / n;
              const double x = a * std::cos(t), y = b * std::sin(t);
              pts.push_back({e.center[0] + co * x - si * y, e.center[1] + si * x + co * y});
            }
            double len = 0;
            for (int i = 0; i < n; ++i) len += std::hypot(pts[(i + 1) % n][0] - pts[i][0], pts[(i + 1) % n][1] - pts[i][1]);
            acc.add_polyline(pts, weight, spacing, per / len);
          },
          [&](const Polygon& p) { acc.add_polyline(p.vertices, weight, spacing, 1.0); },
          [&](const NurbsCurve& c) {
            const int n = std::max(512, static_cast<int>(c.control_points.size()) * 64);
            acc.add_polyline(nurbs_polyline(c, n), weight, spacing, 1.0);
          },
          [&](const Sphere& s) {
            const double area = 4 * M_PI * sq(s.radius);
            const auto n = std::max<std::int64_t>(64, static_cast<std::int64_t>(std::ceil(area / sq(spacing))));
            const double golden = M_PI * (3 - std::sqrt(5.0));
            for (std::int64_t i = 0; i < n; ++i) {
              const double z = 1 - (2 * i + 1.0) / n, rr = std::sqrt(1 - z * z), phi = golden * i;
              acc.add_point({s.center[0] + s.radius * rr * std::cos(phi), s.center[1] + s.radius * rr * std::sin(phi),
                             s.center[2] + s.radius * z},
                            weight * area / n);
            }
          },
          [&](const Ellipsoid& e) {
            const double a = e.semi_axes[0], b = e.semi_axes[1], c = e.semi_axes[2];
            const double big = std::max({a, b, c});
            const int nu = std::max(32, static_cast<int>(std::ceil(2 * big / spacing)));
            const int nphi = std::max(64, static_cast<int>(std::ceil(2 * M_PI * big / spacing)));
            const double du = 2.0 / nu, dphi = 2 * M_PI / nphi;
            for (int i = 0; i < nu; ++i) {
              const double u = -1 + (i + 0.5) * du, s = std::sqrt(1 - u * u);
              for (int j = 0; j < nphi; ++j) {
                const double phi = (j + 0.5) * dphi, cp = std::cos(phi), sp = std::sin(phi);
                const Vec3 pu{-a * u / s * cp, -b * u / s * sp, c};
                const Vec3 pp{-a * s * sp, b * s * cp, 0};
                const double dA = std::sqrt(sq(pu[1] * pp[2] - pu[2] * pp[1]) + sq(pu[2] * pp[0] - pu[0] * pp[2]) +
                                            sq(pu[0] * pp[1] - pu[1] * pp[0])) * du * dphi;
                const Vec3 body{a * s * cp, b * s * sp, c * u};
                Vec3 x = e.center;
                for (int r = 0; r < 3; ++r)
                  for (int k = 0; k < 3; ++k) x[r] += e.rotation[r][k] * body[k];
                acc.add_point(x, weight * dA);
              }
            }
          },
          [&](const Cylinder& cy) {
            Vec3 u{cy.end[0] - cy.start[0], cy.end[1] - cy.start[1], cy.end[2] - cy.start[2]};
            const double len = std::sqrt(sq(u[0]) + sq(u[1]) + sq(u[2]));
            for (auto& v : u) v /= len;
            // Two unit vectors perpendicular to the axis.
            Vec3 helper = std::abs(u[0]) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
            Vec3 e1{u[1] * helper[2] - u[2] * helper[1], u[2] * helper[0] - u[0] * helper[2], u[0] * helper[1] - u[1] * helper[0]};
            const double n1 = std::sqrt(sq(e1[0]) + sq(e1[1]) + sq(e1[2]));
            for (auto& v : e1) v /= n1;
            const Vec3 e2{u[1] * e1[2] - u[2] * e1[1], u[2] * e1[0] - u[0] * e1[2], u[0] * e1[1] - u[1] * e1[0]};
            const double r = cy.radius;
            const int nphi = std::max(32, static_cast<int>(std::ceil(2 * M_PI * r / spacing)));
            const int nt = std::max(4, static_cast<int>(std::ceil(len / spacing)));
            const double w_lat = weight * 2 * M_PI * r * len / (double(nphi) * nt);
            for (int i = 0; i < nt; ++i) {
              const double t = (i + 0.5) / nt * len;
              for (int j = 0; j < nphi; ++j) {
                const double phi = 2 * M_PI * (j + 0.5) / nphi;
                Vec3 x{};
                for (int k = 0; k < 3; ++k)
                  x[k] = cy.start[k] + t * u[k] + r * (std::cos(phi) * e1[k] + std::sin(phi) * e2[k]);
                acc.add_point(x, w_lat);
              }
            }
            const int nr = std::max(2, static_cast<int>(std::ceil(r / spacing)));
            for (int cap = 0; cap < 2; ++cap) {
              const Vec3& o = cap == 0 ? cy.start : cy.end;
              for (int k = 0; k < nr; ++k) {
                const double r0 = r * k / nr, r1 = r * (k + 1) / nr, rm = 0.5 * (r0 + r1);
                const int np = std::max(8, static_cast<int>(std::ceil(2 * M_PI * rm / spacing)));
                const double w = weight * M_PI * (r1 * r1 - r0 * r0) / np;
                for (int j = 0; j < np; ++j) {
                  const double phi = 2 * M_PI * (j + 0.5) / np;
                  Vec3 x{};
                  for (int q = 0; q < 3; ++q) x[q] = o[q] + rm * (std::cos(phi) * e1[q] + std::sin(phi) * e2[q]);
                  acc.add_point(x, w);
                }
              }
            }
          },
          [&](const auto& s) {  // STL and NURBS surfaces: samples from the geometry module
            const Shape shape = s;
            const auto pts = shape_boundary_samples(shape, spacing);
            if (pts.empty()) return;
            const double each = weight * shape_boundary_measure(shape) / pts.size();
            for (const auto& p : pts) acc.add_point(p, each);
          },
      },
      inc.shape);
}

}  // namespace

std::vector<Vec2> nurbs_polyline(const NurbsCurve& c, int samples) {
  const int p = c.degree;
  const int ncp = static_cast<int>(c.control_points.size());
  const double u0 = c.knots[p], u1 = c.knots[ncp];
  std::vector<Vec2> pts;
  for (int i = 0; i < samples; ++i) pts.push_back(nurbs_point(c, u0 + (u1 - u0) * i / samples));
  return pts;
}

double ellipse_perimeter(double a, double b) {
  // C = 2π/M(a,b) · (a² − Σ_{n≥0} 2^{n−1} c_n²), c_0² = a² − b².
  double an = std::max(a, b), bn = std::min(a, b);
  double sum = 0.5 * (an * an - bn * bn), pow2 = 0.5;
  const double a2 = an * an;
  for (int i = 0; i < 64 && an - bn > 1e-15 * an; ++i) {
    const double cn = 0.5 * (an - bn);
    const double next_a = 0.5 * (an + bn);
    bn = std::sqrt(an * bn);
    an = next_a;
    pow2 *= 2;
    sum += pow2 * cn * cn;
  }
  return 2 * M_PI / an * (a2 - sum);
}

int effective_levels(const SceneDesc& scene, const Inclusion& inc) {
  return std::max(1, inc.levels > 0 ? inc.levels : scene.levels);
}

Box3 inclusion_box(const Shape& shape, int dim) {
  Box3 b{};
  b.min = {INFINITY, INFINITY, dim == 2 ? 0.0 : INFINITY};
  b.max = {-INFINITY, -INFINITY, dim == 2 ? 0.0 : -INFINITY};
  auto grow = [&](double x, double y, double z) {
    const double p[3] = {x, y, z};
    for (int d = 0; d < dim; ++d) {
      b.min[d] = std::min(b.min[d], p[d]);
      b.max[d] = std::max(b.max[d], p[d]);
    }
  };
  std::visit(Overloaded{
                 [&](const Circle& c) {
                   grow(c.center[0] - c.radius, c.center[1] - c.radius, 0);
                   grow(c.center[0] + c.radius, c.center[1] + c.radius, 0);
                 },
                 [&](const Ellipse& e) {
                   const double co = std::cos(e.angle), si = std::sin(e.angle);
                   const double ex = std::sqrt(sq(e.semi_axes[0] * co) + sq(e.semi_axes[1] * si));
                   const double ey = std::sqrt(sq(e.semi_axes[0] * si) + sq(e.semi_axes[1] * co));
                   grow(e.center[0] - ex, e.center[1] - ey, 0);
                   grow(e.center[0] + ex, e.center[1] + ey, 0);
                 },
                 [&](const Polygon& p) { for (const auto& v : p.vertices) grow(v[0], v[1], 0); },
                 [&](const NurbsCurve& c) { for (const auto& v : c.control_points) grow(v[0], v[1], 0); },
                 [&](const Sphere& s) {
                   grow(s.center[0] - s.radius, s.center[1] - s.radius, s.center[2] - s.radius);
                   grow(s.center[0] + s.radius, s.center[1] + s.radius, s.center[2] + s.radius);
                 },
                 [&](const Ellipsoid& e) {
                   Vec3 ext{};
                   for (int d = 0; d < 3; ++d) {
                     for (int k = 0; k < 3; ++k) ext[d] += sq(e.rotation[d][k] * e.semi_axes[k]);
                     ext[d] = std::sqrt(ext[d]);
                   }
                   grow(e.center[0] - ext[0], e.center[1] - ext[1], e.center[2] - ext[2]);
                   grow(e.center[0] + ext[0], e.center[1] + ext[1], e.center[2] + ext[2]);
                 },
                 [&](const Cylinder& c) {
                   Vec3 u{c.end[0] - c.start[0], c.end[1] - c.start[1], c.end[2] - c.start[2]};
                   const double len = std::sqrt(sq(u[0]) + sq(u[1]) + sq(u[2]));
                   Vec3 ext{};
                   for (int d = 0; d < 3; ++d) ext[d] = c.radius * std::sqrt(std::max(0.0, 1 - sq(u[d] / len)));
                   for (const Vec3* p : {&c.start, &c.end}) {
                     grow((*p)[0] - ext[0], (*p)[1] - ext[1], (*p)[2] - ext[2]);
                     grow((*p)[0] + ext[0], (*p)[1] + ext[1], (*p)[2] + ext[2]);
                   }
                 },
                 [&](const NurbsSurface& s) {
                   for (const auto& patch : s.patches)
                     for (const auto& v : patch.control_points) grow(v[0], v[1], v[2]);
                 },
                 [&](const StlSurface& s) {
                   for (const auto& p : shape_boundary_samples(Shape{s}, 1e300)) grow(p[0], p[1], p[2]);
                 },
             },
             shape);
  return b;
}

double LoadField::box_load(const std::array<std::int64_t, 3>& lo, const std::array<std::int64_t, 3>& hi) const {
  const std::int64_t sx = n[0] + 1, sy = n[1] + 1;
  auto at = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return prefix[i + sx * (j + sy * k)]; };
  if (dim == 2)
    return at(hi[0], hi[1], 0) - at(lo[0], hi[1], 0) - at(hi[0], lo[1], 0) + at(lo[0], lo[1], 0);
  return at(hi[0], hi[1], hi[2]) - at(lo[0], hi[1], hi[2]) - at(hi[0], lo[1], hi[2]) - at(hi[0], hi[1], lo[2]) +
         at(lo[0], lo[1], hi[2]) + at(lo[0], hi[1], lo[2]) + at(hi[0], lo[1], lo[2]) - at(lo[0], lo[1], lo[2]);
}

double LoadField::total() const { return box_load({0, 0, 0}, n); }

LoadField build_load_field(const SceneDesc& scene, const PartitionOptions& options) {
  LoadField f;
  f.dim = scene.dimension;
  f.domain.min = scene.domain_min;
  f.domain.max = scene.domain_max;
  f.h = scene.h;
  f.periodic = scene.periodic;
  f.exponent = options.load_exponent > 0 ? options.load_exponent : (f.dim == 2 ? 1.0 : 1.5);
  std::int64_t total = 1;
  for (int d = 0; d < f.dim; ++d) {
    f.lattice_cells[d] = std::max<std::int64_t>(1, std::llround((f.domain.max[d] - f.domain.min[d]) / f.h));
    total *= f.lattice_cells[d];
  }
  f.coarsen = 1;
  while (total / std::pow(double(f.coarsen), f.dim) > double(options.max_load_cells)) ++f.coarsen;
  for (int d = 0; d < 3; ++d)
    f.n[d] = d < f.dim ? (f.lattice_cells[d] + f.coarsen - 1) / f.coarsen : 1;
  f.cells.assign(static_cast<std::size_t>(f.n[0] * f.n[1] * f.n[2]), 0.0);
  const double spacing = options.sample_spacing > 0 ? options.sample_spacing : 0.25 * f.coarsen * f.h;
  Accumulator acc(f);
  for (const Inclusion& inc : scene.inclusions) {
    const double weight = std::pow(double(effective_levels(scene, inc)), f.exponent);
    add_inclusion(acc, inc, weight, spacing);
  }
  const std::int64_t sx = f.n[0] + 1, sy = f.n[1] + 1, sz = f.dim == 3 ? f.n[2] + 1 : 2;
  f.prefix.assign(static_cast<std::size_t>(sx * sy * sz), 0.0);
  const std::int64_t nz = f.dim == 3 ? f.n[2] : 1;
  for (std::int64_t k = 0; k < nz; ++k)
    for (std::int64_t j = 0; j < f.n[1]; ++j)
      for (std::int64_t i = 0; i < f.n[0]; ++i) {
        auto P = [&](std::int64_t a, std::int64_t b, std::int64_t c) -> double& { return f.prefix[a + sx * (b + sy * c)]; };
        P(i + 1, j + 1, k + 1) = f.cells[i + f.n[0] * (j + f.n[1] * k)] + P(i, j + 1, k + 1) + P(i + 1, j, k + 1) +
                                 P(i + 1, j + 1, k) - P(i, j, k + 1) - P(i, j + 1, k) - P(i + 1, j, k) + P(i, j, k);
      }
  if (f.dim == 2)  // 2D queries read the k = 0 layer: copy the k = 1 layer into it
    for (std::int64_t j = 0; j < sy; ++j)
      for (std::int64_t i = 0; i < sx; ++i) f.prefix[i + sx * j] = f.prefix[i + sx * (j + sy)];
  return f;
}

}  // namespace cisamr::partition
