// NURBS curves in Oracle2: a rational quadratic circle must behave like the analytic one.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>

#include "core/error.hpp"
#include "geometry/oracle.hpp"

using namespace cisamr;
using namespace cisamr::geometry;

namespace {
SceneDesc base_scene() {
  SceneDesc s;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1, 1, 0};
  s.phases = {{1, "matrix", false}, {2, "fiber", false}};
  return s;
}
// The classic 9-point rational quadratic circle.
NurbsCurve nurbs_circle(Vec2 c, double r) {
  NurbsCurve n;
  n.degree = 2;
  n.knots = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};
  const double w = std::sqrt(0.5);
  const double pts[9][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
  for (int i = 0; i < 9; ++i) {
    n.control_points.push_back({c[0] + r * pts[i][0], c[1] + r * pts[i][1]});
    n.weights.push_back(i % 2 ? w : 1.0);
  }
  return n;
}
// Closed uniform cubic B-spline (unclamped knots, wrapped control points).
NurbsCurve periodic_blob(Vec2 c, double r) {
  NurbsCurve n;
  n.degree = 3;
  const int m = 8;
  for (int i = 0; i < m + 3; ++i) {
    const double a = 2 * M_PI * (i % m) / m;
    const double rr = r * (1 + 0.2 * std::cos(3 * a));
    n.control_points.push_back({c[0] + rr * std::cos(a), c[1] + rr * std::sin(a)});
  }
  for (int i = 0; i < m + 3 + 3 + 1; ++i) n.knots.push_back(i);
  return n;
}
std::vector<std::int32_t> all(const Oracle2& o) {
  std::vector<std::int32_t> v(o.inclusion_count());
  std::iota(v.begin(), v.end(), 0);
  return v;
}
}  // namespace

TEST(Oracle2Nurbs, RationalCircleClassifiesLikeTheCircle) {
  SceneDesc s = base_scene();
  s.inclusions = {{nurbs_circle({0.5, 0.5}, 0.3), 2, 0}};
  Oracle2 o(s);
  auto c = all(o);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 20000; ++i) {
    const Vec2 p{u(rng), u(rng)};
    const double d = std::hypot(p[0] - 0.5, p[1] - 0.5) - 0.3;
    if (std::abs(d) < 1e-10) continue;
    EXPECT_EQ(o.phase_at(p, c), d < 0 ? 1 : 0) << p[0] << " " << p[1];
  }
  // Points on the circle (control points at the quadrant ends) are ON.
  EXPECT_EQ(o.closure_phases({0.8, 0.5}, c), PhaseMask(3));
  EXPECT_EQ(o.closure_phases({0.5, 0.2}, c), PhaseMask(3));
  EXPECT_NEAR(o.distance_to_phase({0.5, 0.95}, 1), 0.15, 1e-12);
  EXPECT_NEAR(o.distance_to_phase({0.5, 0.45}, 0), 0.25, 1e-12);
  EXPECT_NEAR(o.phase_measures()[1], M_PI * 0.09, 1e-12);
}

TEST(Oracle2Nurbs, RationalCircleCrossesLikeTheCircle) {
  SceneDesc s = base_scene();
  s.inclusions = {{nurbs_circle({0.5, 0.5}, 0.3), 2, 0}};
  Oracle2 o(s);
  SceneDesc s2 = base_scene();
  s2.inclusions = {{Circle{{0.5, 0.5}, 0.3}, 2, 0}};
  Oracle2 ref(s2);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Crossing> a, b;
  int n = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec2 p{u(rng), u(rng)}, q{u(rng), u(rng)};
    o.crossings(p, q, all(o), a);
    ref.crossings(p, q, all(ref), b);
    ASSERT_EQ(a.size(), b.size()) << i;
    for (std::size_t k = 0; k < a.size(); ++k) {
      EXPECT_NEAR(a[k].t * std::hypot(q[0] - p[0], q[1] - p[1]), b[k].t * std::hypot(q[0] - p[0], q[1] - p[1]), 1e-10);
      EXPECT_EQ(a[k].from_phase, b[k].from_phase);
      EXPECT_EQ(a[k].to_phase, b[k].to_phase);
      ++n;
    }
  }
  EXPECT_GT(n, 1000);
  // A segment starting on the curve and leaving: no crossing at t ≈ 0.
  o.crossings({0.8, 0.5}, {1.0, 0.5}, all(o), a);
  EXPECT_TRUE(a.empty());
  o.crossings({0.8, 0.5}, {0.0, 0.5}, all(o), a);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_NEAR(a[0].t, 0.75, 1e-12);
}

TEST(Oracle2Nurbs, PeriodicCubicAreaAndClassification) {
  SceneDesc s = base_scene();
  s.inclusions = {{periodic_blob({0.5, 0.5}, 0.25), 2, 0}};
  Oracle2 o(s);
  EXPECT_EQ(o.phase_at({0.5, 0.5}, all(o)), 1);
  EXPECT_EQ(o.phase_at({0.02, 0.02}, all(o)), 0);
  const auto a = o.phase_measures();
  // Same blob shifted to straddle the domain edge: clipped areas integrate by lines.
  EXPECT_GT(a[1], 0.1);
  EXPECT_NEAR(a[0] + a[1], 1.0, 1e-12);
  SceneDesc s2 = base_scene();
  s2.inclusions = {{periodic_blob({0.5, 0.5}, 0.25), 2, 0}, {periodic_blob({0.5, 0.5}, 0.25), 2, 0}};
  Oracle2 o2(s2);  // two identical same-phase blobs: integrated, not analytic
  EXPECT_NEAR(o2.phase_measures()[1], a[1], 1e-11);
}

TEST(Oracle2Nurbs, ValidationErrors) {
  auto expect_error = [](NurbsCurve n, const std::string& field, const std::string& words) {
    SceneDesc s = base_scene();
    s.inclusions = {{n, 2, 0}};
    try {
      Oracle2 o(s);
      ADD_FAILURE() << "no error for " << field;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), field) << e.what();
      EXPECT_NE(e.problem().find(words), std::string::npos) << e.what();
    }
  };
  NurbsCurve n = nurbs_circle({0.5, 0.5}, 0.3);
  auto bad = n;
  bad.degree = 0;
  expect_error(bad, "inclusions[0].degree", "at least 1");
  bad = n;
  bad.knots.pop_back();
  expect_error(bad, "inclusions[0].knots", "expected 12");
  bad = n;
  std::swap(bad.knots[4], bad.knots[6]);
  expect_error(bad, "inclusions[0].knots", "non-decreasing");
  bad = n;
  bad.weights[3] = 0;
  expect_error(bad, "inclusions[0].weights", "positive");
  bad = n;
  bad.weights.pop_back();
  expect_error(bad, "inclusions[0].weights", "expected 9");
  bad = n;
  bad.control_points.back() = {0.75, 0.5};
  expect_error(bad, "inclusions[0].control_points", "not closed");
}
