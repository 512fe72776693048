// cisamr compare SCENE --tetgen [--html R.html] [--json R.json]
// Meshes a 3D scene with our mesher and with TetGen 1.5 (lib/compare) and prints both
// side by side: tetrahedra, time, memory, volume errors, aspect-ratio distribution.
// The same code as validation/bench/bench_mesh3. 2D scenes: exit 2 (3D only). A binary
// built without TetGen (CISAMR_WITH_TETGEN=OFF) accepts the same options and exits 2.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/scene_io.hpp"
#ifdef CISAMR_WITH_TETGEN
#include "compare/compare3.hpp"
#endif

namespace cisamr::app {
namespace {

struct CompareArgs {
  std::string scene, html, json;
  bool tetgen = false;
  double max_volume = 0;     // 0: matched to our tetrahedron count
  double quality = 1.4;      // TetGen -q radius-edge ratio
  double surface_edge = 0;   // 0: h / 2^levels
  bool in_process = false;
  bool no_conformity = false;
};

}  // namespace

void add_compare_command(CLI::App& app, GlobalFlags& flags, int& exit_code) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "Mesh a 3D scene with cisamr and with a reference mesher (TetGen) and compare them side by side");
  cmd->add_option("scene", args->scene, "Scene file (cisamr-scene/1, 3D: spheres and ellipsoids)")->required();
  cmd->add_flag("--tetgen", args->tetgen, "Compare with TetGen 1.5 (-pq1.4a...A)")->required();
  cmd->add_option("--html", args->html, "Write the comparison as a self-contained HTML page")->check(output_path());
  cmd->add_option("--json", args->json, "Write the comparison as JSON (cisamr-compare/1)")->check(output_path());
  cmd->add_option("--tetgen-max-volume", args->max_volume,
                  "TetGen's -a bound (default: chosen by two pilot runs to match our tetrahedron count)")
      ->check(number_in(1e-300, 1e300));
  cmd->add_option("--tetgen-quality", args->quality, "TetGen's -q radius-edge bound")
      ->check(number_in(1, 100))
      ->capture_default_str();
  cmd->add_option("--surface-edge", args->surface_edge,
                  "Edge length of TetGen's inclusion surfaces (default h / 2^levels, our interface size)")
      ->check(number_in(1e-300, 1e300));
  cmd->add_flag("--in-process", args->in_process,
                "Run both meshers in this process (default: each in a child process, for clean memory figures)");
  cmd->add_flag("--no-conformity", args->no_conformity, "Skip the conformity check of both meshes");
  cmd->callback([args, &flags, &exit_code] {
#ifndef CISAMR_WITH_TETGEN
    throw InputError("--tetgen", "", "this cisamr was built without TetGen (configure with -DCISAMR_WITH_TETGEN=ON)");
#else
    for (const std::string* out : {&args->json, &args->html})  // before both meshers run
      if (!out->empty()) io::check_writable(*out);
    const geometry::SceneDesc scene = io::read_scene(args->scene);
    if (scene.dimension != 3)
      throw InputError(args->scene, "dimension",
                       "cisamr compare is 3D only (this scene is " + std::to_string(scene.dimension) + "D)");
    compare::CompareOptions options;
    options.tetgen.max_volume = args->max_volume;
    options.tetgen.radius_edge_ratio = args->quality;
    options.tetgen.surface_edge = args->surface_edge;
    options.isolate = !args->in_process;
    options.check_conformity = !args->no_conformity;
    if (show_progress(flags))
      options.progress = [](const std::string& what) { std::fprintf(stderr, "cisamr: %s\n", what.c_str()); };
    const compare::Comparison c = compare::compare3(scene, options);
    if (!args->json.empty()) write_text_file(args->json, compare::comparison_json(c));
    if (!args->html.empty()) write_text_file(args->html, compare::comparison_html(c));
    if (!flags.quiet) std::fputs(compare::comparison_table(c).c_str(), stdout);
    exit_code = 0;
#endif
  });
}

}  // namespace cisamr::app
