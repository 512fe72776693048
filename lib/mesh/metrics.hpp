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

namespace detail {

// positive_within's arithmetic, written once for T = double and for a vector of two doubles
// (one tet per lane, positive_within_pair), so that both do the same operations in the same
// order: the tet's edge vectors from its corners (each a 3-array of T). Always inlined: the
// guard calls these tens of millions of times, and a call costs as much as a test.
template <class T>
struct TetEdges {
  T u[3], v[3], w[3], bc[3], bd[3], cd[3];  // b − a, c − a, d − a, c − b, d − b, d − c
};
template <class T, class Point>
[[gnu::always_inline]] inline TetEdges<T> tet_edges(const Point& a, const Point& b, const Point& c, const Point& d) {
  TetEdges<T> e;
  for (int k = 0; k < 3; ++k) {
    e.u[k] = b[k] - a[k], e.v[k] = c[k] - a[k], e.w[k] = d[k] - a[k];
    e.bc[k] = c[k] - b[k], e.bd[k] = d[k] - b[k], e.cd[k] = d[k] - c[k];
  }
  return e;
}
template <class T>
[[gnu::always_inline]] inline T six_volume(const TetEdges<T>& e) {
  const T *u = e.u, *v = e.v, *w = e.w;
  return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}
// The squared norms of the four faces' cross products (twice their areas, squared) and the
// longest edge's squared length.
template <class T>
[[gnu::always_inline]] inline void face_and_edge_terms(const TetEdges<T>& e, T (&n)[4], T& l2) {
  const auto norm2_cross = [](const T* x, const T* y) {
    const T p = x[1] * y[2] - x[2] * y[1], q = x[2] * y[0] - x[0] * y[2], r = x[0] * y[1] - x[1] * y[0];
    return p * p + q * q + r * r;
  };
  n[0] = norm2_cross(e.u, e.v), n[1] = norm2_cross(e.u, e.w), n[2] = norm2_cross(e.v, e.w), n[3] = norm2_cross(e.bc, e.bd);
  const auto sq = [](const T* x) { return x[0] * x[0] + x[1] * x[1] + x[2] * x[2]; };
  // std::max's choice lane by lane (the larger; the first of equals, the same value).
  const auto larger = [](T x, T y) { return x < y ? y : x; };
  l2 = larger(larger(larger(larger(larger(sq(e.u), sq(e.v)), sq(e.w)), sq(e.bc)), sq(e.bd)), sq(e.cd));
}
inline double limit_of(double bound) { return bound * (1 - 1e-9) * std::sqrt(6.0); }
// The exact test once the square-root-free one did not decide (one tet, one lane).
inline bool within_exact(const double (&n)[4], double l2, double limit) {
  const double faces = 0.5 * (std::sqrt(n[0]) + std::sqrt(n[1]) + std::sqrt(n[2]) + std::sqrt(n[3]));
  return std::sqrt(l2) * faces <= limit;
}

}  // namespace detail

// Is tetrahedron (a, b, c, d) positively oriented with aspect_ratio(a, b, c, d) ≤ bound?
// With AR = l_max·F / (√6·6V) (F the sum of face areas), 5 square roots instead of 10. The
// test is stricter than the bound by a relative 1e-9, so that a tet it accepts passes any
// later evaluation of aspect_ratio() despite round-off.
inline bool positive_within(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double bound) {
  const auto e = detail::tet_edges<double>(a, b, c, d);
  const double six_volume = detail::six_volume(e);
  if (!(six_volume > 0)) return false;
  double n[4], l2;
  detail::face_and_edge_terms(e, n, l2);
  const double limit = detail::limit_of(bound) * six_volume;
  // Without square roots first: Σ√nᵢ ≤ 2·√Σnᵢ, so l2·Σnᵢ ≤ limit² proves the test below
  // (most tets pass with room). The 1e-6 margin dwarfs the round-off of both sides, so the
  // verdict is the one the exact test gives.
  if (l2 * (n[0] + n[1] + n[2] + n[3]) <= limit * limit * (1 - 1e-6)) return true;
  return detail::within_exact(n, l2, limit);
}

// positive_within for two tetrahedra at once, t0 and t1 (their corners): the same
// operations (detail::) on the two lanes of a vector of two doubles (IEEE arithmetic lane by
// lane, no fused multiply-add on the baseline target), so each verdict is positive_within's
// bit for bit; the square roots of the rare exact test per lane. The snapping guard
// evaluates a split's sub-tets in pairs with it.
[[gnu::always_inline]] inline std::array<bool, 2> positive_within_pair(const std::array<const Vec3*, 4>& t0, const std::array<const Vec3*, 4>& t1,
                                                double bound) {
  using Pair = double __attribute__((vector_size(16)));
  std::array<std::array<Pair, 3>, 4> corner;
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t k = 0; k < 3; ++k) corner[i][k] = Pair{(*t0[i])[k], (*t1[i])[k]};
  const auto e = detail::tet_edges<Pair>(corner[0], corner[1], corner[2], corner[3]);
  const Pair six_volume = detail::six_volume(e);
  Pair n[4], l2;
  detail::face_and_edge_terms(e, n, l2);
  const Pair limit = detail::limit_of(bound) * six_volume;
  const Pair lhs = l2 * (n[0] + n[1] + n[2] + n[3]), rhs = limit * limit * (1 - 1e-6);
  std::array<bool, 2> good{};
  for (int k = 0; k < 2; ++k) {
    if (!(six_volume[k] > 0)) continue;
    if (lhs[k] <= rhs[k]) {
      good[static_cast<std::size_t>(k)] = true;
      continue;
    }
    const double lane_n[4] = {n[0][k], n[1][k], n[2][k], n[3][k]};
    good[static_cast<std::size_t>(k)] = detail::within_exact(lane_n, l2[k], limit[k]);
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
