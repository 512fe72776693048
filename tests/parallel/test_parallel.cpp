// lib/parallel through the serial Comm: ghost regions, the merge, partition invariance for
// (1 rank, 1 and 7 partitions), output files, error agreement. The MPI tests
// (test_parallel_mpi.cpp, cli_test.sh) run the same checks on 2-4 ranks.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

#include "io/mesh_io.hpp"
#include "io/scene_io.hpp"
#include "parallel/collective.hpp"
#include "parallel/output.hpp"
#include "scenes.hpp"
#include "support/cohesive_compare.hpp"
#include "quality/quality.hpp"
#include "pipeline/effective_levels.hpp"
#include "samr/samr2.hpp"

namespace cisamr::parallel {
namespace {

namespace fs = std::filesystem;
const SerialComm kSerial;

TEST(InclusionIndex, QueryMatchesBruteForce) {
  const geometry::SceneDesc scene = testing::corner_scene();
  const grid::Lattice2 lattice = scene_lattice2(scene, {});
  for (bool level_aware : {true, false}) {
    GhostRule rule;
    rule.level_aware = level_aware;
    const InclusionIndex2 index(scene, lattice, rule);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-4, 36);
    for (int q = 0; q < 300; ++q) {
      double x0 = u(rng), x1 = u(rng), y0 = u(rng), y1 = u(rng);
      const Box2 box{{std::min(x0, x1), std::min(y0, y1)}, {std::max(x0, x1), std::max(y0, y1)}};
      std::vector<std::int32_t> found, expected;
      index.query(box, found);
      for (std::int32_t k = 0; k < index.size(); ++k)
        if (boxes_overlap(index.inflated(k), box)) expected.push_back(k);
      ASSERT_EQ(found, expected);
    }
  }
}

TEST(InclusionIndex, LevelAwareMarginShrinksWithLevels) {
  const geometry::SceneDesc scene = testing::corner_scene();
  const InclusionIndex2 index(scene, scene_lattice2(scene, {}), GhostRule{});
  // inclusions[22] is a circle of radius 0.9 with levels 3: margin 4·h/8 = 0.5.
  const Box2 b = index.inflated(22);
  EXPECT_NEAR(b.max[0] - b.min[0], 2 * 0.9 + 2 * 0.5, 1e-12);
  // inclusions[0] has levels 1: margin 4·h/2.
  const Box2 c = index.inflated(0);
  EXPECT_NEAR(c.max[0] - c.min[0], 2 * std::get<geometry::Circle>(scene.inclusions[0].shape).radius + 4.0, 1e-12);
}

// The default ghost (no closure rounds: levels are settled by effective_levels2) loads
// exactly the inclusions whose inflated box meets the grown box.
TEST(GhostRegion, DefaultLoadsTheInclusionsMeetingTheGrownBox) {
  const geometry::SceneDesc scene = testing::corner_scene();
  const grid::Lattice2 lattice = scene_lattice2(scene, {});
  const GhostRule rule;
  ASSERT_EQ(rule.max_closure_rounds, 0);
  const InclusionIndex2 index(scene, lattice, rule);
  const grid::CellRange<2> box{{10, 6}, {17, 12}};
  const GhostRegion2 region = ghost_region2(index, lattice, box, rule);
  const Box2 seed{{10.0 - rule.box_margin_cells, 6.0 - rule.box_margin_cells},
                  {17.0 + rule.box_margin_cells, 12.0 + rule.box_margin_cells}};
  std::vector<std::int32_t> expected;
  for (std::int32_t k = 0; k < index.size(); ++k)
    if (boxes_overlap(index.inflated(k), seed)) expected.push_back(k);
  EXPECT_EQ(region.inclusions, expected);
  EXPECT_LT(region.inclusions.size(), scene.inclusions.size());
  // Only the grown box's cells are meshed, not the loaded inclusions' boxes, some of which
  // reach beyond it.
  bool beyond = false;
  for (std::int32_t k : region.inclusions)
    for (int d = 0; d < 2; ++d)
      beyond = beyond || index.inflated(k).min[d] < seed.min[d] || index.inflated(k).max[d] > seed.max[d];
  EXPECT_TRUE(beyond);
  const auto margin = static_cast<std::int64_t>(rule.box_margin_cells);
  for (int d = 0; d < 2; ++d) {
    EXPECT_EQ(region.range.lo[d], std::max<std::int64_t>(0, box.lo[d] - margin));
    EXPECT_EQ(region.range.hi[d], std::min<std::int64_t>(lattice.coarse_cells[d], box.hi[d] + margin));
  }
}

// The full closure, kept for comparison (--ghost-closure-rounds -1).
TEST(GhostRegion, IsTheClosureOfMeetingInflatedBoxes) {
  const geometry::SceneDesc scene = testing::corner_scene();
  const grid::Lattice2 lattice = scene_lattice2(scene, {});
  for (bool level_aware : {true, false}) {
    GhostRule rule;
    rule.level_aware = level_aware;
    rule.max_closure_rounds = -1;
    const InclusionIndex2 index(scene, lattice, rule);
    const grid::CellRange<2> box{{10, 6}, {17, 12}};
    const GhostRegion2 region = ghost_region2(index, lattice, box, rule);
    const Box2 seed{{10.0 - rule.box_margin_cells, 6.0 - rule.box_margin_cells},
                    {17.0 + rule.box_margin_cells, 12.0 + rule.box_margin_cells}};
    // Brute-force fixed point.
    std::vector<char> in(static_cast<std::size_t>(index.size()), 0);
    for (bool changed = true; changed;) {
      changed = false;
      for (std::int32_t k = 0; k < index.size(); ++k) {
        if (in[static_cast<std::size_t>(k)]) continue;
        bool meets = boxes_overlap(index.inflated(k), seed);
        for (std::int32_t j = 0; j < index.size() && !meets; ++j)
          meets = in[static_cast<std::size_t>(j)] && boxes_overlap(index.inflated(k), index.inflated(j));
        if (meets) in[static_cast<std::size_t>(k)] = 1, changed = true;
      }
    }
    std::vector<std::int32_t> expected;
    for (std::int32_t k = 0; k < index.size(); ++k)
      if (in[static_cast<std::size_t>(k)]) expected.push_back(k);
    EXPECT_EQ(region.inclusions, expected);
    if (level_aware) {
      EXPECT_LT(region.inclusions.size(), scene.inclusions.size());  // not the whole scene
    }
    for (std::int32_t k : region.inclusions)  // the range covers every loaded inflated box
      for (int d = 0; d < 2; ++d) {
        EXPECT_LE(static_cast<double>(region.range.lo[d]), std::max(0.0, index.inflated(k).min[d]));
        EXPECT_GE(static_cast<double>(region.range.hi[d]),
                  std::min(static_cast<double>(lattice.coarse_cells[d]), index.inflated(k).max[d]));
        EXPECT_GE(box.lo[d] - region.range.lo[d], 0);
        EXPECT_LE(box.lo[d] - region.range.lo[d], region.ghost);
        EXPECT_LE(region.range.hi[d] - box.hi[d], region.ghost);
      }
  }
}

TEST(GhostRegion, SubsetKeepsOrder) {
  const geometry::SceneDesc scene = testing::corner_scene();
  const geometry::SceneDesc sub = subset_scene(scene, {3, 7, 22});
  ASSERT_EQ(sub.inclusions.size(), 3u);
  EXPECT_EQ(sub.inclusions[1].levels, scene.inclusions[7].levels);
  EXPECT_EQ(std::get<geometry::Circle>(sub.inclusions[2].shape).center,
            std::get<geometry::Circle>(scene.inclusions[22].shape).center);
  EXPECT_EQ(sub.phases.size(), scene.phases.size());
}

TEST(Distribution, BlocksCoverPartitionsInOrder) {
  for (int n = 1; n <= 20; ++n)
    for (int p = 1; p <= n; ++p) {
      int next = 0;
      for (int r = 0; r < p; ++r) {
        const auto [first, last] = partitions_of_rank(n, p, r);
        EXPECT_EQ(first, next);
        EXPECT_GE(last - first, n / p);
        EXPECT_LE(last - first, n / p + 1);
        for (int i = first; i < last; ++i) EXPECT_EQ(rank_of_partition(i, n, p), r);
        next = last;
      }
      EXPECT_EQ(next, n);
    }
}

// The heart of it: the merged mesh of N partitions on one rank is the sequential one.
void expect_invariant(const geometry::SceneDesc& scene, int partitions, bool level_aware, bool strict_quality) {
  const testing::RunOutcome seq = testing::run_sequential(scene);
  const testing::RunOutcome par = testing::run_parallel(kSerial, scene, partitions, level_aware);
  ASSERT_EQ(seq.failed, par.failed) << seq.error << " | " << par.error;
  if (seq.failed) return;
  EXPECT_EQ(par.mesh.cell_count(), seq.mesh.cell_count());
  EXPECT_EQ(par.mesh.node_count(), seq.mesh.node_count());
  EXPECT_TRUE(canonical_triangles(par.mesh) == canonical_triangles(seq.mesh));
  EXPECT_EQ(par.checksum, seq.checksum);
  EXPECT_EQ(mesh_checksum2(par.mesh), seq.checksum);
  // DESIGN.md §2 across partition boundaries.
  bool voids = false;
  for (const auto& p : scene.phases) voids = voids || p.is_void;
  const Box2 domain{{scene.domain_min[0], scene.domain_min[1]}, {scene.domain_max[0], scene.domain_max[1]}};
  const double area = (domain.max[0] - domain.min[0]) * (domain.max[1] - domain.min[1]);
  const auto conf = quality::check_conformity(par.mesh, domain, voids ? -1.0 : area, voids);
  EXPECT_EQ(conf.duplicate_nodes, 0u);
  EXPECT_EQ(conf.hanging_nodes, 0u);
  EXPECT_EQ(conf.open_facets_inside, 0u);
  EXPECT_EQ(conf.unused_nodes, 0u);
  EXPECT_TRUE(conf.ok) << (conf.examples.empty() ? "" : conf.examples.front());
  if (strict_quality) {
    EXPECT_LE(quality::aspect_statistics(par.mesh, 3.0).max, 3.0);
    const geometry::Oracle2 oracle(scene);
    const auto fid = quality::check_fidelity(par.mesh, oracle, quality::default_fidelity_tolerance(scene));
    EXPECT_TRUE(fid.ok) << (fid.examples.empty() ? "" : fid.examples.front());
  }
  // Global ids: 0..n-1, each once; a rank owns the first owned_nodes of its piece.
  std::vector<char> seen(static_cast<std::size_t>(par.distributed.piece.global_nodes), 0);
  for (GlobalId g : par.distributed.piece.mesh.node_global_id) seen[static_cast<std::size_t>(g)]++;
  for (char s : seen) EXPECT_EQ(s, 1);
}

class Invariance : public ::testing::TestWithParam<int> {};

TEST(CornerScene, IsValid) {
  EXPECT_NO_THROW(geometry::Oracle2{testing::corner_scene()});
}

TEST_P(Invariance, CornerScene) {
  const geometry::SceneDesc scene = testing::corner_scene();
  expect_invariant(scene, GetParam(), true, true);
  expect_invariant(scene, GetParam(), false, true);
}

TEST_P(Invariance, RandomScenes) {
  for (unsigned seed = 1; seed <= 16; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    expect_invariant(testing::random_scene(seed), GetParam(), true, false);
  }
}

// Periodic scenes (issue 12): windows wrap across the faces; the mesh is still the
// sequential one, bit for bit.
TEST_P(Invariance, PeriodicRandomScenes) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    expect_invariant(cisamr::testing::periodic_scene(seed), GetParam(), true, false);
  }
}

TEST_P(Invariance, SparseRandomScenes) {
  for (unsigned seed = 1; seed <= 16; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    expect_invariant(testing::sparse_random_scene(seed), GetParam(), true, false);
  }
}

// Packed scenes like the benchmark's at every level: the 2-cell margin holds at each
// (lib/parallel/README.md, "Ghost region (2D)").
TEST_P(Invariance, PackedScenesAtEveryLevel) {
  for (int levels = 0; levels <= 3; ++levels) {
    SCOPED_TRACE("levels " + std::to_string(levels));
    expect_invariant(testing::packed_scene2(40 + static_cast<unsigned>(levels), levels, 48, 40), GetParam(), true, false);
  }
}

// One coarse cell of margin is too few: a box cell's neighbour beyond the face lies in the
// first layer of the range, which the whole run may refine more (cascades from cells the
// partition does not have).
TEST(Invariance, OneCellMarginBreaksIt) {
  GhostRule one;
  one.box_margin_cells = 1;
  int differing = 0;
  for (int levels = 0; levels <= 3; ++levels) {
    const geometry::SceneDesc scene = testing::packed_scene2(40 + static_cast<unsigned>(levels), levels, 48, 40);
    const testing::RunOutcome seq = testing::run_sequential(scene);
    const testing::RunOutcome par = testing::run_parallel(kSerial, scene, 7, one);
    differing += seq.failed || par.failed || par.checksum != seq.checksum;
  }
  EXPECT_GE(differing, 3);
}

// The tests can fail: without the ghost margins the merged mesh is not the sequential one.
TEST(Invariance, NoMarginBreaksIt) {
  GhostRule none;
  none.level_aware = false;
  none.fixed_cells = 0;
  none.box_margin_cells = 0;
  int differing = 0;
  for (unsigned seed = 1; seed <= 8; ++seed) {
    const geometry::SceneDesc scene = testing::sparse_random_scene(seed);
    const testing::RunOutcome seq = testing::run_sequential(scene);
    const testing::RunOutcome par = testing::run_parallel(kSerial, scene, 7, none);
    differing += seq.failed || par.failed || par.checksum != seq.checksum;
  }
  EXPECT_GE(differing, 4);
}

// Sparse scenes: a partition loads part of the scene, not all of it.
TEST(Invariance, GhostRegionsArePartial) {
  const geometry::SceneDesc scene = testing::corner_scene();
  const testing::RunOutcome par = testing::run_parallel(kSerial, scene, 8);
  ASSERT_FALSE(par.failed) << par.error;
  for (const auto& p : par.distributed.partitions) EXPECT_LT(p.inclusions, par.distributed.scene_inclusions);
}

TEST_P(Invariance, DataExample) {
  const geometry::SceneDesc scene = io::read_scene(CISAMR_SOURCE_DIR "/data/examples/composite.json");
  expect_invariant(scene, GetParam(), true, false);
}

// Cohesive cells (issue 13): the same cells and copies for 1, 7 and 13 partitions, each
// interface facet covered once in the gathered mesh, across partition faces and periodic
// planes (facets there are paired between partitions), one global id per copy.
std::int64_t expect_cohesive_invariant(const geometry::SceneDesc& scene, int partitions) {
  pipeline::Options options;
  options.cohesive = true;
  const testing::RunOutcome seq = testing::run_sequential(scene, options);
  const testing::RunOutcome par = testing::run_parallel(kSerial, scene, partitions, GhostRule{}, options);
  EXPECT_EQ(seq.failed, par.failed) << seq.error << " | " << par.error;
  if (seq.failed || par.failed) return 0;
  EXPECT_EQ(par.checksum, seq.checksum);
  EXPECT_EQ(mesh_checksum2(par.mesh), seq.checksum);
  EXPECT_EQ(par.mesh.node_count(), seq.mesh.node_count());
  EXPECT_EQ(par.mesh.cohesive.count(), seq.mesh.cohesive.count());
  const auto frame = cisamr::testing::cohesive_frame<2>(scene, pipeline::make_lattice<2>(scene, options));
  const bool voids = std::ranges::any_of(scene.phases, [](const geometry::Phase& p) { return p.is_void; });
  EXPECT_TRUE(cisamr::testing::cohesive_mesh_is_right(seq.mesh, frame, voids));
  EXPECT_TRUE(cisamr::testing::cohesive_mesh_is_right(par.mesh, frame, voids));
  std::vector<char> seen(static_cast<std::size_t>(par.distributed.piece.global_nodes), 0);
  for (GlobalId g : par.distributed.piece.mesh.node_global_id) seen[static_cast<std::size_t>(g)]++;
  for (char s : seen) EXPECT_EQ(s, 1);
  return static_cast<std::int64_t>(par.mesh.cohesive.count());
}

TEST_P(Invariance, CohesiveScenes) {
  std::int64_t cells = expect_cohesive_invariant(testing::corner_scene(), GetParam());
  for (unsigned seed = 1; seed <= 8; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    cells += expect_cohesive_invariant(testing::random_scene(seed), GetParam());
  }
  for (unsigned seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE("periodic seed " + std::to_string(seed));
    cells += expect_cohesive_invariant(cisamr::testing::periodic_scene(seed), GetParam());
  }
  EXPECT_GT(cells, 1000);
}

TEST_P(Invariance, CohesiveCellsOnPeriodicPlanes) {
  const geometry::SceneDesc scene = testing::periodic_plane_scene();
  expect_cohesive_invariant(scene, GetParam());
  pipeline::Options options;
  options.cohesive = true;
  const testing::RunOutcome par = testing::run_parallel(kSerial, scene, GetParam(), GhostRule{}, options);
  ASSERT_FALSE(par.failed) << par.error;
  const auto frame = cisamr::testing::cohesive_frame<2>(scene, pipeline::make_lattice<2>(scene, options));
  // Box 2 on x = 0 (length 4), box 3 on x = 0 (3) and y = 0 (2): the cells on the planes
  // (edges of the finest level the contact asked for) have these lengths in all.
  EXPECT_GT(cisamr::testing::cohesive_cells_on_periodic_planes(par.mesh, frame), 9);
  double plane_length = 0;
  for (std::size_t c = 0; c < par.mesh.cohesive.count(); ++c) {
    const Vec2 a = par.mesh.point(par.mesh.cohesive.cell(c)[0]), b = par.mesh.point(par.mesh.cohesive.cell(c)[1]);
    if ((a[0] == 0 && b[0] == 0) || (a[1] == 0 && b[1] == 0)) plane_length += std::hypot(b[0] - a[0], b[1] - a[1]);
  }
  EXPECT_DOUBLE_EQ(plane_length, 9.0);
  // Where boxes 2 and 3 meet the matrix, at (2, 3) and on the plane at (0, 3): three copies.
  EXPECT_GE(cisamr::testing::multi_phase_points(par.mesh), 2);
  mesh::Mesh2 broken = par.mesh;
  for (std::size_t c = 0; c < broken.cohesive.count(); ++c)
    if (broken.point(broken.cohesive.cell(c)[0])[0] == 0 && broken.point(broken.cohesive.cell(c)[1])[0] == 0) {
      broken.cohesive.nodes.erase(broken.cohesive.nodes.begin() + static_cast<std::ptrdiff_t>(4 * c),
                                  broken.cohesive.nodes.begin() + static_cast<std::ptrdiff_t>(4 * c + 4));
      broken.cohesive.phase.erase(broken.cohesive.phase.begin() + static_cast<std::ptrdiff_t>(2 * c),
                                  broken.cohesive.phase.begin() + static_cast<std::ptrdiff_t>(2 * c + 2));
      broken.cohesive.partition.erase(broken.cohesive.partition.begin() + static_cast<std::ptrdiff_t>(c));
      break;
    }
  const auto r = quality::check_cohesive<2>(broken, &frame);
  EXPECT_EQ(r.uncovered.count, 1u) << r.summary();
  EXPECT_EQ(quality::check_cohesive<2>(broken).uncovered.count, 0u);  // not seen without the period
}

INSTANTIATE_TEST_SUITE_P(OneRank, Invariance, ::testing::Values(1, 7, 13));

// samr::kReachCoarseCells2, directly: SAMR over a sub-range (its cells beyond missing, the
// inclusions that meet it loaded, the whole scene's effective levels) gives every coarse
// cell beyond the range's first layer the whole run's leaves; in the first layer it may not.
TEST(SamrReach2, BeyondTheFirstLayerTheForestIsTheWholeRunsForest) {
  using Leaf = std::array<std::int64_t, 3>;  // level, i, j
  const auto leaves = [](const samr::RefinedGrid2& g, const grid::CellRange<2>& inner) {
    std::vector<Leaf> out;
    for (std::int32_t c = 0; c < static_cast<std::int32_t>(g.forest.size()); ++c) {
      if (!g.forest.is_leaf(c)) continue;
      const auto at = g.forest.coarse_cell(c);
      if (at[0] < inner.lo[0] || at[0] >= inner.hi[0] || at[1] < inner.lo[1] || at[1] >= inner.hi[1]) continue;
      const auto& x = g.forest.cell(c);
      out.push_back({x.level, x.i, x.j});
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  int compared = 0, first_layer_differs = 0;
  for (int levels = 1; levels <= 3; ++levels)
    for (unsigned seed = 1; seed <= 3; ++seed) {
      const geometry::SceneDesc scene = testing::packed_scene2(60 + seed, levels, 48, 40);
      const auto lattice = scene_lattice2(scene, {});
      const std::vector<int> levels_all = pipeline::effective_levels2(scene, lattice);
      const samr::RefinedGrid2 whole = samr::refine2(geometry::Oracle2(scene), lattice, {{0, 0}, {48, 40}}, levels_all);
      const InclusionIndex2 index(scene, lattice, GhostRule{});
      for (const grid::CellRange<2> range : {grid::CellRange<2>{{7, 5}, {29, 23}}, grid::CellRange<2>{{20, 13}, {41, 35}}}) {
        std::vector<std::int32_t> loaded;
        index.query(Box2{{static_cast<double>(range.lo[0]), static_cast<double>(range.lo[1])},
                         {static_cast<double>(range.hi[0]), static_cast<double>(range.hi[1])}},
                    loaded);
        std::vector<int> levels_part;
        for (std::int32_t k : loaded) levels_part.push_back(levels_all[static_cast<std::size_t>(k)]);
        const samr::RefinedGrid2 part =
            samr::refine2(geometry::Oracle2(subset_scene(scene, loaded)), lattice, range, levels_part);
        const int r = samr::kReachCoarseCells2;
        const grid::CellRange<2> inner{{range.lo[0] + r, range.lo[1] + r}, {range.hi[0] - r, range.hi[1] - r}};
        EXPECT_EQ(leaves(part, inner), leaves(whole, inner)) << "levels " << levels << ", seed " << seed;
        first_layer_differs += leaves(part, range) != leaves(whole, range) ? 1 : 0;
        ++compared;
      }
    }
  EXPECT_EQ(compared, 18);
  EXPECT_GT(first_layer_differs, 0);  // the comparison can fail
}

// The sweep behind the 2D margin (lib/parallel/README.md, "Ghost region (2D)"): scenes of
// every kind at levels 0-3 against the whole-domain mesh at 4 to 64 partitions; minutes, so
// not in the suite: `test_parallel --gtest_also_run_disabled_tests
// --gtest_filter='*SweepOfPackedAndRandomScenes'`.
TEST(Invariance, DISABLED_SweepOfPackedAndRandomScenes) {
  GhostRule rule;
  if (const char* m = std::getenv("CISAMR_SWEEP_MARGIN2")) rule.box_margin_cells = std::atof(m);
  int runs = 0, differing = 0;
  const auto check = [&](const geometry::SceneDesc& scene, const std::string& name, const pipeline::Options& options = {}) {
    const testing::RunOutcome seq = testing::run_sequential(scene, options);
    ASSERT_FALSE(seq.failed) << name << ": " << seq.error;
    for (int n : {4, 7, 13, 16, 27, 64}) {
      const testing::RunOutcome par = testing::run_parallel(kSerial, scene, n, rule, options);
      ++runs;
      const bool same = !par.failed && par.checksum == seq.checksum && par.mesh.cell_count() == seq.mesh.cell_count();
      differing += same ? 0 : 1;
      EXPECT_TRUE(same) << name << ", " << n << " partitions" << (par.failed ? ": " + par.error : "");
    }
  };
  for (unsigned seed = 1; seed <= 6; ++seed)
    for (int levels = 0; levels <= 3; ++levels)
      check(testing::packed_scene2(seed, levels, 48, 40), "packed, level " + std::to_string(levels) + ", seed " + std::to_string(seed));
  pipeline::Options no_extra, cohesive;
  no_extra.extra_levels = 0;
  cohesive.cohesive = true;
  for (unsigned seed = 1; seed <= 4; ++seed)
    for (int levels = 0; levels <= 2; ++levels) {
      const geometry::SceneDesc s = testing::packed_scene2(100 + seed, levels, 48, 40, 0.35, 1.5, 0.2);
      const std::string name = "dense small, level " + std::to_string(levels) + ", seed " + std::to_string(seed);
      check(s, name);
      check(s, name + ", no extra levels", no_extra);
    }
  for (unsigned seed = 1; seed <= 4; ++seed) check(testing::random_scene(seed), "cohesive, seed " + std::to_string(seed), cohesive);
  for (unsigned seed = 17; seed <= 48; ++seed) check(testing::random_scene(seed), "random, seed " + std::to_string(seed));
  for (unsigned seed = 17; seed <= 40; ++seed) check(testing::sparse_random_scene(seed), "sparse, seed " + std::to_string(seed));
  for (unsigned seed = 5; seed <= 12; ++seed) check(cisamr::testing::periodic_scene(seed), "periodic, seed " + std::to_string(seed));
  check(testing::corner_scene(), "corner");
  std::printf("%d runs, %d differ from the whole-domain mesh (margin %g)\n", runs, differing, rule.box_margin_cells);
}

TEST(Invariance, PartitionCornersAreStraddled) {
  const geometry::SceneDesc scene = testing::corner_scene();
  for (int n : {5, 7}) {  // the (2 ranks, 5) and (1 rank, 7) cases
    const testing::RunOutcome par = testing::run_parallel(kSerial, scene, n);
    ASSERT_FALSE(par.failed) << par.error;
    EXPECT_GE(testing::straddled_corners(par.distributed, scene), 1) << n << " partitions";
  }
}

TEST(Invariance, GlobalIdsDoNotDependOnRanksOnlyOnPartitions) {
  // Owned-first numbering in (owner partition, kernel order): for 1 rank and N partitions
  // the gathered mesh's node order equals the piece's, owned first = all.
  const geometry::SceneDesc scene = testing::corner_scene();
  const testing::RunOutcome par = testing::run_parallel(kSerial, scene, 6);
  ASSERT_FALSE(par.failed);
  const auto& piece = par.distributed.piece;
  EXPECT_EQ(piece.owned_nodes, piece.global_nodes);
  for (std::size_t i = 0; i < piece.mesh.node_global_id.size(); ++i)
    ASSERT_EQ(piece.mesh.node_global_id[i], static_cast<GlobalId>(i));
  // Cells come partition by partition.
  EXPECT_TRUE(std::is_sorted(piece.mesh.cell_partition.begin(), piece.mesh.cell_partition.end()));
}

TEST(Merge, DifferentCoordinatesForOneKeyAreABug) {
  const grid::Lattice2 lattice{{0, 0}, 1.0, 0, {2, 1}};
  std::vector<PartitionOutput2> parts(2);
  for (int p = 0; p < 2; ++p) {
    parts[static_cast<std::size_t>(p)].partition = p;
    parts[static_cast<std::size_t>(p)].box = {{p, 0}, {p + 1, 1}};
    auto& r = parts[static_cast<std::size_t>(p)].result;
    const double x0 = p, x1 = p + 1;
    r.mesh.coords = {x0, 0, x1, 0, x1, 1, x0, 1};
    r.mesh.cell_nodes = {0, 1, 2, 0, 2, 3};
    r.mesh.cell_phase = {1, 1};
    r.node_identity = {grid::key2(p, 0), grid::key2(p + 1, 0), grid::key2(p + 1, 1), grid::key2(p, 1)};
  }
  {
    auto copy = parts;
    const NumberedPiece2 piece = merge_and_number2(kSerial, copy, lattice);
    EXPECT_EQ(piece.global_nodes, 6);  // two shared nodes merged by key
    EXPECT_EQ(piece.mesh.cell_count(), 4u);
  }
  parts[1].result.mesh.coords[0] = 1.0 + 1e-15;  // the shared node (1,0), placed differently
  try {
    merge_and_number2(kSerial, parts, lattice);
    FAIL();
  } catch (const CollectiveInternalError& e) {  // a bug, agreed between ranks like any error
    EXPECT_STREQ(e.what(), "partitions 0 and 1 place lattice node (1, 0) differently");
  }
}

// A rank's first partition is moved into the piece, not merged with itself: an identity
// on its face twice is a bug, reported as such.
TEST(Merge, AFaceIdentityTwiceInOnePartitionIsABug) {
  const grid::Lattice2 lattice{{0, 0}, 1.0, 0, {2, 1}};
  std::vector<PartitionOutput2> parts(1);
  parts[0].box = {{0, 0}, {1, 1}};
  auto& r = parts[0].result;
  r.mesh.coords = {0, 0, 1, 0, 1, 1, 0, 1};
  r.mesh.cell_nodes = {0, 1, 2, 0, 2, 3};
  r.mesh.cell_phase = {1, 1};
  r.node_identity = {grid::key2(0, 0), grid::key2(1, 0), grid::key2(1, 0), grid::key2(0, 1)};
  try {
    merge_and_number2(kSerial, parts, lattice);
    FAIL();
  } catch (const CollectiveInternalError& e) {
    EXPECT_STREQ(e.what(), "partition 0 emits lattice node (1, 0) twice");
  }
}

TEST(Collective, ErrorsKeepTheirKindAndText) {
  try {
    run_collectively(kSerial, [] { throw InputError("a.json", "inclusions[2].radius", "must be positive"); });
    FAIL();
  } catch (const InputError& e) {
    EXPECT_TRUE(is_collective(e));
    EXPECT_STREQ(e.what(), "a.json: inclusions[2].radius: must be positive");
  }
  EXPECT_THROW(run_collectively(kSerial, [] { throw MeshingError("too fine"); }), CollectiveMeshingError);
  EXPECT_THROW(run_collectively(kSerial, [] { throw std::out_of_range("bug"); }), CollectiveInternalError);
  EXPECT_NO_THROW(run_collectively(kSerial, [] {}));
}

TEST(Collective, SubsetOracleErrorsNameSceneIndices) {
  geometry::SceneDesc scene = testing::corner_scene();
  // Two overlapping circles of different phases, far from the others' first partition.
  geometry::Inclusion a, b;
  a.shape = geometry::Circle{{30.5, 1.5}, 1.0};
  a.phase = 2;
  b.shape = geometry::Circle{{31.0, 1.6}, 0.8};
  b.phase = 3;
  scene.inclusions.push_back(a);
  scene.inclusions.push_back(b);
  std::string sequential, parallel;
  try {
    geometry::Oracle2 oracle(scene);
  } catch (const InputError& e) {
    sequential = e.what();
  }
  MeshOptions options;
  options.partitions = 1;
  try {
    mesh_distributed<2>(kSerial, scene, options);
  } catch (const InputError& e) {
    parallel = e.what();
  }
  EXPECT_FALSE(sequential.empty());
  EXPECT_EQ(parallel, sequential);
}

TEST(Collective, TooFewPartitionsForTheRanksIsAnInputError) {
  MeshOptions options;
  options.partitions = 0;
  EXPECT_THROW(mesh_distributed<2>(kSerial, testing::corner_scene(), options), CollectiveInputError);
}

class TempDir {
 public:
  TempDir() : path_(fs::temp_directory_path() / ("cisamr_parallel_test_" + std::to_string(::getpid()))) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  std::size_t entries() const {
    return static_cast<std::size_t>(std::distance(fs::directory_iterator(path_), fs::directory_iterator()));
  }

 private:
  fs::path path_;
};

TEST(Output, PvtuListsPiecesThatReadBack) {
  TempDir dir;
  const testing::RunOutcome par = testing::run_parallel(kSerial, testing::corner_scene(), 4);
  ASSERT_FALSE(par.failed);
  write_pvtu2(kSerial, dir.file("out.pvtu"), par.distributed.piece.mesh);
  EXPECT_EQ(dir.entries(), 2u);
  std::ifstream in(dir.file("out.pvtu"));
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("<Piece Source=\"out_0.vtu\"/>"), std::string::npos);
  EXPECT_NE(text.find("Name=\"global_id\""), std::string::npos);
  const io::LoadedMesh piece = io::read_mesh(dir.file("out_0.vtu"));
  EXPECT_EQ(piece.mesh2.cell_count(), par.mesh.cell_count());
  EXPECT_EQ(piece.mesh2.node_global_id, par.distributed.piece.mesh.node_global_id);
  EXPECT_EQ(piece.mesh2.cell_partition, par.distributed.piece.mesh.cell_partition);
}

TEST(Output, UnwritablePieceLeavesNothing) {
  TempDir dir;
  const testing::RunOutcome par = testing::run_parallel(kSerial, testing::corner_scene(), 2);
  ASSERT_FALSE(par.failed);
  fs::create_directories(dir.file("out_0.vtu/inside"));  // the piece's name is a directory
  try {
    write_pvtu2(kSerial, dir.file("out.pvtu"), par.distributed.piece.mesh);
    FAIL();
  } catch (const CollectiveInputError& e) {
    EXPECT_NE(std::string(e.what()).find("out_0.vtu: cannot write"), std::string::npos) << e.what();
  }
  EXPECT_EQ(dir.entries(), 1u);  // only the directory we made
}

}  // namespace
}  // namespace cisamr::parallel
