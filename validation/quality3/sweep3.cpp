// sweep3 [scenes] [first_seed] [h]: meshes seeded random 3D scenes (spheres, rotated
// ellipsoids up to 5:1, fibres, some clipped by the box) and prints the aspect-ratio
// picture of the 3D mesher: worst value by origin (closure tables, leaves kept whole,
// sub-tets of cut leaves), tets above the bound 5, face swaps, dihedral extremes, and the
// seed of the worst scene. A tool for working on the 3D quality rules; the property
// tests in tests/pipeline3 assert the bound.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <string>
#include <cstdlib>

#include "geometry/oracle.hpp"
#include "pipeline/pipeline.hpp"
#include "quality/quality.hpp"

using namespace cisamr;
using namespace cisamr::geometry;

namespace {

Rotation3 random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  double q[4], len = 0;
  for (double& x : q) x = n(rng), len += x * x;
  len = std::sqrt(len);
  for (double& x : q) x /= len;
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  return quaternion_rotation(w, x, y, z);
}

SceneDesc random_scene(std::uint64_t seed, double h) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  SceneDesc s;
  s.dimension = 3;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1, 1, 1};
  s.h = h;
  s.levels = static_cast<int>(seed % 2);
  s.phases = {{1, "matrix", false}, {2, "particle", false}};
  s.matrix_phase = 1;
  const int count = 1 + static_cast<int>(u(rng) * 3);
  for (int i = 0; i < count; ++i) {
    const Vec3 c{0.15 + 0.7 * u(rng), 0.15 + 0.7 * u(rng), 0.15 + 0.7 * u(rng)};
    double kind = u(rng);
    if (std::getenv("SPHERES_ONLY")) kind = 0;
    Shape shape;
    if (kind < 0.4) {
      shape = Sphere{c, 0.08 + 0.2 * u(rng)};
    } else if (kind < 0.8) {
      const double a = 0.1 + 0.2 * u(rng);
      shape = Ellipsoid{c, {a, a / (1 + 4 * u(rng)), a / (1 + 4 * u(rng))}, random_rotation(rng)};
    } else {
      const Vec3 d{u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5};
      const double len = 0.2 + 0.4 * u(rng);
      shape = Cylinder{{c[0] - len * d[0], c[1] - len * d[1], c[2] - len * d[2]},
                       {c[0] + len * d[0], c[1] + len * d[1], c[2] + len * d[2]},
                       0.05 + 0.08 * u(rng)};
    }
    s.inclusions.push_back({shape, 2, s.levels});
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const int scenes = argc > 1 ? std::atoi(argv[1]) : 50;
  const std::uint64_t first = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 1;
  const double h = argc > 3 ? std::atof(argv[3]) : 0.1;
  double worst = 0, worst_kept = 0, worst_split = 0, worst_closure = 0, min_angle = 180, max_angle = 0;
  std::uint64_t worst_seed = 0;
  long long tets = 0, above = 0, kept_above = 0, split_above = 0, inverted = 0, swaps = 0;
  long long snapped = 0, refused = 0, collapsed = 0, guarded = 0, combinations = 0, unresolved = 0;
  double max_deviation = 0, deviation_cells = 0;
  int bad_scenes = 0;
  long long above3 = 0, above4 = 0, nonconforming = 0;
  std::map<std::string, double> phase_seconds;
  for (int i = 0; i < scenes; ++i) {
    const std::uint64_t seed = first + static_cast<std::uint64_t>(i);
    const SceneDesc scene = random_scene(seed, h);
    const Oracle3 oracle(scene);
    pipeline::Options options;
    if (const char* a = std::getenv("SWEEP_ALPHA")) options.alpha = std::atof(a);
    if (const char* a = std::getenv("SWEEP_ALPHA_DIAGONAL")) options.alpha_diagonal3 = std::atof(a);
    if (const char* a = std::getenv("SWEEP_BOUND")) options.bound3 = std::atof(a);
    if (const char* a = std::getenv("SWEEP_CANDIDATES")) options.max_candidates3 = std::atoi(a);
    if (const char* a = std::getenv("SWEEP_SWAP")) options.swap_trigger3 = std::atof(a);
    const auto r = pipeline::mesh(oracle, options);
    for (const auto& [name, sec] : r.times.phases()) phase_seconds[name] += sec;
    {
      const Box3 domain{{scene.domain_min[0], scene.domain_min[1], scene.domain_min[2]},
                        {scene.domain_max[0], scene.domain_max[1], scene.domain_max[2]}};
      const double volume = (domain.max[0] - domain.min[0]) * (domain.max[1] - domain.min[1]) * (domain.max[2] - domain.min[2]);
      const auto c = quality::check_conformity(r.mesh, domain, volume, false);
      if (!c.ok) {
        ++nonconforming;
        std::printf("seed %llu not conforming: open %zu hanging %zu inverted %zu nonmanifold %zu orientation %zu measure %.3g %s\n",
                    static_cast<unsigned long long>(seed), c.open_facets_inside, c.hanging_nodes, c.inverted_cells,
                    c.non_manifold_facets, c.mismatched_orientation_facets, c.measure_error,
                    c.examples.empty() ? "" : c.examples[0].c_str());
      }
    }
    const auto a = quality::aspect_statistics<3>(r.mesh, 5.0);
    tets += static_cast<long long>(r.mesh.cell_count());
    for (std::size_t b = 0; b + 1 < a.bin_edges.size(); ++b) {
      if (a.bin_edges[b] >= 3.0 - 1e-9) above3 += static_cast<long long>(a.histogram[b]);
      if (a.bin_edges[b] >= 4.0 - 1e-9) above4 += static_cast<long long>(a.histogram[b]);
    }
    above += static_cast<long long>(a.above_bound);
    bad_scenes += a.above_bound > 0 ? 1 : 0;
    kept_above += r.counters.kept_above_5;
    split_above += r.counters.split_above_5;
    inverted += r.counters.inverted;
    swaps += r.counters.face_swaps;
    snapped += r.counters.snapped_nodes, refused += r.counters.refused_nodes, collapsed += r.counters.collapsed_nodes;
    guarded += r.counters.guarded_leaves, combinations += r.counters.guard_combinations, unresolved += r.counters.unresolved;
    max_deviation = std::max(max_deviation, r.counters.max_collapse_deviation);
    deviation_cells = std::max(deviation_cells, r.counters.max_collapse_deviation / (h / (1 << scene.levels)));
    worst_kept = std::max(worst_kept, r.counters.worst_kept);
    worst_split = std::max(worst_split, r.counters.worst_split);
    worst_closure = std::max(worst_closure, r.counters.worst_closure);
    min_angle = std::min(min_angle, a.min_angle_deg);
    max_angle = std::max(max_angle, a.max_angle_deg);
    if (a.max > worst) worst = a.max, worst_seed = seed;
    if (argc > 4 && a.above_bound > 0) {
      std::printf("seed %llu (levels %d): %zu tets, max %.3f, above 5: %zu, refused %lld of %lld snaps:",
                  static_cast<unsigned long long>(seed), scene.levels, r.mesh.cell_count(), a.max, a.above_bound,
                  static_cast<long long>(r.counters.refused_nodes), static_cast<long long>(r.counters.snapped_nodes));
      for (const auto& inc : scene.inclusions) {
        if (const auto* sp = std::get_if<Sphere>(&inc.shape)) std::printf(" sphere r %.3f;", sp->radius);
        if (const auto* e = std::get_if<Ellipsoid>(&inc.shape))
          std::printf(" ellipsoid %.3f %.3f %.3f;", e->semi_axes[0], e->semi_axes[1], e->semi_axes[2]);
        if (const auto* c = std::get_if<Cylinder>(&inc.shape)) std::printf(" cylinder r %.3f;", c->radius);
      }
      std::printf("\n");
    }
  }
  std::printf("%d scenes, %lld tets, worst %.3f (seed %llu), above 5: %lld tets in %d scenes (kept %lld, split %lld)\n",
              scenes, tets, worst, static_cast<unsigned long long>(worst_seed), above, bad_scenes, kept_above,
              split_above);
  std::printf("worst by origin: closure %.3f, kept %.3f, split %.3f; inverted %lld; face swaps %lld; dihedral "
              "%.2f..%.2f deg\n",
              worst_closure, worst_kept, worst_split, inverted, swaps, min_angle, max_angle);
  std::printf("non-conforming meshes: %lld\n", nonconforming);
  std::printf("tets above 3: %lld (%.4f %%), above 4: %lld (%.4f %%)\n", above3, 100.0 * above3 / tets, above4, 100.0 * above4 / tets);
  std::printf("phases:");
  for (const auto& [name, sec] : phase_seconds) std::printf(" %s %.2f s", name.c_str(), sec);
  std::printf("\n");
  std::printf("guard: %lld snapped, %lld refused a first option, %lld collapsed (max deviation %.3g = %.3f cells); "
              "%lld leaves checked, %lld combinations; unresolved leaves %lld\n",
              snapped, refused, collapsed, max_deviation, deviation_cells, guarded, combinations, unresolved);
  return 0;
}
