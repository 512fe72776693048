// The machinery shared by 2D NURBS curves, STL meshes and 3D NURBS bodies: Bézier
// extraction (against de Boor's evaluation, clamped and unclamped knots), de Casteljau
// splits, the flat BVH (against brute force) and stl::build_indexed (against stl::build).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "geometry/flat_bvh.hpp"
#include "geometry/nurbs_bezier.hpp"
#include "geometry/stl_mesh.hpp"

using namespace cisamr;
using namespace cisamr::geometry;

namespace {

// Homogeneous point of a B-spline at u by de Boor's algorithm (U_p ≤ u ≤ U_n).
template <int C>
std::array<double, C> de_boor(int p, const std::vector<double>& U, const std::vector<std::array<double, C>>& P,
                              double u) {
  const int n = static_cast<int>(P.size());
  int k = p;  // the last non-empty span starting at or before u
  for (int j = p; j < n; ++j)
    if (U[j] <= u && U[j] < U[j + 1]) k = j;
  std::vector<std::array<double, C>> d(P.begin() + (k - p), P.begin() + k + 1);
  for (int r = 1; r <= p; ++r)
    for (int j = p; j >= r; --j) {
      const int i = j + k - p;
      const double alpha = (u - U[i]) / (U[i + p - r + 1] - U[i]);
      for (int c = 0; c < C; ++c) d[j][c] = (1 - alpha) * d[j - 1][c] + alpha * d[j][c];
    }
  return d[p];
}

// Random non-decreasing knots, interior values repeated at most p times (a continuous
// spline); clamped or not.
std::vector<double> random_knots(std::mt19937_64& rng, int p, int n, bool clamped) {
  std::uniform_real_distribution<double> U(0.1, 1.0);
  std::vector<double> k;
  double x = -U(rng);
  int mult = 0;
  for (int i = 0; i < n + p + 1; ++i) {
    const bool end = clamped && (i <= p || i > n);
    const bool hold = !k.empty() && (end || (mult < p && U(rng) < 0.3));
    if (!hold) x += U(rng), mult = 0;
    ++mult;
    k.push_back(x);
  }
  return k;
}

}  // namespace

TEST(NurbsBezier, ExtractionMatchesDeBoorForAnyDegreeClampedOrNot) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 400; ++trial) {
    const int p = 1 + trial % 6;
    const int n = p + 1 + static_cast<int>(rng() % 7);
    const bool clamped = trial % 2 == 0;
    const std::vector<double> knots = random_knots(rng, p, n, clamped);
    std::vector<std::array<double, 4>> P(n);
    for (auto& q : P) {
      const double w = 0.5 + 0.5 * (U(rng) + 1);
      q = {w * U(rng), w * U(rng), w * U(rng), w};
    }
    const auto pieces = nurbs::extract_bezier<4>(p, knots, P);
    ASSERT_EQ(pieces.points.size(), pieces.spans.size());
    // Every non-empty span of [U_p, U_n] gives one piece, in order.
    double covered = knots[p];
    for (std::size_t k = 0; k < pieces.points.size(); ++k) {
      const auto [u0, u1] = pieces.spans[k];
      EXPECT_EQ(u0, covered);
      covered = u1;
      for (double s : {0.0, 0.17, 0.5, 0.83, 1.0}) {
        double H[4], D[4];
        nurbs::eval_hom<4>(pieces.points[k].data(), p, s, H, D);
        const auto ref = de_boor<4>(p, knots, P, u0 + s * (u1 - u0));
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(H[c], ref[c], 1e-12) << "trial " << trial << " piece " << k;
      }
    }
    EXPECT_EQ(covered, knots[n]);
  }
}

TEST(NurbsBezier, SplitsAgreeWithEvaluation) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int p = 1; p <= 8; ++p) {
    std::vector<double> h(3 * (p + 1));
    for (int i = 0; i <= p; ++i) {
      const double w = 1.5 + 0.5 * U(rng);
      h[3 * i] = w * U(rng), h[3 * i + 1] = w * U(rng), h[3 * i + 2] = w;
    }
    std::vector<double> left(h.size()), right(h.size()), l2(h.size()), r2(h.size());
    nurbs::split_half<3>(h.data(), p, left.data(), right.data());
    nurbs::split_at<3>(h.data(), p, 0.5, l2.data(), r2.data());
    EXPECT_EQ(left, l2);
    EXPECT_EQ(right, r2);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(left[3 * p + c], right[c]);  // the shared middle point
    const double s = 0.3;
    nurbs::split_at<3>(h.data(), p, s, left.data(), right.data());
    for (double x : {0.0, 0.4, 1.0}) {
      double H[3], D[3], HL[3], DL[3], HR[3], DR[3];
      nurbs::eval_hom<3>(h.data(), p, s * x, H, D);
      nurbs::eval_hom<3>(left.data(), p, x, HL, DL);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(HL[c], H[c], 1e-14);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(DL[c], s * D[c], 1e-13);
      nurbs::eval_hom<3>(h.data(), p, s + (1 - s) * x, H, D);
      nurbs::eval_hom<3>(right.data(), p, x, HR, DR);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(HR[c], H[c], 1e-14);
    }
  }
}

TEST(FlatBvh, TraversalFindsExactlyTheOverlappingBoxes) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> U(0, 1);
  std::vector<Box3> boxes(1000);
  for (auto& b : boxes)
    for (int k = 0; k < 3; ++k) {
      b.min[k] = U(rng);
      b.max[k] = b.min[k] + 0.05 * U(rng);
    }
  FlatBvh<3> bvh;
  bvh.build(boxes);
  for (int q = 0; q < 200; ++q) {
    Box3 query;
    for (int k = 0; k < 3; ++k) query.min[k] = U(rng), query.max[k] = query.min[k] + 0.1 * U(rng);
    std::vector<int> found, expected;
    bvh.traverse([&](const Box3& b) { return boxes_overlap(b, query); },
                 [&](std::int32_t i) {
                   if (boxes_overlap(boxes[i], query)) found.push_back(i);
                   return false;
                 });
    for (int i = 0; i < 1000; ++i)
      if (boxes_overlap(boxes[i], query)) expected.push_back(i);
    std::sort(found.begin(), found.end());
    EXPECT_EQ(found, expected);
  }
  FlatBvh<2> empty;
  empty.build({});
  EXPECT_TRUE(empty.empty());
}

namespace {
// A regular octahedron around (0.5, 0.5, 0.5), outward faces.
void octahedron(std::vector<Vec3>& v, std::vector<std::array<std::int32_t, 3>>& f) {
  v = {{0.9, 0.5, 0.5}, {0.1, 0.5, 0.5}, {0.5, 0.9, 0.5}, {0.5, 0.1, 0.5}, {0.5, 0.5, 0.9}, {0.5, 0.5, 0.1}};
  f = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
}
}  // namespace

TEST(StlBuildIndexed, SameMeshAndAnswersAsFromTriangles) {
  std::vector<Vec3> v;
  std::vector<std::array<std::int32_t, 3>> f;
  octahedron(v, f);
  StlSurface s;
  for (const auto& t : f) s.triangles.push_back({v[t[0]], v[t[1]], v[t[2]]});
  stl::Mesh a, b;
  ASSERT_EQ(stl::build(s, a, true), "");
  ASSERT_EQ(stl::build_indexed(v, f, b, true), "");
  EXPECT_EQ(a.box.min, b.box.min);
  EXPECT_EQ(a.box.max, b.box.max);
  EXPECT_DOUBLE_EQ(stl::volume(b), stl::volume(a));
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> U(0, 1);
  for (int q = 0; q < 500; ++q) {
    const Vec3 p{U(rng), U(rng), U(rng)}, e{U(rng), U(rng), U(rng)};
    EXPECT_EQ(stl::side(a, p), stl::side(b, p));
    std::vector<double> ta, tb;
    stl::segment_hits(a, p, e, ta);
    stl::segment_hits(b, p, e, tb);
    std::sort(ta.begin(), ta.end());
    std::sort(tb.begin(), tb.end());
    EXPECT_EQ(ta, tb);
  }
  EXPECT_EQ(stl::side(b, {0.5, 0.5, 0.9}), 0);
}

TEST(StlBuildIndexed, ValidationNamesTheFace) {
  std::vector<Vec3> v;
  std::vector<std::array<std::int32_t, 3>> f;
  stl::Mesh m;
  octahedron(v, f);
  auto open = f;
  open.pop_back();
  EXPECT_EQ(stl::build_indexed(v, open, m, true), "surface is not closed (a boundary edge) (face 3)");
  auto flipped = f;
  std::swap(flipped[5][0], flipped[5][1]);
  EXPECT_EQ(stl::build_indexed(v, flipped, m, true), "inconsistently oriented neighbouring faces (face 5)");
  auto bad = f;
  bad[2][1] = 6;
  EXPECT_EQ(stl::build_indexed(v, bad, m, true), "vertex index out of range (face 2)");
  EXPECT_EQ(stl::build_indexed(v, {}, m, true), "no triangles");
  EXPECT_EQ(stl::build_indexed(v, open, m, false), "");  // without validation, never fails
}
