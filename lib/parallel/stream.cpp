#include "parallel/stream.hpp"

#include <array>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/msh_stream.hpp"
#include "parallel/exchange.hpp"
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

// A partition's chunks of the streamed .msh (io/msh_stream.hpp): hidden temporaries beside
// the output, never committed (gone with the run, or when a signal ends it).
struct MshChunks {
  int partition = 0;
  std::unique_ptr<io::AtomicFile> nodes, cells;
  std::array<std::unique_ptr<io::AtomicFile>, 6> faces;  // 2·Dim used
};

std::unique_ptr<io::AtomicFile> chunk_file(const std::string& path, int partition, const std::string& what) {
  const fs::path p(path);
  return std::make_unique<io::AtomicFile>(
      (p.parent_path() / ("." + p.stem().string() + "." + std::to_string(partition) + "." + what + ".chunk")).string());
}

// Appends the bytes of `from` (a chunk another rank may have written: the output's folder is
// shared, as the pieces' and spools' are).
void append_file(io::AtomicFile& to, const std::string& from) {
  std::ifstream in(from, std::ios::binary);
  std::vector<char> buffer(std::size_t(1) << 20);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    to.write(buffer.data(), static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw std::runtime_error("cannot read back the chunk " + from);
}

// The .msh of a streamed run: every partition's summary to every rank, chunks written where
// the partitions are, then rank 0 writes the head and the chunks in order.
template <int Dim>
void write_streamed_msh(const Comm& comm, const std::string& path, const std::vector<PartitionFaces<Dim>>& faces,
                        const StreamNumbering<Dim>& numbering, std::vector<std::unique_ptr<io::AtomicFile>>& spools,
                        std::vector<io::MshPartSummary>& summaries, int partitions,
                        const std::vector<geometry::Phase>& phases, const io::MeshWriteOptions& write_options,
                        const std::function<void(const mesh::SimplexMesh<Dim>&)>& on_partition) {
  constexpr std::size_t kFaces = static_cast<std::size_t>(2 * Dim);
  Packer mine;
  for (std::size_t k = 0; k < faces.size(); ++k) {
    std::uint64_t copies = 0;  // face nodes owned by a lower partition
    for (const GlobalId id : numbering.face_ids[k]) copies += id < numbering.offset[k] ? 1 : 0;
    summaries[k].owned_nodes = static_cast<std::uint64_t>(faces[k].nodes) - copies;
    mine.put<std::int32_t>(faces[k].partition);
    mine.put<std::uint64_t>(summaries[k].cells);
    mine.put<std::uint64_t>(summaries[k].owned_nodes);
    mine.put_vector(summaries[k].phases);
    mine.put(summaries[k].faces);
  }
  std::vector<io::MshPartSummary> all(static_cast<std::size_t>(partitions));
  for (const Bytes& bytes : allgather_bytes(comm, mine.bytes())) {
    Unpacker u(bytes);
    while (!u.done()) {
      io::MshPartSummary& s = all.at(static_cast<std::size_t>(u.get<std::int32_t>()));
      s.cells = u.get<std::uint64_t>();
      s.owned_nodes = u.get<std::uint64_t>();
      s.phases = u.get_vector<io::MshGroup>();
      s.faces = u.get<std::array<io::MshGroup, 6>>();
    }
  }
  // Tags: cells by partition, then the facets face by face, partition by partition.
  std::vector<std::uint64_t> first_cell(all.size() + 1, 0);
  for (std::size_t p = 0; p < all.size(); ++p) first_cell[p + 1] = first_cell[p] + all[p].cells;
  std::vector<std::array<std::uint64_t, 6>> first_facet(all.size());
  std::uint64_t tag = first_cell.back();
  for (std::size_t f = 0; f < kFaces; ++f)
    for (std::size_t p = 0; p < all.size(); ++p) first_facet[p][f] = tag, tag += all[p].faces[f].count;
  const int node_entity = io::msh_node_entity(all);

  std::vector<MshChunks> chunks;
  run_collectively(comm, [&] {
    for (std::size_t k = 0; k < faces.size(); ++k) {
      mesh::SimplexMesh<Dim> m = unspool<Dim>(*spools[k]);
      spools[k].reset();
      const int p = faces[k].partition;
      m.node_global_id = global_ids_of<Dim>(faces[k], numbering.offset[k], numbering.face_ids[k]);
      m.cell_partition.assign(m.cell_phase.size(), p);
      if (on_partition) on_partition(m);
      MshChunks c;
      c.partition = p;
      c.nodes = chunk_file(path, p, "nodes");
      io::write_msh_node_chunk<Dim>(*c.nodes, m, numbering.offset[k], summaries[k].owned_nodes, node_entity);
      c.cells = chunk_file(path, p, "cells");
      io::write_msh_cell_chunk<Dim>(*c.cells, m, first_cell[static_cast<std::size_t>(p)]);
      std::array<io::AtomicFile*, 6> face_files{};
      for (std::size_t f = 0; f < kFaces; ++f) {
        c.faces[f] = chunk_file(path, p, "face" + std::to_string(f));
        face_files[f] = c.faces[f].get();
      }
      io::write_msh_face_chunks<Dim>(face_files, m, write_options, first_facet[static_cast<std::size_t>(p)]);
      c.nodes->flush();
      c.cells->flush();
      for (std::size_t f = 0; f < kFaces; ++f) c.faces[f]->flush();
      chunks.push_back(std::move(c));
    }
  });
  Packer paths;
  for (const MshChunks& c : chunks) {
    paths.put<std::int32_t>(c.partition);
    paths.put_string(c.nodes->temporary_path());
    paths.put_string(c.cells->temporary_path());
    for (std::size_t f = 0; f < kFaces; ++f) paths.put_string(c.faces[f]->temporary_path());
  }
  const std::vector<Bytes> gathered = allgather_bytes(comm, paths.bytes());
  run_collectively(comm, [&] {
    if (comm.rank() != 0) return;
    std::vector<std::vector<std::string>> chunk_paths(all.size());  // per partition: nodes, cells, faces
    for (const Bytes& bytes : gathered) {
      Unpacker u(bytes);
      while (!u.done()) {
        std::vector<std::string>& c = chunk_paths.at(static_cast<std::size_t>(u.get<std::int32_t>()));
        for (std::size_t i = 0; i < 2 + kFaces; ++i) c.push_back(u.get_string());
      }
    }
    io::AtomicFile file(path);
    io::write_msh_head<Dim>(file, all, phases);
    for (const auto& c : chunk_paths) append_file(file, c[0]);
    io::write_msh_elements_head(file, all);
    for (const auto& c : chunk_paths) append_file(file, c[1]);
    for (std::size_t f = 0; f < kFaces; ++f)
      for (const auto& c : chunk_paths) append_file(file, c[2 + f]);
    io::write_msh_tail(file);
    file.commit();
  });
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
  const bool msh = write_options.format ? *write_options.format == io::MeshFormat::msh
                                        : fs::path(pvtu_path).extension() == ".msh";
  run_collectively(comm, [&] {
    if (!msh && (write_options.format || fs::path(pvtu_path).extension() != ".pvtu"))
      throw InputError(pvtu_path, "", "--stream writes .pvtu pieces or one .msh: name the output NAME.pvtu or NAME.msh");
    check_streamable(scene, options.pipeline);
  });
  std::vector<PartitionFaces<Dim>> faces;
  std::vector<std::unique_ptr<io::AtomicFile>> spools;
  std::vector<io::MshPartSummary> summaries;
  PhaseTimes spooling;
  DistributedMesh<Dim> out =
      mesh_partitions<Dim>(comm, std::move(scene), options, [&](PartitionOutput<Dim>& o, const grid::Lattice<Dim>& lattice) {
        ScopedPhase timer(&spooling, "write");
        faces.push_back(partition_faces<Dim>(o, lattice));
        if (msh) summaries.push_back(io::msh_part_summary<Dim>(o.result.mesh, write_options));
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
  if (msh) {
    write_streamed_msh<Dim>(comm, pvtu_path, faces, numbering, spools, summaries, options.partitions, out.phases,
                            write_options, on_partition);
    return out;
  }
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
