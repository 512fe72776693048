// lib/parallel in 3D through the serial Comm: effective_levels3, partition invariance for
// (1 rank, 1 and 7 partitions) against the sequential kernel, the merge of cut nodes, lazy
// STL reading, a ghost too small to be exact. test_parallel3_mpi.cpp runs the invariance
// on 2-4 ranks.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "io/scene_io.hpp"
#include "parallel/collective.hpp"
#include "parallel/output.hpp"
#include "scenes3.hpp"

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

TEST(CornerScene3, IsValid) { EXPECT_NO_THROW(geometry::Oracle3{testing::corner_scene3()}); }

void expect_invariant3(const geometry::SceneDesc& scene, int partitions) {
  SCOPED_TRACE(scene.source + ", " + std::to_string(partitions) + " partitions");
  const testing::RunOutcome3 seq = testing::run_sequential3(scene);
  const testing::RunOutcome3 par = testing::run_parallel3(kSerial, scene, partitions);
  ASSERT_FALSE(seq.failed) << seq.error;
  ASSERT_FALSE(par.failed) << par.error;
  EXPECT_EQ(par.checksum, seq.checksum);
  EXPECT_EQ(mesh_checksum3(par.mesh), seq.checksum);
  EXPECT_TRUE(canonical_tets(par.mesh) == canonical_tets(seq.mesh));
  EXPECT_EQ(par.mesh.cell_count(), seq.mesh.cell_count());
  EXPECT_EQ(par.mesh.node_count(), seq.mesh.node_count());  // no duplicate, no missing node
  testing::expect_conforming3(par.mesh, scene);
  std::vector<char> seen(static_cast<std::size_t>(par.distributed.piece.global_nodes), 0);
  for (GlobalId g : par.distributed.piece.mesh.node_global_id) seen[static_cast<std::size_t>(g)]++;
  for (char s : seen) EXPECT_EQ(s, 1);
}

class Invariance3 : public ::testing::TestWithParam<int> {};

TEST_P(Invariance3, CornerScene) { expect_invariant3(testing::corner_scene3(), GetParam()); }

TEST_P(Invariance3, DataExampleAtCoarserH) {
  geometry::SceneDesc scene = io::read_scene(CISAMR_SOURCE_DIR "/data/examples/spheres3d.json");
  scene.h = 0.1;
  expect_invariant3(scene, GetParam());
}

INSTANTIATE_TEST_SUITE_P(OneRank, Invariance3, ::testing::Values(1, 7));

TEST(Invariance3, PartitionCornersAreStraddled) {
  const geometry::SceneDesc scene = testing::corner_scene3();
  for (int n : {7, 8}) {  // the (1 rank, 7) and (3 ranks, 8) cases
    const testing::RunOutcome3 par = testing::run_parallel3(kSerial, scene, n);
    ASSERT_FALSE(par.failed) << par.error;
    EXPECT_GE(testing::straddled_corners3(par.distributed, scene), 1) << n << " partitions";
  }
}

// The tests can fail: with no ghost at all (no box margin, inclusion boxes not inflated)
// the merged mesh is not the sequential one.
TEST(Invariance3, NoGhostBreaksIt) {
  GhostRule none;
  none.level_aware = false;
  none.fixed_cells = 0;
  none.box_margin_cells = 0;
  const geometry::SceneDesc scene = testing::corner_scene3();
  const testing::RunOutcome3 seq = testing::run_sequential3(scene);
  const testing::RunOutcome3 par = testing::run_parallel3(kSerial, scene, 7, none);
  EXPECT_TRUE(par.failed || par.checksum != seq.checksum);
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

// Lazy STL: read from a scene file, the parallel mesher reads the STL surfaces itself and
// meshes them like the sequential mesher given every triangle.
TEST(LazyStl, SceneFileWithStlSurfacesMeshesAsSequential) {
  const fs::path dir = fs::temp_directory_path() / "cisamr_parallel3_stl";
  fs::create_directories(dir);
  const std::string path = (dir / "stl.json").string();
  {
    std::ofstream f(path);
    f << R"({"format": "cisamr-scene/1", "dimension": 3, "domain": {"min": [0, 0, 0], "max": [3, 1, 1]},
      "mesh": {"h": 0.125, "levels": 0}, "phases": [{"id": 1, "name": "m"}, {"id": 2, "name": "g"}],
      "inclusions": [
        {"shape": "stl", "file": ")" CISAMR_SOURCE_DIR R"(/data/shapes/cube.stl", "scale": 0.3,
         "translate": [0.2, 0.3, 0.3], "phase": 2},
        {"shape": "stl", "file": ")" CISAMR_SOURCE_DIR R"(/data/shapes/octahedron.stl", "scale": 0.2,
         "translate": [2.6, 0.6, 0.6], "phase": 2, "levels": 1}]})";
  }
  const geometry::SceneDesc lazy = io::read_scene(path, io::ReadSceneOptions{.load_stl = false});
  for (const auto& inc : lazy.inclusions) EXPECT_TRUE(std::get<geometry::StlSurface>(inc.shape).triangles.empty());
  const geometry::SceneDesc full = io::read_scene(path);
  const testing::RunOutcome3 seq = testing::run_sequential3(full);
  ASSERT_FALSE(seq.failed) << seq.error;
  MeshOptions options;
  options.partitions = 16;
  const DistributedMesh3 dm = mesh3_distributed(kSerial, path, options);
  EXPECT_EQ(mesh_checksum3(dm.piece.mesh), seq.checksum);
  EXPECT_EQ(dm.stl_files_read, 2);  // rank 0 reads each file once (for the partition loads)
  // The two surfaces are 2 apart: some partition does not load both.
  bool partial = false;
  for (const auto& p : dm.partitions) partial = partial || p.inclusions < 2;
  EXPECT_TRUE(partial);
  fs::remove_all(dir);
}

TEST(Output3, PvtuPiecesOfTetrahedra) {
  const fs::path dir = fs::temp_directory_path() / "cisamr_parallel3_pvtu";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const testing::RunOutcome3 par = testing::run_parallel3(kSerial, testing::corner_scene3(), 3);
  ASSERT_FALSE(par.failed) << par.error;
  write_pvtu<3>(kSerial, (dir / "m.pvtu").string(), par.distributed.piece.mesh);
  EXPECT_TRUE(fs::exists(dir / "m.pvtu"));
  EXPECT_GT(fs::file_size(dir / "m_0.vtu"), 1000u);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace cisamr::parallel
