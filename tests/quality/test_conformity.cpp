// Conformity: correct meshes pass; each deliberately broken mesh is caught by its counter.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "mesh_builders.hpp"
#include "quality/quality.hpp"

namespace cisamr::quality {
namespace {
using namespace testing;

Box2 box2(double x0, double y0, double x1, double y1) { return Box2{{x0, y0}, {x1, y1}}; }
Box3 unit_box3(double nx, double ny, double nz) { return Box3{{0, 0, 0}, {nx, ny, nz}}; }

bool mentions(const ConformityReport& r, const std::string& word) {
  return std::any_of(r.examples.begin(), r.examples.end(),
                     [&](const std::string& e) { return e.find(word) != std::string::npos; });
}

// Every error counter except the ones named is zero.
void expect_only(const ConformityReport& r, std::initializer_list<const char*> allowed) {
  auto allowed_has = [&](const char* k) {
    return std::find_if(allowed.begin(), allowed.end(), [&](const char* a) { return std::string(a) == k; }) != allowed.end();
  };
  const std::pair<const char*, std::size_t> counters[] = {
      {"duplicate", r.duplicate_nodes},          {"degenerate", r.degenerate_cells},
      {"inverted", r.inverted_cells},            {"bad", r.bad_node_references},
      {"non_manifold", r.non_manifold_facets},   {"orientation", r.mismatched_orientation_facets},
      {"open", r.open_facets_inside},            {"hanging", r.hanging_nodes},
      {"unused", r.unused_nodes}};
  for (const auto& [name, value] : counters)
    if (!allowed_has(name)) {
      EXPECT_EQ(value, 0u) << name;
    }
}

TEST(Conformity, StructuredTriangleMeshPasses) {
  const mesh::Mesh2 m = structured_triangles(4, 3, 0.5, {1, 2});
  const auto r = check_conformity<2>(m, box2(1, 2, 3, 3.5), 3.0, false);
  EXPECT_TRUE(r.ok);
  expect_only(r, {});
  EXPECT_EQ(r.boundary_facets, 2u * (4 + 3));
  EXPECT_EQ(r.inner_boundary_facets, 0u);
  EXPECT_NEAR(r.measure, 3.0, 1e-14);
  EXPECT_LT(r.measure_error, 1e-14);
  EXPECT_TRUE(r.examples.empty());
}

TEST(Conformity, DomainLargerThanMeshShowsOpenFacets) {
  // The same mesh checked against a bigger box: its border is now "inside".
  const mesh::Mesh2 m = structured_triangles(2, 2);
  const auto r = check_conformity<2>(m, box2(0, 0, 3, 2), -1, false);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.open_facets_inside, 2u);  // the right side x = 2
  EXPECT_EQ(r.boundary_facets, 6u);
}

TEST(Conformity, FlippedTriangleIsInverted) {
  mesh::Mesh2 m = structured_triangles(3, 3);
  std::swap(m.cell_nodes[3 * 8 + 1], m.cell_nodes[3 * 8 + 2]);  // a cell in the middle
  const auto r = check_conformity<2>(m, box2(0, 0, 3, 3), 9.0, false);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.inverted_cells, 1u);
  EXPECT_EQ(r.mismatched_orientation_facets, 3u);  // all its edges are interior
  expect_only(r, {"inverted", "orientation"});
  EXPECT_LT(r.measure_error, 1e-14);  // the measure alone would not see it
  EXPECT_TRUE(mentions(r, "inverted cell 8"));
}

// Square A = [0,1]² in 2 triangles; square B = [1,2]×[0,1] in 3 triangles fanned from the
// midpoint m = (1, 0.5) of the shared side: m is a hanging node on A's edge.
TEST(Conformity, TJunctionIsAHangingNode) {
  mesh::Mesh2 g;
  const LocalId a0 = add_node(g, 0, 0), a1 = add_node(g, 1, 0), a2 = add_node(g, 1, 1), a3 = add_node(g, 0, 1);
  const LocalId b1 = add_node(g, 2, 0), b2 = add_node(g, 2, 1), mid = add_node(g, 1, 0.5);
  add_cell<2>(g, {a0, a1, a2});
  add_cell<2>(g, {a0, a2, a3});
  add_cell<2>(g, {mid, a1, b1});
  add_cell<2>(g, {mid, b1, b2});
  add_cell<2>(g, {mid, b2, a2});
  const auto r = check_conformity<2>(g, box2(0, 0, 2, 1), 2.0, false);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.hanging_nodes, 1u);
  EXPECT_EQ(r.open_facets_inside, 3u);  // A's side and B's two half sides
  expect_only(r, {"hanging", "open"});
  EXPECT_LT(r.measure_error, 1e-14);
  EXPECT_TRUE(mentions(r, "hanging node 6 (1, 0.5)"));

  // Splitting A's side at the same node repairs it.
  mesh::Mesh2 fixed = g;
  fixed.cell_nodes.clear();
  fixed.cell_phase.clear();
  fixed.cell_partition.clear();
  add_cell<2>(fixed, {a0, a1, mid});
  add_cell<2>(fixed, {a0, mid, a2});
  add_cell<2>(fixed, {a0, a2, a3});
  add_cell<2>(fixed, {mid, a1, b1});
  add_cell<2>(fixed, {mid, b1, b2});
  add_cell<2>(fixed, {mid, b2, a2});
  EXPECT_TRUE(check_conformity<2>(fixed, box2(0, 0, 2, 1), 2.0, false).ok);
}

TEST(Conformity, DuplicatedNode) {
  mesh::Mesh2 m = structured_triangles(2, 2);
  // Node 4 = (1,1) is interior; give cell 0 (a = 0, b = 1, c = 4) its own copy.
  ASSERT_EQ(m.cell_nodes[2], 4);
  m.cell_nodes[2] = add_node(m, 1, 1);
  const auto r = check_conformity<2>(m, box2(0, 0, 2, 2), 4.0, false);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.duplicate_nodes, 1u);
  EXPECT_EQ(r.open_facets_inside, 4u);  // the crack: two edges on each side
  expect_only(r, {"duplicate", "open"});
  EXPECT_TRUE(mentions(r, "(exact)"));
}

TEST(Conformity, NearDuplicatedNode) {
  mesh::Mesh2 m = structured_triangles(2, 2);
  m.cell_nodes[2] = add_node(m, 1 + 1e-14, 1 - 1e-14);  // within 1e-12 · diagonal
  const auto r = check_conformity<2>(m, box2(0, 0, 2, 2), 4.0, false);
  EXPECT_EQ(r.duplicate_nodes, 1u);
  EXPECT_FALSE(mentions(r, "(exact)"));

  // 1e-9 apart is not a duplicate (but still a crack).
  mesh::Mesh2 n = structured_triangles(2, 2);
  n.cell_nodes[2] = add_node(n, 1 + 1e-9, 1);
  const auto s = check_conformity<2>(n, box2(0, 0, 2, 2), 4.0, false);
  EXPECT_EQ(s.duplicate_nodes, 0u);
  EXPECT_FALSE(s.ok);
}

TEST(Conformity, MissingTriangleIsAHole) {
  mesh::Mesh2 m = structured_triangles(3, 3);
  remove_cell<2>(m, 8);  // in the middle square
  const auto r = check_conformity<2>(m, box2(0, 0, 3, 3), 9.0, false);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.open_facets_inside, 3u);
  expect_only(r, {"open"});
  EXPECT_NEAR(r.measure, 8.5, 1e-14);
  EXPECT_NEAR(r.measure_error, 0.5 / 9, 1e-14);
  EXPECT_TRUE(mentions(r, "total measure"));

  // With voids allowed the open facets are an inner boundary; the measure still fails...
  const auto v = check_conformity<2>(m, box2(0, 0, 3, 3), 9.0, true);
  EXPECT_EQ(v.open_facets_inside, 0u);
  EXPECT_EQ(v.inner_boundary_facets, 3u);
  EXPECT_FALSE(v.ok);
  // ...unless the expected measure accounts for the hole.
  EXPECT_TRUE(check_conformity<2>(m, box2(0, 0, 3, 3), 8.5, true).ok);
}

TEST(Conformity, DegenerateTriangle) {
  // [0,1]² with a midpoint m on the bottom side, plus a flat triangle (0, 1, m).
  mesh::Mesh2 g;
  const LocalId p0 = add_node(g, 0, 0), p1 = add_node(g, 1, 0), p2 = add_node(g, 1, 1), p3 = add_node(g, 0, 1);
  const LocalId mid = add_node(g, 0.5, 0);
  add_cell<2>(g, {p0, mid, p3});
  add_cell<2>(g, {mid, p1, p2});
  add_cell<2>(g, {mid, p2, p3});
  EXPECT_TRUE(check_conformity<2>(g, box2(0, 0, 1, 1), 1.0, false).ok);
  add_cell<2>(g, {p0, p1, mid});
  const auto r = check_conformity<2>(g, box2(0, 0, 1, 1), 1.0, false);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.degenerate_cells, 1u);
  expect_only(r, {"degenerate"});
  EXPECT_TRUE(mentions(r, "degenerate cell 3"));
}

TEST(Conformity, OverlappingTriangles) {
  // [0,1]² as (0,1,2) + (0,2,3), and a third triangle (0,1,3) over both.
  mesh::Mesh2 g;
  for (auto [x, y] : {std::pair{0., 0.}, {1., 0.}, {1., 1.}, {0., 1.}}) add_node(g, x, y);
  add_cell<2>(g, {0, 1, 2});
  add_cell<2>(g, {0, 2, 3});
  add_cell<2>(g, {0, 1, 3});
  const auto r = check_conformity<2>(g, box2(0, 0, 1, 1), 1.0, false);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.mismatched_orientation_facets, 2u);  // (0,1) and (3,0) listed twice the same way
  EXPECT_EQ(r.open_facets_inside, 1u);             // its diagonal (1,3)
  EXPECT_NEAR(r.measure_error, 0.5, 1e-14);

  // The same triangle twice: three cells on its interior edges.
  mesh::Mesh2 m = structured_triangles(3, 3);
  add_cell<2>(m, {m.cell(8)[0], m.cell(8)[1], m.cell(8)[2]});
  const auto s = check_conformity<2>(m, box2(0, 0, 3, 3), 9.0, false);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.non_manifold_facets, 3u);
  EXPECT_GT(s.measure_error, 0.05);
}

TEST(Conformity, UnusedNodeAndBadReference) {
  mesh::Mesh2 m = structured_triangles(2, 2);
  add_node(m, 0.5, 0.5);
  const auto r = check_conformity<2>(m, box2(0, 0, 2, 2), 4.0, false);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.unused_nodes, 1u);
  expect_only(r, {"unused"});

  mesh::Mesh2 b = structured_triangles(2, 2);
  b.cell_nodes[5] = 999;
  const auto s = check_conformity<2>(b, box2(0, 0, 2, 2), -1, false);
  EXPECT_FALSE(s.ok);
  EXPECT_EQ(s.bad_node_references, 1u);
}

// ---- 3D ----

TEST(Conformity3, FiveTetCubePasses) {
  const mesh::Mesh3 one = structured_tets(1, 1, 1);
  const auto r = check_conformity<3>(one, unit_box3(1, 1, 1), 1.0, false);
  EXPECT_TRUE(r.ok);
  expect_only(r, {});
  EXPECT_EQ(r.boundary_facets, 12u);
  EXPECT_NEAR(r.measure, 1.0, 1e-14);

  const mesh::Mesh3 grid = structured_tets(2, 3, 2);
  const auto g = check_conformity<3>(grid, unit_box3(2, 3, 2), 12.0, false);
  EXPECT_TRUE(g.ok);
  EXPECT_EQ(g.boundary_facets, 2u * 2 * (2 * 3 + 3 * 2 + 2 * 2));
}

TEST(Conformity3, NonMatchingDiagonalsAreCaught) {
  // Two cubes with the same (unmirrored) decomposition: their shared face gets crossing
  // diagonals, i.e. open facets inside.
  mesh::Mesh3 m = structured_tets(1, 1, 1);
  const mesh::Mesh3 copy = structured_tets(1, 1, 1);
  const auto offset = static_cast<LocalId>(m.node_count());
  for (std::size_t n = 0; n < copy.node_count(); ++n) {
    const Vec3 p = copy.point(static_cast<LocalId>(n));
    add_node(m, p[0] + 1, p[1], p[2]);
  }
  for (std::size_t c = 0; c < copy.cell_count(); ++c) {
    const LocalId* t = copy.cell(c);
    add_cell<3>(m, {t[0] + offset, t[1] + offset, t[2] + offset, t[3] + offset});
  }
  const auto r = check_conformity<3>(m, unit_box3(2, 1, 1), 2.0, false);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.duplicate_nodes, 4u);  // the shared face's corners, not merged
  EXPECT_EQ(r.open_facets_inside, 4u);
}

TEST(Conformity3, BrokenTetMeshes) {
  const Box3 box = unit_box3(2, 2, 2);
  {  // inverted
    mesh::Mesh3 m = structured_tets(2, 2, 2);
    std::swap(m.cell_nodes[4 * 10 + 2], m.cell_nodes[4 * 10 + 3]);
    const auto r = check_conformity<3>(m, box, 8.0, false);
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(r.inverted_cells, 1u);
    expect_only(r, {"inverted", "orientation"});
    EXPECT_GE(r.mismatched_orientation_facets, 1u);
  }
  {  // missing: the central tet of the first cube
    mesh::Mesh3 m = structured_tets(2, 2, 2);
    remove_cell<3>(m, 0);
    const auto r = check_conformity<3>(m, box, 8.0, false);
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(r.open_facets_inside, 4u);
    expect_only(r, {"open"});
    EXPECT_NEAR(r.measure_error, (1.0 / 3) / 8, 1e-14);
  }
  {  // degenerate: a flat tet in a cube's face plane
    mesh::Mesh3 m = structured_tets(1, 1, 1);
    add_cell<3>(m, {0, 1, 2, 3});  // the four corners z = 0
    const auto r = check_conformity<3>(m, unit_box3(1, 1, 1), 1.0, false);
    EXPECT_EQ(r.degenerate_cells, 1u);
    EXPECT_FALSE(r.ok);
  }
}

// Cube A = [0,1]³ in 5 tets; cube B = [1,2]×[0,1]² coned from its centre over its faces,
// with the shared face x = 1 split into 4 at its centre f = (1, .5, .5). f lies on A's face
// diagonal: a hanging node.
TEST(Conformity3, HangingNodeOnSharedFace) {
  mesh::Mesh3 m = structured_tets(1, 1, 1);
  auto id = [](int x, int y, int z) { return static_cast<LocalId>(x + 2 * y + 4 * z); };
  const LocalId b1[4] = {add_node(m, 2, 0, 0), add_node(m, 2, 1, 0), add_node(m, 2, 0, 1), add_node(m, 2, 1, 1)};
  auto bnode = [&](int x, int y, int z) { return x == 1 ? id(1, y, z) : b1[y + 2 * z]; };
  const LocalId centre = add_node(m, 1.5, 0.5, 0.5), face = add_node(m, 1, 0.5, 0.5);
  // Shared face x = 1: 4 triangles around f.
  const std::array<std::array<int, 2>, 4> ring = {{{0, 0}, {1, 0}, {1, 1}, {0, 1}}};
  for (int k = 0; k < 4; ++k) {
    const auto [y0, z0] = ring[k];
    const auto [y1, z1] = ring[(k + 1) % 4];
    add_positive_tet(m, {centre, face, bnode(1, y0, z0), bnode(1, y1, z1)});
  }
  // The five other faces of B, 2 triangles each.
  auto quad = [&](LocalId a, LocalId b, LocalId c, LocalId d) {
    add_positive_tet(m, {centre, a, b, c});
    add_positive_tet(m, {centre, a, c, d});
  };
  quad(bnode(2, 0, 0), bnode(2, 1, 0), bnode(2, 1, 1), bnode(2, 0, 1));  // x = 2
  quad(bnode(1, 0, 0), bnode(2, 0, 0), bnode(2, 0, 1), bnode(1, 0, 1));  // y = 0
  quad(bnode(1, 1, 0), bnode(2, 1, 0), bnode(2, 1, 1), bnode(1, 1, 1));  // y = 1
  quad(bnode(1, 0, 0), bnode(2, 0, 0), bnode(2, 1, 0), bnode(1, 1, 0));  // z = 0
  quad(bnode(1, 0, 1), bnode(2, 0, 1), bnode(2, 1, 1), bnode(1, 1, 1));  // z = 1
  const auto r = check_conformity<3>(m, unit_box3(2, 1, 1), 2.0, false);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.hanging_nodes, 1u);
  EXPECT_EQ(r.open_facets_inside, 6u);  // A's 2 halves of x = 1, B's 4 quarters
  expect_only(r, {"hanging", "open"});
  EXPECT_LT(r.measure_error, 1e-14);
}

}  // namespace
}  // namespace cisamr::quality
