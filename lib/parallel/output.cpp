#include "parallel/output.hpp"

#include <filesystem>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/mesh_io.hpp"
#include "parallel/collective.hpp"
#include "parallel/exchange.hpp"
#include "parallel/periodic_masters.hpp"

namespace cisamr::parallel {
namespace fs = std::filesystem;

std::string piece_path(const std::string& pvtu_path, int rank) {
  fs::path p(pvtu_path);
  const std::string stem = p.stem().string();
  return (p.parent_path() / (stem + "_" + std::to_string(rank) + ".vtu")).string();
}

template <int Dim>
void write_pvtu(const Comm& comm, const std::string& pvtu_path, const mesh::SimplexMesh<Dim>& piece,
                const std::vector<geometry::Phase>& phases, const io::MeshWriteOptions& options) {
  // Joins the caller's io::OutputSet when one is open; otherwise the pieces and the .pvtu
  // are renamed into place together once every rank has written.
  io::OutputSet outputs;
  // A periodic mesh's pieces: each node's full master may be on another rank (collective).
  io::MeshWriteOptions piece_options;
  const io::MeshWriteOptions* used = &options;
  if (options.any_periodic() && options.periodic_master.empty()) {
    if (!options.face_box) throw std::invalid_argument("write_pvtu: a periodic mesh's pieces need options.face_box");
    Box<Dim> faces;
    std::array<bool, Dim> axes{};
    for (int d = 0; d < Dim; ++d) {
      faces.min[d] = options.face_box->min[d], faces.max[d] = options.face_box->max[d];
      axes[static_cast<std::size_t>(d)] = options.periodic[static_cast<std::size_t>(d)];
    }
    piece_options = options;
    piece_options.periodic_master = periodic_masters<Dim>(comm, piece, faces, axes, options.periodic_voids);
    used = &piece_options;
  }
  run_collectively(comm, [&] {
    if (fs::path(pvtu_path).extension() != ".pvtu")
      throw InputError(pvtu_path, "", "a parallel output must end in .pvtu");
    io::write_vtu(piece_path(pvtu_path, comm.rank()), piece, phases, *used);
  });
  run_collectively(comm, [&] {
    if (comm.rank() != 0) return;
    io::AtomicFile file(pvtu_path);
    std::vector<std::string> pieces;
    for (int r = 0; r < comm.size(); ++r) pieces.push_back(fs::path(piece_path(pvtu_path, r)).filename().string());
    file.write(io::pvtu_text(pieces, options.any_periodic(), !piece.node_phase.empty()));
    file.commit();
  });
  run_collectively(comm, [&] { outputs.commit(); });
}

template <int Dim>
void write_gathered(const Comm& comm, const std::string& path, const mesh::SimplexMesh<Dim>& gathered,
                    const std::vector<geometry::Phase>& phases, const io::MeshWriteOptions& options, int root) {
  run_collectively(comm, [&] {
    if (comm.rank() == root) io::write_mesh(path, gathered, phases, options);
  });
}

template void write_pvtu<2>(const Comm&, const std::string&, const mesh::SimplexMesh<2>&,
                            const std::vector<geometry::Phase>&, const io::MeshWriteOptions&);
template void write_pvtu<3>(const Comm&, const std::string&, const mesh::SimplexMesh<3>&,
                            const std::vector<geometry::Phase>&, const io::MeshWriteOptions&);
template void write_gathered<2>(const Comm&, const std::string&, const mesh::SimplexMesh<2>&,
                                const std::vector<geometry::Phase>&, const io::MeshWriteOptions&, int);
template void write_gathered<3>(const Comm&, const std::string&, const mesh::SimplexMesh<3>&,
                                const std::vector<geometry::Phase>&, const io::MeshWriteOptions&, int);

std::vector<PhaseSpread> spread_over_ranks(const Comm& comm, const PhaseTimes& times,
                                           const std::vector<std::string>& names) {
  std::vector<PhaseSpread> out;
  for (const std::string& name : names) {
    double mine = 0;
    for (const auto& [n, s] : times.phases())
      if (n == name) mine = s;
    PhaseSpread s{name, comm.allreduce_min(mine), comm.allreduce_max(mine), comm.allreduce_sum(mine) / comm.size()};
    out.push_back(s);
  }
  return out;
}

quality::AspectStats merge_aspect_statistics(const Comm& comm, const quality::AspectStats& local) {
  quality::AspectStats g;
  g.bound = local.bound;
  g.max = comm.allreduce_max(local.max);
  g.count = static_cast<std::size_t>(comm.allreduce_sum(static_cast<std::int64_t>(local.count)));
  g.above_bound = static_cast<std::size_t>(comm.allreduce_sum(static_cast<std::int64_t>(local.above_bound)));
  const double weighted = comm.allreduce_sum(local.mean * static_cast<double>(local.count));
  g.mean = g.count > 0 ? weighted / static_cast<double>(g.count) : 0;
  const bool has = local.count > 0;
  g.min_angle_deg = -comm.allreduce_max(has ? -local.min_angle_deg : -1e300);
  g.max_angle_deg = comm.allreduce_max(has ? local.max_angle_deg : -1e300);
  if (g.count == 0) g.min_angle_deg = g.max_angle_deg = 0;
  Packer p;
  p.put_vector(local.bin_edges);
  std::vector<std::uint64_t> hist(local.histogram.begin(), local.histogram.end());
  p.put_vector(hist);
  for (const Bytes& b : allgather_bytes(comm, p.bytes())) {
    Unpacker u(b);
    const auto edges = u.get_vector<double>();
    const auto h = u.get_vector<std::uint64_t>();
    quality::add_histogram(g, edges, std::vector<std::size_t>(h.begin(), h.end()));
  }
  return g;
}

}  // namespace cisamr::parallel
