#pragma once
// Seeded free-form closed NURBS particles (geometry::NurbsSurface) for the 3D NURBS tests
// (issue #14, docs/nurbs-step-design.md §6), and the exact shapes they start from:
//
//   exact_sphere(c, r)       the exact rational sphere, one biquadratic 9 × 5 patch (u around
//                            z, a seam at u = 0 = 1; v from the south to the north pole, two
//                            poles), built at unit size and placed by scale = r, translate = c
//   exact_torus(c, R, r)     the exact torus around z, one biquadratic 9 × 9 patch (seams both
//                            ways), control points built with R and r, translate = c
//   cube_sphere(c, r)        six bicubic Bézier patches: the cube [-1, 1]³'s faces, each a
//                            uniform 4 × 4 grid projected onto the unit sphere (p / |p|),
//                            weights empty (all 1), scale = r, translate = c
//   random_particle(rng, kind, c, radius)
//     perturbed_sphere       exact_sphere with the rows between the poles moved radially by a
//                            smooth field in [0.85, 1.15] and their weights multiplied by a
//                            smooth field in [0.7, 1.4]; the pole rows stay, the seam column
//                            u = 1 is a copy of u = 0
//     perturbed_torus        the torus R = 0.7, r = 0.3 with the tube radius at each control
//                            point scaled by a smooth periodic field in [0.85, 1.15] and the
//                            weights by one in [0.7, 1.4]; the last row and column are copies
//                            of the first
//     cube_sphere            cube_sphere with every distinct control point moved radially by a
//                            smooth field in [0.85, 1.15] (each cube point computed once and
//                            shared, so neighbouring patches keep bit-identical boundaries)
//                            and the weights of each face's 2 × 2 interior points multiplied by
//                            factors in [0.7, 1.4]
//   each at unit size, placed by scale = radius and translate = centre: the placed control
//   points lie within 1.15·radius of the centre in each coordinate.
//
// The same files data/shapes/make_nurbs.py writes (nurbs_sphere.json, nurbs_torus.json with
// R = 1, r = 0.3, nurbs_cubesphere.json) are exact_sphere({0, 0, 0}, 1), exact_torus({0, 0,
// 0}, 1, 0.3) and cube_sphere({0, 0, 0}, 1) bit for bit. S_u × S_v points outwards. Random
// numbers come from the bits of std::mt19937_64 (no std distributions), so a seed gives the
// same particle with every standard library.
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include "geometry/scene.hpp"

namespace cisamr::testing::nurbs3 {

enum class Kind { perturbed_sphere, perturbed_torus, cube_sphere };
inline constexpr std::array<Kind, 3> kKinds = {Kind::perturbed_sphere, Kind::perturbed_torus, Kind::cube_sphere};
inline const char* kind_name(Kind k) {
  switch (k) {
    case Kind::perturbed_sphere: return "perturbed_sphere";
    case Kind::perturbed_torus: return "perturbed_torus";
    case Kind::cube_sphere: return "cube_sphere";
  }
  return "?";
}

namespace detail {

inline constexpr double kHalf = 0.7071067811865476;  // √2/2 = std::sqrt(0.5), correctly rounded
// The unit circle as a rational quadratic: 9 control points (x, y, w), knots with it.
inline constexpr double kCircle[9][3] = {{1, 0, 1},   {1, 1, kHalf},   {0, 1, 1},  {-1, 1, kHalf}, {-1, 0, 1},
                                         {-1, -1, kHalf}, {0, -1, 1}, {1, -1, kHalf}, {1, 0, 1}};
inline const std::vector<double> kCircleKnots = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};
// The half circle from the south to the north pole: (ρ, z, w).
inline constexpr double kHalfCircle[5][3] = {{0, -1, 1}, {1, -1, kHalf}, {1, 0, 1}, {1, 1, kHalf}, {0, 1, 1}};
inline const std::vector<double> kHalfKnots = {0, 0, 0, 0.5, 0.5, 1, 1, 1};

// w_a·w_b, with the product of two √2/2 the exact 1/2.
inline double weight(double a, double b) { return a == kHalf && b == kHalf ? 0.5 : a * b; }

// Uniform in [lo, hi] from 53 bits of the generator.
inline double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
}

// A smooth field g in [-1, 1]: Σ a_k·sin(f_k·x + φ_k) with Σ |a_k| = 1 and moderate
// frequencies, evaluated at a point of the unit sphere (or at angles, for the torus).
struct SmoothField {
  static constexpr int kTerms = 4;
  std::array<Vec3, kTerms> frequency{};
  std::array<double, kTerms> amplitude{}, phase{};

  SmoothField(std::mt19937_64& rng, double max_frequency, bool integer_frequencies) {
    double total = 0;
    for (int k = 0; k < kTerms; ++k) {
      for (int d = 0; d < 3; ++d) {
        const double f = uniform(rng, -max_frequency, max_frequency);
        frequency[k][d] = integer_frequencies ? std::round(f) : f;  // integers: 2π-periodic in angles
      }
      amplitude[k] = uniform(rng, 0.2, 1.0);
      phase[k] = uniform(rng, 0, 6.283185307179586);
      total += amplitude[k];
    }
    for (double& a : amplitude) a /= total;
  }
  double operator()(const Vec3& x) const {
    double g = 0;
    for (int k = 0; k < kTerms; ++k)
      g += amplitude[k] * std::sin(frequency[k][0] * x[0] + frequency[k][1] * x[1] + frequency[k][2] * x[2] + phase[k]);
    return std::fmax(-1.0, std::fmin(1.0, g));
  }
};

inline Vec3 scaled(const Vec3& x, double s) { return {x[0] * s, x[1] * s, x[2] * s}; }
inline Vec3 unit(const Vec3& x) {
  return scaled(x, 1 / std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]));
}

// The unit sphere's patch (no placement). Pole rows are 9 copies of (0, 0, ∓1) (+0.0).
inline geometry::NurbsPatch unit_sphere_patch() {
  geometry::NurbsPatch p;
  p.degree = {2, 2};
  p.knots_u = kCircleKnots;
  p.knots_v = kHalfKnots;
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 9; ++i) {
      const double rho = kHalfCircle[j][0], z = kHalfCircle[j][1];
      p.control_points.push_back(rho == 0 ? Vec3{0, 0, z}
                                          : Vec3{rho * kCircle[i][0], rho * kCircle[i][1], z});
      p.weights.push_back(weight(kCircle[i][2], kHalfCircle[j][2]));
    }
  return p;
}

// The torus patch around z through the origin, with the tube radius at control point (i, j)
// scaled by tube[i][j] (1: exact), in the operation order of make_nurbs.py.
inline geometry::NurbsPatch torus_patch(double R, double r, const double (*tube)[9] = nullptr) {
  geometry::NurbsPatch p;
  p.degree = {2, 2};
  p.knots_u = p.knots_v = kCircleKnots;
  for (int j = 0; j < 9; ++j)
    for (int i = 0; i < 9; ++i) {
      const double t = tube ? r * tube[i][j] : r;
      const double rho = R + t * kCircle[j][0];
      p.control_points.push_back({rho * kCircle[i][0], rho * kCircle[i][1], t * kCircle[j][1]});
      p.weights.push_back(weight(kCircle[i][2], kCircle[j][2]));
    }
  return p;
}

// The six cube-sphere patches at unit size; map_point(x) maps each projected cube point (once per
// distinct point: neighbours share the result).
template <class Map>
std::vector<geometry::NurbsPatch> cube_sphere_patches(const Map& map_point) {
  static constexpr int kGrid[4] = {-3, -1, 1, 3};  // the face grid in thirds
  std::map<std::array<int, 3>, Vec3> points;
  const auto point = [&](const std::array<int, 3>& key) {
    auto it = points.find(key);
    if (it == points.end()) {
      const Vec3 c{key[0] / 3.0, key[1] / 3.0, key[2] / 3.0};
      const double n = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
      it = points.emplace(key, map_point(Vec3{c[0] / n, c[1] / n, c[2] / n})).first;
    }
    return it->second;
  };
  std::vector<geometry::NurbsPatch> patches;
  for (int axis = 0; axis < 3; ++axis)
    for (int sign : {1, -1}) {
      // e1 × e2 = sign·axis: S_u × S_v points outwards.
      const int e1 = sign > 0 ? (axis + 1) % 3 : (axis + 2) % 3, e2 = sign > 0 ? (axis + 2) % 3 : (axis + 1) % 3;
      geometry::NurbsPatch p;
      p.degree = {3, 3};
      p.knots_u = p.knots_v = {0, 0, 0, 0, 1, 1, 1, 1};
      for (int b : kGrid)
        for (int a : kGrid) {
          std::array<int, 3> key{};
          key[static_cast<std::size_t>(axis)] = 3 * sign;
          key[static_cast<std::size_t>(e1)] = a;
          key[static_cast<std::size_t>(e2)] = b;
          p.control_points.push_back(point(key));
        }
      patches.push_back(std::move(p));  // weights empty: all 1
    }
  return patches;
}

inline geometry::NurbsSurface placed(std::vector<geometry::NurbsPatch> patches, const Vec3& centre,
                                     double scale) {
  geometry::NurbsSurface s;
  s.patches = std::move(patches);
  s.scale = scale;
  s.translate = centre;
  return s;
}

}  // namespace detail

inline geometry::NurbsSurface exact_sphere(const Vec3& c, double r) {
  return detail::placed({detail::unit_sphere_patch()}, c, r);
}

inline geometry::NurbsSurface exact_torus(const Vec3& c, double R, double r) {
  return detail::placed({detail::torus_patch(R, r)}, c, 1);
}

inline geometry::NurbsSurface cube_sphere(const Vec3& c, double r) {
  return detail::placed(detail::cube_sphere_patches([](const Vec3& x) { return x; }), c, r);
}

inline geometry::NurbsSurface random_particle(std::mt19937_64& rng, Kind kind, const Vec3& centre,
                                              double radius) {
  using detail::SmoothField;
  constexpr double kRadial = 0.15;                   // radial factors in [0.85, 1.15]
  constexpr double kWeightMid = 1.05, kWeightAmp = 0.35;  // weight factors in [0.7, 1.4]
  switch (kind) {
    case Kind::perturbed_sphere: {
      const SmoothField radial(rng, 1.5, false), weights(rng, 1.5, false);
      geometry::NurbsPatch p = detail::unit_sphere_patch();
      for (std::size_t j = 1; j < 4; ++j) {  // rows between the poles
        for (std::size_t i = 0; i < 8; ++i) {
          const std::size_t k = i + 9 * j;
          const Vec3 direction = detail::unit(p.control_points[k]);
          p.control_points[k] = detail::scaled(p.control_points[k], 1 + kRadial * radial(direction));
          p.weights[k] *= kWeightMid + kWeightAmp * weights(direction);
        }
        p.control_points[8 + 9 * j] = p.control_points[9 * j];  // the seam: u = 1 is u = 0
        p.weights[8 + 9 * j] = p.weights[9 * j];
      }
      return detail::placed({std::move(p)}, centre, radius);
    }
    case Kind::perturbed_torus: {
      // Fields over the angles (θ around z, φ around the tube), 2π-periodic: integer
      // frequencies in θ and φ (the third component is unused).
      const SmoothField radial(rng, 2.4, true), weights(rng, 2.4, true);
      double tube[9][9];
      std::array<std::array<double, 9>, 9> factor{};
      for (int i = 0; i < 9; ++i)
        for (int j = 0; j < 9; ++j) {
          const int a = i % 8, b = j % 8;  // the last row and column repeat the first
          const Vec3 angles{a * 0.7853981633974483, b * 0.7853981633974483, 0};
          tube[i][j] = 1 + kRadial * radial(angles);
          factor[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] = kWeightMid + kWeightAmp * weights(angles);
        }
      geometry::NurbsPatch p = detail::torus_patch(0.7, 0.3, tube);
      for (std::size_t j = 0; j < 9; ++j)
        for (std::size_t i = 0; i < 9; ++i) p.weights[i + 9 * j] *= factor[i][j];
      return detail::placed({std::move(p)}, centre, radius);
    }
    case Kind::cube_sphere: {
      const SmoothField radial(rng, 1.5, false);
      std::vector<geometry::NurbsPatch> patches = detail::cube_sphere_patches(
          [&](const Vec3& x) { return detail::scaled(x, 1 + kRadial * radial(x)); });
      for (geometry::NurbsPatch& p : patches) {
        p.weights.assign(16, 1.0);
        for (std::size_t k : {5u, 6u, 9u, 10u}) p.weights[k] = detail::uniform(rng, 0.7, 1.4);  // the 2 × 2 interior
      }
      return detail::placed(std::move(patches), centre, radius);
    }
  }
  return {};
}

}  // namespace cisamr::testing::nurbs3
