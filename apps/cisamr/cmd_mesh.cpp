// cisamr mesh SCENE -o OUT.{vtu,pvtu,msh,inp,mesh} [--partitions N] [--gather] [--report R.json]
//             [--svg PICTURE.svg]
// Without --partitions and outside mpiexec: the sequential mesher, as before. With
// --partitions N, or under mpiexec -n P: the parallel mesher of lib/parallel (Algorithm 2),
// through MPI or, on one process, through the serial Comm.
#include <chrono>
#include <cmath>
#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <vector>

#include "commands.hpp"
#include "core/error.hpp"
#include "geometry/oracle.hpp"
#include "io/atomic_file.hpp"
#include "io/mesh_io.hpp"
#include "io/mesh_svg.hpp"
#include "io/scene_io.hpp"
#include "mesh/metrics.hpp"
#include "parallel/checksum.hpp"
#include "parallel/collective.hpp"
#include "parallel/distributed.hpp"
#include "parallel/output.hpp"
#include "parallel/session.hpp"
#include "pipeline/pipeline.hpp"
#include "pipeline/pipeline3.hpp"
#include "quality/quality.hpp"

namespace cisamr::app {
namespace {

struct MeshArgs {
  std::string scene, output, report, svg;
  double alpha = 0.5;
  int extra_levels = 3;
  double bound = 0;  // 0: the dimension's bound
  int partitions = 0;  // 0: not given (sequential outside mpiexec, one per rank inside)
  bool gather = false;
  bool fixed_ghost = false;  // the fixed 3-cell inclusion margin instead of the level-aware one
  int closure_rounds = 0;    // ghost closure rounds (0: none, the default; -1: the full closure)
  double ghost_cubes = 0;    // 3D: a forced ghost margin in coarse cubes (0: the reach-derived one)
};

void progress(const GlobalFlags& flags, const char* what) {
  if (show_progress(flags)) std::fprintf(stderr, "cisamr: %s\n", what);
}

std::string checksum_text(std::uint64_t sum) {
  char text[20];
  std::snprintf(text, sizeof text, "%016" PRIx64, sum);
  return text;
}

nlohmann::json aspect_json(const quality::AspectStats& aspect) {
  return {{"max", aspect.max},
          {"mean", aspect.mean},
          {"bound", aspect.bound},
          {"above_bound", aspect.above_bound},
          {"bin_edges", aspect.bin_edges},
          {"histogram", aspect.histogram},
          {"min_angle_deg", aspect.min_angle_deg},
          {"max_angle_deg", aspect.max_angle_deg}};
}

nlohmann::json algorithm_json(const MeshArgs& args, const pipeline::Stats& stats) {
  return {{"alpha", args.alpha},
          {"extra_levels", args.extra_levels},
          {"coarse_cells", stats.coarse_cells},
          {"leaves", stats.leaves},
          {"refinements", stats.refinements},
          {"lattice_nodes", stats.lattice_nodes},
          {"snapped_nodes", stats.snapped_nodes},
          {"cut_quads", stats.cut_quads},
          {"double_diagonal_splits", stats.double_diagonal},
          {"hanging_node_cells", stats.hanging_cells},
          {"unresolved_quads", stats.unresolved},
          {"finest_level", stats.max_level},
          {"collapsed_features", stats.collapsed},
          {"max_collapse_deviation", stats.max_collapse_deviation}};
}

nlohmann::json algorithm_json(const MeshArgs& args, const pipeline::Stats3& stats) {
  const pipeline::Options defaults;
  return {{"alpha", args.alpha},
          {"alpha_diagonal", defaults.alpha_diagonal3},
          {"extra_levels", args.extra_levels},
          {"coarse_cubes", stats.coarse_cubes},
          {"leaves", stats.leaves},
          {"refinements", stats.refinements},
          {"finest_level", stats.max_level},
          {"lattice_nodes", stats.lattice_nodes},
          {"snapped_nodes", stats.snapped_nodes},
          {"guard_bound", defaults.bound3},
          {"guarded_leaves", stats.guarded_leaves},
          {"guard_combinations", stats.guard_combinations},
          {"nodes_refused_first_option", stats.refused_nodes},
          {"collapsed_nodes", stats.collapsed_nodes},
          {"collapsed_cut_points", stats.collapsed_cut_points},
          {"max_collapse_deviation", stats.max_collapse_deviation},
          {"face_swaps", stats.face_swaps},
          {"cut_tets", stats.cut_tets},
          {"cut_nodes", stats.cut_nodes},
          {"closed_tets", stats.closed_tets},
          {"steiner_points", stats.steiner_points},
          {"unresolved", stats.unresolved},
          {"inverted", stats.inverted},
          {"missing_crossings", stats.missing_crossings}};
}

// Measure of cell c: area in 2D, volume in 3D.
double cell_measure(const mesh::Mesh2& m, std::size_t c) {
  const LocalId* n = m.cell(c);
  return mesh::signed_area(m.point(n[0]), m.point(n[1]), m.point(n[2]));
}
double cell_measure(const mesh::Mesh3& m, std::size_t c) {
  const LocalId* n = m.cell(c);
  return mesh::signed_volume(m.point(n[0]), m.point(n[1]), m.point(n[2]), m.point(n[3]));
}

template <int Dim, class Stats>
nlohmann::json report_json(const MeshArgs& args, const geometry::SceneDesc& scene, const mesh::SimplexMesh<Dim>& m,
                           const Stats& stats, const quality::AspectStats& aspect, double total_seconds) {
  nlohmann::json j;
  j["format"] = "cisamr-report/1";
  j["scene"] = args.scene;
  j["output"] = args.output;
  j["dimension"] = Dim;
  j["nodes"] = m.node_count();
  j["elements"] = m.cell_count();
  // Per-phase element counts and measures (area in 2D, volume in 3D).
  nlohmann::json phases = nlohmann::json::array();
  std::vector<std::size_t> count(scene.phases.size(), 0);
  std::vector<double> measure(scene.phases.size(), 0.0);
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    const int k = scene.phase_index(m.cell_phase[c]);
    if (k < 0) continue;
    ++count[static_cast<std::size_t>(k)];
    measure[static_cast<std::size_t>(k)] += cell_measure(m, c);
  }
  for (std::size_t k = 0; k < scene.phases.size(); ++k) {
    const auto& ph = scene.phases[k];
    phases.push_back({{"id", ph.id}, {"name", ph.name}, {"void", ph.is_void}, {"elements", count[k]}, {"measure", measure[k]}});
  }
  j["phases"] = phases;
  j["aspect_ratio"] = aspect_json(aspect);  // angles: triangle angles in 2D, dihedral angles in 3D
  j["algorithm"] = algorithm_json(args, stats);
  nlohmann::json times = nlohmann::json::object();
  for (const auto& [name, seconds] : stats.times.phases())
    times[name] = {{"min", seconds}, {"max", seconds}, {"mean", seconds}};
  j["timings_s"] = times;
  j["total_s"] = total_seconds;
  j["ranks"] = 1;
  j["partitions"] = nlohmann::json::array({{{"partition", 0}, {"rank", 0}, {"elements", m.cell_count()}}});
  j["checksum"] = checksum_text(parallel::mesh_checksum(m));
  return j;
}

// One process, no partitions: the sequential mesher (pipeline::mesh2 / mesh3).
template <int Dim>
void run_sequential(const MeshArgs& args, const geometry::SceneDesc& scene, const GlobalFlags& flags, int& exit_code,
                    std::chrono::steady_clock::time_point start) {
  progress(flags, "building the geometry oracle");
  using Oracle = std::conditional_t<Dim == 2, geometry::Oracle2, geometry::Oracle3>;
  const Oracle oracle(scene);
  pipeline::Options options;
  options.alpha = args.alpha;
  options.extra_levels = args.extra_levels;
  progress(flags, Dim == 2 ? "meshing (SAMR, r-adaptivity, subdivision)"
                           : "meshing (SAMR, r-adaptivity with the quality guard, face swapping, subdivision)");
  auto result = [&] {
    if constexpr (Dim == 2)
      return pipeline::mesh2(oracle, options);
    else
      return pipeline::mesh3_with_stats(oracle, options);
  }();
  const double bound = args.bound > 0 ? args.bound : Dim == 2 ? 3.0 : 5.0;
  quality::AspectStats aspect;
  {
    ScopedPhase timer(&result.stats.times, "quality");
    aspect = quality::aspect_statistics(result.mesh, bound);
  }
  progress(flags, "writing the mesh");
  {
    ScopedPhase timer(&result.stats.times, "write");
    io::write_mesh(args.output, result.mesh, scene.phases);
    if constexpr (Dim == 2)
      if (!args.svg.empty()) io::write_mesh_svg(args.svg, result.mesh, scene);
  }
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!args.report.empty()) {
    io::AtomicFile file(args.report);
    file.write(report_json<Dim>(args, scene, result.mesh, result.stats, aspect, total).dump(2) + "\n");
    file.commit();
  }
  if (!flags.quiet)
    std::printf("%s: %zu nodes, %zu %s, max aspect ratio %.3f (bound %.1f, %zu above), %.3f s\n", args.output.c_str(),
                result.mesh.node_count(), result.mesh.cell_count(), Dim == 2 ? "triangles" : "tetrahedra", aspect.max,
                bound, aspect.above_bound, total);
  if (flags.verbose)
    for (const auto& [name, seconds] : result.stats.times.phases()) std::printf("  %-10s %8.3f s\n", name.c_str(), seconds);
  if constexpr (Dim == 2) {
    if (result.stats.collapsed > 0 && !flags.quiet)
      std::printf("%lld quads held a feature below the local resolution (a tangency, a thin gap or a wedge "
                  "sharper than the bound allows); collapsed with nodes at most %.3g from the phases they serve\n",
                  static_cast<long long>(result.stats.collapsed), result.stats.max_collapse_deviation);
  } else {
    if (result.stats.collapsed_nodes + result.stats.collapsed_cut_points > 0 && !flags.quiet)
      std::printf("%lld nodes could neither stay nor snap without a tetrahedron above the bound (a tangency, a "
                  "thin gap or a wedge at the domain boundary); collapsed onto the interface, at most %.3g from "
                  "the phases they serve\n",
                  static_cast<long long>(result.stats.collapsed_nodes), result.stats.max_collapse_deviation);
  }
  if (result.stats.unresolved > 0)
    std::fprintf(stderr, "cisamr: warning: %lld %s below the finest level's resolution\n",
                 static_cast<long long>(result.stats.unresolved), Dim == 2 ? "quads" : "leaves");
  exit_code = aspect.above_bound > 0 ? 3 : 0;
}

// The parallel mesher (lib/parallel). Collective: every rank runs all of it; only rank 0
// prints and writes the report. Errors are agreed between ranks inside lib/parallel.
template <int Dim>
void run_parallel(const MeshArgs& args, const GlobalFlags& flags, int& exit_code, geometry::SceneDesc scene,
                  std::chrono::steady_clock::time_point start) {
  const Comm& comm = parallel::world();
  const bool root = comm.rank() == 0;
  const double read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  namespace fs = std::filesystem;
  const std::string extension = fs::path(args.output).extension().string();
  // Pieces + .pvtu for a .pvtu name, or for .vtu on several ranks without --gather.
  const bool pieces = extension == ".pvtu" || (extension == ".vtu" && comm.size() > 1 && !args.gather);
  const std::string output = pieces ? fs::path(args.output).replace_extension(".pvtu").string() : args.output;
  parallel::run_collectively(comm, [&] {
    if (pieces && args.gather)
      throw InputError(args.output, "", "--gather writes one file: use .vtu, .msh, .inp or .mesh");
    if (!pieces) io::mesh_format_of(output);
    if (!pieces && comm.size() > 1 && !args.gather)
      throw InputError(args.output, "", "a parallel run writes .pvtu pieces; add --gather to write one " + extension +
                                            " file on rank 0");
  });
  const bool show = root && show_progress(flags);
  if (show) std::fprintf(stderr, "cisamr: meshing on %d rank(s)\n", comm.size());

  parallel::MeshOptions options;
  options.pipeline.alpha = args.alpha;
  options.pipeline.extra_levels = args.extra_levels;
  options.partitions = args.partitions > 0 ? args.partitions : comm.size();
  options.ghost.level_aware = !args.fixed_ghost;
  options.ghost.max_closure_rounds = args.closure_rounds;
  options.ghost.margin3_cubes = args.ghost_cubes;
  parallel::DistributedMesh<Dim> dm = parallel::mesh_distributed<Dim>(comm, std::move(scene), options);
  dm.times.add("read", read_seconds);
  const mesh::SimplexMesh<Dim>& piece = dm.piece.mesh;

  const double bound = args.bound > 0 ? args.bound : Dim == 2 ? 3.0 : 5.0;
  quality::AspectStats aspect;
  std::vector<std::pair<std::int64_t, double>> per_phase;  // elements, measure
  {
    ScopedPhase timer(&dm.times, "quality");
    aspect = parallel::merge_aspect_statistics(comm, quality::aspect_statistics(piece, bound));
    for (const auto& ph : dm.phases) {
      std::int64_t count = 0;
      double area = 0;
      for (std::size_t c = 0; c < piece.cell_count(); ++c)
        if (piece.cell_phase[c] == ph.id) {
          ++count;
          area += cell_measure(piece, c);
        }
      per_phase.emplace_back(comm.allreduce_sum(count), comm.allreduce_sum(area));
    }
  }
  const std::uint64_t checksum = parallel::mesh_checksum(comm, piece);
  // STL files read per rank (3D: each file by one rank for boxes, loads and unions, then by
  // the ranks whose partitions need it).
  const std::int64_t stl_min = -comm.allreduce_max(-dm.stl_files_read);
  const std::int64_t stl_max = comm.allreduce_max(dm.stl_files_read);
  const std::int64_t stl_total = comm.allreduce_sum(dm.stl_files_read);
  if (show) std::fprintf(stderr, "cisamr: writing the mesh\n");
  {
    ScopedPhase timer(&dm.times, "write");
    // One rank: its piece is already the gathered mesh (nodes in global-id order).
    const bool svg = Dim == 2 && !args.svg.empty();
    mesh::SimplexMesh<Dim> gathered_copy;
    if ((!pieces || svg) && comm.size() > 1) gathered_copy = parallel::gather_mesh<Dim>(comm, dm.piece);
    const mesh::SimplexMesh<Dim>& gathered = comm.size() > 1 ? gathered_copy : piece;
    if (pieces)
      parallel::write_pvtu<Dim>(comm, output, piece);
    else
      parallel::write_gathered<Dim>(comm, output, gathered, dm.phases);
    if constexpr (Dim == 2)
      if (svg)
      parallel::run_collectively(comm, [&] {
        if (!root) return;
        geometry::SceneDesc header;
        header.phases = dm.phases;
        header.domain_min = {dm.domain.min[0], dm.domain.min[1], 0};
        header.domain_max = {dm.domain.max[0], dm.domain.max[1], 0};
        io::write_mesh_svg(args.svg, gathered, header);
      });
  }
  const double total_local = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  dm.times.add("total", total_local);
  static const std::vector<std::string> kPhases = {"read",     "partition", "ghost",    "oracle", "samr",
                                                   "radapt",   "faceswap",  "subdivide", "assemble", "merge",
                                                   "quality",  "write",     "total"};
  const std::vector<parallel::PhaseSpread> spread = parallel::spread_over_ranks(comm, dm.times, kPhases);
  const double total = spread.back().max;

  double max_load = 0, sum_load = 0;
  for (const auto& p : dm.partitions) max_load = std::max(max_load, p.load), sum_load += p.load;
  const double mean_load = dm.partitions.empty() ? 0 : sum_load / static_cast<double>(dm.partitions.size());
  if (!args.report.empty())
    parallel::run_collectively(comm, [&] {
      if (!root) return;
      nlohmann::json j;
      j["format"] = "cisamr-report/1";
      j["scene"] = args.scene;
      j["output"] = output;
      if (pieces) {
        nlohmann::json names = nlohmann::json::array();
        for (int r = 0; r < comm.size(); ++r) names.push_back(parallel::piece_path(output, r));
        j["pieces"] = names;
      }
      j["dimension"] = Dim;
      j["nodes"] = dm.piece.global_nodes;
      j["elements"] = dm.global_cells;
      nlohmann::json phases = nlohmann::json::array();
      for (std::size_t i = 0; i < dm.phases.size(); ++i)
        phases.push_back({{"id", dm.phases[i].id}, {"name", dm.phases[i].name}, {"void", dm.phases[i].is_void},
                          {"elements", per_phase[i].first}, {"measure", per_phase[i].second}});
      j["phases"] = phases;
      j["aspect_ratio"] = aspect_json(aspect);
      j["algorithm"] = algorithm_json(args, dm.stats);
      if constexpr (Dim == 2) j["algorithm"]["coarse_cells_meshed"] = dm.stats.coarse_cells;
      if constexpr (Dim == 3) j["stl_files_read"] = {{"min", stl_min}, {"max", stl_max}, {"total", stl_total}};
      nlohmann::json times = nlohmann::json::object();
      for (const auto& s : spread) times[s.name] = {{"min", s.min}, {"max", s.max}, {"mean", s.mean}};
      j["timings_s"] = times;
      j["total_s"] = total;
      j["ranks"] = comm.size();
      j["partition_method"] = dm.partition_method;
      j["ghost_rule"] = Dim == 3 ? (args.ghost_cubes > 0 ? "forced-" + std::to_string(static_cast<int>(std::ceil(args.ghost_cubes))) + "-cubes" : std::string("reach-3d"))
                                 : args.fixed_ghost ? "fixed-3-cells" : "level-aware";
      j["load"] = {{"max", max_load}, {"mean", mean_load}, {"imbalance", mean_load > 0 ? max_load / mean_load : 1.0}};
      nlohmann::json parts = nlohmann::json::array();
      for (const auto& p : dm.partitions)
        parts.push_back({{"partition", p.id},
                         {"rank", p.rank},
                         {"lattice_min", std::vector<std::int64_t>(p.lattice_min.begin(), p.lattice_min.begin() + Dim)},
                         {"lattice_max", std::vector<std::int64_t>(p.lattice_max.begin(), p.lattice_max.begin() + Dim)},
                         {"load", p.load},
                         {"elements", p.elements},
                         {"nodes", p.nodes},
                         {"ghost_cells", p.ghost},
                         {"ghost_coarse_cells", p.ghost_cells},
                         {"inclusions_loaded", p.inclusions},
                         {"kernel_s", p.kernel_seconds}});
      j["partitions"] = parts;
      j["scene_inclusions"] = dm.scene_inclusions;
      j["checksum"] = checksum_text(checksum);
      io::AtomicFile file(args.report);
      file.write(j.dump(2) + "\n");
      file.commit();
    });
  if (root && !flags.quiet) {
    std::printf("%s: %lld nodes, %lld %s, max aspect ratio %.3f (bound %.1f), %.3f s, %d rank(s), %zu partitions\n",
                output.c_str(), static_cast<long long>(dm.piece.global_nodes), static_cast<long long>(dm.global_cells),
                Dim == 2 ? "triangles" : "tetrahedra", aspect.max, bound, total, comm.size(), dm.partitions.size());
    if constexpr (Dim == 2) {
      if (dm.stats.collapsed > 0)
        std::printf("%lld quads held a feature below the local resolution (a tangency, a thin gap or a wedge "
                    "sharper than the bound allows); collapsed with nodes at most %.3g from the phases they serve\n",
                    static_cast<long long>(dm.stats.collapsed), dm.stats.max_collapse_deviation);
    } else {
      if (dm.stats.collapsed_nodes + dm.stats.collapsed_cut_points > 0)
        std::printf("%lld nodes could neither stay nor snap without a tetrahedron above the bound; collapsed onto the "
                    "interface, at most %.3g from the phases they serve\n",
                    static_cast<long long>(dm.stats.collapsed_nodes), dm.stats.max_collapse_deviation);
    }
  }
  if (root && flags.verbose) {
    std::printf("  %-10s %9s %9s %9s   (seconds over %d rank(s))\n", "phase", "min", "max", "mean", comm.size());
    for (const auto& s : spread) std::printf("  %-10s %9.3f %9.3f %9.3f\n", s.name.c_str(), s.min, s.max, s.mean);
    std::printf("  partition loads: max %.4g, mean %.4g, imbalance %.3f (%s)\n", max_load, mean_load,
                mean_load > 0 ? max_load / mean_load : 1.0, dm.partition_method.c_str());
    for (const auto& p : dm.partitions) {
      std::printf("  part %3d rank %2d cells ", p.id, p.rank);
      for (int d = 0; d < Dim; ++d)
        std::printf("%s[%lld,%lld)", d ? "x" : "", static_cast<long long>(p.lattice_min[d]),
                    static_cast<long long>(p.lattice_max[d]));
      std::printf(" load %10.4g elements %9lld ghost %3d inclusions %6lld kernel %.3f s\n", p.load,
                  static_cast<long long>(p.elements), p.ghost, static_cast<long long>(p.inclusions), p.kernel_seconds);
    }
  }
  if (root && dm.stats.unresolved > 0)
    std::fprintf(stderr, "cisamr: warning: %lld %s below the finest level's resolution\n",
                 static_cast<long long>(dm.stats.unresolved), Dim == 2 ? "quads" : "leaves");
  exit_code = aspect.above_bound > 0 ? 3 : 0;
}

}  // namespace

void add_mesh_command(CLI::App& app, GlobalFlags& flags, int& exit_code) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* cmd = app.add_subcommand("mesh", "Mesh a scene (cisamr-scene/1 JSON) into a conforming simplex mesh");
  cmd->add_option("scene", args->scene, "Scene file")->required();
  cmd->add_option("-o,--output", args->output,
                  "Output mesh: .vtu, .msh (Gmsh 4.1), .inp (Abaqus) or .mesh (Medit); in parallel also .pvtu "
                  "(one .vtu piece per rank)")
      ->required();
  cmd->add_option("--report", args->report, "Write a JSON report (counts, per-phase measure, aspect ratios, timings)");
  cmd->add_option("--svg", args->svg, "Write a picture of the 2D mesh coloured by phase");
  cmd->add_option("--alpha", args->alpha, "r-adaptivity snap threshold, fraction of the edge length")
      ->check(CLI::Range(0.05, 0.5));
  cmd->add_option("--extra-levels", args->extra_levels,
                  "Levels beyond the largest requested one that may separate close interfaces")
      ->check(CLI::Range(0, 10));
  cmd->add_option("--bound", args->bound, "Aspect-ratio bound for the exit status (default 3 in 2D, 5 in 3D)");
  cmd->add_option("--partitions", args->partitions,
                  "Mesh N load-balanced partitions with the parallel mesher (N >= MPI ranks; default under "
                  "mpiexec: one per rank)")
      ->check(CLI::Range(1, 1 << 20));
  cmd->add_flag("--gather", args->gather,
                "Parallel run: write one file on rank 0 (any format) instead of .pvtu pieces");
  cmd->add_flag("--fixed-ghost", args->fixed_ghost,
                "Parallel run (2D): a fixed 3-cell margin around every inclusion instead of the level-aware one");
  cmd->add_option("--ghost-closure-rounds", args->closure_rounds,
                  "Comparison: chain the ghost region through R rounds of nearby inclusions (0, the default, "
                  "is exact because inclusion levels are settled beforehand; -1: the full closure)")
      ->group("");
  cmd->add_option("--ghost-cubes", args->ghost_cubes,
                  "Comparison (3D): a ghost of this many coarse cubes instead of the one derived from the "
                  "kernel's reach (lib/parallel/README.md); too few break partition invariance")
      ->check(CLI::Range(0.0, 1e6))
      ->group("");
  cmd->callback([args, &flags, &exit_code] {
    if (parallel::world().size() > 1 || args->partitions > 0) {
      // Every rank reads the scene's descriptors (STL triangles later, where needed).
      const auto start = std::chrono::steady_clock::now();
      geometry::SceneDesc scene;
      parallel::run_collectively(parallel::world(), [&] {
        scene = io::read_scene(args->scene, io::ReadSceneOptions{.load_stl = false, .probe_stl = false});
      });
      if (scene.dimension == 3)
        run_parallel<3>(*args, flags, exit_code, std::move(scene), start);
      else
        run_parallel<2>(*args, flags, exit_code, std::move(scene), start);
      return;
    }
    const auto start = std::chrono::steady_clock::now();
    io::mesh_format_of(args->output);  // fail on a bad extension before any work
    progress(flags, "reading the scene");
    const geometry::SceneDesc scene = io::read_scene(args->scene);
    if (scene.dimension == 3)
      run_sequential<3>(*args, scene, flags, exit_code, start);
    else
      run_sequential<2>(*args, scene, flags, exit_code, start);
  });
}

}  // namespace cisamr::app
