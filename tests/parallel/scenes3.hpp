#pragma once
// 3D scenes and runs shared by the serial and the MPI tests of lib/parallel.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/comm.hpp"
#include "geometry/oracle.hpp"
#include "geometry/scene.hpp"
#include "io/scene_io.hpp"
#include "io/stl_io.hpp"
#include "parallel/checksum.hpp"
#include "parallel/distributed.hpp"
#include "parallel/merge.hpp"
#include "pipeline/effective_levels.hpp"
#include "pipeline/pipeline.hpp"
#include "quality/quality.hpp"
#include "support/periodic_images.hpp"

namespace cisamr::parallel::testing {

// A small 3D scene (6 x 6 x 4 cubes of 0.25, levels 0) with inclusions of every analytic
// shape and an STL surface, spread so that partition corners fall inside some of them: a
// 3 x 3 x 2 grid of spheres, a rotated ellipsoid, a fibre (cylinder) crossing the whole
// domain, two overlapping same-phase spheres (a union), an octahedron from data/shapes.
// Its contacts (the STL surface is compared by its box) raise every inclusion to Lmax
// (effective_levels3): the tests mesh it with extra_levels = 1 (Lmax = 1) to keep it cheap.
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

// Portable pseudo-random doubles in [0, 1) (splitmix64: the same scene on every platform,
// unlike std:: distributions).
class Random3 {
 public:
  explicit Random3(std::uint64_t seed) : state_(seed) {}
  double next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  }

 private:
  std::uint64_t state_;
};

// Dense random spheres on nx × ny × nz cubes of h = 0.125, every inclusion at `levels`:
// radii 0.8-2.8 h of two phases, half of them placed next to an earlier one (0.1-0.8 of a
// cell of the level apart, or overlapping it when of the same phase: unions), the others
// anywhere; pairs that are no union stay 1.85 cells of the level apart, so the contact rule
// leaves every level as given (effective_levels3), which keeps the scene cheap while the
// guard refuses and collapses and face swaps happen everywhere, partition faces and
// corners included. The first sphere is clipped by a corner of the domain.
inline geometry::SceneDesc packed_scene3(std::uint64_t seed, int levels, int nx, int ny, int nz, int count) {
  using namespace geometry;
  SceneDesc s;
  s.source = "packed-scene-3d";
  s.dimension = 3;
  s.h = 0.125;
  s.levels = levels;
  s.domain_min = {0, 0, 0};
  s.domain_max = {nx * s.h, ny * s.h, nz * s.h};
  s.phases = {{1, "matrix", false}, {2, "particle", false}, {3, "fibre", false}};
  Random3 random(seed);
  const double cell = std::ldexp(s.h, -levels), gap = 1.85 * cell;
  struct Placed {
    Vec3 c;
    double r;
    int phase;
  };
  std::vector<Placed> placed;
  const auto fits = [&](const Placed& p) {
    for (const Placed& o : placed) {
      const double d = std::sqrt((p.c[0] - o.c[0]) * (p.c[0] - o.c[0]) + (p.c[1] - o.c[1]) * (p.c[1] - o.c[1]) +
                                 (p.c[2] - o.c[2]) * (p.c[2] - o.c[2]));
      const bool deep_union = p.phase == o.phase && d < p.r + o.r - 0.2 * std::min(p.r, o.r);
      if (!deep_union && d < p.r + o.r + gap) return false;
    }
    return true;
  };
  placed.push_back({{s.domain_max[0] - 0.02, s.domain_max[1] - 0.03, 0.04}, 0.22, 2});  // clipped by a corner
  for (int tries = 0; static_cast<int>(placed.size()) < count && tries < 200 * count; ++tries) {
    Placed p{{}, (0.8 + 2.0 * random.next()) * s.h, random.next() < 0.5 ? 2 : 3};
    if (random.next() < 0.5) {
      const Placed& o = placed[static_cast<std::size_t>(random.next() * static_cast<double>(placed.size()))];
      const double z = 2 * random.next() - 1, phi = 2 * M_PI * random.next(), rho = std::sqrt(1 - z * z);
      double d = o.r + p.r + gap + (0.1 + 0.7 * random.next()) * cell;
      if (p.phase == o.phase && random.next() < 0.4) d = o.r + p.r - 0.35 * std::min(o.r, p.r);  // a union
      p.c = {o.c[0] + d * rho * std::cos(phi), o.c[1] + d * rho * std::sin(phi), o.c[2] + d * z};
    } else {
      for (int a = 0; a < 3; ++a) p.c[a] = s.domain_max[a] * random.next();
    }
    if (fits(p)) placed.push_back(p);
  }
  for (const Placed& p : placed) s.inclusions.push_back({Sphere{p.c, p.r}, p.phase, levels});
  return s;
}

// The packed scene as a periodic RVE along every axis (even cell counts): the spheres near
// the faces wrap, and partitions touching a face see their window wrap. Spheres overlapping
// an image of another phase are dropped as the oracle names them.
inline geometry::SceneDesc periodic_packed_scene3(std::uint64_t seed, int levels, int nx, int ny, int nz, int count) {
  geometry::SceneDesc s = packed_scene3(seed, levels, nx, ny, nz, count);
  s.source = "periodic-packed-scene-3d";
  s.periodic = {true, true, true};
  cisamr::testing::drop_refused_images(s, [](const geometry::SceneDesc& scene) { const geometry::Oracle3 probe(scene); }, 400);
  return s;
}

// Level-0 spheres in the -x part (16 cubes), level-2 ones in the +x part (12 cubes), two
// cubes of matrix between them: a partition's box sees different levels beyond different
// faces, so its ghost differs by face (lib/parallel/README.md, "Ghost region (3D)").
inline geometry::SceneDesc mixed_level_scene3() {
  const geometry::SceneDesc coarse = packed_scene3(31, 0, 16, 12, 10, 60);
  const geometry::SceneDesc fine = packed_scene3(32, 2, 12, 12, 10, 40);
  geometry::SceneDesc s = coarse;
  s.source = "mixed-level-scene-3d";
  const double shift = 18 * s.h;
  s.domain_max[0] = shift + fine.domain_max[0];
  s.inclusions.clear();
  for (const geometry::Inclusion& inc : coarse.inclusions) {
    const auto& sphere = std::get<geometry::Sphere>(inc.shape);
    if (sphere.center[0] + sphere.radius < coarse.domain_max[0]) s.inclusions.push_back(inc);
  }
  for (geometry::Inclusion inc : fine.inclusions) {
    auto& sphere = std::get<geometry::Sphere>(inc.shape);
    sphere.center[0] += shift;
    if (sphere.center[0] - sphere.radius > shift) s.inclusions.push_back(inc);
  }
  return s;
}

// Contacts, unions, STL surfaces and the domain boundary at levels 0-2 (run with
// extra_levels = 1: Lmax = 3) on 12 × 12 × 8 cubes of h = 0.125: spheres of two phases
// touching at one point, a sphere a hundredth of a cell from another of its phase, two
// overlapping same-phase spheres, an STL octahedron overlapping a same-phase sphere (a
// union that pipeline::surface_unions decides from the triangles), an STL cube and a
// torus, spheres clipped by faces, an edge and a corner of the domain. The STL surfaces
// hold no triangles: the parallel mesher reads their files (run_sequential3 reads them
// for the whole-domain run).
inline geometry::SceneDesc contact_scene3() {
  using namespace geometry;
  SceneDesc s;
  s.source = "contact-scene-3d";
  s.dimension = 3;
  s.h = 0.125;
  s.levels = 0;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1.5, 1.5, 1.0};
  s.phases = {{1, "matrix", false}, {2, "particle", false}, {3, "fibre", false}};
  const auto sphere = [&](Vec3 c, double r, int phase, int levels) { s.inclusions.push_back({Sphere{c, r}, phase, levels}); };
  const auto stl = [&](const char* name, double scale, Vec3 at, int phase, int levels) {
    StlSurface t;
    t.file = std::string(CISAMR_SOURCE_DIR "/data/shapes/") + name;
    t.scale = scale;
    t.translate = at;
    s.inclusions.push_back({t, phase, levels});
  };
  // [0], [1]: tangent, different phases (dyadic: the contact is exact), level 0.
  sphere({0.3125, 0.3125, 0.375}, 0.1875, 2, 0);
  sphere({0.625, 0.3125, 0.375}, 0.125, 3, 0);
  // [2]: 0.01 cells from [0], same phase, level 1.
  sphere({0.3125, 0.3125 + 0.1875 + 0.15 + 0.00125, 0.375}, 0.15, 2, 1);
  // [3], [4]: a same-phase union, levels 1 and 2.
  sphere({1.05, 0.35, 0.4}, 0.17, 3, 1);
  sphere({1.2, 0.45, 0.5}, 0.12, 3, 1);
  // [5], [6]: an STL octahedron overlapping a sphere of its phase (a union), level 1.
  stl("octahedron.stl", 0.2, {0.45, 1.05, 0.5}, 2, 1);
  sphere({0.6, 1.1, 0.55}, 0.1, 2, 1);
  // [7]: an STL cube, level 0; [8]: a torus, level 2.
  stl("cube.stl", 0.22, {1.05, 1.0, 0.35}, 2, 0);
  stl("torus.stl", 0.12, {0.95, 0.9, 0.78}, 3, 1);
  // [9], [10], [11]: clipped by the face x = 0, the edge y = 0, z = 0, the corner (1.5, 1.5, 1).
  sphere({0.02, 0.8, 0.45}, 0.14, 3, 0);
  sphere({0.8, 0.03, 0.02}, 0.16, 2, 1);
  sphere({1.47, 1.46, 0.97}, 0.2, 2, 0);
  return s;
}

// The options the contact scene is meshed with (Lmax = 3).
inline pipeline::Options contact_options3() {
  pipeline::Options o;
  o.extra_levels = 1;
  return o;
}

// The scene with every STL surface's triangles read (as the sequential mesher reads it).
inline geometry::SceneDesc with_triangles(geometry::SceneDesc scene) {
  std::vector<std::int32_t> all(scene.inclusions.size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = static_cast<std::int32_t>(k);
  io::load_stl_surfaces(scene, all);
  return scene;
}

struct RunOutcome3 {
  bool failed = false;  // the mesher threw (the sequential and parallel runs must agree)
  std::string error;
  mesh::Mesh3 mesh;     // gathered on rank 0 (parallel) or the sequential mesh
  std::uint64_t checksum = 0;
  pipeline::Counters<3> counters;  // sequential: the whole-domain run's counters
  DistributedMesh3 distributed;
};

// The sequential mesher (pipeline::mesh, what `cisamr mesh` runs without
// --partitions), STL files read first.
inline RunOutcome3 run_sequential3(const geometry::SceneDesc& scene, const pipeline::Options& options = {}) {
  RunOutcome3 out;
  try {
    const geometry::Oracle3 oracle(with_triangles(scene));
    pipeline::Result<3> r = pipeline::mesh(oracle, options);
    out.mesh = std::move(r.mesh);
    out.counters = r.counters;
    out.checksum = mesh_checksum3(out.mesh);
  } catch (const std::exception& e) {
    out.failed = true;
    out.error = e.what();
  }
  return out;
}

// Collective: every rank must call it with the same arguments.
inline RunOutcome3 run_parallel3(const Comm& comm, const geometry::SceneDesc& scene, int partitions,
                                 const GhostRule& rule = {}, const pipeline::Options& pipeline = {},
                                 bool exchange_near_faces = true) {
  RunOutcome3 out;
  MeshOptions options;
  options.partitions = partitions;
  options.ghost = rule;
  options.pipeline = pipeline;
  options.exchange_near_faces = exchange_near_faces;
  try {
    out.distributed = mesh_distributed<3>(comm, scene, options);
    out.checksum = mesh_checksum3(comm, out.distributed.piece.mesh);
    out.mesh = gather_mesh<3>(comm, out.distributed.piece);
  } catch (const std::exception& e) {
    out.failed = true;
    out.error = e.what();
  }
  return out;
}

// The scenes every invariance test runs (serial and MPI), with their options: dense packed
// spheres at levels 0, 1 and 2, the contact scene (tangent spheres, STL surfaces, unions,
// the domain boundary), and the corner scene (every analytic shape) at Lmax = 1.
struct Case3 {
  std::string name;
  geometry::SceneDesc scene;
  pipeline::Options options;
};
inline std::vector<Case3> invariance_cases3() {
  pipeline::Options lmax1;
  lmax1.extra_levels = 1;
  return {{"packed-level0", packed_scene3(11, 0, 32, 32, 16, 300), {}},
          {"packed-level1", packed_scene3(12, 1, 16, 16, 12, 80), {}},
          {"packed-level2", packed_scene3(13, 2, 10, 10, 8, 30), {}},
          {"periodic-level0", periodic_packed_scene3(14, 0, 20, 20, 8, 15), {}},
          {"contact", contact_scene3(), contact_options3()},
          {"corner", corner_scene3(), lmax1}};
}

// A ghost of `cubes` coarse cubes (too small ones break invariance).
inline GhostRule margin3(double cubes) {
  GhostRule rule;
  rule.margin3_cubes = cubes;
  return rule;
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
