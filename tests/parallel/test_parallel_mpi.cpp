// lib/parallel under mpiexec (2, 3 or 4 ranks, see CMakeLists.txt): partition invariance
// for (ranks, partitions) in {(2,2), (2,5), (3,8), (4,4)}, error agreement when one rank
// fails, and the .pvtu output. Every test reaches every collective on every rank before it
// checks anything (an early return on one rank would leave the others waiting).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "parallel/collective.hpp"
#include "parallel/exchange.hpp"
#include "parallel/output.hpp"
#include "parallel/session.hpp"
#include "quality/quality.hpp"
#include "scenes.hpp"
#include "support/cohesive_compare.hpp"

namespace cisamr::parallel {
namespace {

namespace fs = std::filesystem;

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

// Rank 0's value on every rank (the sequential references are meshed on rank 0 only: the
// other ranks would repeat the same work on the same cores).
std::uint64_t from_root(std::uint64_t v) { return allreduce_sum_u64(comm(), root() ? v : 0); }

void expect_invariant(const geometry::SceneDesc& scene, int partitions, bool strict) {
  SCOPED_TRACE(std::to_string(comm().size()) + " ranks, " + std::to_string(partitions) + " partitions");
  const testing::RunOutcome seq = root() ? testing::run_sequential(scene) : testing::RunOutcome{};
  const bool seq_failed = from_root(seq.failed ? 1 : 0) != 0;
  const testing::RunOutcome par = testing::run_parallel(comm(), scene, partitions);
  EXPECT_EQ(seq_failed, par.failed) << seq.error << " | " << par.error;
  if (seq_failed || par.failed) return;  // both agreed collectively: safe on every rank
  EXPECT_EQ(par.checksum, from_root(seq.checksum));  // every rank holds the global checksum
  // Each rank meshed a block of consecutive partitions.
  for (int p : std::vector<int>(par.distributed.piece.mesh.cell_partition.begin(),
                                par.distributed.piece.mesh.cell_partition.end()))
    EXPECT_EQ(rank_of_partition(p, partitions, comm().size()), comm().rank());
  if (!root()) return;
  EXPECT_TRUE(canonical_triangles(par.mesh) == canonical_triangles(seq.mesh));
  EXPECT_EQ(mesh_checksum2(par.mesh), seq.checksum);
  const Box2 domain{{scene.domain_min[0], scene.domain_min[1]}, {scene.domain_max[0], scene.domain_max[1]}};
  bool voids = false;
  for (const auto& p : scene.phases) voids = voids || p.is_void;
  const double area = (domain.max[0] - domain.min[0]) * (domain.max[1] - domain.min[1]);
  const auto conf = quality::check_conformity(par.mesh, domain, voids ? -1.0 : area, voids);
  EXPECT_TRUE(conf.ok) << (conf.examples.empty() ? "" : conf.examples.front());
  EXPECT_EQ(conf.duplicate_nodes, 0u);
  EXPECT_EQ(conf.hanging_nodes, 0u);
  if (strict) {
    EXPECT_LE(quality::aspect_statistics(par.mesh, 3.0).max, 3.0);
    const geometry::Oracle2 oracle(scene);
    EXPECT_TRUE(quality::check_fidelity(par.mesh, oracle, quality::default_fidelity_tolerance(scene)).ok);
  }
}

TEST(MpiInvariance, CornerScene) {
  for (int n : partition_counts()) expect_invariant(testing::corner_scene(), n, true);
}

TEST(MpiInvariance, RandomScenes) {
  for (int n : partition_counts())
    for (unsigned seed = 1; seed <= 8; ++seed) {
      SCOPED_TRACE("seed " + std::to_string(seed));
      expect_invariant(testing::random_scene(seed), n, false);
    }
}

TEST(MpiInvariance, PeriodicRandomScenes) {
  for (int n : partition_counts())
    for (unsigned seed = 1; seed <= 2; ++seed) {
      SCOPED_TRACE("seed " + std::to_string(seed));
      expect_invariant(cisamr::testing::periodic_scene(seed), n, false);
    }
}

// Cohesive cells (issue 13) under MPI: the sequential mesh's cells and copies, every
// interface facet covered once in the gathered mesh (partition faces, periodic planes),
// the copies' global ids those of one rank with the same partitions.
TEST(MpiInvariance, CohesiveScenes) {
  pipeline::Options options;
  options.cohesive = true;
  // (The corner scene's partition corners are covered on one rank: test_parallel.cpp.)
  std::vector<geometry::SceneDesc> scenes = {testing::periodic_plane_scene(), testing::random_scene(1)};
  scenes.push_back(cisamr::testing::periodic_scene(1));
  for (const geometry::SceneDesc& scene : scenes)
    for (int n : partition_counts()) {
      SCOPED_TRACE(scene.source + ", " + std::to_string(comm().size()) + " ranks, " + std::to_string(n) + " partitions");
      const testing::RunOutcome seq = root() ? testing::run_sequential(scene, options) : testing::RunOutcome{};
      const bool seq_failed = from_root(seq.failed ? 1 : 0) != 0;
      const testing::RunOutcome par = testing::run_parallel(comm(), scene, n, GhostRule{}, options);
      EXPECT_EQ(seq_failed, par.failed) << seq.error << " | " << par.error;
      if (seq_failed || par.failed) continue;
      EXPECT_EQ(par.checksum, from_root(seq.checksum));
      if (!root()) continue;
      EXPECT_EQ(par.mesh.node_count(), seq.mesh.node_count());
      EXPECT_EQ(par.mesh.cohesive.count(), seq.mesh.cohesive.count());
      const auto frame = cisamr::testing::cohesive_frame<2>(scene, pipeline::make_lattice<2>(scene, options));
      const bool voids = std::ranges::any_of(scene.phases, [](const geometry::Phase& p) { return p.is_void; });
      EXPECT_TRUE(cisamr::testing::cohesive_mesh_is_right(par.mesh, frame, voids));
      const testing::RunOutcome one = testing::run_parallel(SerialComm{}, scene, n, GhostRule{}, options);
      EXPECT_TRUE(par.mesh.coords == one.mesh.coords);
      EXPECT_TRUE(par.mesh.node_phase == one.mesh.node_phase);
      EXPECT_TRUE(par.mesh.cohesive.nodes == one.mesh.cohesive.nodes);
    }
}

TEST(MpiInvariance, OwnedNodesFirstAndGlobalIdsContiguous) {
  const int n = partition_counts().back();
  const testing::RunOutcome par = testing::run_parallel(comm(), testing::corner_scene(), n);
  ASSERT_FALSE(par.failed);  // collective outcome: the same on every rank
  const NumberedPiece2& piece = par.distributed.piece;
  const std::int64_t offset = comm().exclusive_scan_sum(piece.owned_nodes);
  for (std::int64_t i = 0; i < piece.owned_nodes; ++i)
    EXPECT_EQ(piece.mesh.node_global_id[static_cast<std::size_t>(i)], offset + i);
  for (std::size_t i = static_cast<std::size_t>(piece.owned_nodes); i < piece.mesh.node_count(); ++i) {
    const GlobalId g = piece.mesh.node_global_id[i];
    EXPECT_TRUE(g < offset || g >= offset + piece.owned_nodes);  // copies of others' nodes
  }
  // The same ids as one rank with the same partitions: they depend on N, not on P.
  const testing::RunOutcome one = testing::run_parallel(SerialComm(), testing::corner_scene(), n);
  ASSERT_FALSE(one.failed);
  for (std::size_t i = 0; i < piece.mesh.node_count(); ++i) {
    const auto g = static_cast<std::size_t>(piece.mesh.node_global_id[i]);
    EXPECT_EQ(piece.mesh.coords[2 * i], one.distributed.piece.mesh.coords[2 * g]);
    EXPECT_EQ(piece.mesh.coords[2 * i + 1], one.distributed.piece.mesh.coords[2 * g + 1]);
  }
}

TEST(MpiFailure, OneRankFailsEveryRankThrowsItsError) {
  const int failing = comm().size() - 1;
  std::string text;
  int failed_rank = -1;
  try {
    run_collectively(comm(), [&] {
      if (comm().rank() == failing) throw InputError("s.json", "mesh.h", "rank-specific failure");
    });
  } catch (const CollectiveInputError& e) {
    text = e.what();
    failed_rank = e.failed_rank;
  }
  EXPECT_EQ(text, "s.json: mesh.h: rank-specific failure");
  EXPECT_EQ(failed_rank, failing);
  // Two ranks fail differently: the lowest one's error wins, everywhere.
  try {
    run_collectively(comm(), [&] {
      if (comm().rank() >= 1) throw MeshingError("from rank " + std::to_string(comm().rank()));
    });
    ADD_FAILURE();
  } catch (const CollectiveMeshingError& e) {
    EXPECT_STREQ(e.what(), "from rank 1");
  }
  // After a failure the ranks still agree: the next collective works.
  EXPECT_EQ(comm().allreduce_sum(std::int64_t{1}), comm().size());
}

TEST(MpiFailure, UnwritablePieceOnOneRankLeavesNoFiles) {
  const fs::path dir = fs::temp_directory_path() / ("cisamr_mpi_test_" + std::to_string(comm().size()));
  if (root()) {
    fs::remove_all(dir);
    fs::create_directories(dir / "out_1.vtu" / "inside");  // rank 1's piece name is a directory
  }
  comm().barrier();
  const testing::RunOutcome par = testing::run_parallel(comm(), testing::corner_scene(), comm().size());
  std::string text;
  try {
    write_pvtu2(comm(), (dir / "out.pvtu").string(), par.distributed.piece.mesh);
  } catch (const CollectiveInputError& e) {
    text = e.what();
  }
  comm().barrier();
  EXPECT_NE(text.find("out_1.vtu: cannot write"), std::string::npos) << text;
  if (root()) {
    std::size_t entries = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
    EXPECT_EQ(entries, 1u);  // the directory we made, nothing else
    fs::remove_all(dir / "out_1.vtu");
  }
  comm().barrier();
  // And with nothing in the way every piece and the .pvtu appear.
  text.clear();
  try {
    write_pvtu2(comm(), (dir / "out.pvtu").string(), par.distributed.piece.mesh);
  } catch (const std::exception& e) {
    text = e.what();
  }
  comm().barrier();
  EXPECT_EQ(text, "");
  EXPECT_TRUE(fs::exists(piece_path((dir / "out.pvtu").string(), comm().rank())));
  comm().barrier();
  if (root()) {
    EXPECT_TRUE(fs::exists(dir / "out.pvtu"));
    fs::remove_all(dir);
  }
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
  // Every rank's verdict counts: a failure on any rank fails the run.
  return session.comm().allreduce_max(std::int64_t{failed}) != 0 ? 1 : 0;
}
