// mesh::exploded_coords (cisamr mesh --explode): each connected region moves by (F − 1)
// times its measure-weighted centroid's offset from the domain's.
#include "mesh/explode.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "mesh/cohesive.hpp"

namespace cisamr::mesh {
namespace {

// A 4×1 strip of unit squares (2 triangles each); cells of x < 1 are phase 2.
Mesh2 strip() {
  Mesh2 m;
  for (int j = 0; j <= 1; ++j)
    for (int i = 0; i <= 4; ++i) m.coords.insert(m.coords.end(), {double(i), double(j)});
  for (int i = 0; i < 4; ++i) {
    const LocalId a = i, b = i + 1, c = i + 6, d = i + 5;
    m.cell_nodes.insert(m.cell_nodes.end(), {a, b, c, a, c, d});
    m.cell_phase.insert(m.cell_phase.end(), 2, i < 1 ? 2 : 1);
  }
  m.cell_partition.assign(m.cell_phase.size(), 0);
  return m;
}

TEST(ExplodedCoords, ConnectedMeshDoesNotMove) {
  const Mesh2 m = strip();  // one region: its centroid is the domain's
  EXPECT_EQ(exploded_coords(m, 3.0), m.coords);
}

TEST(ExplodedCoords, SplitRegionsMoveApartByTheirCentroidOffsets) {
  Mesh2 m = strip();
  insert_cohesive(m, 0);
  ASSERT_EQ(m.cohesive.count(), 1u);
  // Domain centroid x = 2; the phase-2 square's centroid x = 0.5, the rest's 2.5; y = 0.5
  // for all, so y stays.
  const double factor = 1.5;
  const std::vector<double> x = exploded_coords(m, factor);
  ASSERT_EQ(x.size(), m.coords.size());
  for (std::size_t n = 0; n < m.node_count(); ++n) {
    const double shift = m.node_phase[n] == 2 ? (factor - 1) * (0.5 - 2.0) : (factor - 1) * (2.5 - 2.0);
    EXPECT_DOUBLE_EQ(x[2 * n], m.coords[2 * n] + shift) << "node " << n;
    EXPECT_DOUBLE_EQ(x[2 * n + 1], m.coords[2 * n + 1]) << "node " << n;
  }
  // The cohesive cell opens: its top (phase 2, on the left) moves 1 away from its bottom.
  const LocalId* c = m.cohesive.cell(0);
  for (int k = 0; k < 2; ++k) EXPECT_DOUBLE_EQ(x[2 * c[2 + k]] - x[2 * c[k]], -1.0);
  EXPECT_EQ(exploded_coords(m, 1.0), m.coords);
}

// 3D: two tetrahedra sharing no node move apart along the line joining their centroids,
// weighted by volume; a node in no cell stays.
TEST(ExplodedCoords, WeightsByVolumeAndLeavesLooseNodes) {
  Mesh3 m;
  m.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1,     // unit corner tet, volume 1/6
              10, 0, 0, 12, 0, 0, 10, 2, 0, 10, 0, 2,  // twice the size: volume 8/6
              5, 5, 5};                                // loose
  m.cell_nodes = {0, 1, 2, 3, 4, 5, 6, 7};
  m.cell_phase = {1, 2};
  m.cell_partition = {0, 0};
  const double small = 0.25, large = 10.5;  // centroid x
  const double domain = (small * 1 + large * 8) / 9;
  const std::vector<double> x = exploded_coords(m, 2.0);
  for (int n = 0; n < 4; ++n) EXPECT_NEAR(x[3 * n], m.coords[3 * n] + (small - domain), 1e-12);
  for (int n = 4; n < 8; ++n) EXPECT_NEAR(x[3 * n], m.coords[3 * n] + (large - domain), 1e-12);
  for (int d = 0; d < 3; ++d) EXPECT_EQ(x[24 + d], 5.0);
}

}  // namespace
}  // namespace cisamr::mesh
