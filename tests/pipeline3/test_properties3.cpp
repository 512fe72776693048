// Property suite of the 3D mesher (DESIGN.md §2) over seeded random scenes
// (random_scenes3.hpp: spheres, ellipsoids up to 5:1, fibres, STL shapes, voids, clipped,
// tangent, lattice-aligned, overlapping, mixed). For every scene:
//   - Oracle3 accepts it; the mesh is conforming (quality::check_conformity: shared facets,
//     orientation, no duplicate or hanging node, volume = domain − voids), no tet inverted;
//   - every tetrahedron's aspect ratio ≤ 5.0 (DESIGN.md §2.2, no exception);
//   - phase fidelity (quality::check_fidelity): every node within 1e-9 of the domain of the
//     closure of its tets' phases, except nodes the snapping guard collapsed
//     (radapt/README.md): those may be off by the reported largest deviation, which must stay
//     below one cell diagonal, and no more nodes than were collapsed may need it;
//   - on scenes whose features span at least two cells of their level, every phase's volume
//     close to the exact one (10 % on smooth interfaces, first-order slack on sharp ones),
//     and on smooth ones (spheres and ellipsoids, none clipped or touching) no tet in
//     another phase and no centroid beyond check_fidelity's strict slack. Sharp edges and
//     corners are chamfered by up to a cell (no feature matching: lib/pipeline/README.md),
//     so tets there may straddle them.
// Prints a summary per shard and over every scene that ran: worst aspect ratio and its seed,
// dihedral extremes, face swaps, collapsed nodes, volume errors, by scene kind.
//
// One scene: CISAMR_SEED=N test_properties3 --gtest_filter='*FromEnvironment'
// (CISAMR_VERBOSE=1 prints a line per scene).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "geometry/oracle.hpp"
#include "io/stl_io.hpp"
#include "mesh/metrics.hpp"
#include "pipeline/pipeline.hpp"
#include "quality/quality.hpp"
#include "random_scenes3.hpp"
#include "reference_volumes3.hpp"
#include "support/cohesive_split.hpp"

namespace cisamr {
namespace {

constexpr double kMaxAspect3 = 5.0;       // DESIGN.md §2.2
// Per-phase volume error on resolved scenes (features ≥ kResolvedCells cells): smooth
// interfaces converge at second order (a sphere of radius 2 cells loses ~8 %); sharp
// edges and corners (STL cubes and octahedra, fibre rims) are chamfered by up to a cell,
// first order: 1.25 / (feature size in cells), measured 0.48 at 2.5 cells, 0.06 at 7.4.
constexpr double kMaxVolumeErrorSmooth = 0.10;
double max_volume_error_sharp(double cells) { return std::min(0.5, 1.25 / cells); }
constexpr double kResolvedCells = 2.0;
constexpr double kVolumeCheckFloor = 0.005;  // phases smaller than this fraction of the box: not checked

constexpr int kShards = 8;
constexpr int kScenesPerShard = 28;  // 224 scenes

testing::StlShapes load_shapes() {
  const std::string dir = std::string(CISAMR_SOURCE_DIR) + "/data/shapes/";
  testing::StlShapes s;
  s.cube = io::read_stl(dir + "cube.stl");
  s.octahedron = io::read_stl(dir + "octahedron.stl");
  s.torus = io::read_stl(dir + "torus.stl");
  return s;
}

const testing::StlShapes& shapes() {
  static const testing::StlShapes s = load_shapes();
  return s;
}

struct KindSummary {
  int scenes = 0, resolved = 0;
  std::size_t tets = 0, above_5 = 0;
  double worst = 0;
  std::uint64_t worst_seed = 0;
  double worst_volume_error = 0, worst_centroid_ratio = 0;
  std::int64_t swaps = 0, collapsed = 0, unresolved_leaves = 0;
  double max_collapse_cells = 0;  // largest collapse deviation in cells of the coarse level
  void add(const KindSummary& k) {
    scenes += k.scenes, resolved += k.resolved, tets += k.tets, above_5 += k.above_5;
    if (k.worst > worst) worst = k.worst, worst_seed = k.worst_seed;
    worst_volume_error = std::max(worst_volume_error, k.worst_volume_error);
    worst_centroid_ratio = std::max(worst_centroid_ratio, k.worst_centroid_ratio);
    swaps += k.swaps, collapsed += k.collapsed, unresolved_leaves += k.unresolved_leaves;
    max_collapse_cells = std::max(max_collapse_cells, k.max_collapse_cells);
  }
};

struct Summary {
  std::map<std::string, KindSummary> kinds;
  double min_dihedral = 180, max_dihedral = 0, seconds = 0;
  void print(const char* title) const {
    KindSummary all;
    for (const auto& [name, k] : kinds) all.add(k);
    std::printf("[pipeline3] %s: %d scenes (%d resolved), %zu tets in %.1f s; worst aspect %.3f (seed %llu), %zu above "
                "5; dihedral %.2f..%.2f deg; %lld face swaps; %lld collapsed nodes (max %.3f cells); %lld unresolved "
                "leaves; worst volume error %.2e, centroid ratio %.3f (resolved scenes)\n",
                title, all.scenes, all.resolved, all.tets, seconds, all.worst,
                static_cast<unsigned long long>(all.worst_seed), all.above_5, min_dihedral, max_dihedral,
                static_cast<long long>(all.swaps), static_cast<long long>(all.collapsed), all.max_collapse_cells,
                static_cast<long long>(all.unresolved_leaves), all.worst_volume_error, all.worst_centroid_ratio);
    for (const auto& [name, k] : kinds)
      std::printf("[pipeline3]   %-12s %3d scenes %8zu tets: worst %6.3f (seed %4llu), above 5: %zu; swaps %6lld, "
                  "collapsed %4lld (max %.3f cells); volume error %.2e, centroid ratio %.3f\n",
                  name.c_str(), k.scenes, k.tets, k.worst, static_cast<unsigned long long>(k.worst_seed), k.above_5,
                  static_cast<long long>(k.swaps), static_cast<long long>(k.collapsed), k.max_collapse_cells,
                  k.worst_volume_error, k.worst_centroid_ratio);
  }
  void add(const Summary& o) {
    for (const auto& [name, k] : o.kinds) kinds[name].add(k);
    min_dihedral = std::min(min_dihedral, o.min_dihedral);
    max_dihedral = std::max(max_dihedral, o.max_dihedral);
    seconds += o.seconds;
  }
};

Summary& total() {
  static Summary s;
  return s;
}

class PrintTotal : public ::testing::Environment {
 public:
  void TearDown() override {
    if (!total().kinds.empty()) total().print("all scenes");
  }
};
const auto* const print_total = ::testing::AddGlobalTestEnvironment(new PrintTotal);

std::string describe(const geometry::SceneDesc& s) {
  std::string d;
  char buf[160];
  std::snprintf(buf, sizeof buf, "box [%g,%g]x[%g,%g]x[%g,%g], h %g, levels %d:", s.domain_min[0], s.domain_max[0],
                s.domain_min[1], s.domain_max[1], s.domain_min[2], s.domain_max[2], s.h, s.levels);
  d += buf;
  for (const auto& inc : s.inclusions) {
    if (const auto* p = std::get_if<geometry::Sphere>(&inc.shape))
      std::snprintf(buf, sizeof buf, " sphere (%g,%g,%g) r %g", p->center[0], p->center[1], p->center[2], p->radius);
    else if (const auto* e = std::get_if<geometry::Ellipsoid>(&inc.shape))
      std::snprintf(buf, sizeof buf, " ellipsoid (%g,%g,%g) axes %g %g %g", e->center[0], e->center[1], e->center[2],
                    e->semi_axes[0], e->semi_axes[1], e->semi_axes[2]);
    else if (const auto* c = std::get_if<geometry::Cylinder>(&inc.shape))
      std::snprintf(buf, sizeof buf, " cylinder r %g", c->radius);
    else if (const auto* t = std::get_if<geometry::StlSurface>(&inc.shape))
      std::snprintf(buf, sizeof buf, " %s scale %g at (%g,%g,%g)", t->file.c_str(), t->scale, t->translate[0],
                    t->translate[1], t->translate[2]);
    d += buf;
    d += " phase " + std::to_string(inc.phase) + " L" + std::to_string(inc.levels) + ";";
  }
  return d;
}

double ms(std::chrono::steady_clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

std::string fidelity_text(const quality::FidelityReport& f) {
  std::string text = std::to_string(f.nodes_off_phase) + " nodes off phase, " +
                     std::to_string(f.interface_nodes_off_interface) + " interface nodes off, " +
                     std::to_string(f.boundary_nodes_off_void) + " void-boundary nodes off, " +
                     std::to_string(f.cells_off_phase) + " centroids off (max ratio " +
                     std::to_string(f.max_centroid_ratio) + "), max deviation " + std::to_string(f.max_deviation);
  for (const auto& e : f.examples) text += "\n  " + e;
  return text;
}

// Meshes one scene, checks every property (gtest failures name the seed), adds to `sum`.
void check_scene(std::uint64_t seed, Summary& sum) {
  testing::RandomScene3 gen(seed, shapes());
  const geometry::SceneDesc scene = gen.make();
  const std::string kind = testing::kind_name(gen.kind());
  SCOPED_TRACE("seed " + std::to_string(seed) + " (" + kind + "): " + describe(scene));
  const bool verbose = std::getenv("CISAMR_VERBOSE") != nullptr;
  const bool resolved = gen.min_feature_cells() >= kResolvedCells;

  std::unique_ptr<geometry::Oracle3> oracle;
  try {
    oracle = std::make_unique<geometry::Oracle3>(scene);
  } catch (const std::exception& e) {
    ADD_FAILURE() << "the oracle rejects the scene: " << e.what();
    return;
  }
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const auto r = pipeline::mesh(*oracle);
  const auto t1 = Clock::now();
  const mesh::Mesh3& m = r.mesh;
  ASSERT_GT(m.cell_count(), 0u);
  EXPECT_EQ(r.counters.inverted, 0);

  // Conformity. With voids the expected volume is the box minus the meshed voids' exact
  // volume, up to their discretisation error.
  const std::vector<double> exact = testing::reference_volumes(*oracle);
  const auto t2 = Clock::now();
  const Box3 domain{{scene.domain_min[0], scene.domain_min[1], scene.domain_min[2]},
                    {scene.domain_max[0], scene.domain_max[1], scene.domain_max[2]}};
  const double box_volume =
      (domain.max[0] - domain.min[0]) * (domain.max[1] - domain.min[1]) * (domain.max[2] - domain.min[2]);
  double void_volume = 0;
  bool voids = false;
  for (std::size_t k = 0; k < scene.phases.size(); ++k)
    if (scene.phases[k].is_void) void_volume += exact[k], voids = true;
  const auto conformity = quality::check_conformity(m, domain, box_volume - void_volume, voids, voids ? 0.05 : 1e-9);
  EXPECT_TRUE(conformity.ok) << "not conforming: open inside " << conformity.open_facets_inside << ", hanging "
                             << conformity.hanging_nodes << ", inverted " << conformity.inverted_cells
                             << ", degenerate " << conformity.degenerate_cells << ", non-manifold "
                             << conformity.non_manifold_facets << ", duplicates " << conformity.duplicate_nodes
                             << ", orientation " << conformity.mismatched_orientation_facets << ", measure error "
                             << conformity.measure_error << (conformity.examples.empty() ? "" : "; " + conformity.examples[0]);
  const auto t3 = Clock::now();

  // Aspect ratio: the bound, everywhere.
  const auto aspect = quality::aspect_statistics<3>(m, kMaxAspect3, 3);
  EXPECT_LE(aspect.max, kMaxAspect3) << "worst tet at (" << aspect.worst[0].centroid[0] << ", "
                                     << aspect.worst[0].centroid[1] << ", " << aspect.worst[0].centroid[2]
                                     << "), phase " << aspect.worst[0].phase;
  EXPECT_EQ(aspect.above_bound, 0u);

  // Phase fidelity. Strict (1e-9 of the domain) unless the guard collapsed nodes; then
  // within the reported deviation, for no more nodes than were collapsed. The centroid
  // part of the check is meaningful on smooth, resolved interfaces only.
  const double tol = quality::default_fidelity_tolerance(scene);
  const double coarse_diagonal = scene.h * std::sqrt(3.0);
  EXPECT_LE(r.counters.max_collapse_deviation, coarse_diagonal) << "a collapse moved an interface by more than a cell";
  const double relaxed_tol = std::max(tol, r.counters.max_collapse_deviation * (1 + 1e-9));
  const auto fidelity = quality::check_fidelity(m, *oracle, relaxed_tol, exact, tol);
  EXPECT_LE(fidelity.nodes_beyond_strict, static_cast<std::size_t>(r.counters.collapsed_nodes + r.counters.collapsed_cut_points))
      << "more nodes off their phase than the guard collapsed: " << fidelity_text(fidelity);
  const std::size_t off =
      fidelity.nodes_off_phase + fidelity.interface_nodes_off_interface + fidelity.boundary_nodes_off_void;
  EXPECT_EQ(off, 0u) << "nodes off their phase beyond the collapse deviation: " << fidelity_text(fidelity);
  EXPECT_EQ(fidelity.cells_unknown_phase, 0u);
  // The same mesh split with cohesive cells (issue #13), checked independently.
  EXPECT_TRUE(testing::cohesive_split_is_right(m));
  if (resolved && gen.smooth())
    EXPECT_EQ(fidelity.cells_wrong_phase, 0u) << "tets lying in another phase: " << fidelity_text(fidelity);
  if (resolved && gen.smooth())
    EXPECT_EQ(fidelity.cells_off_phase, 0u) << "tets straddling a smooth interface: " << fidelity_text(fidelity);
  const auto t4 = Clock::now();

  double worst_volume_error = 0;
  for (std::size_t k = 0; k < scene.phases.size(); ++k) {
    if (scene.phases[k].is_void || exact[k] < kVolumeCheckFloor * box_volume) continue;
    worst_volume_error = std::max(worst_volume_error, fidelity.relative_error[k]);
    if (resolved)
      EXPECT_LE(fidelity.relative_error[k],
                gen.smooth() ? kMaxVolumeErrorSmooth : max_volume_error_sharp(gen.min_feature_cells()))
          << "phase " << scene.phases[k].id << ": meshed " << fidelity.phase_measure[k] << ", exact " << exact[k];
  }

  KindSummary& k = sum.kinds[kind];
  ++k.scenes;
  k.resolved += resolved ? 1 : 0;
  k.tets += m.cell_count();
  k.above_5 += aspect.above_bound;
  if (aspect.max > k.worst) k.worst = aspect.max, k.worst_seed = seed;
  if (resolved) {
    k.worst_volume_error = std::max(k.worst_volume_error, worst_volume_error);
    if (gen.smooth()) k.worst_centroid_ratio = std::max(k.worst_centroid_ratio, fidelity.max_centroid_ratio);
  }
  k.swaps += r.counters.face_swaps;
  k.collapsed += r.counters.collapsed_nodes;
  k.unresolved_leaves += r.counters.unresolved;
  k.max_collapse_cells = std::max(k.max_collapse_cells, r.counters.max_collapse_deviation / scene.h);
  sum.min_dihedral = std::min(sum.min_dihedral, aspect.min_angle_deg);
  sum.max_dihedral = std::max(sum.max_dihedral, aspect.max_angle_deg);
  if (verbose)
    std::printf("[pipeline3] seed %4llu %-12s %7zu tets, aspect %.3f, dihedral %.2f..%.2f, swaps %lld, collapsed %lld "
                "(%.3g), features %.1f cells%s, volume error %.2e, centroid ratio %.3f; ms: mesh %.0f volumes %.0f "
                "conformity %.0f fidelity %.0f: %s\n",
                static_cast<unsigned long long>(seed), kind.c_str(), m.cell_count(), aspect.max, aspect.min_angle_deg,
                aspect.max_angle_deg, static_cast<long long>(r.counters.face_swaps),
                static_cast<long long>(r.counters.collapsed_nodes), r.counters.max_collapse_deviation,
                gen.min_feature_cells(), gen.smooth() ? ", smooth" : "", worst_volume_error, fidelity.max_centroid_ratio,
                ms(t1 - t0), ms(t2 - t1), ms(t3 - t2), ms(t4 - t3), describe(scene).c_str());
}

class Properties3 : public ::testing::TestWithParam<int> {};

TEST_P(Properties3, RandomScenes) {
  const int shard = GetParam();
  Summary sum;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < kScenesPerShard; ++i)
    check_scene(static_cast<std::uint64_t>(shard * kScenesPerShard + i + 1), sum);
  sum.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  sum.print(("shard " + std::to_string(shard)).c_str());
  total().add(sum);
}

INSTANTIATE_TEST_SUITE_P(Shards, Properties3, ::testing::Range(0, kShards));

// One scene by seed (CISAMR_SEED), for debugging; skipped otherwise.
TEST(Properties3Seed, FromEnvironment) {
  const char* seed = std::getenv("CISAMR_SEED");
  if (!seed) GTEST_SKIP() << "set CISAMR_SEED to run one scene";
  Summary sum;
  check_scene(std::strtoull(seed, nullptr, 10), sum);
  sum.print("one scene");
}

// The mesher is deterministic: the same scene meshed twice, and again through a second
// oracle built from it, gives bit-equal coordinates, connectivity and phases. The scenes
// (an STL scene, tangent spheres of two phases, a void phase among mixed shapes) exercise
// the guard's refusals and collapses and the face swaps, whose conflicts are resolved by
// rules that must not depend on visiting order.
TEST(Pipeline3, IsDeterministic) {
  std::int64_t swaps = 0, refused = 0, collapsed = 0;
  for (const std::uint64_t seed : {13u, 16u, 14u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    testing::RandomScene3 gen(seed, shapes());
    const geometry::SceneDesc scene = gen.make();
    const geometry::Oracle3 oracle(scene), other(scene);
    const auto a = pipeline::mesh(oracle);
    const auto b = pipeline::mesh(oracle);
    const auto c = pipeline::mesh(other);
    ASSERT_GT(a.mesh.cell_count(), 0u);
    for (const auto* r : {&b, &c}) {
      EXPECT_EQ(a.mesh.coords, r->mesh.coords);
      EXPECT_EQ(a.mesh.cell_nodes, r->mesh.cell_nodes);
      EXPECT_EQ(a.mesh.cell_phase, r->mesh.cell_phase);
    }
    swaps += a.counters.face_swaps;
    refused += a.counters.refused_nodes;
    collapsed += a.counters.collapsed_nodes;
  }
  EXPECT_GT(swaps, 0);
  EXPECT_GT(refused, 0);
  EXPECT_GT(collapsed, 0);
}

// The generator covers every kind and is deterministic (same seed, same scene); at least a
// quarter of the scenes are resolved, so the volume and centroid checks do run.
TEST(Properties3Generator, EveryKindDeterministicAndEnoughResolvedScenes) {
  std::map<std::string, int> kinds;
  int resolved = 0, smooth = 0;
  const int scenes = kShards * kScenesPerShard;
  for (std::uint64_t seed = 1; seed <= std::uint64_t(scenes); ++seed) {
    testing::RandomScene3 gen(seed, shapes());
    const auto s = gen.make();
    ++kinds[testing::kind_name(gen.kind())];
    resolved += gen.min_feature_cells() >= kResolvedCells ? 1 : 0;
    smooth += gen.min_feature_cells() >= kResolvedCells && gen.smooth() ? 1 : 0;
    EXPECT_FALSE(s.inclusions.empty()) << "seed " << seed;
    testing::RandomScene3 again(seed, shapes());
    EXPECT_EQ(describe(again.make()), describe(s));
  }
  EXPECT_EQ(kinds.size(), std::size_t(testing::kSceneKinds));
  for (const auto& [name, count] : kinds) EXPECT_GE(count, 20) << name;
  EXPECT_GE(resolved, scenes / 4);
  EXPECT_GE(smooth, scenes / 10);
  std::printf("[pipeline3] generator: %d scenes, %d resolved, %d resolved and smooth\n", scenes, resolved, smooth);
}

}  // namespace
}  // namespace cisamr
