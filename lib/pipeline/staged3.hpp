#pragma once
// The 3D kernel in parts, for a parallel mesher that exchanges the forest and the decisions
// near its boxes' faces between them (lib/parallel/README.md, "Decisions exchanged near
// faces"): refine3_part runs SAMR, snap3_first r-adaptivity up to its guard's first pass,
// snap3_second the second pass and every node's decision, finish3 face swapping,
// subdivision and assembly. run<3> is the four in a row: the same code, the same mesh.
#include <memory>
#include <optional>
#include <span>

#include "pipeline/pipeline.hpp"
#include "radapt/radapt3.hpp"
#include "samr/samr3.hpp"

namespace cisamr::pipeline {

// What the kernel holds between its parts: the forest (with its cut lists after
// refine3_part: samr::take_cube_refinements), r-adaptivity between the guard's passes
// (after snap3_first) or every node's decision (after snap3_second), and the result
// so far (counters, stage times).
struct Snapped3 {
  std::unique_ptr<samr::RefinedGrid3> grid;  // on the heap: `snapping` refers to it
  std::optional<radapt::Snapping3> snapping;
  radapt::Nodes3 nodes;
  Result<3> result;
};

Snapped3 refine3_part(const geometry::Oracle3& oracle, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
                      const Ghost& ghost, const Options& options, std::span<const int> levels);
void snap3_first(const geometry::Oracle3& oracle, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
                 const Ghost& ghost, const Options& options, Snapped3& refined);
// refine3_part and snap3_first.
Snapped3 snap3_first(const geometry::Oracle3& oracle, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
                     const Ghost& ghost, const Options& options, std::span<const int> levels);
void snap3_second(Snapped3& snapped, const Options& options);
// Both.
Snapped3 snap3(const geometry::Oracle3& oracle, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
               const Ghost& ghost, const Options& options, std::span<const int> levels);

// Consumes `snapped` (its working state is released before assembly).
Result<3> finish3(const geometry::Oracle3& oracle, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
                  const Ghost& ghost, const Options& options, int partition_id, Snapped3&& snapped);

}  // namespace cisamr::pipeline
