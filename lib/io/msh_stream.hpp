#pragma once
// Gmsh MSH 4.1 written a partition at a time (`cisamr mesh … -o OUT.msh --stream`): the
// file is a head (physical names, entities, the node section's counts), then one block of
// the nodes each partition owns (global id + 1 as tag, in partition order: the owned ids of
// a partition are one run), then the element section: each partition's cells by phase
// (tag = cell number over all partitions + 1), then the facets on each box face, face by
// face, partition by partition. Each partition's blocks are chunks written on its rank as
// soon as its ids are known; the head needs only every partition's summary (counts and
// bounding boxes). The same physical groups and entities as write_mesh's .msh.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/scene.hpp"
#include "io/atomic_file.hpp"
#include "io/mesh_io.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::io {

// An entity's bounding box (z 0 in 2D).
struct MshBox {
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  bool empty = true;
  void add(const double* p, int dim);
  void add(const MshBox& other);
};

// What the head needs of one partition (trivially copyable parts: it travels between ranks).
struct MshGroup {
  std::int32_t id = 0;  // phase id (cells) or box face (facets)
  std::uint64_t count = 0;
  MshBox box;
};
struct MshPartSummary {
  std::uint64_t cells = 0, owned_nodes = 0;
  std::vector<MshGroup> phases;      // ascending id, non-empty groups only
  std::array<MshGroup, 6> faces{};   // facets on box face f (count 0: none); 2·Dim used
};

// A partition's summary (owned_nodes left 0): its cells by phase, its facets on the faces of
// options.face_box (which must be set: the whole domain's).
template <int Dim>
MshPartSummary msh_part_summary(const mesh::SimplexMesh<Dim>& partition, const MeshWriteOptions& options);

// The file's head, from every partition's summary in partition order: $MeshFormat,
// $PhysicalNames, $Entities, and the $Nodes line of counts.
template <int Dim>
void write_msh_head(AtomicFile& file, const std::vector<MshPartSummary>& parts, const std::vector<geometry::Phase>& phases);
// "$EndNodes", "$Elements" and its line of counts.
void write_msh_elements_head(AtomicFile& file, const std::vector<MshPartSummary>& parts);
void write_msh_tail(AtomicFile& file);  // "$EndElements"

// A partition's chunks (node_global_id set; it owns the nodes with ids in
// [first_owned, first_owned + summary.owned_nodes)): its node block on `node_entity`; its
// cells by phase, tags from first_cell_tag + 1; its facets on face f, tags from
// first_facet_tag[f] + 1 (faces[f] receives them; faces without facets get nothing).
template <int Dim>
void write_msh_node_chunk(AtomicFile& file, const mesh::SimplexMesh<Dim>& partition, GlobalId first_owned,
                          std::uint64_t owned, int node_entity);
template <int Dim>
void write_msh_cell_chunk(AtomicFile& file, const mesh::SimplexMesh<Dim>& partition, std::uint64_t first_cell_tag);
template <int Dim>
void write_msh_face_chunks(const std::array<AtomicFile*, 6>& faces, const mesh::SimplexMesh<Dim>& partition,
                           const MeshWriteOptions& options, const std::array<std::uint64_t, 6>& first_facet_tag);

// The entity the node blocks sit on: the smallest phase id any partition has (1 if none).
int msh_node_entity(const std::vector<MshPartSummary>& parts);

}  // namespace cisamr::io
