// Phase fidelity (DESIGN.md §2.3) of a 2D mesh against the scene's oracle.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "geometry/oracle.hpp"
#include "mesh/metrics.hpp"
#include "quality/facet_table.hpp"
#include "quality/quality.hpp"

namespace cisamr::quality {
namespace {

constexpr std::size_t kMaxExamples = 24;

std::string node_text(const mesh::Mesh2& m, std::size_t n) {
  char buf[80];
  std::snprintf(buf, sizeof buf, "%zu (%.12g, %.12g)", n, m.coords[2 * n], m.coords[2 * n + 1]);
  return buf;
}

}  // namespace

double default_fidelity_tolerance(const geometry::SceneDesc& scene) {
  double s = 0;
  for (int d = 0; d < scene.dimension; ++d) {
    const double e = scene.domain_max[d] - scene.domain_min[d];
    s += e * e;
  }
  return 1e-9 * std::sqrt(s);
}

FidelityReport check_fidelity(const mesh::Mesh2& m, const geometry::Oracle2& oracle, double tol) {
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
  r.exact_phase_measure = oracle.phase_measures();
  r.exact_phase_measure.resize(phases, 0.0);
  r.relative_error.assign(phases, std::numeric_limits<double>::quiet_NaN());
  auto example = [&](std::string s) {
    if (r.examples.size() < kMaxExamples) r.examples.push_back(std::move(s));
  };

  // Phases around every node (bit = phase index), per-phase measure.
  const std::size_t nodes = m.node_count();
  const std::vector<bool> valid = detail::valid_cells(m);
  std::vector<PhaseMask> around(nodes, 0);
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
    const LocalId* cn = m.cell(c);
    r.phase_measure[std::size_t(k)] += std::abs(mesh::signed_area(m.point(cn[0]), m.point(cn[1]), m.point(cn[2])));
    for (int v = 0; v < 3; ++v) around[std::size_t(cn[v])] |= PhaseMask(1) << k;
  }
  for (int k = 0; k < phases; ++k) {
    if (scene.phases[std::size_t(k)].is_void) continue;
    const double exact = r.exact_phase_measure[std::size_t(k)], got = r.phase_measure[std::size_t(k)];
    r.relative_error[std::size_t(k)] =
        exact > 0 ? std::abs(got - exact) / exact : (got > 0 ? std::numeric_limits<double>::infinity() : 0.0);
  }

  // Every node must lie in the closure of each phase it touches.
  // The exact classification settles almost every node; distances (costly for NURBS) are
  // computed only for the phases a node's closure does not contain.
  std::size_t shown_off_phase = 0, shown_off_interface = 0;
  std::vector<std::int32_t> candidates;
  for (std::size_t n = 0; n < nodes; ++n) {
    const PhaseMask mask = around[n];
    if (mask == 0) continue;
    const bool interface = (mask & (mask - 1)) != 0;
    const Vec2 p = m.point(LocalId(n));
    oracle.candidates(Box2{p, p}, candidates);
    const PhaseMask closure = oracle.closure_phases(p, candidates);
    if ((mask & ~closure) == 0) continue;
    double worst = 0;
    int worst_phase = -1;
    for (int k = 0; k < phases && k < 64; ++k) {
      if (!(mask >> k & 1) || (closure >> k & 1)) continue;
      const double d = oracle.distance_to_phase(p, k);
      if (!(d <= worst)) worst = d, worst_phase = k;  // NaN counts as off
    }
    if (std::isfinite(worst)) r.max_deviation = std::max(r.max_deviation, worst);
    if (worst <= tol) continue;
    char buf[96];
    std::snprintf(buf, sizeof buf, " is %.3g from phase %d", worst,
                  worst_phase >= 0 ? scene.phases[std::size_t(worst_phase)].id : -1);
    if (interface) {
      ++r.interface_nodes_off_interface;
      if (shown_off_interface++ < 3) example("interface node " + node_text(m, n) + buf);
    } else {
      ++r.nodes_off_phase;
      if (shown_off_phase++ < 3) example("node " + node_text(m, n) + buf);
    }
  }

  // Open facets inside the domain are void interfaces: their nodes must lie on a void.
  Box2 domain;
  domain.min = {scene.domain_min[0], scene.domain_min[1]};
  domain.max = {scene.domain_max[0], scene.domain_max[1]};
  const std::vector<LocalId> boundary_nodes =
      detail::open_facet_nodes_inside_box<2>(m, domain, kOnBoxTolerance * box_diagonal(domain));
  std::size_t shown_off_void = 0;
  PhaseMask void_mask = 0;
  for (int k = 0; k < phases && k < 64; ++k)
    if (scene.phases[std::size_t(k)].is_void) void_mask |= PhaseMask(1) << k;
  for (LocalId n : boundary_nodes) {
    const Vec2 p = m.point(n);
    oracle.candidates(Box2{p, p}, candidates);
    if (oracle.closure_phases(p, candidates) & void_mask) continue;
    double nearest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < phases; ++k)
      if (scene.phases[std::size_t(k)].is_void) nearest = std::min(nearest, oracle.distance_to_phase(m.point(n), k));
    if (std::isfinite(nearest)) r.max_deviation = std::max(r.max_deviation, nearest);
    if (nearest <= tol) continue;
    ++r.boundary_nodes_off_void;
    if (shown_off_void++ < 3) {
      char buf[96];
      if (std::isfinite(nearest))
        std::snprintf(buf, sizeof buf, " is %.3g from the nearest void", nearest);
      else
        std::snprintf(buf, sizeof buf, " (the scene has no void)");
      example("node " + node_text(m, std::size_t(n)) + " of an open facet inside the domain" + buf);
    }
  }

  r.ok = r.nodes_off_phase == 0 && r.interface_nodes_off_interface == 0 &&
         r.boundary_nodes_off_void == 0 && r.cells_unknown_phase == 0;
  return r;
}

}  // namespace cisamr::quality
