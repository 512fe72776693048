// The generic geometry oracle (contract in oracle.hpp, schemes in README.md): candidate
// search, the crossing sweep, phase lookup, interface groups, measures and distances,
// over the shape models of shape_model.hpp. The per-family geometry is in shape_*.cpp,
// the CGAL search trees in box_index.cpp.
#include "geometry/periodic.hpp"
#include "geometry/oracle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>

#include "core/error.hpp"
#include "core/vec_math.hpp"
#include "geometry/box_index.hpp"
#include "geometry/overlap_groups.hpp"
#include "geometry/shape_family.hpp"
#include "geometry/shape_model.hpp"
#include "geometry/shapes.hpp"
#include "geometry/shapes_detail.hpp"

namespace cisamr::geometry {
namespace {


double point_distance(const Vec2& q, const Vec2& p) { return std::hypot(q[0] - p[0], q[1] - p[1]); }
double point_distance(const Vec3& q, const Vec3& p) { return norm(sub(q, p)); }

template <int Dim>
Box<Dim> cube_around(const Vec<Dim>& p, double r) {
  Box<Dim> b;
  for (int d = 0; d < Dim; ++d) b.min[d] = p[d] - r, b.max[d] = p[d] + r;
  return b;
}

// Gauss–Legendre 10 points on [-1, 1].
constexpr double kGx[5] = {0.1488743389816312, 0.4333953941292472, 0.6794095682990244,
                           0.8650633666889845, 0.9739065285171717};
constexpr double kGw[5] = {0.2955242247147529, 0.2692667193099963, 0.2190863625159820,
                           0.1494513491505806, 0.0666713443086881};

// ∫_{x0}^{x1} f (vector valued, np entries) with x = x0 + (x1−x0)(1 − cos πs)/2 (smooths
// square-root ends) and adaptive halving in s until |left + right − whole| ≤ tol·Δs.
template <class F>
void integrate(double x0, double x1, std::size_t np, double tol, int max_depth, F&& f, std::vector<double>& acc) {
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
    if (diff <= tol * (tk.s1 - tk.s0) || tk.depth >= max_depth) {
      for (std::size_t p = 0; p < np; ++p) acc[p] += left[p] + right[p];
    } else {
      stack.push_back({tk.s0, sm, tk.depth + 1, left});
      stack.push_back({sm, tk.s1, tk.depth + 1, right});
    }
  }
}

}  // namespace

template <int Dim>
struct Oracle<Dim>::Impl {
  using Model = DimensionModel<Dim>;
  using Index = std::conditional_t<Dim == 2, BoxIndex2, BoxIndex3>;
  struct Item {
    std::int32_t phase;  // phase index
    std::int32_t levels;
    std::int32_t group = -1;
  };

  SceneDesc scene;
  int matrix = 0;
  std::vector<Item> items;
  std::vector<std::unique_ptr<Model>> shapes;
  std::vector<Box<Dim>> boxes;  // shapes[k]->box(), contiguous for the hot paths
  std::unique_ptr<Index> index;

  // +1 inside, 0 on the boundary, -1 outside inclusion k.
  int side(std::int32_t k, const Point& p) const {
    if (!point_in_box(p, boxes[k])) return -1;
    return shapes[k]->side(p);
  }

  int phase_of_states(std::span<const std::int32_t> cands, const std::vector<std::uint8_t>& state) const {
    std::int32_t best = std::numeric_limits<std::int32_t>::max();
    for (std::size_t i = 0; i < cands.size(); ++i)
      if (state[i] && cands[i] < best) best = cands[i];
    return best == std::numeric_limits<std::int32_t>::max() ? matrix : items[best].phase;
  }

  void validate_and_build(const SceneDesc& s);
  bool regions_intersect(std::int32_t i, std::int32_t j, bool interiors) const;
  PhaseMask closure_mask(const Point& p, std::span<const std::int32_t> cands) const;
  double matrix_distance(const Point& p) const;
};

// ---------------------------------------------------------------- build and validation
namespace {

// The scene-wide checks of the oracle: the matrix phase and the number of phases.
void check_phases(const SceneDesc& scene) {
  const int matrix = scene.phase_index(scene.matrix_phase);
  if (matrix < 0)
    throw InputError(scene.source, "matrix_phase", "no phase has id " + std::to_string(scene.matrix_phase));
  if (scene.phases.size() > 64) throw InputError(scene.source, "phases", "at most 64 phases are supported");
}

// The phase index of inclusion i (checked) and its shape model (validated).
template <int Dim>
std::unique_ptr<DimensionModel<Dim>> checked_inclusion(const SceneDesc& scene, std::size_t i, int& phase) {
  const Inclusion& inc = scene.inclusions[i];
  const std::string field = inclusion_field(scene, i);
  phase = scene.phase_index(inc.phase);
  if (phase < 0) throw InputError(scene.source, field + ".phase", "no phase has id " + std::to_string(inc.phase));
  return make_shape_model<Dim>(inc.shape, scene.source, field);
}

}  // namespace

template <int Dim>
void validate_inclusions(const SceneDesc& scene) {
  check_phases(scene);
  for (std::size_t i = 0; i < scene.inclusions.size(); ++i) {
    const auto* stl = std::get_if<StlSurface>(&scene.inclusions[i].shape);
    if (stl != nullptr && stl->triangles.empty()) continue;
    int phase = 0;
    checked_inclusion<Dim>(scene, i, phase);
  }
}

template void validate_inclusions<2>(const SceneDesc&);
template void validate_inclusions<3>(const SceneDesc&);

template <int Dim>
void Oracle<Dim>::Impl::validate_and_build(const SceneDesc& s) {
  scene = s;
  check_phases(scene);
  matrix = scene.phase_index(scene.matrix_phase);
  items.reserve(scene.inclusions.size());
  shapes.reserve(scene.inclusions.size());
  for (std::size_t i = 0; i < scene.inclusions.size(); ++i) {
    Item it{};
    shapes.push_back(checked_inclusion<Dim>(scene, i, it.phase));
    it.levels = scene.inclusions[i].levels;
    items.push_back(it);
  }
  boxes.reserve(shapes.size());
  for (const auto& sh : shapes) boxes.push_back(sh->box());
  index = std::make_unique<Index>(boxes);
  detail::group_overlapping_inclusions(*this);
}

// Do the closed regions of i and j meet (interiors == false) or do their interiors meet
// (interiors == true)? Interiors must overlap by more than rounding-level depth to count:
// decimal input cannot express an exact tangency (README: overlap tolerance). Analytic
// pairs answer themselves; otherwise boundary samples of each go through the other's
// classifier.
template <int Dim>
bool Oracle<Dim>::Impl::regions_intersect(std::int32_t i, std::int32_t j, bool interiors) const {
  const Model& a = *shapes[i];
  const Model& b = *shapes[j];
  const double depth_tol = 1e-10 * std::min(box_diagonal(a.box()), box_diagonal(b.box()));
  if (const auto exact = a.regions_intersect(b, interiors, depth_tol)) return *exact;
  // Convex pair: min over directions of h_a(d) + h_b(−d) is the penetration depth (in 2D
  // this replaced boundary polylines of both, rebuilt per pair: 2.8 s of E2's 12,000 pits).
  const Shape &sa = scene.inclusions[i].shape, &sb = scene.inclusions[j].shape;
  if constexpr (Dim == 3) {
    if (a.convex() && b.convex()) return detail::overlap3(sa, sb, interiors ? -depth_tol : 0.0);
  } else {
    if (shape_family(sa).convex(sa) && shape_family(sb).convex(sb)) return shapes_overlap(sa, sb, interiors ? -depth_tol : 0.0);
  }
  auto boundary_samples = [&](std::int32_t k) {
    if constexpr (Dim == 2) return shapes[k]->boundary_polyline();
    else return shapes[k]->boundary_points(96);
  };
  const std::int32_t ks[2] = {i, j};
  for (int w = 0; w < 2; ++w) {
    const std::int32_t self = ks[w], other = ks[1 - w];
    for (const Point& q : boundary_samples(self)) {
      const int s = side(other, q);
      if (interiors ? (s > 0 && shapes[other]->boundary_distance(q) > depth_tol) : s >= 0) return true;
    }
  }
  if constexpr (Dim == 2) {
    if (interiors) {
      // Boundaries crossing each other without a sample inside: test chord midpoints.
      const std::vector<Vec2> pts = a.boundary_polyline();
      for (std::size_t q = 0; q < pts.size(); ++q) {
        const Vec2& u = pts[q];
        const Vec2& v = pts[(q + 1) % pts.size()];
        const Vec2 mid{0.5 * (u[0] + v[0]), 0.5 * (u[1] + v[1])};
        if (side(j, mid) > 0 && b.boundary_distance(mid) > depth_tol) return true;
      }
    }
  }
  return false;
}

// ---------------------------------------------------------------- public API
template <int Dim>
Oracle<Dim>::Oracle(const SceneDesc& scene) : impl_(std::make_unique<Impl>()) {
  // A periodic scene as listed: its geometry wraps, so the oracle holds the images too.
  if (scene.any_periodic() && !scene.images_expanded)
    impl_->validate_and_build(expand_periodic(scene, periodic_reach(scene)));
  else
    impl_->validate_and_build(scene);
}
template <int Dim>
Oracle<Dim>::~Oracle() = default;
template <int Dim>
Oracle<Dim>::Oracle(Oracle&&) noexcept = default;
template <int Dim>
Oracle<Dim>& Oracle<Dim>::operator=(Oracle&&) noexcept = default;

template <int Dim>
const SceneDesc& Oracle<Dim>::scene() const { return impl_->scene; }
template <int Dim>
int Oracle<Dim>::inclusion_count() const { return static_cast<int>(impl_->items.size()); }
template <int Dim>
int Oracle<Dim>::phase_count() const { return static_cast<int>(impl_->scene.phases.size()); }
template <int Dim>
int Oracle<Dim>::matrix_phase() const { return impl_->matrix; }
template <int Dim>
int Oracle<Dim>::phase_of(std::int32_t k) const { return impl_->items[k].phase; }
template <int Dim>
int Oracle<Dim>::levels_of(std::int32_t k) const { return impl_->items[k].levels; }
template <int Dim>
int Oracle<Dim>::interface_group(std::int32_t k) const { return impl_->items[k].group; }
template <int Dim>
Box<Dim> Oracle<Dim>::bounding_box(std::int32_t k) const { return impl_->boxes[k]; }

template <int Dim>
void Oracle<Dim>::candidates(const Box<Dim>& box, std::vector<std::int32_t>& out) const {
  impl_->index->query(box, out);
}

template <int Dim>
bool Oracle<Dim>::boundary_touches(std::int32_t k, const Box<Dim>& box_in) const {
  const Impl& m = *impl_;
  const Box<Dim>& own = m.boxes[k];
  const double slack = 1e-12 * std::max(box_diagonal(box_in), box_diagonal(own)) + 1e-300;
  Box<Dim> box = box_in;
  for (int d = 0; d < Dim; ++d) box.min[d] -= slack, box.max[d] += slack;
  if (!boxes_overlap(box, own)) return false;
  return m.shapes[k]->boundary_touches(box);
}

// ---------------------------------------------------------------- classification
template <int Dim>
PhaseMask Oracle<Dim>::closure_phases(const Point& p, std::span<const std::int32_t> cands) const {
  return impl_->closure_mask(p, cands);
}

template <int Dim>
PhaseMask Oracle<Dim>::Impl::closure_mask(const Point& p, std::span<const std::int32_t> cands) const {
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
  // On several boundaries and inside none (touching inclusions, shared polygon edges):
  // the matrix reaches p iff some nearby direction leaves every inclusion. Probe the
  // tangent directions of the curved boundaries at p (where tangent shapes leave a cusp
  // of matrix) and a fan of directions.
  double scale = std::numeric_limits<double>::infinity();
  for (std::int32_t k : cands) scale = std::min(scale, box_diagonal(boxes[k]));
  auto outside_all = [&](const Point& q) {
    for (std::int32_t k : cands)
      if (side(k, q) >= 0) return false;
    return true;
  };
  for (std::int32_t k : cands) {
    Point n{};
    if (!shapes[k]->outward_normal(p, n)) continue;
    if constexpr (Dim == 2) {
      const Vec2 tan{-n[1], n[0]};
      const double len = std::hypot(tan[0], tan[1]);
      if (!(len > 0)) continue;
      const double rho = 1e-6 * scale / len;
      if (outside_all({p[0] + rho * tan[0], p[1] + rho * tan[1]}) ||
          outside_all({p[0] - rho * tan[0], p[1] - rho * tan[1]}))
        return on | matrix_bit;
    } else {
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
  }
  if constexpr (Dim == 2) {
    const double rho = 1e-9 * scale;
    for (int dir = 0; dir < 32; ++dir) {
      const double ang = (dir + 0.5) * (2 * M_PI / 32);
      if (outside_all({p[0] + rho * std::cos(ang), p[1] + rho * std::sin(ang)})) return on | matrix_bit;
    }
  } else {
    const double rho = 1e-9 * scale;
    const int n = 128;
    const double golden = M_PI * (3 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
      const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(std::max(0.0, 1 - z * z));
      if (outside_all({p[0] + rho * r * std::cos(golden * i), p[1] + rho * r * std::sin(golden * i), p[2] + rho * z}))
        return on | matrix_bit;
    }
  }
  return on;
}

template <int Dim>
int Oracle<Dim>::phase_at(const Point& p, std::span<const std::int32_t> cands) const {
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

// The crossing sweep: every candidate's events sorted by (t, inclusion, order); the phase
// of a state is the phase of the lowest-index inclusion holding it; only phase changes
// are reported, then sub-intervals shorter than rounding are merged away. Everything here
// is per (a, b) and per inclusion, hence independent of extra candidates.
template <int Dim>
void Oracle<Dim>::crossings(const Point& a, const Point& b, std::span<const std::int32_t> cands,
                            std::vector<Crossing>& out) const {
  const Impl& m = *impl_;
  out.clear();
  if (a == b || cands.empty()) return;
  thread_local std::vector<SegmentEvent> events;
  thread_local std::vector<std::uint8_t> state;
  thread_local std::vector<double> scratch;
  events.clear();
  state.assign(cands.size(), 0);
  Box<Dim> seg;
  for (int d = 0; d < Dim; ++d) seg.min[d] = std::min(a[d], b[d]), seg.max[d] = std::max(a[d], b[d]);
  for (std::size_t i = 0; i < cands.size(); ++i) {
    const std::int32_t k = cands[i];
    if (!boxes_overlap(seg, m.boxes[k])) continue;  // a is outside the box, hence outside
    EventSink sink(events, k, static_cast<std::int32_t>(i));
    state[i] = m.shapes[k]->segment_events(a, b, seg, sink, scratch);
  }
  if (events.empty()) return;
  std::sort(events.begin(), events.end(), [](const SegmentEvent& x, const SegmentEvent& y) {
    if (x.t != y.t) return x.t < y.t;
    if (x.inclusion != y.inclusion) return x.inclusion < y.inclusion;
    return x.order < y.order;
  });
  int before = m.phase_of_states(cands, state);
  for (std::size_t i = 0; i < events.size();) {
    const double t = events[i].t;
    const std::int32_t first = events[i].inclusion;
    std::size_t j = i;
    for (; j < events.size() && events[j].t == t; ++j) state[events[j].slot] = events[j].inside_after;
    const int after = m.phase_of_states(cands, state);
    if (after != before) out.push_back({t, first, before, after});
    before = after;
    i = j;
  }
  // Sub-intervals shorter than rounding are not phases: merge or drop their ends.
  std::size_t w = 0;
  for (std::size_t r = 0; r < out.size(); ++r) {
    if (w > 0 && out[r].t - out[w - 1].t < kMergeT) {
      Crossing& prev = out[w - 1];
      if (prev.from_phase == out[r].to_phase) {
        --w;  // a vanishing excursion: no crossing at all
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

// ---------------------------------------------------------------- measures
// Inclusions alone in their interface group and inside the domain: their analytic
// measure. The rest: the phase lengths on lines parallel to the last axis (from
// `crossings`), integrated over the other axes between breakpoints (README: measures).
template <int Dim>
std::vector<double> Oracle<Dim>::phase_measures() const {
  const Impl& m = *impl_;
  const SceneDesc& sc = m.scene;
  Box<Dim> dom{};
  for (int d = 0; d < Dim; ++d) dom.min[d] = sc.domain_min[d], dom.max[d] = sc.domain_max[d];
  double dom_measure = 1;
  for (int d = 0; d < Dim; ++d) dom_measure *= dom.max[d] - dom.min[d];
  const std::size_t np = sc.phases.size();
  std::vector<double> meas(np, 0.0);
  std::vector<int> group_size(m.items.size(), 0);
  for (const auto& it : m.items) ++group_size[it.group];
  std::vector<std::int32_t> integrated;
  for (std::size_t k = 0; k < m.items.size(); ++k) {
    const Box<Dim>& box = m.boxes[k];
    bool inside_domain = true;
    for (int d = 0; d < Dim; ++d) inside_domain = inside_domain && box.min[d] >= dom.min[d] && box.max[d] <= dom.max[d];
    if (inside_domain && group_size[m.items[k].group] == 1) {
      meas[m.items[k].phase] += m.shapes[k]->measure();
      continue;
    }
    if (boxes_overlap(box, dom)) integrated.push_back(static_cast<std::int32_t>(k));
  }
  if (!integrated.empty()) {
    std::vector<double> xb{dom.min[0], dom.max[0]};
    for (std::int32_t k : integrated) {
      xb.push_back(m.boxes[k].min[0]);
      xb.push_back(m.boxes[k].max[0]);
      m.shapes[k]->x_breakpoints(xb);
    }
    if constexpr (Dim == 3)
      for (std::size_t i = 0; i < integrated.size(); ++i)
        for (std::size_t j = i + 1; j < integrated.size(); ++j)
          if (boxes_overlap(m.boxes[integrated[i]], m.boxes[integrated[j]]))
            m.shapes[integrated[i]]->pair_x_breakpoints(*m.shapes[integrated[j]], xb);
    for (double& x : xb) x = std::clamp(x, dom.min[0], dom.max[0]);
    std::sort(xb.begin(), xb.end());
    xb.erase(std::unique(xb.begin(), xb.end()), xb.end());
    std::vector<std::int32_t> cands, col;
    std::vector<Crossing> cr;
    // Length of each phase on the line through `at` along the last axis; the inclusions
    // whose box holds `at` in the other coordinates are taken from `from`.
    const double span = dom.max[Dim - 1] - dom.min[Dim - 1];
    auto line = [&](const Point& at, const std::vector<std::int32_t>& from, std::vector<double>& len) {
      len.assign(np, 0.0);
      cands.clear();
      for (std::int32_t k : from)
        if (m.boxes[k].min[Dim - 2] <= at[Dim - 2] && at[Dim - 2] <= m.boxes[k].max[Dim - 2]) cands.push_back(k);
      if (cands.empty()) return;
      Point a = at, b = at, mid = at;
      a[Dim - 1] = dom.min[Dim - 1];
      b[Dim - 1] = dom.max[Dim - 1];
      mid[Dim - 1] = 0.5 * (a[Dim - 1] + b[Dim - 1]);
      crossings(a, b, cands, cr);
      double t0 = 0;
      int ph = cr.empty() ? phase_at(mid, cands) : cr[0].from_phase;
      for (const Crossing& c : cr) {
        len[ph] += (c.t - t0) * span;
        t0 = c.t;
        ph = c.to_phase;
      }
      len[ph] += (1 - t0) * span;
    };
    // Surfaces whose points carry rounding beyond the analytic shapes' (NURBS: the chord
    // of a nearly tangent line moves by √(u·r)) cannot meet the 1e-13 tolerance near a
    // tangency; 1e-10 of the domain is far below what any mesh measure is compared with.
    double relax = 1;
    for (std::int32_t k : integrated)
      if (m.shapes[k]->approximate_sections()) relax = 1e3;
    if constexpr (Dim == 2) {
      const double tol = 1e-13 * relax * dom_measure;
      for (std::size_t i = 0; i + 1 < xb.size(); ++i)
        integrate(xb[i], xb[i + 1], np, tol, 40, [&](double x, std::vector<double>& len) { line({x, 0}, integrated, len); },
                  meas);
    } else {
      const double tol_inner = 1e-13 * relax * (dom.max[1] - dom.min[1]) * span;
      const double tol_outer = 1e-12 * relax * dom_measure;
      std::vector<double> yb;
      auto section = [&](double x, std::vector<double>& area) {
        area.assign(np, 0.0);
        col.clear();
        for (std::int32_t k : integrated)
          if (m.boxes[k].min[0] <= x && x <= m.boxes[k].max[0]) col.push_back(k);
        if (col.empty()) return;
        yb.assign({dom.min[1], dom.max[1]});
        for (std::int32_t k : col) {
          yb.push_back(m.boxes[k].min[1]);
          yb.push_back(m.boxes[k].max[1]);
          m.shapes[k]->y_breakpoints_at(x, yb);
        }
        for (std::size_t i = 0; i < col.size(); ++i)
          for (std::size_t j = i + 1; j < col.size(); ++j)
            if (boxes_overlap(m.boxes[col[i]], m.boxes[col[j]]))
              m.shapes[col[i]]->pair_y_breakpoints_at(*m.shapes[col[j]], x, yb);
        for (double& y : yb) y = std::clamp(y, dom.min[1], dom.max[1]);
        std::sort(yb.begin(), yb.end());
        yb.erase(std::unique(yb.begin(), yb.end()), yb.end());
        const std::vector<double> ys = yb;  // `section` is re-entered below; keep a copy
        for (std::size_t i = 0; i + 1 < ys.size(); ++i)
          integrate(ys[i], ys[i + 1], np, tol_inner, 30,
                    [&](double y, std::vector<double>& len) { line({x, y, 0}, col, len); }, area);
      };
      for (std::size_t i = 0; i + 1 < xb.size(); ++i) integrate(xb[i], xb[i + 1], np, tol_outer, 30, section, meas);
    }
  }
  double total = 0;
  for (std::size_t p = 0; p < np; ++p)
    if (static_cast<int>(p) != m.matrix) total += meas[p];
  meas[m.matrix] = dom_measure - total;
  return meas;
}

// ---------------------------------------------------------------- distances
template <int Dim>
double Oracle<Dim>::distance_to_phase(const Point& p, int phase_index) const {
  const Impl& m = *impl_;
  const std::int32_t n = static_cast<std::int32_t>(m.items.size());
  if (phase_index != m.matrix) {
    // Distance to a union is the minimum over its members.
    double best = std::numeric_limits<double>::infinity();
    for (std::int32_t k = 0; k < n; ++k) {
      if (m.items[k].phase != phase_index || box_distance(m.boxes[k], p) >= best) continue;
      if (m.side(k, p) >= 0) return 0;
      best = std::min(best, m.shapes[k]->boundary_distance(p));
    }
    return best;
  }
  // Matrix: 0 unless p is interior to some inclusion. Inside exactly one inclusion with
  // no other box nearer than its boundary: the distance to that boundary.
  if constexpr (Dim == 2) {
    std::vector<std::int32_t> inside;
    for (std::int32_t k = 0; k < n; ++k)
      if (m.side(k, p) > 0) inside.push_back(k);
    if (inside.size() == 1) {
      const double best = m.shapes[inside[0]]->boundary_distance(p);
      bool alone = true;
      for (std::int32_t k = 0; k < n && alone; ++k)
        if (k != inside[0] && box_distance(m.boxes[k], p) <= best * (1 + 1e-9)) alone = false;
      if (alone) return best;
    }
  } else {
    std::vector<std::int32_t> here;
    m.index->query(Box3{p, p}, here);
    std::int32_t inside = -1;
    int inside_count = 0;
    for (std::int32_t k : here)
      if (m.side(k, p) > 0) inside = k, ++inside_count;
    if (inside_count == 1) {
      const double d = m.shapes[inside]->boundary_distance(p);
      m.index->query(cube_around<3>(p, d * (1 + 1e-9)), here);
      if (here.size() == 1) return d;
    }
  }
  return m.matrix_distance(p);
}

// Distance from p to the matrix: 0 unless p is interior to an inclusion; then the
// distance to ∂U (U = union of the inclusions), minimal over candidate points that no
// inclusion but their owners covers: each boundary's nearest points, the points where
// two (3D: three) boundaries meet (README: distances).
template <int Dim>
double Oracle<Dim>::Impl::matrix_distance(const Point& p) const {
  std::vector<std::int32_t> near;
  index->query(Box<Dim>{p, p}, near);
  double lower = 0;
  bool inside_any = false, on_any = false;
  for (std::int32_t k : near) {
    const int s = side(k, p);
    if (s > 0) {
      inside_any = true;
      lower = std::max(lower, shapes[k]->boundary_distance(p));
    }
    on_any |= s == 0;
  }
  const PhaseMask matrix_bit = PhaseMask(1) << matrix;
  // ON boundaries only: 0 unless the matrix does not reach p (a shared polygon edge).
  if (!inside_any && (!on_any || (closure_mask(p, near) & matrix_bit))) return 0;
  std::vector<Point> pts;
  double reach = std::max(lower, 1e-300);
  for (;;) {
    // Slightly inflated: a candidate at distance ≤ reach must see every box holding it.
    index->query(cube_around<Dim>(p, reach * (1 + 1e-9)), near);
    double best = std::numeric_limits<double>::infinity();
    // Keep q when no inclusion other than its owners holds it; a q ON another one (shared
    // polygon edges, tangencies) is kept only if the matrix reaches it.
    auto consider = [&](const Point& q, std::int32_t k, std::int32_t j, std::int32_t l) {
      const double d = point_distance(q, p);
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
    for (std::int32_t k : near) {
      pts.clear();
      shapes[k]->nearest_boundary_points(p, pts);
      for (const Point& q : pts) consider(q, k, -1, -1);
    }
    for (std::size_t x = 0; x < near.size(); ++x)
      for (std::size_t y = x + 1; y < near.size(); ++y) {
        if constexpr (Dim == 2)
          if (!boxes_overlap(boxes[near[x]], boxes[near[y]])) continue;
        pts.clear();
        shapes[near[x]]->boundary_meetings(*shapes[near[y]], p, pts);
        for (const Point& q : pts) consider(q, near[x], near[y], -1);
        if constexpr (Dim == 3) {
          if (pts.empty()) continue;
          for (std::size_t z = y + 1; z < near.size(); ++z) {
            pts.clear();
            shapes[near[x]]->triple_meetings(*shapes[near[y]], *shapes[near[z]], pts);
            for (const Point& q : pts) consider(q, near[x], near[y], near[z]);
          }
        }
      }
    if (best <= reach || near.size() == items.size()) return best;
    reach = std::isfinite(best) ? best : 2 * reach;
  }
}

template class Oracle<2>;
template class Oracle<3>;

}  // namespace cisamr::geometry
