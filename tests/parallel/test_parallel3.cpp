// lib/parallel in 3D through the serial Comm: effective_levels3, the 3D ghost margin,
// partition invariance for (1 rank, 1, 7 and 64 partitions) against the sequential mesher
// (pipeline::mesh) on dense scenes where the guard refuses and collapses and
// face swaps happen near partition faces and corners, a ghost too small to be exact, the
// merge of cut nodes, the STL files read in shares, and errors in them.
// test_parallel3_mpi.cpp runs the invariance on 2-4 ranks.
#include <gtest/gtest.h>

#include <filesystem>
#include <cstring>
#include <fstream>
#include <numeric>
#include <random>
#include <span>

#include "grid/tet_lattice.hpp"
#include "io/scene_io.hpp"
#include "parallel/collective.hpp"
#include "parallel/output.hpp"
#include "partition/partition.hpp"
#include "pipeline/effective_levels.hpp"
#include "pipeline/staged3.hpp"
#include "samr/samr3.hpp"
#include "scenes3.hpp"
#include "support/cohesive_compare.hpp"

namespace cisamr::parallel {
namespace {

namespace fs = std::filesystem;
const SerialComm kSerial;

geometry::SceneDesc two_spheres(double gap, int phase_b, int levels_a, int levels_b) {
  geometry::SceneDesc s;
  s.dimension = 3;
  s.domain_max = {2, 1, 1};
  s.h = 0.125;
  s.phases = {{1, "m", false}, {2, "a", false}, {3, "b", false}};
  const double r = 0.2;
  s.inclusions.push_back({geometry::Sphere{{0.5, 0.5, 0.5}, r}, 2, levels_a});
  s.inclusions.push_back({geometry::Sphere{{0.5 + 2 * r + gap, 0.5, 0.5}, r}, phase_b, levels_b});
  return s;
}

std::vector<int> levels_of(const geometry::SceneDesc& s) {
  return pipeline::effective_levels3(s, scene_lattice<3>(s, {}));
}

TEST(EffectiveLevels3, ContactRaisesBothToTheFirstSeparatingLevel) {
  // h_l = 0.125 / 2^l; contact below 1.8 h_l. A gap of 0.05: l = 3 (1.8 h_3 = 0.028).
  EXPECT_EQ(levels_of(two_spheres(0.05, 3, 0, 0)), (std::vector<int>{3, 3}));
  // Far apart (≥ 8 cells): own levels.
  EXPECT_EQ(levels_of(two_spheres(1.05, 3, 0, 1)), (std::vector<int>{0, 1}));
  // Same phase, overlapping: one union, no contact.
  EXPECT_EQ(levels_of(two_spheres(-0.1, 2, 0, 0)), (std::vector<int>{0, 0}));
}

TEST(EffectiveLevels3, SpreadCarriesTheFinerLevelToCloseNeighbours) {
  // 0.5 apart: closer than 8 cells of level 0 (1.0), same phase, not touching.
  EXPECT_EQ(levels_of(two_spheres(0.5, 2, 0, 2)), (std::vector<int>{2, 2}));
  // Level 1 needs closer than 8·0.0625 = 0.5: 0.55 is not.
  EXPECT_EQ(levels_of(two_spheres(0.55, 2, 1, 2)), (std::vector<int>{1, 2}));
}

// The canonical form of a cell is the lexicographically smallest of its even permutations
// (checksum.hpp); the checksum's shortcut for distinct vertices must find the same one as
// trying them all, and cells with coincident vertices (degenerate, but a checksum must
// still be order-free for them) take the full search. `even`: the even permutations, tried
// by brute force; every `repeat_every`-th cell repeats a vertex.
template <int Dim, std::size_t N>
void expect_smallest_even_permutation(const std::array<std::array<int, Dim + 1>, N>& even, std::uint64_t seed,
                                      int cells, int repeat_every) {
  constexpr int kCorners = Dim + 1;
  std::mt19937_64 rng(seed);
  mesh::SimplexMesh<Dim> m;
  for (int c = 0; c < cells; ++c) {
    // Few distinct values per coordinate, so that vertices often share coordinates (ties
    // decided by later components) and some cells repeat a vertex.
    for (int k = 0; k < kCorners; ++k) {
      const bool repeat = c % repeat_every == 0 && k == Dim;
      for (int d = 0; d < Dim; ++d)
        m.coords.push_back(repeat ? m.coords[m.coords.size() - Dim] : std::array{-1.0, -0.0, 0.0, 1.0}[rng() % 4]);
      m.cell_nodes.push_back(static_cast<LocalId>(kCorners * c + k));
    }
    m.cell_phase.push_back(static_cast<std::int32_t>(c % 3));
  }
  std::vector<CanonicalSimplex<Dim>> expected;
  for (int c = 0; c < cells; ++c) {
    CanonicalSimplex<Dim> best;
    for (std::size_t p = 0; p < even.size(); ++p) {
      CanonicalSimplex<Dim> t;
      for (int k = 0; k < kCorners; ++k)
        for (int d = 0; d < Dim; ++d) {
          double x = m.coords[Dim * static_cast<std::size_t>(kCorners * c + even[p][static_cast<std::size_t>(k)]) + static_cast<std::size_t>(d)];
          if (x == 0) x = 0;  // -0 and +0 are one point
          std::memcpy(&t.xyz[static_cast<std::size_t>(Dim * k + d)], &x, sizeof x);
        }
      if (p == 0 || t.xyz < best.xyz) best = t;
    }
    best.phase = m.cell_phase[static_cast<std::size_t>(c)];
    expected.push_back(best);
  }
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(canonical_simplices(m), expected);
}

TEST(Checksum, CanonicalFormIsTheSmallestEvenPermutation) {
  const std::array<std::array<int, 4>, 12> even{{{0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2}, {1, 0, 3, 2},
                                                 {1, 3, 2, 0}, {1, 2, 0, 3}, {2, 0, 1, 3}, {2, 1, 3, 0},
                                                 {2, 3, 0, 1}, {3, 0, 2, 1}, {3, 2, 1, 0}, {3, 1, 0, 2}}};
  expect_smallest_even_permutation<3>(even, 7, 4000, 5);
}

// The same for triangles (the rotations): the lead vertex alone picks the rotation.
TEST(Checksum, CanonicalTriangleIsTheSmallestRotation) {
  const std::array<std::array<int, 3>, 3> even{{{0, 1, 2}, {1, 2, 0}, {2, 0, 1}}};
  expect_smallest_even_permutation<2>(even, 11, 3000, 7);
}

TEST(Scenes3, AreValid) {
  for (const auto& c : testing::invariance_cases3()) EXPECT_NO_THROW(geometry::Oracle3{testing::with_triangles(c.scene)}) << c.name;
}

// The least whole number of coarse cubes greater than SAMR's reach + 5/2^l, chosen by the
// coarsest effective level l near the box; SAMR's reach is the first cube of the region (0
// when nothing refines), whatever Lmax.
TEST(GhostMargin3, FollowsTheCoarsestLevelNearTheBox) {
  EXPECT_EQ(ghost_margin3(0), 7);  // 1 + 5 is a whole number: one more
  EXPECT_EQ(ghost_margin3(1), 4);
  EXPECT_EQ(ghost_margin3(2), 3);
  EXPECT_EQ(ghost_margin3(3), 2);
  EXPECT_EQ(ghost_margin3(6), 2);
  EXPECT_EQ(samr::reach_coarse_cells3(0), 0.0);
  EXPECT_EQ(samr::reach_coarse_cells3(1), 1.0);
  EXPECT_EQ(samr::reach_coarse_cells3(2), 1.0);
  EXPECT_EQ(samr::reach_coarse_cells3(5), 1.0);
  EXPECT_EQ(ghost_margin3(0, 0), 6);  // nothing refines: the kernel's 5 cubes, and one more
  EXPECT_EQ(ghost_margin3(0, 2), 7);
  EXPECT_EQ(ghost_margin3(1, 1), 4);
  EXPECT_EQ(ghost_margin3(1, 3), 4);
  EXPECT_EQ(ghost_margin3(2, 2), 3);
  EXPECT_EQ(ghost_margin3(3, 3), 2);
  // With the forest and the decisions near faces exchanged: the larger of SAMR's reach and
  // 2/2^l, rounded up.
  EXPECT_EQ(ghost_margin3(0, 4, true), 2);
  EXPECT_EQ(ghost_margin3(1, 4, true), 1);
  EXPECT_EQ(ghost_margin3(2, 4, true), 1);
  EXPECT_EQ(ghost_margin3(6, 6, true), 1);
  EXPECT_EQ(ghost_margin3(0, 0, true), 2);
  geometry::SceneDesc s;
  s.dimension = 3;
  s.domain_max = {8, 4, 4};
  s.h = 0.125;  // 64 x 32 x 32 cubes
  s.phases = {{1, "m", false}, {2, "a", false}};
  s.inclusions.push_back({geometry::Sphere{{2.0, 2.0, 2.0}, 0.2}, 2, 2});
  s.inclusions.push_back({geometry::Sphere{{6.0, 2.0, 2.0}, 0.2}, 2, 0});  // 24 cubes from the box
  // Lmax = 2 + the default 3 extra levels: SAMR reaches into the first cube, 1 + 1.25 → 3.
  const auto lattice = scene_lattice<3>(s, {});
  ASSERT_EQ(lattice.max_level, 5);
  const InclusionIndex3 index(s, lattice, GhostRule{});
  const grid::CellRange<3> box{{8, 8, 8}, {24, 24, 24}};  // x in [1, 3]
  std::vector<int> levels{2, 0};
  GhostRegion3 r = ghost_region3(index, lattice, box, GhostRule{}, levels);
  EXPECT_EQ(r.margin, 3);
  EXPECT_EQ(r.ghost, 3);
  EXPECT_EQ(r.range.lo[0], 5);
  EXPECT_EQ(r.range.hi[0], 27);
  EXPECT_EQ(r.inclusions, (std::vector<std::int32_t>{0}));
  // Without extra levels (Lmax 2): the same.
  pipeline::Options no_extra;
  no_extra.extra_levels = 0;
  const auto lattice2 = scene_lattice<3>(s, no_extra);
  ASSERT_EQ(lattice2.max_level, 2);
  const InclusionIndex3 index2(s, lattice2, GhostRule{});
  r = ghost_region3(index2, lattice2, box, GhostRule{}, levels);
  EXPECT_EQ(r.margin, 3);
  EXPECT_EQ(r.range.lo[0], 5);
  EXPECT_EQ(r.range.hi[0], 27);
  // The level-0 sphere within 7 cubes of the box's +x face (and near the ±y and ±z faces'
  // slabs): their margin, and it is loaded. The -x face has only the level-2 sphere within
  // 7 cubes: its own margin, 3.
  s.inclusions[1].shape = geometry::Sphere{{3.7, 2.0, 2.0}, 0.2};
  const InclusionIndex3 near(s, lattice, GhostRule{});
  r = ghost_region3(near, lattice, box, GhostRule{}, levels);
  EXPECT_EQ(r.margin, 7);
  EXPECT_EQ(r.inclusions, (std::vector<std::int32_t>{0, 1}));
  EXPECT_EQ(r.range.lo[0], 5);
  EXPECT_EQ(r.range.hi[0], 31);
  EXPECT_EQ(r.sides, (pipeline::GhostSides{{{3, 7}, {7, 7}, {7, 7}}}));
  // Near the -x face instead: that face's margin.
  s.inclusions[1].shape = geometry::Sphere{{0.3, 2.0, 2.0}, 0.2};
  const InclusionIndex3 near_low(s, lattice, GhostRule{});
  r = ghost_region3(near_low, lattice, box, GhostRule{}, levels);
  EXPECT_EQ(r.range.lo[0], 1);
  EXPECT_EQ(r.range.hi[0], 27);
  EXPECT_EQ(r.sides, (pipeline::GhostSides{{{7, 3}, {7, 7}, {7, 7}}}));
  // No inclusion near: one cube.
  const grid::CellRange<3> far{{40, 0, 0}, {44, 4, 4}};
  r = ghost_region3(near, lattice, far, GhostRule{}, levels);
  EXPECT_EQ(r.margin, 1);
  EXPECT_TRUE(r.inclusions.empty());
  // Forced.
  EXPECT_EQ(ghost_region3(near, lattice, box, testing::margin3(2), levels).margin, 2);
}

// Partitions that meshed fewer ghost cubes than their widest side all round would have
// (clipped to the domain): their ghost is narrower beyond some face.
int partitions_narrowed_by_face(const testing::RunOutcome3& par, const geometry::SceneDesc& scene) {
  int narrowed = 0;
  for (const auto& p : par.distributed.partitions) {
    std::int64_t grown = 1, inside = 1;
    for (std::size_t a = 0; a < 3; ++a) {
      const std::int64_t cubes = std::llround((scene.domain_max[a] - scene.domain_min[a]) / scene.h);
      grown *= std::min(cubes, p.lattice_max[a] + p.ghost) - std::max<std::int64_t>(0, p.lattice_min[a] - p.ghost);
      inside *= p.lattice_max[a] - p.lattice_min[a];
    }
    narrowed += p.ghost_cells < grown - inside ? 1 : 0;
  }
  return narrowed;
}

// The parallel mesh against the sequential one: the same set of elements (bit-equal
// coordinates, same phase) and checksum, no duplicate or missing node, conforming across
// partition faces, global ids 0..n-1 once each.
void expect_invariant3(const testing::RunOutcome3& seq, const testing::RunOutcome3& par, const geometry::SceneDesc& scene) {
  ASSERT_FALSE(seq.failed) << seq.error;
  ASSERT_FALSE(par.failed) << par.error;
  EXPECT_EQ(par.checksum, seq.checksum);
  EXPECT_EQ(mesh_checksum3(par.mesh), seq.checksum);
  EXPECT_TRUE(canonical_tets(par.mesh) == canonical_tets(seq.mesh));
  EXPECT_EQ(par.mesh.cell_count(), seq.mesh.cell_count());
  EXPECT_EQ(par.mesh.node_count(), seq.mesh.node_count());
  testing::expect_conforming3(par.mesh, scene);
  std::vector<char> seen(static_cast<std::size_t>(par.distributed.piece.global_nodes), 0);
  for (GlobalId g : par.distributed.piece.mesh.node_global_id) seen[static_cast<std::size_t>(g)]++;
  for (char s : seen) EXPECT_EQ(s, 1);
}

class Invariance3 : public ::testing::TestWithParam<int> {};

TEST_P(Invariance3, DenseScenes) {
  const int n = GetParam();
  int straddled = 0;
  for (const auto& c : testing::invariance_cases3()) {
    SCOPED_TRACE(c.name + ", " + std::to_string(n) + " partitions");
    const testing::RunOutcome3 seq = testing::run_sequential3(c.scene, c.options);
    const testing::RunOutcome3 par = testing::run_parallel3(kSerial, c.scene, n, {}, c.options);
    expect_invariant3(seq, par, c.scene);
    // What the scene is for: the guard refuses and collapses, faces are swapped, and with
    // several partitions inclusions straddle their corners.
    EXPECT_GT(seq.counters.refused_nodes, 0);
    EXPECT_GT(seq.counters.collapsed_nodes, 0);
    EXPECT_GT(seq.counters.face_swaps, 10);
    straddled += testing::straddled_corners3(par.distributed, c.scene);
  }
  if (n > 1) {
    EXPECT_GE(straddled, 2);  // spheres meeting four or more boxes
  }
}

// Cohesive cells (issue 13): the same cells and copies for 1 and 7 partitions as the
// sequential mesh, every interface facet covered once in the gathered mesh (across the
// partition faces and, periodic-level0, the periodic planes), one global id per copy.
TEST_P(Invariance3, CohesiveScenes) {
  std::int64_t cells = 0;
  for (const auto& c : testing::invariance_cases3()) {
    if (c.name != "periodic-level0" && c.name != "contact" && c.name != "corner") continue;
    SCOPED_TRACE(c.name + ", " + std::to_string(GetParam()) + " partitions");
    pipeline::Options options = c.options;
    options.cohesive = true;
    const testing::RunOutcome3 seq = testing::run_sequential3(c.scene, options);
    const testing::RunOutcome3 par = testing::run_parallel3(kSerial, c.scene, GetParam(), {}, options);
    ASSERT_FALSE(seq.failed) << seq.error;
    ASSERT_FALSE(par.failed) << par.error;
    EXPECT_EQ(par.checksum, seq.checksum);
    EXPECT_EQ(mesh_checksum3(par.mesh), seq.checksum);
    EXPECT_EQ(par.mesh.node_count(), seq.mesh.node_count());
    EXPECT_EQ(par.mesh.cohesive.count(), seq.mesh.cohesive.count());
    const auto frame = cisamr::testing::cohesive_frame<3>(c.scene, pipeline::make_lattice<3>(c.scene, options));
    const bool voids = std::ranges::any_of(c.scene.phases, [](const geometry::Phase& p) { return p.is_void; });
    EXPECT_TRUE(cisamr::testing::cohesive_mesh_is_right(par.mesh, frame, voids));
    std::vector<char> seen(static_cast<std::size_t>(par.distributed.piece.global_nodes), 0);
    for (GlobalId g : par.distributed.piece.mesh.node_global_id) seen[static_cast<std::size_t>(g)]++;
    for (char s : seen) EXPECT_EQ(s, 1);
    cells += static_cast<std::int64_t>(par.mesh.cohesive.count());
    // Tangent spheres of phases 2 and 3 in the matrix: triple lines, each node in 3 copies.
    if (c.name == "contact") {
      EXPECT_GT(cisamr::testing::multi_phase_points(par.mesh), 0);
    }
  }
  EXPECT_GT(cells, 10000);
}

INSTANTIATE_TEST_SUITE_P(OneRank, Invariance3, ::testing::Values(1, 7));

// 64 small boxes (8 x 8 x 4 cubes and their 8-cube ghosts) on the level-0 scene: most
// ghost regions end inside the domain, where the kernel's reach is widest.
TEST(Invariance3, SixtyFourPartitions) {
  const auto c = testing::invariance_cases3().front();
  const testing::RunOutcome3 seq = testing::run_sequential3(c.scene, c.options);
  const testing::RunOutcome3 par = testing::run_parallel3(kSerial, c.scene, 64, {}, c.options);
  expect_invariant3(seq, par, c.scene);
  int inside = 0;  // partitions whose ghost region stops short of the domain on some side
  for (const auto& p : par.distributed.partitions)
    for (int a = 0; a < 3; ++a)
      inside += p.lattice_min[a] - p.ghost > 0 || p.lattice_max[a] + p.ghost < (a < 2 ? 32 : 16) ? 1 : 0;
  EXPECT_GT(inside, 64);
}

// SAMR's reach is the region's first cube whatever Lmax, and the kernel's 5 cells of the
// level are counted as such (no safety cube since KernelReach3 tests that reach), so
// level-1 and level-2 scenes take 4 and 3 cubes with or without extra levels (5 and 4
// before), and one cube with the forest and the decisions near faces exchanged (the box's
// forest is right with one cube around it, the ghost's cubes take their owners' trees, and
// the kernel's 2 cells are one cube at level 1): still the whole-domain mesh. Some ghost
// cubes' own trees differ from their owners' (the first layer SAMR cannot get right).
TEST(Invariance3, LevelOneAndTwoTakeTheirMargins) {
  pipeline::Options no_extra;
  no_extra.extra_levels = 0;
  struct Scene {
    geometry::SceneDesc scene;
    int margin, exchanged_margin;
  };
  const std::vector<Scene> scenes{{testing::packed_scene3(12, 1, 16, 16, 12, 80), 4, 1},
                                  {testing::packed_scene3(13, 2, 10, 10, 8, 30), 3, 1}};
  std::int64_t replaced = 0;
  for (const auto& [scene, recomputed_margin, exchanged_margin] : scenes)
    for (const pipeline::Options& options : {pipeline::Options{}, no_extra}) {
      const testing::RunOutcome3 seq = testing::run_sequential3(scene, options);
      EXPECT_GT(seq.counters.refused_nodes, 0);
      for (const bool exchange : {false, true}) {
        for (int n : {7, 27, 64}) {
          SCOPED_TRACE("level " + std::to_string(scene.levels) + ", " + std::to_string(options.extra_levels) +
                       " extra levels, " + std::to_string(n) + " partitions" + (exchange ? ", exchanged" : ""));
          const int margin = exchange ? exchanged_margin : recomputed_margin;
          const testing::RunOutcome3 par = testing::run_parallel3(kSerial, scene, n, {}, options, exchange);
          EXPECT_EQ(par.distributed.exchanged_nodes > 0, exchange);
          EXPECT_EQ(par.distributed.exchanged_cubes > 0, exchange);
          replaced += par.distributed.replaced_cubes;
          expect_invariant3(seq, par, scene);
          int narrowed = 0;
          for (const auto& p : par.distributed.partitions) {
            EXPECT_LE(p.ghost, margin);
            narrowed += p.ghost == margin ? 1 : 0;
          }
          EXPECT_GT(narrowed, 0);
        }
      }
    }
  EXPECT_GT(replaced, 0);
}

// Each face its own margin: on a scene of level-0 spheres beside level-2 ones, boxes whose
// faces see different levels take a narrower ghost beyond the finer faces, with and
// without extra levels, and the mesh is still the whole-domain one.
TEST(Invariance3, EachFaceTakesTheMarginOfWhatLiesNearIt) {
  const geometry::SceneDesc scene = testing::mixed_level_scene3();
  pipeline::Options no_extra;
  no_extra.extra_levels = 0;
  for (const pipeline::Options& options : {pipeline::Options{}, no_extra}) {
    const testing::RunOutcome3 seq = testing::run_sequential3(scene, options);
    ASSERT_FALSE(seq.failed) << seq.error;
    for (int n : {7, 27, 64}) {
      SCOPED_TRACE(std::to_string(options.extra_levels) + " extra levels, " + std::to_string(n) + " partitions");
      const testing::RunOutcome3 par = testing::run_parallel3(kSerial, scene, n, {}, options);
      expect_invariant3(seq, par, scene);
      if (n >= 27) {  // 7 boxes: the -x faces see level 0, the +x faces are the domain's
        EXPECT_GT(partitions_narrowed_by_face(par, scene), 0);
      }
    }
  }
  // The sides themselves: a box in the level-2 part whose -x face has the level-0 spheres
  // within 8 cubes and whose +x face does not.
  const grid::Lattice3 lattice = scene_lattice<3>(scene, no_extra);
  const InclusionIndex3 index(scene, lattice, GhostRule{});
  std::vector<int> levels;
  for (const auto& inc : scene.inclusions) levels.push_back(inc.levels);
  const grid::CellRange<3> box{{20, 0, 0}, {26, 12, 10}};
  const GhostRegion3 r = ghost_region3(index, lattice, box, GhostRule{}, levels);
  EXPECT_EQ(r.sides[0][0], ghost_margin3(0, 2));  // the level-0 spheres within 8 cubes
  EXPECT_EQ(r.sides[0][1], ghost_margin3(2, 2));
  EXPECT_LT(r.sides[0][1], r.sides[0][0]);
}

// samr::kReachCoarseCells3, directly: SAMR over a sub-range (its cubes beyond missing, the
// inclusions that meet it loaded, the whole scene's effective levels) gives every cube
// beyond the range's first layer the whole run's leaves, with and without extra levels; in
// the first layer it may not. Given the whole run's refinement of the first layer's cubes
// (samr::take_cube_refinements, what the parallel mesher takes from the cubes' owners), the
// whole range holds the whole run's leaves, each with the whole run's count of cut
// inclusions.
TEST(SamrReach3, BeyondTheFirstLayerTheForestIsTheWholeRunsForest) {
  using Leaf = std::array<std::int64_t, 6>;  // level, cube, local, inclusions cutting it
  const auto leaves = [](const samr::RefinedGrid3& g, const grid::CellRange<3>& inner) {
    std::vector<Leaf> out;
    for (std::int32_t t = 0; t < static_cast<std::int32_t>(g.forest.size()); ++t) {
      if (!g.forest.is_leaf(t)) continue;
      const auto at = g.forest.coarse_cell(t);
      bool in = true;
      for (int d = 0; d < 3; ++d) in = in && at[static_cast<std::size_t>(d)] >= inner.lo[d] && at[static_cast<std::size_t>(d)] < inner.hi[d];
      if (!in) continue;
      const auto& x = g.forest.tet(t);
      out.push_back({x.level, x.cube[0], x.cube[1], x.cube[2], x.local, g.touch_count[static_cast<std::size_t>(t)]});
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  pipeline::Options no_extra;
  no_extra.extra_levels = 0;
  int compared = 0, first_layer_differs = 0;
  std::int64_t replaced = 0;
  for (int levels = 1; levels <= 2; ++levels)
    for (std::uint64_t seed = 1; seed <= 2; ++seed)
      for (const pipeline::Options& options : {pipeline::Options{}, no_extra}) {
        const geometry::SceneDesc scene = levels == 1 ? testing::packed_scene3(800 + seed, 1, 16, 16, 12, 80)
                                                      : testing::packed_scene3(800 + seed, 2, 10, 10, 8, 30);
        const auto lattice = scene_lattice<3>(scene, options);
        const std::vector<int> levels_all = pipeline::effective_levels3(scene, lattice, pipeline::holding_boxes(scene));
        const grid::CellRange<3> domain{{0, 0, 0}, {lattice.coarse_cells[0], lattice.coarse_cells[1], lattice.coarse_cells[2]}};
        const samr::RefinedGrid3 whole = samr::refine3(geometry::Oracle3(scene), lattice, domain, levels_all);
        const InclusionIndex3 index(scene, lattice, GhostRule{});
        for (int corner = 0; corner < 2; ++corner) {
          grid::CellRange<3> range;
          for (int d = 0; d < 3; ++d) {
            const std::int64_t n = lattice.coarse_cells[d];
            range.lo[d] = corner == 0 ? 1 : n / 3;
            range.hi[d] = corner == 0 ? n - n / 3 : n - 1;
          }
          Box3 box;
          for (int d = 0; d < 3; ++d) {
            box.min[d] = lattice.origin[d] + static_cast<double>(range.lo[d]) * lattice.h;
            box.max[d] = lattice.origin[d] + static_cast<double>(range.hi[d]) * lattice.h;
          }
          std::vector<std::int32_t> loaded;
          index.query(box, loaded);
          std::vector<int> levels_part;
          for (std::int32_t k : loaded) levels_part.push_back(levels_all[static_cast<std::size_t>(k)]);
          const geometry::Oracle3 part_oracle(subset_scene(scene, loaded));
          samr::RefinedGrid3 part = samr::refine3(part_oracle, lattice, range, levels_part);
          const int r = samr::kReachCoarseCells3;
          grid::CellRange<3> inner = range;
          for (int d = 0; d < 3; ++d) inner.lo[d] += r, inner.hi[d] -= r;
          EXPECT_EQ(leaves(part, inner), leaves(whole, inner))
              << "level " << levels << ", seed " << seed << ", " << options.extra_levels << " extra levels, corner " << corner;
          first_layer_differs += leaves(part, range) != leaves(whole, range) ? 1 : 0;
          ++compared;
          std::vector<samr::CubeRefinement> owners;
          for (std::int64_t ck = range.lo[2]; ck < range.hi[2]; ++ck)
            for (std::int64_t cj = range.lo[1]; cj < range.hi[1]; ++cj)
              for (std::int64_t ci = range.lo[0]; ci < range.hi[0]; ++ci) {
                if (inner.contains({ci, cj, ck})) continue;
                samr::CubeRefinement c{{ci, cj, ck}, {}};
                for (int local = 0; local < 5; ++local) whole.forest.append_refinement(whole.forest.root(ci, cj, ck, local), c.bits);
                owners.push_back(std::move(c));
              }
          replaced += samr::take_cube_refinements(part_oracle, part, owners);
          EXPECT_EQ(leaves(part, range), leaves(whole, range))
              << "level " << levels << ", seed " << seed << ", " << options.extra_levels << " extra levels, corner " << corner;
        }
      }
  EXPECT_EQ(compared, 16);
  EXPECT_GT(first_layer_differs, 0);  // the comparison can fail
  EXPECT_GT(replaced, 0);
}

// The kernel's reach (kKernelReach3 = 5 cells of the deciding level: the guard 3, face
// swapping 5, subdivision 3), directly: on the whole run's forest and inclusions, with
// r-adaptivity and face swapping given only the leaves within w cells of a box (the others
// get no nodes, make no options, refusals or swap candidates: as if missing), the box's
// mesh is the whole run's for w = kKernelReach3 (the margin counts that much beyond SAMR's
// first layer), and for the windows the partitions use (leaves starting within them: face
// swapping kSwapWindow3 = kCompetitorCells3 − 1, r-adaptivity kRadaptWindow3 =
// kCompetitorCells3 + radapt::kReachCells3 − 1). With
// half a cell it may not be (so the comparison can fail). The partitions' windows run the
// guard's passes on kFirstPassWindow3 and kSecondPassWindow3 (a forced window, as w, runs
// them on all of r-adaptivity's); with both passes on the box alone it may differ. Boxes of a
// 3×3×2 split: box 13 has six inner faces, the others meet the domain.
// A scene of the reach comparisons below and what they compare on: its lattice, effective
// levels, oracle and inclusion index, and ghost sides that cover the whole domain.
struct ReachScene {
  geometry::SceneDesc scene;
  grid::Lattice3 lattice;
  std::vector<int> levels;
  geometry::Oracle3 oracle;
  InclusionIndex3 index;
  pipeline::GhostSides whole_domain{};
  explicit ReachScene(const testing::Case3& c)
      : scene(testing::with_triangles(c.scene)),
        lattice(scene_lattice<3>(scene, c.options)),
        levels(pipeline::effective_levels3(scene, lattice, pipeline::holding_boxes(scene))),
        oracle(scene),
        index(scene, lattice, GhostRule{}) {
    for (int d = 0; d < 3; ++d)
      whole_domain[static_cast<std::size_t>(d)] = {static_cast<int>(lattice.coarse_cells[d]), static_cast<int>(lattice.coarse_cells[d])};
  }
};

// Box b of the 3×3×2 split of the lattice's coarse cubes (box 13 has six inner faces).
grid::CellRange<3> split_box(const grid::Lattice3& lattice, int b) {
  const std::array<int, 3> split{3, 3, 2};
  grid::CellRange<3> box;
  for (int d = 0, rest = b; d < 3; ++d) {
    const int i = rest % split[static_cast<std::size_t>(d)];
    rest /= split[static_cast<std::size_t>(d)];
    const std::int64_t n = lattice.coarse_cells[d];
    box.lo[d] = n * i / split[static_cast<std::size_t>(d)];
    box.hi[d] = n * (i + 1) / split[static_cast<std::size_t>(d)];
  }
  return box;
}

struct KernelReachCounts {
  int compared = 0;
  int half_differs = 0;            // with half-cell windows
  int guard_on_box_differs = 0;    // with the partitions' windows, the guard's passes on the box alone
};
KernelReachCounts compare_kernel_reach(const std::vector<testing::Case3>& cases, std::span<const int> boxes,
                                       bool try_guard_on_box = false) {
  struct Windows {
    double swap, radapt;
  };
  const Windows reach{kKernelReach3, kKernelReach3};
  const Windows used{0, 0};  // derived: the guard's passes on narrower windows still
  const Windows half{0.5, 0.5};
  KernelReachCounts counts;
  for (const auto& c : cases) {
    const ReachScene reach_scene(c);
    const auto& [scene, lattice, levels, oracle, index, whole_domain] = reach_scene;
    for (int b : boxes) {
      const grid::CellRange<3> box = split_box(lattice, b);
      const auto mesh = [&](const Windows* w, bool guard_on_box_only = false) {
        pipeline::Ghost ghost{whole_domain, -1, -1};
        if (w != nullptr) {  // the windows in fine units, at the level that decides near the box
          GhostRule rule;
          rule.swap_window_cells3 = w->swap;
          rule.radapt_window_cells3 = w->radapt;
          const GhostRegion3 region = ghost_region3(index, lattice, box, rule, levels);
          ghost = kernel_ghost(region);
          ghost.sides = whole_domain;
          if (guard_on_box_only) ghost.first_pass_reach = ghost.second_pass_reach = 0;
        }
        return mesh_checksum3(pipeline::run<3>(oracle, lattice, box, ghost, c.options, 0, levels).mesh);
      };
      const std::uint64_t exact = mesh(nullptr);
      const std::string where = c.name + ", box " + std::to_string(b);
      EXPECT_EQ(mesh(&reach), exact) << where << ", windows of kKernelReach3 cells";
      EXPECT_EQ(mesh(&used), exact) << where << ", the partitions' windows";
      counts.half_differs += mesh(&half) != exact ? 1 : 0;
      if (try_guard_on_box) counts.guard_on_box_differs += mesh(&used, true) != exact ? 1 : 0;
      ++counts.compared;
    }
  }
  return counts;
}

// The scenes of the reach tests: the invariance scenes but the periodic one (its windows are
// the whole ghost, and it exchanges nothing), packed level-1 and level-2 scenes without extra
// levels, and level-0 spheres beside level-2 ones.
std::vector<testing::Case3> reach_cases() {
  pipeline::Options no_extra;
  no_extra.extra_levels = 0;
  std::vector<testing::Case3> cases = testing::invariance_cases3();
  std::erase_if(cases, [](const testing::Case3& c) { return c.name == "periodic-level0"; });
  cases.push_back({"packed-level1-no-extra", testing::packed_scene3(12, 1, 16, 16, 12, 80), no_extra});
  cases.push_back({"packed-level2-no-extra", testing::packed_scene3(13, 2, 10, 10, 8, 30), no_extra});
  cases.push_back({"levels-0-and-2", testing::mixed_level_scene3(), {}});
  return cases;
}

TEST(KernelReach3, TheBoxReadsNothingBeyondFiveCellsOfItsLevel) {
  const std::array<int, 5> boxes{0, 4, 8, 13, 16};
  const KernelReachCounts counts = compare_kernel_reach(reach_cases(), boxes);
  EXPECT_EQ(counts.compared, 8 * 5);
  EXPECT_GT(counts.half_differs, 0);  // the comparison can fail
}

// The guard's windows matter: refusals near a box face are rare (none of the 40 boxes above
// needs the guard beyond its box), but in 3 of the wider run's 774 boxes the guard's passes on
// the box alone change the box's mesh; this is one of them. With the partitions' windows it
// is the whole run's.
TEST(KernelReach3, TheGuardOnTheBoxAloneBreaksIt) {
  const std::vector<testing::Case3> cases{{"packed level 2, seed 901", testing::packed_scene3(901, 2, 10, 10, 8, 30), {}}};
  const std::array<int, 1> boxes{5};
  const KernelReachCounts counts = compare_kernel_reach(cases, boxes, true);
  EXPECT_EQ(counts.compared, 1);
  EXPECT_EQ(counts.guard_on_box_differs, 1);
}

// Dense level-0 scenes, packed ones at levels 1-3 with and without extra levels (six seeds
// each) and the contact scene.
std::vector<testing::Case3> wider_sweep_cases() {
  pipeline::Options no_extra;
  no_extra.extra_levels = 0;
  std::vector<testing::Case3> cases;
  for (std::uint64_t seed = 900; seed < 906; ++seed) {
    const std::string s = ", seed " + std::to_string(seed);
    cases.push_back({"dense level 0" + s, testing::packed_scene3(seed, 0, 24, 24, 16, 200), {}});
    for (const pipeline::Options& options : {pipeline::Options{}, no_extra}) {
      const std::string e = options.extra_levels == 0 ? " without extra levels" : "";
      cases.push_back({"packed level 1" + e + s, testing::packed_scene3(seed, 1, 16, 16, 12, 80), options});
      cases.push_back({"packed level 2" + e + s, testing::packed_scene3(seed, 2, 10, 10, 8, 30), options});
      cases.push_back({"packed level 3" + e + s, testing::packed_scene3(seed, 3, 8, 8, 6, 12), options});
    }
  }
  cases.push_back({"contact", testing::contact_scene3(), testing::contact_options3()});
  return cases;
}

// With the decisions near faces exchanged, a partition decides only the nodes of its closed
// box (the others come from their owners): on the whole run's forest, r-adaptivity on the
// leaves within kExchangedRadaptWindow3 = 1 cell of the box, both guard passes on the leaves
// touching it (kExchangedFirstPassWindow3 = kExchangedSecondPassWindow3 = 0), with the
// whole run's first-pass refusals for the nodes outside the closed box that the second pass
// reads (what their owners send), gives every node of the closed box the whole run's final
// position, mask, state and finest level around. With r-adaptivity on the touching leaves
// only, some boxes' nodes differ (the comparison can fail); without the refusals taken,
// some of the wider sweep's do (refusals near a face are rare). The same scenes and boxes as
// KernelReach3.TheBoxReadsNothingBeyondFiveCellsOfItsLevel.
struct ExchangedWindowCounts {
  int compared = 0;
  std::int64_t nodes_compared = 0;
  int box_only_differs = 0;     // boxes whose nodes differ with r-adaptivity on the box's touching leaves only
  int own_refusals_differ = 0;  // boxes whose nodes differ without the first-pass refusals exchanged
};
ExchangedWindowCounts compare_exchanged_windows(const std::vector<testing::Case3>& cases, std::span<const int> boxes) {
  ExchangedWindowCounts counts;
  int& compared = counts.compared;
  int& box_only_differs = counts.box_only_differs;
  int& own_refusals_differ = counts.own_refusals_differ;
  std::int64_t& nodes_compared = counts.nodes_compared;
  for (const auto& c : cases) {
    const ReachScene reach_scene(c);
    const auto& [scene, lattice, levels, oracle, index, whole_domain] = reach_scene;
    grid::CellRange<3> domain;
    for (int d = 0; d < 3; ++d) domain.lo[d] = 0, domain.hi[d] = lattice.coarse_cells[d];
    // The whole run, its first-pass refusals kept (what the owners send).
    pipeline::Snapped3 whole = pipeline::snap3_first(oracle, lattice, domain, pipeline::Ghost{whole_domain}, c.options, levels);
    std::vector<std::uint32_t> whole_refusals(whole.snapping->nodes().key.size());
    std::vector<int> whole_options(whole_refusals.size());
    for (std::size_t n = 0; n < whole_refusals.size(); ++n) {
      whole_refusals[n] = whole.snapping->first_pass_refusals(static_cast<std::int32_t>(n));
      whole_options[n] = whole.snapping->option_count(static_cast<std::int32_t>(n));
    }
    pipeline::snap3_second(whole, c.options);
    GhostRule exchanging;
    exchanging.exchange = true;
    for (int b : boxes) {
      const grid::CellRange<3> box = split_box(lattice, b);
      const GhostRegion3 region = ghost_region3(index, lattice, box, exchanging, levels);
      if (!region.exchange) continue;  // no inclusion near the box: nothing snaps there
      const grid::LeafWindow closed = grid::LeafWindow::around(lattice, box, 0);
      const auto in_closed_box = [&](grid::LatticeKey3 key) {
        const grid::LatticePoint3 p = grid::key3_point(key);
        bool inside = true;
        for (int d = 0; d < 3; ++d) inside = inside && p[d] >= closed.lo[d] && p[d] <= closed.hi[d];
        return inside;
      };
      // The nodes of the closed box whose decision (or finest level around) differs from the
      // whole run's (all must be there); with `take_refusals`, the first-pass refusals of the
      // nodes outside the closed box that the second pass's leaves read are the whole run's.
      const auto differing = [&](pipeline::Ghost ghost, bool take_refusals) {
        ghost.sides = whole_domain;
        pipeline::Snapped3 part = pipeline::snap3_first(oracle, lattice, box, ghost, c.options, levels);
        int differ = 0;  // options unlike the owner's count (the mesher refuses to take their refusals)
        if (take_refusals) {
          const radapt::Nodes3& nodes = part.snapping->nodes();
          const grid::TetForest& forest = part.grid->forest;
          const grid::LeafWindow second = grid::LeafWindow::around(lattice, box, ghost.second_pass_reach);
          for (std::int32_t t = 0; t < static_cast<std::int32_t>(forest.size()); ++t) {
            if (!forest.is_leaf(t) || !nodes.registered(t) || !second.holds(forest, t)) continue;
            for (const std::int32_t m : nodes.tet_nodes[static_cast<std::size_t>(t)]) {
              const grid::LatticeKey3 key = nodes.key[static_cast<std::size_t>(m)];
              if (in_closed_box(key)) continue;
              const auto w = static_cast<std::size_t>(whole.nodes.id(key));
              if (part.snapping->option_count(m) != whole_options[w]) {
                ++differ;
                continue;
              }
              part.snapping->set_first_pass_refusals(m, whole_refusals[w]);
            }
          }
        }
        pipeline::snap3_second(part, c.options);
        for (std::size_t n = 0; n < whole.nodes.key.size(); ++n) {
          if (!in_closed_box(whole.nodes.key[n])) continue;
          const std::int32_t m = part.nodes.id(whole.nodes.key[n]);
          EXPECT_GE(m, 0) << c.name << ", box " << b << ": a node of the closed box missing";
          if (m < 0) continue;
          const auto k = static_cast<std::size_t>(m);
          ++nodes_compared;
          differ += part.nodes.position[k] != whole.nodes.position[n] || part.nodes.mask[k] != whole.nodes.mask[n] ||
                            part.nodes.state[k] != whole.nodes.state[n] ||
                            part.nodes.finest_level[k] != whole.nodes.finest_level[n]
                        ? 1
                        : 0;
        }
        return differ;
      };
      EXPECT_EQ(differing(kernel_ghost(region), true), 0) << c.name << ", box " << b << ", the exchanged windows";
      pipeline::Ghost box_only = kernel_ghost(region);
      box_only.radapt_reach = 0;
      box_only_differs += differing(box_only, true) > 0 ? 1 : 0;
      own_refusals_differ += differing(kernel_ghost(region), false) > 0 ? 1 : 0;
      ++compared;
    }
  }
  std::printf("%d boxes, %lld nodes compared; %d boxes differ with r-adaptivity on the box's touching leaves only, %d "
              "without the first-pass refusals exchanged\n",
              compared, static_cast<long long>(nodes_compared), box_only_differs, own_refusals_differ);
  return counts;
}

TEST(KernelReach3, ExchangedWindowsDecideTheClosedBoxsNodes) {
  const std::array<int, 5> boxes{0, 4, 8, 13, 16};
  const ExchangedWindowCounts counts = compare_exchanged_windows(reach_cases(), boxes);
  EXPECT_EQ(counts.compared, 8 * 5);
  EXPECT_GT(counts.nodes_compared, 100000);
  EXPECT_GT(counts.box_only_differs, 0);  // the comparison can fail
}

// The same over KernelReach3.DISABLED_WiderSweep's scenes and every box of the split, not in
// the suite: `test_parallel3 --gtest_also_run_disabled_tests --gtest_filter='*ExchangedWiderSweep'`.
TEST(KernelReach3, DISABLED_ExchangedWiderSweep) {
  std::vector<int> boxes(18);
  std::iota(boxes.begin(), boxes.end(), 0);
  const ExchangedWindowCounts counts = compare_exchanged_windows(wider_sweep_cases(), boxes);
  EXPECT_GT(counts.compared, 700);
  EXPECT_GT(counts.box_only_differs, 0);
}

// The same over more scenes (dense level-0 ones, packed ones at levels 1-3 with and without
// extra levels, the contact scene) and every box of the split, about 5 minutes, so not in
// the suite: `test_parallel3 --gtest_also_run_disabled_tests --gtest_filter='*WiderSweep'`.
TEST(KernelReach3, DISABLED_WiderSweep) {
  std::vector<int> boxes(18);
  std::iota(boxes.begin(), boxes.end(), 0);
  const KernelReachCounts counts = compare_kernel_reach(wider_sweep_cases(), boxes, true);
  std::printf("%d boxes compared; with half-cell windows %d differ, with the guard on the box alone %d\n",
              counts.compared, counts.half_differs, counts.guard_on_box_differs);
  EXPECT_GT(counts.half_differs, 0);
}

// The sweep behind the per-face margins and SAMR's one-cube reach (lib/parallel/README.md,
// "Ghost region (3D)"): 70 scenes at 7, 8, 27 and 64 partitions against the whole-domain
// mesh (280 runs), about 3 minutes, so
// not in the suite: `test_parallel3 --gtest_also_run_disabled_tests
// --gtest_filter='*SweepOfSparseAndMixedScenes'`.
TEST(Invariance3, DISABLED_SweepOfSparseAndMixedScenes) {
  int runs = 0, narrowed_runs = 0;
  const auto check = [&](const geometry::SceneDesc& scene, const pipeline::Options& options, const std::string& name) {
    const testing::RunOutcome3 seq = testing::run_sequential3(scene, options);
    ASSERT_FALSE(seq.failed) << name << ": " << seq.error;
    for (int n : {7, 8, 27, 64}) {
      const testing::RunOutcome3 par = testing::run_parallel3(kSerial, scene, n, {}, options);
      ++runs;
      EXPECT_EQ(par.checksum, seq.checksum) << name << ", " << n << " partitions";
      EXPECT_EQ(par.mesh.cell_count(), seq.mesh.cell_count()) << name << ", " << n << " partitions";
      narrowed_runs += partitions_narrowed_by_face(par, scene) > 0 ? 1 : 0;
    }
  };
  pipeline::Options no_extra;
  no_extra.extra_levels = 0;
  for (std::uint64_t seed = 600; seed < 612; ++seed) {
    check(testing::packed_scene3(seed, 0, 40, 24, 16, 5), {}, "very sparse, level 0, seed " + std::to_string(seed));
    check(testing::packed_scene3(seed, 1, 32, 16, 12, 4), {}, "very sparse, level 1, seed " + std::to_string(seed));
  }
  check(testing::contact_scene3(), testing::contact_options3(), "contact");
  for (std::uint64_t seed = 400; seed < 406; ++seed) {
    check(testing::packed_scene3(seed, 0, 32, 24, 16, 12), {}, "sparse, level 0, seed " + std::to_string(seed));
    check(testing::packed_scene3(seed, 1, 24, 16, 12, 10), no_extra, "sparse, level 1, seed " + std::to_string(seed));
    check(testing::packed_scene3(seed, 2, 16, 12, 10, 8), {}, "sparse, level 2, seed " + std::to_string(seed));
  }
  for (std::uint64_t seed = 500; seed < 504; ++seed) {
    geometry::SceneDesc s = testing::packed_scene3(seed, 1, 24, 16, 12, 60);
    for (auto& inc : s.inclusions)
      if (std::get<geometry::Sphere>(inc.shape).center[0] < 1.2) inc.levels = 0;
    check(s, {}, "levels 0 and 1, seed " + std::to_string(seed));
    check(s, no_extra, "levels 0 and 1 without extra levels, seed " + std::to_string(seed));
  }
  check(testing::mixed_level_scene3(), {}, "levels 0 and 2");
  // Packed scenes with the default extra levels (margins 5 at level 1, 4 at level 2, 3 at
  // level 3: SAMR's reach is the first cube whatever Lmax) and without them at level 3.
  for (std::uint64_t seed = 700; seed < 706; ++seed) {
    check(testing::packed_scene3(seed, 1, 16, 16, 12, 80), {}, "packed, level 1, seed " + std::to_string(seed));
    check(testing::packed_scene3(seed, 2, 10, 10, 8, 30), {}, "packed, level 2, seed " + std::to_string(seed));
  }
  for (std::uint64_t seed = 710; seed < 713; ++seed) {
    check(testing::packed_scene3(seed, 3, 8, 8, 6, 12), {}, "packed, level 3, seed " + std::to_string(seed));
    check(testing::packed_scene3(seed, 3, 8, 8, 6, 12), no_extra, "packed, level 3 without extra levels, seed " + std::to_string(seed));
  }
  std::printf("%d runs, %d with partitions whose ghost is narrower on some face\n", runs, narrowed_runs);
}

// The tests can fail: with a ghost of one cube, SAMR cascades, the guard's and the face
// swaps' decisions near the faces differ from the whole-domain run's.
TEST(Invariance3, TooSmallGhostBreaksIt) {
  for (const auto& c : testing::invariance_cases3()) {
    if (c.name != "packed-level1" && c.name != "contact") continue;
    SCOPED_TRACE(c.name);
    const testing::RunOutcome3 seq = testing::run_sequential3(c.scene, c.options);
    const testing::RunOutcome3 par = testing::run_parallel3(kSerial, c.scene, 8, testing::margin3(1), c.options);
    ASSERT_FALSE(seq.failed) << seq.error;
    // Either the merge catches two partitions placing one node differently, or the meshes differ.
    EXPECT_TRUE(par.failed || par.checksum != seq.checksum);
  }
}

// The windows of r-adaptivity and face swapping inside the ghost (pipeline::Ghost) leave
// the ghost's outer part out (fewer leaves snapped than the forest holds) and mesh what the
// whole ghost meshes. r-adaptivity's window holds the leaves whose cube starts within 4
// cells of the box: 4 of the 7-cube ghost at level 0, 2 of 4 cubes at level 1, 1 of 3 at
// level 2; the guard's second pass runs on 2 of those cells, and meshes what it meshes on
// all 4. With the decisions near faces exchanged the windows are 2 cells (the guard's passes
// 1 and 0) in a narrower ghost: fewer leaves still, the same mesh.
TEST(Invariance3, WindowsLeaveOutTheGhostsOuterPart) {
  GhostRule whole_ghost;
  whole_ghost.radapt_window_cells3 = whole_ghost.swap_window_cells3 = -1;
  GhostRule guard_on_all_rule;  // the same windows forced: the guard's passes on all of r-adaptivity's
  guard_on_all_rule.radapt_window_cells3 = kRadaptWindow3;
  guard_on_all_rule.swap_window_cells3 = kSwapWindow3;
  for (const auto& c : testing::invariance_cases3()) {
    if (c.name.rfind("packed-level", 0) != 0) continue;
    SCOPED_TRACE(c.name);
    const testing::RunOutcome3 windows = testing::run_parallel3(kSerial, c.scene, 8, {}, c.options, false);
    const testing::RunOutcome3 whole = testing::run_parallel3(kSerial, c.scene, 8, whole_ghost, c.options);
    const testing::RunOutcome3 guard_on_all = testing::run_parallel3(kSerial, c.scene, 8, guard_on_all_rule, c.options);
    const testing::RunOutcome3 exchanged = testing::run_parallel3(kSerial, c.scene, 8, {}, c.options);
    ASSERT_FALSE(windows.failed) << windows.error;
    ASSERT_FALSE(exchanged.failed) << exchanged.error;
    EXPECT_EQ(exchanged.checksum, whole.checksum);
    EXPECT_GT(exchanged.distributed.exchanged_nodes, 0);
    EXPECT_LT(exchanged.distributed.counters.leaves, windows.distributed.counters.leaves);
    EXPECT_LT(exchanged.distributed.counters.snapping_leaves, windows.distributed.counters.snapping_leaves);
    EXPECT_LT(exchanged.distributed.counters.guarded_leaves, windows.distributed.counters.guarded_leaves);
    ASSERT_FALSE(whole.failed) << whole.error;
    ASSERT_FALSE(guard_on_all.failed) << guard_on_all.error;
    EXPECT_EQ(windows.checksum, whole.checksum);
    EXPECT_EQ(guard_on_all.checksum, whole.checksum);
    // The guard's second pass on 2 of r-adaptivity's 4 cells checks fewer leaves.
    EXPECT_LT(windows.distributed.counters.guarded_leaves, guard_on_all.distributed.counters.guarded_leaves);
    const auto& w = windows.distributed.counters;
    EXPECT_EQ(w.leaves, whole.distributed.counters.leaves);  // the same forests
    EXPECT_EQ(whole.distributed.counters.snapping_leaves, w.leaves);
    EXPECT_LT(w.snapping_leaves, 0.8 * static_cast<double>(w.leaves));
  }
}

// The tests can fail: with windows of half a cell, nodes on the box faces miss the options
// and refusals of the leaves beyond them (measured: one cell is the least these scenes pass
// with, at 7, 8, 27 and 64 partitions; README.md, "Ghost region (3D)"). Half a cell of the
// deciding level is a whole number of fine cells only below Lmax (these scenes have
// extra levels); at Lmax the window would round up to a whole cell. Whether a face meets a
// refusal there depends on where the boxes lie: each scene must break at 7 or 8 partitions.
TEST(Invariance3, TooSmallWindowBreaksIt) {
  GhostRule narrow;
  narrow.radapt_window_cells3 = narrow.swap_window_cells3 = 0.5;
  for (const auto& c : testing::invariance_cases3()) {
    if (c.name != "packed-level1" && c.name != "packed-level2") continue;
    SCOPED_TRACE(c.name);
    const testing::RunOutcome3 seq = testing::run_sequential3(c.scene, c.options);
    ASSERT_FALSE(seq.failed) << seq.error;
    int broken = 0;
    for (int n : {7, 8}) {
      const testing::RunOutcome3 par = testing::run_parallel3(kSerial, c.scene, n, narrow, c.options);
      broken += par.failed || par.checksum != seq.checksum;
    }
    EXPECT_GT(broken, 0);
  }
}

// A merge identity seen twice with different coordinates is a bug, named by its edge.
TEST(Merge3, DifferentCoordinatesForOneCutNodeAreABug) {
  grid::Lattice3 lattice;
  lattice.h = 1;
  lattice.max_level = 0;
  lattice.coarse_cells = {2, 1, 1};
  std::vector<PartitionOutput3> parts(2);
  const std::uint64_t a = grid::key3(1, 0, 0), b = grid::key3(1, 1, 1);
  for (int p = 0; p < 2; ++p) {
    auto& part = parts[static_cast<std::size_t>(p)];
    part.partition = p;
    part.box = {{p, 0, 0}, {p + 1, 1, 1}};
    auto& r = part.result;
    const double x = p == 0 ? 0.0 : 2.0;  // a tet on each side of the face x = 1
    r.mesh.coords = {1, 0, 0, 1, 1, 1, 1, 0.5, 0.5, x, 0, 0};
    r.mesh.cell_nodes = p == 0 ? std::vector<LocalId>{0, 1, 2, 3} : std::vector<LocalId>{0, 2, 1, 3};
    r.mesh.cell_phase = {1};
    r.node_identity = {{a, a}, {b, b}, {a, b}, {grid::key3(2 * p, 0, 0), grid::key3(2 * p, 0, 0)}};
  }
  {
    auto copy = parts;
    const NumberedPiece3 piece = merge_and_number<3>(kSerial, copy, lattice);
    EXPECT_EQ(piece.global_nodes, 5);  // two lattice nodes and a cut node merged
  }
  parts[1].result.mesh.coords[7] = 0.5 + 1e-15;
  try {
    merge_and_number<3>(kSerial, parts, lattice);
    FAIL();
  } catch (const CollectiveInternalError& e) {
    EXPECT_STREQ(e.what(), "partitions 0 and 1 place cut node on edge (1, 0, 0)-(1, 1, 1) differently");
  }
}

// What the STL shares give: every surface's box, the partition loads and the same-phase
// unions exactly as the sequential mesher computes them from every triangle.
TEST(StlShares, EqualTheWholeScenesBoxesLoadsAndUnions) {
  const geometry::SceneDesc lazy = testing::contact_scene3();
  const geometry::SceneDesc full = testing::with_triangles(lazy);
  geometry::SceneDesc scene = lazy;
  const StlShares shares = share_stl_surfaces(kSerial, scene, {}, true);
  EXPECT_EQ(shares.files_read, 3);  // octahedron, cube, torus: once each
  const std::vector<pipeline::SurfacePair> unions = pipeline::surface_unions(full);
  EXPECT_EQ(shares.unions, unions);
  ASSERT_EQ(unions.size(), 1u);  // the octahedron and the sphere it overlaps
  EXPECT_EQ(unions[0], (pipeline::SurfacePair{5, 6}));
  const std::vector<Box3> boxes = pipeline::holding_boxes(full);
  const std::vector<Box3> known = pipeline::holding_boxes(scene, shares.known);
  for (std::size_t k = 0; k < boxes.size(); ++k)
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(known[k].min[d], boxes[k].min[d]);
      EXPECT_EQ(known[k].max[d], boxes[k].max[d]);
    }
  for (const auto& inc : scene.inclusions)
    if (const auto* s = std::get_if<geometry::StlSurface>(&inc.shape)) {
      EXPECT_TRUE(s->triangles.empty());
    }
  const partition::Partition a = partition::partition_domain(full, 7);
  const partition::Partition b = partition::partition_domain(scene, 7, {}, shares.loads);
  ASSERT_EQ(a.parts.size(), b.parts.size());
  for (std::size_t i = 0; i < a.parts.size(); ++i) {
    EXPECT_EQ(a.parts[i].lattice_min, b.parts[i].lattice_min);
    EXPECT_EQ(a.parts[i].lattice_max, b.parts[i].lattice_max);
    EXPECT_EQ(a.parts[i].load, b.parts[i].load);  // bit for bit
    EXPECT_EQ(a.parts[i].inclusions, b.parts[i].inclusions);
  }
}

std::string write_scene_file(const fs::path& dir, const std::string& stl_a, const std::string& stl_b) {
  fs::create_directories(dir);
  const std::string path = (dir / "stl.json").string();
  std::ofstream f(path);
  f << R"({"format": "cisamr-scene/1", "dimension": 3, "domain": {"min": [0, 0, 0], "max": [3, 1, 1]},
    "mesh": {"h": 0.125, "levels": 0}, "phases": [{"id": 1, "name": "m"}, {"id": 2, "name": "g"}],
    "inclusions": [
      {"shape": "stl", "file": ")" << stl_a << R"(", "scale": 0.3, "translate": [0.2, 0.3, 0.3], "phase": 2},
      {"shape": "stl", "file": ")" << stl_b << R"(", "scale": 0.2, "translate": [2.6, 0.6, 0.6], "phase": 2,
       "levels": 1}]})";
  return path;
}

// Read from a scene file, the parallel mesher reads the STL files itself (each once per
// rank at most) and meshes as the sequential mesher given every triangle.
TEST(LazyStl, SceneFileWithStlSurfacesMeshesAsSequential) {
  const fs::path dir = fs::temp_directory_path() / "cisamr_parallel3_stl";
  const std::string path =
      write_scene_file(dir, CISAMR_SOURCE_DIR "/data/shapes/cube.stl", CISAMR_SOURCE_DIR "/data/shapes/octahedron.stl");
  const geometry::SceneDesc lazy = io::read_scene(path, io::ReadSceneOptions{.load_stl = false, .probe_stl = false});
  for (const auto& inc : lazy.inclusions) EXPECT_TRUE(std::get<geometry::StlSurface>(inc.shape).triangles.empty());
  const testing::RunOutcome3 seq = testing::run_sequential3(io::read_scene(path));
  ASSERT_FALSE(seq.failed) << seq.error;
  MeshOptions options;
  options.partitions = 16;
  const DistributedMesh3 dm = mesh_distributed<3>(kSerial, path, options);
  EXPECT_EQ(mesh_checksum3(dm.piece.mesh), seq.checksum);
  EXPECT_EQ(dm.stl_files_read, 2);  // one rank: its share is every file, kept for the kernel
  // The two surfaces are 2 apart: some partition does not load both.
  bool partial = false;
  for (const auto& p : dm.partitions) partial = partial || p.inclusions < 2;
  EXPECT_TRUE(partial);
  fs::remove_all(dir);
}

// An STL file that cannot be opened or parsed: the same one-line error as the sequential
// reader's, from whichever rank reads it.
TEST(LazyStl, BadFilesAreInputErrors) {
  const fs::path dir = fs::temp_directory_path() / "cisamr_parallel3_badstl";
  fs::create_directories(dir);
  {
    std::ofstream bad(dir / "bad.stl");
    bad << "solid broken\n  facet normal 0 0 1\n    outer loop\n      vertex 0 0\n";
  }
  const std::string good = CISAMR_SOURCE_DIR "/data/shapes/cube.stl";
  const auto error_of = [&](const std::string& path) {
    try {
      MeshOptions options;
      options.partitions = 3;
      mesh_distributed<3>(kSerial, path, options);
    } catch (const CollectiveInputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string sequential = [&] {
    try {
      io::read_scene(write_scene_file(dir, good, (dir / "bad.stl").string()));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  }();
  EXPECT_NE(sequential.find("bad.stl"), std::string::npos) << sequential;
  EXPECT_EQ(error_of(write_scene_file(dir, good, (dir / "bad.stl").string())), sequential);
  const std::string missing = error_of(write_scene_file(dir, good, (dir / "missing.stl").string()));
  EXPECT_NE(missing.find("inclusions[1].file: cannot read"), std::string::npos) << missing;
  EXPECT_NE(missing.find("missing.stl"), std::string::npos) << missing;
  fs::remove_all(dir);
}

TEST(Output3, PvtuPiecesOfTetrahedra) {
  const fs::path dir = fs::temp_directory_path() / "cisamr_parallel3_pvtu";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto c = testing::invariance_cases3().back();
  const testing::RunOutcome3 par = testing::run_parallel3(kSerial, c.scene, 3, {}, c.options);
  ASSERT_FALSE(par.failed) << par.error;
  write_pvtu<3>(kSerial, (dir / "m.pvtu").string(), par.distributed.piece.mesh);
  EXPECT_TRUE(fs::exists(dir / "m.pvtu"));
  EXPECT_GT(fs::file_size(dir / "m_0.vtu"), 1000u);
  fs::remove_all(dir);
}

}  // namespace

}  // namespace cisamr::parallel
