// The periodic-master exchange under mpiexec (2, 3 or 4 ranks): each rank's piece of a
// real parallel run of a periodic scene gets, for every node on a periodic max face, the
// global id of its full master, the one mesh::periodic_links gives on the gathered mesh
// (masters often live on another rank); the .pvtu pieces carry it and read back merged;
// a slave moved off its translate by one ulp on some rank fails on every rank alike.
// Every test reaches every collective on every rank before it checks anything.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>

#include "io/mesh_io.hpp"
#include "mesh/periodic_links.hpp"
#include "parallel/collective.hpp"
#include "parallel/exchange.hpp"
#include "parallel/output.hpp"
#include "parallel/periodic_masters.hpp"
#include "parallel/session.hpp"
#include "scenes.hpp"
#include "support/random_scenes.hpp"

namespace cisamr::parallel {
namespace {

namespace fs = std::filesystem;

const Comm& comm() { return world(); }
bool root() { return comm().rank() == 0; }

Box2 face_box(const geometry::SceneDesc& s) {
  const grid::Lattice2 l = pipeline::make_lattice<2>(s, {});
  return Box2{{l.coordinate(0, 0), l.coordinate(1, 0)}, {l.coordinate(0, l.fine_period(0)), l.coordinate(1, l.fine_period(1))}};
}

TEST(PeriodicMpi, PiecesGetTheGatheredMasters) {
  const fs::path dir = fs::temp_directory_path() / ("cisamr_periodic_mpi_" + std::to_string(comm().size()));
  if (root()) fs::create_directories(dir);
  comm().barrier();
  std::int64_t remote = 0, checked = 0;
  for (unsigned seed : {1u, 3u, 4u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const geometry::SceneDesc scene = cisamr::testing::periodic_scene(seed);
    const testing::RunOutcome par = testing::run_parallel(comm(), scene, 2 * comm().size());
    ASSERT_FALSE(par.failed) << par.error;  // agreed collectively: every rank leaves alike
    const Box2 faces = face_box(scene);
    const std::array<bool, 2> axes{scene.periodic[0], scene.periodic[1]};
    const mesh::Mesh2& piece = par.distributed.piece.mesh;
    const std::vector<GlobalId> masters = periodic_masters<2>(comm(), piece, faces, axes);
    // Every rank's (global id, master) pairs, checked on rank 0 against the gathered mesh.
    std::vector<std::int64_t> mine;
    for (std::size_t n = 0; n < piece.node_count(); ++n) mine.push_back(piece.node_global_id[n]), mine.push_back(masters[n]);
    const std::vector<std::int64_t> all = allgather_vector(comm(), mine);
    // Masters this rank does not hold.
    std::map<GlobalId, bool> held;
    for (GlobalId g : piece.node_global_id) held[g] = true;
    for (GlobalId g : masters) remote += g >= 0 && !held.count(g);

    io::MeshWriteOptions options;
    options.face_box = Box3{{faces.min[0], faces.min[1], 0}, {faces.max[0], faces.max[1], 0}};
    options.periodic = {axes[0], axes[1], false};
    write_pvtu<2>(comm(), (dir / "p.pvtu").string(), piece, scene.phases, options);
    if (root()) {
      const auto links = mesh::periodic_links<2>(par.mesh, faces, axes);  // gathered: node = global id
      std::vector<GlobalId> expected(par.mesh.node_count(), -1);
      for (const auto& s : links.slaves) expected[static_cast<std::size_t>(s.node)] = s.master;
      int bad = 0;
      for (std::size_t k = 0; k < all.size(); k += 2, ++checked) bad += expected[static_cast<std::size_t>(all[k])] != all[k + 1];
      EXPECT_EQ(bad, 0);
      const io::LoadedMesh back = io::read_mesh((dir / "p.pvtu").string());
      ASSERT_EQ(back.periodic_master.size(), back.mesh2.node_count());
      bad = 0;
      for (std::size_t n = 0; n < back.mesh2.node_count(); ++n)
        bad += back.periodic_master[n] != expected[static_cast<std::size_t>(back.mesh2.node_global_id[n])];
      EXPECT_EQ(bad, 0);
      EXPECT_GT(links.slaves.size(), 0u);
    }
    comm().barrier();
  }
  remote = comm().allreduce_sum(remote);
  if (root()) {
    EXPECT_GT(checked, 0);
    EXPECT_GT(remote, 0) << "no master was on another rank: the exchange was not exercised";
    fs::remove_all(dir);
  }
}

TEST(PeriodicMpi, ASlaveOffItsTranslateFailsOnEveryRank) {
  const geometry::SceneDesc scene = cisamr::testing::periodic_scene(1);
  const testing::RunOutcome par = testing::run_parallel(comm(), scene, comm().size());
  ASSERT_FALSE(par.failed) << par.error;
  const Box2 faces = face_box(scene);
  const std::array<bool, 2> axes{scene.periodic[0], scene.periodic[1]};
  mesh::Mesh2 piece = par.distributed.piece.mesh;
  // The last rank moves one of its x-max face nodes (not a corner) by one ulp along y.
  if (comm().rank() == comm().size() - 1)
    for (std::size_t n = 0; n < piece.node_count(); ++n)
      if (piece.coords[2 * n] == faces.max[0] && piece.coords[2 * n + 1] > faces.min[1] && piece.coords[2 * n + 1] < faces.max[1]) {
        piece.coords[2 * n + 1] = std::nextafter(piece.coords[2 * n + 1], 1e300);
        break;
      }
  std::string text;
  try {
    periodic_masters<2>(comm(), piece, faces, axes);
  } catch (const CollectiveMeshingError& e) {
    text = e.what();
  }
  EXPECT_NE(text.find("not periodic"), std::string::npos) << text;
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
