// The 3D mesher (pipeline::mesh3) on analytic scenes: conformity, volume, phase fidelity,
// every tetrahedron within the aspect-ratio bound 5, and the distribution (printed; see
// lib/pipeline/README.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <cstdio>
#include <string>

#include "geometry/oracle.hpp"
#include "mesh/metrics.hpp"
#include "pipeline/pipeline.hpp"
#include "quality/quality.hpp"

using namespace cisamr;
using namespace cisamr::geometry;

namespace {

SceneDesc unit_box(double h, int levels) {
  SceneDesc s;
  s.dimension = 3;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1, 1, 1};
  s.h = h;
  s.levels = levels;
  s.phases = {{1, "matrix", false}, {2, "fiber", false}};
  s.matrix_phase = 1;
  return s;
}

Rotation3 rotation_xyz(double a, double b, double c) {
  const double ca = std::cos(a), sa = std::sin(a), cb = std::cos(b), sb = std::sin(b), cc = std::cos(c),
               sc = std::sin(c);
  // Rz(c)·Ry(b)·Rx(a)
  return {{{cc * cb, cc * sb * sa - sc * ca, cc * sb * ca + sc * sa},
           {sc * cb, sc * sb * sa + cc * ca, sc * sb * ca - cc * sa},
           {-sb, cb * sa, cb * ca}}};
}

constexpr double kBound = 5.0;  // DESIGN.md §2.2: every tetrahedron, no exception

struct Outcome {
  pipeline::Result<3> result;
  quality::AspectStats aspect;
  double inclusion_volume_error = 0;
};

// Meshes the scene and checks the invariants. `interior`: every inclusion lies inside the box
// and is smooth, so the snapping guard has no reason to collapse a node (radapt/README.md).
Outcome mesh_and_check(const std::string& name, const SceneDesc& scene, double volume_tolerance, bool interior = true) {
  const Oracle3 oracle(scene);
  Outcome out{pipeline::mesh(oracle), {}};
  const mesh::Mesh3& m = out.result.mesh;
  const pipeline::Counters<3>& s = out.result.counters;
  EXPECT_GT(m.cell_count(), 0u);
  EXPECT_EQ(s.unresolved, 0) << name;
  EXPECT_EQ(s.inverted, 0) << name;
  EXPECT_EQ(s.missing_crossings, 0) << name;

  // Conforming, volumes sum to the box.
  const Box3 domain{{0, 0, 0}, {1, 1, 1}};
  const auto conformity = quality::check_conformity(m, domain, 1.0, false);
  EXPECT_TRUE(conformity.ok) << name << ": " << (conformity.examples.empty() ? "" : conformity.examples[0])
                             << " (open inside " << conformity.open_facets_inside << ", hanging "
                             << conformity.hanging_nodes << ", inverted " << conformity.inverted_cells
                             << ", degenerate " << conformity.degenerate_cells << ", measure error "
                             << conformity.measure_error << ")";

  // Per-phase volume against the exact one; every node of a phase-k tet in phase k's closure.
  const std::vector<double> exact = oracle.phase_measures();
  std::vector<double> volume(scene.phases.size(), 0.0);
  double worst_distance = 0;
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    const LocalId* n = m.cell(c);
    const int phase = scene.phase_index(m.cell_phase[c]);
    EXPECT_GE(phase, 0);
    if (phase < 0) continue;
    volume[static_cast<std::size_t>(phase)] += mesh::signed_volume(m.point(n[0]), m.point(n[1]), m.point(n[2]), m.point(n[3]));
    for (int k = 0; k < 4; ++k) worst_distance = std::max(worst_distance, oracle.distance_to_phase(m.point(n[k]), phase));
  }
  if (interior) {
    EXPECT_EQ(s.collapsed_nodes, 0) << name;
  }
  EXPECT_LE(worst_distance, std::max(1e-9, s.max_collapse_deviation * (1 + 1e-9)))
      << name << ": a node of a phase-k tet lies outside phase k";
  for (std::size_t k = 0; k < volume.size(); ++k) {
    const double rel = std::abs(volume[k] - exact[k]) / exact[k];
    std::printf("[mesh3] %-14s phase %zu volume %.6f exact %.6f (relative error %.2e)\n", name.c_str(), k, volume[k],
                exact[k], rel);
    EXPECT_LE(rel, volume_tolerance) << name << " phase " << k;
  }

  out.aspect = quality::aspect_statistics<3>(m, 5.0, 5);
  const auto& a = out.aspect;
  std::printf("[mesh3] %-14s %zu tets, %lld leaves (Lmax %d, %d sweeps), %lld snapped, %lld cut leaves, %lld cut nodes, "
              "%lld closed leaves (%lld Steiner)\n",
              name.c_str(), m.cell_count(), static_cast<long long>(s.leaves), s.max_level, s.samr_sweeps,
              static_cast<long long>(s.snapped_nodes), static_cast<long long>(s.cut_tets),
              static_cast<long long>(s.cut_nodes), static_cast<long long>(s.closed_tets),
              static_cast<long long>(s.steiner_points));
  std::printf("[mesh3] %-14s aspect max %.3f mean %.3f, above 5: %zu (%.4f%%), dihedral %.2f..%.2f deg\n", name.c_str(),
              a.max, a.mean, a.above_bound, 100.0 * static_cast<double>(a.above_bound) / static_cast<double>(a.count),
              a.min_angle_deg, a.max_angle_deg);
  std::printf("[mesh3] %-14s worst by origin: closure %.3f, kept whole %.3f, cut-leaf sub-tets %.3f, swapped cubes "
              "%.3f; %lld face swaps, %lld snaps, %lld nodes refused their first option, %lld collapsed\n",
              name.c_str(), s.worst_closure, s.worst_kept, s.worst_split, s.worst_swapped,
              static_cast<long long>(s.face_swaps), static_cast<long long>(s.snapped_nodes),
              static_cast<long long>(s.refused_nodes), static_cast<long long>(s.collapsed_nodes));
  EXPECT_LE(s.worst_closure, 4.2) << name;  // the closure tables' bound (subdivide/README.md)
  std::string hist = "[mesh3] " + name + " histogram:";
  for (std::size_t i = 0; i < a.histogram.size(); ++i)
    if (a.histogram[i] > 0) {
      char buf[64];
      if (i + 1 < a.bin_edges.size())
        std::snprintf(buf, sizeof buf, " [%.1f,%.1f):%zu", a.bin_edges[i], a.bin_edges[i + 1], a.histogram[i]);
      else
        std::snprintf(buf, sizeof buf, " >=%.1f:%zu", a.bin_edges[i], a.histogram[i]);
      hist += buf;
    }
  std::printf("%s\n", hist.c_str());
  EXPECT_EQ(a.above_bound, 0u) << name;
  EXPECT_LE(a.max, kBound) << name;
  out.inclusion_volume_error = std::abs(volume[1] - exact[1]) / exact[1];
  return out;
}

TEST(Mesh3, BoxWithoutInclusionsIsTheHoneycomb) {
  const SceneDesc s = unit_box(0.25, 0);
  const Oracle3 oracle(s);
  const auto r = pipeline::mesh(oracle);
  EXPECT_EQ(r.mesh.cell_count(), 5u * 64u);  // five tets per cube, nothing refined
  EXPECT_EQ(r.mesh.node_count(), 125u);
  EXPECT_EQ(r.counters.refinements, 0);
  const auto a = quality::aspect_statistics<3>(r.mesh, 5.0);
  EXPECT_NEAR(a.max, 1.3660254, 1e-6);  // the corner tet
}

TEST(Mesh3, SphereLevel0) {
  SceneDesc s = unit_box(0.1, 0);
  s.inclusions = {{Sphere{{0.51, 0.48, 0.53}, 0.27}, 2, 0}};
  const auto o = mesh_and_check("sphere-L0", s, 0.08);
  EXPECT_EQ(o.result.counters.refinements, 0);
  EXPECT_GT(o.result.counters.cut_tets, 0);
  EXPECT_LE(o.aspect.max, kBound);
}

TEST(Mesh3, SphereLevel1) {
  SceneDesc s = unit_box(0.1, 1);
  s.inclusions = {{Sphere{{0.51, 0.48, 0.53}, 0.27}, 2, 1}};
  const auto o = mesh_and_check("sphere-L1", s, 0.025);
  EXPECT_GT(o.result.counters.refinements, 0);
  EXPECT_GT(o.result.counters.closed_tets, 0);
  EXPECT_LE(o.aspect.max, kBound);
}

TEST(Mesh3, TwoSpheres) {
  SceneDesc s = unit_box(0.1, 1);
  s.inclusions = {{Sphere{{0.28, 0.31, 0.52}, 0.17}, 2, 1}, {Sphere{{0.7, 0.66, 0.45}, 0.21}, 2, 1}};
  const auto o = mesh_and_check("two-spheres", s, 0.045);
  EXPECT_LE(o.aspect.max, kBound);
}

TEST(Mesh3, Ellipsoid) {
  SceneDesc s = unit_box(0.1, 1);
  s.inclusions = {{Ellipsoid{{0.49, 0.52, 0.5}, {0.36, 0.2, 0.14}, rotation_xyz(0.3, 0.5, 0.7)}, 2, 1}};
  const auto o = mesh_and_check("ellipsoid", s, 0.04);
  EXPECT_LE(o.aspect.max, kBound);
}

TEST(Mesh3, Cylinder) {
  SceneDesc s = unit_box(0.1, 1);
  s.inclusions = {{Cylinder{{0.2, 0.47, 0.44}, {0.81, 0.56, 0.52}, 0.13}, 2, 1}};
  const auto o = mesh_and_check("cylinder", s, 0.06);
  EXPECT_LE(o.aspect.max, kBound);
}

TEST(Mesh3, InclusionVolumeConvergesWithTheLevel) {
  // All interface nodes lie on the sphere: the mesh inscribes it, error O(h^2).
  double error[2];
  for (int level = 0; level < 2; ++level) {
    SceneDesc s = unit_box(0.1, level);
    s.inclusions = {{Sphere{{0.51, 0.48, 0.53}, 0.27}, 2, level}};
    error[level] = mesh_and_check("sphere-L" + std::to_string(level), s, 0.08).inclusion_volume_error;
  }
  EXPECT_LT(error[1], error[0] / 3) << "volume error " << error[0] << " -> " << error[1];
}

TEST(Mesh3, SphereClippedByTheDomainBoundary) {
  // Nodes on the domain faces slide along them only; the box stays the box.
  SceneDesc s = unit_box(0.1, 1);
  s.inclusions = {{Sphere{{0.93, 0.46, 0.52}, 0.26}, 2, 1}};
  const auto o = mesh_and_check("clipped-sphere", s, 0.04, false);
  EXPECT_LE(o.aspect.max, kBound);
}

}  // namespace

// ---------------------------------------------------------------------------------------
// The snapping guard and face swapping (radapt/README.md, faceswap/README.md).
// ---------------------------------------------------------------------------------------

namespace {

// Three separate spheres (radius 1–2.5 cells, a cell apart from each other and from the
// box), at random, levels 0–1: smooth interfaces in the configurations where unguarded
// snapping flattens corner tets.
SceneDesc random_spheres(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  SceneDesc s = unit_box(0.1, static_cast<int>(seed % 2));
  while (s.inclusions.size() < 3) {
    const double r = 0.1 + 0.15 * u(rng);
    const double m = r + 0.1;
    const Vec3 c{m + (1 - 2 * m) * u(rng), m + (1 - 2 * m) * u(rng), m + (1 - 2 * m) * u(rng)};
    bool apart = true;
    for (const auto& inc : s.inclusions) {
      const auto& o = std::get<Sphere>(inc.shape);
      apart = apart && std::hypot(c[0] - o.center[0], c[1] - o.center[1], c[2] - o.center[2]) > r + o.radius + 0.1;
    }
    if (apart) s.inclusions.push_back({Sphere{c, r}, 2, s.levels});
  }
  return s;
}
constexpr std::uint64_t kSphereScenes = 6;

struct MeshRun {
  double worst = 0;
  std::size_t above_3 = 0, above_5 = 0;
  pipeline::Counters<3> counters;
  bool conforming = false;
};

MeshRun run(const SceneDesc& scene, const pipeline::Options& options) {
  const Oracle3 oracle(scene);
  const auto r = pipeline::mesh(oracle, options);
  MeshRun out;
  const auto a = quality::aspect_statistics<3>(r.mesh, 5.0);
  out.worst = a.max;
  out.above_5 = a.above_bound;
  for (std::size_t i = 0; i + 1 < a.bin_edges.size(); ++i)
    if (a.bin_edges[i] >= 3.0 - 1e-9) out.above_3 += a.histogram[i];
  out.above_3 += a.histogram.back();
  out.counters = r.counters;
  out.conforming = quality::check_conformity(r.mesh, Box3{{0, 0, 0}, {1, 1, 1}}, 1.0, false).ok;
  return out;
}

}  // namespace

// Without the guard, snapping alone leaves tets far above 5 on these scenes (slivers of
// corner tets, flat tets with four snapped vertices, cut points next to vertices that could
// not snap); with it, none. Both meshes are conforming.
TEST(SnapGuard3, RemovesEveryTetAboveTheBound) {
  std::size_t unguarded_above = 0;
  double unguarded_worst = 0;
  for (std::uint64_t seed = 1; seed <= kSphereScenes; ++seed) {
    const SceneDesc scene = random_spheres(seed);
    pipeline::Options off;
    off.bound3 = 0;
    off.swap_trigger3 = 0;
    const MeshRun bare = run(scene, off);
    unguarded_above += bare.above_5;
    unguarded_worst = std::max(unguarded_worst, bare.worst);
    const MeshRun guarded = run(scene, pipeline::Options{});
    EXPECT_EQ(guarded.above_5, 0u) << "seed " << seed;
    EXPECT_LE(guarded.worst, 5.0) << "seed " << seed;
    EXPECT_TRUE(guarded.conforming) << "seed " << seed;
    EXPECT_EQ(guarded.counters.collapsed_nodes, 0) << "seed " << seed << ": interior spheres need no collapse";
  }
  std::printf("[guard] unguarded: %zu tets above 5 over %d scenes (worst %.1f); guarded: none\n", unguarded_above,
              static_cast<int>(kSphereScenes), unguarded_worst);
  EXPECT_GT(unguarded_above, 0u) << "the scenes no longer exercise the guard";
}

// A sphere barely poking through a domain face: a wedge of matrix between the sphere and the
// face, thinner than the cells; nodes on the face may not move along its normal. The guard
// collapses a few nodes there, each within a cell of the phase it joins, and reports it.
TEST(SnapGuard3, CollapsesOnlyWhatTheLatticeCannotResolve) {
  SceneDesc s = unit_box(0.1, 1);
  s.inclusions = {{Sphere{{0.5, 0.5, 1.247}, 0.25}, 2, 1}};  // a cap 0.003 high above z = 1, at 11.5°
  const MeshRun r = run(s, pipeline::Options{});
  EXPECT_EQ(r.above_5, 0u);
  EXPECT_TRUE(r.conforming);
  EXPECT_GT(r.counters.collapsed_nodes, 0);
  EXPECT_LE(r.counters.max_collapse_deviation, 0.05);  // one cell of level 1
}

// Face swapping repairs sliver/cap pairs: never a worse mesh, fewer tets above 3, conforming.
TEST(FaceSwap3, ImprovesAndStaysConforming) {
  std::size_t above_3_without = 0, above_3_with = 0;
  std::int64_t swaps = 0;
  for (std::uint64_t seed = 1; seed <= kSphereScenes; ++seed) {
    const SceneDesc scene = random_spheres(seed);
    pipeline::Options no_swap;
    no_swap.swap_trigger3 = 0;
    const MeshRun without = run(scene, no_swap);
    const MeshRun with = run(scene, pipeline::Options{});
    EXPECT_TRUE(with.conforming) << "seed " << seed;
    EXPECT_LE(with.worst, without.worst + 1e-12) << "seed " << seed;
    above_3_without += without.above_3, above_3_with += with.above_3;
    swaps += with.counters.face_swaps;
    EXPECT_EQ(without.counters.face_swaps, 0);
  }
  std::printf("[faceswap] %lld swaps; tets above 3: %zu without, %zu with\n", static_cast<long long>(swaps),
              above_3_without, above_3_with);
  EXPECT_GT(swaps, 0);
  EXPECT_LT(above_3_with, above_3_without);
}
