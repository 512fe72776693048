// Exact 3D predicates: CGAL's filtered Epick kernel for orientation and intersection
// tests; a static floating-point filter then exact Mpzf for the quadric signs.
#include "geometry/predicates3.hpp"

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
using M = CGAL::Mpzf;
constexpr double kEps = std::numeric_limits<double>::epsilon() * 0.5;  // unit roundoff
constexpr double kTiny = std::numeric_limits<double>::min();

K::Point_3 pt(const Vec3& v) { return K::Point_3(v[0], v[1], v[2]); }

}  // namespace

int orientation(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return static_cast<int>(CGAL::orientation(pt(a), pt(b), pt(c), pt(d)));
}

bool collinear(const Vec3& a, const Vec3& b, const Vec3& c) {
  return CGAL::collinear(pt(a), pt(b), pt(c));
}

int sphere_side(const Vec3& p, const Vec3& c, double r) {
  const double dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2];
  const double rr = r * r, q = dx * dx + dy * dy + dz * dz, f = rr - q;
  const double bound = 10 * kEps * (rr + q) + kTiny;
  if (f > bound) return 1;
  if (f < -bound) return -1;
  M v = M(r) * M(r);
  for (int k = 0; k < 3; ++k) {
    const M d = M(p[k]) - M(c[k]);
    v = v - d * d;
  }
  return static_cast<int>(v.sign());
}

int balls_side(const Vec3& c1, double r1, const Vec3& c2, double r2) {
  const double dx = c2[0] - c1[0], dy = c2[1] - c1[1], dz = c2[2] - c1[2], rs = r1 + r2;
  const double q = dx * dx + dy * dy + dz * dz, f = rs * rs - q;
  const double bound = 14 * kEps * (rs * rs + q) + kTiny;
  if (f > bound) return 1;
  if (f < -bound) return -1;
  const M er = M(r1) + M(r2);
  M v = er * er;
  for (int k = 0; k < 3; ++k) {
    const M d = M(c2[k]) - M(c1[k]);
    v = v - d * d;
  }
  return static_cast<int>(v.sign());
}

CircleSegmentHits sphere_segment_hits(const Vec3& a, const Vec3& b, const Vec3& c, double r) {
  int s[5];
  detail::ball_segment_signs<3>(a, b, c, r, s);
  double f0 = r * r, ed = 0, dd = 0;
  for (int k = 0; k < 3; ++k) {
    const double e = a[k] - c[k], d = b[k] - a[k];
    f0 -= e * e;
    ed += e * d;
    dd += d * d;
  }
  return circle_hits_from_signs(s[0], s[1], s[2], s[3], s[4], ed, dd, f0, ed * ed + dd * f0);
}

int cylinder_side(const Vec3& p, const Vec3& s, const Vec3& e, double r) {
  // g1 = w·ax ≥ 0, g2 = (e − p)·ax ≥ 0, g3 = r²|ax|² − (|w|²|ax|² − (w·ax)²) ≥ 0, w = p − s.
  double w[3], v[3], ax[3];
  for (int k = 0; k < 3; ++k) w[k] = p[k] - s[k], v[k] = e[k] - p[k], ax[k] = e[k] - s[k];
  double g1 = 0, g2 = 0, s1 = 0, s2 = 0, A = 0, W = 0;
  for (int k = 0; k < 3; ++k) {
    g1 += w[k] * ax[k];
    g2 += v[k] * ax[k];
    s1 += std::abs(w[k] * ax[k]);
    s2 += std::abs(v[k] * ax[k]);
    A += ax[k] * ax[k];
    W += w[k] * w[k];
  }
  const double rr = r * r;
  const double g3 = rr * A - (W * A - g1 * g1);
  const double b1 = 8 * kEps * s1 + kTiny, b2 = 8 * kEps * s2 + kTiny;
  const double b3 = 32 * kEps * (rr * A + W * A + s1 * s1) + kTiny;
  int sg[3] = {0, 0, 0};
  const double g[3] = {g1, g2, g3}, bnd[3] = {b1, b2, b3};
  bool exact_needed = false;
  for (int i = 0; i < 3; ++i) {
    if (g[i] > bnd[i]) sg[i] = 1;
    else if (g[i] < -bnd[i]) return -1;  // one certainly failed constraint: outside
    else exact_needed = true;
  }
  if (exact_needed) {
    M mw[3], mv[3], ma[3];
    for (int k = 0; k < 3; ++k) mw[k] = M(p[k]) - M(s[k]), mv[k] = M(e[k]) - M(p[k]), ma[k] = M(e[k]) - M(s[k]);
    M e1 = mw[0] * ma[0] + mw[1] * ma[1] + mw[2] * ma[2];
    M e2 = mv[0] * ma[0] + mv[1] * ma[1] + mv[2] * ma[2];
    M ea = ma[0] * ma[0] + ma[1] * ma[1] + ma[2] * ma[2];
    M ew = mw[0] * mw[0] + mw[1] * mw[1] + mw[2] * mw[2];
    M e3 = M(r) * M(r) * ea - (ew * ea - e1 * e1);
    sg[0] = static_cast<int>(e1.sign());
    sg[1] = static_cast<int>(e2.sign());
    sg[2] = static_cast<int>(e3.sign());
  }
  const int lo = std::min({sg[0], sg[1], sg[2]});
  return lo;  // -1 if any constraint fails, 0 if one is tight, +1 strictly inside
}

bool triangles_intersect(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0,
                         const Vec3& b1, const Vec3& b2) {
  return CGAL::do_intersect(K::Triangle_3(pt(a0), pt(a1), pt(a2)), K::Triangle_3(pt(b0), pt(b1), pt(b2)));
}

bool segment_triangle_intersect(const Vec3& p, const Vec3& q, const Vec3& t0, const Vec3& t1,
                                const Vec3& t2) {
  return CGAL::do_intersect(K::Segment_3(pt(p), pt(q)), K::Triangle_3(pt(t0), pt(t1), pt(t2)));
}

bool triangle_box_intersect(const Vec3& t0, const Vec3& t1, const Vec3& t2, const Box3& box) {
  const CGAL::Bbox_3 b(box.min[0], box.min[1], box.min[2], box.max[0], box.max[1], box.max[2]);
  return CGAL::do_intersect(K::Triangle_3(pt(t0), pt(t1), pt(t2)), b);
}

}  // namespace cisamr::geometry::exact
