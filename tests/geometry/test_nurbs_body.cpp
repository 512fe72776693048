// NURBS surface bodies (surface_body): the exact rational sphere and torus, classified and
// crossed on the exact surface, against their analytic forms; the cube-sphere; the body
// errors that name a patch (docs/nurbs-step-design.md §2, §4.2, §6).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/vec_math.hpp"
#include "geometry/shapes.hpp"
#include "geometry/surface_body.hpp"
#include "../support/random_nurbs3.hpp"

namespace cisamr::geometry {
namespace {

namespace rn = cisamr::testing::nurbs3;

constexpr double kPi = 3.14159265358979323846;
const Vec3 kCentre{0.31, 0.47, 0.53};

surface::Body body_of(const NurbsSurface& s) {
  surface::Body b;
  const std::string problem = surface::build(s, b);
  EXPECT_EQ(problem, "");
  return b;
}

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
}

Vec3 random_point(std::mt19937_64& rng, const Box3& b) {
  return {uniform(rng, b.min[0], b.max[0]), uniform(rng, b.min[1], b.max[1]), uniform(rng, b.min[2], b.max[2])};
}

Box3 around(const Vec3& c, double h) { return {{c[0] - h, c[1] - h, c[2] - h}, {c[0] + h, c[1] + h, c[2] + h}}; }

// Signed distance-like functions of the analytic shapes (negative inside).
double sphere_f(const Vec3& x, const Vec3& c, double r) { return norm(sub(x, c)) - r; }
double torus_f(const Vec3& x, const Vec3& c, double R, double r) {
  const Vec3 d = sub(x, c);
  return std::hypot(std::hypot(d[0], d[1]) - R, d[2]) - r;
}

// The parameters in (0, 1) where a→b crosses the sphere.
std::vector<double> sphere_hits(const Vec3& a, const Vec3& b, const Vec3& c, double r) {
  const Vec3 d = sub(b, a), m = sub(a, c);
  const double A = dot(d, d), B = 2 * dot(m, d), C = dot(m, m) - r * r;
  const double disc = B * B - 4 * A * C;
  std::vector<double> out;
  if (disc <= 0) return out;
  const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
  double t0 = q / A, t1 = C / q;
  if (t0 > t1) std::swap(t0, t1);
  for (double t : {t0, t1})
    if (t > 0 && t < 1) out.push_back(t);
  return out;
}

TEST(NurbsBody, ExactSphereClassifiesLikeTheSphere) {
  const double r = 0.2;
  const surface::Body body = body_of(rn::exact_sphere(kCentre, r));
  EXPECT_GT(body.mesh.faces.size(), 500u);
  EXPECT_LT(body.mesh.faces.size(), 5000u);
  EXPECT_LE(body.max_thickness, 4e-3 * body.size);
  EXPECT_NEAR(surface::volume(body), 4.0 / 3 * kPi * r * r * r, 1e-13);
  EXPECT_NEAR(surface::area(body), 4 * kPi * r * r, 1e-12);

  std::mt19937_64 rng(7);
  const Box3 box = around(kCentre, 1.2 * r);
  int in_shell = 0;
  for (int i = 0; i < 40000; ++i) {
    Vec3 p = random_point(rng, box);
    if (i % 4 == 0) {  // many points close to the surface
      const Vec3 d = sub(p, kCentre);
      p = add(kCentre, scale(d, r * (1 + uniform(rng, -1e-3, 1e-3)) / norm(d)));
    }
    const double f = sphere_f(p, kCentre, r);
    if (std::abs(f) <= 1e-11) continue;
    const auto before = surface::stats().side_in_shell;
    ASSERT_EQ(surface::side(body, p), f < 0 ? 1 : -1) << "p = " << p[0] << " " << p[1] << " " << p[2] << " f = " << f;
    in_shell += surface::stats().side_in_shell != before;
  }
  EXPECT_GT(in_shell, 100);  // the exact path was exercised
  // Surface points (the poles, the seam, the tessellation's vertices) are ON.
  EXPECT_EQ(surface::side(body, {kCentre[0], kCentre[1], kCentre[2] + r}), 0);
  EXPECT_EQ(surface::side(body, {kCentre[0], kCentre[1], kCentre[2] - r}), 0);
  EXPECT_EQ(surface::side(body, {kCentre[0] + r, kCentre[1], kCentre[2]}), 0);
  for (std::size_t v = 0; v < body.mesh.vertices.size(); v += 7)
    EXPECT_EQ(surface::side(body, body.mesh.vertices[v]), 0) << v;
  // 1e-10 off the surface, either way.
  for (int i = 0; i < 2000; ++i) {
    Vec3 d = sub(random_point(rng, box), kCentre);
    d = scale(d, 1 / norm(d));
    EXPECT_EQ(surface::side(body, add(kCentre, scale(d, r - 1e-10))), 1);
    EXPECT_EQ(surface::side(body, add(kCentre, scale(d, r + 1e-10))), -1);
  }
  EXPECT_EQ(surface::stats().side_fallback, 0);
}

TEST(NurbsBody, ExactSphereRootsMatchTheAnalyticOnes) {
  const double r = 0.2;
  const surface::Body body = body_of(rn::exact_sphere(kCentre, r));
  std::mt19937_64 rng(11);
  const Box3 box = around(kCentre, 1.3 * r);
  std::vector<double> ts;
  int with_roots = 0;
  for (int i = 0; i < 6000; ++i) {
    Vec3 a = random_point(rng, box), b = random_point(rng, box);
    if (i % 3 == 0) b = add(a, scale(sub(b, a), 0.05));  // short segments, as mesh edges
    const std::vector<double> want = sphere_hits(a, b, kCentre, r);
    ts.clear();
    surface::segment_roots(body, a, b, ts);
    // A near-tangent pair closer than τ is one root or none.
    if (want.size() == 2 && (want[1] - want[0]) * norm(sub(b, a)) < 1e-9) continue;
    ASSERT_EQ(ts.size(), want.size()) << i;
    for (std::size_t k = 0; k < ts.size(); ++k) EXPECT_NEAR(ts[k], want[k], 1e-12 * r / norm(sub(b, a)) + 1e-13);
    with_roots += !want.empty();
  }
  EXPECT_GT(with_roots, 1000);
  // Through both poles, along the seam plane.
  ts.clear();
  surface::segment_roots(body, add(kCentre, {0, 0, -2 * r}), add(kCentre, {0, 0, 2 * r}), ts);
  ASSERT_EQ(ts.size(), 2u);
  EXPECT_NEAR(ts[0], 0.25, 1e-13);
  EXPECT_NEAR(ts[1], 0.75, 1e-13);
  ts.clear();
  surface::segment_roots(body, add(kCentre, {-2 * r, 0, 0}), add(kCentre, {2 * r, 0, 0}), ts);
  ASSERT_EQ(ts.size(), 2u);
}

TEST(NurbsBody, TwoPatchSphereAndReversedSphereAgreeWithOnePatch) {
  const double r = 0.25;
  NurbsSurface one = rn::exact_sphere(kCentre, r);
  // Reversed orientation: u runs the other way (rows reversed).
  NurbsSurface reversed = one;
  {
    NurbsPatch& p = reversed.patches[0];
    const int cu = 9, cv = 5;
    for (int j = 0; j < cv; ++j) {
      std::reverse(p.control_points.begin() + j * cu, p.control_points.begin() + (j + 1) * cu);
      std::reverse(p.weights.begin() + j * cu, p.weights.begin() + (j + 1) * cu);
    }
  }
  const surface::Body a = body_of(one), b = body_of(reversed);
  EXPECT_NEAR(surface::volume(b), surface::volume(a), 1e-14);
  std::mt19937_64 rng(3);
  const Box3 box = around(kCentre, 1.1 * r);
  for (int i = 0; i < 5000; ++i) {
    const Vec3 p = random_point(rng, box);
    if (std::abs(sphere_f(p, kCentre, r)) <= 1e-11) continue;
    ASSERT_EQ(surface::side(a, p), surface::side(b, p));
  }
}

TEST(NurbsBody, ExactTorusClassifiesLikeTheTorus) {
  const double R = 0.3, r = 0.1;
  const surface::Body body = body_of(rn::exact_torus(kCentre, R, r));
  EXPECT_NEAR(surface::volume(body), 2 * kPi * kPi * R * r * r, 1e-13);
  std::mt19937_64 rng(5);
  const Box3 box = around(kCentre, R + 1.2 * r);
  for (int i = 0; i < 30000; ++i) {
    const Vec3 p = random_point(rng, box);
    const double f = torus_f(p, kCentre, R, r);
    if (std::abs(f) <= 1e-11) continue;
    ASSERT_EQ(surface::side(body, p), f < 0 ? 1 : -1) << i;
  }
  // Points on the tube, 1e-10 inside and outside.
  for (int i = 0; i < 2000; ++i) {
    const double u = uniform(rng, 0, 2 * kPi), v = uniform(rng, 0, 2 * kPi);
    auto at = [&](double rr) {
      return add(kCentre, {(R + rr * std::cos(v)) * std::cos(u), (R + rr * std::cos(v)) * std::sin(u), rr * std::sin(v)});
    };
    EXPECT_EQ(surface::side(body, at(r - 1e-10)), 1);
    EXPECT_EQ(surface::side(body, at(r + 1e-10)), -1);
  }
}

TEST(NurbsBody, TouchesAndDistancesAgreeWithTheSphere) {
  const double r = 0.2;
  const surface::Body body = body_of(rn::exact_sphere(kCentre, r));
  std::mt19937_64 rng(13);
  const Box3 box = around(kCentre, 1.3 * r);
  for (int i = 0; i < 4000; ++i) {
    const Vec3 c = random_point(rng, box);
    const double h = uniform(rng, 1e-4, 0.1) * r;
    const Box3 q = around(c, h);
    double near2 = 0, far2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double lo = q.min[k] - kCentre[k], hi = q.max[k] - kCentre[k];
      const double n = lo > 0 ? lo : (hi < 0 ? hi : 0);
      near2 += n * n;
      far2 += std::max(lo * lo, hi * hi);
    }
    const bool meets = std::sqrt(near2) <= r && std::sqrt(far2) >= r;
    const bool got = surface::touches_box(body, q);
    if (meets) ASSERT_TRUE(got) << i;
    if (std::sqrt(near2) > r + 1e-9 || std::sqrt(far2) < r - 1e-9) ASSERT_FALSE(got) << i;
  }
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p = random_point(rng, box);
    Vec3 n;
    const double d = surface::distance(body, p, &n);
    // Exact near the surface (what fidelity and collapse deviations ask); far inside, where
    // the distance is nearly the same from every surface point, to 1e-4 of itself.
    const double want = std::abs(sphere_f(p, kCentre, r));
    EXPECT_NEAR(d, want, want < 0.2 * r ? 1e-12 : 1e-4 * want) << i;
    if (dot(n, n) > 0) {  // outward: along p − c
      EXPECT_GT(dot(n, sub(p, kCentre)), 0.99 * norm(n) * norm(sub(p, kCentre)));
    }
  }
}

TEST(NurbsBody, CubeSphereAndRandomParticlesBuildClosedAndAgreeWithTheirTessellationAwayFromIt) {
  std::mt19937_64 rng(17);
  for (rn::Kind kind : rn::kKinds)
    for (int seed = 0; seed < 6; ++seed) {
      std::mt19937_64 gen(static_cast<std::uint64_t>(100 + seed));
      const NurbsSurface s = rn::random_particle(gen, kind, kCentre, 0.2);
      surface::Body body;
      ASSERT_EQ(surface::build(s, body), "") << rn::kind_name(kind) << " " << seed;
      // The volume on the exact surface is close to the tessellation's.
      EXPECT_NEAR(surface::volume(body), stl::volume(body.mesh), 2e-2 * surface::volume(body));
      // Far from the shells the tessellation and the body agree (the body asks it there).
      for (int i = 0; i < 2000; ++i) {
        const Vec3 p = random_point(rng, body.box);
        const int s_body = surface::side(body, p);
        if (surface::distance(body, p) > 2 * body.max_thickness) {
          ASSERT_EQ(s_body, stl::side(body.mesh, p));
        }
      }
      // Roots of segments agree with sides at their ends: parity.
      std::vector<double> ts;
      for (int i = 0; i < 500; ++i) {
        const Vec3 a = random_point(rng, body.box), b = random_point(rng, body.box);
        const int sa = surface::side(body, a), sb = surface::side(body, b);
        if (sa == 0 || sb == 0) continue;
        ts.clear();
        surface::segment_roots(body, a, b, ts);
        // Tangential double roots are possible but rare; odd parity must match.
        EXPECT_EQ(ts.size() % 2 == 1, sa != sb) << rn::kind_name(kind) << " " << seed << " " << i;
      }
    }
}

// Boehm's knot insertion of x into every row (along u) or column (along v) of a patch, in
// homogeneous coordinates: the same surface with one more knot (independent of lib/geometry).
NurbsPatch with_knot(const NurbsPatch& p, bool along_u, double x) {
  const int deg = along_u ? p.degree[0] : p.degree[1];
  const std::vector<double>& U = along_u ? p.knots_u : p.knots_v;
  const int nu = static_cast<int>(p.knots_u.size()) - p.degree[0] - 1, nv = static_cast<int>(p.knots_v.size()) - p.degree[1] - 1;
  const int n = along_u ? nu : nv, lines = along_u ? nv : nu;
  int k = deg;
  while (k + 1 < n && U[static_cast<std::size_t>(k + 1)] <= x) ++k;
  NurbsPatch out = p;
  std::vector<double> knots = U;
  knots.insert(knots.begin() + k + 1, x);
  (along_u ? out.knots_u : out.knots_v) = knots;
  const int mu = along_u ? nu + 1 : nu, mv = along_u ? nv : nv + 1;
  out.control_points.assign(static_cast<std::size_t>(mu * mv), Vec3{});
  out.weights.assign(static_cast<std::size_t>(mu * mv), 1.0);
  for (int line = 0; line < lines; ++line) {
    auto in_at = [&](int i) { return static_cast<std::size_t>(along_u ? i + nu * line : line + nu * i); };
    auto out_at = [&](int i) { return static_cast<std::size_t>(along_u ? i + mu * line : line + mu * i); };
    auto hom = [&](int i) {
      const double w = p.weights.empty() ? 1.0 : p.weights[in_at(i)];
      const Vec3& c = p.control_points[in_at(i)];
      return std::array<double, 4>{c[0] * w, c[1] * w, c[2] * w, w};
    };
    for (int i = 0; i <= n; ++i) {
      std::array<double, 4> q;
      if (i <= k - deg) {
        q = hom(i);
      } else if (i >= k + 1) {
        q = hom(i - 1);
      } else {
        const double a = (x - U[static_cast<std::size_t>(i)]) / (U[static_cast<std::size_t>(i + deg)] - U[static_cast<std::size_t>(i)]);
        const auto h0 = hom(i - 1), h1 = hom(i);
        for (int e = 0; e < 4; ++e) q[static_cast<std::size_t>(e)] = (1 - a) * h0[static_cast<std::size_t>(e)] + a * h1[static_cast<std::size_t>(e)];
      }
      out.control_points[out_at(i)] = {q[0] / q[3], q[1] / q[3], q[2] / q[3]};
      out.weights[out_at(i)] = q[3];
    }
  }
  return out;
}

// Neighbouring patches whose shared side is the same curve broken at different knots (one
// patch refined, as CAD models often are) meet: the body splits each at the other's knots.
// The same body as the unrefined surface, side for side; a side moved off by 1e-6 is refused.
TEST(NurbsBody, SidesBrokenAtDifferentKnotsStillMeet) {
  for (const auto& [name, surface] : {std::pair<const char*, NurbsSurface>{"cube sphere", rn::cube_sphere(kCentre, 0.2)},
                                      std::pair<const char*, NurbsSurface>{"torus", rn::exact_torus(kCentre, 0.2, 0.07)}}) {
    SCOPED_TRACE(name);
    NurbsSurface refined = surface;
    refined.patches[0] = with_knot(with_knot(with_knot(refined.patches[0], true, 0.3), false, 0.55), false, 0.8);
    const surface::Body a = body_of(surface), b = body_of(refined);
    EXPECT_NEAR(surface::volume(b), surface::volume(a), 1e-13 * surface::volume(a));
    std::mt19937_64 rng(5);
    int checked = 0;
    for (int i = 0; i < 5000; ++i) {
      const Vec3 p = random_point(rng, a.box);
      const int sa = surface::side(a, p);
      if (sa == 0 || surface::distance(a, p) < 1e-9) continue;
      ASSERT_EQ(surface::side(b, p), sa) << i;
      ++checked;
    }
    EXPECT_GT(checked, 4000);
    // The knot must matter: a boundary point of the refined side moved off by 1e-6 is refused.
    NurbsSurface moved = refined;
    moved.patches[0].control_points[1][2] += 1e-6;
    surface::Body c;
    const std::string problem = surface::build(moved, c);
    EXPECT_NE(problem.find("meets no other patch boundary"), std::string::npos) << problem;
  }
}

// The level rules' question for a NURBS body and a convex analytic shape (shapes_overlap
// with a gap): answered on the body's pieces, so true whenever they come within the gap,
// false once they miss it by more than the resolution (1e-3 of the body's size); a sphere
// inside the body, or the body inside a sphere, overlaps.
TEST(NurbsBody, OverlapsWithConvexShapesOnItsPieces) {
  const double r = 0.2, rs = 0.1, gap = 0.05;
  const Shape nurbs = rn::exact_sphere(kCentre, r);
  std::mt19937_64 rng(9);
  int near_true = 0, far_false = 0;
  for (int i = 0; i < 300; ++i) {
    Vec3 d{uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)};
    d = scale(d, 1 / norm(d));
    const double dist = uniform(rng, 0.25, 0.45);  // centre distance; the surfaces' gap is dist − 0.3
    const Shape ball = Sphere{add(kCentre, scale(d, dist)), rs};
    const bool answer = shapes_overlap(nurbs, ball, gap);
    const double miss = dist - r - rs;
    if (miss < gap) {
      EXPECT_TRUE(answer) << "miss " << miss;
      ++near_true;
    } else if (miss > gap + 2e-3) {
      EXPECT_FALSE(answer) << "miss " << miss;
      ++far_false;
    }
    EXPECT_EQ(shapes_overlap(ball, nurbs, gap), answer);  // either order
  }
  EXPECT_GT(near_true, 50);
  EXPECT_GT(far_false, 50);
  EXPECT_TRUE(shapes_overlap(nurbs, Shape{Sphere{kCentre, 0.05}}, gap));  // inside the body
  EXPECT_TRUE(shapes_overlap(nurbs, Shape{Sphere{kCentre, 1.0}}, gap));   // the body inside it
  // A cylinder beside it, its axis along z: apart by 0.1 − 0.05, then by more than the gap.
  const Vec3 side{kCentre[0] + r + 0.05 + 0.05, kCentre[1], kCentre[2]};
  EXPECT_TRUE(shapes_overlap(nurbs, Shape{Cylinder{sub(side, {0, 0, 0.3}), add(side, {0, 0, 0.3}), 0.05}}, gap));
  const Vec3 far{kCentre[0] + r + 0.05 + 0.06, kCentre[1], kCentre[2]};
  EXPECT_FALSE(shapes_overlap(nurbs, Shape{Cylinder{sub(far, {0, 0, 0.3}), add(far, {0, 0, 0.3}), 0.05}}, gap));
}

TEST(NurbsBody, ErrorsNameThePatchAndSide) {
  // Half a sphere: open along its cut.
  NurbsSurface half = rn::exact_sphere(kCentre, 0.2);
  {
    NurbsPatch& p = half.patches[0];
    NurbsPatch h;
    h.degree = p.degree;
    h.knots_u = {0, 0, 0, 0.5, 0.5, 1, 1, 1};
    h.knots_v = p.knots_v;
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 5; ++i) {
        h.control_points.push_back(p.control_points[static_cast<std::size_t>(j * 9 + i)]);
        h.weights.push_back(p.weights[static_cast<std::size_t>(j * 9 + i)]);
      }
    p = h;
  }
  surface::Body b;
  std::string problem = surface::build(half, b);
  EXPECT_EQ(problem.rfind(".patches[0].u_max: meets no other patch boundary", 0), 0u) << problem;

  // Two overlapping spheres as one surface: closed, but self-intersecting.
  NurbsSurface two = rn::exact_sphere(kCentre, 0.2);
  NurbsPatch second = two.patches[0];
  for (Vec3& v : second.control_points) v[0] += 0.5;  // unit size: moved by 0.1 after scaling by 0.2
  two.patches.push_back(second);
  problem = surface::build(two, b);
  EXPECT_EQ(problem.rfind(".patches: patches[0] and patches[1] intersect (tessellation, near", 0), 0u) << problem;

  // Degenerate: all control points of a patch's boundary coincide.
  NurbsSurface point = rn::exact_sphere(kCentre, 0.2);
  for (Vec3& v : point.patches[0].control_points) v = {0, 0, 0};
  problem = surface::build(point, b);
  EXPECT_NE(problem.find("coincide"), std::string::npos) << problem;

  // Bad placement.
  NurbsSurface rotated = rn::exact_sphere(kCentre, 0.2);
  rotated.rotation = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 2}}};
  EXPECT_EQ(surface::build(rotated, b).rfind(".rotation:", 0), 0u);
}

}  // namespace
}  // namespace cisamr::geometry
