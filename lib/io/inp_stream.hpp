#pragma once
// Abaqus .inp written a partition at a time (`cisamr mesh … -o OUT.inp --stream`), as
// write_mesh writes it: *HEADING, one *NODE block (each partition's owned nodes, global id
// + 1, partition by partition: ascending), one *ELEMENT block per phase (each partition's
// cells of that phase, tag = cell number over all partitions + 1), per box face a *NSET of
// its nodes (each by its owner) and *ELSET <FACE>_S<k> / *SURFACE <FACE>_FACES of the
// element faces on it, CORNER0. Each partition writes its lines as chunks; the joiner adds
// the keyword lines (a set no partition has lines for is left out, as write_mesh does).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/scene.hpp"
#include "io/atomic_file.hpp"
#include "io/mesh_io.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::io {

std::string inp_stream_head(std::uint64_t nodes, std::uint64_t cells, int dim);  // *HEADING … *NODE
std::string inp_stream_element_header(const std::vector<geometry::Phase>& phases, int id, int dim, PlaneKind plane);
std::string inp_stream_nset_header(int face);
std::string inp_stream_elset_header(int face, int side);  // side: the Abaqus face id, 1..Dim+1
std::string inp_stream_surface(int face, const std::vector<int>& sides);

// The node lines of the nodes a partition owns (ids [first_owned, first_owned + owned)).
template <int Dim>
void write_inp_node_chunk(AtomicFile& file, const mesh::SimplexMesh<Dim>& partition, GlobalId first_owned,
                          std::uint64_t owned);
// Its element lines, into per_phase[i] for the cells of phase phase_ids[i].
template <int Dim>
void write_inp_cell_chunks(const std::vector<AtomicFile*>& per_phase, const std::vector<int>& phase_ids,
                           const mesh::SimplexMesh<Dim>& partition, std::uint64_t first_cell_tag);
// Its id lines of each face's node set (owned nodes only) and of each face's element sides;
// returns the global id of the domain's min corner node when this partition owns it, else -1.
template <int Dim>
GlobalId write_inp_set_chunks(const std::array<AtomicFile*, 6>& nsets,
                              const std::array<std::array<AtomicFile*, 4>, 6>& elsets,
                              const mesh::SimplexMesh<Dim>& partition, const MeshWriteOptions& options,
                              GlobalId first_owned, std::uint64_t owned, std::uint64_t first_cell_tag);

}  // namespace cisamr::io
