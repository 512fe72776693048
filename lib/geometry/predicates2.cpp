// Exact 2D predicates: CGAL's filtered Epick orientation, and for the circle terms a
// static floating-point filter, then interval arithmetic, then exact Mpzf arithmetic.
#include "geometry/predicates2.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Interval_nt.h>
#include <CGAL/Mpzf.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry/predicates_detail.hpp"

namespace cisamr::geometry::exact {
namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
constexpr double kEps = std::numeric_limits<double>::epsilon() * 0.5;  // unit roundoff

template <class NT>
int sign_of(const NT& x) {
  return x > NT(0) ? 1 : (x < NT(0) ? -1 : 0);
}

// F(p) = r² − |p − c|² in the number type NT.
template <class NT>
NT circle_value(const Vec2& p, const Vec2& c, double r) {
  NT dx = NT(p[0]) - NT(c[0]);
  NT dy = NT(p[1]) - NT(c[1]);
  NT rr = NT(r);
  return rr * rr - (dx * dx + dy * dy);
}

}  // namespace

int orientation(const Vec2& a, const Vec2& b, const Vec2& c) {
  return static_cast<int>(
      CGAL::orientation(K::Point_2(a[0], a[1]), K::Point_2(b[0], b[1]), K::Point_2(c[0], c[1])));
}

int circle_side(const Vec2& p, const Vec2& c, double r) {
  // Static filter: |error| ≤ 8u·(r² + dx² + dy²) covers the rounding of the two
  // differences, three products and two sums (first-order bound with slack).
  double dx = p[0] - c[0], dy = p[1] - c[1];
  double rr = r * r, q = dx * dx + dy * dy;
  double f = rr - q;
  double bound = 8 * kEps * (rr + q) + std::numeric_limits<double>::min();
  if (f > bound) return 1;
  if (f < -bound) return -1;
  return sign_of(circle_value<CGAL::Mpzf>(p, c, r));
}

int disks_side(const Vec2& c1, double r1, const Vec2& c2, double r2) {
  const double dx = c2[0] - c1[0], dy = c2[1] - c1[1], rs = r1 + r2;
  const double q = dx * dx + dy * dy, f = rs * rs - q;
  const double bound = 12 * kEps * (rs * rs + q) + std::numeric_limits<double>::min();
  if (f > bound) return 1;
  if (f < -bound) return -1;
  using M = CGAL::Mpzf;
  const M ex = M(c2[0]) - M(c1[0]), ey = M(c2[1]) - M(c1[1]), er = M(r1) + M(r2);
  return static_cast<int>((er * er - (ex * ex + ey * ey)).sign());
}

int polygon_side(std::span<const Vec2> poly, const Vec2& p) {
  const std::size_t n = poly.size();
  bool inside = false;
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Vec2& u = poly[j];
    const Vec2& v = poly[i];
    const double xmin = std::min(u[0], v[0]), xmax = std::max(u[0], v[0]);
    const double ymin = std::min(u[1], v[1]), ymax = std::max(u[1], v[1]);
    const bool in_box = p[0] >= xmin && p[0] <= xmax && p[1] >= ymin && p[1] <= ymax;
    int o = 2;  // not computed yet
    if (in_box) {
      o = orientation(u, v, p);
      if (o == 0) return 0;  // on the closed edge
    }
    // Half-open rule on y: the edge counts when it straddles the horizontal line
    // through p with one end strictly above.
    if ((u[1] > p[1]) != (v[1] > p[1])) {
      if (p[0] > xmax) continue;  // edge entirely left of p: the ray misses it
      if (p[0] < xmin) {
        inside = !inside;
        continue;
      }
      if (o == 2) o = orientation(u, v, p);
      // p is left of the upward edge (or right of the downward one) ⇔ the ray crosses it
      if ((o > 0) == (v[1] > u[1])) inside = !inside;
    }
  }
  return inside ? 1 : -1;
}

bool segments_intersect(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  return CGAL::do_intersect(K::Segment_2(K::Point_2(a[0], a[1]), K::Point_2(b[0], b[1])),
                            K::Segment_2(K::Point_2(c[0], c[1]), K::Point_2(d[0], d[1])));
}

bool segments_cross_properly(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const int o1 = orientation(a, b, c), o2 = orientation(a, b, d);
  if (o1 * o2 >= 0) return false;
  const int o3 = orientation(c, d, a), o4 = orientation(c, d, b);
  return o3 * o4 < 0;
}

CircleSegmentHits circle_hits_from_signs(int f0, int f1, int ed, int fd, int disc,
                                         double ed_value, double dd, double f0_value,
                                         double disc_value) {
  // On the line x(t) = a + t(b−a), F(t) = r² − |x(t) − c|² is a concave quadratic that is
  // positive exactly on (t1, t2). Its apex t* = −ed/dd; t* > 0 ⇔ ed < 0, t* < 1 ⇔ fd > 0.
  CircleSegmentHits h;
  if (disc <= 0) return h;  // misses the circle or only touches it
  const bool apex_after_start = ed < 0, apex_before_end = fd > 0;
  const bool t1_in = (f0 < 0 && apex_after_start) && (f1 > 0 || apex_before_end);
  const bool t2_in = (f0 > 0 || apex_after_start) && (f1 < 0 && apex_before_end);
  h.start_inside = f0 > 0 || (f0 == 0 && apex_after_start);
  if (!t1_in && !t2_in) return h;
  // Stable roots of dd·t² + 2·ed·t − f0 = 0 (product of the roots = −f0/dd).
  const double s = std::sqrt(std::max(disc_value, 0.0));
  double t1, t2;
  if (ed_value <= 0) {
    const double q = -ed_value + s;
    t2 = q / dd;
    t1 = q != 0 ? -f0_value / q : t2;
  } else {
    const double q = -ed_value - s;
    t1 = q / dd;
    t2 = q != 0 ? -f0_value / q : t1;
  }
  const double lo = std::numeric_limits<double>::denorm_min(), hi = 1 - kEps;
  if (t1_in) h.t[h.count++] = std::clamp(t1, lo, hi);
  if (t2_in) h.t[h.count++] = std::clamp(t2, lo, hi);
  if (h.count == 2 && h.t[1] < h.t[0]) h.t[1] = h.t[0];
  return h;
}

CircleSegmentHits circle_segment_hits(const Vec2& a, const Vec2& b, const Vec2& c, double r) {
  double v[5];
  int s[5];
  detail::ball_segment_signs<2>(a, b, c, r, s);
  // Rounded values for the roots.
  const double ex = a[0] - c[0], ey = a[1] - c[1];
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  const double dd = dx * dx + dy * dy;
  const double f0 = r * r - (ex * ex + ey * ey);
  const double ed = ex * dx + ey * dy;
  v[0] = f0;
  v[2] = ed;
  v[4] = ed * ed + dd * f0;
  return circle_hits_from_signs(s[0], s[1], s[2], s[3], s[4], v[2], dd, v[0], v[4]);
}

}  // namespace cisamr::geometry::exact
