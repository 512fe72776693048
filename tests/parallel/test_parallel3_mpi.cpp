// lib/parallel in 3D under mpiexec (2, 3 or 4 ranks): partition invariance against the
// sequential mesher for (ranks, partitions) in {(2,2), (2,5), (3,8), (4,4)} on the dense
// scenes of scenes3.hpp and a scene of NURBS surfaces, the gathered mesh equal to the
// one-rank one (global ids included), the STL files read in shares, and failures on one rank (its kernel, an STL
// file it reads) reaching every rank. Every test reaches every collective on every rank
// before it checks anything; the sequential and one-rank reference runs are rank 0's only.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "parallel/collective.hpp"
#include "parallel/exchange.hpp"
#include "parallel/session.hpp"
#include "scenes3.hpp"
#include "support/cohesive_compare.hpp"
#include "support/random_nurbs3.hpp"

namespace cisamr::parallel {
namespace {

namespace fs = std::filesystem;
namespace nurbs3 = cisamr::testing::nurbs3;

const Comm& comm() { return world(); }
bool root() { return comm().rank() == 0; }

std::vector<int> partition_counts() {
  switch (comm().size()) {
    case 2: return {2, 5};
    case 3: return {8};
    case 4: return {4};
    default: return {comm().size()};
  }
}

// Rank 0's value on every rank.
std::uint64_t from_root(std::uint64_t v) { return allreduce_sum_u64(comm(), root() ? v : 0); }

// The scene meshed on every rank with each partition count of this rank count: the
// sequential mesh's checksum, each cell on the rank of its partition, owned nodes first and
// numbered contiguously; on rank 0, the gathered mesh with the sequential mesh's tets and
// node count, conforming, and the one-rank mesh with the same partitions node for node,
// cell for cell and counter for counter.
void expect_invariant(const testing::Case3& c) {
  const testing::RunOutcome3 seq = root() ? testing::run_sequential3(c.scene, c.options) : testing::RunOutcome3{};
  if (root()) {
    EXPECT_FALSE(seq.failed) << c.name << ": " << seq.error;  // no ASSERT: every rank goes on
  }
  const std::uint64_t expected = from_root(seq.checksum);
  for (int n : partition_counts()) {
    SCOPED_TRACE(c.name + ", " + std::to_string(comm().size()) + " ranks, " + std::to_string(n) + " partitions");
    const testing::RunOutcome3 par = testing::run_parallel3(comm(), c.scene, n, {}, c.options);
    EXPECT_FALSE(par.failed) << par.error;
    if (par.failed) continue;  // agreed collectively: safe on every rank
    EXPECT_EQ(par.checksum, expected);
    for (std::int32_t p : par.distributed.piece.mesh.cell_partition)
      EXPECT_EQ(rank_of_partition(p, n, comm().size()), comm().rank());
    // Owned nodes first, numbered contiguously.
    const auto& piece = par.distributed.piece;
    for (std::int64_t i = 1; i < piece.owned_nodes; ++i)
      EXPECT_EQ(piece.mesh.node_global_id[static_cast<std::size_t>(i)],
                piece.mesh.node_global_id[static_cast<std::size_t>(i - 1)] + 1);
    if (!root()) continue;
    EXPECT_TRUE(canonical_tets(par.mesh) == canonical_tets(seq.mesh));
    EXPECT_EQ(par.mesh.node_count(), seq.mesh.node_count());
    testing::expect_conforming3(par.mesh, c.scene);
    // Global ids depend on the partitions only: the gathered mesh is the one-rank mesh,
    // node for node and cell for cell.
    const testing::RunOutcome3 one = testing::run_parallel3(SerialComm{}, c.scene, n, {}, c.options);
    EXPECT_TRUE(par.mesh.coords == one.mesh.coords);
    EXPECT_TRUE(par.mesh.cell_nodes == one.mesh.cell_nodes);
    EXPECT_TRUE(par.mesh.cell_phase == one.mesh.cell_phase);
    // The counters reduced across ranks are the one-rank run's, counter by counter.
    pipeline::Counters<3>::for_each([&](const char* name, auto member, pipeline::Reduction) {
      EXPECT_EQ(par.distributed.counters.*member, one.distributed.counters.*member) << name;
    });
  }
}

TEST(MpiInvariance3, DenseScenes) {
  for (const auto& c : testing::invariance_cases3()) expect_invariant(c);
}

// NURBS surface inclusions (issue #14) on 16 × 16 × 16 cubes of h = 1/16 (the unit cube):
// exact rational spheres (one clipped by the face x = 1), an exact torus, a rotated six-patch
// cube-sphere and a seeded perturbed sphere (tests/support/random_nurbs3.hpp), all of phase
// 2, and an analytic sphere of phase 3 in the middle, about two cells from the nearest three.
// Requested at levels 0 and 1 and meshed with extra_levels = 0 (Lmax = 1): the contact rule,
// which compares NURBS surfaces by their boxes, and the spread raise every inclusion to
// level 1 (effective_levels3; 69k tets, about 0.3 s sequentially). The partition boxes of
// every partition count cut some particles, meshed in pieces on different ranks, each from
// its own copy of the patches: the checksum must still be the sequential mesh's.
geometry::SceneDesc nurbs_scene3() {
  using namespace geometry;
  SceneDesc s;
  s.source = "nurbs-scene-3d";
  s.dimension = 3;
  s.h = 0.0625;
  s.levels = 0;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1, 1, 1};
  s.phases = {{1, "matrix", false}, {2, "particle", false}, {3, "fibre", false}};
  const auto add = [&](Shape shape, int phase, int levels) {
    s.inclusions.push_back({std::move(shape), phase, levels});
  };
  add(nurbs3::exact_sphere({0.27, 0.28, 0.3}, 0.17), 2, 1);
  add(nurbs3::exact_sphere({0.97, 0.55, 0.45}, 0.15), 2, 0);  // clipped by x = 1
  add(nurbs3::exact_torus({0.28, 0.74, 0.72}, 0.17, 0.07), 2, 1);
  NurbsSurface blob = nurbs3::cube_sphere({0.72, 0.3, 0.74}, 0.15);
  blob.rotation = {{{0.8, -0.6, 0}, {0.6, 0.8, 0}, {0, 0, 1}}};
  add(blob, 2, 0);
  std::mt19937_64 rng(14);
  add(nurbs3::random_particle(rng, nurbs3::Kind::perturbed_sphere, {0.7, 0.76, 0.22}, 0.13), 2, 0);
  add(Sphere{{0.52, 0.5, 0.5}, 0.09}, 3, 0);
  return s;
}

TEST(MpiInvariance3, NurbsScene) {
  // Default levels: the NURBS bodies near the analytic sphere are judged on their pieces
  // (shapes_overlap), not by their boxes, so the level rules refine only where they meet.
  expect_invariant({"nurbs", nurbs_scene3(), pipeline::Options{}});
}

// Cohesive cells (issue 13) under MPI: the sequential mesh's cells and copies (checksum),
// every interface facet covered once in the gathered mesh, and the copies' global ids those
// of one rank with the same partitions.
TEST(MpiInvariance3, CohesiveScenes) {
  for (const auto& c : testing::invariance_cases3()) {
    if (c.name != "periodic-level0" && c.name != "contact") continue;
    pipeline::Options options = c.options;
    options.cohesive = true;
    const testing::RunOutcome3 seq = root() ? testing::run_sequential3(c.scene, options) : testing::RunOutcome3{};
    const std::uint64_t expected = from_root(seq.checksum);
    for (int n : partition_counts()) {
      SCOPED_TRACE(c.name + ", " + std::to_string(comm().size()) + " ranks, " + std::to_string(n) + " partitions");
      const testing::RunOutcome3 par = testing::run_parallel3(comm(), c.scene, n, {}, options);
      EXPECT_FALSE(par.failed) << par.error;
      if (par.failed) continue;
      EXPECT_EQ(par.checksum, expected);
      if (!root()) continue;
      EXPECT_EQ(par.mesh.node_count(), seq.mesh.node_count());
      EXPECT_EQ(par.mesh.cohesive.count(), seq.mesh.cohesive.count());
      const auto frame = cisamr::testing::cohesive_frame<3>(c.scene, pipeline::make_lattice<3>(c.scene, options));
      EXPECT_TRUE(cisamr::testing::cohesive_mesh_is_right(par.mesh, frame));
      const testing::RunOutcome3 one = testing::run_parallel3(SerialComm{}, c.scene, n, {}, options);
      EXPECT_TRUE(par.mesh.coords == one.mesh.coords);
      EXPECT_TRUE(par.mesh.node_phase == one.mesh.node_phase);
      EXPECT_TRUE(par.mesh.cohesive.nodes == one.mesh.cohesive.nodes);
      EXPECT_TRUE(par.mesh.cohesive.phase == one.mesh.cohesive.phase);
    }
  }
}

// Each STL file is read by one rank for the boxes, loads and unions; the result is the
// whole scene's.
TEST(MpiStl3, EachFileReadOnceForTheShares) {
  geometry::SceneDesc scene = testing::contact_scene3();
  const StlShares shares = share_stl_surfaces(comm(), scene, {}, true);
  EXPECT_EQ(comm().allreduce_sum(shares.files_read), 3);  // octahedron, cube, torus
  EXPECT_LE(shares.files_read, 2);
  if (root()) {
    const geometry::SceneDesc full = testing::with_triangles(testing::contact_scene3());
    EXPECT_EQ(shares.unions, pipeline::surface_unions(full));
    const std::vector<Box3> boxes = pipeline::holding_boxes(full);
    const std::vector<Box3> known = pipeline::holding_boxes(scene, shares.known);
    for (std::size_t k = 0; k < boxes.size(); ++k) EXPECT_EQ(std::memcmp(&known[k], &boxes[k], sizeof(Box3)), 0) << k;
  } else {
    EXPECT_EQ(shares.unions.size(), 1u);
  }
}

// A failure in one rank's 3D kernel (an inclusion of another phase overlapping a sphere,
// seen only by the partitions near it) ends every rank with the same message.
TEST(MpiFailure3, OneRanksKernelFailsEveryRankThrowsIt) {
  geometry::SceneDesc scene = testing::corner_scene3();
  scene.inclusions.push_back({geometry::Sphere{{1.3, 1.3, 0.8}, 0.1}, 3, 0});  // overlaps inclusions[17]
  const testing::RunOutcome3 par = testing::run_parallel3(comm(), scene, comm().size());
  EXPECT_TRUE(par.failed);
  EXPECT_NE(par.error.find("inclusions[17]"), std::string::npos) << par.error;
  EXPECT_NE(par.error.find("inclusions[22]"), std::string::npos) << par.error;
  EXPECT_EQ(comm().allreduce_sum(std::int64_t{1}), comm().size());  // still in step
}

// A malformed STL file, read by one rank only (its share): every rank throws the reader's
// message naming the file.
TEST(MpiFailure3, OneRankReadsABadStlEveryRankThrowsIt) {
  const fs::path dir = fs::temp_directory_path() / ("cisamr_mpi3_badstl_" + std::to_string(comm().rank()));
  fs::create_directories(dir);
  {
    std::ofstream bad(dir / "bad.stl");
    bad << "solid broken\n  facet normal 0 0 1\n    outer loop\n      vertex 0 0\n";
  }
  geometry::SceneDesc scene = testing::contact_scene3();
  // The third file (the torus, read by rank 2 % P) is replaced by the bad one.
  std::get<geometry::StlSurface>(scene.inclusions[8].shape).file = (dir / "bad.stl").string();
  const testing::RunOutcome3 par = testing::run_parallel3(comm(), scene, comm().size(), {}, testing::contact_options3());
  EXPECT_TRUE(par.failed);
  EXPECT_NE(par.error.find("bad.stl"), std::string::npos) << par.error;
  // The same text on every rank.
  const std::uint64_t mine = std::hash<std::string>{}(par.error);
  EXPECT_EQ(comm().allreduce_max(static_cast<std::int64_t>(mine >> 1)), static_cast<std::int64_t>(mine >> 1));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace cisamr::parallel

int main(int argc, char** argv) {
  cisamr::parallel::MpiSession session(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  if (session.comm().rank() != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  const int failed = RUN_ALL_TESTS();
  return session.comm().allreduce_max(std::int64_t{failed}) != 0 ? 1 : 0;
}
