// shapes.hpp free functions, and ellipses in Oracle2.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>

#include "geometry/oracle.hpp"
#include "geometry/shapes.hpp"

using namespace cisamr;
using namespace cisamr::geometry;

TEST(Shapes, MeasuresAndBoxes) {
  EXPECT_DOUBLE_EQ(shape_measure(Circle{{0, 0}, 2}), 4 * M_PI);
  EXPECT_DOUBLE_EQ(shape_measure(Ellipse{{0, 0}, {2, 1}, 0.3}), 2 * M_PI);
  EXPECT_DOUBLE_EQ(shape_measure(Polygon{{{0, 0}, {2, 0}, {2, 1}, {0, 1}}}), 2.0);
  EXPECT_NEAR(shape_boundary_measure(Ellipse{{0, 0}, {1, 1}, 0.3}), 2 * M_PI, 1e-12);
  EXPECT_NEAR(shape_boundary_measure(Ellipse{{0, 0}, {2, 1}, 0}), 9.688448220547675, 1e-12);
  EXPECT_NEAR(shape_measure(Ellipsoid{{0, 0, 0}, {3, 2, 1}}), 8 * M_PI, 1e-12);
  EXPECT_NEAR(shape_boundary_measure(Ellipsoid{{0, 0, 0}, {1, 1, 1}}), 4 * M_PI, 1e-9);
  EXPECT_NEAR(shape_boundary_measure(Ellipsoid{{0, 0, 0}, {3, 2, 1}}), 48.88214630, 1e-6);
  EXPECT_EQ(shape_dimension(Sphere{}), 3);
  EXPECT_EQ(shape_dimension(Polygon{}), 2);
  const Box3 b = shape_bounding_box(Ellipse{{1, 1}, {2, 1}, M_PI / 2});
  EXPECT_NEAR(b.min[0], 0, 1e-15);
  EXPECT_NEAR(b.max[1], 3, 1e-15);
  const Box3 c = shape_bounding_box(Cylinder{{0, 0, 0}, {0, 0, 5}, 1});
  EXPECT_NEAR(c.min[0], -1, 1e-15);
  EXPECT_NEAR(c.max[2], 5, 1e-15);
  EXPECT_NEAR(c.max[1], 1, 1e-15);
  EXPECT_TRUE(shape_contains(Cylinder{{0, 0, 0}, {0, 0, 5}, 1}, {0.5, 0.5, 4.9}));
  EXPECT_FALSE(shape_contains(Cylinder{{0, 0, 0}, {0, 0, 5}, 1}, {0.5, 0.5, 5.1}));
  const Shape moved = translated(Circle{{1, 2}, 3}, {1, 1, 0});
  EXPECT_EQ(std::get<Circle>(moved).center, (Vec2{2, 3}));
}

TEST(Shapes, BoundarySamplesAreCloseAndOnTheBoundary) {
  const Ellipse e{{0.5, 0.5}, {0.3, 0.1}, 0.7};
  const auto pts = shape_boundary_samples(e, 0.01);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vec3& p = pts[i];
    const Vec3& q = pts[(i + 1) % pts.size()];
    EXPECT_LE(std::hypot(p[0] - q[0], p[1] - q[1]), 0.01 + 1e-15);
  }
  EXPECT_GT(pts.size(), 100u);
  for (const Vec3& p : shape_boundary_samples(Sphere{{1, 2, 3}, 2}, 0.2))
    EXPECT_NEAR(std::hypot(p[0] - 1, p[1] - 2, p[2] - 3), 2, 1e-12);
}

TEST(Shapes, OverlapPairs) {
  EXPECT_TRUE(shapes_overlap(Circle{{0, 0}, 1}, Circle{{2, 0}, 1}));  // touching counts
  EXPECT_FALSE(shapes_overlap(Circle{{0, 0}, 1}, Circle{{2.5, 0}, 1}));
  EXPECT_TRUE(shapes_overlap(Circle{{0, 0}, 1}, Circle{{2.5, 0}, 1}, 0.5));
  EXPECT_TRUE(shapes_overlap(Sphere{{0, 0, 0}, 1}, Sphere{{0, 0, 2.1}, 1}, 0.1));
  EXPECT_FALSE(shapes_overlap(Sphere{{0, 0, 0}, 1}, Sphere{{0, 0, 2.1}, 1}, 0.09));
  // Ellipses side by side: a = 2 along x, touching at x = 2 when the second sits at 4.
  EXPECT_TRUE(shapes_overlap(Ellipse{{0, 0}, {2, 1}, 0}, Ellipse{{3.999999, 0}, {2, 1}, 0}));
  EXPECT_FALSE(shapes_overlap(Ellipse{{0, 0}, {2, 1}, 0}, Ellipse{{4.000001, 0}, {2, 1}, 0}));
  // Rotated by 90°: the second now reaches only 1 along x.
  EXPECT_FALSE(shapes_overlap(Ellipse{{0, 0}, {2, 1}, 0}, Ellipse{{3.000001, 0}, {2, 1}, M_PI / 2}));
  EXPECT_TRUE(shapes_overlap(Ellipse{{0, 0}, {2, 1}, 0}, Ellipse{{2.999999, 0}, {2, 1}, M_PI / 2}));
  // Ellipsoids and cylinders.
  EXPECT_TRUE(shapes_overlap(Ellipsoid{{0, 0, 0}, {2, 1, 1}}, Ellipsoid{{3.999999, 0, 0}, {2, 1, 1}}));
  EXPECT_FALSE(shapes_overlap(Ellipsoid{{0, 0, 0}, {2, 1, 1}}, Ellipsoid{{4.000001, 0, 0}, {2, 1, 1}}));
  EXPECT_FALSE(shapes_overlap(Cylinder{{0, 0, 0}, {0, 0, 5}, 1}, Cylinder{{2.000001, 0, 0}, {2.000001, 0, 5}, 1}));
  EXPECT_TRUE(shapes_overlap(Cylinder{{0, 0, 0}, {0, 0, 5}, 1}, Cylinder{{1.999999, 0, 0}, {1.999999, 5, 0}, 1}));
  // Cap against cap: end to end along z.
  EXPECT_FALSE(shapes_overlap(Cylinder{{0, 0, 0}, {0, 0, 5}, 1}, Cylinder{{0, 0, 5.000001}, {0, 0, 9}, 1}));
  EXPECT_TRUE(shapes_overlap(Cylinder{{0, 0, 0}, {0, 0, 5}, 1}, Sphere{{0, 0, 5.999999}, 1}));
  // Polygons: exact, including the L-shaped (non-convex) case.
  const Polygon l{{{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 3}, {0, 3}}};
  EXPECT_FALSE(shapes_overlap(l, Polygon{{{1.5, 1.5}, {2.5, 1.5}, {2.5, 2.5}}}));
  EXPECT_TRUE(shapes_overlap(l, Polygon{{{1, 1}, {2.5, 1.5}, {2.5, 2.5}}}));
  EXPECT_TRUE(shapes_overlap(l, Circle{{2, 2}, 1.0}));
  EXPECT_FALSE(shapes_overlap(l, Circle{{2, 2}, 0.99}));
}

TEST(Oracle2Ellipse, ClassificationCrossingsAndArea) {
  SceneDesc s;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1, 1, 0};
  s.phases = {{1, "m", false}, {2, "f", false}};
  const Ellipse e{{0.5, 0.5}, {0.3, 0.1}, 0.5};
  s.inclusions = {{e, 2, 0}};
  Oracle2 o(s);
  std::vector<std::int32_t> c{0};
  const double cs = std::cos(0.5), sn = std::sin(0.5);
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Crossing> cr;
  for (int i = 0; i < 3000; ++i) {
    const Vec2 a{u(rng), u(rng)}, b{u(rng), u(rng)};
    o.crossings(a, b, c, cr);
    for (const Crossing& x : cr) {
      const double px = a[0] + x.t * (b[0] - a[0]) - 0.5, py = a[1] + x.t * (b[1] - a[1]) - 0.5;
      const double uu = (px * cs + py * sn) / 0.3, vv = (-px * sn + py * cs) / 0.1;
      EXPECT_NEAR(uu * uu + vv * vv, 1.0, 1e-12);
    }
    const double px = a[0] - 0.5, py = a[1] - 0.5;
    const double uu = (px * cs + py * sn) / 0.3, vv = (-px * sn + py * cs) / 0.1;
    if (std::abs(uu * uu + vv * vv - 1) > 1e-12) {
      EXPECT_EQ(o.phase_at(a, c), uu * uu + vv * vv < 1 ? 1 : 0);
    }
  }
  // Vertex of the ellipse: ON.
  const Vec2 v{0.5 + 0.3 * cs, 0.5 + 0.3 * sn};
  EXPECT_EQ(o.closure_phases(v, c), PhaseMask(3));
  EXPECT_NEAR(o.phase_measures()[1], M_PI * 0.03, 1e-14);
  EXPECT_NEAR(o.distance_to_phase({0.5, 0.5}, 0), 0.1, 1e-14);
  EXPECT_NEAR(o.distance_to_phase({0.5 - 0.4 * cs, 0.5 - 0.4 * sn}, 1), 0.1, 1e-14);
  // The same ellipse clipped by the domain: the line integral path.
  SceneDesc s2 = s;
  s2.inclusions = {{Ellipse{{1.0, 0.5}, {0.3, 0.1}, M_PI / 2}, 2, 0}};
  Oracle2 o2(s2);
  EXPECT_NEAR(o2.phase_measures()[1], 0.5 * M_PI * 0.03, 1e-12);
}
