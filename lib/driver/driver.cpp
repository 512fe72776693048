#include "driver/driver.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <type_traits>
#include <utility>

#include "core/error.hpp"
#include "core/memory.hpp"
#include "geometry/oracle.hpp"
#include "geometry/periodic.hpp"
#include "io/atomic_file.hpp"
#include "io/mesh_io.hpp"
#include "io/mesh_svg.hpp"
#include "io/scene_io.hpp"
#include "mesh/metrics.hpp"
#include "mesh/explode.hpp"
#include "mesh/periodic_links.hpp"
#include "parallel/checksum.hpp"
#include "parallel/collective.hpp"
#include "parallel/ghost.hpp"
#include "parallel/merge.hpp"
#include "parallel/periodic_masters.hpp"
#include "parallel/stream.hpp"

namespace cisamr::driver {
namespace {

// Phases without a timer of their own (the timed ones tell Options::progress through
// PhaseTimes::progress).
void tell(const Options& options, const std::string& what) { begin_phase(options.progress, what); }

std::string about(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2g", value);
  return text;
}

double physical_memory() {
  return static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
}

// The most elements one run holds in memory: Options::max_elements, or what this machine's
// memory holds at kBytesPerElement.
double elements_in_memory(const Options& options) {
  return options.max_elements > 0 ? options.max_elements : physical_memory() / kBytesPerElement;
}

// The share of the whole mesh in memory at once when `ranks` ranks (all assumed on this
// machine) stream `partitions` partitions, each rank one at a time: a partition is about
// 1/partitions of the elements (the partitioner balances them), grown by the widest ghost
// on every side (3D: ghost_margin3(0) coarse cubes, 2D: kGhostMargin2). 1 when not
// streamed. (A constant "6 partitions' worth" before: E4's 8 partitions on 2 ranks, 4.6 GiB,
// were refused as 45 GB.)
template <int Dim>
double streamed_share(const geometry::SceneDesc& scene, int partitions, int ranks) {
  if (partitions <= 0) return 1.0;
  const double cells = pipeline::coarse_cells<Dim>(scene);
  const double side = std::pow(cells / partitions, 1.0 / Dim);
  const double ghost = Dim == 3 ? parallel::ghost_margin3(0) : parallel::kGhostMargin2;
  const double grown = std::min(cells, std::pow(side + 2 * ghost, Dim));
  return std::min(1.0, ranks * grown / cells);
}

// The partitions to stream over: the fewest, a multiple of the ranks and at least
// max(kStreamedPartitionsPerRank per rank, `least`), whose share held at once fits in memory.
template <int Dim>
int fewest_streamed_partitions(const geometry::SceneDesc& scene, const pipeline::MeshEstimate& estimate,
                               const Options& options, int ranks, int least) {
  const double fits = elements_in_memory(options);
  int partitions = std::max(kStreamedPartitionsPerRank * ranks, least);
  partitions = (partitions + ranks - 1) / ranks * ranks;
  // Never more than the coarse cells (check_request refuses what still does not fit).
  while (partitions + ranks <= std::min<double>(pipeline::coarse_cells<Dim>(scene), 1 << 20) &&
         estimate.total() * streamed_share<Dim>(scene, partitions, ranks) > fits)
    partitions += ranks;
  return partitions;
}

// With Options::stream_if_needed: the partitions to stream over when the mesh would not fit
// (fewest_streamed_partitions), 0 when it fits or cannot be streamed.
template <int Dim>
int partitions_to_stream(const geometry::SceneDesc& scene, const pipeline::MeshEstimate& estimate, const Options& options,
                         int ranks) {
  if (options.stream_if_needed.empty() || !options.stream.empty()) return 0;
  if (options.pipeline.cohesive || scene.any_periodic()) return 0;
  if (estimate.total() <= elements_in_memory(options)) return 0;
  return fewest_streamed_partitions<Dim>(scene, estimate, options, ranks, options.partitions);
}

// Whether an in-memory 3D run exchanges its decisions near faces: asked (the default), and
// either one partition per rank (nothing more is held) or room for every partition's working
// state (kExchangeMemoryFactor).
bool exchange_fits(const pipeline::MeshEstimate& estimate, const Options& options, int partitions, int ranks) {
  if (!options.exchange_near_faces) return false;
  return partitions <= ranks || estimate.total() * kExchangeMemoryFactor <= elements_in_memory(options);
}

// Refuses, before any memory is taken, a mesh estimated above Options::max_elements, and
// more partitions than coarse cells. Throws InputError naming the scene's field.
template <int Dim>
void check_request(const geometry::SceneDesc& scene, const pipeline::MeshEstimate& estimate, const Options& options,
                   int ranks) {
  const double memory = physical_memory();
  // Streamed, a rank holds one partition at a time (its ghost included).
  const double share = options.stream.empty() ? 1.0 : streamed_share<Dim>(scene, options.partitions, ranks);
  const double limit = elements_in_memory(options) / share;
  if (estimate.total() > limit) {
    std::string field = "mesh.h";
    if (estimate.background <= limit && estimate.largest_inclusion >= 0) {
      const auto k = static_cast<std::size_t>(estimate.largest_inclusion);
      field = scene.inclusions[k].levels == scene.levels ? "mesh.levels" : geometry::inclusion_field(scene, k) + ".levels";
    }
    const std::string limit_text =
        options.max_elements > 0 ? "the limit of " + about(limit)
                                 : "the " + about(limit) + " this machine's " + about(memory / 1e9) + " GB of memory holds";
    throw InputError(scene.source, field,
                     "the mesh would have about " + about(estimate.total()) + " elements (about " +
                         about(estimate.total() * kBytesPerElement / 1e9) + " GB), more than " + limit_text +
                         (options.stream.empty() ? " (--stream writes .pvtu or .msh partition by partition; "
                                                   "--max-elements overrides)"
                                                 : " (more --partitions hold less at a time; --max-elements overrides)"));
  }
  if (options.partitions > 0) {
    const double cells = pipeline::coarse_cells<Dim>(scene);
    if (options.partitions > cells)
      throw InputError(scene.source, "", "--partitions " + std::to_string(options.partitions) +
                                             ": more partitions than the scene's " + std::to_string(static_cast<long long>(cells)) +
                                             " coarse cells (domain / mesh.h)");
  }
}

// A MeshingError says what the rules could not build; the scene's `mesh` settings (h,
// levels) are what to change: name the file and them, keeping the error collective or not.
[[noreturn]] void rethrow_with_scene(const MeshingError& e, const std::string& scene_path) {
  const std::string what = InputError(scene_path, "mesh", e.what()).what();
  if (const auto* collective = dynamic_cast<const parallel::CollectiveFailure*>(&e)) {
    parallel::CollectiveMeshingError agreed(what);
    agreed.failed_rank = collective->failed_rank;
    throw agreed;
  }
  throw MeshingError(what);
}

// Area (2D) or volume (3D) of cell c.
template <int Dim>
double cell_measure(const mesh::SimplexMesh<Dim>& m, std::size_t c) {
  const LocalId* n = m.cell(c);
  if constexpr (Dim == 2)
    return mesh::signed_area(m.point(n[0]), m.point(n[1]), m.point(n[2]));
  else
    return mesh::signed_volume(m.point(n[0]), m.point(n[1]), m.point(n[2]), m.point(n[3]));
}

// One process, no partitions: the sequential mesher, its result as the one partition.
template <int Dim>
void mesh_sequential(const Comm& comm, const geometry::SceneDesc& scene, MeshRun<Dim>& run) {
  using Oracle = geometry::Oracle<Dim>;
  tell(run.options, "oracle");
  const Oracle oracle(scene);  // a periodic scene's holds the images that wrap in (geometry/periodic.hpp)
  pipeline::Result<Dim> result = pipeline::mesh(oracle, run.options.pipeline);
  parallel::DistributedMesh<Dim>& m = run.mesh;
  m.piece.mesh = std::move(result.mesh);
  m.piece.node_key = std::move(result.node_identity);
  m.piece.owned_nodes = m.piece.global_nodes = static_cast<std::int64_t>(m.piece.mesh.node_count());
  m.global_cells = static_cast<std::int64_t>(m.piece.mesh.cell_count());
  m.phases = scene.phases;
  for (int d = 0; d < Dim; ++d) m.domain.min[d] = scene.domain_min[d], m.domain.max[d] = scene.domain_max[d];
  m.scene_inclusions = static_cast<std::int64_t>(scene.inclusions.size());
  if (scene.any_periodic()) m.periodic_images = geometry::images_in_domain(oracle.scene(), {});
  parallel::PartitionSummary whole;
  whole.elements = m.global_cells;
  whole.nodes = m.piece.global_nodes;
  m.partitions = {whole};
  m.counters = result.counters;
  m.times = std::move(result.times);
}

// Adds the elements and measure per phase (in `phases` order) of `piece`'s cells.
template <int Dim>
void add_phase_figures(const mesh::SimplexMesh<Dim>& piece, const std::vector<geometry::Phase>& phases,
                       std::vector<PhaseFigures>& figures) {
  figures.resize(phases.size());
  for (std::size_t c = 0; c < piece.cell_count(); ++c) {
    const auto k = std::ranges::find_if(phases, [&](const geometry::Phase& p) { return p.id == piece.cell_phase[c]; });
    if (k == phases.end()) continue;
    PhaseFigures& f = figures[static_cast<std::size_t>(k - phases.begin())];
    ++f.elements;
    f.measure += cell_measure(piece, c);
  }
}

// A streamed partition's share of the figures take_figures reduces (this rank's so far).
template <int Dim>
void add_figures(MeshRun<Dim>& run, const mesh::SimplexMesh<Dim>& part, const std::vector<geometry::Phase>& phases,
                 std::uint64_t& checksum, std::vector<double>* cell_aspect_ratio) {
  quality::merge_into(run.aspect, quality::aspect_statistics(part, run.bound, 20, cell_aspect_ratio));
  if (!run.options.figures) return;
  add_phase_figures(part, phases, run.phase_figures);
  checksum += parallel::mesh_checksum(part);
}

// Aspect ratios, and with Options::figures per-phase counts and measures and the checksum,
// all over every rank's cells.
template <int Dim>
void take_figures(const Comm& comm, MeshRun<Dim>& run) {
  const mesh::SimplexMesh<Dim>& piece = run.mesh.piece.mesh;
  {
    ScopedPhase timer(&run.mesh.times, "quality");
    // Streamed: this rank's partitions added their share as they were written.
    const quality::AspectStats local = run.streamed ? run.aspect : quality::aspect_statistics(piece, run.bound);
    run.aspect = run.distributed ? parallel::merge_aspect_statistics(comm, local) : local;
    if (run.options.figures) {
      if (!run.streamed) add_phase_figures(piece, run.mesh.phases, run.phase_figures);
      run.phase_figures.resize(run.mesh.phases.size());
      for (PhaseFigures& f : run.phase_figures) f = {comm.allreduce_sum(f.elements), comm.allreduce_sum(f.measure)};
      // In this phase as a streamed run's partitions add theirs (add_figures): a pass over
      // every cell (E4 at 40 µm: 0.12 s of 3.1, uncounted in any phase before).
      run.checksum = run.streamed ? parallel::sum_over_ranks(comm, run.checksum) : parallel::mesh_checksum(comm, piece);
    }
  }
  if (run.options.pipeline.cohesive) {  // per phase pair (lower, upper), over every rank
    const std::vector<geometry::Phase>& phases = run.mesh.phases;
    const auto index = [&](std::int32_t id) {
      return static_cast<std::size_t>(std::ranges::find_if(phases, [&](const geometry::Phase& p) { return p.id == id; }) -
                                      phases.begin());
    };
    std::vector<std::int64_t> pairs(phases.size() * phases.size(), 0);
    for (std::size_t c = 0; c < piece.cohesive.count(); ++c) {
      const std::size_t p = index(piece.cohesive.phase[2 * c]), q = index(piece.cohesive.phase[2 * c + 1]);
      if (p < phases.size() && q < phases.size()) ++pairs[p * phases.size() + q];
    }
    std::vector<typename MeshRun<Dim>::CohesiveSet> sets;
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      const std::int64_t elements = comm.allreduce_sum(pairs[i]);
      if (elements > 0)
        sets.push_back({phases[i / phases.size()].id, phases[i % phases.size()].id, elements});
    }
    std::ranges::sort(sets, {}, [](const auto& s) { return std::pair(s.lower, s.upper); });
    run.cohesive_sets = std::move(sets);
    run.cohesive_elements = 0;
    for (const auto& set : run.cohesive_sets) run.cohesive_elements += set.elements;
  }
  if (run.any_periodic()) {  // every node on a max face is a slave (each eliminated once)
    std::int64_t slaves = 0;
    for (std::int64_t n = 0; n < run.mesh.piece.owned_nodes; ++n)
      slaves += mesh::periodic_shift<Dim>(&piece.coords[static_cast<std::size_t>(n) * Dim], run.face_box, run.periodic) != 0;
    run.periodic_slaves = comm.allreduce_sum(slaves);
  }
}

}  // namespace

template <int Dim>
Box<Dim> face_box(const geometry::SceneDesc& scene, const pipeline::Options& options) {
  const grid::Lattice<Dim> lattice = pipeline::make_lattice<Dim>(scene, options);
  Box<Dim> box;
  for (int d = 0; d < Dim; ++d) {
    box.min[d] = lattice.coordinate(d, 0);
    box.max[d] = lattice.coordinate(d, lattice.coarse_cells[d] * lattice.units(0));
  }
  return box;
}

template Box<2> face_box<2>(const geometry::SceneDesc&, const pipeline::Options&);
template Box<3> face_box<3>(const geometry::SceneDesc&, const pipeline::Options&);

bool is_distributed(const Comm& comm, const Options& options) { return comm.size() > 1 || options.partitions > 0; }

std::variant<MeshRun<2>, MeshRun<3>> mesh_scene(const Comm& comm, const std::string& scene_path,
                                                 const Options& options) {
  const auto start = std::chrono::steady_clock::now();
  const bool distributed = is_distributed(comm, options);
  tell(options, "read");
  geometry::SceneDesc scene;
  if (distributed)  // every rank reads the descriptors; STL triangles later, where needed
    parallel::run_collectively(comm, [&] {
      scene = io::read_scene(scene_path, io::ReadSceneOptions{.load_stl = false, .probe_stl = false});
    });
  else
    scene = io::read_scene(scene_path);
  const double read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto mesh = [&]<int Dim>(MeshRun<Dim> run) -> std::variant<MeshRun<2>, MeshRun<3>> {
    run.options = options;
    run.options.pipeline.progress = options.progress;
    run.mesh.times.progress = run.options.pipeline.progress;
    run.distributed = distributed;
    run.ranks = comm.size();
    run.start = start;
    run.bound = options.bound > 0 ? options.bound : Dim == 2 ? 3.0 : 5.0;
    pipeline::MeshEstimate estimate;  // the same on every rank: from the descriptors
    parallel::run_collectively(comm, [&] { estimate = pipeline::estimate_mesh<Dim>(scene); });
    if (!options.stream.empty() && options.stream_fewest_partitions)
      parallel::run_collectively(comm, [&] {
        run.options.partitions = fewest_streamed_partitions<Dim>(scene, estimate, options, comm.size(), options.partitions);
      });
    if (distributed) {
      int partitions = 0;
      parallel::run_collectively(comm, [&] { partitions = partitions_to_stream<Dim>(scene, estimate, options, comm.size()); });
      if (partitions > 0) {
        run.options.stream = options.stream_if_needed;
        run.options.partitions = partitions;
        run.note = "the mesh would have about " + about(estimate.total()) +
                   " elements, more than the " + about(elements_in_memory(options)) +
                   " held in memory: streamed over " + std::to_string(partitions) + " partitions (--stream)";
      }
    }
    parallel::run_collectively(comm, [&] { check_request<Dim>(scene, estimate, run.options, comm.size()); });
    try {
      run.face_box = face_box<Dim>(scene, options.pipeline);  // builds the lattice: may refuse the scene
      const grid::Lattice<Dim> lattice = pipeline::make_lattice<Dim>(scene, options.pipeline);
      for (int d = 0; d < Dim; ++d) {
        run.periodic[static_cast<std::size_t>(d)] = scene.periodic[static_cast<std::size_t>(d)];
        run.period[d] = lattice.period(d);
      }
      if (distributed) {
        const int partitions = run.options.partitions > 0 ? run.options.partitions : comm.size();
        parallel::MeshOptions o{.pipeline = run.options.pipeline,
                                .partitions = partitions,
                                .partitioning = {},
                                .ghost = options.ghost,
                                .exchange_near_faces = exchange_fits(estimate, options, partitions, comm.size())};
        if (Dim == 3 && options.exchange_near_faces && !o.exchange_near_faces && run.options.stream.empty() &&
            !run.any_periodic() && run.note.empty())  // (periodic and streamed runs never exchange)
          run.note = "the mesh would have about " + about(estimate.total()) + " elements: too many to hold every one of " +
                     std::to_string(partitions) + " partitions between the kernel's parts, so their decisions near faces "
                     "are recomputed one partition at a time (fewer --partitions, or --max-elements, allow the exchange)";
        if (run.options.stream.empty()) {
          run.mesh = parallel::mesh_distributed<Dim>(comm, std::move(scene), o);
        } else {
          run.streamed = true;
          run.aspect.bound = run.bound;
          io::MeshWriteOptions write;
          write.format = options.stream_format;
          write.plane = options.stream_plane;
          write.face_box = Box3{};
          for (int d = 0; d < Dim; ++d) write.face_box->min[d] = run.face_box.min[d], write.face_box->max[d] = run.face_box.max[d];
          const std::vector<geometry::Phase> phases = scene.phases;
          std::uint64_t checksum = 0;
          PhaseTimes figures;
          run.mesh = parallel::mesh_streamed<Dim>(comm, std::move(scene), o, run.options.stream, write,
                                                  [&](const mesh::SimplexMesh<Dim>& part, std::vector<double>* ratios) {
                                                    ScopedPhase timer(&figures, "quality");
                                                    add_figures(run, part, phases, checksum, ratios);
                                                  });
          for (const auto& [name, seconds] : figures.phases()) run.mesh.times.add(name, seconds);
          run.checksum = checksum;
        }
        run.mesh.times.add("read", read_seconds);
        const std::int64_t files = run.mesh.stl_files_read;
        run.stl_files_read = {-comm.allreduce_max(-files), comm.allreduce_max(files), comm.allreduce_sum(files)};
      } else {
        mesh_sequential<Dim>(comm, scene, run);
      }
    } catch (const MeshingError& e) {
      rethrow_with_scene(e, scene_path);
    }
    take_figures(comm, run);
    return run;
  };
  if (scene.dimension == 3) return mesh(MeshRun<3>{});
  return mesh(MeshRun<2>{});
}

Output plan_output(const Comm& comm, const std::string& requested, bool gather, bool distributed,
                   const std::string& format, io::PlaneKind plane) {
  namespace fs = std::filesystem;
  const std::string extension = format.empty() ? fs::path(requested).extension().string() : "." + format;
  Output out;
  out.plane = plane;
  out.pieces = distributed && (extension == ".pvtu" || (extension == ".vtu" && comm.size() > 1 && !gather));
  out.path = out.pieces ? fs::path(requested).replace_extension(".pvtu").string() : requested;
  parallel::run_collectively(comm, [&] {
    if (out.pieces && gather)
      throw InputError(requested, "", "--gather writes one file: use .vtu, .msh, .inp or .mesh");
    if (!out.pieces && !format.empty()) out.format = io::mesh_format_of("mesh." + format);
    if (!out.pieces && format.empty()) io::mesh_format_of(out.path);
    if (!out.pieces && comm.size() > 1 && !gather)
      throw InputError(requested, "", "a parallel run writes .pvtu pieces; add --gather to write one " + extension +
                                          " file on rank 0");
  });
  if (out.pieces)
    for (int r = 0; r < comm.size(); ++r) out.piece_paths.push_back(parallel::piece_path(out.path, r));
  // Where the files go, before any work: rank 0 writes the .pvtu or the one file, every rank
  // its pieces (in the .pvtu's folder, which may be a different disk on each node).
  parallel::run_collectively(comm, [&] {
    if (out.pieces) io::check_writable(out.piece_paths[static_cast<std::size_t>(comm.rank())]);
    if (comm.rank() == 0) io::check_writable(out.path);
  });
  return out;
}

template <int Dim>
void write_outputs(const Comm& comm, MeshRun<Dim>& run, const Output& output, const std::string& svg) {
  if (run.streamed) return;  // the pieces were written as the partitions were meshed
  ScopedPhase timer(&run.mesh.times, "write");
  const parallel::NumberedPiece<Dim>& piece = run.mesh.piece;
  const bool picture = !svg.empty();
  // On one rank the piece is the whole mesh (nodes in global-id order).
  mesh::SimplexMesh<Dim> gathered_copy;
  if ((!output.pieces || picture) && comm.size() > 1) gathered_copy = parallel::gather_mesh<Dim>(comm, piece);
  mesh::SimplexMesh<Dim>& gathered = comm.size() > 1 ? gathered_copy : run.mesh.piece.mesh;
  io::MeshWriteOptions options;
  options.format = output.format;
  options.plane = output.plane;
  options.face_box = Box3{};
  for (int d = 0; d < Dim; ++d) options.face_box->min[d] = run.face_box.min[d], options.face_box->max[d] = run.face_box.max[d];
  for (int d = 0; d < Dim; ++d) {  // periodic constraints (.inp, .msh, .vtu)
    options.periodic[static_cast<std::size_t>(d)] = run.periodic[static_cast<std::size_t>(d)];
    options.period[static_cast<std::size_t>(d)] = run.period[d];
  }
  options.periodic_voids = std::ranges::any_of(run.mesh.phases, [](const geometry::Phase& p) { return p.is_void; });
  if (output.pieces && run.any_periodic()) {  // the masters of this rank's slaves, from any rank
    ScopedPhase exchange(&run.mesh.times, "periodic");
    options.periodic_master =
        parallel::periodic_masters<Dim>(comm, piece.mesh, run.face_box, run.periodic, options.periodic_voids);
  }
  std::vector<double> meshed_coords;  // --explode: the regions moved apart, in the file only
  if (output.explode > 1 && !output.pieces) {
    options.periodic = {};
    if (comm.rank() == 0) meshed_coords = std::exchange(gathered.coords, mesh::exploded_coords<Dim>(gathered, output.explode));
  }
  if (output.pieces)
    parallel::write_pvtu<Dim>(comm, output.path, piece.mesh, run.mesh.phases, options);
  else
    parallel::write_gathered<Dim>(comm, output.path, gathered, run.mesh.phases, options);
  if (!meshed_coords.empty()) gathered.coords = std::move(meshed_coords);
  if (picture)
    parallel::run_collectively(comm, [&] {
      if (comm.rank() != 0) return;
      geometry::SceneDesc header;  // what the picture needs: phases and domain
      header.phases = run.mesh.phases;
      for (int d = 0; d < Dim; ++d) header.domain_min[d] = run.mesh.domain.min[d], header.domain_max[d] = run.mesh.domain.max[d];
      if constexpr (Dim == 2)
        io::write_mesh_svg(svg, gathered, header);
      else
        io::write_mesh_svg(svg, gathered, header, run.options.svg_slice);
    });
}

template <int Dim>
void finish(const Comm& comm, MeshRun<Dim>& run) {
  run.mesh.times.add("total", std::chrono::duration<double>(std::chrono::steady_clock::now() - run.start).count());
  // A distributed run reports every phase (the same list on every rank); a sequential one
  // the phases it ran.
  static const std::vector<std::string> kPhases = {"read",      "partition", "ghost",  "oracle",
                                                   "samr",      "radapt",    "exchange", "faceswap", "subdivide",
                                                   "assemble",  "cohesive",  "merge",   "quality", "periodic",
                                                   "write",     "total"};
  std::vector<std::string> names;
  for (const std::string& name : kPhases)
    if ((run.distributed && (name != "periodic" || run.any_periodic()) && (name != "cohesive" || run.options.pipeline.cohesive) &&
         (name != "exchange" || Dim == 3)) ||
        std::ranges::any_of(run.mesh.times.phases(), [&](const auto& p) { return p.first == name; }))
      names.push_back(name);
  run.timings = parallel::spread_over_ranks(comm, run.mesh.times, names);
  run.total_seconds = run.timings.back().max;
  const std::int64_t peak = peak_resident_bytes();  // meshing and writing are over
  run.peak_rss_bytes = {-comm.allreduce_max(-peak), comm.allreduce_max(peak), comm.allreduce_sum(peak)};
}

template void write_outputs<2>(const Comm&, MeshRun<2>&, const Output&, const std::string&);
template void write_outputs<3>(const Comm&, MeshRun<3>&, const Output&, const std::string&);
template void finish<2>(const Comm&, MeshRun<2>&);
template void finish<3>(const Comm&, MeshRun<3>&);

}  // namespace cisamr::driver
