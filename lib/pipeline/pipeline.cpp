#include "pipeline/pipeline.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "pipeline/effective_levels.hpp"
#include "radapt/radapt2.hpp"
#include "samr/samr2.hpp"
#include "subdivide/subdivide2.hpp"

namespace cisamr::pipeline {

grid::Lattice2 make_lattice2(const geometry::Oracle2& oracle, const Options& options) {
  const auto& scene = oracle.scene();
  grid::Lattice2 lattice;
  lattice.h = scene.h;
  int levels = scene.levels;
  for (int k = 0; k < oracle.inclusion_count(); ++k) levels = std::max(levels, oracle.levels_of(k));
  lattice.max_level = levels + std::max(0, options.extra_levels);
  for (int d = 0; d < 2; ++d) {
    lattice.origin[d] = scene.domain_min[static_cast<std::size_t>(d)];
    const double cells = (scene.domain_max[static_cast<std::size_t>(d)] - scene.domain_min[static_cast<std::size_t>(d)]) / scene.h;
    lattice.coarse_cells[d] = static_cast<std::int64_t>(std::llround(cells));
    if (lattice.coarse_cells[d] < 1) throw InputError(scene.source, "mesh.h", "larger than the domain");
  }
  return lattice;
}

Result2 run2(const geometry::Oracle2& oracle, const grid::Lattice2& lattice, const grid::CellRange<2>& box,
             int ghost, const Options& options, int partition_id, std::span<const int> levels) {
  Result2 result;
  Stats& stats = result.stats;
  grid::CellRange<2> range = box;
  for (int d = 0; d < 2; ++d) {
    range.lo[d] = std::max<std::int64_t>(0, box.lo[d] - ghost);
    range.hi[d] = std::min<std::int64_t>(lattice.coarse_cells[d], box.hi[d] + ghost);
  }
  samr::RefinedGrid2 grid = [&] {
    ScopedPhase timer(&stats.times, "samr");
    return samr::refine2(oracle, lattice, range, levels);
  }();
  stats.coarse_cells = grid.forest.root_count();
  stats.refinements = grid.refinements;
  stats.leaves = static_cast<std::int64_t>(grid.forest.size()) - grid.refinements;

  radapt::Nodes2 nodes = [&] {
    ScopedPhase timer(&stats.times, "radapt");
    return radapt::snap2(oracle, grid, radapt::Options{options.alpha});
  }();
  stats.lattice_nodes = static_cast<std::int64_t>(nodes.key.size());
  stats.snapped_nodes = nodes.snapped_count;

  subdivide::Triangles2 tris = [&] {
    ScopedPhase timer(&stats.times, "subdivide");
    return subdivide::subdivide2(oracle, grid, nodes, box, options.alpha);
  }();
  stats.cut_quads = tris.cut_quads;
  stats.double_diagonal = tris.double_diagonal;
  stats.hanging_cells = tris.hanging_cells;
  stats.unresolved = tris.unresolved;
  stats.collapsed = tris.collapsed;
  stats.max_collapse_deviation = tris.max_collapse_deviation;
  stats.max_collapse_ratio = tris.max_collapse_ratio;
  stats.min_collapse_level = tris.collapsed ? tris.min_collapse_level : -1;
  stats.max_level = lattice.max_level;

  {
    ScopedPhase timer(&stats.times, "assemble");
    const auto& scene = oracle.scene();
    const std::size_t lattice_count = nodes.key.size();
    const std::size_t total = lattice_count + tris.extra_points.size();
    std::vector<std::int32_t> new_id(total, -1);
    mesh::Mesh2& m = result.mesh;
    const std::size_t ntri = tris.phase.size();
    m.cell_nodes.reserve(tris.triangles.size());
    m.cell_phase.reserve(ntri);
    std::int32_t next = 0;
    for (std::size_t t = 0; t < ntri; ++t) {
      const auto& phase = scene.phases[static_cast<std::size_t>(tris.phase[t])];
      if (phase.is_void) continue;
      for (int k = 0; k < 3; ++k) {
        std::int32_t& id = new_id[static_cast<std::size_t>(tris.triangles[3 * t + static_cast<std::size_t>(k)])];
        if (id < 0) id = next++;
        m.cell_nodes.push_back(id);
      }
      m.cell_phase.push_back(phase.id);
    }
    m.coords.resize(2 * static_cast<std::size_t>(next));
    result.node_key.resize(static_cast<std::size_t>(next));
    for (std::size_t n = 0; n < total; ++n) {
      const std::int32_t id = new_id[n];
      if (id < 0) continue;
      result.node_key[static_cast<std::size_t>(id)] = n < lattice_count ? nodes.key[n] : Result2::kInteriorNode;
      const Vec2& p = n < lattice_count ? nodes.position[n] : tris.extra_points[n - lattice_count];
      m.coords[2 * static_cast<std::size_t>(id)] = p[0];
      m.coords[2 * static_cast<std::size_t>(id) + 1] = p[1];
    }
    m.cell_partition.assign(m.cell_phase.size(), partition_id);
    m.node_global_id.resize(static_cast<std::size_t>(next));
    for (std::int32_t i = 0; i < next; ++i) m.node_global_id[static_cast<std::size_t>(i)] = i;
  }
  return result;
}

Result2 mesh2(const geometry::Oracle2& oracle, const Options& options) {
  const grid::Lattice2 lattice = make_lattice2(oracle, options);
  const std::vector<int> levels = effective_levels2(oracle.scene(), lattice);
  return run2(oracle, lattice, lattice.whole_domain(), 0, options, 0, levels);
}

}  // namespace cisamr::pipeline
