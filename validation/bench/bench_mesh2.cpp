// Benchmark of the 2D mesher (not a test): a scene with thousands of inclusions, meshed
// in-process; prints triangles per second (mesh phases only, no writing) and peak memory.
//
//   build/bin/bench_mesh2 [--inclusions N] [--cells-per-side C] [--levels L] [--repeat R]
//                         [--scene FILE.json]
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>

#include "geometry/oracle.hpp"
#include "io/scene_io.hpp"
#include "pipeline/pipeline.hpp"
#include "quality/quality.hpp"

using namespace cisamr;

namespace {

// Non-overlapping circles and ellipses of two phases, ~35% area fraction, on a grid hash.
geometry::SceneDesc make_scene(int inclusions, int cells_per_side, int levels, unsigned seed) {
  geometry::SceneDesc s;
  s.source = "bench";
  s.dimension = 2;
  const double L = cells_per_side;  // h = 1
  s.domain_min = {0, 0, 0};
  s.domain_max = {L, L, 0};
  s.h = 1;
  s.levels = levels;
  s.phases = {{1, "matrix", false}, {2, "particle", false}, {3, "fibre", false}};
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const double mean_r = std::sqrt(0.35 * L * L / (inclusions * M_PI));
  struct Disk { double x, y, r; };
  std::vector<Disk> placed;
  const double cell = 3 * mean_r;
  const int n = static_cast<int>(L / cell) + 1;
  std::vector<std::vector<int>> bucket(static_cast<std::size_t>(n * n));
  int attempts = 0;
  while (static_cast<int>(placed.size()) < inclusions && attempts < 200 * inclusions) {
    ++attempts;
    const double r = mean_r * (0.7 + 0.6 * u(rng));
    const double x = u(rng) * L, y = u(rng) * L;
    const int bi = static_cast<int>(x / cell), bj = static_cast<int>(y / cell);
    bool ok = true;
    for (int j = std::max(0, bj - 1); j <= std::min(n - 1, bj + 1) && ok; ++j)
      for (int i = std::max(0, bi - 1); i <= std::min(n - 1, bi + 1) && ok; ++i)
        for (int k : bucket[static_cast<std::size_t>(j * n + i)])
          if (std::hypot(x - placed[k].x, y - placed[k].y) < r + placed[k].r + 0.5) { ok = false; break; }
    if (!ok) continue;
    bucket[static_cast<std::size_t>(bj * n + bi)].push_back(static_cast<int>(placed.size()));
    placed.push_back({x, y, r});
    geometry::Inclusion inc;
    inc.levels = levels;
    if (placed.size() % 3 == 0) {
      inc.shape = geometry::Ellipse{{x, y}, {r, r * (0.5 + 0.5 * u(rng))}, u(rng) * M_PI};
      inc.phase = 3;
    } else {
      inc.shape = geometry::Circle{{x, y}, r};
      inc.phase = 2;
    }
    s.inclusions.push_back(inc);
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  int inclusions = 2000, cells = 800, levels = 2, repeat = 3;
  std::string scene_file;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--inclusions") inclusions = std::atoi(argv[i + 1]);
    else if (a == "--cells-per-side") cells = std::atoi(argv[i + 1]);
    else if (a == "--levels") levels = std::atoi(argv[i + 1]);
    else if (a == "--repeat") repeat = std::atoi(argv[i + 1]);
    else if (a == "--scene") scene_file = argv[i + 1];
    else { std::fprintf(stderr, "unknown option %s\n", a.c_str()); return 2; }
  }
  const geometry::SceneDesc scene = scene_file.empty() ? make_scene(inclusions, cells, levels, 42) : io::read_scene(scene_file);
  const auto t0 = std::chrono::steady_clock::now();
  const geometry::Oracle2 oracle(scene);
  const double oracle_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("scene: %zu inclusions, %g x %g, h = %g, levels = %d\n", scene.inclusions.size(),
              scene.domain_max[0] - scene.domain_min[0], scene.domain_max[1] - scene.domain_min[1], scene.h, scene.levels);
  std::printf("oracle (validation + AABB tree): %.3f s\n", oracle_s);
  double best = 1e300;
  pipeline::Result<2> result;
  for (int r = 0; r < repeat; ++r) {
    const auto t = std::chrono::steady_clock::now();
    result = pipeline::mesh(oracle);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    best = std::min(best, s);
    std::printf("run %d: %.3f s (", r + 1, s);
    for (const auto& [name, sec] : result.times.phases()) std::printf(" %s %.3f", name.c_str(), sec);
    std::printf(" )\n");
  }
  const auto aspect = quality::aspect_statistics(result.mesh, 3.0);
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  const double tri = static_cast<double>(result.mesh.cell_count());
  std::printf("triangles: %.0f, nodes: %zu, max aspect ratio %.3f, above 3: %zu, unresolved quads: %lld\n", tri,
              result.mesh.node_count(), aspect.max, aspect.above_bound, static_cast<long long>(result.counters.unresolved));
  std::printf("best of %d: %.3f s, %.2f M triangles/s (one core, writing excluded)\n", repeat, best, tri / best / 1e6);
  std::printf("peak memory (max RSS): %.1f MiB, %.0f bytes per triangle\n", ru.ru_maxrss / 1024.0,
              ru.ru_maxrss * 1024.0 / tri);
  return 0;
}
