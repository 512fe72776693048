// Boundary sets (mesh/boundary.hpp) on meshes from the mesher, checked against the geometry
// and the facet topology independently of the classification itself:
//  - every open facet (used by one cell, found here by hashing node sets) that lies on a
//    box plane (all nodes within 1e-9 of the domain's size of it) is in that face's set,
//    and every facet of a face set is open and on that plane: nothing else;
//  - exactness: a node within that distance of a face plane carries the face's bit, so no
//    boundary node drifted off its face by a rounding;
//  - on faces no void touches, the face facets tile the face (areas sum to its area);
//  - with no inclusion near the boundary the counts equal the structured grid's;
//  - CORNER0 is the node at the min corner, absent when a void covers the corner.
#include "mesh/boundary.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "driver/driver.hpp"
#include "geometry/oracle.hpp"
#include "mesh/metrics.hpp"
#include "pipeline/pipeline.hpp"
#include "support/random_scenes.hpp"

namespace cisamr::mesh {
namespace {

template <int Dim>
using FacetKey = std::array<LocalId, Dim>;

template <int Dim>
FacetKey<Dim> sorted_facet(const SimplexMesh<Dim>& m, std::size_t cell, int opposite) {
  FacetKey<Dim> key;
  int k = 0;
  for (int v = 0; v <= Dim; ++v)
    if (v != opposite) key[k++] = m.cell(cell)[v];
  std::sort(key.begin(), key.end());
  return key;
}

// (Dim-1)-measure of a facet: edge length or triangle area.
template <int Dim>
double facet_measure(const SimplexMesh<Dim>& m, const FacetKey<Dim>& f) {
  if constexpr (Dim == 2)
    return distance<2>(m.point(f[0]), m.point(f[1]));
  else
    return triangle_area_3d(m.point(f[0]), m.point(f[1]), m.point(f[2]));
}

template <int Dim>
Box<Dim> scene_box(const geometry::SceneDesc& s) {
  Box<Dim> b;
  for (int d = 0; d < Dim; ++d) b.min[d] = s.domain_min[d], b.max[d] = s.domain_max[d];
  return b;
}

// The face planes a point lies on, within tol (bit f as in BoundarySets::node_faces).
template <int Dim>
unsigned near_faces(const Vec<Dim>& p, const Box<Dim>& box, double tol) {
  unsigned bits = 0;
  for (int d = 0; d < Dim; ++d) {
    if (std::abs(p[d] - box.min[d]) <= tol) bits |= 1u << (2 * d);
    if (std::abs(p[d] - box.max[d]) <= tol) bits |= 1u << (2 * d + 1);
  }
  return bits;
}

struct Checked {
  std::array<std::size_t, 6> facets{}, nodes{};
  bool corner0 = false;
};

template <int Dim>
void check_sets(const geometry::SceneDesc& scene, const SimplexMesh<Dim>& m, const std::string& what, Checked& out) {
  const Box<Dim> faces = driver::face_box<Dim>(scene, {});
  const BoundarySets<Dim> sets = boundary_sets(m, faces);
  const Box<Dim> box = scene_box<Dim>(scene);
  double size = 0;
  for (int d = 0; d < Dim; ++d) size = std::max(size, box.max[d] - box.min[d]);
  const double tol = 1e-9 * size;

  // Nodes: the exact bits are the near planes' bits.
  EXPECT_EQ(sets.node_faces.size(), m.node_count()) << what;
  for (std::size_t n = 0; n < m.node_count(); ++n) {
    const unsigned near = near_faces<Dim>(m.point(static_cast<LocalId>(n)), box, tol);
    ASSERT_EQ(sets.node_faces[n], near) << what << ": node " << n << " is near faces " << near
                                        << " but carries bits " << int(sets.node_faces[n]);
    for (int f = 0; f < 2 * Dim; ++f) out.nodes[f] += (near >> f) & 1;
  }

  // Facets: open facets by hashing, compared with the face sets.
  std::map<FacetKey<Dim>, int> uses;
  for (std::size_t c = 0; c < m.cell_count(); ++c)
    for (int v = 0; v <= Dim; ++v) ++uses[sorted_facet(m, c, v)];
  std::map<FacetKey<Dim>, int> in_set;  // facet -> face
  for (int f = 0; f < 2 * Dim; ++f)
    for (const CellFacet& cf : sets.facets[f]) {
      const FacetKey<Dim> key = sorted_facet(m, static_cast<std::size_t>(cf.cell), cf.opposite);
      EXPECT_TRUE(in_set.emplace(key, f).second) << what << ": a facet is listed twice";
      EXPECT_EQ(uses[key], 1) << what << ": a facet of face " << f << " is not a boundary facet";
    }
  std::array<double, 6> area{};
  for (const auto& [key, count] : uses) {
    if (count != 1) continue;
    unsigned on = 0xff;
    for (LocalId n : key) on &= near_faces<Dim>(m.point(n), box, tol);
    ASSERT_LE(std::popcount(on), 1) << what << ": a boundary facet on two faces";
    const auto it = in_set.find(key);
    if (on == 0) {
      EXPECT_EQ(it, in_set.end()) << what << ": a void-interface facet is in a face set";
      continue;
    }
    const int f = std::countr_zero(on);
    ASSERT_NE(it, in_set.end()) << what << ": a boundary facet on face " << f << " is in no face set";
    EXPECT_EQ(it->second, f) << what;
    ++out.facets[f];
    area[f] += facet_measure<Dim>(m, key);
  }
  for (int f = 0; f < 2 * Dim; ++f) EXPECT_EQ(out.facets[f], sets.facets[f].size()) << what << " face " << f;

  // Faces no void touches are tiled by their facets.
  bool voids = false;
  for (const auto& p : scene.phases) voids = voids || p.is_void;
  if (!voids)
    for (int f = 0; f < 2 * Dim; ++f) {
      double face_area = 1;
      for (int d = 0; d < Dim; ++d)
        if (d != f / 2) face_area *= box.max[d] - box.min[d];
      EXPECT_NEAR(area[f], face_area, 1e-12 * face_area) << what << " face " << f;
    }

  // CORNER0: the node at the min corner.
  out.corner0 = sets.corner0 >= 0;
  if (out.corner0) {
    for (int d = 0; d < Dim; ++d) EXPECT_EQ(m.coords[static_cast<std::size_t>(sets.corner0) * Dim + d], faces.min[d]) << what;
  }
  if (!voids) {
    EXPECT_TRUE(out.corner0) << what;
  }
}

template <int Dim>
Checked checked(const geometry::SceneDesc& scene, const SimplexMesh<Dim>& m, const std::string& what) {
  Checked out;
  check_sets<Dim>(scene, m, what, out);
  return out;
}

// A domain written in decimals, as a scene file gives it, whose max faces the lattice puts
// elsewhere in the last bits: min + N·h is 1.1e-16, not 0, for y (-0.7 + 7·0.1).
geometry::SceneDesc awkward_box(int dimension, std::array<int, 3> cells) {
  geometry::SceneDesc s;
  s.source = "boundary-sets";
  s.dimension = dimension;
  s.h = 0.1;
  s.domain_min = {0.1, -0.7, 0.3};
  for (int d = 0; d < 3; ++d) s.domain_max[d] = std::round((s.domain_min[d] + cells[d] * s.h) * 1e10) / 1e10;
  s.phases = {{1, "matrix", false}, {2, "particle", false}, {3, "pore", true}};
  return s;
}

TEST(BoundarySets, AwkwardBoxHasExactFaceCoordinates) {
  // The nodes on the max y face are at -0.7 + 7·0.1 = 1.1e-16, not at domain.max = 0: the
  // face box is the lattice's.
  geometry::SceneDesc s = awkward_box(3, {3, 7, 9});
  const Box<3> faces = driver::face_box<3>(s, {});
  for (int d = 0; d < 3; ++d) EXPECT_EQ(faces.min[d], s.domain_min[d]);
  EXPECT_EQ(s.domain_max[1], 0.0);
  EXPECT_NE(faces.max[1], 0.0);
  s.inclusions.push_back({geometry::Sphere{{0.25, -0.35, 0.75}, 0.1}, 2, 0});
  const pipeline::Result<3> r = pipeline::mesh(geometry::Oracle3(s));
  const BoundarySets<3> sets = boundary_sets(r.mesh, faces);
  EXPECT_EQ(sets.facets[3].size(), 2u * 3 * 9);
  EXPECT_TRUE(boundary_sets(r.mesh, scene_box<3>(s)).facets[3].empty());
}

TEST(BoundarySets, CountsEqualTheStructuredGridsWithoutInclusionsAtTheBoundary2d) {
  geometry::SceneDesc s = awkward_box(2, {12, 9, 0});
  s.levels = 1;
  s.inclusions.push_back({geometry::Circle{{0.7, -0.25}, 0.17}, 2, 2});
  const pipeline::Result<2> r = pipeline::mesh(geometry::Oracle2(s));
  const Checked c = checked<2>(s, r.mesh, "2D grid");
  // The coarse grid along the faces (refinement stays near the circle): 12 x 9 squares.
  EXPECT_EQ(c.facets, (std::array<std::size_t, 6>{9, 9, 12, 12, 0, 0}));
  EXPECT_EQ(c.nodes, (std::array<std::size_t, 6>{10, 10, 13, 13, 0, 0}));
  EXPECT_TRUE(c.corner0);
}

TEST(BoundarySets, CountsEqualTheStructuredGridsWithoutInclusionsAtTheBoundary3d) {
  geometry::SceneDesc s = awkward_box(3, {8, 7, 6});
  s.inclusions.push_back({geometry::Sphere{{0.5, -0.35, 0.6}, 0.12}, 2, 1});
  const pipeline::Result<3> r = pipeline::mesh(geometry::Oracle3(s));
  const Checked c = checked<3>(s, r.mesh, "3D grid");
  // 5-tet cubes: two triangles per cube face, (n+1)(m+1) nodes.
  EXPECT_EQ(c.facets, (std::array<std::size_t, 6>{2 * 7 * 6, 2 * 7 * 6, 2 * 8 * 6, 2 * 8 * 6, 2 * 8 * 7, 2 * 8 * 7}));
  EXPECT_EQ(c.nodes, (std::array<std::size_t, 6>{8 * 7, 8 * 7, 9 * 7, 9 * 7, 9 * 8, 9 * 8}));
}

TEST(BoundarySets, RandomScenes2d) {
  for (unsigned seed = 0; seed < 60; ++seed) {
    const geometry::SceneDesc s = testing::RandomScene2(seed).make();
    const pipeline::Result<2> r = pipeline::mesh(geometry::Oracle2(s));
    checked<2>(s, r.mesh, "2D seed " + std::to_string(seed));
    if (HasFatalFailure()) return;
  }
}

// Spheres, ellipsoids and fibres, many crossing faces, edges and corners; a void in some.
geometry::SceneDesc random_scene3(unsigned seed) {
  std::mt19937_64 rng(seed);
  const auto uniform = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  geometry::SceneDesc s = awkward_box(3, {6 + int(seed % 3), 5, 4 + int(seed % 2)});
  s.levels = int(seed % 2);
  if (seed % 3 != 0) s.phases.pop_back();  // the void phase in a third of the scenes
  const int count = 3 + int(seed % 4);
  for (int i = 0; i < count; ++i) {
    const Vec3 c{uniform(s.domain_min[0] - 0.05, s.domain_max[0] + 0.05),
                           uniform(s.domain_min[1] - 0.05, s.domain_max[1] + 0.05),
                           uniform(s.domain_min[2] - 0.05, s.domain_max[2] + 0.05)};
    const int phase = (seed % 3 == 0 && i == 0) ? 3 : 2;
    if (i % 3 == 2)
      s.inclusions.push_back({geometry::Cylinder{{s.domain_min[0] - 0.1, c[1], c[2]}, {s.domain_max[0] + 0.1, c[1] + 0.05, c[2]}, 0.06}, phase, s.levels});
    else if (i % 3 == 1)
      s.inclusions.push_back({geometry::Ellipsoid{c, {0.14, 0.08, 0.07}}, phase, s.levels});
    else
      s.inclusions.push_back({geometry::Sphere{c, uniform(0.06, 0.15)}, phase, s.levels});
  }
  return s;
}

TEST(BoundarySets, RandomScenes3d) {
  int meshed = 0;
  for (unsigned seed = 0; seed < 24; ++seed) {
    const geometry::SceneDesc s = random_scene3(seed);
    pipeline::Result<3> r;
    try {
      r = pipeline::mesh(geometry::Oracle3(s));
    } catch (const InputError&) {
      continue;  // overlapping inclusions of different phases: not a scene
    }
    checked<3>(s, r.mesh, "3D seed " + std::to_string(seed));
    if (HasFatalFailure()) return;
    ++meshed;
  }
  EXPECT_GE(meshed, 16);
}

TEST(BoundarySets, NoCorner0WhenAVoidCoversTheCorner) {
  geometry::SceneDesc s = awkward_box(2, {8, 8, 0});
  s.inclusions.push_back({geometry::Circle{{0.1, -0.7}, 0.25}, 3, 0});
  const pipeline::Result<2> r = pipeline::mesh(geometry::Oracle2(s));
  EXPECT_FALSE(checked<2>(s, r.mesh, "void at the corner").corner0);
}

}  // namespace
}  // namespace cisamr::mesh
