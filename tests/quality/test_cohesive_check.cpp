// The independent cohesive checker (quality/cohesive.hpp): correct hand-made cohesive
// meshes pass, and each deliberately broken variant is caught by its own counter.
// The meshes are split here by a brute-force reference written for this test, not by
// lib/mesh's insertion, so the checker is tested against the rules alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "mesh/boundary.hpp"
#include "mesh_builders.hpp"
#include "quality/cohesive.hpp"
#include "quality/quality.hpp"

namespace cisamr::quality {
namespace {
using namespace testing;

// ---- the reference split ------------------------------------------------------------------

// Every node used by cells of k phases becomes k nodes: the phase of its first cell keeps
// the id, the others get copies appended in order of first use. Each facet between cells
// of phases p < q gets one cohesive cell: the bottom is the p-cell's facet in
// mesh::FacetVertices order, reversed in 2D (that order has the p-cell's apex on the
// positive side in 2D, on the negative side in 3D), and top k is the q-copy of bottom k.
template <int Dim>
mesh::SimplexMesh<Dim> split_reference(const mesh::SimplexMesh<Dim>& in) {
  mesh::SimplexMesh<Dim> m = in;
  const std::size_t nodes = in.node_count();
  std::vector<int> first(nodes, INT_MIN);
  std::vector<LocalId> origin(nodes);
  for (std::size_t n = 0; n < nodes; ++n) origin[n] = static_cast<LocalId>(n);
  std::map<std::pair<LocalId, int>, LocalId> copy;
  for (std::size_t c = 0; c < m.cell_count(); ++c)
    for (int k = 0; k <= Dim; ++k) {
      LocalId& n = m.cell_nodes[c * (Dim + 1) + k];
      const int p = m.cell_phase[c];
      if (first[n] == INT_MIN) first[n] = p;
      if (first[n] == p) continue;
      auto [it, added] = copy.try_emplace({n, p}, static_cast<LocalId>(m.node_count()));
      if (added) {
        add_node<Dim>(m, in.point(n));
        origin.push_back(n);
      }
      n = it->second;
    }
  m.node_phase.assign(first.begin(), first.end());
  for (const auto& [key, id] : copy) {
    m.node_phase.resize(std::max<std::size_t>(m.node_phase.size(), id + 1));
    m.node_phase[id] = key.second;
  }
  using FV = mesh::FacetVertices<Dim>;
  auto facet_origins = [&](std::size_t c, int f) {
    std::array<LocalId, Dim> v;
    for (int k = 0; k < Dim; ++k) v[k] = origin[m.cell(c)[FV::local[f][k]]];
    std::sort(v.begin(), v.end());
    return v;
  };
  for (std::size_t i = 0; i < m.cell_count(); ++i)
    for (std::size_t j = i + 1; j < m.cell_count(); ++j)
      for (int f = 0; f <= Dim; ++f)
        for (int g = 0; g <= Dim; ++g) {
          if (m.cell_phase[i] == m.cell_phase[j] || facet_origins(i, f) != facet_origins(j, g)) continue;
          const bool i_lower = m.cell_phase[i] < m.cell_phase[j];
          const std::size_t lo = i_lower ? i : j, up = i_lower ? j : i;
          const int lf = i_lower ? f : g;
          std::array<LocalId, Dim> b;
          for (int k = 0; k < Dim; ++k) b[k] = m.cell(lo)[FV::local[lf][k]];
          if (Dim == 2) std::swap(b[0], b[1]);
          std::array<LocalId, Dim> t;
          for (int k = 0; k < Dim; ++k)
            for (int l = 0; l <= Dim; ++l)
              if (origin[m.cell(up)[l]] == origin[b[k]]) t[k] = m.cell(up)[l];
          m.cohesive.nodes.insert(m.cohesive.nodes.end(), b.begin(), b.end());
          m.cohesive.nodes.insert(m.cohesive.nodes.end(), t.begin(), t.end());
          m.cohesive.phase.push_back(m.cell_phase[lo]);
          m.cohesive.phase.push_back(m.cell_phase[up]);
          m.cohesive.partition.push_back(0);
        }
  return m;
}

// ---- the scenes ---------------------------------------------------------------------------

// Two triangles of the unit square, phase 1 below the diagonal 0-2, phase 2 above.
mesh::Mesh2 two_triangles() {
  mesh::Mesh2 m;
  add_node(m, 0, 0);
  add_node(m, 1, 0);
  add_node(m, 1, 1);
  add_node(m, 0, 1);
  add_cell<2>(m, {0, 1, 2}, 1);
  add_cell<2>(m, {0, 2, 3}, 2);
  return m;
}

// Two tets on the triangle (0,0,0) (1,0,0) (0,1,0): phase 2 above it, phase 1 below, so
// the lower phase is the second cell.
mesh::Mesh3 two_tets() {
  mesh::Mesh3 m;
  add_node(m, 0, 0, 0);
  add_node(m, 1, 0, 0);
  add_node(m, 0, 1, 0);
  add_node(m, 0, 0, 1);
  add_node(m, 0, 0, -1);
  add_cell<3>(m, {0, 1, 2, 3}, 2);
  add_cell<3>(m, {0, 2, 1, 4}, 1);
  return m;
}

constexpr std::array<std::array<double, 2>, 6> kRing = {{{2, 0}, {1, 2}, {-1, 2}, {-2, 0}, {-1, -2}, {1, -2}}};

// Six triangles around the origin with phases 1 1 2 2 3 3: a triple point, three interface
// edges and three same-phase edges around it.
mesh::Mesh2 triple_point() {
  mesh::Mesh2 m;
  add_node(m, 0, 0);
  for (const auto& p : kRing) add_node(m, p[0], p[1]);
  for (int i = 0; i < 6; ++i)
    add_cell<2>(m, {0, LocalId(1 + i), LocalId(1 + (i + 1) % 6)}, 1 + i / 2);
  return m;
}

// Six tets around the edge (0,0,0)-(0,0,1) with phases 1 1 2 2 3 3: a triple line.
mesh::Mesh3 triple_edge() {
  mesh::Mesh3 m;
  add_node(m, 0, 0, 0);
  add_node(m, 0, 0, 1);
  for (const auto& p : kRing) add_node(m, p[0], p[1], 0.5);
  for (int i = 0; i < 6; ++i) add_positive_tet(m, {0, 1, LocalId(2 + i), LocalId(2 + (i + 1) % 6)}, 1 + i / 2);
  return m;
}

// ---- helpers ------------------------------------------------------------------------------

template <int Dim>
std::vector<std::pair<const char*, std::size_t>> counters(const CohesiveReport<Dim>& r) {
  return {{"malformed", r.malformed.count},
          {"phase_mixed_nodes", r.phase_mixed_nodes.count},
          {"duplicate_copies", r.duplicate_copies.count},
          {"uncovered", r.uncovered.count},
          {"covered_twice", r.covered_twice.count},
          {"misplaced", r.misplaced.count},
          {"not_coincident", r.not_coincident.count},
          {"wrong_sides", r.wrong_sides.count},
          {"wrong_orientation", r.wrong_orientation.count},
          {"node_phase_mismatch", r.node_phase_mismatch.count}};
}

// Every failure counter except the ones named is zero, and the ones named are not.
template <int Dim>
void expect_only(const CohesiveReport<Dim>& r, std::initializer_list<std::string> failing) {
  for (const auto& [name, value] : counters(r)) {
    const bool expected = std::find(failing.begin(), failing.end(), name) != failing.end();
    if (expected)
      EXPECT_GT(value, 0u) << name << ": " << r.summary();
    else
      EXPECT_EQ(value, 0u) << name << ": " << r.summary();
  }
  EXPECT_EQ(r.ok(), failing.size() == 0) << r.summary();
}

// A cell with its nodes and coordinates, independent of node ids.
template <int Dim>
using CellPoints = std::pair<int, std::array<Vec<Dim>, Dim + 1>>;

template <int Dim>
std::vector<CellPoints<Dim>> cell_points(const mesh::SimplexMesh<Dim>& m) {
  std::vector<CellPoints<Dim>> cells;
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    CellPoints<Dim> e{m.cell_phase[c], {}};
    for (int k = 0; k <= Dim; ++k) e.second[k] = m.point(m.cell(c)[k]);
    cells.push_back(e);
  }
  std::sort(cells.begin(), cells.end());
  return cells;
}

// The checks every correct scene goes through: it passes; the welded view is the unsplit
// mesh; each broken variant is caught by its counter.
template <int Dim>
void check_scene(const mesh::SimplexMesh<Dim>& unsplit, std::size_t expected_cohesive) {
  const mesh::SimplexMesh<Dim> m = split_reference(unsplit);
  ASSERT_EQ(m.cohesive.count(), expected_cohesive);
  const auto good = check_cohesive(m);
  expect_only(good, {});
  EXPECT_EQ(good.cohesive_cells, expected_cohesive);
  EXPECT_EQ(good.interface_facets, expected_cohesive);
  EXPECT_NE(good.summary().find("every interface facet covered once"), std::string::npos) << good.summary();

  {  // The welded view is the unsplit mesh: the copies were appended after the originals.
    const auto w = weld_view(m);
    EXPECT_EQ(w.mesh.coords, unsplit.coords);
    EXPECT_EQ(w.mesh.cell_nodes, unsplit.cell_nodes);
    EXPECT_EQ(w.mesh.cell_phase, unsplit.cell_phase);
    EXPECT_EQ(cell_points(w.mesh), cell_points(unsplit));
    EXPECT_TRUE(w.mesh.cohesive.nodes.empty());
    EXPECT_TRUE(w.mesh.node_phase.empty());
    ASSERT_EQ(w.class_of.size(), m.node_count());
    for (std::size_t n = 0; n < m.node_count(); ++n) EXPECT_EQ(w.mesh.point(w.class_of[n]), m.point(LocalId(n)));
    // And the unsplit mesh welds to itself.
    EXPECT_EQ(weld_view(unsplit).mesh.cell_nodes, unsplit.cell_nodes);
  }
  constexpr int C = 2 * Dim;
  auto first_cell = [](mesh::SimplexMesh<Dim>& b) { return b.cohesive.nodes.begin(); };
  {
    SCOPED_TRACE("missing cell");
    auto b = m;
    b.cohesive.nodes.erase(first_cell(b), first_cell(b) + C);
    b.cohesive.phase.erase(b.cohesive.phase.begin(), b.cohesive.phase.begin() + 2);
    b.cohesive.partition.pop_back();
    const auto r = check_cohesive(b);
    expect_only(r, {"uncovered"});
    EXPECT_EQ(r.uncovered.count, 1u);
  }
  {
    SCOPED_TRACE("cell duplicated");
    auto b = m;
    b.cohesive.nodes.insert(b.cohesive.nodes.end(), m.cohesive.nodes.begin(), m.cohesive.nodes.begin() + C);
    b.cohesive.phase.insert(b.cohesive.phase.end(), m.cohesive.phase.begin(), m.cohesive.phase.begin() + 2);
    b.cohesive.partition.push_back(0);
    const auto r = check_cohesive(b);
    expect_only(r, {"covered_twice"});
    EXPECT_EQ(r.covered_twice.count, 1u);
  }
  {
    SCOPED_TRACE("bottom and top swapped");
    auto b = m;
    std::swap_ranges(first_cell(b), first_cell(b) + Dim, first_cell(b) + Dim);
    const auto r = check_cohesive(b);
    expect_only(r, {"wrong_sides"});
    EXPECT_EQ(r.wrong_sides.count, 1u);
    EXPECT_EQ(r.wrong_sides.ids, std::vector<std::int64_t>{0});
  }
  {
    SCOPED_TRACE("bottom and top swapped with their phases");
    auto b = m;
    std::swap_ranges(first_cell(b), first_cell(b) + Dim, first_cell(b) + Dim);
    std::swap(b.cohesive.phase[0], b.cohesive.phase[1]);
    expect_only(check_cohesive(b), {"wrong_sides"});
  }
  {
    SCOPED_TRACE("bottom reversed");
    auto b = m;
    std::swap(b.cohesive.nodes[0], b.cohesive.nodes[1]);
    std::swap(b.cohesive.nodes[Dim], b.cohesive.nodes[Dim + 1]);
    const auto r = check_cohesive(b);
    expect_only(r, {"wrong_orientation"});
    EXPECT_EQ(r.wrong_orientation.count, 1u);
  }
  {
    SCOPED_TRACE("top nodes permuted");
    auto b = m;
    std::swap(b.cohesive.nodes[Dim], b.cohesive.nodes[Dim + 1]);
    expect_only(check_cohesive(b), {"not_coincident"});
  }
  {
    SCOPED_TRACE("top node moved by one ulp");
    auto b = m;
    const LocalId t0 = m.cohesive.nodes[Dim];
    double& x = b.coords[std::size_t(t0) * Dim];
    x = std::nextafter(x, std::numeric_limits<double>::infinity());
    const auto r = check_cohesive(b);
    EXPECT_FALSE(r.ok());
    EXPECT_GE(r.not_coincident.count, 1u);
    // The moved copy no longer welds to the lower cells' nodes: conformity sees the crack.
    EXPECT_GT(check_conformity<Dim>(weld_view(b).mesh, quality::bounding_box<Dim>(b), -1, false).duplicate_nodes, 0u);
  }
  {
    SCOPED_TRACE("top refers to a node one ulp away");
    auto b = m;
    const LocalId t0 = m.cohesive.nodes[Dim];
    Vec<Dim> p = m.point(t0);
    p[Dim - 1] = std::nextafter(p[Dim - 1], -std::numeric_limits<double>::infinity());
    b.cohesive.nodes[Dim] = add_node<Dim>(b, p);
    b.node_phase.push_back(m.node_phase[t0]);
    expect_only(check_cohesive(b), {"not_coincident", "wrong_sides"});
  }
  {
    SCOPED_TRACE("a node shared by two phases");
    auto b = m;
    const LocalId b0 = m.cohesive.nodes[0], t0 = m.cohesive.nodes[Dim];
    std::replace(b.cell_nodes.begin(), b.cell_nodes.end(), t0, b0);  // the upper cells use the lower copy
    const auto r = check_cohesive(b);
    EXPECT_FALSE(r.ok());
    EXPECT_GE(r.phase_mixed_nodes.count, 1u);
    EXPECT_EQ(r.phase_mixed_nodes.ids.front(), b0);
  }
  {
    SCOPED_TRACE("wrong phase pair order");
    auto b = m;
    std::swap(b.cohesive.phase[0], b.cohesive.phase[1]);
    const auto r = check_cohesive(b);
    expect_only(r, {"wrong_sides"});
    EXPECT_EQ(r.wrong_sides.count, 1u);
  }
  {
    SCOPED_TRACE("phases of another interface");
    auto b = m;
    b.cohesive.phase[1] += 10;
    expect_only(check_cohesive(b), {"misplaced"});
  }
  {
    SCOPED_TRACE("a bottom that is no facet");
    auto b = m;
    // Bottom and top node 0 replaced by bottom node 1: coincident still, but a degenerate
    // bottom that no facet of the mesh has.
    b.cohesive.nodes[0] = b.cohesive.nodes[1];
    b.cohesive.nodes[Dim] = b.cohesive.nodes[1];
    const auto r = check_cohesive(b);
    expect_only(r, {"misplaced", "uncovered"});
    EXPECT_EQ(r.misplaced.ids, std::vector<std::int64_t>{0});
  }
  {
    SCOPED_TRACE("node_phase wrong");
    auto b = m;
    b.node_phase[m.cohesive.nodes[Dim]] = m.cohesive.phase[0];
    const auto r = check_cohesive(b);
    expect_only(r, {"node_phase_mismatch"});
    EXPECT_EQ(r.node_phase_mismatch.ids, std::vector<std::int64_t>{m.cohesive.nodes[Dim]});
  }
  {
    SCOPED_TRACE("node_phase too short");
    auto b = m;
    b.node_phase.pop_back();
    expect_only(check_cohesive(b), {"node_phase_mismatch"});
  }
  {
    SCOPED_TRACE("a node id out of range");
    auto b = m;
    b.cohesive.nodes[Dim] = static_cast<LocalId>(m.node_count());
    const auto r = check_cohesive(b);
    expect_only(r, {"malformed", "uncovered"});
    EXPECT_EQ(r.malformed.ids, std::vector<std::int64_t>{0});
  }
  {
    SCOPED_TRACE("no cohesive cells on a split mesh");
    auto b = m;
    b.cohesive = {};
    const auto r = check_cohesive(b);
    expect_only(r, {"uncovered"});
    EXPECT_EQ(r.uncovered.count, expected_cohesive);
    EXPECT_NE(r.summary().find("uncovered"), std::string::npos);
  }
  {
    SCOPED_TRACE("no split at all");
    auto b = unsplit;
    const auto r = check_cohesive(b);
    expect_only(r, {"uncovered", "phase_mixed_nodes"});
  }
}

// ---- the tests ----------------------------------------------------------------------------

TEST(CohesiveCheck, TwoTrianglesSplitByHand) {
  const mesh::Mesh2 m = split_reference(two_triangles());
  // Nodes 0 and 2 get phase-2 copies 4 and 5; the bottom is edge 0→2 of the phase-1 cell,
  // whose +90° normal (-1, 1)/√2 points to node 3 of the phase-2 cell.
  EXPECT_EQ(m.cell_nodes, (std::vector<LocalId>{0, 1, 2, 4, 5, 3}));
  EXPECT_EQ(m.cohesive.nodes, (std::vector<LocalId>{0, 2, 4, 5}));
  EXPECT_EQ(m.cohesive.phase, (std::vector<std::int32_t>{1, 2}));
  EXPECT_EQ(m.node_phase, (std::vector<std::int32_t>{1, 1, 1, 2, 2, 2}));
  expect_only(check_cohesive(m), {});
  EXPECT_EQ(check_cohesive(m).summary(), "cohesive: 1 cells on 1 interface facets; every interface facet covered once");
}

TEST(CohesiveCheck, TwoTrianglesBrokenVariants) { check_scene(two_triangles(), 1); }

TEST(CohesiveCheck, TwoTetsSplitByHand) {
  const mesh::Mesh3 m = split_reference(two_tets());
  // The phase-1 tet is the second: its nodes 0 2 1 become copies 5 6 7. Bottom: its facet
  // 5 7 6 = (0,0,0) (1,0,0) (0,1,0), normal +z, towards the phase-2 apex (0,0,1).
  EXPECT_EQ(m.cell_nodes, (std::vector<LocalId>{0, 1, 2, 3, 5, 6, 7, 4}));
  EXPECT_EQ(m.cohesive.nodes, (std::vector<LocalId>{5, 7, 6, 0, 1, 2}));
  EXPECT_EQ(m.cohesive.phase, (std::vector<std::int32_t>{1, 2}));
  expect_only(check_cohesive(m), {});
}

TEST(CohesiveCheck, TwoTetsBrokenVariants) { check_scene(two_tets(), 1); }

TEST(CohesiveCheck, TriplePoint2) {
  const mesh::Mesh2 unsplit = triple_point();
  check_scene(unsplit, 3);
  const mesh::Mesh2 m = split_reference(unsplit);
  // The centre has one copy per phase, each interface ring node two.
  EXPECT_EQ(m.node_count(), 7u + 2 + 3);
  EXPECT_EQ(check_cohesive(m).interface_facets, 3u);
}

TEST(CohesiveCheck, TripleEdge3) {
  const mesh::Mesh3 unsplit = triple_edge();
  check_scene(unsplit, 3);
  const mesh::Mesh3 m = split_reference(unsplit);
  EXPECT_EQ(m.node_count(), 8u + 2 * 2 + 3);  // both edge ends ×3, three ring nodes ×2
}

TEST(CohesiveCheck, CellOnSamePhaseFacetIsMisplaced) {
  // Triangles 0 and 1 are both phase 1 and share the edge centre-ring node 2.
  mesh::Mesh2 m = split_reference(triple_point());
  ASSERT_EQ(m.cell_phase[0], m.cell_phase[1]);
  m.cohesive.nodes.insert(m.cohesive.nodes.end(), {0, 2, 0, 2});
  m.cohesive.phase.insert(m.cohesive.phase.end(), {1, 2});
  m.cohesive.partition.push_back(0);
  const auto r = check_cohesive(m);
  expect_only(r, {"misplaced"});
  EXPECT_EQ(r.misplaced.ids, std::vector<std::int64_t>{3});
  EXPECT_EQ(r.misplaced.points.front(), (Vec2{0.5, 1}));  // the edge's midpoint
}

TEST(CohesiveCheck, CellOnSamePhaseFacet3IsMisplaced) {
  mesh::Mesh3 m = split_reference(triple_edge());
  ASSERT_EQ(m.cell_phase[0], m.cell_phase[1]);
  // Tets 0 and 1 share the facet 0 1 3 (edge ends and ring node 1).
  m.cohesive.nodes.insert(m.cohesive.nodes.end(), {0, 1, 3, 0, 1, 3});
  m.cohesive.phase.insert(m.cohesive.phase.end(), {1, 1});
  m.cohesive.partition.push_back(0);
  expect_only(check_cohesive(m), {"misplaced"});
}

TEST(CohesiveCheck, CellOnBoundaryFacetIsMisplaced) {
  mesh::Mesh2 m = split_reference(two_triangles());
  // Edge 1→2 (x = 1) lies on the box: one cell, nothing on the other side.
  m.cohesive.nodes.insert(m.cohesive.nodes.end(), {1, 2, 1, 2});
  m.cohesive.phase.insert(m.cohesive.phase.end(), {1, 2});
  m.cohesive.partition.push_back(0);
  expect_only(check_cohesive(m), {"misplaced"});
}

TEST(CohesiveCheck, SamePhaseMeshNeedsNothing) {
  const mesh::Mesh2 m2 = structured_triangles(3, 2);
  expect_only(check_cohesive(m2), {});
  EXPECT_EQ(check_cohesive(m2).interface_facets, 0u);
  const mesh::Mesh3 m3 = structured_tets(2, 1, 1);
  expect_only(check_cohesive(m3), {});
  EXPECT_EQ(split_reference(m3).cohesive.count(), 0u);
}

TEST(CohesiveCheck, VoidFacetsNeedNothing) {
  // The triple point with its last phase-3 triangle removed (a void there): the facets
  // toward the void have one cell, so only 1|2 and 2|3 need cells.
  mesh::Mesh2 unsplit = triple_point();
  remove_cell<2>(unsplit, 5);
  check_scene(unsplit, 2);
  mesh::Mesh3 unsplit3 = triple_edge();
  remove_cell<3>(unsplit3, 0);
  check_scene(unsplit3, 2);
}

TEST(CohesiveCheck, WeldedViewPassesConformity) {
  // Unwelded, the copies are near-duplicates and the interfaces open facets; welded, the
  // mesh is the unit square again.
  const mesh::Mesh2 m = split_reference(two_triangles());
  EXPECT_FALSE(check_conformity<2>(m, Box2{{0, 0}, {1, 1}}, 1.0, false).ok);
  const auto c = check_conformity<2>(weld_view(m).mesh, Box2{{0, 0}, {1, 1}}, 1.0, false);
  EXPECT_TRUE(c.ok) << (c.examples.empty() ? "" : c.examples.front());
  // The fans are no boxes: their outer facets count as inner boundary.
  const mesh::Mesh2 t2 = split_reference(triple_point());
  EXPECT_TRUE(check_conformity<2>(weld_view(t2).mesh, quality::bounding_box<2>(t2), 12.0, true).ok);
  EXPECT_FALSE(check_conformity<2>(t2, quality::bounding_box<2>(t2), 12.0, true).ok);
  const mesh::Mesh3 t3 = split_reference(triple_edge());
  EXPECT_TRUE(check_conformity<3>(weld_view(t3).mesh, quality::bounding_box<3>(t3), -1, true).ok);
  EXPECT_FALSE(check_conformity<3>(t3, quality::bounding_box<3>(t3), -1, true).ok);
}

TEST(CohesiveCheck, TwoCopiesOfOnePhaseAtOnePosition) {
  // A crack inside one phase: cell 0 gets its own copy of its first node, which other
  // cells of the same phase keep using.
  mesh::Mesh2 m2 = structured_triangles(2, 2);
  const LocalId n2 = 4;  // the centre, used by six cells
  const LocalId c2 = add_node(m2, m2.point(n2));
  *std::find(m2.cell_nodes.begin(), m2.cell_nodes.end(), n2) = c2;
  auto r2 = check_cohesive(m2);
  expect_only(r2, {"duplicate_copies"});
  EXPECT_EQ(r2.duplicate_copies.ids, std::vector<std::int64_t>{c2});
  EXPECT_EQ(r2.duplicate_copies.points.front(), (Vec2{1, 1}));
  // Both nodes welded: the welded mesh is the structured one.
  EXPECT_EQ(weld_view(m2).mesh.cell_nodes, structured_triangles(2, 2).cell_nodes);

  mesh::Mesh3 m3 = structured_tets(2, 1, 1);
  const LocalId n3 = 1;  // (1, 0, 0), on the face between the two cubes
  const LocalId c3 = add_node(m3, m3.point(n3));
  *std::find(m3.cell_nodes.begin(), m3.cell_nodes.end(), n3) = c3;
  expect_only(check_cohesive(m3), {"duplicate_copies"});
  // Copies of different phases at one position are what a split makes: fine.
  for (std::size_t c = 0; c < m3.cell_count(); ++c)
    if (std::find(m3.cell(c), m3.cell(c) + 4, c3) != m3.cell(c) + 4) m3.cell_phase[c] = 2;
  EXPECT_EQ(check_cohesive(m3).duplicate_copies.count, 0u);
}

TEST(CohesiveCheck, WeldTreatsNegativeZeroAsZero) {
  mesh::Mesh2 m = two_triangles();
  // Node 4 at (-0, 0) is node 0's position: welded, it is node 0.
  const LocalId n = add_node(m, -0.0, 0.0);
  m.cell_nodes[3] = n;  // the phase-2 cell's first node
  const auto w = weld_view(m);
  EXPECT_EQ(w.class_of[n], 0);
  EXPECT_EQ(w.mesh.node_count(), 4u);
  EXPECT_EQ(w.mesh.cell_nodes, two_triangles().cell_nodes);
  // One ulp off zero is another position.
  m.coords[2 * std::size_t(n)] = -std::numeric_limits<double>::denorm_min();
  EXPECT_EQ(weld_view(m).mesh.node_count(), 5u);
}

TEST(CohesiveCheck, WeldKeepsBadIdsVisible) {
  mesh::Mesh2 m = two_triangles();
  m.cell_nodes[5] = 17;
  const auto w = weld_view(m);
  EXPECT_EQ(w.mesh.cell_nodes[5], -1);
  EXPECT_EQ(check_conformity<2>(w.mesh, quality::bounding_box<2>(w.mesh), -1, false).bad_node_references, 1u);
}

TEST(CohesiveCheck, ExamplesAreCapped) {
  // A strip of triangles alternating phases 1 and 2 without cohesive cells: more
  // uncovered edges than examples kept.
  mesh::Mesh2 m = structured_triangles(10, 1);
  for (std::size_t c = 0; c < m.cell_count(); ++c) m.cell_phase[c] = 1 + int(c % 2);
  m = split_reference(m);
  m.cohesive = {};
  const auto r = check_cohesive(m);
  EXPECT_GT(r.uncovered.count, kCohesiveExamples);
  EXPECT_EQ(r.uncovered.count, r.interface_facets);
  EXPECT_EQ(r.uncovered.ids.size(), kCohesiveExamples);
  EXPECT_EQ(r.uncovered.points.size(), kCohesiveExamples);
}

}  // namespace
}  // namespace cisamr::quality
