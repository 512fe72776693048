// Benchmark of the 3D mesher against TetGen 1.5 (not a test): one scene, both meshers in
// one run, measured alike (lib/compare/compare3.hpp): tetrahedra, wall time,
// tets/s, peak memory (each mesher in a forked child), bytes per tet, volume errors,
// aspect-ratio distribution, dihedral angles, conformity; the time ratio TetGen / ours.
//
//   build-val/bin/bench_mesh3 [--scene FILE.json] [--h H] [--levels L] [--json OUT.json]
//                             [--repeat N] [--tetgen-max-volume A] [--match-runs K]
//                             [--match-tolerance T] [--surface-edge E]
//                             [--extra-levels E] [--no-tetgen] [--no-fork] [--no-conformity]
// Default scene: data/bench/spheres300.json (300 spheres, r 0.03-0.06, unit cube).
// --repeat N: N timed runs of each mesher, each in a fresh child; the median is reported.
// Without --tetgen-max-volume, TetGen's -a is matched to our count by up to K measured runs
// (default 4) until within T (default 0.05); the table prints the -a to reuse.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "io/scene_io.hpp"
#include "compare/compare3.hpp"

using namespace cisamr;

int main(int argc, char** argv) {
  std::string scene_file = std::string(CISAMR_SOURCE_DIR) + "/data/bench/spheres300.json", json_file;
  double h = 0, max_volume = 0, surface_edge = 0;
  int match_runs = -1, repeats = 1;
  double match_tolerance = -1;
  int levels = -1;
  compare::CompareOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--scene" && has_value) scene_file = argv[++i];
    else if (a == "--h" && has_value) h = std::atof(argv[++i]);
    else if (a == "--levels" && has_value) levels = std::atoi(argv[++i]);
    else if (a == "--json" && has_value) json_file = argv[++i];
    else if (a == "--tetgen-max-volume" && has_value) max_volume = std::atof(argv[++i]);
    else if (a == "--match-runs" && has_value) match_runs = std::atoi(argv[++i]);
    else if (a == "--match-tolerance" && has_value) match_tolerance = std::atof(argv[++i]);
    else if (a == "--extra-levels" && has_value) options.cisamr.extra_levels = std::atoi(argv[++i]);
    else if (a == "--repeat" && has_value) repeats = std::max(1, std::atoi(argv[++i]));
    else if (a == "--surface-edge" && has_value) surface_edge = std::atof(argv[++i]);
    else if (a == "--no-tetgen") options.run_tetgen = false;
    else if (a == "--no-fork") options.isolate = false;
    else if (a == "--no-conformity") options.check_conformity = false;
    else {
      std::fprintf(stderr, "bench_mesh3: unknown or incomplete option %s\n", a.c_str());
      return 2;
    }
  }
  try {
    geometry::SceneDesc scene = io::read_scene(scene_file);
    // Overrides: h is rounded so that it divides the domain's x extent exactly.
    if (h > 0) {
      const double extent = scene.domain_max[0] - scene.domain_min[0];
      scene.h = extent / std::max(1.0, std::round(extent / h));
    }
    if (levels >= 0) {
      scene.levels = levels;
      for (auto& inc : scene.inclusions) inc.levels = levels;
    }
    options.tetgen.max_volume = max_volume;
    options.tetgen.surface_edge = surface_edge;
    if (match_runs > 0) options.match_runs = match_runs;
    if (match_tolerance > 0) options.match_tolerance = match_tolerance;
    options.repeats = repeats;
    options.progress = [](const std::string& what) { std::fprintf(stderr, "bench_mesh3: %s\n", what.c_str()); };
    const compare::Comparison c = compare::compare3(scene, options);
    std::fputs(compare::comparison_table(c).c_str(), stdout);
    if (!json_file.empty()) {
      std::ofstream out(json_file);
      out << compare::comparison_json(c);
      if (!out) throw std::runtime_error("cannot write " + json_file);
    }
  } catch (const InputError& e) {
    std::fprintf(stderr, "bench_mesh3: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_mesh3: %s\n", e.what());
    return 1;
  }
  return 0;
}
