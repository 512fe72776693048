#include "pack/convex.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/vec_math.hpp"

namespace cisamr::pack {
namespace {


// Closest point to the origin of the convex hull of `w` (1 to 4 points), by enumerating
// the sub-simplices (Johnson's sub-algorithm, written as a brute-force search: at most 15
// subsets, each a k×k solve with k ≤ 3). Keeps in `w` only the points of the sub-simplex
// that realises the minimum.
Vec3 closest_on_simplex(std::vector<Vec3>& w) {
  const int n = static_cast<int>(w.size());
  double best = INFINITY;
  Vec3 best_point{};
  unsigned best_mask = 1;
  for (unsigned mask = 1; mask < (1u << n); ++mask) {
    int idx[4] = {0, 0, 0, 0}, k = 0;
    for (int i = 0; i < n; ++i)
      if (mask & (1u << i)) idx[k++] = i;
    const Vec3& p0 = w[idx[0]];
    Vec3 x = p0;
    if (k > 1) {
      // Minimise |p0 + Σ μ_i e_i| : G μ = -Eᵀ p0.
      const int m = k - 1;
      double g[3][4];
      Vec3 e[3];
      for (int i = 0; i < m; ++i) e[i] = sub(w[idx[i + 1]], p0);
      for (int i = 0; i < m; ++i) {
        for (int j = 0; j < m; ++j) g[i][j] = dot(e[i], e[j]);
        g[i][m] = -dot(e[i], p0);
      }
      double diag_scale = 0;
      for (int i = 0; i < m; ++i) diag_scale = std::max(diag_scale, g[i][i]);
      bool singular = false;
      for (int c = 0; c < m && !singular; ++c) {
        int piv = c;
        for (int r = c + 1; r < m; ++r)
          if (std::abs(g[r][c]) > std::abs(g[piv][c])) piv = r;
        if (std::abs(g[piv][c]) <= 1e-14 * diag_scale) { singular = true; break; }
        if (piv != c)
          for (int j = 0; j <= m; ++j) std::swap(g[c][j], g[piv][j]);
        for (int r = 0; r < m; ++r) {
          if (r == c) continue;
          const double f = g[r][c] / g[c][c];
          for (int j = c; j <= m; ++j) g[r][j] -= f * g[c][j];
        }
      }
      if (singular) continue;
      double mu[3], sum = 0;
      bool inside = true;
      for (int i = 0; i < m; ++i) {
        mu[i] = g[i][m] / g[i][i];
        sum += mu[i];
        if (!(mu[i] > 0)) inside = false;
      }
      if (!inside || !(sum < 1)) continue;
      for (int i = 0; i < m; ++i) x = add(x, scale(e[i], mu[i]));
    }
    const double d = dot(x, x);
    if (d < best) { best = d; best_point = x; best_mask = mask; }
  }
  std::vector<Vec3> kept;
  for (int i = 0; i < n; ++i)
    if (best_mask & (1u << i)) kept.push_back(w[i]);
  w.swap(kept);
  return best_point;
}

// Support of the Minkowski difference (a + oa) − (b + ob) along d.
Vec3 support_difference(const ConvexBody& a, const Vec3& oa, const ConvexBody& b,
                        const Vec3& ob, const Vec3& d) {
  return sub(a.support(d, oa), b.support(scale(d, -1), ob));
}

enum class Verdict { within, separated, converged };

// GJK on the Minkowski difference. Stops as soon as the bounds decide "distance < gap" or
// "distance ≥ gap"; when deciding is not asked (gap < 0) it runs until the bounds meet
// within `tolerance`.
Verdict gjk(const ConvexBody& a, const Vec3& oa, const ConvexBody& b, const Vec3& ob,
            double gap, double tolerance, DistanceBounds* bounds) {
  Vec3 dir = sub(add(b.reference, ob), add(a.reference, oa));
  if (dot(dir, dir) == 0) dir = {1, 0, 0};
  std::vector<Vec3> w{support_difference(a, oa, b, ob, dir)};
  double lower = 0;
  for (int iter = 0; iter < 96; ++iter) {
    const Vec3 x = closest_on_simplex(w);
    const double upper = norm(x);
    if (bounds) *bounds = {lower, upper};
    if (upper <= tolerance * 1e-3) { if (bounds) *bounds = {0, upper}; return Verdict::within; }
    if (gap >= 0 && upper < gap) return Verdict::within;
    const Vec3 s = support_difference(a, oa, b, ob, scale(x, -1));
    lower = std::max(lower, dot(s, x) / upper);
    if (bounds) *bounds = {lower, upper};
    if (gap >= 0 && lower >= gap + tolerance) return Verdict::separated;
    if (upper - lower <= tolerance) return Verdict::converged;
    if (w.size() >= 4) return Verdict::converged;  // degenerate: cannot grow the simplex
    w.push_back(s);
  }
  return Verdict::converged;
}

}  // namespace

Vec3 ConvexBody::support(const Vec3& d, const Vec3& offset) const {
  switch (kind) {
    case Kind::ball: {
      const double n = norm(d);
      if (n == 0) return add(center, offset);
      return add(add(center, offset), scale(d, radius / n));
    }
    case Kind::ellipsoid: {
      // Body frame: d_b = Rᵀ d; s_b = D² d_b / |D d_b|; world = c + R s_b.
      Vec3 db{}, dd{};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) db[i] += rotation[j][i] * d[j];
      double n2 = 0;
      for (int i = 0; i < 3; ++i) { dd[i] = semi_axes[i] * db[i]; n2 += dd[i] * dd[i]; }
      Vec3 p = add(center, offset);
      if (n2 == 0) return p;
      const double inv = 1.0 / std::sqrt(n2);
      for (int i = 0; i < 3; ++i) {
        const double sb = semi_axes[i] * dd[i] * inv;
        for (int j = 0; j < 3; ++j) p[j] += rotation[j][i] * sb;
      }
      return p;
    }
    case Kind::cylinder: {
      Vec3 u = sub(end, center);
      const double len = norm(u);
      u = scale(u, 1.0 / len);
      const double du = dot(d, u);
      Vec3 p = add(du >= 0 ? end : center, offset);
      const Vec3 perp = sub(d, scale(u, du));
      const double np = norm(perp);
      if (np > 1e-300) p = add(p, scale(perp, radius / np));
      return p;
    }
    case Kind::hull: {
      std::size_t best = 0;
      double best_dot = -INFINITY;
      for (std::size_t i = 0; i < points.size(); ++i) {
        const double v = dot(points[i], d);
        if (v > best_dot) { best_dot = v; best = i; }
      }
      return add(points[best], offset);
    }
  }
  return center;
}

bool convex_within(const ConvexBody& a, const Vec3& offset_a, const ConvexBody& b,
                   const Vec3& offset_b, double gap) {
  const double tolerance = 1e-10 * std::max(a.bound_radius, b.bound_radius) + 1e-300;
  return gjk(a, offset_a, b, offset_b, gap, tolerance, nullptr) != Verdict::separated;
}

DistanceBounds convex_distance(const ConvexBody& a, const Vec3& offset_a, const ConvexBody& b,
                               const Vec3& offset_b, double tolerance) {
  DistanceBounds bounds;
  gjk(a, offset_a, b, offset_b, -1, tolerance, &bounds);
  return bounds;
}

}  // namespace cisamr::pack
