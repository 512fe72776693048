#pragma once
// Exact 2D predicates on double inputs (private to lib/geometry). The inputs are taken
// as exact numbers; the answers are the exact signs (filtered evaluation, exact Mpzf
// fallback), so topology decided with them never depends on rounding.
// Implemented in predicates2.cpp, with box_index.cpp and predicates3.cpp the only places that see CGAL.
#include <span>

#include "core/types.hpp"

namespace cisamr::geometry::exact {

// +1 when a, b, c turn counter-clockwise, -1 clockwise, 0 collinear.
int orientation(const Vec2& a, const Vec2& b, const Vec2& c);

// sign(r² − |p − c|²): +1 inside the circle, 0 on it, -1 outside.
int circle_side(const Vec2& p, const Vec2& c, double r);

// sign((r1 + r2)² − |c1 − c2|²): +1 the disks overlap, 0 they touch, -1 apart.
int disks_side(const Vec2& c1, double r1, const Vec2& c2, double r2);

// Closed polygon (either orientation, simple): +1 strictly inside, 0 on an edge or
// vertex, -1 strictly outside.
int polygon_side(std::span<const Vec2> poly, const Vec2& p);

// Do the closed segments [a,b] and [c,d] meet?
bool segments_intersect(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);

// Do the closed segments cross at a single point interior to both (proper crossing)?
bool segments_cross_properly(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);

// Where the open segment a→b (a ≠ b) crosses the circle, decided exactly:
// `start_inside` is the state on (0, first root); `count` roots follow, alternately
// entering/leaving when start_inside is false (leaving/entering otherwise). The roots
// themselves are rounded values clamped into (0,1). Tangencies give no root.
struct CircleSegmentHits {
  bool start_inside = false;
  int count = 0;
  double t[2]{};
};
CircleSegmentHits circle_segment_hits(const Vec2& a, const Vec2& b, const Vec2& c, double r);

// The same decision from given signs (used for ellipses mapped to the unit circle, where
// the signs come from a tolerant classification): f0 = sign F(a), f1 = sign F(b),
// ed = sign((a−c)·(b−a)), fd = sign((b−c)·(b−a)), disc = sign of the discriminant.
// F = r² − |x − c|². `ed_value`, `dd`, `f0_value`, `disc_value` give the numeric roots.
CircleSegmentHits circle_hits_from_signs(int f0, int f1, int ed, int fd, int disc,
                                         double ed_value, double dd, double f0_value,
                                         double disc_value);

}  // namespace cisamr::geometry::exact
