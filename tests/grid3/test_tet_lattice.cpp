// Lattice keys, the 5-tet honeycomb and the nested-honeycomb refinement templates.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "core/error.hpp"
#include "exact_mesh3.hpp"
#include "grid/tet_lattice.hpp"

namespace cisamr::grid {
namespace {

std::int64_t sq_dist(const LatticePoint3& a, const LatticePoint3& b) {
  std::int64_t s = 0;
  for (int d = 0; d < 3; ++d) s += (a[d] - b[d]) * (a[d] - b[d]);
  return s;
}

TEST(LatticeKey3, RoundTripsAndOrdersLexicographically) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<std::int64_t> coord(0, kKey3MaxCoordinate);
  for (int i = 0; i < 1000; ++i) {
    const LatticePoint3 p{coord(rng), coord(rng), coord(rng)}, q{coord(rng), coord(rng), coord(rng)};
    EXPECT_EQ(key3_point(key3(p)), p);
    EXPECT_EQ(key3(p) < key3(q), p < q);  // numeric order = (X, Y, Z) order
    EXPECT_EQ(wide_key3(p[0], p[1], p[2]) < wide_key3(q[0], q[1], q[2]), p < q);
  }
  EXPECT_EQ(key3_point(key3(kKey3MaxCoordinate, 0, kKey3MaxCoordinate)),
            (LatticePoint3{kKey3MaxCoordinate, 0, kKey3MaxCoordinate}));
  EXPECT_EQ(midpoint_key3(key3(2, 4, 6), key3(4, 8, 0)), key3(3, 6, 3));
}

TEST(LatticeKey3, RefusesLatticesThatDoNotFit) {
  Lattice3 l;
  l.h = 1;
  l.max_level = 4;
  l.coarse_cells = {131071, 10, 10};  // 131071·16 = 2^21 − 16: fits
  EXPECT_TRUE(fits_key3(l));
  EXPECT_NO_THROW(require_key3(l));
  l.coarse_cells[1] = 131072;  // 2^21: one too many
  EXPECT_FALSE(fits_key3(l));
  try {
    require_key3(l);
    FAIL() << "expected MeshingError";
  } catch (const MeshingError& e) {
    EXPECT_NE(std::string(e.what()).find("131072"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("2^4"), std::string::npos) << e.what();
  }
}

// The five tets of a cube, for both parities.
TEST(Honeycomb, CubeSplitsIntoOneRegularAndFourCornerTets) {
  for (std::int64_t i0 : {0, 1, 7}) {
    const TetCode base{{i0, 3, 5}, 0};
    const int parity = cube_parity(base.cube);
    std::int64_t volume6 = 0;
    std::set<LatticePoint3> apexes;
    for (int local = 0; local < 5; ++local) {
      TetCode c = base;
      c.local = static_cast<std::uint8_t>(local);
      const auto v = tet_vertices(c);
      const std::int64_t o = tet::orient(v[0], v[1], v[2], v[3]);
      ASSERT_GT(o, 0);
      volume6 += o;
      for (const auto& p : v) {
        const int sum_parity = static_cast<int>((p[0] + p[1] + p[2]) & 1);
        // Regular tet: even corners; corner tet: odd apex, even legs.
        if (local == 0 || &p != &v[0]) EXPECT_EQ(sum_parity, 0);
        else EXPECT_EQ(sum_parity, 1);
      }
      if (local == 0) {
        for (int a = 0; a < 4; ++a)
          for (int b = a + 1; b < 4; ++b) EXPECT_EQ(sq_dist(v[a], v[b]), 2);
      } else {
        apexes.insert(v[0]);
        for (int a = 1; a < 4; ++a) EXPECT_EQ(sq_dist(v[0], v[a]), 1);
        for (int a = 1; a < 4; ++a)
          for (int b = a + 1; b < 4; ++b) EXPECT_EQ(sq_dist(v[a], v[b]), 2);
      }
    }
    EXPECT_EQ(volume6, 6) << "parity " << parity;
    EXPECT_EQ(apexes.size(), 4u);
  }
}

TEST(Honeycomb, BlockOfCubesIsConforming) {
  testing::ExactMesh3 m;
  for (std::int64_t k = 0; k < 3; ++k)
    for (std::int64_t j = 0; j < 3; ++j)
      for (std::int64_t i = 0; i < 4; ++i)
        for (int local = 0; local < 5; ++local) {
          const auto v = tet_vertices(TetCode{{i, j, k}, static_cast<std::uint8_t>(local)});
          m.add(v[0], v[1], v[2], v[3]);
        }
  const auto r = testing::check_conformity(m, {0, 0, 0}, {4, 3, 3});
  EXPECT_TRUE(r.ok(6 * 36)) << r.first_problem;
  EXPECT_EQ(r.boundary_faces, 2u * (12 + 12 + 9) * 2);  // two triangles per boundary square
}

TEST(Honeycomb, LocateFindsEachTetFromInteriorPoints) {
  std::mt19937_64 rng(3);
  for (std::int64_t i : {0, 1, -1, 6}) {
    for (int local = 0; local < 5; ++local) {
      const TetCode c{{i, 2, -3}, static_cast<std::uint8_t>(local)};
      EXPECT_EQ(locate(centroid4(c), 2), c);
      // Random interior points: positive barycentric weights summing to 64.
      const auto v = tet_vertices(c);
      for (int n = 0; n < 50; ++n) {
        std::array<std::int64_t, 4> w{};
        std::uniform_int_distribution<int> cut(1, 63);
        std::array<int, 3> cuts{cut(rng), cut(rng), cut(rng)};
        std::sort(cuts.begin(), cuts.end());
        w = {cuts[0], cuts[1] - cuts[0], cuts[2] - cuts[1], 64 - cuts[2]};
        if (std::find(w.begin(), w.end(), 0) != w.end()) continue;
        LatticePoint3 p{};
        for (int d = 0; d < 3; ++d)
          for (int a = 0; a < 4; ++a) p[d] += w[a] * v[a][d];
        EXPECT_EQ(locate(p, 6), c);
      }
    }
  }
}

TEST(Honeycomb, FaceNeighbourSharesTheFaceAndLiesOnTheOtherSide) {
  for (std::int64_t i : {0, 1}) {
    for (int local = 0; local < 5; ++local) {
      const TetCode c{{i, 4, 2}, static_cast<std::uint8_t>(local)};
      const auto v = tet_vertices(c);
      for (int f = 0; f < 4; ++f) {
        const TetCode n = face_neighbour(c, f);
        ASSERT_NE(n, c);
        const auto w = tet_vertices(n);
        int shared = 0;
        for (int a = 0; a < 4; ++a)
          if (a != f) shared += std::count(w.begin(), w.end(), v[a]) > 0 ? 1 : 0;
        EXPECT_EQ(shared, 3) << "tet " << local << " face " << f;
        // Across a right face of a corner tet: the corner tet with the same apex.
        if (local != 0 && f != 0) {
          EXPECT_EQ(w[0], v[0]);
        }
        // Across the hypotenuse face / a face of R: the other kind, same cube.
        if (local == 0 || f == 0) {
          EXPECT_EQ(n.cube, c.cube);
        }
        if (local == 0) {
          EXPECT_NE(n.local, 0);
        }
      }
    }
  }
}

// Children of every tet kind, both parities: volumes, orientation, shapes, and each child
// is the honeycomb tet of the next level named by its code.
TEST(Refinement, ChildrenAreTheNextLevelHoneycombTets) {
  for (std::int64_t i : {0, 1, 5}) {
    for (int local = 0; local < 5; ++local) {
      const TetCode parent{{i, 2, 3}, static_cast<std::uint8_t>(local)};
      const auto pv = tet_vertices(parent);
      const std::int64_t parent_volume6 = 8 * tet::orient(pv[0], pv[1], pv[2], pv[3]);  // at level l+1
      std::array<TetCode, 12> children{};
      const int n = children_codes(parent, children);
      EXPECT_EQ(n, local == 0 ? 12 : 7);
      // The template's own points, at level l+1.
      std::array<LatticePoint3, 11> p{};
      for (int a = 0; a < 4; ++a)
        for (int d = 0; d < 3; ++d) p[a][d] = 2 * pv[a][d];
      for (int e = 0; e < 6; ++e)
        for (int d = 0; d < 3; ++d) p[tet::midpoint(e)][d] = (p[tet::kEdges[e][0]][d] + p[tet::kEdges[e][1]][d]) / 2;
      for (int d = 0; d < 3; ++d) p[tet::kCentroid][d] = (p[0][d] + p[1][d] + p[2][d] + p[3][d]) / 4;
      std::int64_t sum = 0;
      int regular = 0;
      std::set<TetCode, bool (*)(const TetCode&, const TetCode&)> distinct(
          [](const TetCode& a, const TetCode& b) { return std::tie(a.cube, a.local) < std::tie(b.cube, b.local); });
      for (int c = 0; c < n; ++c) {
        const auto& t = local == 0 ? tet::kRegularChildren[c] : tet::kCornerChildren[c];
        const std::int64_t o = tet::orient(p[t[0]], p[t[1]], p[t[2]], p[t[3]]);
        EXPECT_GT(o, 0);
        sum += o;
        // Same vertex set as the honeycomb tet of the code, and the same orientation.
        const auto cv = tet_vertices(children[c]);
        std::set<LatticePoint3> a{p[t[0]], p[t[1]], p[t[2]], p[t[3]]}, b(cv.begin(), cv.end());
        EXPECT_EQ(a, b) << "parent local " << local << " child " << c;
        EXPECT_GT(tet::orient(cv[0], cv[1], cv[2], cv[3]), 0);
        if (children[c].local == 0) {
          ++regular;
          EXPECT_EQ(o, 2);  // regular tet of a unit cube: volume 1/3
        } else {
          EXPECT_EQ(o, 1);  // trirectangular, legs 1: volume 1/6
        }
        distinct.insert(children[c]);
      }
      EXPECT_EQ(sum, parent_volume6);
      EXPECT_EQ(regular, local == 0 ? 4 : 1);
      EXPECT_EQ(distinct.size(), static_cast<std::size_t>(n));
    }
  }
}

}  // namespace
}  // namespace cisamr::grid
