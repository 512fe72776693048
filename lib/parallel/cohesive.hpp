#pragma once
// Cohesive cells across partitions and periodic planes (docs/cohesive-design.md §1.3, §4):
// the exchanges around pipeline/cohesive.hpp's pure steps. Every partition splits its nodes
// and inserts its local cells; the facets on partition faces and periodic planes are paired
// at a rendezvous rank (hash of the facet's canonical key), whose decision goes back to the
// emitter; on a periodic mesh a second rendezvous (hash of the node's canonical identity)
// adds the masters no bulk cell made. Runs between the kernel and merge_and_number(...,
// cohesive = true), which then matches the copies by (identity, phase). Four alltoallv in
// all, of the facets and nodes on partition faces and periodic planes only.
#include <vector>

#include "core/comm.hpp"
#include "parallel/merge.hpp"

namespace cisamr::parallel {

// Collective. `parts`: this rank's partitions (their kernel results).
template <int Dim>
void join_cohesive(const Comm& comm, std::vector<PartitionOutput<Dim>>& parts, const grid::Lattice<Dim>& lattice);

}  // namespace cisamr::parallel
