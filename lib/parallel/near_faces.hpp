#pragma once
// The 3D decisions near faces, exchanged between partitions after r-adaptivity (README.md,
// "Decisions exchanged near faces").
#include <cstdint>
#include <span>
#include <vector>

#include "core/comm.hpp"
#include "grid/lattice.hpp"
#include "pipeline/staged3.hpp"

namespace cisamr::parallel {

// This rank's partitions between pipeline::snap3 and pipeline::finish3.
struct SnappedPartition {
  int id = 0;                   // partition id
  bool asks = false;            // GhostRegion::exchange: its windows count on the exchange
  pipeline::Snapped3* snapped;  // its forest and nodes
};

// Collective. Every asking partition takes the decision (final position, mask, state) of
// each of its nodes outside its closed box from the partition of the lowest id whose closed
// box holds the node, which decided it on its own data (its windows cover its closed box's
// nodes). Answers are read before any node is overwritten. `boxes`: every partition's box,
// by id; partitions are spread over the ranks as partitions_of_rank says. Returns the nodes
// this rank's partitions took.
std::int64_t exchange_near_faces(const Comm& comm, const grid::Lattice<3>& lattice,
                                 const std::vector<grid::CellRange<3>>& boxes, std::span<SnappedPartition> mine);

}  // namespace cisamr::parallel
