#pragma once
// Scenes and checks shared by the serial and the MPI tests of lib/parallel.
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/comm.hpp"
#include "geometry/oracle.hpp"
#include "geometry/scene.hpp"
#include "parallel/checksum.hpp"
#include "parallel/distributed.hpp"
#include "parallel/merge.hpp"
#include "pipeline/pipeline.hpp"
#include "support/random_scenes.hpp"

namespace cisamr::parallel::testing {

// Inclusions everywhere (so that every partition corner of any N is straddled), of every
// 2D shape, with different levels: a long thin ellipse across many boxes, a chain of close
// circles whose levels differ (rule R4 carries the finest level along it, across boxes),
// overlapping same-phase circles (C0 corners), a void, shapes crossing the domain boundary.
inline geometry::SceneDesc corner_scene() {
  using namespace geometry;
  SceneDesc s;
  s.source = "corner-scene";
  s.dimension = 2;
  s.domain_min = {0, 0, 0};
  s.domain_max = {44, 36, 0};
  s.h = 1;
  s.levels = 1;
  s.phases = {{1, "matrix", false}, {2, "particle", false}, {3, "fibre", false}, {4, "pore", true}};
  const auto add = [&](Shape shape, int phase, int levels) {
    Inclusion inc;
    inc.shape = std::move(shape);
    inc.phase = phase;
    inc.levels = levels;
    s.inclusions.push_back(std::move(inc));
  };
  // inclusions[0..19]: a grid of circles (spacing 9 x 9), some box corner of every
  // partitioning lies in one of them. Levels 1 and 2.
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 5; ++i) {
      const double x = 4.3 + 9.0 * i + 0.37 * j, y = 4.1 + 9.0 * j + 0.23 * i;
      const double r = 1.1 + 0.3 * ((i * 3 + j) % 4);
      add(Circle{{x, y}, r}, 2, 1 + (i + 2 * j) % 2);
    }
  // inclusions[20]: long and thin across a few boxes, overlapping two circles (C0 corners).
  add(Ellipse{{9.1, 8.7}, {7.0, 0.7}, 0.4}, 2, 1);
  // inclusions[21]: crosses the domain boundary and overlaps a circle.
  add(Polygon{{{38.0, 30.0}, {45.5, 31.2}, {42.1, 37.5}, {37.2, 35.9}}}, 2, 2);
  // inclusions[22]: another phase 0.3 from circle 12 (rule R2), levels 3.
  add(Circle{{23.04 - 1.1 - 0.3 - 0.9, 22.56}, 0.9}, 3, 3);
  // inclusions[23]: a void at the domain corner.
  add(Circle{{43.5, 0.5}, 1.2}, 4, 1);
  return s;
}

// Sparse random scenes: circles and ellipses of radius 0.5-2.5 h with levels 0-3 on a
// 40 x 32 domain, some near pairs of different phases, some overlapping same-phase pairs;
// sparse enough that ghost regions load only part of the scene.
inline geometry::SceneDesc sparse_random_scene(unsigned seed) {
  using namespace geometry;
  std::mt19937_64 rng(seed);
  const auto uniform = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  SceneDesc s;
  s.source = "sparse-random-" + std::to_string(seed);
  s.dimension = 2;
  s.h = uniform(0, 1) < 0.5 ? 1.0 : 0.5;
  s.domain_min = {std::round(uniform(-4, 4)), std::round(uniform(-4, 4)), 0};
  s.domain_max = {s.domain_min[0] + 40 * s.h, s.domain_min[1] + 32 * s.h, 0};
  s.levels = 1;
  s.phases = {{1, "matrix", false}, {2, "particle", false}, {3, "fibre", false}};
  struct Disk { double x, y, r; int phase; };
  std::vector<Disk> placed;
  const int count = static_cast<int>(uniform(12, 22));
  for (int attempt = 0; attempt < 400 && static_cast<int>(placed.size()) < count; ++attempt) {
    const double r = uniform(0.5, 2.5) * s.h;
    const double x = uniform(s.domain_min[0] - r, s.domain_max[0] + r);
    const double y = uniform(s.domain_min[1] - r, s.domain_max[1] + r);
    const int phase = uniform(0, 1) < 0.7 ? 2 : 3;
    bool ok = true;
    for (const Disk& d : placed) {
      const double gap = std::hypot(x - d.x, y - d.y) - r - d.r;
      if (d.phase != phase ? gap < 0.15 * s.h : (gap < 2 * s.h && uniform(0, 1) < 0.8)) ok = false;
    }
    if (!ok) continue;
    placed.push_back({x, y, r, phase});
    Inclusion inc;
    if (uniform(0, 1) < 0.7)
      inc.shape = Circle{{x, y}, r};
    else
      inc.shape = Ellipse{{x, y}, {r, r * uniform(0.3, 1.0)}, uniform(0, 3.14)};
    inc.phase = phase;
    inc.levels = static_cast<int>(uniform(0, 3.99));
    s.inclusions.push_back(std::move(inc));
  }
  return s;
}

// Interfaces lying on the periodic planes: boxes with a side on x = 0 and y = 0 of a
// periodic domain, matrix across the period, a third phase at the corner; a disc across
// the y faces. The cells on the planes are made by the join of the min- and max-side
// facets, once, at the min face; the checker catches one of them removed.
inline geometry::SceneDesc periodic_plane_scene() {
  using namespace geometry;
  SceneDesc s;
  s.source = "periodic-plane-scene";
  s.dimension = 2;
  s.domain_min = {0, 0, 0};
  s.domain_max = {16, 12, 0};
  s.periodic = {true, true, false};
  s.h = 1;
  s.levels = 2;
  s.phases = {{1, "matrix", false}, {2, "box", false}, {3, "corner", false}};
  const auto add = [&](Shape shape, int phase) {
    Inclusion inc;
    inc.shape = std::move(shape);
    inc.phase = phase;
    inc.levels = 2;
    s.inclusions.push_back(std::move(inc));
  };
  add(Polygon{{{0, 3}, {3.5, 3}, {3.5, 7}, {0, 7}}}, 2);
  add(Polygon{{{0, 0}, {2, 0}, {2, 3}, {0, 3}}}, 3);  // meets box 2 along y = 3: triple points
  add(Circle{{9.3, 11.6}, 1.7}, 3);
  return s;
}

// Packed scenes like the 2D benchmark's (validation/bench/bench_parallel.sh): non-overlapping
// circles of two phases covering about `fraction` of an nx × ny domain (h = 1), radii
// 0.7-1.3 of the mean, gaps of at least `gap` cells, every inclusion at `levels`.
inline geometry::SceneDesc packed_scene2(unsigned seed, int levels, int nx, int ny, double fraction = 0.3,
                                         double mean_radius = 2.5, double gap = 0.5) {
  using namespace geometry;
  std::mt19937_64 rng(seed);
  const auto uniform = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  SceneDesc s;
  s.source = "packed-" + std::to_string(seed);
  s.dimension = 2;
  s.h = 1;
  s.domain_min = {0, 0, 0};
  s.domain_max = {static_cast<double>(nx), static_cast<double>(ny), 0};
  s.levels = levels;
  s.phases = {{1, "matrix", false}, {2, "particle", false}, {3, "fibre", false}};
  const int count = static_cast<int>(fraction * nx * ny / (std::numbers::pi * mean_radius * mean_radius));
  struct Disk { double x, y, r; };
  std::vector<Disk> placed;
  for (int attempt = 0; attempt < 200 * count && static_cast<int>(placed.size()) < count; ++attempt) {
    const double r = mean_radius * uniform(0.7, 1.3), x = uniform(0, nx), y = uniform(0, ny);
    bool ok = true;
    for (const Disk& d : placed) ok = ok && std::hypot(x - d.x, y - d.y) >= r + d.r + gap;
    if (!ok) continue;
    placed.push_back({x, y, r});
    Inclusion inc;
    inc.shape = Circle{{x, y}, r};
    inc.phase = 2 + static_cast<int>(placed.size() % 2);
    inc.levels = levels;
    s.inclusions.push_back(std::move(inc));
  }
  return s;
}

// Random scenes of the pipeline's property tests (every shape, voids, tangencies, tiny ones).
inline geometry::SceneDesc random_scene(unsigned seed) { return cisamr::testing::RandomScene2(seed).make(); }

struct RunOutcome {
  bool failed = false;  // the mesher threw (the sequential and parallel runs must agree)
  std::string error;
  mesh::Mesh2 mesh;     // gathered on rank 0 (parallel) or the sequential mesh
  std::uint64_t checksum = 0;
  DistributedMesh2 distributed;
};

inline RunOutcome run_sequential(const geometry::SceneDesc& scene, const pipeline::Options& options = {}) {
  RunOutcome out;
  try {
    const geometry::Oracle2 oracle(scene);
    out.mesh = pipeline::mesh(oracle, options).mesh;
    out.checksum = mesh_checksum2(out.mesh);
  } catch (const std::exception& e) {
    out.failed = true;
    out.error = e.what();
  }
  return out;
}

// Collective: every rank must call it with the same arguments.
inline RunOutcome run_parallel(const Comm& comm, const geometry::SceneDesc& scene, int partitions,
                               const GhostRule& rule, const pipeline::Options& pipeline = {}) {
  RunOutcome out;
  MeshOptions options;
  options.partitions = partitions;
  options.ghost = rule;
  options.pipeline = pipeline;
  try {
    out.distributed = mesh_distributed<2>(comm, scene, options);
    out.checksum = mesh_checksum2(comm, out.distributed.piece.mesh);
    out.mesh = gather_mesh2(comm, out.distributed.piece);
  } catch (const std::exception& e) {
    out.failed = true;
    out.error = e.what();
  }
  return out;
}

inline RunOutcome run_parallel(const Comm& comm, const geometry::SceneDesc& scene, int partitions,
                               bool level_aware = true) {
  GhostRule rule;
  rule.level_aware = level_aware;
  return run_parallel(comm, scene, partitions, rule);
}

// Do some inclusion's bounding box and the interior corners of the partition boxes meet?
inline int straddled_corners(const DistributedMesh2& d, const geometry::SceneDesc& scene) {
  int count = 0;
  for (const auto& p : d.partitions)
    for (int cx = 0; cx < 2; ++cx)
      for (int cy = 0; cy < 2; ++cy) {
        const double x = scene.domain_min[0] + scene.h * static_cast<double>(cx ? p.lattice_max[0] : p.lattice_min[0]);
        const double y = scene.domain_min[1] + scene.h * static_cast<double>(cy ? p.lattice_max[1] : p.lattice_min[1]);
        if (x <= scene.domain_min[0] || x >= scene.domain_max[0] || y <= scene.domain_min[1] || y >= scene.domain_max[1])
          continue;
        for (const auto& inc : scene.inclusions)
          if (const auto* c = std::get_if<geometry::Circle>(&inc.shape))
            if (std::hypot(x - c->center[0], y - c->center[1]) < c->radius) {
              ++count;
              break;
            }
      }
  return count;
}

}  // namespace cisamr::parallel::testing
