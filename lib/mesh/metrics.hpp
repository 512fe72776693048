#pragma once
// Element measures and the aspect ratio of DESIGN.md §2 (ParaView/Verdict definition):
//   triangle     AR = l_max / (2·√3·r_in),  r_in = 2·Area / perimeter
//   tetrahedron  AR = l_max / (2·√6·r_in),  r_in = 3·Volume / (sum of face areas)
// 1 for the equilateral triangle / regular tetrahedron; +inf for a degenerate element.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/types.hpp"

namespace cisamr::mesh {

inline double signed_area(const Vec2& a, const Vec2& b, const Vec2& c) {
  return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
}

inline double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
          u[2] * (v[0] * w[1] - v[1] * w[0])) / 6.0;
}

template <int Dim>
inline double distance(const Vec<Dim>& a, const Vec<Dim>& b) {
  double s = 0;
  for (int d = 0; d < Dim; ++d) s += (a[d] - b[d]) * (a[d] - b[d]);
  return std::sqrt(s);
}

inline double aspect_ratio(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double lab = distance<2>(a, b), lbc = distance<2>(b, c), lca = distance<2>(c, a);
  const double area = std::abs(signed_area(a, b, c));
  if (!(area > 0)) return std::numeric_limits<double>::infinity();
  const double r_in = 2.0 * area / (lab + lbc + lca);
  return std::max({lab, lbc, lca}) / (2.0 * std::sqrt(3.0) * r_in);
}

inline double triangle_area_3d(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2],
               z = u[0] * v[1] - u[1] * v[0];
  return 0.5 * std::sqrt(x * x + y * y + z * z);
}

// The aspect ratio of tetrahedron (a, b, c, d) given the sum of its face areas, in the
// order area(bcd) + area(acd) + area(abd) + area(abc) (quality's statistics pass the areas
// of the cross products they compute for the dihedral angles: the same value, bit for bit).
inline double aspect_ratio_with_faces(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double faces) {
  const double volume = std::abs(signed_volume(a, b, c, d));
  if (!(volume > 0)) return std::numeric_limits<double>::infinity();
  const double r_in = 3.0 * volume / faces;
  const auto sq = [](const Vec3& x, const Vec3& y) {
    return (x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) + (x[2] - y[2]) * (x[2] - y[2]);
  };
  const double l_max = std::sqrt(std::max({sq(a, b), sq(a, c), sq(a, d), sq(b, c), sq(b, d), sq(c, d)}));
  return l_max / (2.0 * std::sqrt(6.0) * r_in);
}

inline double aspect_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return aspect_ratio_with_faces(a, b, c, d,
                                 triangle_area_3d(b, c, d) + triangle_area_3d(a, c, d) + triangle_area_3d(a, b, d) +
                                     triangle_area_3d(a, b, c));
}

// Is tetrahedron (a, b, c, d) positively oriented with aspect_ratio(a, b, c, d) ≤ bound?
// With AR = l_max·F / (√6·6V) (F the sum of face areas), 5 square roots instead of 10. The
// test is stricter than the bound by a relative 1e-9, so that a tet it accepts passes any
// later evaluation of aspect_ratio() despite round-off.
inline bool positive_within(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double bound) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  const double six_volume = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                            u[2] * (v[0] * w[1] - v[1] * w[0]);
  if (!(six_volume > 0)) return false;
  const auto norm2_cross = [](const double* x, const double* y) {
    const double p = x[1] * y[2] - x[2] * y[1], q = x[2] * y[0] - x[0] * y[2], r = x[0] * y[1] - x[1] * y[0];
    return p * p + q * q + r * r;
  };
  const double bc[3] = {c[0] - b[0], c[1] - b[1], c[2] - b[2]};
  const double bd[3] = {d[0] - b[0], d[1] - b[1], d[2] - b[2]};
  const double cd[3] = {d[0] - c[0], d[1] - c[1], d[2] - c[2]};
  const double n0 = norm2_cross(u, v), n1 = norm2_cross(u, w), n2 = norm2_cross(v, w), n3 = norm2_cross(bc, bd);
  const auto sq = [](const double* x) { return x[0] * x[0] + x[1] * x[1] + x[2] * x[2]; };
  const double l2 = std::max({sq(u), sq(v), sq(w), sq(bc), sq(bd), sq(cd)});
  const double limit = bound * (1 - 1e-9) * std::sqrt(6.0) * six_volume;
  // Without square roots first: Σ√nᵢ ≤ 2·√Σnᵢ, so l2·Σnᵢ ≤ limit² proves the test below
  // (most tets pass with room). The 1e-6 margin dwarfs the round-off of both sides, so the
  // verdict is the one the exact test gives.
  if (l2 * (n0 + n1 + n2 + n3) <= limit * limit * (1 - 1e-6)) return true;
  const double faces = 0.5 * (std::sqrt(n0) + std::sqrt(n1) + std::sqrt(n2) + std::sqrt(n3));
  return std::sqrt(l2) * faces <= limit;
}

// positive_within for two tetrahedra at once, (a0, b0, c0, d0) and (a1, b1, c1, d1): the
// same operations in the same order on the two lanes of a vector of two doubles (IEEE
// arithmetic lane by lane, no fused multiply-add on the baseline target), so each verdict
// is positive_within's bit for bit; the square roots of the rare exact test per lane. The
// snapping guard evaluates a split's sub-tets in pairs with it.
inline std::array<bool, 2> positive_within_pair(const std::array<const Vec3*, 4>& t0, const std::array<const Vec3*, 4>& t1,
                                                double bound) {
  using Pair = double __attribute__((vector_size(16)));
  const auto lane = [&](int point, int d) { return Pair{(*t0[static_cast<std::size_t>(point)])[static_cast<std::size_t>(d)], (*t1[static_cast<std::size_t>(point)])[static_cast<std::size_t>(d)]}; };
  const Pair a[3] = {lane(0, 0), lane(0, 1), lane(0, 2)}, b[3] = {lane(1, 0), lane(1, 1), lane(1, 2)},
             c[3] = {lane(2, 0), lane(2, 1), lane(2, 2)}, d[3] = {lane(3, 0), lane(3, 1), lane(3, 2)};
  const Pair u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const Pair v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const Pair w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  const Pair six_volume = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                          u[2] * (v[0] * w[1] - v[1] * w[0]);
  const auto norm2_cross = [](const Pair* x, const Pair* y) {
    const Pair p = x[1] * y[2] - x[2] * y[1], q = x[2] * y[0] - x[0] * y[2], r = x[0] * y[1] - x[1] * y[0];
    return p * p + q * q + r * r;
  };
  const Pair bc[3] = {c[0] - b[0], c[1] - b[1], c[2] - b[2]};
  const Pair bd[3] = {d[0] - b[0], d[1] - b[1], d[2] - b[2]};
  const Pair cd[3] = {d[0] - c[0], d[1] - c[1], d[2] - c[2]};
  const Pair n0 = norm2_cross(u, v), n1 = norm2_cross(u, w), n2 = norm2_cross(v, w), n3 = norm2_cross(bc, bd);
  const auto sq = [](const Pair* x) { return x[0] * x[0] + x[1] * x[1] + x[2] * x[2]; };
  // std::max's order of comparisons, lane by lane (ties and NaN-free inputs give the same value).
  const auto larger = [](Pair x, Pair y) { return x < y ? y : x; };
  const Pair l2 = larger(larger(larger(larger(larger(sq(u), sq(v)), sq(w)), sq(bc)), sq(bd)), sq(cd));
  const Pair limit = bound * (1 - 1e-9) * std::sqrt(6.0) * six_volume;
  const Pair lhs = l2 * (n0 + n1 + n2 + n3), rhs = limit * limit * (1 - 1e-6);
  std::array<bool, 2> good{};
  for (int k = 0; k < 2; ++k) {
    if (!(six_volume[k] > 0)) continue;
    if (lhs[k] <= rhs[k]) {
      good[static_cast<std::size_t>(k)] = true;
      continue;
    }
    const double faces = 0.5 * (std::sqrt(n0[k]) + std::sqrt(n1[k]) + std::sqrt(n2[k]) + std::sqrt(n3[k]));
    good[static_cast<std::size_t>(k)] = std::sqrt(l2[k]) * faces <= limit[k];
  }
  return good;
}

// Aspect ratio of cell c of a mesh.
template <class MeshT>
inline double cell_aspect_ratio(const MeshT& m, std::size_t c) {
  const LocalId* n = m.cell(c);
  if constexpr (MeshT::dim == 2)
    return aspect_ratio(m.point(n[0]), m.point(n[1]), m.point(n[2]));
  else
    return aspect_ratio(m.point(n[0]), m.point(n[1]), m.point(n[2]), m.point(n[3]));
}

}  // namespace cisamr::mesh
