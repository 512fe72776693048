#include "parallel/stream.hpp"

#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "parallel/collective.hpp"
#include "parallel/output.hpp"

namespace cisamr::parallel {
namespace fs = std::filesystem;
namespace {

template <class T>
void spool_vector(io::AtomicFile& file, const std::vector<T>& v) {
  const std::uint64_t n = v.size();
  file.write(&n, sizeof n);
  file.write(v.data(), v.size() * sizeof(T));
}

template <class T>
std::vector<T> unspool_vector(std::ifstream& in, const std::string& path) {
  std::uint64_t n = 0;
  in.read(reinterpret_cast<char*>(&n), sizeof n);
  std::vector<T> v(in ? n : 0);
  in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(T)));
  if (!in) throw std::runtime_error("cannot read back the spooled partition " + path);
  return v;
}

// A partition's cells on disk until its global ids are known: never committed, so the
// temporary goes when the spool does (or when a signal ends the run).
template <int Dim>
std::unique_ptr<io::AtomicFile> spool(const std::string& pvtu_path, const mesh::SimplexMesh<Dim>& m) {
  const fs::path p(pvtu_path);
  auto file = std::make_unique<io::AtomicFile>((p.parent_path() / ("." + p.stem().string() + ".spool")).string());
  spool_vector(*file, m.coords);
  spool_vector(*file, m.cell_nodes);
  spool_vector(*file, m.cell_phase);
  file->flush();
  return file;
}

template <int Dim>
mesh::SimplexMesh<Dim> unspool(const io::AtomicFile& file) {
  std::ifstream in(file.temporary_path(), std::ios::binary);
  mesh::SimplexMesh<Dim> m;
  m.coords = unspool_vector<double>(in, file.temporary_path());
  m.cell_nodes = unspool_vector<LocalId>(in, file.temporary_path());
  m.cell_phase = unspool_vector<std::int32_t>(in, file.temporary_path());
  return m;
}

}  // namespace

void check_streamable(const geometry::SceneDesc& scene, const pipeline::Options& options) {
  if (options.cohesive)
    throw InputError("--stream", "",
                     "cohesive cells are paired between partitions after meshing and are not streamed yet; run "
                     "without --stream");
  if (scene.any_periodic())
    throw InputError(scene.source, "domain.periodic",
                     "--stream does not stream periodic meshes yet (their masters lie across the domain); run "
                     "without --stream");
}

template <int Dim>
DistributedMesh<Dim> mesh_streamed(const Comm& comm, geometry::SceneDesc scene, const MeshOptions& options,
                                   const std::string& pvtu_path, const io::MeshWriteOptions& write_options,
                                   const std::function<void(const mesh::SimplexMesh<Dim>&)>& on_partition) {
  run_collectively(comm, [&] {
    if (fs::path(pvtu_path).extension() != ".pvtu")
      throw InputError(pvtu_path, "", "--stream writes .pvtu pieces: name the output NAME.pvtu");
    check_streamable(scene, options.pipeline);
  });
  std::vector<PartitionFaces<Dim>> faces;
  std::vector<std::unique_ptr<io::AtomicFile>> spools;
  PhaseTimes spooling;
  DistributedMesh<Dim> out =
      mesh_partitions<Dim>(comm, std::move(scene), options, [&](PartitionOutput<Dim>& o, const grid::Lattice<Dim>& lattice) {
        ScopedPhase timer(&spooling, "write");
        faces.push_back(partition_faces<Dim>(o, lattice));
        spools.push_back(spool<Dim>(pvtu_path, o.result.mesh));
        o.result = pipeline::Result<Dim>{};
      });
  for (const auto& [name, seconds] : spooling.phases()) out.times.add(name, seconds);

  StreamNumbering<Dim> numbering;
  {
    ScopedPhase timer(&out.times, "merge");
    numbering = number_streamed<Dim>(comm, faces, options.partitions);
  }
  out.piece.global_nodes = numbering.global_nodes;
  out.piece.owned_nodes = numbering.owned_nodes;

  ScopedPhase timer(&out.times, "write");
  run_collectively(comm, [&] {
    for (std::size_t k = 0; k < faces.size(); ++k) {
      mesh::SimplexMesh<Dim> m = unspool<Dim>(*spools[k]);
      spools[k].reset();  // the temporary is deleted
      m.node_global_id = global_ids_of<Dim>(faces[k], numbering.offset[k], numbering.face_ids[k]);
      m.cell_partition.assign(m.cell_phase.size(), faces[k].partition);
      if (on_partition) on_partition(m);
      io::write_vtu(piece_path(pvtu_path, faces[k].partition), m, out.phases, write_options);
    }
  });
  run_collectively(comm, [&] {
    if (comm.rank() != 0) return;
    io::AtomicFile file(pvtu_path);
    std::vector<std::string> pieces;
    for (int p = 0; p < options.partitions; ++p) pieces.push_back(fs::path(piece_path(pvtu_path, p)).filename().string());
    file.write(io::pvtu_text(pieces));
    file.commit();
  });
  return out;
}

template DistributedMesh<2> mesh_streamed<2>(const Comm&, geometry::SceneDesc, const MeshOptions&, const std::string&,
                                             const io::MeshWriteOptions&,
                                             const std::function<void(const mesh::SimplexMesh<2>&)>&);
template DistributedMesh<3> mesh_streamed<3>(const Comm&, geometry::SceneDesc, const MeshOptions&, const std::string&,
                                             const io::MeshWriteOptions&,
                                             const std::function<void(const mesh::SimplexMesh<3>&)>&);

}  // namespace cisamr::parallel
