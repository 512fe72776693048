// Phase fidelity (DESIGN.md §2.3) of a 3D mesh against the scene's oracle: nodes in the
// closure of their cells' phases, centroids in (or near) their cell's phase, per-phase
// volumes against the oracle's exact or integrated ones (README.md, "Phase fidelity").
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include "geometry/oracle.hpp"
#include "mesh/metrics.hpp"
#include "quality/facet_table.hpp"
#include "quality/quality.hpp"

namespace cisamr::quality {
namespace {

constexpr std::size_t kMaxExamples = 24;
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string point_text(const Vec3& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.12g, %.12g, %.12g)", p[0], p[1], p[2]);
  return buf;
}

// The 26 directions to the neighbours of a cube in a 3×3×3 block, unit length.
std::array<Vec3, 26> probe_directions() {
  std::array<Vec3, 26> dirs{};
  std::size_t n = 0;
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      for (int k = -1; k <= 1; ++k) {
        if (i == 0 && j == 0 && k == 0) continue;
        const double len = std::sqrt(double(i * i + j * j + k * k));
        dirs[n++] = {i / len, j / len, k / len};
      }
  return dirs;
}

// Geometry questions of the check, with the candidate buffer reused.
class Probe {
 public:
  explicit Probe(const geometry::Oracle3& oracle) : oracle_(oracle), dirs_(probe_directions()) {}

  PhaseMask closure(const Vec3& p) {
    oracle_.candidates(Box3{p, p}, candidates_);
    return oracle_.closure_phases(p, candidates_);
  }

  // Distance from p to the closure of phase k, or an upper bound of it no larger than
  // `limit` when one can be proven (reported deviations are then such bounds): a point of
  // phase k at distance limit·{1e-6, 1e-3, 1} in one of 26 directions around p. These
  // probes come first: exact classifications are cheap, while the oracle's distance to a
  // cluster of ellipsoids, cylinders or STL surfaces comes from surface samples
  // (geometry/README.md: an upper bound, coarse and slow), and most questions (a snapped
  // node a rounding error off its surface, a centroid a sagitta across a curved interface)
  // are settled by a probe.
  double distance(const Vec3& p, int k, double limit) {
    const PhaseMask bit = PhaseMask(1) << k;
    if (limit > 0)
      for (double r : {1e-6 * limit, 1e-3 * limit, limit})
        for (const Vec3& u : dirs_) {
          const Vec3 q{p[0] + r * u[0], p[1] + r * u[1], p[2] + r * u[2]};
          if (closure(q) & bit) return r;  // an upper bound within the limit: settled
        }
    return oracle_.distance_to_phase(p, k);
  }

 private:
  const geometry::Oracle3& oracle_;
  std::array<Vec3, 26> dirs_;
  std::vector<std::int32_t> candidates_;
};

double longest_edge(const std::array<Vec3, 4>& v) {
  double l = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) l = std::max(l, mesh::distance<3>(v[i], v[j]));
  return l;
}

}  // namespace

FidelityReport check_fidelity(const mesh::Mesh3& m, const geometry::Oracle3& oracle, double tol,
                              std::span<const double> exact_volumes, double strict_tol) {
  const geometry::SceneDesc& scene = oracle.scene();
  FidelityReport r;
  r.tolerance = tol;
  const int phases = static_cast<int>(scene.phases.size());
  for (const geometry::Phase& p : scene.phases) {
    r.phase_id.push_back(p.id);
    r.phase_name.push_back(p.name);
    r.phase_is_void.push_back(p.is_void);
  }
  r.phase_measure.assign(phases, 0.0);
  if (exact_volumes.empty())
    r.exact_phase_measure = oracle.phase_measures();
  else
    r.exact_phase_measure.assign(exact_volumes.begin(), exact_volumes.end());
  r.exact_phase_measure.resize(phases, 0.0);
  r.relative_error.assign(phases, std::numeric_limits<double>::quiet_NaN());
  auto example = [&](std::string s) {
    if (r.examples.size() < kMaxExamples) r.examples.push_back(std::move(s));
  };
  Probe probe(oracle);

  // Phases around every node (bit = phase index), per-phase volume.
  const std::size_t nodes = m.node_count();
  const std::vector<bool> valid = detail::valid_cells(m);
  std::vector<PhaseMask> around(nodes, 0);
  std::vector<int> cell_phase_index(m.cell_count(), -1);
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    if (!valid[c]) continue;
    const int id = c < m.cell_phase.size() ? m.cell_phase[c] : 0;
    const int k = scene.phase_index(id);
    if (k < 0 || k >= 64 || scene.phases[std::size_t(k)].is_void) {
      ++r.cells_unknown_phase;
      if (r.cells_unknown_phase <= 3)
        example("cell " + std::to_string(c) + " has phase id " + std::to_string(id) +
                (k < 0 ? ", which the scene does not define" : ", a void phase (voids are not meshed)"));
      continue;
    }
    cell_phase_index[c] = k;
    const LocalId* cn = m.cell(c);
    r.phase_measure[std::size_t(k)] +=
        std::abs(mesh::signed_volume(m.point(cn[0]), m.point(cn[1]), m.point(cn[2]), m.point(cn[3])));
    for (int v = 0; v < 4; ++v) around[std::size_t(cn[v])] |= PhaseMask(1) << k;
  }
  for (int k = 0; k < phases; ++k) {
    if (scene.phases[std::size_t(k)].is_void) continue;
    const double exact = r.exact_phase_measure[std::size_t(k)], got = r.phase_measure[std::size_t(k)];
    r.relative_error[std::size_t(k)] = exact > 0 ? std::abs(got - exact) / exact : (got > 0 ? kInf : 0.0);
  }

  // Every node must lie in the closure of each phase it serves. The exact classification
  // settles almost every node; distances only for the phases its closure lacks. A node
  // counts as "on the interface" for the centroid check when its closure holds a phase
  // other than a cell's (or it serves several phases, or lies off one within tol).
  std::vector<PhaseMask> node_closure(nodes, 0);
  std::size_t shown_off_phase = 0, shown_off_interface = 0;
  for (std::size_t n = 0; n < nodes; ++n) {
    const PhaseMask mask = around[n];
    if (mask == 0) continue;
    const bool interface = (mask & (mask - 1)) != 0;
    const Vec3 p = m.point(LocalId(n));
    const PhaseMask closure = probe.closure(p);
    node_closure[n] = closure;
    if ((mask & ~closure) == 0) continue;
    double worst = 0;
    int worst_phase = -1;
    const bool strict = strict_tol >= 0 && strict_tol < tol;
    bool beyond_strict = false;
    for (int k = 0; k < phases && k < 64; ++k) {
      if (!(mask >> k & 1) || (closure >> k & 1)) continue;
      double d = probe.distance(p, k, strict ? strict_tol : tol);
      if (strict && !(d <= strict_tol)) {
        beyond_strict = true;
        if (!(d <= tol)) d = probe.distance(p, k, tol);  // the strict probes may not settle tol
      }
      if (!(d <= worst)) worst = d, worst_phase = k;  // NaN counts as off
    }
    r.nodes_beyond_strict += beyond_strict ? 1 : 0;
    if (std::isfinite(worst)) r.max_deviation = std::max(r.max_deviation, worst);
    if (worst <= tol) continue;
    char buf[96];
    std::snprintf(buf, sizeof buf, " is %.3g from phase %d", worst,
                  worst_phase >= 0 ? scene.phases[std::size_t(worst_phase)].id : -1);
    if (interface) {
      ++r.interface_nodes_off_interface;
      if (shown_off_interface++ < 3) example("interface node " + std::to_string(n) + " " + point_text(p) + buf);
    } else {
      ++r.nodes_off_phase;
      if (shown_off_phase++ < 3) example("node " + std::to_string(n) + " " + point_text(p) + buf);
    }
  }

  // Centroids: in the cell's phase, or within the slack of README.md (counted beyond it,
  // failed beyond kWrongPhaseRatio).
  std::size_t shown_cells = 0;
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    const int k = cell_phase_index[c];
    if (k < 0) continue;
    const LocalId* cn = m.cell(c);
    const std::array<Vec3, 4> v{m.point(cn[0]), m.point(cn[1]), m.point(cn[2]), m.point(cn[3])};
    const Vec3 g{(v[0][0] + v[1][0] + v[2][0] + v[3][0]) / 4, (v[0][1] + v[1][1] + v[2][1] + v[3][1]) / 4,
                 (v[0][2] + v[1][2] + v[2][2] + v[3][2]) / 4};
    const PhaseMask bit = PhaseMask(1) << k;
    if (probe.closure(g) & bit) continue;
    bool all_on_interface = true;
    for (int i = 0; i < 4; ++i) all_on_interface = all_on_interface && node_closure[std::size_t(cn[i])] != bit;
    const double l = longest_edge(v);
    const double allowed = std::max(tol, (all_on_interface ? kInterfaceCentroidSlack : kCentroidSlack) * l);
    const double d = probe.distance(g, k, allowed);
    if (l > 0 && std::isfinite(d)) r.max_centroid_ratio = std::max(r.max_centroid_ratio, d / l);
    if (d <= allowed) continue;
    ++r.cells_off_phase;
    const bool wrong = !(d <= std::max(tol, kWrongPhaseRatio * l));
    r.cells_wrong_phase += wrong ? 1 : 0;
    if (shown_cells++ < 3) {
      char buf[160];
      std::snprintf(buf, sizeof buf, " is %.3g (%.3g of its longest edge) from phase %d%s%s", d, l > 0 ? d / l : kInf,
                    scene.phases[std::size_t(k)].id, all_on_interface ? " (all its vertices on an interface)" : "",
                    wrong ? ": in another phase" : "");
      example("centroid " + point_text(g) + " of cell " + std::to_string(c) + buf);
    }
  }

  // Open facets inside the domain are void interfaces: their nodes must lie on a void.
  Box3 domain;
  for (int d = 0; d < 3; ++d) domain.min[d] = scene.domain_min[d], domain.max[d] = scene.domain_max[d];
  const std::vector<LocalId> boundary_nodes =
      detail::open_facet_nodes_inside_box<3>(m, domain, kOnBoxTolerance * box_diagonal(domain));
  std::size_t shown_off_void = 0;
  PhaseMask void_mask = 0;
  for (int k = 0; k < phases && k < 64; ++k)
    if (scene.phases[std::size_t(k)].is_void) void_mask |= PhaseMask(1) << k;
  for (LocalId n : boundary_nodes) {
    const Vec3 p = m.point(n);
    if (probe.closure(p) & void_mask) continue;
    double nearest = kInf;
    for (int k = 0; k < phases && k < 64; ++k)
      if (scene.phases[std::size_t(k)].is_void) nearest = std::min(nearest, probe.distance(p, k, tol));
    if (std::isfinite(nearest)) r.max_deviation = std::max(r.max_deviation, nearest);
    if (nearest <= tol) continue;
    ++r.boundary_nodes_off_void;
    if (shown_off_void++ < 3) {
      char buf[96];
      if (std::isfinite(nearest))
        std::snprintf(buf, sizeof buf, " is %.3g from the nearest void", nearest);
      else
        std::snprintf(buf, sizeof buf, " (the scene has no void)");
      example("node " + std::to_string(n) + " " + point_text(p) + " of an open facet inside the domain" + buf);
    }
  }

  r.ok = r.nodes_off_phase == 0 && r.interface_nodes_off_interface == 0 && r.boundary_nodes_off_void == 0 &&
         r.cells_unknown_phase == 0 && r.cells_wrong_phase == 0;
  return r;
}

}  // namespace cisamr::quality
