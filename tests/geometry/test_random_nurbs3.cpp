// The seeded NURBS particles of tests/support/random_nurbs3.hpp: every particle is closed
// (poles are rows of one point, every other patch side meets exactly one other side bit for
// bit, weights included), lies within 1.3 radii of its centre, keeps positive weights and
// outward normals with its surface star-shaped (sphere kinds) or around its tube (torus);
// the exact sphere and torus evaluate on the analytic surfaces. Evaluation by a de Boor
// written here, independent of lib/geometry's nurbs3.
#include "support/random_nurbs3.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

using namespace cisamr;
using namespace cisamr::geometry;
namespace rn = cisamr::testing::nurbs3;

namespace {

bool same_bits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }
bool same_bits(const Vec3& a, const Vec3& b) { return same_bits(a[0], b[0]) && same_bits(a[1], b[1]) && same_bits(a[2], b[2]); }

// ---- a plain rational de Boor (homogeneous coordinates, rows in u, then v)

using Hom = std::array<double, 4>;

std::size_t span(const std::vector<double>& knots, int p, double u) {
  const std::size_t n = knots.size() - static_cast<std::size_t>(p) - 1;
  if (u >= knots[n]) {
    std::size_t k = n - 1;
    while (knots[k] == knots[k + 1]) --k;
    return k;
  }
  std::size_t k = static_cast<std::size_t>(p);
  while (!(knots[k] <= u && u < knots[k + 1])) ++k;
  return k;
}

Hom de_boor(const std::vector<double>& knots, int p, const std::vector<Hom>& ctrl, double u) {
  const std::size_t k = span(knots, p, u), q = static_cast<std::size_t>(p);
  std::vector<Hom> d(ctrl.begin() + static_cast<std::ptrdiff_t>(k - q), ctrl.begin() + static_cast<std::ptrdiff_t>(k + 1));
  for (std::size_t r = 1; r <= q; ++r)
    for (std::size_t j = q; j >= r; --j) {
      const double lo = knots[j + k - q], hi = knots[j + 1 + k - r];
      const double a = (u - lo) / (hi - lo);
      for (int c = 0; c < 4; ++c) d[j][c] = (1 - a) * d[j - 1][c] + a * d[j][c];
    }
  return d[q];
}

std::size_t count_u(const NurbsPatch& p) { return p.knots_u.size() - static_cast<std::size_t>(p.degree[0]) - 1; }
std::size_t count_v(const NurbsPatch& p) { return p.knots_v.size() - static_cast<std::size_t>(p.degree[1]) - 1; }

// The placed surface point at (s, t) ∈ [0, 1]² of the patch's parameter rectangle.
Vec3 evaluate(const NurbsSurface& surface, const NurbsPatch& p, double s, double t) {
  const std::size_t nu = count_u(p), nv = count_v(p);
  const double u0 = p.knots_u[static_cast<std::size_t>(p.degree[0])], u1 = p.knots_u[nu];
  const double v0 = p.knots_v[static_cast<std::size_t>(p.degree[1])], v1 = p.knots_v[nv];
  std::vector<Hom> column;
  for (std::size_t j = 0; j < nv; ++j) {
    std::vector<Hom> row;
    for (std::size_t i = 0; i < nu; ++i) {
      const Vec3& x = p.control_points[i + nu * j];
      const double w = p.weights.empty() ? 1.0 : p.weights[i + nu * j];
      row.push_back({w * x[0], w * x[1], w * x[2], w});
    }
    column.push_back(de_boor(p.knots_u, p.degree[0], row, u0 + s * (u1 - u0)));
  }
  const Hom h = de_boor(p.knots_v, p.degree[1], column, v0 + t * (v1 - v0));
  Vec3 x{};
  for (int d = 0; d < 3; ++d) x[d] = surface.scale * (h[d] / h[3]) + surface.translate[d];  // rotation: identity here
  return x;
}

Vec3 minus(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot3(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross3(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

// ---- closure: the sides of every patch as (point, weight) lists

struct Side {
  std::string name;
  std::vector<Vec3> points;
  std::vector<double> weights;
};

std::vector<Side> sides_of(const NurbsSurface& s) {
  std::vector<Side> out;
  for (std::size_t k = 0; k < s.patches.size(); ++k) {
    const NurbsPatch& p = s.patches[k];
    const std::size_t nu = count_u(p), nv = count_v(p);
    const auto side = [&](const char* name, std::size_t first, std::size_t step, std::size_t count) {
      Side side{"patches[" + std::to_string(k) + "]." + name, {}, {}};
      for (std::size_t m = 0; m < count; ++m) {
        side.points.push_back(p.control_points[first + m * step]);
        side.weights.push_back(p.weights.empty() ? 1.0 : p.weights[first + m * step]);
      }
      out.push_back(side);
    };
    side("u_min", 0, nu, nv);
    side("u_max", nu - 1, nu, nv);
    side("v_min", 0, 1, nu);
    side("v_max", nu * (nv - 1), 1, nu);
  }
  return out;
}

bool is_pole(const Side& s) {
  for (const Vec3& x : s.points)
    if (!same_bits(x, s.points[0])) return false;
  return true;
}

bool same_side(const Side& a, const Side& b, bool reversed) {
  if (a.points.size() != b.points.size()) return false;
  const std::size_t n = a.points.size();
  for (std::size_t m = 0; m < n; ++m) {
    const std::size_t o = reversed ? n - 1 - m : m;
    if (!same_bits(a.points[m], b.points[o]) || !same_bits(a.weights[m], b.weights[o])) return false;
  }
  return true;
}

// Poles counted; every other side meets exactly one other side bit for bit.
int expect_closed(const NurbsSurface& s, const std::string& what) {
  const std::vector<Side> sides = sides_of(s);
  int poles = 0;
  for (std::size_t a = 0; a < sides.size(); ++a) {
    if (is_pole(sides[a])) {
      ++poles;
      continue;
    }
    int mates = 0;
    for (std::size_t b = 0; b < sides.size(); ++b)
      if (b != a && !is_pole(sides[b]) && (same_side(sides[a], sides[b], false) || same_side(sides[a], sides[b], true)))
        ++mates;
    EXPECT_EQ(mates, 1) << what << " " << sides[a].name;
  }
  return poles;
}

// Sampled interior parameters of a patch (poles and sides excluded).
std::vector<std::array<double, 2>> interior_samples(std::mt19937_64& rng, int grid, int random) {
  std::vector<std::array<double, 2>> out;
  for (int i = 0; i < grid; ++i)
    for (int j = 0; j < grid; ++j) out.push_back({0.01 + 0.98 * i / (grid - 1), 0.01 + 0.98 * j / (grid - 1)});
  for (int k = 0; k < random; ++k)
    out.push_back({0.01 + 0.98 * rn::detail::uniform(rng, 0, 1), 0.01 + 0.98 * rn::detail::uniform(rng, 0, 1)});
  return out;
}

// S_u × S_v (central differences) against x − reference(x).
template <class Reference>
double worst_normal(const NurbsSurface& s, std::mt19937_64& rng, const Reference& reference) {
  constexpr double e = 1e-6;
  double worst = INFINITY;
  for (const NurbsPatch& p : s.patches)
    for (const auto& [u, v] : interior_samples(rng, 9, 40)) {
      const Vec3 su = minus(evaluate(s, p, u + e, v), evaluate(s, p, u - e, v));
      const Vec3 sv = minus(evaluate(s, p, u, v + e), evaluate(s, p, u, v - e));
      const Vec3 x = evaluate(s, p, u, v);
      const Vec3 n = cross3(su, sv), r = minus(x, reference(x));
      worst = std::min(worst, dot3(n, r) / std::sqrt(dot3(n, n) * dot3(r, r)));
    }
  return worst;  // the smallest cosine between the normal and the outward direction
}

}  // namespace

TEST(RandomNurbs3, ParticlesAreClosedBoundedAndFaceOutwards) {
  for (rn::Kind kind : rn::kKinds)
    for (std::uint64_t seed = 1; seed <= 50; ++seed) {
      const std::string what = std::string(rn::kind_name(kind)) + " seed " + std::to_string(seed);
      std::mt19937_64 rng(seed);
      const Vec3 centre{rn::detail::uniform(rng, -2, 2), rn::detail::uniform(rng, -2, 2), rn::detail::uniform(rng, -2, 2)};
      const double radius = rn::detail::uniform(rng, 0.05, 3);
      const NurbsSurface s = rn::random_particle(rng, kind, centre, radius);

      // Placement, shape of the nets, weights.
      EXPECT_TRUE(same_bits(s.scale, radius)) << what;
      EXPECT_TRUE(same_bits(s.translate, centre)) << what;
      ASSERT_EQ(s.patches.size(), kind == rn::Kind::cube_sphere ? 6u : 1u) << what;
      for (const NurbsPatch& p : s.patches) {
        ASSERT_EQ(p.control_points.size(), count_u(p) * count_v(p)) << what;
        ASSERT_EQ(p.weights.size(), p.control_points.size()) << what;
        for (double w : p.weights)  // exact weights 1, √2/2, 1/2 times factors in [0.7, 1.4]
          EXPECT_TRUE(w >= 0.35 - 1e-12 && w <= 1.4 + 1e-12) << what << ": weight " << w;
      }

      // Closure: the sphere's two poles, and every other side shared bit for bit.
      const int poles = expect_closed(s, what);
      EXPECT_EQ(poles, kind == rn::Kind::perturbed_sphere ? 2 : 0) << what;
      if (kind == rn::Kind::perturbed_sphere) {  // poles at the unit sphere's, the seam u = 0 = 1
        const NurbsPatch& p = s.patches[0];
        for (std::size_t i = 0; i < 9; ++i) {
          EXPECT_TRUE(same_bits(p.control_points[i], Vec3{0, 0, -1})) << what;
          EXPECT_TRUE(same_bits(p.control_points[i + 36], Vec3{0, 0, 1})) << what;
        }
        for (std::size_t j = 0; j < 5; ++j) EXPECT_TRUE(same_bits(p.control_points[9 * j], p.control_points[9 * j + 8]));
      }

      // The placed control points lie within 1.3 radii of the centre (the box per axis).
      for (const NurbsPatch& p : s.patches)
        for (const Vec3& x : p.control_points)
          for (int d = 0; d < 3; ++d)
            EXPECT_LE(std::abs(s.scale * x[d] + s.translate[d] - centre[d]), 1.3 * radius) << what;

      // Normals outward; sphere kinds star-shaped around the centre, the torus around its tube.
      double cosine = 0;
      if (kind == rn::Kind::perturbed_torus) {
        cosine = worst_normal(s, rng, [&](const Vec3& x) {
          const Vec3 r = minus(x, centre);
          const double rho = std::hypot(r[0], r[1]);
          return Vec3{centre[0] + 0.7 * radius * r[0] / rho, centre[1] + 0.7 * radius * r[1] / rho, centre[2]};
        });
      } else {
        cosine = worst_normal(s, rng, [&](const Vec3&) { return centre; });
      }
      EXPECT_GT(cosine, 0.5) << what;
    }
}

TEST(RandomNurbs3, ParticlesDependOnlyOnTheSeed) {
  for (rn::Kind kind : rn::kKinds) {
    std::mt19937_64 a(7), b(7), c(8);
    const NurbsSurface x = rn::random_particle(a, kind, {1, 2, 3}, 0.5);
    const NurbsSurface y = rn::random_particle(b, kind, {1, 2, 3}, 0.5);
    const NurbsSurface z = rn::random_particle(c, kind, {1, 2, 3}, 0.5);
    bool differs = false;
    for (std::size_t k = 0; k < x.patches.size(); ++k)
      for (std::size_t i = 0; i < x.patches[k].control_points.size(); ++i) {
        EXPECT_TRUE(same_bits(x.patches[k].control_points[i], y.patches[k].control_points[i]));
        EXPECT_TRUE(same_bits(x.patches[k].weights[i], y.patches[k].weights[i]));
        differs |= !same_bits(x.patches[k].control_points[i], z.patches[k].control_points[i]);
      }
    EXPECT_TRUE(differs) << rn::kind_name(kind);
  }
}

TEST(RandomNurbs3, ExactSphereAndTorusLieOnTheAnalyticSurfaces) {
  std::mt19937_64 rng(14);
  const Vec3 c{0.25, -0.5, 0.75};
  const double r = 2.0;
  const NurbsSurface sphere = rn::exact_sphere(c, r);
  ASSERT_EQ(sphere.patches.size(), 1u);
  EXPECT_EQ(expect_closed(sphere, "sphere"), 2);
  std::vector<std::array<double, 2>> params = interior_samples(rng, 2, 3000);
  for (int i = 0; i <= 40; ++i)  // the whole rectangle: poles, seam, knot lines
    for (int j = 0; j <= 40; ++j) params.push_back({i / 40.0, j / 40.0});
  double worst = 0;
  for (const auto& [u, v] : params) {
    const Vec3 d = minus(evaluate(sphere, sphere.patches[0], u, v), c);
    worst = std::max(worst, std::abs(std::sqrt(dot3(d, d)) - r));
  }
  EXPECT_LE(worst, 1e-12 * r);
  EXPECT_GT(worst_normal(sphere, rng, [&](const Vec3&) { return c; }), 0.99);

  const NurbsSurface torus = rn::exact_torus(c, 1.0, 0.3);
  EXPECT_EQ(expect_closed(torus, "torus"), 0);
  worst = 0;
  for (const auto& [u, v] : params) {
    const Vec3 d = minus(evaluate(torus, torus.patches[0], u, v), c);
    worst = std::max(worst, std::abs(std::hypot(std::hypot(d[0], d[1]) - 1.0, d[2]) - 0.3));
  }
  EXPECT_LE(worst, 1e-12);

  const NurbsSurface cube = rn::cube_sphere(c, r);
  EXPECT_EQ(expect_closed(cube, "cube sphere"), 0);
  EXPECT_GT(worst_normal(cube, rng, [&](const Vec3&) { return c; }), 0.5);
}
