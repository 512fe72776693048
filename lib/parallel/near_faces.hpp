#pragma once
// The 3D forest and decisions near faces, exchanged between partitions during the kernel
// (README.md, "Decisions exchanged near faces"). Each partition takes, for its cubes outside
// its box, the refinement of the partition whose box holds the cube, and for its nodes
// outside its closed box, what the partition of the lowest id whose closed box holds the
// node decided there on its own data. Answers are read before anything is overwritten.
#include <cstdint>
#include <span>
#include <vector>

#include "core/comm.hpp"
#include "grid/lattice.hpp"
#include "pipeline/staged3.hpp"

namespace cisamr::parallel {

// This rank's partitions in the kernel (every one of them, ascending ids).
struct SnappedPartition {
  int id = 0;                           // partition id
  bool asks = false;                    // GhostRegion::exchange: its windows count on the exchange
  std::int64_t second_pass_reach = -1;  // GhostRegion::second_pass_reach (fine lattice units)
  pipeline::Snapped3* snapped = nullptr;
};

// Collective, between pipeline::refine3_part and snap3_first: for every coarse cube of its
// forest's range outside its box, a partition that asks takes the refinement of the
// partition whose box holds the cube (which refined it as the whole run does). Returns per
// partition of `mine` what it took (samr::take_cube_refinements applies it); `cubes` counts
// them.
std::vector<std::vector<samr::CubeRefinement>> exchange_forests(const Comm& comm,
                                                                const std::vector<grid::CellRange<3>>& boxes,
                                                                std::span<SnappedPartition> mine, std::int64_t& cubes);

// Collective, between pipeline::snap3_first and snap3_second: the guard's first-pass
// refusals of the options of every node outside the closed box that a leaf of the second
// pass's window holds (the owner ran the first pass on every leaf around it). Returns the
// nodes this rank's partitions took.
std::int64_t exchange_first_pass_refusals(const Comm& comm, const grid::Lattice<3>& lattice,
                                          const std::vector<grid::CellRange<3>>& boxes, std::span<SnappedPartition> mine);

// Collective, between pipeline::snap3_second and finish3: every node outside the closed box
// takes its owner's final position, mask and state, and the finest level of the leaves
// around it (the owner holds all of them). Returns the nodes this rank's partitions took.
std::int64_t exchange_decisions(const Comm& comm, const grid::Lattice<3>& lattice,
                                const std::vector<grid::CellRange<3>>& boxes, std::span<SnappedPartition> mine);

}  // namespace cisamr::parallel
