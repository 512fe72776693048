#pragma once
// One call that meshes a scene file, sequentially or distributed, and what the run reports
// (README.md). On one process without partitions it is the plain sequential mesher
// (pipeline::mesh); with partitions, or on several ranks, the parallel mesher
// (parallel::mesh_distributed). Every function taking a Comm is collective.
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "core/comm.hpp"
#include "core/progress.hpp"
#include "io/mesh_svg.hpp"
#include "parallel/distributed.hpp"
#include "parallel/output.hpp"
#include "quality/quality.hpp"

namespace cisamr::driver {

struct Options {
  pipeline::Options pipeline;
  // 0: the sequential mesher on one process, one partition per rank on several; N: the
  // parallel mesher over N partitions (N ≥ ranks).
  int partitions = 0;
  // --stream: the .pvtu (or one .msh or .inp) to write while meshing (parallel/stream.hpp),
  // partitions one after another on each rank; empty: the mesh is assembled in memory and
  // written after.
  std::string stream;
  // With `stream` and no --partitions: the run takes the fewest partitions, at least
  // kStreamedPartitionsPerRank per rank and a multiple of the ranks, whose share held at
  // once fits in memory.
  bool stream_fewest_partitions = false;
  // The .pvtu a parallel run writes when it is asked for pieces (or its --gather .msh or
  // .inp): the mesh is streamed there when its estimate would not fit in memory (and it can
  // be streamed), instead of refused.
  std::string stream_if_needed;
  // The streamed file's format when its name does not say it, and the 2D Abaqus element type.
  std::optional<io::MeshFormat> stream_format;
  io::PlaneKind stream_plane = io::PlaneKind::stress;
  parallel::GhostRule ghost;
  bool exchange_near_faces = true;  // parallel::MeshOptions::exchange_near_faces (false: comparisons)
  double bound = 0;     // aspect-ratio bound of the statistics (0: 3 in 2D, 5 in 3D)
  bool figures = true;  // per-phase counts and measures, checksum (a pass and a sort over the cells)
  // A scene whose mesh pipeline::estimate_mesh puts above this many elements is refused
  // before any work (InputError naming mesh.h or the levels). 0: as many as this machine's
  // memory holds at kBytesPerElement each.
  double max_elements = 0;
  io::SlicePlane svg_slice;  // the plane of a 3D mesh's picture (write_outputs)
  // Told of every phase (read, oracle, levels, samr, ..., write) on every rank: in a parallel
  // run a parallel::RankProgress, which reports the slowest rank on rank 0.
  Progress* progress = nullptr;
};

// Partitions per rank a streamed run takes at least, unless told: more partitions hold less
// at a time and cost little time (E4 on 2 ranks, one build: 16 partitions 209 s in 2.9 GiB,
// 8 partitions 218 s in 4.6 GiB; smaller partitions mesh faster per element, which pays for
// their ghosts).
inline constexpr int kStreamedPartitionsPerRank = 8;

// Peak memory of a run per element, measured on the examples (about 60 bytes in 2D, 95
// in 3D: validation/bench/MEMORY.md), with a margin.
inline constexpr double kBytesPerElement = 130;

// How much more a 3D in-memory run with several partitions per rank may hold when it
// exchanges the forest and the decisions near faces (every partition's forest and nodes held
// between the kernel's parts): 64 partitions of spheres300 on one rank peak at 419 MB, one
// partition at 282 MB. Where the mesh's estimate times this would not fit, the partitions recompute those
// decisions one at a time instead (parallel::MeshOptions::exchange_near_faces).
inline constexpr double kExchangeMemoryFactor = 2.0;

// Whether `options` ask for the parallel mesher on `comm`.
bool is_distributed(const Comm& comm, const Options& options);

struct PhaseFigures {
  std::int64_t elements = 0;
  double measure = 0;  // area in 2D, volume in 3D
};

struct RankSpread {
  std::int64_t min = 0, max = 0, total = 0;
};

template <int Dim>
struct MeshRun {
  static constexpr int dim = Dim;
  Options options;
  bool distributed = false;
  int ranks = 1;
  // piece.mesh: the whole mesh (sequential) or this rank's piece (global node ids);
  // counters over every partition of every rank; every partition with its box, load and
  // ghost (sequential: one); this rank's phase times.
  parallel::DistributedMesh<Dim> mesh;
  Box<Dim> face_box{};  // the exact coordinates of the nodes on each domain face (face_box)
  // The scene's periodic axes (domain.periodic) and the lattice's period N_a·h along each
  // axis (face_box.max = fl(face_box.min + period)): the writers' periodic constraints.
  std::array<bool, Dim> periodic{};
  Vec<Dim> period{};
  std::int64_t periodic_slaves = 0;  // nodes on a periodic max face, over every rank
  // --cohesive: the cohesive cells per phase pair (ascending), over every rank, and the
  // node copies the split added (nodes less those of the mesh without cohesive cells).
  struct CohesiveSet {
    std::int32_t lower = 0, upper = 0;
    std::int64_t elements = 0;
  };
  std::vector<CohesiveSet> cohesive_sets;
  std::int64_t cohesive_elements = 0;
  bool any_periodic() const { return std::ranges::any_of(periodic, [](bool p) { return p; }); }
  double bound = 0;
  quality::AspectStats aspect;              // of the whole mesh
  std::vector<PhaseFigures> phase_figures;  // per scene phase (Options::figures)
  std::uint64_t checksum = 0;               // order-free, of the whole mesh (Options::figures)
  RankSpread stl_files_read;                // STL files read per rank (distributed)
  std::chrono::steady_clock::time_point start;
  std::vector<parallel::PhaseSpread> timings;  // per phase, over ranks (finish)
  double total_seconds = 0;                    // slowest rank (finish)
  RankSpread peak_rss_bytes;                   // each rank's peak resident memory so far (finish)
  bool streamed = false;                       // written while meshing (Options::stream): no piece
  std::string note;                            // what the run decided for the user (printed by the app)
};

// The box whose faces hold the mesh's boundary nodes, coordinate for coordinate: the
// lattice's position of the domain's first and last lattice planes (the min corner, and
// min + N·h rounded once, which may differ from domain.max in the last bit). The writers'
// boundary sets compare node coordinates with it exactly.
template <int Dim>
Box<Dim> face_box(const geometry::SceneDesc& scene, const pipeline::Options& options);

// Reads the scene (every rank parses it; STL files as lib/parallel's README says), meshes
// it, and takes the aspect-ratio statistics, and with Options::figures the per-phase
// figures and the checksum. Before meshing it refuses a scene above Options::max_elements
// and more partitions than the scene has coarse cells (InputError); a MeshingError names the
// scene file and its `mesh` settings. Errors are thrown on every rank alike.
std::variant<MeshRun<2>, MeshRun<3>> mesh_scene(const Comm& comm, const std::string& scene_path,
                                                 const Options& options);

// Where the mesh goes: one file (on rank 0 when distributed), or a .pvtu listing one .vtu
// piece per rank (a .pvtu name, or .vtu on several ranks without `gather`).
struct Output {
  std::string path;  // "-": standard output (one file, `format` named)
  std::optional<io::MeshFormat> format;  // when the path's extension does not name it
  io::PlaneKind plane = io::PlaneKind::stress;  // 2D Abaqus elements (CPS3 / CPE3)
  bool pieces = false;
  std::vector<std::string> piece_paths;
  // --explode F (> 1; one file): each phase region moved apart by mesh::exploded_coords in the
  // written mesh only, without periodic constraints; picture, report and summary unchanged.
  double explode = 0;
};

// Checks the requested output before any work (format; pieces or one gathered file; that
// the folders it goes to exist and can be written, io::check_writable).
// `format` ("vtu", "msh", "inp", "mesh"; empty: from the extension) names the format of a
// path without one, such as "-"; `plane` the 2D Abaqus element type. Throws InputError on
// every rank.
Output plan_output(const Comm& comm, const std::string& requested, bool gather, bool distributed,
                   const std::string& format = "", io::PlaneKind plane = io::PlaneKind::stress);

// Writes the mesh where `output` says and, with `svg` given, a picture of it (3D: the slice
// by Options::svg_slice) (timed as "write").
template <int Dim>
void write_outputs(const Comm& comm, MeshRun<Dim>& run, const Output& output, const std::string& svg);

// Ends the run's clock: "total" added to this rank's times, every phase's spread over ranks.
template <int Dim>
void finish(const Comm& comm, MeshRun<Dim>& run);

// The cisamr-report/1 JSON document of a finished run (indented, ending with a newline),
// in the same wording sequential and distributed (the distributed run's keys added).
// Complete on rank 0.
template <int Dim>
std::string report(const MeshRun<Dim>& run, const std::string& scene_path, const Output& output);

}  // namespace cisamr::driver
