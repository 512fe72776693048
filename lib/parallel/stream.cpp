#include "parallel/stream.hpp"

#include <algorithm>
#include <array>
#include <optional>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/inp_stream.hpp"
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

// Partition k of this rank read back from its spool (deleted then) with its global ids and
// partition index: what a one-file output (.msh, .inp) writes.
template <int Dim>
mesh::SimplexMesh<Dim> read_back_numbered(std::vector<std::unique_ptr<io::AtomicFile>>& spools,
                                          const std::vector<PartitionFaces<Dim>>& faces,
                                          const StreamNumbering<Dim>& numbering, std::size_t k) {
  mesh::SimplexMesh<Dim> m = unspool<Dim>(*spools[k]);
  spools[k].reset();  // the temporary is deleted
  m.node_global_id = global_ids_of<Dim>(faces[k], numbering.offset[k], numbering.face_ids[k]);
  m.cell_partition.assign(m.cell_phase.size(), faces[k].partition);
  return m;
}

// A partition's chunks of a streamed one-file output (.msh, .inp), in the order its joiner
// reads them: hidden temporaries beside the output, never committed (gone with the run, or
// when a signal ends it); and the min corner node's global id when the partition owns it.
struct PartitionChunks {
  int partition = 0;
  std::vector<std::unique_ptr<io::AtomicFile>> files;
  GlobalId corner0 = -1;
  io::AtomicFile& add(const std::string& path, const std::string& what) {
    const fs::path p(path);
    files.push_back(std::make_unique<io::AtomicFile>(
        (p.parent_path() / ("." + p.stem().string() + "." + std::to_string(partition) + "." + what + ".chunk")).string()));
    return *files.back();
  }
};

// What rank 0 reads of a partition's chunks.
struct ChunkList {
  std::vector<std::string> paths;
  std::vector<std::uint64_t> bytes;
  GlobalId corner0 = -1;
};

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

// A one-file output from chunks: every partition's summary (owned counts from the
// numbering) to every rank; each partition read back, numbered and written as chunks by
// `write_chunks(mesh, local index, summaries, chunks)`; rank 0 opens the output and
// `join(file, summaries, chunk lists by partition)`.
template <int Dim, class WriteChunks, class Join>
void write_streamed_file(const Comm& comm, const std::string& path, const std::vector<PartitionFaces<Dim>>& faces,
                         const StreamNumbering<Dim>& numbering, std::vector<std::unique_ptr<io::AtomicFile>>& spools,
                         std::vector<io::MshPartSummary>& summaries, int partitions,
                         WriteChunks&& write_chunks, Join&& join) {
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
  std::vector<PartitionChunks> chunks;
  run_collectively(comm, [&] {
    for (std::size_t k = 0; k < faces.size(); ++k) {
      const mesh::SimplexMesh<Dim> m = read_back_numbered<Dim>(spools, faces, numbering, k);
      PartitionChunks c;
      c.partition = faces[k].partition;
      write_chunks(m, k, all, c);
      for (auto& f : c.files) f->flush();
      chunks.push_back(std::move(c));
    }
  });
  Packer lists;
  for (const PartitionChunks& c : chunks) {
    lists.put<std::int32_t>(c.partition);
    lists.put<GlobalId>(c.corner0);
    lists.put<std::uint64_t>(c.files.size());
    for (const auto& f : c.files) {
      lists.put_string(f->temporary_path());
      lists.put<std::uint64_t>(fs::file_size(f->temporary_path()));
    }
  }
  const std::vector<Bytes> gathered = allgather_bytes(comm, lists.bytes());
  run_collectively(comm, [&] {
    if (comm.rank() != 0) return;
    std::vector<ChunkList> by_partition(all.size());
    for (const Bytes& bytes : gathered) {
      Unpacker u(bytes);
      while (!u.done()) {
        ChunkList& c = by_partition.at(static_cast<std::size_t>(u.get<std::int32_t>()));
        c.corner0 = u.get<GlobalId>();
        for (auto n = u.get<std::uint64_t>(); n > 0; --n) {
          c.paths.push_back(u.get_string());
          c.bytes.push_back(u.get<std::uint64_t>());
        }
      }
    }
    io::AtomicFile file(path);
    join(file, all, by_partition);
    file.commit();
  });
}

// Gmsh: chunks nodes, cells, then one per box face (io/msh_stream.hpp).
template <int Dim>
void write_streamed_msh(const Comm& comm, const std::string& path, const std::vector<PartitionFaces<Dim>>& faces,
                        const StreamNumbering<Dim>& numbering, std::vector<std::unique_ptr<io::AtomicFile>>& spools,
                        std::vector<io::MshPartSummary>& summaries, int partitions,
                        const std::vector<geometry::Phase>& phases, const io::MeshWriteOptions& write_options) {
  constexpr std::size_t kFaces = static_cast<std::size_t>(2 * Dim);
  // Tags: cells by partition, then the facets face by face, partition by partition.
  const auto first_cells = [](const std::vector<io::MshPartSummary>& all) {
    std::vector<std::uint64_t> first(all.size() + 1, 0);
    for (std::size_t p = 0; p < all.size(); ++p) first[p + 1] = first[p] + all[p].cells;
    return first;
  };
  write_streamed_file<Dim>(
      comm, path, faces, numbering, spools, summaries, partitions,
      [&](const mesh::SimplexMesh<Dim>& m, std::size_t k, const std::vector<io::MshPartSummary>& all, PartitionChunks& c) {
        const auto p = static_cast<std::size_t>(c.partition);
        std::array<std::uint64_t, 6> first_facet{};
        std::uint64_t tag = first_cells(all).back();
        for (std::size_t f = 0; f < kFaces; ++f)
          for (std::size_t q = 0; q < all.size(); ++q) {
            if (q == p) first_facet[f] = tag;
            tag += all[q].faces[f].count;
          }
        io::write_msh_node_chunk<Dim>(c.add(path, "nodes"), m, numbering.offset[k], summaries[k].owned_nodes,
                                      io::msh_node_entity(all));
        io::write_msh_cell_chunk<Dim>(c.add(path, "cells"), m, first_cells(all)[p]);
        std::array<io::AtomicFile*, 6> face_files{};
        for (std::size_t f = 0; f < kFaces; ++f) face_files[f] = &c.add(path, "face" + std::to_string(f));
        io::write_msh_face_chunks<Dim>(face_files, m, write_options, first_facet);
      },
      [&](io::AtomicFile& file, const std::vector<io::MshPartSummary>& all, const std::vector<ChunkList>& chunks) {
        io::write_msh_head<Dim>(file, all, phases);
        for (const ChunkList& c : chunks) append_file(file, c.paths[0]);
        io::write_msh_elements_head(file, all);
        for (const ChunkList& c : chunks) append_file(file, c.paths[1]);
        for (std::size_t f = 0; f < kFaces; ++f)
          for (const ChunkList& c : chunks) append_file(file, c.paths[2 + f]);
        io::write_msh_tail(file);
      });
}

// Abaqus: chunks nodes, cells per phase (every phase of any partition), then per box face
// its node set and its Dim + 1 element sides (io/inp_stream.hpp).
template <int Dim>
void write_streamed_inp(const Comm& comm, const std::string& path, const std::vector<PartitionFaces<Dim>>& faces,
                        const StreamNumbering<Dim>& numbering, std::vector<std::unique_ptr<io::AtomicFile>>& spools,
                        std::vector<io::MshPartSummary>& summaries, int partitions,
                        const std::vector<geometry::Phase>& phases, const io::MeshWriteOptions& write_options) {
  constexpr int kFaces = 2 * Dim, kSides = Dim + 1;
  const auto phase_ids = [](const std::vector<io::MshPartSummary>& all) {
    std::vector<int> ids;
    for (const io::MshPartSummary& s : all)
      for (const io::MshGroup& g : s.phases) ids.push_back(g.id);
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    return ids;
  };
  write_streamed_file<Dim>(
      comm, path, faces, numbering, spools, summaries, partitions,
      [&](const mesh::SimplexMesh<Dim>& m, std::size_t k, const std::vector<io::MshPartSummary>& all, PartitionChunks& c) {
        std::uint64_t first_cell = 0;
        for (int q = 0; q < c.partition; ++q) first_cell += all[static_cast<std::size_t>(q)].cells;
        io::write_inp_node_chunk<Dim>(c.add(path, "nodes"), m, numbering.offset[k], summaries[k].owned_nodes);
        const std::vector<int> ids = phase_ids(all);
        std::vector<io::AtomicFile*> per_phase;
        for (int id : ids) per_phase.push_back(&c.add(path, "phase" + std::to_string(id)));
        io::write_inp_cell_chunks<Dim>(per_phase, ids, m, first_cell);
        std::array<io::AtomicFile*, 6> nsets{};
        std::array<std::array<io::AtomicFile*, 4>, 6> elsets{};
        for (int f = 0; f < kFaces; ++f) {
          nsets[static_cast<std::size_t>(f)] = &c.add(path, "nset" + std::to_string(f));
          for (int s = 0; s < kSides; ++s)
            elsets[static_cast<std::size_t>(f)][static_cast<std::size_t>(s)] =
                &c.add(path, "elset" + std::to_string(f) + "s" + std::to_string(s + 1));
        }
        c.corner0 = io::write_inp_set_chunks<Dim>(nsets, elsets, m, write_options, numbering.offset[k],
                                                  summaries[k].owned_nodes, first_cell);
      },
      [&](io::AtomicFile& file, const std::vector<io::MshPartSummary>& all, const std::vector<ChunkList>& chunks) {
        std::uint64_t nodes = 0, cells = 0;
        for (const io::MshPartSummary& s : all) nodes += s.owned_nodes, cells += s.cells;
        file.write(io::inp_stream_head(nodes, cells, Dim));
        for (const ChunkList& c : chunks) append_file(file, c.paths[0]);
        const std::vector<int> ids = phase_ids(all);
        for (std::size_t g = 0; g < ids.size(); ++g) {
          file.write(io::inp_stream_element_header(phases, ids[g], Dim, write_options.plane));
          for (const ChunkList& c : chunks) append_file(file, c.paths[1 + g]);
        }
        const std::size_t sets = 1 + ids.size();  // the first set chunk
        const auto any_lines = [&](std::size_t i) {
          return std::any_of(chunks.begin(), chunks.end(), [&](const ChunkList& c) { return c.bytes[i] > 0; });
        };
        for (int f = 0; f < kFaces; ++f) {
          const std::size_t nset = sets + static_cast<std::size_t>(f) * (1 + kSides);
          if (!any_lines(nset)) continue;
          file.write(io::inp_stream_nset_header(f));
          for (const ChunkList& c : chunks) append_file(file, c.paths[nset]);
        }
        for (const ChunkList& c : chunks)
          if (c.corner0 >= 0) file.write("*NSET, NSET=CORNER0\n" + std::to_string(c.corner0 + 1) + "\n");
        for (int f = 0; f < kFaces; ++f) {
          std::vector<int> used;
          for (int s = 1; s <= kSides; ++s) {
            const std::size_t elset = sets + static_cast<std::size_t>(f) * (1 + kSides) + static_cast<std::size_t>(s);
            if (!any_lines(elset)) continue;
            used.push_back(s);
            file.write(io::inp_stream_elset_header(f, s));
            for (const ChunkList& c : chunks) append_file(file, c.paths[elset]);
          }
          if (!used.empty()) file.write(io::inp_stream_surface(f, used));
        }
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
                                   const PartitionHook<Dim>& on_partition) {
  // One file (.msh, .inp) or .pvtu pieces.
  std::optional<io::MeshFormat> one_file;
  run_collectively(comm, [&] {
    if (write_options.format || fs::path(pvtu_path).extension() != ".pvtu") {
      one_file = write_options.format ? *write_options.format : io::mesh_format_of(pvtu_path);
      if (*one_file != io::MeshFormat::msh && *one_file != io::MeshFormat::inp)
        throw InputError(pvtu_path, "", "--stream writes .pvtu pieces or one .msh or .inp file: name the output "
                                        "NAME.pvtu, NAME.msh or NAME.inp");
    }
    check_streamable(scene, options.pipeline);
  });
  std::vector<PartitionFaces<Dim>> faces;
  // One file: each partition spooled until the numbering; .pvtu: each piece written at once
  // but for its global ids, the file's last block, which the numbering gives.
  std::vector<std::unique_ptr<io::AtomicFile>> spools;
  std::vector<io::VtuAwaitingIds> pieces;
  std::vector<io::MshPartSummary> summaries;
  PhaseTimes spooling;
  const std::vector<geometry::Phase> phases = scene.phases;
  // One partition held at a time: its decisions near faces are recomputed, not exchanged.
  MeshOptions one_at_a_time = options;
  one_at_a_time.exchange_near_faces = false;
  DistributedMesh<Dim> out =
      mesh_partitions<Dim>(comm, std::move(scene), one_at_a_time, [&](PartitionOutput<Dim>& o, const grid::Lattice<Dim>& lattice) {
        mesh::SimplexMesh<Dim>& m = o.result.mesh;
        io::MeshWriteOptions piece_options = write_options;
        // The driver's figures, outside the write phase's time (a .vtu piece takes their ratios).
        if (on_partition) on_partition(m, one_file ? nullptr : &piece_options.cell_aspect_ratio);
        ScopedPhase timer(&spooling, "write");
        faces.push_back(partition_faces<Dim>(o, lattice));
        if (one_file) {
          summaries.push_back(io::msh_part_summary<Dim>(m, write_options));
          spools.push_back(spool<Dim>(pvtu_path, m));
        } else {
          m.cell_partition.assign(m.cell_phase.size(), faces.back().partition);
          pieces.emplace_back(piece_path(pvtu_path, faces.back().partition), m, phases, piece_options);
        }
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
  if (one_file) {
    if (*one_file == io::MeshFormat::msh)
      write_streamed_msh<Dim>(comm, pvtu_path, faces, numbering, spools, summaries, options.partitions, out.phases,
                              write_options);
    else
      write_streamed_inp<Dim>(comm, pvtu_path, faces, numbering, spools, summaries, options.partitions, out.phases,
                              write_options);
    return out;
  }
  run_collectively(comm, [&] {
    for (std::size_t k = 0; k < faces.size(); ++k)
      pieces[k].finish(global_ids_of<Dim>(faces[k], numbering.offset[k], numbering.face_ids[k]));
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
                                             const PartitionHook<2>&);
template DistributedMesh<3> mesh_streamed<3>(const Comm&, geometry::SceneDesc, const MeshOptions&, const std::string&,
                                             const io::MeshWriteOptions&,
                                             const PartitionHook<3>&);

}  // namespace cisamr::parallel
