// Phase fidelity (DESIGN.md §2.3) of a 2D or 3D mesh against the scene's oracle: nodes in
// the closure of their cells' phases, void-interface nodes on a void, (3D) centroids in or
// near their cell's phase, per-phase measures against the oracle's exact or integrated
// ones (README.md, "Phase fidelity").
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "quality/cell_geometry.hpp"
#include "quality/facet_table.hpp"
#include "quality/quality.hpp"
#include "quality/pieces_internal.hpp"
#include "quality/scene_queries.hpp"

namespace cisamr::quality {
namespace {

constexpr std::size_t kMaxExamples = 24;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Oracle3's distance to a cluster of ellipsoids, cylinders or STL surfaces comes from
// surface samples (geometry/README.md: an upper bound, coarse and slow), so 3D questions
// try exact classifications of nearby points first. Oracle2's distance is exact and is
// reported as found.
template <int Dim>
constexpr bool kProbeBeforeDistance = Dim == 3;

// The centroid check runs in 3D only: the 2D certificate (cisamr-certificate/1) has no
// centroid counters.
template <int Dim>
constexpr bool kCentroidCheck = Dim == 3;

template <int Dim>
std::string node_text(std::size_t n, const Vec<Dim>& p) {
  return std::to_string(n) + " " + detail::point_text<Dim>(p);
}

// The 3^Dim − 1 directions to the neighbours of a cell in a 3×…×3 block, unit length, the
// last axis varying fastest.
template <int Dim>
constexpr int kProbeDirections = Dim == 2 ? 8 : 26;  // 3^Dim − 1

template <int Dim>
std::array<Vec<Dim>, kProbeDirections<Dim>> probe_directions() {
  std::array<Vec<Dim>, kProbeDirections<Dim>> dirs{};
  std::size_t n = 0;
  for (int code = 0; code <= kProbeDirections<Dim>; ++code) {
    std::array<int, Dim> step;
    int squares = 0;
    for (int d = Dim - 1, rest = code; d >= 0; --d, rest /= 3) step[d] = rest % 3 - 1;
    for (int d = 0; d < Dim; ++d) squares += step[d] * step[d];
    if (squares == 0) continue;
    const double len = std::sqrt(double(squares));
    for (int d = 0; d < Dim; ++d) dirs[n][d] = step[d] / len;
    ++n;
  }
  return dirs;
}

// Geometry questions of the check, with the candidate buffer reused.
template <int Dim>
class Probe {
 public:
  explicit Probe(const geometry::Oracle<Dim>& oracle) : oracle_(oracle) {
    if constexpr (kProbeBeforeDistance<Dim>) dirs_ = probe_directions<Dim>();
  }

  PhaseMask closure(const Vec<Dim>& p) {
    oracle_.candidates(Box<Dim>{p, p}, candidates_);
    return oracle_.closure_phases(p, candidates_);
  }

  // Distance from p to the closure of phase k. In 3D, an upper bound of it no larger than
  // `limit` when one can be proven (reported deviations are then such bounds): a point of
  // phase k at distance limit·{1e-6, 1e-3, 1} in one of the probe directions around p.
  // Most questions (a snapped node a rounding error off its surface, a centroid a sagitta
  // across a curved interface) are settled by a probe.
  double distance(const Vec<Dim>& p, int k, double limit) {
    if constexpr (kProbeBeforeDistance<Dim>) {
      const PhaseMask bit = PhaseMask(1) << k;
      if (limit > 0)
        for (double r : {1e-6 * limit, 1e-3 * limit, limit})
          for (const Vec<Dim>& u : dirs_) {
            Vec<Dim> q;
            for (int d = 0; d < Dim; ++d) q[d] = p[d] + r * u[d];
            if (closure(q) & bit) return r;  // an upper bound within the limit: settled
          }
    }
    return oracle_.distance_to_phase(p, k);
  }

 private:
  const geometry::Oracle<Dim>& oracle_;
  std::array<Vec<Dim>, kProbeDirections<Dim>> dirs_{};
  std::vector<std::int32_t> candidates_;
};

template <int Dim>
void add_example(FidelityReport& r, std::string s) {
  if (r.examples.size() < kMaxExamples) r.examples.push_back(std::move(s));
}

// The checks of one node against the phases `mask` of its cells.
template <int Dim>
detail::NodeVerdict node_verdict(Probe<Dim>& probe, const geometry::SceneDesc& scene, const Vec<Dim>& p,
                                 PhaseMask mask, double tol, double strict_tol) {
  detail::NodeVerdict v;
  v.mask = mask;
  v.closure = probe.closure(p);
  if ((mask & ~v.closure) == 0) return v;
  const bool strict = strict_tol >= 0 && strict_tol < tol;
  const int phases = static_cast<int>(scene.phases.size());
  for (int k = 0; k < phases && k < 64; ++k) {
    if (!(mask >> k & 1) || (v.closure >> k & 1)) continue;
    double d = probe.distance(p, k, strict ? strict_tol : tol);
    if (strict && !(d <= strict_tol)) {
      v.beyond_strict = true;
      if (!(d <= tol)) d = probe.distance(p, k, tol);  // the strict probes may not settle tol
    }
    if (!(d <= v.worst)) v.worst = d, v.worst_phase = k;  // NaN counts as off
  }
  return v;
}

}  // namespace

namespace detail {

template <int Dim>
std::string point_text(const Vec<Dim>& p) {
  char buf[96];
  if constexpr (Dim == 2)
    std::snprintf(buf, sizeof buf, "(%.12g, %.12g)", p[0], p[1]);
  else
    std::snprintf(buf, sizeof buf, "(%.12g, %.12g, %.12g)", p[0], p[1], p[2]);
  return buf;
}

// Counts a node's verdict; `name` is how the examples name it ("17 (x, y)").
template <int Dim>
void count_node(FidelityReport& r, const geometry::SceneDesc& scene, const NodeVerdict& v, double tol,
                const std::string& name) {
  r.nodes_beyond_strict += v.beyond_strict ? 1 : 0;
  if (std::isfinite(v.worst)) r.max_deviation = std::max(r.max_deviation, v.worst);
  if (v.worst <= tol) return;
  char buf[96];
  std::snprintf(buf, sizeof buf, " is %.3g from phase %d", v.worst,
                v.worst_phase >= 0 ? scene.phases[std::size_t(v.worst_phase)].id : -1);
  if ((v.mask & (v.mask - 1)) != 0) {
    if (++r.interface_nodes_off_interface <= 3) add_example<Dim>(r, "interface node " + name + buf);
  } else {
    if (++r.nodes_off_phase <= 3) add_example<Dim>(r, "node " + name + buf);
  }
}

template <int Dim>
FidelityReport start_fidelity(const geometry::Oracle<Dim>& oracle, double tol, std::span<const double> exact_measures) {
  const geometry::SceneDesc& scene = oracle.scene();
  FidelityReport r;
  r.tolerance = tol;
  r.centroids_checked = kCentroidCheck<Dim>;
  const int phases = static_cast<int>(scene.phases.size());
  for (const geometry::Phase& p : scene.phases) {
    r.phase_id.push_back(p.id);
    r.phase_name.push_back(p.name);
    r.phase_is_void.push_back(p.is_void);
  }
  r.phase_measure.assign(phases, 0.0);
  if (exact_measures.empty())
    r.exact_phase_measure = oracle.phase_measures();
  else
    r.exact_phase_measure.assign(exact_measures.begin(), exact_measures.end());
  r.exact_phase_measure.resize(phases, 0.0);
  r.relative_error.assign(phases, std::numeric_limits<double>::quiet_NaN());
  return r;
}

template <int Dim>
void check_mesh_fidelity(const mesh::SimplexMesh<Dim>& m, const geometry::Oracle<Dim>& oracle, double tol,
                         double strict_tol, const std::vector<bool>* shared,
                         std::vector<std::pair<LocalId, NodeVerdict>>* shared_verdicts, FidelityReport& r) {
  const geometry::SceneDesc& scene = oracle.scene();
  Probe<Dim> probe(oracle);

  // Phases around every node (bit = phase index), per-phase measure.
  const std::size_t nodes = m.node_count();
  const std::vector<bool> valid = detail::valid_cells(m);
  std::vector<PhaseMask> around(nodes, 0);
  std::vector<int> cell_phase_index(m.cell_count(), -1);
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    if (!valid[c]) continue;
    const int id = c < m.cell_phase.size() ? m.cell_phase[c] : 0;
    const int k = scene.phase_index(id);
    if (k < 0 || k >= 64 || scene.phases[std::size_t(k)].is_void) {
      if (++r.cells_unknown_phase <= 3)
        add_example<Dim>(r, "cell " + std::to_string(c) + " has phase id " + std::to_string(id) +
                                (k < 0 ? ", which the scene does not define" : ", a void phase (voids are not meshed)"));
      continue;
    }
    cell_phase_index[c] = k;
    const LocalId* cn = m.cell(c);
    r.phase_measure[std::size_t(k)] += std::abs(detail::signed_measure(m, cn));
    for (int v = 0; v <= Dim; ++v) around[std::size_t(cn[v])] |= PhaseMask(1) << k;
  }

  // Every node must lie in the closure of each phase it serves. The exact classification
  // settles almost every node; distances (costly for NURBS, clusters and STL surfaces) only
  // for the phases its closure lacks. A node counts as "on the interface" for the centroid
  // check when its closure holds a phase other than a cell's (or it serves several phases,
  // or lies off one within tol). A node other pieces share is judged once its phases in
  // every piece are known (shared_verdicts).
  std::vector<PhaseMask> node_closure(nodes, 0);
  for (std::size_t n = 0; n < nodes; ++n) {
    if (around[n] == 0) continue;
    const Vec<Dim> p = m.point(LocalId(n));
    const NodeVerdict v = node_verdict<Dim>(probe, scene, p, around[n], tol, strict_tol);
    node_closure[n] = v.closure;
    if (shared && (*shared)[n])
      shared_verdicts->emplace_back(LocalId(n), v);
    else
      count_node<Dim>(r, scene, v, tol, node_text<Dim>(n, p));
  }

  // Centroids: in the cell's phase, or within the slack of README.md (counted beyond it,
  // failed beyond kWrongPhaseRatio).
  if constexpr (kCentroidCheck<Dim>) {
    for (std::size_t c = 0; c < m.cell_count(); ++c) {
      const int k = cell_phase_index[c];
      if (k < 0) continue;
      const LocalId* cn = m.cell(c);
      const Vec<Dim> g = detail::centroid(m, cn);
      const PhaseMask bit = PhaseMask(1) << k;
      if (probe.closure(g) & bit) continue;
      bool all_on_interface = true;
      for (int i = 0; i <= Dim; ++i) all_on_interface = all_on_interface && node_closure[std::size_t(cn[i])] != bit;
      const double l = detail::longest_edge(m, cn, Dim + 1);
      const double allowed = std::max(tol, (all_on_interface ? kInterfaceCentroidSlack : kCentroidSlack) * l);
      const double d = probe.distance(g, k, allowed);
      if (l > 0 && std::isfinite(d)) r.max_centroid_ratio = std::max(r.max_centroid_ratio, d / l);
      if (d <= allowed) continue;
      const bool wrong = !(d <= std::max(tol, kWrongPhaseRatio * l));
      r.cells_wrong_phase += wrong ? 1 : 0;
      if (++r.cells_off_phase <= 3) {
        char buf[160];
        std::snprintf(buf, sizeof buf, " is %.3g (%.3g of its longest edge) from phase %d%s%s", d,
                      l > 0 ? d / l : kInf, scene.phases[std::size_t(k)].id,
                      all_on_interface ? " (all its vertices on an interface)" : "", wrong ? ": in another phase" : "");
        add_example<Dim>(r, "centroid " + point_text<Dim>(g) + " of cell " + std::to_string(c) + buf);
      }
    }
  }
}

template <int Dim>
void check_void_boundary_nodes(const mesh::SimplexMesh<Dim>& m, std::span<const LocalId> boundary_nodes,
                               const geometry::Oracle<Dim>& oracle, double tol, FidelityReport& r) {
  const geometry::SceneDesc& scene = oracle.scene();
  const int phases = static_cast<int>(scene.phases.size());
  Probe<Dim> probe(oracle);
  const PhaseMask void_mask = geometry::void_phase_mask(scene);
  for (LocalId n : boundary_nodes) {
    const Vec<Dim> p = m.point(n);
    if (probe.closure(p) & void_mask) continue;
    double nearest = kInf;
    for (int k = 0; k < phases && k < 64; ++k)
      if (scene.phases[std::size_t(k)].is_void) nearest = std::min(nearest, probe.distance(p, k, tol));
    if (std::isfinite(nearest)) r.max_deviation = std::max(r.max_deviation, nearest);
    if (nearest <= tol) continue;
    if (++r.boundary_nodes_off_void <= 3) {
      char buf[96];
      if (std::isfinite(nearest))
        std::snprintf(buf, sizeof buf, " is %.3g from the nearest void", nearest);
      else
        std::snprintf(buf, sizeof buf, " (the scene has no void)");
      const std::size_t id = m.node_global_id.empty() ? std::size_t(n) : std::size_t(m.node_global_id[std::size_t(n)]);
      add_example<Dim>(r, "node " + node_text<Dim>(id, p) + " of an open facet inside the domain" + buf);
    }
  }
}

template <int Dim>
void finish_fidelity(const geometry::SceneDesc& scene, FidelityReport& r) {
  for (std::size_t k = 0; k < scene.phases.size(); ++k) {
    if (scene.phases[k].is_void) continue;
    const double exact = r.exact_phase_measure[k], got = r.phase_measure[k];
    r.relative_error[k] = exact > 0 ? std::abs(got - exact) / exact : (got > 0 ? kInf : 0.0);
  }
  r.ok = r.nodes_off_phase == 0 && r.interface_nodes_off_interface == 0 && r.boundary_nodes_off_void == 0 &&
         r.cells_unknown_phase == 0 && r.cells_wrong_phase == 0;
}

#define CISAMR_FIDELITY_PARTS(D)                                                                                     \
  template std::string point_text<D>(const Vec<D>&);                                                                 \
  template void count_node<D>(FidelityReport&, const geometry::SceneDesc&, const NodeVerdict&, double,               \
                              const std::string&);                                                                   \
  template FidelityReport start_fidelity<D>(const geometry::Oracle<D>&, double, std::span<const double>);            \
  template void check_mesh_fidelity<D>(const mesh::SimplexMesh<D>&, const geometry::Oracle<D>&, double, double,     \
                                       const std::vector<bool>*, std::vector<std::pair<LocalId, NodeVerdict>>*,      \
                                       FidelityReport&);                                                             \
  template void check_void_boundary_nodes<D>(const mesh::SimplexMesh<D>&, std::span<const LocalId>,                  \
                                             const geometry::Oracle<D>&, double, FidelityReport&);                   \
  template void finish_fidelity<D>(const geometry::SceneDesc&, FidelityReport&);
CISAMR_FIDELITY_PARTS(2)
CISAMR_FIDELITY_PARTS(3)
#undef CISAMR_FIDELITY_PARTS

}  // namespace detail

double default_fidelity_tolerance(const geometry::SceneDesc& scene) {
  double s = 0;
  for (int d = 0; d < scene.dimension; ++d) {
    const double e = scene.domain_max[d] - scene.domain_min[d];
    s += e * e;
  }
  return 1e-9 * std::sqrt(s);
}

template <int Dim>
FidelityReport check_fidelity(const mesh::SimplexMesh<Dim>& m, const geometry::Oracle<Dim>& oracle, double tol,
                              std::span<const double> exact_measures, double strict_tol) {
  FidelityReport r = detail::start_fidelity<Dim>(oracle, tol, exact_measures);
  detail::check_mesh_fidelity<Dim>(m, oracle, tol, strict_tol, nullptr, nullptr, r);
  // Open facets inside the domain are void interfaces: their nodes must lie on a void.
  const Box<Dim> domain = detail::scene_domain<Dim>(oracle.scene());
  const std::vector<LocalId> boundary_nodes =
      detail::open_facet_nodes_inside_box<Dim>(m, domain, kOnBoxTolerance * box_diagonal(domain));
  detail::check_void_boundary_nodes<Dim>(m, boundary_nodes, oracle, tol, r);
  detail::finish_fidelity<Dim>(oracle.scene(), r);
  return r;
}

template FidelityReport check_fidelity<2>(const mesh::SimplexMesh<2>&, const geometry::Oracle<2>&, double,
                                          std::span<const double>, double);
template FidelityReport check_fidelity<3>(const mesh::SimplexMesh<3>&, const geometry::Oracle<3>&, double,
                                          std::span<const double>, double);

}  // namespace cisamr::quality
