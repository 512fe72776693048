// Aspect ratio reference values, histogram, worst list, angles.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>

#include "mesh/metrics.hpp"
#include "mesh_builders.hpp"
#include "quality/quality.hpp"

namespace cisamr::quality {
namespace {
using namespace testing;

mesh::Mesh2 single_triangle(Vec2 a, Vec2 b, Vec2 c) {
  mesh::Mesh2 m;
  add_node(m, a[0], a[1]);
  add_node(m, b[0], b[1]);
  add_node(m, c[0], c[1]);
  add_cell<2>(m, {0, 1, 2}, 7);
  return m;
}
mesh::Mesh3 single_tet(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
  mesh::Mesh3 m;
  for (const Vec3& p : {a, b, c, d}) add_node(m, p[0], p[1], p[2]);
  add_cell<3>(m, {0, 1, 2, 3});
  return m;
}

// Independent form of the triangle aspect ratio: l_max · perimeter / (4√3 · area).
double triangle_ar(Vec2 a, Vec2 b, Vec2 c) {
  const double l0 = std::hypot(b[0] - a[0], b[1] - a[1]), l1 = std::hypot(c[0] - b[0], c[1] - b[1]),
               l2 = std::hypot(a[0] - c[0], a[1] - c[1]);
  const double area = 0.5 * std::abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
  return std::max({l0, l1, l2}) * (l0 + l1 + l2) / (4 * std::sqrt(3.0) * area);
}

std::size_t sum(const std::vector<std::size_t>& v) { return std::accumulate(v.begin(), v.end(), std::size_t(0)); }

TEST(AspectRatio, EquilateralTriangleIsOne) {
  const auto s = aspect_statistics<2>(single_triangle({0, 0}, {2, 0}, {1, std::sqrt(3.0)}), 3.0);
  EXPECT_NEAR(s.max, 1.0, 1e-12);
  EXPECT_NEAR(s.min_angle_deg, 60.0, 1e-9);
  EXPECT_NEAR(s.max_angle_deg, 60.0, 1e-9);
  EXPECT_EQ(s.histogram[0], 1u);  // [1.0, 1.1), round-off below 1 included
}

// l_max / (2√3 r_in) with l_max = √2, r_in = 1 / (2 + √2) gives (1 + √2)/√3 = 1.394.
// The 1.207 quoted in reference/cisamr-algorithm.md §7 is Verdict's *radius ratio*
// R / (2 r_in) = (√2/2)(2 + √2)/2 of this triangle, not its aspect ratio (see README.md).
TEST(AspectRatio, HalfSquareRightTriangle) {
  const auto s = aspect_statistics<2>(single_triangle({0, 0}, {1, 0}, {0, 1}), 3.0);
  EXPECT_NEAR(s.max, (1 + std::sqrt(2.0)) / std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(s.max, 1.394, 5e-4);
  EXPECT_NEAR(s.max, triangle_ar({0, 0}, {1, 0}, {0, 1}), 1e-12);
  const double radius_ratio = (std::sqrt(2.0) / 2) / (2 * (1 / (2 + std::sqrt(2.0))));
  EXPECT_NEAR(radius_ratio, 1.207, 5e-4);
  EXPECT_NEAR(s.min_angle_deg, 45.0, 1e-9);
  EXPECT_NEAR(s.max_angle_deg, 90.0, 1e-9);
  EXPECT_EQ(s.histogram[3], 1u);  // [1.3, 1.4)
}

TEST(AspectRatio, TrirectangularTet) {
  const auto s = aspect_statistics<3>(single_tet({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}), 5.0);
  EXPECT_NEAR(s.max, (1 + std::sqrt(3.0)) / 2, 1e-12);  // 1.366
  EXPECT_NEAR(s.max, 1.366, 5e-4);
  EXPECT_NEAR(s.min_angle_deg, std::acos(1 / std::sqrt(3.0)) * 180 / M_PI, 1e-9);  // 54.74°
  EXPECT_NEAR(s.max_angle_deg, 90.0, 1e-9);
}

TEST(AspectRatio, RegularTetIsOne) {
  const auto s = aspect_statistics<3>(single_tet({1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}), 5.0);
  EXPECT_NEAR(s.max, 1.0, 1e-12);
  const double dihedral = std::acos(1.0 / 3.0) * 180 / M_PI;  // 70.53°
  EXPECT_NEAR(s.min_angle_deg, dihedral, 1e-9);
  EXPECT_NEAR(s.max_angle_deg, dihedral, 1e-9);
}

TEST(AspectRatio, OrientationDoesNotMatter) {
  const auto a = aspect_statistics<2>(single_triangle({0, 0}, {3, 0}, {1, 1}), 3.0);
  const auto b = aspect_statistics<2>(single_triangle({0, 0}, {1, 1}, {3, 0}), 3.0);
  EXPECT_DOUBLE_EQ(a.max, b.max);
  EXPECT_NEAR(a.max, triangle_ar({0, 0}, {3, 0}, {1, 1}), 1e-12);
}

// 3×2 squares split into right triangles (AR 1.394), then one stretched triangle added
// on top whose aspect ratio we compute independently.
TEST(AspectStatistics, HistogramMaxAndWorstOnSmallMesh) {
  mesh::Mesh2 m = structured_triangles(3, 2);
  const LocalId far = add_node(m, 7.2, 1.5);
  add_cell<2>(m, {7, far, 11}, 2);  // nodes (3,1), (7.2,1.5), (3,2)
  const double stretched = triangle_ar({3, 1}, {7.2, 1.5}, {3, 2});
  ASSERT_GT(stretched, 2.5);
  ASSERT_LT(stretched, 3.0);

  const auto s = aspect_statistics<2>(m, 3.0, 4);
  EXPECT_EQ(s.count, 13u);
  EXPECT_NEAR(s.max, stretched, 1e-12);
  const double right = (1 + std::sqrt(2.0)) / std::sqrt(3.0);
  EXPECT_NEAR(s.mean, (12 * right + stretched) / 13, 1e-12);
  EXPECT_EQ(s.above_bound, 0u);
  // Edges 1.0, 1.1, ..., 3.1: 21 regular bins + overflow.
  ASSERT_EQ(s.bin_edges.size(), 22u);
  EXPECT_DOUBLE_EQ(s.bin_edges.front(), 1.0);
  EXPECT_DOUBLE_EQ(s.bin_edges[5], 1.5);
  EXPECT_GT(s.bin_edges.back(), 3.0);
  ASSERT_EQ(s.histogram.size(), s.bin_edges.size());
  EXPECT_EQ(sum(s.histogram), 13u);
  EXPECT_EQ(s.histogram[3], 12u);
  const auto bin = static_cast<std::size_t>((stretched - 1.0) * 10);
  EXPECT_EQ(s.histogram[bin], 1u);
  EXPECT_EQ(s.histogram.back(), 0u);  // overflow empty

  ASSERT_EQ(s.worst.size(), 4u);
  EXPECT_EQ(s.worst[0].cell, 12u);
  EXPECT_EQ(s.worst[0].phase, 2);
  EXPECT_NEAR(s.worst[0].centroid[0], 4.4, 1e-12);
  EXPECT_NEAR(s.worst[0].centroid[1], 1.5, 1e-12);
  EXPECT_EQ(s.worst[0].centroid[2], 0.0);
  for (int i = 1; i < 4; ++i) {
    EXPECT_NEAR(s.worst[i].aspect_ratio, right, 1e-12);
    EXPECT_LT(s.worst[i].cell, 12u);
  }

  const auto tight = aspect_statistics<2>(m, 2.5, 0);
  EXPECT_EQ(tight.above_bound, 1u);
  EXPECT_TRUE(tight.worst.empty());
  EXPECT_GT(tight.bin_edges.back(), stretched);
}

TEST(AspectStatistics, WorstTiesGoToSmallerCellIds) {
  mesh::Mesh2 m;
  for (int k = 0; k < 3; ++k) {  // the same triangle translated by integers: identical ARs
    const LocalId a = add_node(m, 4 * k, 0), b = add_node(m, 4 * k + 3, 0), c = add_node(m, 4 * k + 1, 1);
    add_cell<2>(m, {a, b, c});
  }
  const auto s = aspect_statistics<2>(m, 3.0, 2);
  ASSERT_EQ(s.worst.size(), 2u);
  EXPECT_EQ(s.worst[0].cell, 0u);
  EXPECT_EQ(s.worst[1].cell, 1u);
  EXPECT_EQ(s.worst[0].aspect_ratio, s.worst[1].aspect_ratio);
}

TEST(AspectStatistics, DegenerateAndHugeGoToOverflow) {
  mesh::Mesh2 m = structured_triangles(1, 1);
  const LocalId a = add_node(m, 0, 2), b = add_node(m, 1, 2), c = add_node(m, 2, 2);
  add_cell<2>(m, {a, b, c});                      // collinear: infinite AR
  const LocalId d = add_node(m, 0, 3), e = add_node(m, 1e3, 3), f = add_node(m, 500, 3.0 + 1e-3);
  add_cell<2>(m, {d, e, f});                      // AR ~ 1e8
  const auto s = aspect_statistics<2>(m, 3.0);
  EXPECT_TRUE(std::isinf(s.max));
  EXPECT_TRUE(std::isfinite(s.mean));
  EXPECT_EQ(s.above_bound, 2u);
  EXPECT_DOUBLE_EQ(s.bin_edges.back(), kHistogramMaxEdge);
  EXPECT_EQ(s.histogram.back(), 2u);
  EXPECT_EQ(sum(s.histogram), 4u);
  EXPECT_TRUE(std::isinf(s.worst[0].aspect_ratio));
  EXPECT_EQ(s.worst[0].cell, 2u);
  EXPECT_NEAR(s.min_angle_deg, 0.0, 1e-3);
  EXPECT_NEAR(s.max_angle_deg, 180.0, 1e-3);
}

TEST(AspectStatistics, EmptyMesh) {
  const auto s = aspect_statistics<3>(mesh::Mesh3{}, 5.0);
  EXPECT_EQ(s.count, 0u);
  EXPECT_EQ(s.max, 0.0);
  EXPECT_EQ(sum(s.histogram), 0u);
  EXPECT_GT(s.bin_edges.back(), 5.0);
}

TEST(AspectStatistics, StructuredTetMesh) {
  const auto s = aspect_statistics<3>(structured_tets(2, 2, 2), 5.0);
  EXPECT_EQ(s.count, 40u);
  // Corner tets are trirectangular (1.366), the central ones regular (1).
  EXPECT_NEAR(s.max, (1 + std::sqrt(3.0)) / 2, 1e-12);
  EXPECT_EQ(s.histogram[0], 8u);
  EXPECT_EQ(s.histogram[3], 32u);
  EXPECT_NEAR(s.max_angle_deg, 90.0, 1e-9);
}

// The statistics take each tet's aspect ratio from the face cross products they compute
// for the dihedral angles; it must equal mesh::aspect_ratio bit for bit (the report's
// maximum and worst cells are compared with certify's and with other tools).
TEST(AspectStatistics, RatiosEqualTheMetricBitForBit) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    std::array<Vec3, 4> p;
    for (Vec3& x : p)
      for (int d = 0; d < 3; ++d) x[d] = coordinate(rng);
    if (trial % 7 == 0) p[3] = {p[0][0], p[0][1], p[0][2]};  // degenerate: +inf on both sides
    const auto s = aspect_statistics<3>(single_tet(p[0], p[1], p[2], p[3]), 5.0, 1);
    const double expected = mesh::aspect_ratio(p[0], p[1], p[2], p[3]);
    ASSERT_EQ(s.max, expected) << "trial " << trial;
    ASSERT_EQ(s.worst.at(0).aspect_ratio, expected) << "trial " << trial;
  }
}

// The guard's test (radapt3) decides "positive and aspect ratio within the bound" first
// without square roots; its verdict must be the full test's, also for tets right at the
// bound (scaled so that their ratio is the bound up to round-off).
TEST(PositiveWithin, SameVerdictAsTheFullTest) {
  const auto full = [](const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double bound) {
    const auto sub = [](const Vec3& x, const Vec3& y) { return Vec3{x[0] - y[0], x[1] - y[1], x[2] - y[2]}; };
    const auto cross_norm = [](const Vec3& x, const Vec3& y) {
      const double p = x[1] * y[2] - x[2] * y[1], q = x[2] * y[0] - x[0] * y[2], r = x[0] * y[1] - x[1] * y[0];
      return std::sqrt(p * p + q * q + r * r);
    };
    const Vec3 u = sub(b, a), v = sub(c, a), w = sub(d, a), bc = sub(c, b), bd = sub(d, b), cd = sub(d, c);
    const double six_volume = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                              u[2] * (v[0] * w[1] - v[1] * w[0]);
    if (!(six_volume > 0)) return false;
    const double faces = 0.5 * (cross_norm(u, v) + cross_norm(u, w) + cross_norm(v, w) + cross_norm(bc, bd));
    const auto sq = [](const Vec3& x) { return x[0] * x[0] + x[1] * x[1] + x[2] * x[2]; };
    const double l2 = std::max({sq(u), sq(v), sq(w), sq(bc), sq(bd), sq(cd)});
    return std::sqrt(l2) * faces <= bound * (1 - 1e-9) * std::sqrt(6.0) * six_volume;
  };
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  int accepted = 0, refused = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    std::array<Vec3, 4> p;
    for (Vec3& x : p)
      for (int d = 0; d < 3; ++d) x[d] = coordinate(rng);
    const double ratio = mesh::aspect_ratio(p[0], p[1], p[2], p[3]);
    // Half the trials at the tet's own ratio as the bound (within round-off of it either
    // way), the others at fixed bounds.
    for (const double bound : {ratio * (1 + 1e-9 * (trial % 3 - 1)), 2.0, 5.0}) {
      const bool expected = full(p[0], p[1], p[2], p[3], bound);
      ASSERT_EQ(mesh::positive_within(p[0], p[1], p[2], p[3], bound), expected) << "trial " << trial;
      (expected ? accepted : refused) += 1;
    }
  }
  EXPECT_GT(accepted, 1000);
  EXPECT_GT(refused, 1000);
}

// The guard evaluates a split's sub-tets two at a time: each lane's verdict must be the
// scalar test's, bit for bit, also right at the bound (a tet's own ratio as the bound, up to
// round-off either way), for degenerate and negatively oriented tets, and whichever lane a
// tet is in.
TEST(PositiveWithin, PairsGiveEachTetsVerdict) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  int accepted = 0, refused = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    std::array<std::array<Vec3, 4>, 2> t;
    for (auto& p : t)
      for (Vec3& x : p)
        for (int d = 0; d < 3; ++d) x[d] = coordinate(rng);
    if (trial % 11 == 0) t[1][3] = t[1][0];  // degenerate
    const auto points = [](const std::array<Vec3, 4>& p) { return std::array<const Vec3*, 4>{&p[0], &p[1], &p[2], &p[3]}; };
    for (int near = 0; near < 2; ++near) {
      const auto& p = t[static_cast<std::size_t>(near)];
      const double ratio = mesh::aspect_ratio(p[0], p[1], p[2], p[3]);
      for (const double bound : {ratio * (1 + 1e-9 * (trial % 3 - 1)), 2.0, 5.0}) {
        const auto pair = mesh::positive_within_pair(points(t[0]), points(t[1]), bound);
        const auto swapped = mesh::positive_within_pair(points(t[1]), points(t[0]), bound);
        for (int k = 0; k < 2; ++k) {
          const auto& q = t[static_cast<std::size_t>(k)];
          const bool expected = mesh::positive_within(q[0], q[1], q[2], q[3], bound);
          ASSERT_EQ(pair[static_cast<std::size_t>(k)], expected) << "trial " << trial << ", lane " << k;
          ASSERT_EQ(swapped[static_cast<std::size_t>(1 - k)], expected) << "trial " << trial << ", lane " << 1 - k;
          (expected ? accepted : refused) += 1;
        }
      }
    }
  }
  EXPECT_GT(accepted, 10000);
  EXPECT_GT(refused, 10000);
}

}  // namespace
}  // namespace cisamr::quality
