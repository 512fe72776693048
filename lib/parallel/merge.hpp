#pragma once
// Merging the partitions' meshes by lattice key and numbering nodes globally (DESIGN.md §4).
//
// 2D needs one merge: every partition emits only the cells of its own box, all conforming
// across box faces (subdivision creates no edge nodes in 2D, and a coarse cell whose
// neighbour across the face is finer already closes over the hanging node, because its
// forest saw that neighbour in the ghost layer). Shared nodes and the one-sided hanging
// nodes of the paper are therefore both just lattice keys present in several partitions.
#include <cstdint>
#include <vector>

#include "core/comm.hpp"
#include "grid/lattice.hpp"
#include "mesh/simplex_mesh.hpp"
#include "pipeline/pipeline.hpp"

namespace cisamr::parallel {

struct PartitionOutput2 {
  int partition = 0;
  grid::CellRange<2> box;  // its coarse cells
  pipeline::Result2 result;
};

struct NumberedPiece2 {
  // This rank's cells (partition by partition, ascending); nodes: the ones it owns first,
  // then copies of nodes owned elsewhere. node_global_id set, cell_partition set.
  mesh::Mesh2 mesh;
  std::vector<std::uint64_t> node_key;  // lattice key, or Result2::kInteriorNode
  std::int64_t owned_nodes = 0;
  std::int64_t global_nodes = 0;
};

// Collective. `parts` must be this rank's partitions in ascending id order, and every
// rank's partitions must be a block of consecutive ids, ranks in ascending order (then the
// global ids do not depend on the number of ranks). Owner of a node: the lowest partition
// that emits it (= the lowest partition whose closed box holds it, unless that partition's
// cells there are all void). Global ids: owned nodes first, offset = exclusive scan of the
// owned counts, in (owner partition, kernel output order). Keys on partition faces are
// exchanged with a rendezvous rank (hash of the key), so corners shared by boxes that
// touch only diagonally need no special case. Throws std::logic_error (a bug, not bad
// input) when two partitions give the same key different coordinates.
NumberedPiece2 merge_and_number2(const Comm& comm, std::vector<PartitionOutput2>& parts,
                                 const grid::Lattice2& lattice);

// Collective. The whole mesh on `root` (nodes in global-id order, cells by partition),
// an empty mesh elsewhere. Checks that every copy of a node has the same coordinate bits
// (std::logic_error otherwise).
mesh::Mesh2 gather_mesh2(const Comm& comm, const NumberedPiece2& piece, int root = 0);

}  // namespace cisamr::parallel
