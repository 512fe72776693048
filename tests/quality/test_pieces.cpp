// Certifying a mesh piece by piece (quality::PiecewiseCertifier) gives the certificate of
// the merged mesh: the same counts on clean meshes and on meshes broken across pieces
// (a cell in two pieces, an interface node under two ids, a hanging node on the cut, a
// node off the interface whose phases differ between pieces).
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "geometry/oracle.hpp"
#include "mesh_builders.hpp"
#include "quality/certificate.hpp"
#include "quality/pieces.hpp"
#include "scene_builders.hpp"

namespace cisamr::quality {
namespace {
using namespace testing;

// Cell c goes to the piece numbered by how many `cuts` lie at or below its centroid's x;
// each piece numbers its nodes in order of first use and keeps their global ids.
template <int Dim>
std::vector<mesh::SimplexMesh<Dim>> split(const mesh::SimplexMesh<Dim>& m, const std::vector<double>& cuts) {
  std::vector<mesh::SimplexMesh<Dim>> pieces(cuts.size() + 1);
  std::vector<std::map<LocalId, LocalId>> local(pieces.size());
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    double x = 0;
    for (int k = 0; k <= Dim; ++k) x += m.point(m.cell(c)[k])[0] / (Dim + 1);
    const auto p = static_cast<std::size_t>(std::count_if(cuts.begin(), cuts.end(), [&](double cut) { return cut <= x; }));
    std::array<LocalId, Dim + 1> t;
    for (int k = 0; k <= Dim; ++k) {
      const LocalId n = m.cell(c)[k];
      const auto found = local[p].find(n);
      if (found != local[p].end()) {
        t[k] = found->second;
      } else {
        t[k] = add_node(pieces[p], m.point(n));
        pieces[p].node_global_id.back() = m.node_global_id[std::size_t(n)];
        local[p][n] = t[k];
      }
    }
    add_cell<Dim>(pieces[p], t, m.cell_phase[c]);
  }
  return pieces;
}

// The pieces merged by global id, cells in piece order (what io::read_mesh makes of a .pvtu).
template <int Dim>
mesh::SimplexMesh<Dim> merged(const std::vector<mesh::SimplexMesh<Dim>>& pieces) {
  mesh::SimplexMesh<Dim> m;
  std::map<GlobalId, LocalId> by_id;
  for (const mesh::SimplexMesh<Dim>& p : pieces) {
    std::vector<LocalId> id(p.node_count());
    for (std::size_t n = 0; n < p.node_count(); ++n) {
      const auto [it, added] = by_id.emplace(p.node_global_id[n], LocalId(m.node_count()));
      if (added) {
        add_node(m, p.point(LocalId(n)));
        m.node_global_id.back() = p.node_global_id[n];
      }
      id[n] = it->second;
    }
    for (std::size_t c = 0; c < p.cell_count(); ++c) {
      std::array<LocalId, Dim + 1> t;
      for (int k = 0; k <= Dim; ++k) t[k] = id[std::size_t(p.cell(c)[k])];
      add_cell<Dim>(m, t, p.cell_phase[c]);
    }
  }
  return m;
}

template <int Dim>
Certificate by_pieces(const std::vector<mesh::SimplexMesh<Dim>>& pieces, const geometry::Oracle<Dim>* oracle) {
  PiecewiseCertifier<Dim> certifier(CertifyOptions{}, oracle);
  for (const mesh::SimplexMesh<Dim>& p : pieces) {
    std::vector<double> coords3;
    for (std::size_t n = 0; n < p.node_count(); ++n)
      for (int d = 0; d < 3; ++d) coords3.push_back(d < Dim ? p.coords[Dim * n + d] : 0.0);
    certifier.count_nodes(p.node_global_id, coords3);
  }
  EXPECT_TRUE(certifier.ids_usable());
  for (std::size_t k = 0; k < pieces.size(); ++k) certifier.add_piece(pieces[k], "piece" + std::to_string(k));
  return certifier.finish();
}

// As cisamr certify checks a merged mesh: without a scene, its bounding box and voids allowed.
template <int Dim>
Certificate whole(const mesh::SimplexMesh<Dim>& m, const geometry::Oracle<Dim>* oracle) {
  if (oracle) return certify<Dim>(m, *oracle, CertifyOptions{});
  CertifyOptions o;
  o.allow_inner_boundary = true;
  return certify<Dim>(m, bounding_box(m), o);
}

void expect_same(const Certificate& a, const Certificate& b) {
  EXPECT_EQ(a.passed(), b.passed());
  EXPECT_EQ(a.node_count, b.node_count);
  EXPECT_EQ(a.cell_count, b.cell_count);
  EXPECT_EQ(a.cells_per_phase, b.cells_per_phase);
  EXPECT_EQ(a.aspect.max, b.aspect.max);
  EXPECT_EQ(a.aspect.above_bound, b.aspect.above_bound);
  EXPECT_EQ(a.aspect.histogram, b.aspect.histogram);
  EXPECT_NEAR(a.aspect.mean, b.aspect.mean, 1e-12);
  ASSERT_EQ(a.aspect.worst.size(), b.aspect.worst.size());
  for (std::size_t i = 0; i < a.aspect.worst.size(); ++i) {
    EXPECT_EQ(a.aspect.worst[i].cell, b.aspect.worst[i].cell);
    EXPECT_EQ(a.aspect.worst[i].aspect_ratio, b.aspect.worst[i].aspect_ratio);
  }
  const ConformityReport &x = a.conformity, &y = b.conformity;
  EXPECT_EQ(x.ok, y.ok);
  EXPECT_EQ(x.duplicate_nodes, y.duplicate_nodes);
  EXPECT_EQ(x.degenerate_cells, y.degenerate_cells);
  EXPECT_EQ(x.inverted_cells, y.inverted_cells);
  EXPECT_EQ(x.non_manifold_facets, y.non_manifold_facets);
  EXPECT_EQ(x.mismatched_orientation_facets, y.mismatched_orientation_facets);
  EXPECT_EQ(x.open_facets_inside, y.open_facets_inside);
  EXPECT_EQ(x.inner_boundary_facets, y.inner_boundary_facets);
  EXPECT_EQ(x.boundary_facets, y.boundary_facets);
  EXPECT_EQ(x.hanging_nodes, y.hanging_nodes);
  EXPECT_EQ(x.unused_nodes, y.unused_nodes);
  EXPECT_NEAR(x.measure, y.measure, 1e-12 * y.measure);
  EXPECT_EQ(x.examples.empty(), y.examples.empty());
  ASSERT_EQ(a.fidelity.has_value(), b.fidelity.has_value());
  if (!a.fidelity) return;
  const FidelityReport &f = *a.fidelity, &g = *b.fidelity;
  EXPECT_EQ(f.ok, g.ok);
  EXPECT_EQ(f.nodes_off_phase, g.nodes_off_phase);
  EXPECT_EQ(f.interface_nodes_off_interface, g.interface_nodes_off_interface);
  EXPECT_EQ(f.boundary_nodes_off_void, g.boundary_nodes_off_void);
  EXPECT_EQ(f.cells_unknown_phase, g.cells_unknown_phase);
  EXPECT_EQ(f.cells_off_phase, g.cells_off_phase);
  EXPECT_EQ(f.cells_wrong_phase, g.cells_wrong_phase);
  EXPECT_EQ(f.max_deviation, g.max_deviation);
  ASSERT_EQ(f.phase_measure.size(), g.phase_measure.size());
  for (std::size_t k = 0; k < f.phase_measure.size(); ++k) EXPECT_NEAR(f.phase_measure[k], g.phase_measure[k], 1e-12);
}

template <int Dim>
void expect_as_merged(const std::vector<mesh::SimplexMesh<Dim>>& pieces, const geometry::Oracle<Dim>* oracle = nullptr) {
  expect_same(by_pieces<Dim>(pieces, oracle), whole<Dim>(merged<Dim>(pieces), oracle));
}

TEST(Pieces, CleanMeshesGiveTheMergedMeshCertificate) {
  const auto tets = split<3>(structured_tets(5, 4, 3), {1.5, 3});
  const Certificate c = by_pieces<3>(tets, nullptr);
  EXPECT_TRUE(c.passed());
  EXPECT_EQ(c.cell_count, 5u * 4 * 3 * 5);
  EXPECT_EQ(c.node_count, 6u * 5 * 4);
  EXPECT_TRUE(std::any_of(c.notes.begin(), c.notes.end(),
                          [](const std::string& n) { return n.find("3 pieces") != std::string::npos; }));
  expect_as_merged<3>(tets);
  expect_as_merged<2>(split<2>(structured_triangles(6, 5), {1, 2.5, 4}));
}

TEST(Pieces, AHoleAcrossTheCutIsAnInnerBoundaryAsInTheMergedMesh) {
  mesh::Mesh2 m = structured_triangles(6, 5);
  for (std::size_t c = m.cell_count(); c-- > 0;) {
    const Vec2 g = centroid(m, c);
    if (g[0] > 2 && g[0] < 4 && g[1] > 2 && g[1] < 3) remove_cell<2>(m, c);
  }
  const auto pieces = split<2>(m, {3});
  const Certificate c = by_pieces<2>(pieces, nullptr);
  EXPECT_EQ(c.conformity.inner_boundary_facets, 6u);
  EXPECT_TRUE(c.passed());
  expect_as_merged<2>(pieces);
}

TEST(Pieces, ACellInTwoPiecesIsNonManifold) {
  auto pieces = split<3>(structured_tets(6, 2, 2), {3});
  // A cell of piece 0 away from the cut, copied with its nodes (same ids) into piece 1.
  const mesh::Mesh3& from = pieces[0];
  mesh::Mesh3& to = pieces[1];
  std::array<LocalId, 4> t;
  for (int k = 0; k < 4; ++k) {
    const LocalId n = from.cell(0)[k];
    t[k] = add_node(to, from.point(n));
    to.node_global_id.back() = from.node_global_id[std::size_t(n)];
  }
  add_cell<3>(to, t);
  const Certificate c = by_pieces<3>(pieces, nullptr);
  EXPECT_FALSE(c.passed());
  EXPECT_GT(c.conformity.non_manifold_facets, 0u);
  expect_as_merged<3>(pieces);
}

TEST(Pieces, AnInterfaceNodeUnderTwoIdsIsADuplicateAndOpensTheCut) {
  auto pieces = split<3>(structured_tets(4, 3, 3), {2});
  mesh::Mesh3& p = pieces[1];
  for (std::size_t n = 0; n < p.node_count(); ++n)
    if (p.point(LocalId(n)) == Vec3{2, 1, 1}) p.node_global_id[n] = 1000;
  const Certificate c = by_pieces<3>(pieces, nullptr);
  EXPECT_FALSE(c.passed());
  EXPECT_EQ(c.conformity.duplicate_nodes, 1u);
  EXPECT_GT(c.conformity.inner_boundary_facets, 0u);
  expect_as_merged<3>(pieces);
}

TEST(Pieces, AHangingNodeOnTheCutIsFound) {
  // Piece 0: [0,2]² of unit squares; piece 1: [2,3]×[0,2] of half squares. The fine piece's
  // nodes (2, 0.5) and (2, 1.5) lie inside the coarse piece's edges on x = 2.
  mesh::Mesh2 coarse = structured_triangles(2, 2);
  mesh::Mesh2 fine = structured_triangles(2, 4, 0.5, {2, 0});
  for (std::size_t n = 0; n < fine.node_count(); ++n) {
    const Vec2 p = fine.point(LocalId(n));
    fine.node_global_id[n] = p[0] == 2 && p[1] == std::floor(p[1]) ? GlobalId(3 * p[1] + 2) : GlobalId(100 + n);
  }
  const std::vector<mesh::Mesh2> pieces = {coarse, fine};
  const Certificate c = by_pieces<2>(pieces, nullptr);
  EXPECT_FALSE(c.passed());
  EXPECT_EQ(c.conformity.hanging_nodes, 2u);
  expect_as_merged<2>(pieces);
}

TEST(Pieces, OneIdAtTwoPlacesIsAnInputErrorNamingThePiece) {
  auto pieces = split<2>(structured_triangles(4, 2), {2});
  for (std::size_t n = 0; n < pieces[1].node_count(); ++n)
    if (pieces[1].point(LocalId(n)) == Vec2{2, 1}) pieces[1].coords[2 * n + 1] = 1.25;
  try {
    by_pieces<2>(pieces, nullptr);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("piece1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("global_id"), std::string::npos) << e.what();
  }
}

TEST(Pieces, NegativeOrSparseIdsAskForTheWholeMesh) {
  const std::vector<double> coords = {0, 0, 0, 1, 0, 0};
  PiecewiseCertifier<2> sparse(CertifyOptions{}, nullptr);
  sparse.count_nodes(std::vector<GlobalId>{0, GlobalId(1) << 40}, coords);
  EXPECT_FALSE(sparse.ids_usable());
  PiecewiseCertifier<2> negative(CertifyOptions{}, nullptr);
  negative.count_nodes(std::vector<GlobalId>{-1, 0}, coords);
  EXPECT_FALSE(negative.ids_usable());
  PiecewiseCertifier<2> dense(CertifyOptions{}, nullptr);
  dense.count_nodes(std::vector<GlobalId>{5, 0}, coords);
  EXPECT_TRUE(dense.ids_usable());
}

TEST(Pieces, FidelityAgainstASceneAsInTheMergedMesh) {
  const geometry::Oracle2 square(square_scene(false));
  auto pieces = split<2>(square_mesh(), {0.25, 0.5});
  const Certificate c = by_pieces<2>(pieces, &square);
  EXPECT_TRUE(c.passed());
  expect_as_merged<2>(pieces, &square);
  // The node (0.25, 0.5) serves phase 1 in piece 0 and phase 2 in piece 1: an interface node,
  // which moved off the interface fails as one (its phases are known only across pieces).
  for (mesh::Mesh2& p : pieces)
    for (std::size_t n = 0; n < p.node_count(); ++n)
      if (p.point(LocalId(n)) == Vec2{0.25, 0.5}) p.coords[2 * n] = 0.24;
  const Certificate moved = by_pieces<2>(pieces, &square);
  ASSERT_TRUE(moved.fidelity);
  EXPECT_EQ(moved.fidelity->interface_nodes_off_interface, 1u);
  EXPECT_EQ(moved.fidelity->nodes_off_phase, 0u);
  expect_as_merged<2>(pieces, &square);

  const geometry::Oracle3 cube(cube_scene(false));
  const auto tets = split<3>(cube_mesh(), {2, 4});
  EXPECT_TRUE(by_pieces<3>(tets, &cube).passed());
  expect_as_merged<3>(tets, &cube);
  const geometry::Oracle3 pore(cube_scene(true));
  const auto porous = split<3>(cube_mesh(), {3});
  std::vector<mesh::Mesh3> matrix_only;
  for (const mesh::Mesh3& p : porous)
    matrix_only.push_back(filtered<3>(p, [&](std::size_t c) { return p.cell_phase[c] == 1; }));
  const Certificate voids = by_pieces<3>(matrix_only, &pore);
  EXPECT_TRUE(voids.passed());
  EXPECT_GT(voids.conformity.inner_boundary_facets, 0u);
  expect_as_merged<3>(matrix_only, &pore);
}

}  // namespace
}  // namespace cisamr::quality
