// The packer: random sequential placement with hierarchical bounding boxes (paper §3):
//   enlarged box  = the primary box inflated by the gap, resolved through a uniform grid of
//                   primary boxes (the grid cell is the largest particle's extent);
//   primary box   = the tight AABB, compared pairwise (inflated by the pair's gap);
//   secondary     = a 8×8 (2D) / 4×4×4 (3D) cover of cells of the primary box that may touch
//                   the particle; two particles closer than the gap must have two cover cells
//                   closer than the gap, so disjoint covers prove separation cheaply;
//   exact         = analytic distance (circle/sphere pairs, parallel fibres) or GJK on
//                   support functions (convex_within), conservative near ties.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "core/error.hpp"
#include "geometry/shapes.hpp"
#include "pack/pack.hpp"
#include "pack/particles.hpp"
#include "pack/random.hpp"

namespace cisamr::pack {
namespace {

using namespace geometry;

double sq(double x) { return x * x; }

// What one particle costs while packing (its template, placement record and grid entries;
// about 650 bytes measured for circles), rounded up.
constexpr double kBytesPerParticle = 1000;

std::string about(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2g", value);
  return text;
}

struct Template {
  int population = 0;
  double size = 0;
  Shape shape;  // centred at the origin (fibres: axis through the origin's cross-section)
  Box3 box{};
  ConvexBody body;
  bool use_cover = false;
  std::uint64_t cover = ~std::uint64_t{0};
  double measure = 0;
  double broad = 0;  // extent across the particle (not along a fibre): sizes the grid
};

struct Raster {  // union coverage of an overlapping population, at cell centres
  Box3 box{};
  int n[3] = {1, 1, 1};
  double cell[3] = {1, 1, 1};
  std::vector<std::uint8_t> covered;
  std::int64_t count = 0;
  double fraction() const { return covered.empty() ? 0 : double(count) / double(covered.size()); }
};

struct PopState {
  const Population* spec = nullptr;
  Box3 region{};
  double region_measure = 1;
  int levels = 0;
  double scale = 1;  // applied to sampled sizes (count + volume_fraction)
  int measure_power = 2;
  bool periodic_axis[3] = {false, false, false};
  bool place_axis[3] = {false, false, false};
  std::vector<Vec3> cluster_centres;
  std::vector<Vec3> stl_vertices;  // centred at their centroid
  double stl_volume = 0;
  // accounting
  double placed_measure = 0;
  std::vector<double> placed_sizes;
  std::int64_t trials = 0, failures = 0;
  Raster raster;
};

struct Placed {
  int tmpl = 0;
  Vec3 position{};
};

double sample_law(const Law& l, Random& rng, bool positive) {
  auto accept = [&](double v) {
    return (!positive || v > 0) && (!l.has_min || v >= l.min) && (!l.has_max || v <= l.max);
  };
  auto clamp = [&](double v) {
    if (l.has_min) v = std::max(v, l.min);
    if (l.has_max) v = std::min(v, l.max);
    return positive ? std::max(v, 1e-6 * std::max(l.mean, l.value)) : v;
  };
  switch (l.kind) {
    case Law::Kind::fixed: return l.value;
    case Law::Kind::uniform: return rng.uniform(l.min, l.max);
    case Law::Kind::normal: {
      double v = 0;
      for (int k = 0; k < 100; ++k)
        if (accept(v = l.mean + l.std * rng.normal())) return v;
      return clamp(v);
    }
    case Law::Kind::lognormal: {
      const double s2 = std::log(1 + sq(l.std / l.mean));
      const double mu = std::log(l.mean) - 0.5 * s2;
      double v = 0;
      for (int k = 0; k < 100; ++k)
        if (accept(v = std::exp(mu + std::sqrt(s2) * rng.normal()))) return v;
      return clamp(v);
    }
  }
  return l.value;
}

Rotation3 multiply(const Rotation3& a, const Rotation3& b) {
  Rotation3 c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) c[i][j] += a[i][k] * b[k][j];
  return c;
}

Rotation3 axis_angle(Vec3 u, double angle) {
  const double c = std::cos(angle), s = std::sin(angle), t = 1 - c;
  return {{{t * u[0] * u[0] + c, t * u[0] * u[1] - s * u[2], t * u[0] * u[2] + s * u[1]},
           {t * u[0] * u[1] + s * u[2], t * u[1] * u[1] + c, t * u[1] * u[2] - s * u[0]},
           {t * u[0] * u[2] - s * u[1], t * u[1] * u[2] + s * u[0], t * u[2] * u[2] + c}}};
}

Vec3 random_unit(Random& rng) {
  const double z = rng.uniform(-1, 1), phi = rng.uniform(0, 2 * M_PI), r = std::sqrt(1 - z * z);
  return {r * std::cos(phi), r * std::sin(phi), z};
}

Rotation3 random_rotation(Random& rng) {  // Shoemake's uniform quaternion
  const double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
  const double x = a * std::sin(2 * M_PI * u2), y = a * std::cos(2 * M_PI * u2);
  const double z = b * std::sin(2 * M_PI * u3), w = b * std::cos(2 * M_PI * u3);
  return geometry::quaternion_rotation(w, x, y, z);
}

class Packer {
 public:
  explicit Packer(const PackSpec& spec) : spec_(spec), rng_(spec.seed), dim_(spec.dimension) {}

  PackResult run();

 private:
  void setup_population(std::size_t i);
  Template make_template(int pop);
  void finalize_template(Template& t);
  void setup_grid();
  bool place(int tmpl);
  bool sample_position(const Template& t, PopState& p, Vec3& pos);
  bool conflicts(const Template& t, const Vec3& pos);
  bool pair_conflicts(const Template& a, const Vec3& oa, const Template& b, const Vec3& ob,
                      double gap, bool overlap_ok);
  bool secondary_separated(const Template& a, const Vec3& oa, const Template& b, const Vec3& ob,
                           double gap) const;
  std::vector<int> shifts_of(const Box3& box, double inflate) const;
  Vec3 shift_vector(int s) const;
  void grid_insert(int placed_index);
  void raster_add(PopState& p, const Template& t, const Vec3& pos);
  void note_failure(int pop, const std::string& field, const std::string& what);
  double achieved(const PopState& p) const {
    return p.spec->overlap ? p.raster.fraction() : p.placed_measure / p.region_measure;
  }
  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw InputError(spec_.source, field, what);
  }

  const PackSpec& spec_;
  Random rng_;
  int dim_;
  std::vector<PopState> pops_;
  std::vector<Template> templates_;
  std::vector<Placed> placed_;
  double gap_max_ = 0;
  // grid of primary boxes (and periodic images)
  Vec3 grid_origin_{};
  double grid_cell_ = 1;
  int grid_n_[3] = {1, 1, 1};
  std::vector<std::vector<std::int32_t>> grid_;  // entries: placed_index * 27 + shift
  std::vector<std::uint32_t> stamp_;
  std::uint32_t stamp_now_ = 0;
  std::int64_t total_failures_ = 0;
  PackReport report_;
};

void Packer::setup_population(std::size_t i) {
  const Population& p = spec_.populations[i];
  PopState s;
  s.spec = &p;
  s.region = p.region ? *p.region : spec_.domain;
  s.region_measure = 1;
  for (int d = 0; d < dim_; ++d) s.region_measure *= s.region.max[d] - s.region.min[d];
  s.levels = p.levels >= 0 ? p.levels : spec_.levels;
  s.measure_power = p.shape == ShapeKind::fibre ? 2 : dim_;
  for (int d = 0; d < dim_; ++d) {
    const bool spans = std::abs(s.region.min[d] - spec_.domain.min[d]) < 1e-12 &&
                       std::abs(s.region.max[d] - spec_.domain.max[d]) < 1e-12;
    s.periodic_axis[d] = spec_.periodic && spans;
    s.place_axis[d] = !(p.shape == ShapeKind::fibre && d == p.axis);
  }
  if (p.overlap && p.count && p.volume_fraction)
    fail(p.field + ".volume_fraction", "an overlapping population takes a count or a volume_fraction, not both");
  if (p.overlap && p.shape == ShapeKind::stl) fail(p.field + ".overlap", "not supported for STL grains");
  if (p.shape == ShapeKind::stl) {
    const auto tri = read_stl_triangles(p.file);
    double vol = 0;
    Vec3 c{};
    for (std::size_t t = 0; t < tri.size(); t += 9) {
      const double* a = &tri[t];
      vol += (a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
              a[2] * (a[3] * a[7] - a[4] * a[6])) / 6.0;
    }
    std::vector<Vec3> v;
    for (std::size_t t = 0; t < tri.size(); t += 3) v.push_back({tri[t], tri[t + 1], tri[t + 2]});
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    for (const auto& q : v)
      for (int d = 0; d < 3; ++d) c[d] += q[d] / v.size();
    for (auto& q : v)
      for (int d = 0; d < 3; ++d) q[d] -= c[d];
    if (!(std::abs(vol) > 0)) fail(p.field + ".file", "the STL surface encloses no volume");
    s.stl_vertices = std::move(v);
    s.stl_volume = std::abs(vol);
  }
  if (p.spatial.kind == SpatialLaw::Kind::clustered)
    for (int k = 0; k < p.spatial.clusters; ++k) {
      Vec3 c{};
      for (int d = 0; d < dim_; ++d) c[d] = rng_.uniform(s.region.min[d], s.region.max[d]);
      s.cluster_centres.push_back(c);
    }
  if (p.overlap) {  // union raster: about a quarter of the smallest typical size per cell
    const Law& l = p.size;
    double typical = l.kind == Law::Kind::fixed ? l.value
                     : l.kind == Law::Kind::uniform ? l.min
                                                    : std::max(l.mean - l.std, l.mean / 3);
    if (l.has_min && l.min > 0) typical = std::max(typical, l.min);
    double cell = typical / 4;
    const double cap = dim_ == 2 ? 16.0e6 : 16.0e6;
    double cells = 1;
    for (int d = 0; d < dim_; ++d) cells *= (s.region.max[d] - s.region.min[d]) / cell;
    if (cells > cap) cell *= std::pow(cells / cap, 1.0 / dim_);
    std::size_t total = 1;
    s.raster.box = s.region;
    for (int d = 0; d < dim_; ++d) {
      s.raster.n[d] = std::max(1, static_cast<int>(std::ceil((s.region.max[d] - s.region.min[d]) / cell)));
      s.raster.cell[d] = (s.region.max[d] - s.region.min[d]) / s.raster.n[d];
      total *= s.raster.n[d];
    }
    s.raster.covered.assign(total, 0);
  }
  pops_.push_back(std::move(s));
}

Template Packer::make_template(int pop) {
  PopState& s = pops_[pop];
  const Population& p = *s.spec;
  Template t;
  t.population = pop;
  t.size = sample_law(p.size, rng_, true) * s.scale;
  const double r = t.size;
  auto angle2d = [&](double period) {
    switch (p.orientation.kind) {
      case OrientationLaw::Kind::random: return rng_.uniform(0, period);
      case OrientationLaw::Kind::fixed: return p.orientation.angle;
      case OrientationLaw::Kind::normal: return p.orientation.angle + p.orientation.std * rng_.normal();
    }
    return 0.0;
  };
  auto rotation3d = [&]() -> Rotation3 {
    switch (p.orientation.kind) {
      case OrientationLaw::Kind::random: return random_rotation(rng_);
      case OrientationLaw::Kind::fixed: return p.orientation.rotation;
      case OrientationLaw::Kind::normal: {
        const Vec3 axis = random_unit(rng_);
        return multiply(p.orientation.rotation, axis_angle(axis, p.orientation.std * rng_.normal()));
      }
    }
    return p.orientation.rotation;
  };
  auto aspect = [&](const Law& l) {
    const double q = sample_law(l, rng_, true);
    return q >= 1 ? q : 1 / q;
  };
  auto star = [&](double angle) {
    std::vector<Vec2> v;
    const int n = p.vertices;
    for (int i = 0; i < n; ++i) {
      const double th = angle + 2 * M_PI * (i + 0.3 * rng_.uniform(-1, 1)) / n;
      const double rad = r * (1 + p.roughness * rng_.uniform(-1, 1));
      v.push_back({rad * std::cos(th), rad * std::sin(th)});
    }
    return v;
  };
  switch (p.shape) {
    case ShapeKind::circle: t.shape = Circle{{0, 0}, r}; break;
    case ShapeKind::ellipse: {
      const double q = aspect(p.aspect);
      t.shape = Ellipse{{0, 0}, {r * std::sqrt(q), r / std::sqrt(q)}, angle2d(M_PI)};
      break;
    }
    case ShapeKind::polygon: t.shape = Polygon{star(angle2d(2 * M_PI))}; break;
    case ShapeKind::nurbs: {
      NurbsCurve c;
      c.degree = 3;
      c.control_points = star(angle2d(2 * M_PI));
      for (int k = 0; k < 3; ++k) c.control_points.push_back(c.control_points[k]);
      for (std::size_t k = 0; k < c.control_points.size() + 4; ++k) c.knots.push_back(double(k));
      t.shape = c;
      break;
    }
    case ShapeKind::sphere: t.shape = Sphere{{0, 0, 0}, r}; break;
    case ShapeKind::ellipsoid: {
      const double q1 = aspect(p.aspect);
      const double q2 = p.aspect_c ? aspect(*p.aspect_c) : q1;
      const double a = r * std::cbrt(q1 * q2);
      Ellipsoid e;
      e.semi_axes = {a, a / q1, a / q2};
      e.rotation = rotation3d();
      t.shape = e;
      break;
    }
    case ShapeKind::fibre: {
      Cylinder c;
      c.radius = r;
      const int a = p.axis;
      const bool lo_on_face = std::abs(s.region.min[a] - spec_.domain.min[a]) < 1e-12;
      const bool hi_on_face = std::abs(s.region.max[a] - spec_.domain.max[a]) < 1e-12;
      // A fibre leaving the domain is extended by one element so the mesher clips it cleanly.
      const double ext = spec_.periodic ? 0 : spec_.h;
      c.start[a] = s.region.min[a] - (lo_on_face ? ext : 0);
      c.end[a] = s.region.max[a] + (hi_on_face ? ext : 0);
      t.shape = c;
      break;
    }
    case ShapeKind::stl: {
      StlSurface g;
      g.file = p.file;
      g.scale = r;
      g.rotation = rotation3d();
      g.translate = {0, 0, 0};  // the vertex centroid is the origin of stl_vertices
      t.shape = g;
      break;
    }
  }
  finalize_template(t);
  return t;
}

// Everything derived from t.shape: boxes, body, cover, measure.
void Packer::finalize_template(Template& t) {
  const PopState& s = pops_[t.population];
  const Population& p = *s.spec;
  if (auto* g = std::get_if<StlSurface>(&t.shape)) {
    // The STL's own coordinates are centred at the centroid before scaling and rotating;
    // the scene's translate is set at output so that world = R·(scale·x) + translate.
    std::vector<Vec3> pts;
    pts.reserve(s.stl_vertices.size());
    for (const auto& v : s.stl_vertices) {
      Vec3 w{};
      for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) w[i] += g->rotation[i][k] * g->scale * v[k];
      pts.push_back(w);
    }
    t.box.min = {INFINITY, INFINITY, INFINITY};
    t.box.max = {-INFINITY, -INFINITY, -INFINITY};
    for (const auto& q : pts)
      for (int d = 0; d < 3; ++d) {
        t.box.min[d] = std::min(t.box.min[d], q[d]);
        t.box.max[d] = std::max(t.box.max[d], q[d]);
      }
    double rmax = 0;
    for (const auto& q : pts) rmax = std::max(rmax, std::sqrt(sq(q[0]) + sq(q[1]) + sq(q[2])));
    t.body.kind = ConvexBody::Kind::hull;
    t.body.points = std::move(pts);
    t.body.reference = {0, 0, 0};
    t.body.bound_radius = rmax;
    t.measure = s.stl_volume * g->scale * g->scale * g->scale;
    t.use_cover = false;
  } else {
    t.box = particle_box(t.shape);
    t.body = particle_body(t.shape);
    t.measure = particle_measure(t.shape);
    if (p.shape == ShapeKind::fibre)
      t.measure = M_PI * t.size * t.size * (s.region.max[p.axis] - s.region.min[p.axis]);
    t.use_cover = p.shape == ShapeKind::ellipse || p.shape == ShapeKind::ellipsoid ||
                  p.shape == ShapeKind::polygon || p.shape == ShapeKind::nurbs;
    if (t.use_cover) t.cover = secondary_cover(t.shape, t.box, dim_);
  }
  t.broad = 0;
  for (int d = 0; d < dim_; ++d)
    if (s.place_axis[d]) t.broad = std::max(t.broad, t.box.max[d] - t.box.min[d]);
}

Vec3 Packer::shift_vector(int sidx) const {
  Vec3 v{};
  int k = sidx;
  for (int d = 0; d < 3; ++d) {
    const int step = k % 3 - 1;
    k /= 3;
    v[d] = step * (spec_.domain.max[d] - spec_.domain.min[d]);
  }
  return v;
}

// Periodic images (shift indices, 13 = none) of a box inflated by `inflate`.
std::vector<int> Packer::shifts_of(const Box3& box, double inflate) const {
  int lo[3] = {1, 1, 1}, hi[3] = {1, 1, 1};
  if (spec_.periodic)
    for (int d = 0; d < dim_; ++d) {
      if (box.max[d] + inflate > spec_.domain.max[d]) lo[d] = 0;  // image shifted by −L
      if (box.min[d] - inflate < spec_.domain.min[d]) hi[d] = 2;  // image shifted by +L
    }
  std::vector<int> out;
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x) out.push_back(x + 3 * y + 9 * z);
  return out;
}

void Packer::setup_grid() {
  double cell = 0;
  for (const auto& t : templates_) cell = std::max(cell, t.broad);
  for (const auto& s : pops_) {  // templates made later (top-ups) follow the same law
    const Law& l = s.spec->size;
    const double big = (l.kind == Law::Kind::fixed ? l.value
                        : l.kind == Law::Kind::uniform ? l.max
                                                       : l.mean + 3 * l.std) * s.scale;
    cell = std::max(cell, 2 * big);
  }
  cell += gap_max_;
  double extent_max = 0;
  for (int d = 0; d < dim_; ++d) extent_max = std::max(extent_max, spec_.domain.max[d] - spec_.domain.min[d]);
  // At most 1024² cells in 2D and 128³ in 3D (about 50 MB of empty lists): tiny particles in
  // a huge domain make the cells longer than needed, never the grid larger than memory.
  cell = std::max(cell, extent_max / (dim_ == 2 ? 1024 : 128));
  std::size_t total = 1;
  for (int d = 0; d < 3; ++d) {
    grid_origin_[d] = spec_.domain.min[d];
    grid_n_[d] = d < dim_ ? std::max(1, static_cast<int>((spec_.domain.max[d] - spec_.domain.min[d]) / cell)) : 1;
    total *= grid_n_[d];
  }
  grid_cell_ = cell;
  for (int d = 0; d < dim_; ++d)  // stretch the cells to tile the domain exactly
    grid_cell_ = std::max(grid_cell_, (spec_.domain.max[d] - spec_.domain.min[d]) / grid_n_[d]);
  grid_.assign(total, {});
}

void Packer::grid_insert(int pi) {
  const Placed& pl = placed_[pi];
  const Template& t = templates_[pl.tmpl];
  Box3 b{};
  for (int d = 0; d < 3; ++d) {
    b.min[d] = t.box.min[d] + pl.position[d];
    b.max[d] = t.box.max[d] + pl.position[d];
  }
  for (int sidx : shifts_of(b, gap_max_)) {
    const Vec3 o = shift_vector(sidx);
    int lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::clamp(static_cast<int>(std::floor((b.min[d] + o[d] - gap_max_ - grid_origin_[d]) / grid_cell_)), 0, grid_n_[d] - 1);
      hi[d] = std::clamp(static_cast<int>(std::floor((b.max[d] + o[d] + gap_max_ - grid_origin_[d]) / grid_cell_)), 0, grid_n_[d] - 1);
    }
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x)
          grid_[x + grid_n_[0] * (y + static_cast<std::size_t>(grid_n_[1]) * z)].push_back(pi * 27 + sidx);
  }
}

bool Packer::secondary_separated(const Template& a, const Vec3& oa, const Template& b, const Vec3& ob,
                                 double gap) const {
  const int n = secondary_cells_per_axis(dim_);
  const int nz = dim_ == 3 ? n : 1;
  auto cells = [&](const Template& t, const Vec3& o, const Box3& other, std::vector<Box3>& out) {
    Vec3 c{};
    for (int d = 0; d < dim_; ++d) c[d] = (t.box.max[d] - t.box.min[d]) / n;
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          if (!(t.cover >> (i + n * (j + n * k)) & 1)) continue;
          const int idx[3] = {i, j, k};
          Box3 cell{};
          bool near = true;
          for (int d = 0; d < dim_; ++d) {
            cell.min[d] = t.box.min[d] + o[d] + idx[d] * c[d];
            cell.max[d] = cell.min[d] + c[d];
            if (cell.max[d] + gap < other.min[d] || cell.min[d] - gap > other.max[d]) near = false;
          }
          if (near) out.push_back(cell);
        }
  };
  Box3 ba{}, bb{};
  for (int d = 0; d < 3; ++d) {
    ba.min[d] = a.box.min[d] + oa[d]; ba.max[d] = a.box.max[d] + oa[d];
    bb.min[d] = b.box.min[d] + ob[d]; bb.max[d] = b.box.max[d] + ob[d];
  }
  std::vector<Box3> ca, cb;
  cells(a, oa, bb, ca);
  if (ca.empty()) return true;
  cells(b, ob, ba, cb);
  for (const auto& x : ca)
    for (const auto& y : cb) {
      bool close = true;
      for (int d = 0; d < dim_ && close; ++d)
        if (x.max[d] + gap < y.min[d] || y.max[d] + gap < x.min[d]) close = false;
      if (close) return false;
    }
  return true;
}

bool Packer::pair_conflicts(const Template& a, const Vec3& oa, const Template& b, const Vec3& ob,
                            double gap, bool overlap_ok) {
  for (int d = 0; d < dim_; ++d)
    if (a.box.max[d] + oa[d] + gap < b.box.min[d] + ob[d] || b.box.max[d] + ob[d] + gap < a.box.min[d] + oa[d])
      return false;
  const auto ka = a.body.kind, kb = b.body.kind;
  // Analytic distances: balls, and parallel fibres of the same axis.
  const Population& pa = *pops_[a.population].spec;
  const Population& pb = *pops_[b.population].spec;
  const bool balls = ka == ConvexBody::Kind::ball && kb == ConvexBody::Kind::ball;
  const bool parallel_fibres = pa.shape == ShapeKind::fibre && pb.shape == ShapeKind::fibre && pa.axis == pb.axis;
  if (balls || parallel_fibres) {
    ++report_.exact_checks;
    double d2 = 0;
    for (int d = 0; d < dim_; ++d)
      if (!parallel_fibres || d != pa.axis) d2 += sq(a.body.reference[d] + oa[d] - b.body.reference[d] - ob[d]);
    const double rsum = a.body.radius + b.body.radius;
    if (d2 >= sq(rsum + gap)) return false;
    return !(overlap_ok && d2 <= sq(rsum));
  }
  if (a.use_cover && b.use_cover && secondary_separated(a, oa, b, ob, gap)) {
    ++report_.secondary_rejections;
    return false;
  }
  ++report_.exact_checks;
  if (!convex_within(a.body, oa, b.body, ob, gap)) return false;
  if (!overlap_ok) return true;
  // Overlapping pits must really overlap, or keep the gap: no near-misses.
  ++report_.exact_checks;
  return !convex_within(a.body, oa, b.body, ob, 0);
}

bool Packer::conflicts(const Template& t, const Vec3& pos) {
  const PopState& s = pops_[t.population];
  Box3 b{};
  for (int d = 0; d < 3; ++d) {
    b.min[d] = t.box.min[d] + pos[d];
    b.max[d] = t.box.max[d] + pos[d];
  }
  if (spec_.periodic)  // a particle must not reach its own image
    for (int d = 0; d < dim_; ++d)
      if (s.periodic_axis[d] && b.max[d] - b.min[d] + s.spec->min_gap >= spec_.domain.max[d] - spec_.domain.min[d])
        return true;
  if (stamp_.size() < placed_.size() * 27) stamp_.resize(placed_.size() * 27, 0);
  for (int sc : shifts_of(b, gap_max_)) {
    const Vec3 oc = shift_vector(sc);
    Vec3 cpos{};
    for (int d = 0; d < 3; ++d) cpos[d] = pos[d] + oc[d];
    if (++stamp_now_ == 0) { std::fill(stamp_.begin(), stamp_.end(), 0); stamp_now_ = 1; }
    int lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::clamp(static_cast<int>(std::floor((b.min[d] + oc[d] - gap_max_ - grid_origin_[d]) / grid_cell_)), 0, grid_n_[d] - 1);
      hi[d] = std::clamp(static_cast<int>(std::floor((b.max[d] + oc[d] + gap_max_ - grid_origin_[d]) / grid_cell_)), 0, grid_n_[d] - 1);
    }
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x)
          for (std::int32_t entry : grid_[x + grid_n_[0] * (y + static_cast<std::size_t>(grid_n_[1]) * z)]) {
            if (stamp_[entry] == stamp_now_) continue;
            stamp_[entry] = stamp_now_;
            const Placed& other = placed_[entry / 27];
            const Template& ot = templates_[other.tmpl];
            const Vec3 so = shift_vector(entry % 27);
            Vec3 opos{};
            for (int d = 0; d < 3; ++d) opos[d] = other.position[d] + so[d];
            const Population& pa = *s.spec;
            const Population& pb = *pops_[ot.population].spec;
            const double gap = std::max(pa.min_gap, pb.min_gap);
            const bool overlap_ok = pa.overlap && pb.overlap && pa.phase == pb.phase;
            if (pair_conflicts(t, cpos, ot, opos, gap, overlap_ok)) return true;
          }
  }
  return false;
}

bool Packer::sample_position(const Template& t, PopState& s, Vec3& pos) {
  const Population& p = *s.spec;
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (int d = 0; d < dim_; ++d) {
    if (!s.place_axis[d]) continue;
    if (s.periodic_axis[d]) {
      lo[d] = spec_.domain.min[d];
      hi[d] = spec_.domain.max[d];
    } else {
      lo[d] = s.region.min[d] + p.min_gap - t.box.min[d];
      hi[d] = s.region.max[d] - p.min_gap - t.box.max[d];
    }
  }
  pos = {0, 0, 0};
  const bool near_cluster = !s.cluster_centres.empty() && rng_.uniform() < p.spatial.in_clusters;
  if (near_cluster) {
    const auto k = std::min(s.cluster_centres.size() - 1,
                            static_cast<std::size_t>(rng_.uniform() * s.cluster_centres.size()));
    for (int d = 0; d < dim_; ++d) {
      if (!s.place_axis[d]) continue;
      double v = s.cluster_centres[k][d] + p.spatial.cluster_radius * rng_.normal();
      if (s.periodic_axis[d]) {
        const double L = hi[d] - lo[d];
        v = lo[d] + std::fmod(std::fmod(v - lo[d], L) + L, L);
      } else if (v < lo[d] || v > hi[d]) {
        return false;
      }
      pos[d] = v;
    }
  } else {
    for (int d = 0; d < dim_; ++d)
      if (s.place_axis[d]) pos[d] = rng_.uniform(lo[d], hi[d]);
  }
  return true;
}

bool Packer::place(int ti) {
  const Template& t = templates_[ti];
  PopState& s = pops_[t.population];
  for (int d = 0; d < dim_; ++d)  // does it fit in its region at all?
    if (s.place_axis[d] && !s.periodic_axis[d] &&
        t.box.max[d] - t.box.min[d] + 2 * s.spec->min_gap > s.region.max[d] - s.region.min[d])
      return false;
  Vec3 pos{};
  for (std::int64_t trial = 0; trial < spec_.max_trials; ++trial) {
    ++s.trials;
    if (!sample_position(t, s, pos)) continue;
    if (conflicts(t, pos)) continue;
    placed_.push_back({ti, pos});
    grid_insert(static_cast<int>(placed_.size()) - 1);
    s.placed_measure += t.measure;
    s.placed_sizes.push_back(t.size);
    if (s.spec->overlap) raster_add(s, t, pos);
    return true;
  }
  return false;
}

void Packer::raster_add(PopState& s, const Template& t, const Vec3& pos) {
  Shape shape = translated(t.shape, pos);
  if (auto* c = std::get_if<NurbsCurve>(&shape)) {  // rasterise its fine polyline
    Polygon poly;
    std::vector<Vec2> cp(c->control_points.begin(), c->control_points.end() - 3);
    for (const auto& q : periodic_cubic_polyline(cp, 16)) poly.vertices.push_back({q[0], q[1]});
    shape = poly;
  }
  Raster& r = s.raster;
  Box3 b{};
  for (int d = 0; d < 3; ++d) {
    b.min[d] = t.box.min[d] + pos[d];
    b.max[d] = t.box.max[d] + pos[d];
  }
  for (int sidx : shifts_of(b, 0)) {
    const Vec3 o = shift_vector(sidx);
    int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (int d = 0; d < dim_; ++d) {
      lo[d] = std::max(0, static_cast<int>(std::floor((b.min[d] + o[d] - r.box.min[d]) / r.cell[d])));
      hi[d] = std::min(r.n[d] - 1, static_cast<int>(std::floor((b.max[d] + o[d] - r.box.min[d]) / r.cell[d])));
      if (lo[d] > hi[d]) goto next_image;
    }
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) {
          const std::size_t idx = x + static_cast<std::size_t>(r.n[0]) * (y + static_cast<std::size_t>(r.n[1]) * z);
          if (r.covered[idx]) continue;
          const Vec3 c{r.box.min[0] + (x + 0.5) * r.cell[0] - o[0], r.box.min[1] + (y + 0.5) * r.cell[1] - o[1],
                       dim_ == 3 ? r.box.min[2] + (z + 0.5) * r.cell[2] - o[2] : 0.0};
          if (particle_contains(shape, c)) {
            r.covered[idx] = 1;
            ++r.count;
          }
        }
  next_image:;
  }
}

void Packer::note_failure(int pop, const std::string& field, const std::string& what) {
  ++pops_[pop].failures;
  if (++total_failures_ > spec_.max_failures) fail(field, what);
}

PackResult Packer::run() {
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < spec_.populations.size(); ++i) setup_population(i);
  for (const auto& p : spec_.populations) gap_max_ = std::max(gap_max_, p.min_gap);

  // 0. Requests the machine cannot hold are refused before any particle is drawn (counts of
  // 1e7 and more ran out of memory drawing their templates).
  const double memory = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
  const double particle_limit = spec_.max_particles > 0 ? static_cast<double>(spec_.max_particles)
                                                        : std::max(memory / kBytesPerParticle, 1e6);
  const std::string limit_text =
      spec_.max_particles > 0 ? "the limit of " + about(particle_limit)
                              : "the " + about(particle_limit) + " this machine's " + about(memory / 1e9) + " GB of memory holds";
  double counted = 0;
  for (const auto& p : spec_.populations) {
    if (!p.count) continue;
    counted += static_cast<double>(*p.count);
    if (counted > particle_limit)
      fail(p.field + ".count", "the pack would hold about " + about(counted) + " particles (about " +
                                   about(counted * kBytesPerParticle / 1e9) + " GB), more than " + limit_text);
  }

  // 1. Templates of the non-overlapping populations: sizes and shapes drawn up front.
  std::vector<int> order;
  for (std::size_t pi = 0; pi < pops_.size(); ++pi) {
    PopState& s = pops_[pi];
    const Population& p = *s.spec;
    if (p.overlap) continue;
    const std::size_t first = templates_.size();
    if (p.count) {
      // Non-overlapping particles inside their region cannot measure more than it: stop
      // drawing as soon as the drawn ones do (sizes scaled to a fraction always fit).
      double drawn = 0;
      for (std::int64_t k = 0; k < *p.count; ++k) {
        templates_.push_back(make_template(static_cast<int>(pi)));
        drawn += templates_.back().measure;
        if (!p.volume_fraction && drawn > s.region_measure)
          fail(p.field + ".count", "cannot place " + std::to_string(*p.count) + " particles: the first " +
                                       std::to_string(k + 1) + " drawn already measure " + about(drawn) +
                                       ", more than their region's " + about(s.region_measure));
      }
      if (p.volume_fraction && *p.count > 0) {  // scale the sizes so both targets hold
        double sum = 0;
        for (std::size_t k = first; k < templates_.size(); ++k) sum += templates_[k].measure;
        const double f = std::pow(*p.volume_fraction * s.region_measure / sum, 1.0 / s.measure_power);
        s.scale = f;
        for (std::size_t k = first; k < templates_.size(); ++k) {
          templates_[k].shape = scaled_about_origin(templates_[k].shape, f);
          templates_[k].size *= f;
          finalize_template(templates_[k]);
        }
      }
    } else {
      const double target = *p.volume_fraction * s.region_measure;
      double sum = 0;
      while (sum < target) {
        templates_.push_back(make_template(static_cast<int>(pi)));
        sum += templates_.back().measure;
        if (static_cast<double>(templates_.size() - first) + counted > std::min(particle_limit, 5e7))
          fail(p.field + ".size", "sizes too small for the volume fraction (over " +
                                      about(std::min(particle_limit, 5e7)) + " particles in all)");
      }
    }
    for (std::size_t k = first; k < templates_.size(); ++k) order.push_back(static_cast<int>(k));
  }
  setup_grid();

  // 2. Largest first (ties: population, then draw order: deterministic).
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return templates_[a].measure > templates_[b].measure; });
  auto describe = [&](const PopState& s) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "placed %lld particles, volume fraction %.4f",
                  static_cast<long long>(s.placed_sizes.size()), achieved(s));
    return std::string(buf);
  };
  auto fraction_failure = [&](const PopState& s) {
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "target %.4f not reachable: best %.4f after %lld failed placements of %lld trials each",
                  *s.spec->volume_fraction, achieved(s), static_cast<long long>(total_failures_),
                  static_cast<long long>(spec_.max_trials));
    return std::string(buf);
  };
  for (std::size_t k = 0; k < order.size(); ++k) {
    const int ti = order[k];
    if (place(ti)) continue;
    const int pi = templates_[ti].population;
    PopState& s = pops_[pi];
    if (s.spec->count) {
      note_failure(pi, s.spec->volume_fraction ? s.spec->field + ".volume_fraction" : s.spec->field + ".count",
                   "cannot place " + std::to_string(*s.spec->count) + " particles: " + describe(s) +
                       " before " + std::to_string(total_failures_) + " placements failed (" +
                       std::to_string(spec_.max_trials) + " trials each)");
      templates_.push_back(make_template(pi));  // a fresh draw from the same law, tried later
      order.push_back(static_cast<int>(templates_.size()) - 1);
    } else {
      note_failure(pi, s.spec->field + ".volume_fraction", fraction_failure(s));
    }
  }
  // 3. Top up volume-fraction targets (failed particles left a deficit).
  for (std::size_t pi = 0; pi < pops_.size(); ++pi) {
    PopState& s = pops_[pi];
    if (s.spec->overlap || s.spec->count) continue;
    while (s.placed_measure < *s.spec->volume_fraction * s.region_measure) {
      templates_.push_back(make_template(static_cast<int>(pi)));
      if (!place(static_cast<int>(templates_.size()) - 1)) {
        if (achieved(s) >= *s.spec->volume_fraction - s.spec->tolerance) break;
        note_failure(static_cast<int>(pi), s.spec->field + ".volume_fraction", fraction_failure(s));
      }
    }
  }
  // 4. Overlapping populations (pits), one at a time until the count or the union fraction.
  for (std::size_t pi = 0; pi < pops_.size(); ++pi) {
    PopState& s = pops_[pi];
    const Population& p = *s.spec;
    if (!p.overlap) continue;
    std::int64_t placed = 0;
    while (p.count ? placed < *p.count : s.raster.fraction() < *p.volume_fraction) {
      templates_.push_back(make_template(static_cast<int>(pi)));
      if (place(static_cast<int>(templates_.size()) - 1)) {
        ++placed;
      } else if (p.count) {
        note_failure(static_cast<int>(pi), p.field + ".count",
                     "cannot place " + std::to_string(*p.count) + " particles: " + describe(s));
      } else {
        note_failure(static_cast<int>(pi), p.field + ".volume_fraction", fraction_failure(s));
      }
      if (templates_.size() > 50'000'000) fail(p.field + ".size", "over 5e7 particles drawn");
    }
  }

  // 5. The scene and the report.
  PackResult result;
  SceneDesc& scene = result.scene;
  scene.source = "";
  scene.dimension = dim_;
  scene.domain_min = spec_.domain.min;
  scene.domain_max = spec_.domain.max;
  if (dim_ == 2) scene.domain_min[2] = scene.domain_max[2] = 0;
  scene.periodic = {spec_.periodic, spec_.periodic, dim_ == 3 && spec_.periodic};
  scene.h = spec_.h;
  scene.levels = spec_.levels;
  scene.phases = spec_.phases;
  scene.matrix_phase = spec_.matrix_phase;
  scene.inclusions.reserve(placed_.size());
  for (const Placed& pl : placed_) {
    const Template& t = templates_[pl.tmpl];
    const PopState& s = pops_[t.population];
    scene.inclusions.push_back({translated(t.shape, pl.position), s.spec->phase, s.levels});
  }
  PackReport& rep = report_;
  double domain_measure = 1;
  for (int d = 0; d < dim_; ++d) domain_measure *= spec_.domain.max[d] - spec_.domain.min[d];
  for (const PopState& s : pops_) {
    PopulationReport pr;
    pr.name = s.spec->name;
    pr.placed = static_cast<std::int64_t>(s.placed_sizes.size());
    pr.achieved_fraction = achieved(s);
    pr.fraction_is_estimate = s.spec->overlap;
    pr.size_scale = s.scale;
    pr.trials = s.trials;
    pr.failures = s.failures;
    if (!s.placed_sizes.empty()) {
      pr.size_min = *std::min_element(s.placed_sizes.begin(), s.placed_sizes.end());
      pr.size_max = *std::max_element(s.placed_sizes.begin(), s.placed_sizes.end());
      double sum = 0, sum2 = 0;
      for (double v : s.placed_sizes) { sum += v; sum2 += v * v; }
      const double n = static_cast<double>(s.placed_sizes.size());
      pr.size_mean = sum / n;
      pr.size_std = std::sqrt(std::max(0.0, sum2 / n - pr.size_mean * pr.size_mean));
    }
    rep.total_fraction += pr.achieved_fraction * s.region_measure / domain_measure;
    rep.populations.push_back(pr);
  }
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.report = rep;
  return result;
}

}  // namespace

PackResult pack(const PackSpec& spec) {
  Packer packer(spec);
  return packer.run();
}

}  // namespace cisamr::pack
