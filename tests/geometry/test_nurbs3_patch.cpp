// Rational B-spline surface patches (nurbs3): the exact rational sphere and torus must
// evaluate on the analytic surfaces, and the roots of segments on them must be the
// analytic ones, at poles, seams and piece boundaries too; tangent segments give a root
// at the tangent point or none. Arbitrary degrees and unclamped knots against de Boor.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/vec_math.hpp"
#include "geometry/nurbs3.hpp"

using namespace cisamr;
using namespace cisamr::geometry;

namespace {

const double kHalf = std::sqrt(0.5);

// The unit circle as a 9-point rational quadratic: (x, y, w), knots with it.
const double kCircle[9][3] = {{1, 0, 1},  {1, 1, kHalf},   {0, 1, 1},  {-1, 1, kHalf}, {-1, 0, 1},
                              {-1, -1, kHalf}, {0, -1, 1}, {1, -1, kHalf}, {1, 0, 1}};
const std::vector<double> kCircleKnots = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};

// The standard exact sphere: one biquadratic 9 × 5 patch, u around z (a seam at u = 0, 1),
// v from the south pole to the north pole (two poles).
NurbsPatch sphere_patch(const Vec3& c, double r) {
  const double half[5][3] = {{0, -1, 1}, {1, -1, kHalf}, {1, 0, 1}, {1, 1, kHalf}, {0, 1, 1}};  // (ρ, z, w)
  NurbsPatch p;
  p.degree = {2, 2};
  p.knots_u = kCircleKnots;
  p.knots_v = {0, 0, 0, 0.5, 0.5, 1, 1, 1};
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 9; ++i) {
      p.control_points.push_back({c[0] + r * kCircle[i][0] * half[j][0], c[1] + r * kCircle[i][1] * half[j][0],
                                  c[2] + r * half[j][1]});
      p.weights.push_back(kCircle[i][2] * half[j][2]);
    }
  return p;
}

// The exact torus (major radius R around z, minor radius r): 9 × 9, seams both ways.
NurbsPatch torus_patch(const Vec3& c, double R, double r) {
  NurbsPatch p;
  p.degree = {2, 2};
  p.knots_u = p.knots_v = kCircleKnots;
  for (int j = 0; j < 9; ++j)
    for (int i = 0; i < 9; ++i) {
      const double rho = R + r * kCircle[j][0];
      p.control_points.push_back({c[0] + rho * kCircle[i][0], c[1] + rho * kCircle[i][1], c[2] + r * kCircle[j][1]});
      p.weights.push_back(kCircle[i][2] * kCircle[j][2]);
    }
  return p;
}

double sphere_error(const Vec3& x, const Vec3& c, double r) { return std::abs(norm(sub(x, c)) - r); }
double torus_error(const Vec3& x, const Vec3& c, double R, double r) {
  const Vec3 q = sub(x, c);
  return std::abs(std::hypot(std::hypot(q[0], q[1]) - R, q[2]) - r);
}

nurbs::PatchPieces pieces_of(const NurbsPatch& patch) {
  nurbs::PatchPieces out;
  EXPECT_EQ(nurbs::extract_patch(patch, out), "");
  return out;
}

// The roots of the segment on every piece, merged across piece boundaries (what the body
// will do by topology): one root seen by two pieces lies within `merge` of itself.
std::vector<nurbs::LineRoot> segment_roots(const nurbs::PatchPieces& pp, const nurbs::LineQuery& q, double merge) {
  std::vector<nurbs::LineRoot> all, out;
  for (const nurbs::BezierPatch& piece : pp.pieces) nurbs::line_roots(piece, q, all);
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.lambda < b.lambda; });
  const double len = norm(sub(q.b, q.a));
  for (const auto& r : all)
    if (out.empty() || (r.lambda - out.back().lambda) * len > merge) out.push_back(r);
  return out;
}

// Analytic roots in (0, 1) of |a + λ(b − a) − c| = r; false when nearly tangent.
bool sphere_hits(const Vec3& a, const Vec3& b, const Vec3& c, double r, std::vector<double>& hits) {
  const Vec3 d = sub(b, a), f = sub(a, c);
  const double A = dot(d, d), B = dot(f, d), C = dot(f, f) - r * r;
  const double disc = B * B - A * C;
  hits.clear();
  if (disc < 0) return disc < -1e-12 * A * r * r;
  const double sq = std::sqrt(disc);
  if (sq < 1e-6 * std::sqrt(A) * r) return false;  // two roots within 1e-6·r: ill-conditioned
  const double q = -(B + std::copysign(sq, B));
  for (double t : {q / A, C / q})
    if (t > 0 && t < 1) hits.push_back(t);
  std::sort(hits.begin(), hits.end());
  return true;
}

const Vec3 kCentre{0.25, -0.5, 0.75};
constexpr double kR = 1.0;

nurbs::LineQuery sphere_query(const Vec3& a, const Vec3& b) {
  nurbs::LineQuery q;
  q.a = a, q.b = b;
  q.size = 2 * std::sqrt(3.0) * kR;
  q.tolerance = 1e-12 * kR;
  return q;
}

}  // namespace

TEST(Nurbs3Patch, ExtractionRefusesMalformedPatchesNamingTheField) {
  nurbs::PatchPieces out;
  NurbsPatch p = sphere_patch(kCentre, kR);
  EXPECT_EQ(nurbs::extract_patch(p, out), "");
  EXPECT_EQ(out.count_u, 4);
  EXPECT_EQ(out.count_v, 2);
  NurbsPatch bad = p;
  bad.degree = {0, 2};
  EXPECT_EQ(nurbs::extract_patch(bad, out), ".degree: must be in [1, 30] in u and v");
  bad = p;
  bad.knots_u[4] = 0.1;
  EXPECT_EQ(nurbs::extract_patch(bad, out), ".knots_u: must be non-decreasing (knot 4)");
  bad = p;
  bad.knots_v = {0, 0, 1, 1};
  EXPECT_EQ(nurbs::extract_patch(bad, out), ".knots_v: a degree-2 direction needs at least 6 knots, got 4");
  bad = p;
  bad.knots_v = {0, 0, 0, 0, 0, 0, 0, 0};
  EXPECT_EQ(nurbs::extract_patch(bad, out), ".knots_v: the parameter range is empty");
  bad = p;
  bad.control_points.pop_back();
  EXPECT_EQ(nurbs::extract_patch(bad, out),
            ".control_points: the knot vectors give 9 × 5 = 45 control points (u fastest), got 44");
  bad = p;
  bad.weights[7] = 0;
  EXPECT_EQ(nurbs::extract_patch(bad, out), ".weights: must be positive");
  bad = p;
  bad.weights.pop_back();
  EXPECT_EQ(nurbs::extract_patch(bad, out), ".weights: expected 45 weights (one per control point), got 44");
}

TEST(Nurbs3Patch, ExactSphereAndTorusEvaluateOnTheAnalyticSurfaces) {
  const nurbs::PatchPieces sphere = pieces_of(sphere_patch(kCentre, kR));
  const nurbs::PatchPieces torus = pieces_of(torus_patch(kCentre, 1.0, 0.3));
  double worst_sphere = 0, worst_torus = 0, worst_tangent = 0;
  for (int j = 0; j <= 100; ++j)
    for (int i = 0; i <= 100; ++i) {
      const double u = i / 100.0, v = j / 100.0;
      Vec3 du, dv;
      const Vec3 x = nurbs::evaluate(sphere, u, v, &du, &dv);
      worst_sphere = std::max(worst_sphere, sphere_error(x, kCentre, kR));
      // Derivatives are tangent to the sphere (where they do not vanish: the poles).
      const Vec3 radial = scale(sub(x, kCentre), 1 / kR);
      if (norm(du) > 1e-3) worst_tangent = std::max(worst_tangent, std::abs(dot(du, radial)) / norm(du));
      worst_tangent = std::max(worst_tangent, std::abs(dot(dv, radial)) / norm(dv));
      worst_torus = std::max(worst_torus, torus_error(nurbs::evaluate(torus, u, v), kCentre, 1.0, 0.3));
    }
  EXPECT_LE(worst_sphere, 1e-12);
  EXPECT_LE(worst_torus, 1e-12);
  EXPECT_LE(worst_tangent, 1e-12);
  // Derivatives against central differences.
  for (double u : {0.1, 0.37, 0.6, 0.93})
    for (double v : {0.2, 0.45, 0.8}) {
      Vec3 du, dv;
      nurbs::evaluate(torus, u, v, &du, &dv);
      const double h = 1e-6;
      const Vec3 fu = scale(sub(nurbs::evaluate(torus, u + h, v), nurbs::evaluate(torus, u - h, v)), 0.5 / h);
      const Vec3 fv = scale(sub(nurbs::evaluate(torus, u, v + h), nurbs::evaluate(torus, u, v - h)), 0.5 / h);
      EXPECT_LE(norm(sub(du, fu)), 1e-7 * norm(du));
      EXPECT_LE(norm(sub(dv, fv)), 1e-7 * norm(dv));
    }
  // The poles are single points, the seam closes.
  for (double u : {0.0, 0.3, 0.75, 1.0}) {
    const Vec3 south = nurbs::evaluate(sphere, u, 0), north = nurbs::evaluate(sphere, u, 1);
    EXPECT_LE(norm(sub(south, {kCentre[0], kCentre[1], kCentre[2] - kR})), 1e-15);
    EXPECT_LE(norm(sub(north, {kCentre[0], kCentre[1], kCentre[2] + kR})), 1e-15);
  }
  for (double v : {0.1, 0.5, 0.9}) EXPECT_LE(norm(sub(nurbs::evaluate(sphere, 0, v), nurbs::evaluate(sphere, 1, v))), 1e-15);
}

namespace {
// Point of a rational tensor-product B-spline by de Boor in u then v (homogeneous).
std::array<double, 4> de_boor_curve(int p, const std::vector<double>& U, std::vector<std::array<double, 4>> P,
                                    double u) {
  const int n = static_cast<int>(P.size());
  int k = p;
  for (int j = p; j < n; ++j)
    if (U[j] <= u && U[j] < U[j + 1]) k = j;
  std::vector<std::array<double, 4>> d(P.begin() + (k - p), P.begin() + k + 1);
  for (int r = 1; r <= p; ++r)
    for (int j = p; j >= r; --j) {
      const int i = j + k - p;
      const double alpha = (u - U[i]) / (U[i + p - r + 1] - U[i]);
      for (int c = 0; c < 4; ++c) d[j][c] = (1 - alpha) * d[j - 1][c] + alpha * d[j][c];
    }
  return d[p];
}
Vec3 de_boor_surface(const NurbsPatch& patch, double u, double v) {
  const int p = patch.degree[0], q = patch.degree[1];
  const std::size_t nu = patch.knots_u.size() - p - 1, nv = patch.knots_v.size() - q - 1;
  std::vector<std::array<double, 4>> column(nv);
  for (std::size_t j = 0; j < nv; ++j) {
    std::vector<std::array<double, 4>> row(nu);
    for (std::size_t i = 0; i < nu; ++i) {
      const Vec3& c = patch.control_points[i + nu * j];
      const double w = patch.weights[i + nu * j];
      row[i] = {c[0] * w, c[1] * w, c[2] * w, w};
    }
    column[j] = de_boor_curve(p, patch.knots_u, row, u);
  }
  const auto h = de_boor_curve(q, patch.knots_v, column, v);
  return {h[0] / h[3], h[1] / h[3], h[2] / h[3]};
}
// Random knots (interior values repeated at most p times), with a non-empty range.
std::vector<double> random_knots(std::mt19937_64& rng, int p, int n, bool clamped) {
  std::uniform_real_distribution<double> U(0.1, 1.0);
  std::vector<double> k;
  do {
  k.clear();
  double x = -U(rng);
  int mult = 0;
  for (int i = 0; i < n + p + 1; ++i) {
    const bool end = clamped && (i <= p || i > n);
    const bool hold = !k.empty() && (end || (mult < p && U(rng) < 0.3));
    if (!hold) x += U(rng), mult = 0;
    ++mult;
    k.push_back(x);
  }
  } while (!(k[p] < k[n]));
  return k;
}
}  // namespace

TEST(Nurbs3Patch, AnyDegreeClampedOrNotMatchesDeBoor) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 60; ++trial) {
    NurbsPatch patch;
    patch.degree = {1 + trial % 5, 1 + (trial / 5) % 4};
    const int nu = patch.degree[0] + 1 + static_cast<int>(rng() % 4), nv = patch.degree[1] + 1 + static_cast<int>(rng() % 4);
    patch.knots_u = random_knots(rng, patch.degree[0], nu, trial % 2 == 0);
    patch.knots_v = random_knots(rng, patch.degree[1], nv, trial % 3 == 0);
    for (int i = 0; i < nu * nv; ++i) {
      patch.control_points.push_back({U(rng), U(rng), U(rng)});
      patch.weights.push_back(1 + 0.6 * U(rng));
    }
    const nurbs::PatchPieces pp = pieces_of(patch);
    const double u0 = patch.knots_u[patch.degree[0]], u1 = patch.knots_u[nu];
    const double v0 = patch.knots_v[patch.degree[1]], v1 = patch.knots_v[nv];
    for (int k = 0; k < 50; ++k) {
      const double u = u0 + (u1 - u0) * (0.5 + 0.5 * U(rng)), v = v0 + (v1 - v0) * (0.5 + 0.5 * U(rng));
      EXPECT_LE(norm(sub(nurbs::evaluate(pp, u, v), de_boor_surface(patch, u, v))), 1e-12) << "trial " << trial;
    }
  }
}

TEST(Nurbs3Patch, RestrictionHalvingBoxAndSlabHoldTheSurface) {
  const nurbs::PatchPieces sphere = pieces_of(sphere_patch(kCentre, kR));
  const nurbs::BezierPatch& piece = sphere.pieces[5];
  const nurbs::BezierPatch r = nurbs::restrict_patch(piece, 0.2, 0.7, 0.1, 0.35);
  EXPECT_DOUBLE_EQ(r.u0, piece.u0 + 0.2 * (piece.u1 - piece.u0));
  for (double s : {0.0, 0.3, 1.0})
    for (double t : {0.0, 0.6, 1.0}) {
      const Vec3 x = nurbs::evaluate(r, s, t), y = nurbs::evaluate(piece, 0.2 + 0.5 * s, 0.1 + 0.25 * t);
      EXPECT_LE(norm(sub(x, y)), 1e-15);
    }
  nurbs::BezierPatch low, high;
  nurbs::halve_v(piece, low, high);
  EXPECT_EQ(low.v1, high.v0);
  for (int i = 0; i <= piece.degree_u; ++i)
    for (int c = 0; c < 4; ++c) EXPECT_EQ(low.point(i, piece.degree_v)[c], high.point(i, 0)[c]);
  nurbs::halve_u(piece, low, high);
  EXPECT_LE(norm(sub(nurbs::evaluate(high, 0.5, 0.5), nurbs::evaluate(piece, 0.75, 0.5))), 1e-15);
  const Box3 box = nurbs::control_box(piece);
  const Vec3 n = scale(Vec3{1, 2, -2}, 1.0 / 3);
  const auto [lo, hi] = nurbs::slab(piece, n);
  for (int j = 0; j <= 20; ++j)
    for (int i = 0; i <= 20; ++i) {
      const Vec3 x = nurbs::evaluate(piece, i / 20.0, j / 20.0);
      for (int k = 0; k < 3; ++k) EXPECT_TRUE(x[k] >= box.min[k] - 1e-15 && x[k] <= box.max[k] + 1e-15);
      EXPECT_TRUE(dot(n, x) >= lo - 1e-15 && dot(n, x) <= hi + 1e-15);
    }
}

TEST(Nurbs3Patch, RandomSegmentsCrossTheSphereWhereTheAnalyticRootsAre) {
  const nurbs::PatchPieces sphere = pieces_of(sphere_patch(kCentre, kR));
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> U(-1.6, 1.6);
  int compared = 0, roots = 0;
  double worst = 0;
  for (int k = 0; k < 3000; ++k) {
    Vec3 a = add(kCentre, {U(rng), U(rng), U(rng)}), b = add(kCentre, {U(rng), U(rng), U(rng)});
    if (k % 3 == 0) b = add(a, scale(sub(b, a), 0.1));  // short segments too
    std::vector<double> expected;
    if (!sphere_hits(a, b, kCentre, kR, expected)) continue;
    const double len = norm(sub(b, a));
    bool near_end = false;
    for (double t : expected) near_end |= t * len < 1e-9 || (1 - t) * len < 1e-9;
    if (near_end) continue;
    const auto found = segment_roots(sphere, sphere_query(a, b), 1e-10);
    ++compared;
    ASSERT_EQ(found.size(), expected.size()) << "segment " << k;
    for (std::size_t i = 0; i < found.size(); ++i) {
      worst = std::max(worst, std::abs(found[i].lambda - expected[i]) * len);
      ++roots;
    }
  }
  EXPECT_LE(worst, 1e-12 * kR);
  EXPECT_GT(compared, 2900);
  EXPECT_GT(roots, 1500);
}

TEST(Nurbs3Patch, SegmentsThroughPolesSeamAndPieceBoundaries) {
  const nurbs::PatchPieces sphere = pieces_of(sphere_patch(kCentre, kR));
  const Vec3 c = kCentre;
  auto check = [&](const Vec3& a, const Vec3& b, const char* what) {
    std::vector<double> expected;
    ASSERT_TRUE(sphere_hits(a, b, c, kR, expected)) << what;
    const auto found = segment_roots(sphere, sphere_query(a, b), 1e-10);
    ASSERT_EQ(found.size(), expected.size()) << what;
    for (std::size_t i = 0; i < found.size(); ++i)
      EXPECT_LE(std::abs(found[i].lambda - expected[i]) * norm(sub(b, a)), 1e-12 * kR) << what;
  };
  // Through both poles along the axis, and obliquely through one.
  check(add(c, {0, 0, -1.5}), add(c, {0, 0, 1.5}), "axis");
  check(add(c, {0, 0, 1.3}), add(c, {0, 0, 0.4}), "north pole, axis, from outside");
  check(add(c, {-0.3, 0.2, 1.6}), add(c, {0.3, -0.2, 0.4}), "north pole, oblique");
  check(add(c, {0.7, 0.1, -1.9}), add(c, {-0.7, -0.1, -0.1}), "south pole, oblique");
  // Through seam points (u = 0: y = 0, x > 0) and piece boundaries (u = 1/4: x = 0, y > 0;
  // v = 1/2: the equator), radially and across.
  for (double v : {0.1, 0.3, 0.5, 0.77}) {
    const double phi = M_PI * (v - 0.5);
    const Vec3 seam = {std::cos(phi), 0, std::sin(phi)};
    check(add(c, scale(seam, 0.2)), add(c, scale(seam, 1.7)), "seam, radial");
    check(add(c, add(scale(seam, 1.0), {0.4, 0.5, -0.3})), add(c, add(scale(seam, 1.0), {-0.4, -0.5, 0.3})),
          "seam, across");
    const Vec3 side = {0, std::cos(phi), std::sin(phi)};
    check(add(c, scale(side, 1.4)), add(c, scale(side, -0.1)), "u = 1/4 boundary, radial");
  }
  check(add(c, {1.5, 0, 0}), add(c, {-1.5, 0, 0}), "equator at the seam, both sides");
  check(add(c, {1.5, 1.5, 0}), add(c, {-1.5, -1.5, 0}), "equator at the piece corners");
}

TEST(Nurbs3Patch, TangentSegmentsTouchOnceAtTheTangentPointOrNotAtAll) {
  const nurbs::PatchPieces sphere = pieces_of(sphere_patch(kCentre, kR));
  std::mt19937_64 rng(8);
  std::normal_distribution<double> N(0, 1);
  for (int k = 0; k < 40; ++k) {
    Vec3 n = {N(rng), N(rng), N(rng)};
    if (k == 0) n = {0, 0, 1};  // at the north pole
    if (k == 1) n = {1, 0, 0};  // on the seam
    if (k == 2) n = {kHalf, kHalf, 0};  // at piece corners
    n = scale(n, 1 / norm(n));
    Vec3 t = cross(n, {N(rng), N(rng), N(rng)});
    t = scale(t, 1 / norm(t));
    const Vec3 touch = add(kCentre, scale(n, kR));
    // Exactly tangent (to rounding): one root, at the tangent point, or none.
    {
      const Vec3 a = add(touch, scale(t, -0.6)), b = add(touch, scale(t, 0.7));
      const auto found = segment_roots(sphere, sphere_query(a, b), 1e-5);
      EXPECT_LE(found.size(), 1u) << k;
      for (const auto& r : found) {
        const Vec3 x = add(a, scale(sub(b, a), r.lambda));
        EXPECT_LE(sphere_error(x, kCentre, kR), 1e-12 * kR) << k;
        EXPECT_LE(norm(sub(x, touch)), 1e-5) << k;
      }
    }
    // Missing by 1e-7 · r: no root.
    {
      const Vec3 off = add(touch, scale(n, 1e-7 * kR));
      const auto found = segment_roots(sphere, sphere_query(add(off, scale(t, -0.6)), add(off, scale(t, 0.7))), 1e-10);
      EXPECT_TRUE(found.empty()) << k;
    }
    // Cutting 1e-6 · r deep: two roots, where the analytic ones are.
    {
      const Vec3 in = add(touch, scale(n, -1e-6 * kR));
      const Vec3 a = add(in, scale(t, -0.6)), b = add(in, scale(t, 0.7));
      std::vector<double> expected;
      sphere_hits(a, b, kCentre, kR, expected);
      ASSERT_EQ(expected.size(), 2u);
      const auto found = segment_roots(sphere, sphere_query(a, b), 1e-10);
      ASSERT_EQ(found.size(), 2u) << k;
      for (int i = 0; i < 2; ++i) {
        const Vec3 x = add(a, scale(sub(b, a), found[i].lambda));
        EXPECT_LE(sphere_error(x, kCentre, kR), 1e-12 * kR) << k;
        // Near a tangency λ is ill-conditioned (|Δλ|·|d| ≈ δ/sin θ): within 1e-9.
        EXPECT_LE(std::abs(found[i].lambda - expected[i]) * norm(sub(b, a)), 1e-9) << k;
      }
    }
  }
}

TEST(Nurbs3Patch, RandomSegmentsCrossTheTorusOnTheSurface) {
  const double R = 1.0, r = 0.3;
  const nurbs::PatchPieces torus = pieces_of(torus_patch(kCentre, R, r));
  auto f = [&](const Vec3& x) {
    const Vec3 q = sub(x, kCentre);
    return std::hypot(std::hypot(q[0], q[1]) - R, q[2]) - r;
  };
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> U(-1.5, 1.5), Z(-0.5, 0.5);
  int roots = 0;
  for (int k = 0; k < 600; ++k) {
    const Vec3 a = add(kCentre, {U(rng), U(rng), Z(rng)}), b = add(kCentre, {U(rng), U(rng), Z(rng)});
    nurbs::LineQuery q;
    q.a = a, q.b = b, q.size = 2 * std::sqrt(2 * 1.3 * 1.3 + 0.3 * 0.3), q.tolerance = 1e-12;
    const auto found = segment_roots(torus, q, 1e-10);
    // Sign changes of the implicit distance on a fine sampling, bisected.
    std::vector<double> expected;
    const int n = 4000;
    bool skip = false;
    for (int i = 0; i < n; ++i) {
      double lo = double(i) / n, hi = double(i + 1) / n;
      const double flo = f(add(a, scale(sub(b, a), lo))), fhi = f(add(a, scale(sub(b, a), hi)));
      if (std::min(std::abs(flo), std::abs(fhi)) < 1e-7) skip = true;  // grazing or at a sample: ambiguous
      if ((flo < 0) == (fhi < 0)) continue;
      for (int it = 0; it < 200 && hi - lo > 1e-17; ++it) {
        const double mid = 0.5 * (lo + hi);
        ((f(add(a, scale(sub(b, a), mid))) < 0) == (flo < 0) ? lo : hi) = mid;
      }
      expected.push_back(0.5 * (lo + hi));
    }
    if (skip) continue;
    ASSERT_EQ(found.size(), expected.size()) << "segment " << k;
    for (std::size_t i = 0; i < found.size(); ++i) {
      EXPECT_LE(torus_error(add(a, scale(sub(b, a), found[i].lambda)), kCentre, R, r), 1e-12) << k;
      EXPECT_LE(std::abs(found[i].lambda - expected[i]) * norm(sub(b, a)), 1e-10) << k;
      ++roots;
    }
  }
  EXPECT_GT(roots, 400);
}

TEST(Nurbs3Patch, HigherDegreeUnclampedHeightFieldIsCrossedOnceByVerticalSegments) {
  // Control x, y at the Greville abscissae make x(u, v) = u and y(u, v) = v (linear
  // precision), so the vertical line at (x, y) meets the graph once, at z(x, y).
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> U(0, 1);
  for (const auto& [p, q] : {std::pair{3, 4}, std::pair{5, 2}, std::pair{1, 3}}) {
    NurbsPatch patch;
    patch.degree = {p, q};
    const int nu = p + 4, nv = q + 3;
    patch.knots_u = random_knots(rng, p, nu, false);
    patch.knots_v = random_knots(rng, q, nv, true);
    auto greville = [](const std::vector<double>& k, int deg, int i) {
      double g = 0;
      for (int m = 1; m <= deg; ++m) g += k[i + m];
      return g / deg;
    };
    for (int j = 0; j < nv; ++j)
      for (int i = 0; i < nu; ++i)
        patch.control_points.push_back({greville(patch.knots_u, p, i), greville(patch.knots_v, q, j), 0.3 * U(rng)});
    const nurbs::PatchPieces pp = pieces_of(patch);
    const double u0 = patch.knots_u[p], u1 = patch.knots_u[nu], v0 = patch.knots_v[q], v1 = patch.knots_v[nv];
    for (int k = 0; k < 300; ++k) {
      const double x = u0 + (u1 - u0) * (0.001 + 0.998 * U(rng)), y = v0 + (v1 - v0) * (0.001 + 0.998 * U(rng));
      const Vec3 on = nurbs::evaluate(pp, x, y);
      ASSERT_LE(std::abs(on[0] - x) + std::abs(on[1] - y), 1e-12);
      nurbs::LineQuery query;
      query.a = {x, y, -1}, query.b = {x, y, 2};
      query.size = std::hypot(u1 - u0, v1 - v0, 0.3);
      query.tolerance = 1e-12 * query.size;
      const auto found = segment_roots(pp, query, 1e-10);
      ASSERT_EQ(found.size(), 1u) << p << "×" << q << " at " << x << ", " << y;
      EXPECT_LE(std::abs(-1 + 3 * found[0].lambda - on[2]), 1e-12);
      EXPECT_TRUE(found[0].polished);
    }
  }
}

TEST(Nurbs3Patch, SegmentLyingInAFlatPatchGivesItsEndsNotAnAvalanche) {
  NurbsPatch plane;
  plane.degree = {1, 1};
  plane.knots_u = plane.knots_v = {0, 0, 1, 1};
  plane.control_points = {{0, 0, 0.5}, {1, 0, 0.5}, {0, 1, 0.5}, {1, 1, 0.5}};
  const nurbs::PatchPieces pp = pieces_of(plane);
  nurbs::LineQuery q;
  q.a = {-0.5, 0.3, 0.5}, q.b = {1.5, 0.7, 0.5};
  q.size = std::sqrt(2.0);
  std::vector<nurbs::LineRoot> roots;
  nurbs::line_roots(pp.pieces[0], q, roots);
  ASSERT_EQ(roots.size(), 2u);  // where the segment enters and leaves the square
  EXPECT_NEAR(roots[0].lambda, 0.25, 1e-12);
  EXPECT_NEAR(roots[1].lambda, 0.75, 1e-12);
  // Crossing the same plane transversally: one polished root.
  roots.clear();
  q.a = {0.3, 0.4, 0}, q.b = {0.6, 0.5, 1};
  nurbs::line_roots(pp.pieces[0], q, roots);
  ASSERT_EQ(roots.size(), 1u);
  EXPECT_NEAR(roots[0].lambda, 0.5, 1e-15);
  EXPECT_TRUE(roots[0].polished);
}

TEST(Nurbs3Patch, SegmentAlongARulingOfACylinderGivesTheEndsOfTheStretch) {
  NurbsPatch cylinder;  // radius 1 around the z axis, z in [0, 1]
  cylinder.degree = {2, 1};
  cylinder.knots_u = kCircleKnots;
  cylinder.knots_v = {0, 0, 1, 1};
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 9; ++i) {
      cylinder.control_points.push_back({kCircle[i][0], kCircle[i][1], double(j)});
      cylinder.weights.push_back(kCircle[i][2]);
    }
  const nurbs::PatchPieces pp = pieces_of(cylinder);
  for (const double angle : {0.0, M_PI / 6, M_PI / 2}) {
    const double x = std::cos(angle), y = std::sin(angle);
    nurbs::LineQuery q;
    q.a = {x, y, -0.5}, q.b = {x, y, 1.5}, q.size = std::sqrt(5.0);
    std::vector<nurbs::LineRoot> roots;
    for (const auto& piece : pp.pieces) nurbs::line_roots(piece, q, roots);
    ASSERT_FALSE(roots.empty()) << angle;
    EXPECT_LE(roots.size(), 8u) << angle;  // the two ends, seen from at most two pieces each
    double lo = 1, hi = 0;
    for (const auto& r : roots) lo = std::min(lo, r.lambda), hi = std::max(hi, r.lambda);
    EXPECT_NEAR(lo, 0.25, 1e-9) << angle;
    EXPECT_NEAR(hi, 0.75, 1e-9) << angle;
  }
}
