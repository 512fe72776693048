#pragma once
// Periodic masters across ranks (docs/periodic-design.md §3.3, §5): in a parallel run a
// rank's piece may hold a slave (a node on a periodic max face) without its master, which
// another rank holds. One rendezvous exchange resolves them, the merge's pattern
// (merge.cpp): every candidate master (a node on a periodic min face, on no max face) is
// sent with its global id to the rank its exact coordinate bits hash to; every slave asks
// that rank for the key of its full master (its coordinates with each max-face axis moved
// to the min face, mesh::periodic_key); the rendezvous answers. Matching is exact, as in
// mesh::periodic_links (see there why that is legitimate).
#include <array>
#include <vector>

#include "core/comm.hpp"
#include "core/types.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::parallel {

// Collective. Per node of this rank's `piece` (node_global_id set, or the node index),
// the global id of its full periodic master, or -1 for a node on no periodic max face.
// `faces`: the whole domain's face box (driver::face_box). A slave whose master no rank
// holds throws MeshingError naming the slave and its coordinates, on every rank; with
// `voids` (the scene has void phases) it gets -1 (a void across the period: no constraint,
// as mesh::periodic_links).
// Cost: one alltoallv of the nodes on periodic faces, and one of the answers.
template <int Dim>
std::vector<GlobalId> periodic_masters(const Comm& comm, const mesh::SimplexMesh<Dim>& piece, const Box<Dim>& faces,
                                       const std::array<bool, Dim>& axes, bool voids = false);

}  // namespace cisamr::parallel
