#pragma once
// The 3D kernel in two halves, for a parallel mesher that exchanges the decisions near its
// boxes' faces between them (lib/parallel/README.md, "Ghost region (3D)", exchange):
// snap3 runs SAMR and r-adaptivity, finish3 face swapping, subdivision and assembly. run<3>
// is finish3(snap3(...)): the same code, the same mesh.
#include <span>

#include "pipeline/pipeline.hpp"
#include "radapt/radapt3.hpp"
#include "samr/samr3.hpp"

namespace cisamr::pipeline {

// What the kernel holds between r-adaptivity and face swapping: the forest, every node's
// decision (final position, mask, state) and the result so far (counters, stage times).
struct Snapped3 {
  samr::RefinedGrid3 grid;
  radapt::Nodes3 nodes;
  Result<3> result;
};

Snapped3 snap3(const geometry::Oracle3& oracle, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
               const Ghost& ghost, const Options& options, std::span<const int> levels);

// Consumes `snapped` (its working state is released before assembly).
Result<3> finish3(const geometry::Oracle3& oracle, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
                  const Ghost& ghost, const Options& options, int partition_id, Snapped3&& snapped);

}  // namespace cisamr::pipeline
