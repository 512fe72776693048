// The 3D kernel: SAMR → r-adaptivity with the quality guard → face swapping →
// subdivision, then the shared assembly.
#include <chrono>

#include "core/memory.hpp"
#include "faceswap/faceswap3.hpp"
#include "pipeline/assembly.hpp"
#include "pipeline/staged3.hpp"
#include "subdivide/subdivide3.hpp"

namespace cisamr::pipeline {
namespace {

// SAMR; its time added to `result`. The forest keeps its cut lists (take_cube_refinements).
Snapped3 refine_stage(const geometry::Oracle3& oracle, const grid::Lattice3& lattice, const grid::CellRange<3>& box,
                      const Ghost& ghost, const Options& options, std::span<const int> levels, Result<3> result) {
  const grid::CellRange<3> range = ghosted_range(lattice, box, ghost.sides);
  // On the heap: r-adaptivity's state refers to it while a Snapped3 moves.
  auto grid = [&] {
    ScopedPhase timer(&result.times, "samr");
    return std::make_unique<samr::RefinedGrid3>(samr::refine3(oracle, lattice, range, levels, options.progress));
  }();
  return Snapped3{std::move(grid), std::nullopt, {}, std::move(result)};
}

// r-adaptivity up to its guard's first pass on the refined forest; SAMR's counters and
// r-adaptivity's time added to the result.
void snap_first_half(const geometry::Oracle3& oracle, const grid::Lattice3& lattice, const grid::CellRange<3>& box,
                     const Ghost& ghost, const Options& options, Snapped3& snapped) {
  const auto window = [&](std::int64_t reach) { return grid::LeafWindow::around(lattice, box, reach); };
  samr::RefinedGrid3& grid = *snapped.grid;
  // After each stage: what it freed goes back to the system (hash-map nodes would stay
  // resident in the heap, under the next stage's arrays), and the forest keeps only what
  // the later stages read (validation/bench/MEMORY.md).
  grid.release_lists();
  release_free_memory();
  Counters<3>& counters = snapped.result.counters;
  const grid::CellRange<3>& range = grid.forest.range();
  counters.coarse_cells = range.count(0) * range.count(1) * range.count(2);
  counters.refinements = grid.refinements;
  counters.samr_sweeps = grid.sweeps;
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(grid.forest.size()); ++t)
    counters.leaves += grid.forest.is_leaf(t) ? 1 : 0;
  {
    ScopedPhase timer(&snapped.result.times, "radapt");
    snapped.snapping.emplace(oracle, *snapped.grid,
                             radapt::Options3{.alpha = options.alpha, .alpha_diagonal = options.alpha_diagonal3,
                                              .max_candidates = options.max_candidates3,
                                              .bound = options.bound3,
                                              .window = window(ghost.radapt_reach),
                                              .first_pass_window = window(ghost.first_pass_reach),
                                              .second_pass_window = window(ghost.second_pass_reach),
                                              .progress = options.progress});
  }
}

// The guard's second pass and every node's decision.
void snap_second_half(Snapped3& snapped) {
  {
    // The radapt phase goes on (its progress was told when it began in the first half).
    const auto start = std::chrono::steady_clock::now();
    snapped.nodes = snapped.snapping->finish();
    snapped.result.times.add("radapt", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  snapped.snapping.reset();
  release_free_memory();
  const radapt::Nodes3& nodes = snapped.nodes;
  Counters<3>& counters = snapped.result.counters;
  counters.lattice_nodes = static_cast<std::int64_t>(nodes.key.size());
  counters.snapped_nodes = nodes.snapped_count;
  counters.refused_nodes = nodes.refused_count;
  counters.collapsed_nodes = nodes.collapsed_count;
  counters.collapsed_cut_points = nodes.collapsed_cut_points;
  counters.max_collapse_deviation = nodes.max_collapse_deviation;
  counters.snapping_leaves = nodes.window_leaves;
  counters.guarded_leaves = nodes.guarded_leaves;
  counters.guard_combinations = nodes.combinations;
  counters.missing_crossings = nodes.missing_crossings;
}

// Face swapping and subdivision; returns what the mesh is made of. The working state (the
// forest, the snapping state, the swaps) is released on return, before the mesh is built,
// so that it does not add to the peak (validation/paper3/README.md, memory).
MeshParts<3> finish_stages(const geometry::Oracle3& oracle, const grid::Lattice3& lattice, const grid::CellRange<3>& box,
                           const Ghost& ghost, const Options& options, std::unique_ptr<samr::RefinedGrid3> owned_grid,
                           radapt::Nodes3 nodes, Result<3>& result) {
  Counters<3>& counters = result.counters;
  const samr::RefinedGrid3& grid = *owned_grid;
  const faceswap::Swaps3 swaps = [&] {
    ScopedPhase timer(&result.times, "faceswap");
    return faceswap::swap3(oracle, grid, nodes, faceswap::Options3{.trigger = options.swap_trigger3,
                                                                      .window = grid::LeafWindow::around(lattice, box, ghost.swap_reach),
                                                                      .progress = options.progress});
  }();
  release_free_memory();
  counters.face_swaps = swaps.swaps;

  subdivide::Tets3 tets = [&] {
    ScopedPhase timer(&result.times, "subdivide");
    return subdivide::subdivide3(oracle, grid, nodes, box, &swaps, options.progress);
  }();
  counters.cut_tets = tets.cut_tets;
  counters.cut_nodes = tets.cut_nodes;
  counters.closed_tets = tets.closed_tets;
  counters.steiner_points = tets.steiner_points;
  counters.unresolved = tets.unresolved;
  counters.inverted = tets.inverted;
  counters.max_level = lattice.max_level;
  counters.worst_closure = tets.worst_closure;
  counters.worst_kept = tets.worst_kept;
  counters.worst_split = tets.worst_split;
  counters.worst_swapped = tets.worst_swapped;
  counters.kept_above_5 = tets.kept_above_5;
  counters.split_above_5 = tets.split_above_5;
  return {std::move(nodes.key),  std::move(nodes.position), std::move(tets.extra_points),
          std::move(tets.extra_identity), std::move(tets.tets), std::move(tets.phase)};
}

}  // namespace

MeshParts<3> run_stages(const geometry::Oracle3& oracle, const grid::Lattice3& lattice, const grid::CellRange<3>& box,
                        const Ghost& ghost, const Options& options, std::span<const int> levels, Result<3>& result) {
  Snapped3 snapped = refine_stage(oracle, lattice, box, ghost, options, levels, std::move(result));
  snap_first_half(oracle, lattice, box, ghost, options, snapped);
  snap_second_half(snapped);
  result = std::move(snapped.result);
  return finish_stages(oracle, lattice, box, ghost, options, std::move(snapped.grid), std::move(snapped.nodes), result);
}

Snapped3 refine3_part(const geometry::Oracle3& oracle, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
                      const Ghost& ghost, const Options& options, std::span<const int> levels) {
  Result<3> result;
  result.times.progress = options.progress;
  return refine_stage(oracle, lattice, box, ghost, options, levels, std::move(result));
}

void snap3_first(const geometry::Oracle3& oracle, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
                 const Ghost& ghost, const Options& options, Snapped3& refined) {
  refined.result.times.progress = options.progress;
  snap_first_half(oracle, lattice, box, ghost, options, refined);
}

Snapped3 snap3_first(const geometry::Oracle3& oracle, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
                     const Ghost& ghost, const Options& options, std::span<const int> levels) {
  Snapped3 snapped = refine3_part(oracle, lattice, box, ghost, options, levels);
  snap3_first(oracle, lattice, box, ghost, options, snapped);
  return snapped;
}

void snap3_second(Snapped3& snapped, const Options& options) {
  snapped.result.times.progress = options.progress;
  snap_second_half(snapped);
}

Snapped3 snap3(const geometry::Oracle3& oracle, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
               const Ghost& ghost, const Options& options, std::span<const int> levels) {
  Snapped3 snapped = snap3_first(oracle, lattice, box, ghost, options, levels);
  snap3_second(snapped, options);
  return snapped;
}

Result<3> finish3(const geometry::Oracle3& oracle, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
                  const Ghost& ghost, const Options& options, int partition_id, Snapped3&& snapped) {
  Result<3> result = std::move(snapped.result);
  result.times.progress = options.progress;
  MeshParts<3> parts =
      finish_stages(oracle, lattice, box, ghost, options, std::move(snapped.grid), std::move(snapped.nodes), result);
  {
    ScopedPhase timer(&result.times, "assemble");
    assemble(oracle.scene(), std::move(parts), partition_id, result);
  }
  return result;
}

}  // namespace cisamr::pipeline
