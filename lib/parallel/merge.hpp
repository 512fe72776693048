#pragma once
// Merging the partitions' meshes by lattice identity and numbering nodes globally
// (DESIGN.md §4). One template for 2D and 3D.
//
// 2D needs one merge: every partition emits only the cells of its own box, all conforming
// across box faces (subdivision creates no edge nodes in 2D, and a coarse cell whose
// neighbour across the face is finer already closes over the hanging node, because its
// forest saw that neighbour in the ghost layer). Shared nodes and the one-sided hanging
// nodes of the paper are therefore both just lattice keys present in several partitions.
//
// 3D adds the paper's second merge, the interface nodes that subdivision creates on cut
// edges: a node's identity is a pair, (key, key) for a lattice node, (smaller key, larger
// key) of its edge for a cut node, (~0, ~0) for a closure Steiner point (interior to one
// leaf, never shared: numbered without merging). Both merges are then one exchange of
// identities on partition faces.
#include <array>
#include <cstdint>
#include <vector>

#include "core/comm.hpp"
#include "grid/lattice.hpp"
#include "mesh/simplex_mesh.hpp"
#include "pipeline/pipeline.hpp"

namespace cisamr::parallel {

template <int Dim>
struct PartitionOutput {
  int partition = 0;
  grid::CellRange<Dim> box;  // its coarse cells
  pipeline::Result<Dim> result;
};
using PartitionOutput2 = PartitionOutput<2>;
using PartitionOutput3 = PartitionOutput<3>;

template <int Dim>
struct NumberedPiece {
  // This rank's cells (partition by partition, ascending); nodes: the ones it owns first,
  // then copies of nodes owned elsewhere. node_global_id set, cell_partition set.
  mesh::SimplexMesh<Dim> mesh;
  std::vector<pipeline::NodeIdentity<Dim>> node_key;  // per node, its merge identity
  std::int64_t owned_nodes = 0;
  std::int64_t global_nodes = 0;
};
using NumberedPiece2 = NumberedPiece<2>;
using NumberedPiece3 = NumberedPiece<3>;

// Collective. `parts` must be this rank's partitions in ascending id order, and every
// rank's partitions must be a block of consecutive ids, ranks in ascending order (then the
// global ids do not depend on the number of ranks). Owner of a node: the lowest partition
// that emits it (= the lowest partition whose closed box holds it, unless that partition's
// cells there are all void). Global ids: owned nodes first, offset = exclusive scan of the
// owned counts, in (owner partition, kernel output order). Identities on partition faces
// are exchanged with a rendezvous rank (hash of the identity), so corners shared by boxes
// that touch only diagonally need no special case. Only identities on an inner face of
// their partition's box are looked up (two boxes share no other point): throws
// std::logic_error (a bug, not bad input) when two partitions give such an identity
// different coordinates, or a rank's first partition emits one twice. Empties the
// kernel results as it goes. `cohesive` (the same on every rank): the partitions' nodes are
// copies named (identity, node_phase), merged by that pair; their cohesive cells are carried
// and node_phase is set.
template <int Dim>
NumberedPiece<Dim> merge_and_number(const Comm& comm, std::vector<PartitionOutput<Dim>>& parts,
                                    const grid::Lattice<Dim>& lattice, bool cohesive = false);
inline NumberedPiece2 merge_and_number2(const Comm& comm, std::vector<PartitionOutput2>& parts,
                                        const grid::Lattice2& lattice) {
  return merge_and_number<2>(comm, parts, lattice);
}

// Streamed output (stream.hpp): what a rank keeps of each of its partitions once their cells
// are spooled, and the global ids merge_and_number would give their nodes.
template <int Dim>
struct PartitionFaces {
  int partition = 0;
  std::int64_t nodes = 0;
  std::vector<std::int32_t> local;                    // nodes on an inner face of its box, ascending
  std::vector<pipeline::NodeIdentity<Dim>> identity;  // their identities
};
// The nodes of `part` that other partitions may emit too (merge_and_number's face test).
template <int Dim>
PartitionFaces<Dim> partition_faces(const PartitionOutput<Dim>& part, const grid::Lattice<Dim>& lattice);

// Collective. `parts`: this rank's partitions, ascending, every rank's a block of consecutive
// ids, ranks in ascending order (as merge_and_number). Returns, per partition of `parts`,
// the global id of each of its nodes: exactly those merge_and_number gives the merged nodes
// (owner: the lowest partition emitting a node; owned nodes numbered in (partition, local)
// order). Only face identities travel; `global_nodes` is set to the mesh's node count.
template <int Dim>
std::vector<GlobalId> global_ids_of(const PartitionFaces<Dim>& part, std::int64_t offset,
                                    const std::vector<GlobalId>& face_ids);
template <int Dim>
struct StreamNumbering {
  std::vector<std::int64_t> offset;              // per partition of `parts`: its first owned id
  std::vector<std::vector<GlobalId>> face_ids;   // per partition, per face node: its global id
  std::int64_t owned_nodes = 0;                  // this rank's
  std::int64_t global_nodes = 0;
};
template <int Dim>
StreamNumbering<Dim> number_streamed(const Comm& comm, const std::vector<PartitionFaces<Dim>>& parts, int partitions);

// Collective. The whole mesh on `root` (nodes in global-id order, cells by partition),
// an empty mesh elsewhere. Checks that every copy of a node has the same coordinate bits
// (std::logic_error otherwise).
template <int Dim>
mesh::SimplexMesh<Dim> gather_mesh(const Comm& comm, const NumberedPiece<Dim>& piece, int root = 0);
inline mesh::Mesh2 gather_mesh2(const Comm& comm, const NumberedPiece2& piece, int root = 0) {
  return gather_mesh<2>(comm, piece, root);
}

}  // namespace cisamr::parallel
