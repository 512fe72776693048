#pragma once
// Streamed output (`cisamr mesh --stream`, issue #15): partitions meshed one after another
// on each rank, each written as a .vtu piece of its own, so that memory holds one partition
// at a time instead of the mesh.
//
//   kernel    mesh_partitions (distributed.hpp): each partition, when done, is spooled to a
//             hidden temporary beside the output (coordinates, cells, phases: its bytes on
//             disk, nothing in memory) and only its nodes on inner box faces are kept
//   number    one exchange of those face identities (merge.hpp, number_streamed): owners,
//             owned counts per partition, offsets; the global ids are exactly those of the
//             in-memory path (merge_and_number) for the same partitions
//   write     per partition: its spool read back, global ids set, the piece written
//             (NAME_<partition>.vtu), the spool deleted; rank 0 writes the .pvtu
// The mesh is the in-memory path's (same elements, same global ids, same checksum); the
// pieces are per partition instead of per rank.
#include <functional>
#include <string>

#include "core/comm.hpp"
#include "io/mesh_io.hpp"
#include "parallel/distributed.hpp"

namespace cisamr::parallel {

// Throws InputError for what `--stream` cannot do yet: cohesive cells (their facets are
// paired between partitions after meshing) and periodic scenes (masters across the domain).
void check_streamable(const geometry::SceneDesc& scene, const pipeline::Options& options);

// Sees each streamed partition's mesh as soon as it is meshed, before it is written or
// spooled and before its global ids exist (the driver's figures; not timed as "write"). Where the output has a per-cell aspect-ratio array (.vtu pieces),
// `cell_aspect_ratio` is not null: a hook that computes every cell's ratio anyway may fill
// it (one per cell, mesh::aspect_ratio's values) and the writer takes it instead of
// computing them a second time.
template <int Dim>
using PartitionHook = std::function<void(const mesh::SimplexMesh<Dim>&, std::vector<double>* cell_aspect_ratio)>;

// Collective. Meshes `scene` over options.partitions partitions, writing the .pvtu at
// `pvtu_path` and one piece per partition (inside the caller's io::OutputSet when one is
// open: nothing appears before its commit). `on_partition` sees each partition's mesh
// (PartitionHook). The result has no piece:
// piece.global_nodes and owned_nodes are set, partitions, counters, times as
// mesh_distributed's. Errors are collective.
template <int Dim>
DistributedMesh<Dim> mesh_streamed(const Comm& comm, geometry::SceneDesc scene, const MeshOptions& options,
                                   const std::string& pvtu_path, const io::MeshWriteOptions& write_options,
                                   const PartitionHook<Dim>& on_partition);

}  // namespace cisamr::parallel
