#pragma once
// Rational B-spline surface patches as rational Bézier pieces (private to lib/geometry;
// docs/nurbs-step-design.md §2.1, §2.4): extraction from a `NurbsPatch` of any degree
// (clamped or not), evaluation with first derivatives, restriction to a parameter
// rectangle, halving, control boxes and slabs, and the roots of a line on a piece by
// Bézier clipping and Newton on (s, t, λ). Positive weights keep every piece inside the
// convex hull of its control points; the clipping and every box below rest on that.
#include <array>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"

namespace cisamr::geometry::nurbs {

constexpr int kMaxPatchDegree = 30;  // per direction (the scene reader's bound)

// One rational Bézier piece of degree (p, q): (p+1)·(q+1) homogeneous control points
// (w·x, w·y, w·z, w), point (i, j) at 4·(i + (p+1)·j) (u fastest). Its local parameters
// (s, t) ∈ [0, 1]² map to the patch's (u, v) = (u0 + s·(u1 − u0), v0 + t·(v1 − v0)).
struct BezierPatch {
  int degree_u = 0, degree_v = 0;
  std::vector<double> hom;
  double u0 = 0, u1 = 1, v0 = 0, v1 = 1;

  const double* point(int i, int j) const { return hom.data() + 4 * (i + (degree_u + 1) * j); }
  Vec3 cartesian(int i, int j) const {
    const double* h = point(i, j);
    return {h[0] / h[3], h[1] / h[3], h[2] / h[3]};
  }
};

// The Bézier pieces of one patch: piece (a, b), the a-th non-empty knot span in u and the
// b-th in v, at pieces[a + count_u·b].
struct PatchPieces {
  int count_u = 0, count_v = 0;
  std::vector<BezierPatch> pieces;
};

// Validates the patch (degrees in [1, 30], knot counts, non-decreasing finite knots, a
// non-empty parameter range, finite control points, positive weights) and extracts its
// pieces (knot insertion in u along every row, then in v along every column). Returns ""
// or the problem, field suffix first (".knots_u: must be non-decreasing (knot 4)").
std::string extract_patch(const NurbsPatch& patch, PatchPieces& out);

// Point and (optionally) first partial derivatives at local (s, t) of a piece.
Vec3 evaluate(const BezierPatch& piece, double s, double t, Vec3* ds = nullptr, Vec3* dt = nullptr);
// The same at the patch's (u, v) ∈ [u_min, u_max] × [v_min, v_max] (derivatives in u, v).
Vec3 evaluate(const PatchPieces& patch, double u, double v, Vec3* du = nullptr, Vec3* dv = nullptr);

// The piece restricted to local [s0, s1] × [t0, t1] ⊂ [0, 1]² (parameters follow).
BezierPatch restrict_patch(const BezierPatch& piece, double s0, double s1, double t0, double t1);
// Halves at s = 1/2 (u) or t = 1/2 (v); the halves share their middle row bit for bit.
void halve_u(const BezierPatch& piece, BezierPatch& low, BezierPatch& high);
void halve_v(const BezierPatch& piece, BezierPatch& low, BezierPatch& high);

Box3 control_box(const BezierPatch& piece);  // holds the piece
// [min, max] of n·x over the Cartesian control points: the piece lies in that slab.
std::array<double, 2> slab(const BezierPatch& piece, const Vec3& n);

// A point where the line a + λ·(b − a) meets a piece.
struct LineRoot {
  double lambda = 0;
  double s = 0, t = 0;    // local parameters on the piece
  bool polished = false;  // Newton converged; false: nearest point within τ (tangency, pole), or
                          // the end of a stretch where the line lies in the surface
};

struct LineQuery {
  Vec3 a{}, b{};
  double lambda_lo = 0, lambda_hi = 1;  // roots wanted in this range of λ
  double size = 1;                      // the body's size: scales the internal thresholds
  double tolerance = 1e-12;             // τ, the ON band (raised to 4 × the coordinates' rounding)
};

// The roots of the line on the piece with λ in [lambda_lo, lambda_hi], ascending in λ,
// duplicates (one root seen from two sub-pieces) merged. Bézier clipping (Nishita,
// Sederberg and Kakimoto 1990) against planes through the line chosen along the piece's
// directions (Efremov, Havran and Seidel 2005), halving where an interval shrinks by less
// than 20 %; a sub-piece whose box is below 1e-6·size is polished by Newton on (s, t, λ)
// from its centre (≤ 8 steps). Where Newton cannot converge (tangency, a pole), a point of
// the sub-piece within τ of the line is reported, else clipping goes on down to boxes of
// τ. Where a sub-piece lies within τ of a plane through the line (a segment in a flat
// face, or along a ruling), the line meets it along a stretch: the crossings of the line
// with the sub-piece's sides are reported instead (unpolished), not a root per box.
// A root within τ of the piece's boundary may be reported by both neighbours: merging
// across pieces is the caller's (it knows the topology). Pure function of its arguments.
void line_roots(const BezierPatch& piece, const LineQuery& query, std::vector<LineRoot>& roots);

}  // namespace cisamr::geometry::nurbs
