#pragma once
// Closed rational NURBS curves as chains of rational Bézier pieces (private to
// lib/geometry). Positive weights make every piece lie in the convex hull (hence the
// box) of its control points; the whole robust scheme of README.md rests on that.
#include <string>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"

namespace cisamr::geometry::nurbs {

// One rational Bézier piece of degree p: p+1 homogeneous points (w·x, w·y, w).
struct Piece {
  std::vector<double> hom;  // 3·(p+1)
  Box2 box;                 // box of the Cartesian control points (contains the piece)
  Vec2 start, end;          // curve points at both ends (shared exactly with neighbours)
};

struct Region {
  int degree = 0;
  std::vector<Piece> pieces;  // a closed chain: pieces[i].end == pieces[i+1].start
  Box2 box;                   // box of all control points
  double size = 0;            // diagonal of `box`
  double on_tolerance = 0;    // points closer than about this to the curve are ON
};

// Validates and converts; returns "" on success or the problem (field suffix first,
// e.g. ".knots: must be non-decreasing") on failure.
std::string build_region(const NurbsCurve& curve, Region& out);

// +1 inside, 0 within on_tolerance of the curve, -1 outside (exact crossing parity on
// the adaptively refined chord chain).
int side(const Region& r, const Vec2& p);

// Parameters t in (0,1) where the segment a→b meets the curve (refined chords), unsorted.
void segment_hits(const Region& r, const Vec2& a, const Vec2& b, std::vector<double>& ts);

// Distance from p to the curve (to ~1e-13 of the curve size).
double distance_to_curve(const Region& r, const Vec2& p);

// Does the curve meet the closed box (conservative)?
bool touches_box(const Region& r, const Box2& box);

// Enclosed area (Green's formula, Gauss–Legendre on each piece) and a point sample.
double area(const Region& r);
double length(const Region& r);
Vec2 point(const Piece& piece, int degree, double s);  // s in [0,1]

// x coordinates where the curve has a vertical tangent (x'(s) = 0) or a piece joint:
// the breakpoints of line integrals across the region.
void x_breakpoints(const Region& r, std::vector<double>& xs);

// Polyline through the curve with chord error ≤ tol (closed, first point not repeated).
std::vector<Vec2> flatten(const Region& r, double tol);
// The curve's box, containing it and at most tol larger on each side.
Box2 tight_box(const Region& r, double tol);

}  // namespace cisamr::geometry::nurbs
