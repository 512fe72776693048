// Pinned meshes (issue #11): every refactoring step must leave the meshes bit for bit as
// they were. For the shipped example scenes and 20 seeded random scenes per dimension,
// the sequential mesher's output is reduced to (order-free checksum, elements, nodes)
// and compared with pinned_meshes.tsv beside this file.
//
// A change that is meant to alter meshes re-pins, and says so in its commit:
//   CISAMR_REPIN=1 build/bin/test_pinned_meshes   (rewrites tests/regression/pinned_meshes.tsv)
#include <gtest/gtest.h>

#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "geometry/oracle.hpp"
#include "io/scene_io.hpp"
#include "io/stl_io.hpp"
#include "parallel/checksum.hpp"
#include "pipeline/pipeline.hpp"
#include "pipeline3/random_scenes3.hpp"
#include "support/random_scenes.hpp"

namespace cisamr {
namespace {

const std::string kTable = std::string(CISAMR_SOURCE_DIR) + "/tests/regression/pinned_meshes.tsv";
constexpr int kScenesPerDimension = 20;

struct Pin {
  std::string checksum;
  std::size_t elements = 0, nodes = 0;
  bool operator==(const Pin&) const = default;
};

std::string hex(std::uint64_t v) {
  char text[20];
  std::snprintf(text, sizeof text, "%016" PRIx64, v);
  return text;
}

template <class Mesh>
Pin pin_of(const Mesh& m) {
  return {hex(parallel::mesh_checksum(m)), m.cell_count(), m.node_count()};
}

Pin mesh_scene(const geometry::SceneDesc& scene) {
  if (scene.dimension == 2) return pin_of(pipeline::mesh(geometry::Oracle2(scene)).mesh);
  return pin_of(pipeline::mesh(geometry::Oracle3(scene)).mesh);
}

// Every pinned case, by name, in a fixed order.
std::vector<std::pair<std::string, geometry::SceneDesc>> pinned_scenes() {
  std::vector<std::pair<std::string, geometry::SceneDesc>> cases;
  const std::string root = CISAMR_SOURCE_DIR;
  for (const char* example : {"data/examples/composite.json", "data/examples/spheres3d.json",
                              "data/examples/stl3d.json", "data/bench/spheres300.json"})
    cases.emplace_back(example, io::read_scene(root + "/" + example));
  for (unsigned seed = 1; seed <= kScenesPerDimension; ++seed)
    cases.emplace_back("random2d-" + std::to_string(seed), testing::RandomScene2(seed).make());
  testing::StlShapes shapes;
  shapes.cube = io::read_stl(root + "/data/shapes/cube.stl");
  shapes.octahedron = io::read_stl(root + "/data/shapes/octahedron.stl");
  shapes.torus = io::read_stl(root + "/data/shapes/torus.stl");
  for (std::uint64_t seed = 1; seed <= kScenesPerDimension; ++seed)
    cases.emplace_back("random3d-" + std::to_string(seed), testing::RandomScene3(seed, shapes).make());
  return cases;
}

std::map<std::string, Pin> read_table() {
  std::map<std::string, Pin> table;
  std::ifstream in(kTable);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string name;
    Pin pin;
    fields >> name >> pin.checksum >> pin.elements >> pin.nodes;
    table[name] = pin;
  }
  return table;
}

TEST(PinnedMeshes, ExamplesAndSeededScenesUnchanged) {
  const auto cases = pinned_scenes();
  ASSERT_EQ(cases.size(), 4u + 2u * kScenesPerDimension);
  if (std::getenv("CISAMR_REPIN")) {
    std::ofstream out(kTable);
    out << "# name\tchecksum\telements\tnodes  (tests/regression/test_pinned_meshes.cpp)\n";
    for (const auto& [name, scene] : cases) {
      const Pin pin = mesh_scene(scene);
      out << name << '\t' << pin.checksum << '\t' << pin.elements << '\t' << pin.nodes << '\n';
    }
    GTEST_SKIP() << "re-pinned " << kTable;
  }
  const auto table = read_table();
  ASSERT_EQ(table.size(), cases.size()) << kTable << " is missing or incomplete";
  for (const auto& [name, scene] : cases) {
    SCOPED_TRACE(name);
    const auto it = table.find(name);
    ASSERT_NE(it, table.end());
    const Pin pin = mesh_scene(scene);
    EXPECT_EQ(pin.checksum, it->second.checksum);
    EXPECT_EQ(pin.elements, it->second.elements);
    EXPECT_EQ(pin.nodes, it->second.nodes);
  }
}

// The pin must be able to fail: one moved coordinate bit changes the checksum.
TEST(PinnedMeshes, ChecksumSeesOneBit) {
  const auto cases = pinned_scenes();
  const geometry::SceneDesc& scene = cases[4].second;  // random2d-1
  auto m = pipeline::mesh(geometry::Oracle2(scene)).mesh;
  const Pin before = pin_of(m);
  std::uint64_t bits;
  std::memcpy(&bits, &m.coords[0], sizeof bits);
  bits ^= 1;
  std::memcpy(&m.coords[0], &bits, sizeof bits);
  EXPECT_NE(pin_of(m).checksum, before.checksum);
}

}  // namespace
}  // namespace cisamr
