#include "pipeline/pipeline3.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <utility>

#include "core/error.hpp"
#include "pipeline/effective_levels.hpp"
#include "faceswap/faceswap3.hpp"
#include "radapt/radapt3.hpp"
#include "samr/samr3.hpp"
#include "subdivide/subdivide3.hpp"

namespace cisamr::pipeline {

grid::Lattice3 make_lattice3(const geometry::Oracle3& oracle, const Options& options) {
  const auto& scene = oracle.scene();
  grid::Lattice3 lattice;
  lattice.h = scene.h;
  int levels = scene.levels;
  for (int k = 0; k < oracle.inclusion_count(); ++k) levels = std::max(levels, oracle.levels_of(k));
  lattice.max_level = levels + std::max(0, options.extra_levels);
  for (int d = 0; d < 3; ++d) {
    lattice.origin[d] = scene.domain_min[static_cast<std::size_t>(d)];
    const double cells = (scene.domain_max[static_cast<std::size_t>(d)] - scene.domain_min[static_cast<std::size_t>(d)]) / scene.h;
    lattice.coarse_cells[d] = static_cast<std::int64_t>(std::llround(cells));
    if (lattice.coarse_cells[d] < 1) throw InputError(scene.source, "mesh.h", "larger than the domain");
  }
  grid::require_key3(lattice);
  return lattice;
}

namespace {

// Frees what `x` holds (clear() keeps the capacity).
template <class T>
void release(T& x) {
  T empty;
  std::swap(x, empty);
}

}  // namespace

Result3 run3(const geometry::Oracle3& oracle, const grid::Lattice3& lattice, const grid::CellRange<3>& box,
             int ghost, const Options& options, int partition_id, std::span<const int> levels) {
  Result3 result;
  Stats3& stats = result.stats;
  grid::CellRange<3> range = box;
  for (int d = 0; d < 3; ++d) {
    range.lo[d] = std::max<std::int64_t>(0, box.lo[d] - ghost);
    range.hi[d] = std::min<std::int64_t>(lattice.coarse_cells[d], box.hi[d] + ghost);
  }
  // Optional: released (reset) before assembly.
  std::optional<samr::RefinedGrid3> grid;
  {
    ScopedPhase timer(&stats.times, "samr");
    grid.emplace(samr::refine3(oracle, lattice, range, levels));
  }
  stats.coarse_cubes = range.count(0) * range.count(1) * range.count(2);
  stats.refinements = grid->refinements;
  stats.samr_sweeps = grid->sweeps;
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(grid->forest.size()); ++t)
    stats.leaves += grid->forest.is_leaf(t) ? 1 : 0;

  radapt::Nodes3 nodes = [&] {
    ScopedPhase timer(&stats.times, "radapt");
    return radapt::snap3(oracle, *grid,
                         radapt::Options3{.alpha = options.alpha, .alpha_diagonal = options.alpha_diagonal3,
                                          .max_candidates = options.max_candidates3,
                                          .bound = options.bound3});
  }();
  stats.lattice_nodes = static_cast<std::int64_t>(nodes.key.size());
  stats.snapped_nodes = nodes.snapped_count;
  stats.refused_nodes = nodes.refused_count;
  stats.collapsed_nodes = nodes.collapsed_count;
  stats.collapsed_cut_points = nodes.collapsed_cut_points;
  stats.max_collapse_deviation = nodes.max_collapse_deviation;
  stats.guarded_leaves = nodes.guarded_leaves;
  stats.guard_combinations = nodes.combinations;
  stats.missing_crossings = nodes.missing_crossings;

  faceswap::Swaps3 swaps = [&] {
    ScopedPhase timer(&stats.times, "faceswap");
    return faceswap::swap3(oracle, *grid, nodes, faceswap::Options3{.trigger = options.swap_trigger3});
  }();
  stats.face_swaps = swaps.swaps;

  subdivide::Tets3 tets = [&] {
    ScopedPhase timer(&stats.times, "subdivide");
    return subdivide::subdivide3(oracle, *grid, nodes, box, &swaps);
  }();
  stats.cut_tets = tets.cut_tets;
  stats.cut_nodes = tets.cut_nodes;
  stats.closed_tets = tets.closed_tets;
  stats.steiner_points = tets.steiner_points;
  stats.unresolved = tets.unresolved;
  stats.inverted = tets.inverted;
  stats.max_level = lattice.max_level;
  stats.worst_closure = tets.worst_closure;
  stats.worst_kept = tets.worst_kept;
  stats.worst_split = tets.worst_split;
  stats.worst_swapped = tets.worst_swapped;
  stats.kept_above_5 = tets.kept_above_5;
  stats.split_above_5 = tets.split_above_5;

  {
    ScopedPhase timer(&stats.times, "assemble");
    // The forest, the snapping state and the swaps are done with: released before the mesh
    // is built, so that they do not add to the peak (validation/paper3/README.md, memory).
    grid.reset();
    release(swaps);
    release(nodes.mask);
    release(nodes.state);
    release(nodes.finest_level);
    release(nodes.tet_nodes);
    release(nodes.registry);
    release(nodes.edges);
    release(nodes.edge_index);
    release(nodes.cut_leaf_slot);
    release(nodes.leaf_edges);
    const auto& scene = oracle.scene();
    const std::size_t lattice_count = nodes.key.size();
    const std::size_t total = lattice_count + tets.extra_points.size();
    std::vector<std::int32_t> new_id(total, -1);
    mesh::Mesh3& m = result.mesh;
    const std::size_t ntet = tets.phase.size();
    // Void tets dropped and nodes renumbered in place: the subdivision's arrays become the
    // mesh's (no second copy of the connectivity).
    std::size_t kept = 0;
    std::int32_t next = 0;
    for (std::size_t t = 0; t < ntet; ++t) {
      const auto& phase = scene.phases[static_cast<std::size_t>(tets.phase[t])];
      if (phase.is_void) continue;
      std::array<std::int32_t, 4> ids;
      for (int k = 0; k < 4; ++k) {
        std::int32_t& id = new_id[static_cast<std::size_t>(tets.tets[4 * t + static_cast<std::size_t>(k)])];
        if (id < 0) id = next++;
        ids[static_cast<std::size_t>(k)] = id;
      }
      std::copy(ids.begin(), ids.end(), tets.tets.begin() + static_cast<std::ptrdiff_t>(4 * kept));
      tets.phase[kept++] = phase.id;
    }
    tets.tets.resize(4 * kept);
    tets.phase.resize(kept);
    m.cell_nodes = std::move(tets.tets);
    m.cell_phase = std::move(tets.phase);
    m.coords.resize(3 * static_cast<std::size_t>(next));
    result.node_key.resize(static_cast<std::size_t>(next));
    result.node_identity.resize(static_cast<std::size_t>(next));
    for (std::size_t n = 0; n < total; ++n) {
      const std::int32_t id = new_id[n];
      if (id < 0) continue;
      result.node_key[static_cast<std::size_t>(id)] = n < lattice_count ? nodes.key[n] : Result3::kNotLatticeNode;
      result.node_identity[static_cast<std::size_t>(id)] =
          n < lattice_count ? std::array<std::uint64_t, 2>{nodes.key[n], nodes.key[n]}
                            : tets.extra_identity[n - lattice_count];
      const Vec3& p = n < lattice_count ? nodes.position[n] : tets.extra_points[n - lattice_count];
      for (int d = 0; d < 3; ++d) m.coords[3 * static_cast<std::size_t>(id) + static_cast<std::size_t>(d)] = p[d];
    }
    m.cell_partition.assign(m.cell_phase.size(), partition_id);
    m.node_global_id.resize(static_cast<std::size_t>(next));
    for (std::int32_t i = 0; i < next; ++i) m.node_global_id[static_cast<std::size_t>(i)] = i;
  }
  return result;
}

Result3 mesh3_with_stats(const geometry::Oracle3& oracle, const Options& options) {
  const grid::Lattice3 lattice = make_lattice3(oracle, options);
  // The levels the parallel mesher settles for every partition (effective_levels.hpp), so
  // that one process and any number of partitions mesh alike.
  const std::vector<int> levels =
      effective_levels3(oracle.scene(), lattice, {}, surface_unions(oracle.scene()));
  return run3(oracle, lattice, lattice.whole_domain(), 0, options, 0, levels);
}

mesh::Mesh3 mesh3(const geometry::Oracle3& oracle, const Options& options) {
  return std::move(mesh3_with_stats(oracle, options).mesh);
}

}  // namespace cisamr::pipeline
