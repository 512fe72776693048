// cisamr mesh SCENE -o OUT.{vtu,msh,inp,mesh} [--report R.json] [--svg PICTURE.svg]
#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "geometry/oracle2.hpp"
#include "io/atomic_file.hpp"
#include "io/mesh_io.hpp"
#include "io/mesh_svg.hpp"
#include "io/scene_io.hpp"
#include "mesh/metrics.hpp"
#include "pipeline/pipeline.hpp"
#include "quality/quality.hpp"

namespace cisamr::app {
namespace {

struct MeshArgs {
  std::string scene, output, report, svg;
  double alpha = 0.5;
  int extra_levels = 3;
  double bound = 0;  // 0: the dimension's bound
};

void progress(const GlobalFlags& flags, const char* what) {
  if (show_progress(flags)) std::fprintf(stderr, "cisamr: %s\n", what);
}

nlohmann::json report_json(const MeshArgs& args, const geometry::SceneDesc& scene, const mesh::Mesh2& m,
                           const pipeline::Stats& stats, const quality::AspectStats& aspect, double total_seconds) {
  nlohmann::json j;
  j["format"] = "cisamr-report/1";
  j["scene"] = args.scene;
  j["output"] = args.output;
  j["dimension"] = 2;
  j["nodes"] = m.node_count();
  j["elements"] = m.cell_count();
  // Per-phase element counts and measures.
  nlohmann::json phases = nlohmann::json::array();
  for (const auto& ph : scene.phases) {
    std::size_t count = 0;
    double area = 0;
    for (std::size_t c = 0; c < m.cell_count(); ++c)
      if (m.cell_phase[c] == ph.id) {
        ++count;
        const LocalId* n = m.cell(c);
        area += mesh::signed_area(m.point(n[0]), m.point(n[1]), m.point(n[2]));
      }
    phases.push_back({{"id", ph.id}, {"name", ph.name}, {"void", ph.is_void}, {"elements", count}, {"measure", area}});
  }
  j["phases"] = phases;
  j["aspect_ratio"] = {{"max", aspect.max},
                       {"mean", aspect.mean},
                       {"bound", aspect.bound},
                       {"above_bound", aspect.above_bound},
                       {"bin_edges", aspect.bin_edges},
                       {"histogram", aspect.histogram},
                       {"min_angle_deg", aspect.min_angle_deg},
                       {"max_angle_deg", aspect.max_angle_deg}};
  j["algorithm"] = {{"alpha", args.alpha},
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
  nlohmann::json times = nlohmann::json::object();
  for (const auto& [name, seconds] : stats.times.phases())
    times[name] = {{"min", seconds}, {"max", seconds}, {"mean", seconds}};
  j["timings_s"] = times;
  j["total_s"] = total_seconds;
  j["ranks"] = 1;
  j["partitions"] = nlohmann::json::array({{{"partition", 0}, {"rank", 0}, {"elements", m.cell_count()}}});
  return j;
}

}  // namespace

void add_mesh_command(CLI::App& app, GlobalFlags& flags, int& exit_code) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* cmd = app.add_subcommand("mesh", "Mesh a scene (cisamr-scene/1 JSON) into a conforming simplex mesh");
  cmd->add_option("scene", args->scene, "Scene file")->required();
  cmd->add_option("-o,--output", args->output, "Output mesh: .vtu, .msh (Gmsh 4.1), .inp (Abaqus) or .mesh (Medit)")
      ->required();
  cmd->add_option("--report", args->report, "Write a JSON report (counts, per-phase measure, aspect ratios, timings)");
  cmd->add_option("--svg", args->svg, "Write a picture of the 2D mesh coloured by phase");
  cmd->add_option("--alpha", args->alpha, "r-adaptivity snap threshold, fraction of the edge length")
      ->check(CLI::Range(0.05, 0.5));
  cmd->add_option("--extra-levels", args->extra_levels,
                  "Levels beyond the largest requested one that may separate close interfaces")
      ->check(CLI::Range(0, 10));
  cmd->add_option("--bound", args->bound, "Aspect-ratio bound for the exit status (default 3 in 2D, 5 in 3D)");
  cmd->callback([args, &flags, &exit_code] {
    const auto start = std::chrono::steady_clock::now();
    io::mesh_format_of(args->output);  // fail on a bad extension before any work
    progress(flags, "reading the scene");
    const geometry::SceneDesc scene = io::read_scene(args->scene);
    if (scene.dimension != 2)
      throw InputError(args->scene, "dimension", "3D meshing is not available in this version (2D only)");
    progress(flags, "building the geometry oracle");
    const geometry::Oracle2 oracle(scene);
    pipeline::Options options;
    options.alpha = args->alpha;
    options.extra_levels = args->extra_levels;
    progress(flags, "meshing (SAMR, r-adaptivity, subdivision)");
    pipeline::Result2 result = pipeline::mesh2(oracle, options);
    const double bound = args->bound > 0 ? args->bound : 3.0;
    quality::AspectStats aspect;
    io::MeshWriteOptions write_options;
    {
      ScopedPhase timer(&result.stats.times, "quality");
      aspect = quality::aspect_statistics(result.mesh, bound);
    }
    progress(flags, "writing the mesh");
    {
      ScopedPhase timer(&result.stats.times, "write");
      io::write_mesh(args->output, result.mesh, scene.phases, write_options);
      if (!args->svg.empty()) io::write_mesh_svg(args->svg, result.mesh, scene);
    }
    const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!args->report.empty()) {
      io::AtomicFile file(args->report);
      file.write(report_json(*args, scene, result.mesh, result.stats, aspect, total).dump(2) + "\n");
      file.commit();
    }
    if (!flags.quiet)
      std::printf("%s: %zu nodes, %zu triangles, max aspect ratio %.3f (bound %.1f), %.3f s\n", args->output.c_str(),
                  result.mesh.node_count(), result.mesh.cell_count(), aspect.max, bound, total);
    if (flags.verbose)
      for (const auto& [name, seconds] : result.stats.times.phases()) std::printf("  %-10s %8.3f s\n", name.c_str(), seconds);
    if (result.stats.collapsed > 0 && !flags.quiet)
      std::printf("%lld quads held a feature below the finest resolution (a tangency, a thin gap or a wedge "
                  "sharper than the bound allows); collapsed with nodes at most %.3g from the phases they serve\n",
                  static_cast<long long>(result.stats.collapsed), result.stats.max_collapse_deviation);
    if (result.stats.unresolved > 0)
      std::fprintf(stderr, "cisamr: warning: %lld quads below the finest level's resolution\n",
                   static_cast<long long>(result.stats.unresolved));
    exit_code = aspect.above_bound > 0 ? 3 : 0;
  });
}

}  // namespace cisamr::app
