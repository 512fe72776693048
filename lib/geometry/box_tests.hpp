#pragma once
// Box tests shared by the oracles and the NURBS code (private to lib/geometry).
#include <algorithm>
#include <type_traits>
#include <utility>

#include "core/types.hpp"

namespace cisamr::geometry::detail {

// Does the segment [u, v] meet the closed box? (Liang–Barsky; rounding-level slack is
// added by the callers that need conservativeness.)
inline bool segment_meets_box(const Vec2& u, const Vec2& v, const Box2& b) {
  double t0 = 0, t1 = 1;
  const double d[2] = {v[0] - u[0], v[1] - u[1]};
  for (int k = 0; k < 2; ++k) {
    if (d[k] == 0) {
      if (u[k] < b.min[k] || u[k] > b.max[k]) return false;
    } else {
      double ta = (b.min[k] - u[k]) / d[k], tb = (b.max[k] - u[k]) / d[k];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      if (t0 > t1) return false;
    }
  }
  return true;
}

// Does the circle (2D) or sphere (3D) |x − c| = r meet the closed box? It does iff
// dist_min(c, box) ≤ r ≤ dist_max(c, box) (with 1e-12 relative slack).
template <int Dim>
bool sphere_meets_box(const std::type_identity_t<Vec<Dim>>& c, double r, const Box<Dim>& box) {
  double near2 = 0, far2 = 0;
  for (int d = 0; d < Dim; ++d) {
    const double lo = box.min[d] - c[d], hi = box.max[d] - c[d];
    const double nd = lo > 0 ? lo : (hi < 0 ? hi : 0);
    near2 += nd * nd;
    far2 += std::max(lo * lo, hi * hi);
  }
  const double r2 = r * r;
  return near2 <= r2 * (1 + 1e-12) && r2 <= far2 * (1 + 1e-12);
}

}  // namespace cisamr::geometry::detail
