#pragma once
// 3D scenes and runs shared by the serial and the MPI tests of lib/parallel.
#include <cmath>
#include <string>
#include <vector>

#include "core/comm.hpp"
#include "geometry/oracle3.hpp"
#include "geometry/scene.hpp"
#include "io/stl_io.hpp"
#include "parallel/checksum.hpp"
#include "parallel/distributed.hpp"
#include "parallel/merge.hpp"
#include "pipeline/effective_levels.hpp"
#include "pipeline/pipeline3.hpp"
#include "quality/quality.hpp"

namespace cisamr::parallel::testing {

// A small 3D scene (6 x 6 x 4 cubes of 0.25, levels 0: one finer inclusion would raise
// every level, the spread of effective_levels3 reaches 8 cells; levels are covered by
// the data example) with inclusions of every analytic shape
// and an STL surface, spread so that partition corners fall inside some of them: a 3 x 3
// x 2 grid of spheres, a rotated ellipsoid, a fibre (cylinder) crossing
// the whole domain, two overlapping same-phase spheres (a union), an octahedron from
// data/shapes.
inline geometry::SceneDesc corner_scene3() {
  using namespace geometry;
  SceneDesc s;
  s.source = "corner-scene-3d";
  s.dimension = 3;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1.5, 1.5, 1.0};
  s.h = 0.25;
  s.levels = 0;
  s.phases = {{1, "matrix", false}, {2, "particle", false}, {3, "fibre", false}};
  const auto add = [&](Shape shape, int phase, int levels) {
    Inclusion inc;
    inc.shape = std::move(shape);
    inc.phase = phase;
    inc.levels = levels;
    s.inclusions.push_back(std::move(inc));
  };
  // inclusions[0..17]: spheres on a 3 x 3 x 2 grid, radius 0.16-0.22.
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        const Vec3 c{0.27 + 0.49 * i + 0.013 * j, 0.26 + 0.5 * j + 0.011 * k, 0.26 + 0.49 * k + 0.017 * i};
        add(Sphere{c, 0.16 + 0.02 * ((i + 2 * j + k) % 4)}, 2, 0);
      }
  // inclusions[18]: a rotated ellipsoid.
  Ellipsoid e;
  e.center = {0.75, 0.52, 0.5};
  e.semi_axes = {0.2, 0.08, 0.06};
  e.rotation = {{{0.8, -0.6, 0}, {0.6, 0.8, 0}, {0, 0, 1}}};
  add(e, 2, 0);
  // inclusions[19]: a fibre across the domain (the particles' phase: it crosses some).
  add(Cylinder{{-0.1, 0.1, 0.9}, {1.6, 1.4, 0.62}, 0.06}, 2, 0);
  // inclusions[20]: overlapping the sphere inclusions[4] (centre ≈ (0.773, 0.763, 0.277)):
  // one same-phase union.
  add(Sphere{{0.95, 0.85, 0.3}, 0.12}, 2, 0);
  // inclusions[21]: an STL octahedron. (Contacts of phases, rule R2, are left to the
  // effective_levels3 tests: in a scene this small they would raise every level.)
  StlSurface stl;
  stl.file = CISAMR_SOURCE_DIR "/data/shapes/octahedron.stl";
  stl.triangles = io::read_stl(stl.file);
  stl.scale = 0.15;
  stl.translate = {1.24, 0.3, 0.74};
  add(stl, 2, 0);
  return s;
}

struct RunOutcome3 {
  bool failed = false;  // the mesher threw (the sequential and parallel runs must agree)
  std::string error;
  mesh::Mesh3 mesh;     // gathered on rank 0 (parallel) or the sequential mesh
  std::uint64_t checksum = 0;
  DistributedMesh3 distributed;
};

// The sequential mesher as mesh3 will be once it asks rule R1 for effective_levels3: the
// unchanged kernel on the whole domain with the levels the partitions use.
inline RunOutcome3 run_sequential3(const geometry::SceneDesc& scene) {
  RunOutcome3 out;
  try {
    const geometry::Oracle3 oracle(scene);
    const pipeline::Options options;
    const grid::Lattice3 lattice = pipeline::make_lattice3(oracle, options);
    const std::vector<int> levels = pipeline::effective_levels3(scene, lattice);
    out.mesh = pipeline::run3(oracle, lattice, lattice.whole_domain(), 0, options, 0, levels).mesh;
    out.checksum = mesh_checksum3(out.mesh);
  } catch (const std::exception& e) {
    out.failed = true;
    out.error = e.what();
  }
  return out;
}

// Collective: every rank must call it with the same arguments.
inline RunOutcome3 run_parallel3(const Comm& comm, const geometry::SceneDesc& scene, int partitions,
                                 const GhostRule& rule = {}) {
  RunOutcome3 out;
  MeshOptions options;
  options.partitions = partitions;
  options.ghost = rule;
  try {
    out.distributed = mesh3_distributed(comm, scene, options);
    out.checksum = mesh_checksum3(comm, out.distributed.piece.mesh);
    out.mesh = gather_mesh<3>(comm, out.distributed.piece);
  } catch (const std::exception& e) {
    out.failed = true;
    out.error = e.what();
  }
  return out;
}

// Spheres whose inside meets four or more partition boxes: they straddle an edge or a
// corner where several boxes meet.
inline int straddled_corners3(const DistributedMesh3& d, const geometry::SceneDesc& scene) {
  int count = 0;
  for (const auto& inc : scene.inclusions) {
    const auto* s = std::get_if<geometry::Sphere>(&inc.shape);
    if (s == nullptr) continue;
    int boxes = 0;
    for (const auto& p : d.partitions) {
      double gap = 0;  // distance from the centre to the box
      for (int a = 0; a < 3; ++a) {
        const double lo = scene.domain_min[a] + scene.h * static_cast<double>(p.lattice_min[a]);
        const double hi = scene.domain_min[a] + scene.h * static_cast<double>(p.lattice_max[a]);
        const double g = std::max({0.0, lo - s->center[a], s->center[a] - hi});
        gap += g * g;
      }
      boxes += gap < s->radius * s->radius;
    }
    count += boxes >= 4;
  }
  return count;
}

// Root only (the gathered mesh): the checks of DESIGN.md §2 across partition faces.
inline void expect_conforming3(const mesh::Mesh3& m, const geometry::SceneDesc& scene) {
  const Box3 domain{{scene.domain_min[0], scene.domain_min[1], scene.domain_min[2]},
                    {scene.domain_max[0], scene.domain_max[1], scene.domain_max[2]}};
  const double volume = (domain.max[0] - domain.min[0]) * (domain.max[1] - domain.min[1]) * (domain.max[2] - domain.min[2]);
  const auto conf = quality::check_conformity(m, domain, volume, false);
  EXPECT_TRUE(conf.ok) << (conf.examples.empty() ? "" : conf.examples.front());
  EXPECT_EQ(conf.duplicate_nodes, 0u);
  EXPECT_EQ(conf.hanging_nodes, 0u);
  EXPECT_EQ(conf.open_facets_inside, 0u);
}

}  // namespace cisamr::parallel::testing
