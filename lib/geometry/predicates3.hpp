#pragma once
// Exact 3D predicates on double inputs (private to lib/geometry). Inputs are exact
// numbers, answers exact signs (floating-point filter, then CGAL's filtered kernel or
// exact Mpzf). Implemented in predicates3.cpp, which with box_index.cpp and
// predicates2.cpp is all of lib/geometry that sees CGAL.
#include "core/types.hpp"
#include "geometry/predicates2.hpp"

namespace cisamr::geometry::exact {

// sign(det[b−a, c−a, d−a]) = sign(((b−a)×(c−a))·(d−a)).
int orientation(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// Are a, b, c collinear (a zero-area triangle)?
bool collinear(const Vec3& a, const Vec3& b, const Vec3& c);

// sign(r² − |p − c|²): +1 inside the sphere, 0 on it, -1 outside.
int sphere_side(const Vec3& p, const Vec3& c, double r);

// sign((r1 + r2)² − |c1 − c2|²).
int balls_side(const Vec3& c1, double r1, const Vec3& c2, double r2);

// The open segment a→b against a sphere, decided exactly (see circle_segment_hits).
CircleSegmentHits sphere_segment_hits(const Vec3& a, const Vec3& b, const Vec3& c, double r);

// Finite cylinder with flat caps (axis s→e, s ≠ e, radius r): +1 inside, 0 on, -1 outside.
int cylinder_side(const Vec3& p, const Vec3& s, const Vec3& e, double r);

// Do the closed triangles meet? Does the closed segment meet the closed triangle? Does
// the closed triangle meet the closed box?
bool triangles_intersect(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0,
                         const Vec3& b1, const Vec3& b2);
bool segment_triangle_intersect(const Vec3& p, const Vec3& q, const Vec3& t0, const Vec3& t1,
                                const Vec3& t2);
bool triangle_box_intersect(const Vec3& t0, const Vec3& t1, const Vec3& t2, const Box3& box);

}  // namespace cisamr::geometry::exact
