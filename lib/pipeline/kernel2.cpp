// The 2D kernel: SAMR → r-adaptivity → subdivision, then the shared assembly.
#include "core/memory.hpp"
#include "pipeline/assembly.hpp"
#include "radapt/radapt2.hpp"
#include "samr/samr2.hpp"
#include "subdivide/subdivide2.hpp"

namespace cisamr::pipeline {

// Runs the stages and returns what the mesh is made of; their working state (the forest,
// the node table's masks and registry) is released on return, before assembly.
MeshParts<2> run_stages(const geometry::Oracle2& oracle, const grid::Lattice2& lattice, const grid::CellRange<2>& box,
                        const Ghost& ghost, const Options& options, std::span<const int> levels, Result<2>& result) {
  Counters<2>& counters = result.counters;
  samr::RefinedGrid2 grid = [&] {
    ScopedPhase timer(&result.times, "samr");
    return samr::refine2(oracle, lattice, ghosted_range(lattice, box, ghost.sides), levels, options.progress);
  }();
  // As in 3D (kernel3.cpp): freed working state back to the system after each stage.
  grid.release_lists();
  release_free_memory();
  counters.coarse_cells = grid.forest.root_count();
  counters.refinements = grid.refinements;
  counters.leaves = static_cast<std::int64_t>(grid.forest.size()) - grid.refinements;

  radapt::Nodes2 nodes = [&] {
    ScopedPhase timer(&result.times, "radapt");
    return radapt::snap2(oracle, grid, radapt::Options{.alpha = options.alpha, .progress = options.progress});
  }();
  release_free_memory();
  counters.lattice_nodes = static_cast<std::int64_t>(nodes.key.size());
  counters.snapped_nodes = nodes.snapped_count;

  subdivide::Triangles2 tris = [&] {
    ScopedPhase timer(&result.times, "subdivide");
    return subdivide::subdivide2(oracle, grid, nodes, box, options.alpha, options.progress);
  }();
  counters.cut_quads = tris.cut_quads;
  counters.double_diagonal = tris.double_diagonal;
  counters.hanging_cells = tris.hanging_cells;
  counters.unresolved = tris.unresolved;
  counters.collapsed = tris.collapsed;
  counters.max_collapse_deviation = tris.max_collapse_deviation;
  counters.max_collapse_ratio = tris.max_collapse_ratio;
  counters.min_collapse_level = tris.collapsed ? tris.min_collapse_level : -1;
  counters.max_level = lattice.max_level;
  static_assert(subdivide::Triangles2::kNoKey == Result<2>::kUnshared);
  return {std::move(nodes.key),          std::move(nodes.position), std::move(tris.extra_points),
          std::move(tris.extra_identity), std::move(tris.triangles),     std::move(tris.phase)};
}

}  // namespace cisamr::pipeline
