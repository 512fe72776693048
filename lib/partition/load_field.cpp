#include "partition/load_field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include "core/error.hpp"
#include "geometry/shapes.hpp"

namespace cisamr::partition {
namespace {

using namespace geometry;

double sq(double x) { return x * x; }

class Accumulator {
 public:
  explicit Accumulator(LoadField& f) : f_(f) {}

  // Adds `value` at point x (wrapped when periodic, dropped outside the domain otherwise).
  const LoadField& field() const { return f_; }

  void add_point(Vec3 x, double value) {
    const std::int64_t c = cell_of(x);
    if (c >= 0) f_.cells[static_cast<std::size_t>(c)] += value;
  }

  // The raster cell holding x, -1 outside a non-periodic domain.
  std::int64_t cell_of(Vec3 x) const {
    std::int64_t idx[3] = {0, 0, 0};
    for (int d = 0; d < f_.dim; ++d) {
      const double L = f_.domain.max[d] - f_.domain.min[d];
      double t = x[d] - f_.domain.min[d];
      if (f_.periodic[static_cast<std::size_t>(d)]) {
        t = std::fmod(t, L);
        if (t < 0) t += L;
      } else if (t < 0 || t > L) {
        return -1;
      }
      idx[d] = std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor(t / (f_.coarsen * f_.h))), 0, f_.n[d] - 1);
    }
    return idx[0] + f_.n[0] * (idx[1] + f_.n[1] * idx[2]);
  }

  // A 2D closed polyline carrying `weight` per unit length; pieces shorter than `spacing`
  // go to the cell of their midpoint. `scale` corrects the polyline length to the exact one.
  void add_polyline(const std::vector<Vec2>& pts, double weight, double spacing, double scale) {
    for (std::size_t i = 0, n = pts.size(); i < n; ++i) {
      const Vec2& a = pts[i];
      const Vec2& b = pts[(i + 1) % n];
      const double len = std::sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]));
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
      const int copies = f_.periodic[static_cast<std::size_t>(d)] ? 1 : 0;
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

bool box_within(const Box3& inner, const Box3& outer) {
  for (int d = 0; d < 3; ++d)
    if (!(inner.min[d] >= outer.min[d] && inner.max[d] <= outer.max[d])) return false;
  return true;
}

// ceil(x), at least `least`, at most `most` (also for x = inf or NaN): sample counts stay
// bounded and their conversion defined, however large the shape.
std::int64_t sample_count(double x, std::int64_t least, std::int64_t most) {
  if (!(x < static_cast<double>(most))) return most;
  return std::max(least, static_cast<std::int64_t>(std::ceil(x)));
}
// Per ring and per cap radius (binds only for radii beyond ~1,300 sample spacings).
constexpr std::int64_t kMaxRingSamples = std::int64_t{1} << 13;

// Cylinders keep their own midpoint quadrature (rings at the middle of equal slices, caps in
// rings of equal area): geometry's cylinder samples lie on rings at t = i/n, which for fibres
// ending on the lattice sit exactly on raster planes and put whole rings on one side.
// In a bounded domain only the slices whose rings can meet it are visited: a fibre far
// longer than the domain costs what its part inside costs.
void add_cylinder(Accumulator& acc, const Cylinder& cy, double weight, double spacing) {
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
  const std::int64_t nphi = sample_count(2 * M_PI * r / spacing, 32, kMaxRingSamples);
  const std::int64_t nt = sample_count(len / spacing, 4, std::int64_t{1} << 52);
  // A ring at axial position t lies in the plane x·u = start·u + t; it meets the domain box
  // only if that plane does (the box's corners span the range of x·u), give or take rounding.
  std::int64_t first = 0, last = nt - 1;
  const LoadField& f = acc.field();
  if (!f.any_periodic()) {
    double lo = INFINITY, hi = -INFINITY;
    for (int corner = 0; corner < 8; ++corner) {
      double t = 0;
      for (int k = 0; k < 3; ++k) t += ((corner >> k & 1) ? f.domain.max[k] : f.domain.min[k]) * u[k] - cy.start[k] * u[k];
      lo = std::min(lo, t), hi = std::max(hi, t);
    }
    // Slice i's ring sits at t = (i + ½)·len/nt; one slice of margin against rounding.
    const double slices = static_cast<double>(nt) / len;
    const double top = static_cast<double>(nt - 1);
    first = static_cast<std::int64_t>(std::clamp(std::floor(lo * slices - 0.5) - 1, 0.0, top + 1));
    last = static_cast<std::int64_t>(std::clamp(std::ceil(hi * slices - 0.5) + 1, -1.0, top));
  }
  const double w_lat = weight * 2 * M_PI * r * len / (double(nphi) * nt);
  for (std::int64_t i = first; i <= last; ++i) {
    const double t = (i + 0.5) / nt * len;
    for (std::int64_t j = 0; j < nphi; ++j) {
      const double phi = 2 * M_PI * (j + 0.5) / nphi;
      Vec3 x{};
      for (int k = 0; k < 3; ++k)
        x[k] = cy.start[k] + t * u[k] + r * (std::cos(phi) * e1[k] + std::sin(phi) * e2[k]);
      acc.add_point(x, w_lat);
    }
  }
  const std::int64_t nr = sample_count(r / spacing, 2, kMaxRingSamples / 2);
  for (int cap = 0; cap < 2; ++cap) {
    const Vec3& o = cap == 0 ? cy.start : cy.end;
    for (std::int64_t k = 0; k < nr; ++k) {
      const double r0 = r * k / nr, r1 = r * (k + 1) / nr, rm = 0.5 * (r0 + r1);
      const std::int64_t np = sample_count(2 * M_PI * rm / spacing, 8, kMaxRingSamples);
      const double w = weight * M_PI * (r1 * r1 - r0 * r0) / np;
      for (std::int64_t j = 0; j < np; ++j) {
        const double phi = 2 * M_PI * (j + 0.5) / np;
        Vec3 x{};
        for (int q = 0; q < 3; ++q) x[q] = o[q] + rm * (std::cos(phi) * e1[q] + std::sin(phi) * e2[q]);
        acc.add_point(x, w);
      }
    }
  }
}

// geometry's 3D samples are evenly spread over the boundary, except on ellipsoids: Fibonacci
// points of the unit sphere, stretched, so the area around body point b grows with
// abc·|(b₀/a², b₁/b², b₂/c²)|. Returns the area each sample stands for.
std::vector<double> sample_areas(const Shape& shape, const std::vector<Vec3>& pts) {
  const double measure = shape_boundary_measure(shape);
  std::vector<double> area(pts.size(), measure / pts.size());
  if (const auto* e = std::get_if<Ellipsoid>(&shape)) {
    double total = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      double stretch = 0;
      for (int j = 0; j < 3; ++j) {
        double body = 0;
        for (int k = 0; k < 3; ++k) body += e->rotation[k][j] * (pts[i][k] - e->center[k]);
        stretch += sq(body / sq(e->semi_axes[j]));
      }
      total += area[i] = std::sqrt(stretch);
    }
    for (double& a : area) a *= measure / total;
  }
  return area;
}

// An STL surface's samples, summed per raster cell in sample order (cells ascending): what
// the surface adds to the raster, computable wherever its triangles are (stl_surface_load).
InclusionLoad stl_load(const Accumulator& acc, const Inclusion& inc, double weight, double spacing) {
  const auto pts = shape_boundary_samples(inc.shape, spacing);
  const std::vector<double> area = sample_areas(inc.shape, pts);
  std::vector<std::pair<std::int64_t, double>> cell_value;
  std::unordered_map<std::int64_t, std::size_t> slot;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const std::int64_t c = acc.cell_of(pts[i]);
    if (c < 0) continue;
    const auto [it, inserted] = slot.try_emplace(c, cell_value.size());
    if (inserted) cell_value.emplace_back(c, 0.0);
    cell_value[it->second].second += weight * area[i];
  }
  std::sort(cell_value.begin(), cell_value.end());
  InclusionLoad out;
  for (const auto& [c, v] : cell_value) out.cells.push_back(c), out.loads.push_back(v);
  return out;
}

void add_load(LoadField& f, const InclusionLoad& load) {
  for (std::size_t i = 0; i < load.cells.size(); ++i) {
    const std::int64_t c = load.cells[i];
    if (c < 0 || c >= static_cast<std::int64_t>(f.cells.size())) throw std::invalid_argument("inclusion load: cell outside the raster");
    f.cells[static_cast<std::size_t>(c)] += load.loads[i];
  }
}

// Spreads R^M · |A_k| over the raster: the samples of geometry::shape_boundary_samples,
// weighted so that their total is the exact shape_boundary_measure (circles: exact arcs;
// cylinders: add_cylinder).
void add_inclusion(Accumulator& acc, const Inclusion& inc, double weight, double spacing) {
  if (const auto* c = std::get_if<Circle>(&inc.shape)) return acc.add_circle(*c, weight);
  if (const auto* c = std::get_if<Cylinder>(&inc.shape)) return add_cylinder(acc, *c, weight, spacing);
  if (shape_dimension(inc.shape) == 2) {
    // A closed polyline scaled to the exact perimeter: its chords (a quarter cell) fall
    // short of the arcs by a relative (chord · curvature)² / 24, about 3e-4 for a radius of
    // 3 cells, which the scaling spreads over the curve. (Sampled 8× finer before: E1's
    // 11,200 ellipses took 0.6 s of a 2-rank run's 8 on rank 0 alone, for no better balance.)
    const auto pts = shape_boundary_samples(inc.shape, spacing);
    std::vector<Vec2> poly;
    double length = 0;
    for (std::size_t i = 0, n = pts.size(); i < n; ++i) {
      poly.push_back({pts[i][0], pts[i][1]});
      const double dx = pts[(i + 1) % n][0] - pts[i][0], dy = pts[(i + 1) % n][1] - pts[i][1];
      length += std::sqrt(dx * dx + dy * dy);
    }
    return acc.add_polyline(poly, weight, spacing, shape_boundary_measure(inc.shape) / length);
  }
  // Only what lies in a bounded domain counts: a surface that reaches out of it is
  // sampled there only, so that its cost follows the part inside.
  const LoadField& f = acc.field();
  if (!f.any_periodic() && !box_within(shape_bounding_box(inc.shape), f.domain)) {
    std::vector<Vec3> pts;
    std::vector<double> area;
    shape_boundary_samples_within(inc.shape, spacing, f.domain, pts, area);
    for (std::size_t i = 0; i < pts.size(); ++i) acc.add_point(pts[i], weight * area[i]);
    return;
  }
  const auto pts = shape_boundary_samples(inc.shape, spacing);
  if (pts.empty()) return;
  const std::vector<double> area = sample_areas(inc.shape, pts);
  for (std::size_t i = 0; i < pts.size(); ++i) acc.add_point(pts[i], weight * area[i]);
}

}  // namespace

int requested_levels(const SceneDesc& scene, const Inclusion& inc) { return inc.levels > 0 ? inc.levels : scene.levels; }

int effective_levels(const SceneDesc& scene, const Inclusion& inc) { return std::max(1, requested_levels(scene, inc)); }

Box3 inclusion_box(const Shape& shape) { return shape_holding_box(shape); }

double LoadField::box_load(const std::array<std::int64_t, 3>& lo, const std::array<std::int64_t, 3>& hi) const {
  const std::int64_t sx = n[0] + 1, sy = n[1] + 1;
  auto at = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return prefix[i + sx * (j + sy * k)]; };
  // The differences of prefix sums leave round-off where a box holds no load: -1e-19 made
  // the bisection's "within tolerance of the best cut" test, best · (1 + tol), reject every
  // cut of an empty region, which then lost its boxes (64 partitions of a sparse scene
  // left a hole in the mesh). A load is never negative.
  if (dim == 2)
    return std::max(0.0, at(hi[0], hi[1], 0) - at(lo[0], hi[1], 0) - at(hi[0], lo[1], 0) + at(lo[0], lo[1], 0));
  return std::max(0.0, at(hi[0], hi[1], hi[2]) - at(lo[0], hi[1], hi[2]) - at(hi[0], lo[1], hi[2]) -
                           at(hi[0], hi[1], lo[2]) + at(lo[0], lo[1], hi[2]) + at(lo[0], hi[1], lo[2]) +
                           at(hi[0], lo[1], lo[2]) - at(lo[0], lo[1], lo[2]));
}

double LoadField::total() const { return box_load({0, 0, 0}, n); }

double LoadField::box_cost(const std::array<std::int64_t, 3>& lo, const std::array<std::int64_t, 3>& hi) const {
  const double own = box_load(lo, hi);
  if (ghost_raster == 0 || ghost_weight == 0) return own;
  std::array<std::int64_t, 3> glo = lo, ghi = hi;
  for (int d = 0; d < dim; ++d) {
    glo[d] = std::max<std::int64_t>(0, lo[d] - ghost_raster);
    ghi[d] = std::min(n[d], hi[d] + ghost_raster);
  }
  return own + ghost_weight * std::max(0.0, box_load(glo, ghi) - own);
}

namespace {

// The raster of `scene` (no loads yet) and the sample spacing.
LoadField empty_field(const SceneDesc& scene, const PartitionOptions& options, double& spacing, bool allocate = true) {
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
  if (allocate) f.cells.assign(static_cast<std::size_t>(f.n[0] * f.n[1] * f.n[2]), 0.0);
  spacing = options.sample_spacing > 0 ? options.sample_spacing : 0.25 * f.coarsen * f.h;
  const auto& widths = options.ghost_cells_at_level;
  if (!widths.empty() && options.ghost_weight > 0 && !f.any_periodic() && !scene.inclusions.empty()) {
    int coarsest = std::numeric_limits<int>::max();
    for (const Inclusion& inc : scene.inclusions) coarsest = std::min(coarsest, requested_levels(scene, inc));
    f.ghost_cells = widths[static_cast<std::size_t>(std::clamp<int>(coarsest, 0, static_cast<int>(widths.size()) - 1))];
    f.ghost_raster = (f.ghost_cells + f.coarsen - 1) / f.coarsen;
    f.ghost_weight = options.ghost_weight;
  }
  return f;
}

bool stl_without_triangles(const Inclusion& inc) {
  const auto* s = std::get_if<StlSurface>(&inc.shape);
  return s != nullptr && s->triangles.empty();
}

}  // namespace

InclusionLoad stl_surface_load(const SceneDesc& scene, std::int32_t k, const PartitionOptions& options) {
  double spacing = 0;
  LoadField f = empty_field(scene, options, spacing, false);  // the raster's shape only
  const Inclusion& inc = scene.inclusions.at(static_cast<std::size_t>(k));
  const auto* stl = std::get_if<StlSurface>(&inc.shape);
  if (stl == nullptr || stl->triangles.empty())
    throw std::invalid_argument("stl_surface_load: inclusion " + std::to_string(k) + " is no STL surface with triangles");
  const double weight = std::pow(double(effective_levels(scene, inc)), f.exponent);
  InclusionLoad out = stl_load(Accumulator(f), inc, weight, spacing);
  out.box = inclusion_box(inc.shape);
  return out;
}

LoadField build_load_field(const SceneDesc& scene, const PartitionOptions& options, std::span<const InclusionLoad> given) {
  double spacing = 0;
  LoadField f = empty_field(scene, options, spacing);
  Accumulator acc(f);
  for (std::size_t k = 0; k < scene.inclusions.size(); ++k) {
    const Inclusion& inc = scene.inclusions[k];
    const double weight = std::pow(double(effective_levels(scene, inc)), f.exponent);
    if (stl_without_triangles(inc)) {
      if (k >= given.size()) throw std::invalid_argument("partition: an STL surface without triangles and no load given");
      add_load(f, given[k]);
    } else if (std::holds_alternative<StlSurface>(inc.shape)) {
      add_load(f, stl_load(acc, inc, weight, spacing));  // as stl_surface_load gives it
    } else {
      add_inclusion(acc, inc, weight, spacing);
    }
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
