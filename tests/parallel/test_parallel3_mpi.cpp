// lib/parallel in 3D under mpiexec (2, 3 or 4 ranks): partition invariance against the
// sequential kernel for (ranks, partitions) in {(2,2), (2,5), (3,8), (4,4)}, owned-first
// global ids equal to the one-rank ones, lazy STL reading per rank, and a failure inside
// one rank's 3D kernel reaching every rank. Every test reaches every collective on every
// rank before it checks anything.
#include <gtest/gtest.h>

#include "parallel/collective.hpp"
#include "parallel/session.hpp"
#include "scenes3.hpp"

namespace cisamr::parallel {
namespace {

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

TEST(MpiInvariance3, CornerScene) {
  const geometry::SceneDesc scene = testing::corner_scene3();
  const testing::RunOutcome3 seq = testing::run_sequential3(scene);
  ASSERT_FALSE(seq.failed) << seq.error;  // the same on every rank: no collective skipped
  for (int n : partition_counts()) {
    SCOPED_TRACE(std::to_string(comm().size()) + " ranks, " + std::to_string(n) + " partitions");
    const testing::RunOutcome3 par = testing::run_parallel3(comm(), scene, n);
    const testing::RunOutcome3 one = testing::run_parallel3(SerialComm{}, scene, n);
    EXPECT_FALSE(par.failed) << par.error;
    if (par.failed) continue;  // agreed collectively: safe on every rank
    EXPECT_EQ(par.checksum, seq.checksum);
    for (std::int32_t p : par.distributed.piece.mesh.cell_partition)
      EXPECT_EQ(rank_of_partition(p, n, comm().size()), comm().rank());
    // Global ids depend on the partitions only: the same node has the same id on 1 rank.
    const auto& piece = par.distributed.piece;
    EXPECT_EQ(piece.global_nodes, one.distributed.piece.global_nodes);
    for (std::size_t i = 0; i < piece.mesh.node_count(); ++i) {
      const auto g = static_cast<std::size_t>(piece.mesh.node_global_id[i]);
      if (i < static_cast<std::size_t>(piece.owned_nodes) && i > 0) {
        EXPECT_EQ(piece.mesh.node_global_id[i], piece.mesh.node_global_id[i - 1] + 1);
      }
      for (int d = 0; d < 3; ++d) EXPECT_EQ(piece.mesh.coords[3 * i + d], one.distributed.piece.mesh.coords[3 * g + d]);
    }
    if (!root()) continue;
    EXPECT_TRUE(canonical_tets(par.mesh) == canonical_tets(seq.mesh));
    EXPECT_EQ(par.mesh.node_count(), seq.mesh.node_count());
    testing::expect_conforming3(par.mesh, scene);
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
