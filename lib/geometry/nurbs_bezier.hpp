#pragma once
// Rational B-splines as rational Bézier pieces, in homogeneous coordinates (private to
// lib/geometry): knot insertion up to Bézier form, and de Casteljau on one piece. Shared
// by the 2D curves (nurbs2.cpp, C = 3: w·x, w·y, w) and the 3D surface patches
// (nurbs3.cpp, C = 4: w·x, w·y, w·z, w). The operation order is part of the contract:
// 2D meshes are pinned bit for bit (tests/regression), so a change here must keep it.
#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

namespace cisamr::geometry::nurbs {

// The Bézier pieces of a B-spline of degree p, in the order of its knot spans.
template <int C>
struct BezierPieces {
  std::vector<std::vector<double>> points;  // per piece: C·(p+1) homogeneous coordinates
  std::vector<std::array<double, 2>> spans; // per piece: its knot interval [U_k, U_k+1]
};

// Knot insertion (Boehm) until every knot value in [U_p, U_n] has multiplicity ≥ p, then
// one piece per non-empty span inside [U_p, U_n]. Clamped or not is the same case: the
// ends are raised to multiplicity p too, which clamps them. Expects degree ≥ 1, knots of
// size P.size() + p + 1, non-decreasing, U_p < U_n (the caller validates).
template <int C>
BezierPieces<C> extract_bezier(int p, std::vector<double> U, std::vector<std::array<double, C>> P) {
  const std::size_t n = P.size();
  const double u_lo = U[static_cast<std::size_t>(p)], u_hi = U[n];
  std::vector<double> values;
  for (double u : U)
    if (u >= u_lo && u <= u_hi && (values.empty() || values.back() != u)) values.push_back(u);
  for (double u : values) {
    int mult = static_cast<int>(std::count(U.begin(), U.end(), u));
    for (; mult < p; ++mult) {
      // Span k with U[k] ≤ u ≤ U[k+1] inside the domain: the one to the right of u_lo,
      // to the left of every other value (keeps k ≤ n − 1 at u = u_hi).
      const auto it = u == u_lo ? std::upper_bound(U.begin(), U.end(), u) : std::lower_bound(U.begin(), U.end(), u);
      const std::size_t k = static_cast<std::size_t>(it - U.begin()) - 1;
      std::vector<std::array<double, C>> Q(P.size() + 1);
      for (std::size_t i = 0; i < Q.size(); ++i) {
        if (i + p <= k) Q[i] = P[i];
        else if (i > k) Q[i] = P[i - 1];
        else {
          const double alpha = (u - U[i]) / (U[i + p] - U[i]);
          for (int c = 0; c < C; ++c) Q[i][c] = alpha * P[i][c] + (1 - alpha) * P[i - 1][c];
        }
      }
      U.insert(U.begin() + static_cast<std::ptrdiff_t>(k) + 1, u);
      P.swap(Q);
    }
  }
  BezierPieces<C> out;
  for (std::size_t k = static_cast<std::size_t>(p); k + 1 < U.size() && k < P.size(); ++k) {
    if (!(U[k] < U[k + 1]) || U[k] < u_lo || U[k + 1] > u_hi) continue;
    std::vector<double> h;
    h.reserve(static_cast<std::size_t>(C * (p + 1)));
    for (std::size_t i = k - p; i <= k; ++i) h.insert(h.end(), P[i].begin(), P[i].end());
    out.points.push_back(std::move(h));
    out.spans.push_back({U[k], U[k + 1]});
  }
  return out;
}

// Halves a piece at s = 1/2: left and right share the middle point bit for bit. `h`
// may alias neither output.
template <int C>
void split_half(const double* h, int p, double* left, double* right) {
  double tmp[C * 32];  // degree ≤ 31
  std::copy(h, h + C * (p + 1), tmp);
  for (int r = 0; r <= p; ++r) {
    for (int c = 0; c < C; ++c) {
      left[C * r + c] = tmp[c];
      right[C * (p - r) + c] = tmp[C * (p - r) + c];
    }
    for (int i = 0; i < p - r; ++i)
      for (int c = 0; c < C; ++c) tmp[C * i + c] = 0.5 * (tmp[C * i + c] + tmp[C * (i + 1) + c]);
  }
}

// Splits a piece at s ∈ [0, 1]: left covers [0, s], right [s, 1] (either may be null).
template <int C>
void split_at(const double* h, int p, double s, double* left, double* right) {
  double tmp[C * 32];
  std::copy(h, h + C * (p + 1), tmp);
  for (int r = 0; r <= p; ++r) {
    for (int c = 0; c < C; ++c) {
      if (left) left[C * r + c] = tmp[c];
      if (right) right[C * (p - r) + c] = tmp[C * (p - r) + c];
    }
    for (int i = 0; i < p - r; ++i)
      for (int c = 0; c < C; ++c) tmp[C * i + c] = (1 - s) * tmp[C * i + c] + s * tmp[C * (i + 1) + c];
  }
}

// Homogeneous point H(s) and derivative H'(s) of a piece (de Casteljau to the last two
// points). The Cartesian derivative is (H' − x·H'_w) / H_w.
template <int C>
void eval_hom(const double* h, int p, double s, double* H, double* D) {
  double tmp[C * 32];
  std::copy(h, h + C * (p + 1), tmp);
  for (int r = 1; r < p; ++r)
    for (int i = 0; i <= p - r; ++i)
      for (int k = 0; k < C; ++k) tmp[C * i + k] = (1 - s) * tmp[C * i + k] + s * tmp[C * (i + 1) + k];
  for (int k = 0; k < C; ++k) {
    H[k] = (1 - s) * tmp[k] + s * tmp[C + k];
    D[k] = p * (tmp[C + k] - tmp[k]);
  }
}

// 16-point Gauss–Legendre on [0, 1] (the areas and volumes of curves and surfaces).
template <class F>
double gauss16(F&& f) {
  static const double x[8] = {0.0950125098376374, 0.2816035507792589, 0.4580167776572274, 0.6178762444026438,
                              0.7554044083550030, 0.8656312023878318, 0.9445750230732326, 0.9894009349916499};
  static const double w[8] = {0.1894506104550685, 0.1826034150449236, 0.1691565193950025, 0.1495959888165767,
                              0.1246289712555339, 0.0951585116824928, 0.0622535239386479, 0.0271524594117541};
  double s = 0;
  for (int i = 0; i < 8; ++i) s += w[i] * (f(0.5 - 0.5 * x[i]) + f(0.5 + 0.5 * x[i]));
  return 0.5 * s;
}

}  // namespace cisamr::geometry::nurbs
