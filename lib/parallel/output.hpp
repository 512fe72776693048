#pragma once
// Output of a parallel run (DESIGN.md §7): one .vtu piece per rank plus the .pvtu that
// lists them, or one gathered file on rank 0; and the per-rank phase-time spread for the
// report. Every function here is collective; files appear only when every rank succeeded.
#include <string>
#include <vector>

#include "core/comm.hpp"
#include "core/timer.hpp"
#include "geometry/scene.hpp"
#include "io/mesh_io.hpp"
#include "mesh/simplex_mesh.hpp"
#include "quality/quality.hpp"

namespace cisamr::parallel {

// "DIR/NAME.pvtu" → "DIR/NAME_<rank>.vtu".
std::string piece_path(const std::string& pvtu_path, int rank);

// Collective. Each rank writes its piece and rank 0 the .pvtu, all through io::AtomicFile
// inside an io::OutputSet: once every rank has written, every rank renames its files into
// place (inside a caller's open OutputSet, the caller's commit does). A failure anywhere
// deletes what this call wrote on every rank and is thrown on every rank (collective.hpp).
// The pieces' boundary bits refer to `options.face_box`: give the whole domain's (unset,
// each piece's own bounding box would be taken). With options.periodic, each piece gets
// periodic_master through one exchange (periodic_masters.hpp; face_box required), and the
// .pvtu declares it.
template <int Dim>
void write_pvtu(const Comm& comm, const std::string& pvtu_path, const mesh::SimplexMesh<Dim>& piece,
                const std::vector<geometry::Phase>& phases = {}, const io::MeshWriteOptions& options = {});
inline void write_pvtu2(const Comm& comm, const std::string& pvtu_path, const mesh::Mesh2& piece) {
  write_pvtu<2>(comm, pvtu_path, piece);
}

// Collective. Rank `root` writes `gathered` (any format io::write_mesh knows; `options`
// may name it, for a path without an extension such as "-").
template <int Dim>
void write_gathered(const Comm& comm, const std::string& path, const mesh::SimplexMesh<Dim>& gathered,
                    const std::vector<geometry::Phase>& phases, const io::MeshWriteOptions& options = {},
                    int root = 0);

struct PhaseSpread {
  std::string name;
  double min = 0, max = 0, mean = 0;  // seconds over ranks
};

// Collective. For each name (the same list on every rank), min/max/mean over ranks of this
// rank's time under that name (0 when it has none).
std::vector<PhaseSpread> spread_over_ranks(const Comm& comm, const PhaseTimes& times,
                                           const std::vector<std::string>& names);

// Collective. Aspect-ratio statistics of the union of every rank's cells from each rank's
// own (quality::aspect_statistics with the same bound): max/min, counts, mean weighted by
// count, histograms summed bin by bin (every rank's edges are a prefix of 1.0, 1.1, ...).
// `worst` is left empty (cell ids are per rank).
quality::AspectStats merge_aspect_statistics(const Comm& comm, const quality::AspectStats& local);

}  // namespace cisamr::parallel
