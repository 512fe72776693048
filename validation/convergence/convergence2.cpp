// Per-phase area error of the 2D mesher against the exact areas, for several background
// sizes h: shows the convergence of phase measures as h → 0 (DESIGN.md §2.3).
//
//   build/bin/convergence2 SCENE.json [h1 h2 ...]     (default: h, h/2, h/4 of the scene)
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "geometry/oracle.hpp"
#include "io/scene_io.hpp"
#include "mesh/metrics.hpp"
#include "pipeline/pipeline.hpp"

using namespace cisamr;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: convergence2 SCENE.json [h ...]\n");
    return 2;
  }
  geometry::SceneDesc scene = io::read_scene(argv[1]);
  std::vector<double> hs;
  for (int i = 2; i < argc; ++i) hs.push_back(std::atof(argv[i]));
  if (hs.empty()) hs = {scene.h, scene.h / 2, scene.h / 4};
  std::printf("%-10s %-12s %12s %16s %16s %12s\n", "h", "phase", "triangles", "mesh area", "exact area", "rel. error");
  std::vector<double> previous;
  for (double h : hs) {
    scene.h = h;
    const geometry::Oracle2 oracle(scene);
    const auto exact = oracle.phase_measures();
    const auto result = pipeline::mesh(oracle);
    const auto& m = result.mesh;
    std::vector<double> area(scene.phases.size(), 0);
    for (std::size_t c = 0; c < m.cell_count(); ++c) {
      const LocalId* n = m.cell(c);
      area[static_cast<std::size_t>(scene.phase_index(m.cell_phase[c]))] +=
          mesh::signed_area(m.point(n[0]), m.point(n[1]), m.point(n[2]));
    }
    std::vector<double> errors;
    for (std::size_t p = 0; p < scene.phases.size(); ++p) {
      if (scene.phases[p].is_void) {
        // Not meshed: its measure is the domain minus every meshed phase.
        double meshed = 0;
        for (std::size_t q = 0; q < area.size(); ++q) meshed += area[q];
        area[p] = (scene.domain_max[0] - scene.domain_min[0]) * (scene.domain_max[1] - scene.domain_min[1]) - meshed;
      }
      const double err = std::abs(area[p] - exact[p]) / exact[p];
      errors.push_back(err);
      std::printf("%-10g %-12s %12zu %16.9f %16.9f %12.3e", h, scene.phases[p].name.c_str(), m.cell_count(), area[p],
                  exact[p], err);
      if (!previous.empty() && err > 0) std::printf("   (÷%.1f)", previous[p] / err);
      std::printf("\n");
    }
    previous = errors;
  }
  return 0;
}
