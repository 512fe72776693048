// Rational B-spline surface patches as rational Bézier pieces (contract in nurbs3.hpp).
#include "geometry/nurbs3.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/vec_math.hpp"
#include "geometry/nurbs_bezier.hpp"

namespace cisamr::geometry::nurbs {
namespace {

constexpr double kUnit = std::numeric_limits<double>::epsilon() / 2;
constexpr int kLine = 4 * (kMaxPatchDegree + 2);  // one row or column of homogeneous points

std::string knot_problem(const std::vector<double>& U, int p, const char* key) {
  const std::string field = std::string(".") + key;
  const std::size_t minimum = 2 * static_cast<std::size_t>(p + 1);
  if (U.size() < minimum)
    return field + ": a degree-" + std::to_string(p) + " direction needs at least " + std::to_string(minimum) +
           " knots, got " + std::to_string(U.size());
  for (std::size_t i = 0; i < U.size(); ++i) {
    if (!std::isfinite(U[i])) return field + ": must be finite";
    if (i > 0 && U[i] < U[i - 1]) return field + ": must be non-decreasing (knot " + std::to_string(i) + ")";
  }
  if (!(U[static_cast<std::size_t>(p)] < U[U.size() - static_cast<std::size_t>(p) - 1]))
    return field + ": the parameter range is empty";
  return "";
}

// Applies op(line, degree) to every row (along u) or column (along v) of the control net,
// each as a contiguous run of homogeneous points.
template <class Op>
void for_each_line(std::vector<double>& hom, int p, int q, bool along_u, Op&& op) {
  if (along_u) {
    for (int j = 0; j <= q; ++j) op(hom.data() + 4 * (p + 1) * j, p);
    return;
  }
  double line[kLine];
  for (int i = 0; i <= p; ++i) {
    for (int j = 0; j <= q; ++j) std::copy_n(hom.data() + 4 * (i + (p + 1) * j), 4, line + 4 * j);
    op(line, q);
    for (int j = 0; j <= q; ++j) std::copy_n(line + 4 * j, 4, hom.data() + 4 * (i + (p + 1) * j));
  }
}

// A curve restricted to [s0, s1] ⊂ [0, 1], in place.
void restrict_line(double* h, int p, double s0, double s1) {
  if (s0 == 0 && s1 == 1) return;
  if (s1 < 1) split_at<4>(h, p, s1, h, nullptr);  // now [0, s1]
  if (s0 > 0 && s1 > 0) split_at<4>(h, p, s0 / s1, nullptr, h);
}

// Halves every row (along u) or column (along v) into `low` and `high`.
void halve(const BezierPatch& piece, bool along_u, BezierPatch& low, BezierPatch& high) {
  const int p = piece.degree_u, q = piece.degree_v;
  low = piece;
  high = piece;
  double a[kLine], b[kLine];
  if (along_u) {
    for (int j = 0; j <= q; ++j) {
      split_half<4>(piece.point(0, j), p, a, b);
      std::copy_n(a, 4 * (p + 1), low.hom.data() + 4 * (p + 1) * j);
      std::copy_n(b, 4 * (p + 1), high.hom.data() + 4 * (p + 1) * j);
    }
    low.u1 = high.u0 = 0.5 * (piece.u0 + piece.u1);
    return;
  }
  double line[kLine];
  for (int i = 0; i <= p; ++i) {
    for (int j = 0; j <= q; ++j) std::copy_n(piece.point(i, j), 4, line + 4 * j);
    split_half<4>(line, q, a, b);
    for (int j = 0; j <= q; ++j) {
      std::copy_n(a + 4 * j, 4, low.hom.data() + 4 * (i + (p + 1) * j));
      std::copy_n(b + 4 * j, 4, high.hom.data() + 4 * (i + (p + 1) * j));
    }
  }
  low.v1 = high.v0 = 0.5 * (piece.v0 + piece.v1);
}

Vec3 unit_or_zero(const Vec3& v) {
  const double n = norm(v);
  return n > 0 ? scale(v, 1 / n) : Vec3{0, 0, 0};
}

// Some unit vector perpendicular to the unit vector d.
Vec3 perpendicular(const Vec3& d) {
  const int k = std::abs(d[0]) <= std::abs(d[1]) && std::abs(d[0]) <= std::abs(d[2]) ? 0
                : std::abs(d[1]) <= std::abs(d[2])                                  ? 1
                                                                                      : 2;
  Vec3 e{0, 0, 0};
  e[k] = 1;
  return unit_or_zero(cross(d, e));
}

// Where the convex hull of the points (i/n, lo_i) and (i/n, hi_i) meets the axis y = 0:
// [x0, x1] ⊂ [0, 1] (widened by 1e-12), or false when it misses it.
bool hull_zero_interval(const double* lo, const double* hi, int n, double& x0, double& x1) {
  bool below = false, above = false;
  for (int i = 0; i <= n; ++i) below |= lo[i] <= 0, above |= hi[i] >= 0;
  if (!below || !above) return false;
  double a = std::numeric_limits<double>::infinity(), b = -a;
  auto take = [&](double x) { a = std::min(a, x), b = std::max(b, x); };
  for (int i = 0; i <= n; ++i) {
    const double xi = static_cast<double>(i) / n;
    if (lo[i] <= 0 && hi[i] >= 0) take(xi);
    for (int k = i + 1; k <= n; ++k) {
      const double xk = static_cast<double>(k) / n;
      for (const double y1 : {lo[i], hi[i]})
        for (const double y2 : {lo[k], hi[k]})
          if (((y1 <= 0 && y2 >= 0) || (y1 >= 0 && y2 <= 0)) && y1 != y2)
            take(xi + (xk - xi) * (y1 / (y1 - y2)));
    }
  }
  if (!(a <= b)) return false;
  x0 = std::max(0.0, a - 1e-12);
  x1 = std::min(1.0, b + 1e-12);
  return true;
}

class LineClipper {
 public:
  LineClipper(const BezierPatch& piece, const LineQuery& q, std::vector<LineRoot>& out)
      : piece_(piece), q_(q), out_(out) {
    d_ = sub(q.b, q.a);
    dd_ = dot(d_, d_);
    dlen_ = std::sqrt(dd_);
    dn_ = scale(d_, 1 / dlen_);
    double big = std::max({std::abs(q.a[0]), std::abs(q.a[1]), std::abs(q.a[2])});
    for (int j = 0; j <= piece.degree_v; ++j)
      for (int i = 0; i <= piece.degree_u; ++i) {
        const Vec3 c = piece.cartesian(i, j);
        big = std::max({big, std::abs(c[0]), std::abs(c[1]), std::abs(c[2])});
      }
    // Slack of the hull tests: the rounding of the coordinates (restriction, the plane
    // distances), so that no root is lost to it, plus a sixteenth of the ON band. The band
    // itself is at least 4× the rounding: a line between the slack and the band from the
    // surface would otherwise be chased down to boxes of the band.
    const double rounding = 64 * kUnit * big;
    tolerance_ = std::max(q.tolerance, 4 * rounding);
    margin_ = tolerance_ / 16 + rounding;
    newton_box_ = 1e-6 * q.size;
    newton_step_ = 8 * kUnit * (q.size + big);
  }

  void run(const BezierPatch& part, double s0, double s1, double t0, double t1, int depth) {
    const int p = part.degree_u, q = part.degree_v;
    // The λ range of the control points (the piece lies in their hull).
    double lam_min = std::numeric_limits<double>::infinity(), lam_max = -lam_min;
    Box3 box{part.cartesian(0, 0), part.cartesian(0, 0)};
    Vec3 u_dir{0, 0, 0}, v_dir{0, 0, 0};
    for (int j = 0; j <= q; ++j)
      for (int i = 0; i <= p; ++i) {
        const Vec3 c = part.cartesian(i, j);
        const double lam = dot(sub_a(c), d_) / dd_;
        lam_min = std::min(lam_min, lam), lam_max = std::max(lam_max, lam);
        for (int k = 0; k < 3; ++k) box.min[k] = std::min(box.min[k], c[k]), box.max[k] = std::max(box.max[k], c[k]);
      }
    const double lam_slack = margin_ / dlen_;
    if (lam_max + lam_slack < q_.lambda_lo || lam_min - lam_slack > q_.lambda_hi) return;
    for (int j = 0; j <= q; ++j) u_dir = add(u_dir, sub(part.cartesian(p, j), part.cartesian(0, j)));
    for (int i = 0; i <= p; ++i) v_dir = add(v_dir, sub(part.cartesian(i, q), part.cartesian(i, 0)));

    // Planes through the line: one along the v direction (its distance varies with u:
    // clips u well), one along u, and the one perpendicular to the first.
    Vec3 n_u = unit_or_zero(cross(dn_, v_dir)), n_v = unit_or_zero(cross(dn_, u_dir));
    if (n_u == Vec3{0, 0, 0}) n_u = n_v == Vec3{0, 0, 0} ? perpendicular(dn_) : unit_or_zero(cross(dn_, n_v));
    if (n_v == Vec3{0, 0, 0}) n_v = unit_or_zero(cross(dn_, n_u));
    const Vec3 n_w = unit_or_zero(cross(dn_, n_u));
    const double diag = norm(sub(box.max, box.min));
    double us0 = 0, us1 = 1, vs0 = 0, vs1 = 1;
    for (const Vec3& n : {n_u, n_v, n_w}) {
      double lo_u[kMaxPatchDegree + 1], hi_u[kMaxPatchDegree + 1], lo_v[kMaxPatchDegree + 1], hi_v[kMaxPatchDegree + 1];
      std::fill_n(lo_u, p + 1, std::numeric_limits<double>::infinity());
      std::fill_n(hi_u, p + 1, -std::numeric_limits<double>::infinity());
      std::fill_n(lo_v, q + 1, std::numeric_limits<double>::infinity());
      std::fill_n(hi_v, q + 1, -std::numeric_limits<double>::infinity());
      for (int j = 0; j <= q; ++j)
        for (int i = 0; i <= p; ++i) {
          const double* h = part.point(i, j);
          // Homogeneous distance w·n·(x − a): the same sign as the Cartesian one.
          const double c = plane_distance(h, n);
          const double m = h[3] * margin_;
          lo_u[i] = std::min(lo_u[i], c - m), hi_u[i] = std::max(hi_u[i], c + m);
          lo_v[j] = std::min(lo_v[j], c - m), hi_v[j] = std::max(hi_v[j], c + m);
        }
      if (diag > newton_box_ && flat_along(part, n)) {
        // The sub-piece lies in a plane through the line (within the band): the line
        // meets it along a stretch, no isolated roots; its ends are where the line
        // crosses the sub-piece's sides.
        side_crossings(part, unit_or_zero(cross(dn_, n)), s0, s1, t0, t1);
        return;
      }
      double a, b;
      if (!hull_zero_interval(lo_u, hi_u, p, a, b)) return;
      us0 = std::max(us0, a), us1 = std::min(us1, b);
      if (!hull_zero_interval(lo_v, hi_v, q, a, b)) return;
      vs0 = std::max(vs0, a), vs1 = std::min(vs1, b);
      if (us0 > us1 || vs0 > vs1) return;
    }

    if (diag <= newton_box_ || depth >= kMaxDepth) {
      if (newton(s0, s1, t0, t1)) return;
      if (nearest_point_root(s0, s1, t0, t1, diag <= tolerance_ || depth >= kMaxDepth)) return;
    }
    const double ns0 = s0 + us0 * (s1 - s0), ns1 = s0 + us1 * (s1 - s0);
    const double nt0 = t0 + vs0 * (t1 - t0), nt1 = t0 + vs1 * (t1 - t0);
    const BezierPatch clipped = restrict_patch(part, us0, us1, vs0, vs1);
    if (us1 - us0 > 0.8 && vs1 - vs0 > 0.8) {
      // Clipping stalls (several roots, or a tangency): halve the longer direction.
      BezierPatch low, high;
      const bool along_u = norm(u_dir) * (us1 - us0) >= norm(v_dir) * (vs1 - vs0);
      halve(clipped, along_u, low, high);
      if (along_u) {
        const double mid = 0.5 * (ns0 + ns1);
        run(low, ns0, mid, nt0, nt1, depth + 1);
        run(high, mid, ns1, nt0, nt1, depth + 1);
      } else {
        const double mid = 0.5 * (nt0 + nt1);
        run(low, ns0, ns1, nt0, mid, depth + 1);
        run(high, ns0, ns1, mid, nt1, depth + 1);
      }
      return;
    }
    run(clipped, ns0, ns1, nt0, nt1, depth + 1);
  }

 private:
  static constexpr int kMaxDepth = 160;

  // Homogeneous distance w·n·(x − a) of one control point to the plane n through a.
  double plane_distance(const double* h, const Vec3& n) const {
    return n[0] * (h[0] - h[3] * q_.a[0]) + n[1] * (h[1] - h[3] * q_.a[1]) + n[2] * (h[2] - h[3] * q_.a[2]);
  }

  bool flat_along(const BezierPatch& part, const Vec3& n) const {
    for (int j = 0; j <= part.degree_v; ++j)
      for (int i = 0; i <= part.degree_u; ++i) {
        const double* h = part.point(i, j);
        if (!(std::abs(plane_distance(h, n)) <= h[3] * tolerance_)) return false;
      }
    return true;
  }

  // The crossings of the line, in the plane of a flat sub-piece, with its four sides: the
  // zeros of the distance to the plane m (through the line, across the flat one).
  void side_crossings(const BezierPatch& part, const Vec3& m, double s0, double s1, double t0, double t1) {
    const int p = part.degree_u, q = part.degree_v;
    double line[kLine];
    for (int side = 0; side < 4; ++side) {
      const bool along_u = side < 2;
      const int deg = along_u ? p : q;
      for (int k = 0; k <= deg; ++k)
        std::copy_n(along_u ? part.point(k, side == 0 ? 0 : q) : part.point(side == 2 ? 0 : p, k), 4, line + 4 * k);
      curve_zeros(line, deg, m, 0, 1, 0, [&](double x) {
        const double s = along_u ? s0 + x * (s1 - s0) : (side == 2 ? s0 : s1);
        const double t = along_u ? (side == 0 ? t0 : t1) : t0 + x * (t1 - t0);
        report(dot(sub_a(evaluate(piece_, s, t)), d_) / dd_, s, t, false);
      });
    }
  }

  // Zeros of w·m·(x − a) on a rational Bézier curve restricted to [x0, x1] ⊂ [0, 1]:
  // one sign change of the coefficients isolates one zero (variation diminishing), found
  // by bisection; otherwise halving. A stretch lying on the line gives its two ends.
  template <class Found>
  void curve_zeros(const double* h, int deg, const Vec3& m, double x0, double x1, int depth, Found&& found) {
    int changes = 0, prev = 0;
    bool all_small = true, any_below = false, any_above = false;
    for (int k = 0; k <= deg; ++k) {
      const double f = plane_distance(h + 4 * k, m), slack = h[4 * k + 3] * margin_;
      all_small &= std::abs(f) <= slack;
      any_below |= f - slack <= 0, any_above |= f + slack >= 0;
      const int sign = f > slack ? 1 : f < -slack ? -1 : 0;
      if (sign != 0 && prev != 0 && sign != prev) ++changes;
      if (sign != 0) prev = sign;
    }
    if (!any_below || !any_above) return;
    if (all_small || depth >= 60) {
      found(x0);
      if (x1 > x0) found(x1);
      return;
    }
    const double f0 = plane_distance(h, m), f1 = plane_distance(h + 4 * deg, m);
    const bool ends_clear = std::abs(f0) > h[3] * margin_ && std::abs(f1) > h[4 * deg + 3] * margin_;
    if (changes == 1 && ends_clear && (f0 < 0) != (f1 < 0)) {
      double lo = 0, hi = 1;
      for (int it = 0; it < 64 && hi - lo > 4 * kUnit; ++it) {
        const double mid = 0.5 * (lo + hi);
        double H[4], D[4];
        eval_hom<4>(h, deg, mid, H, D);
        ((plane_distance(H, m) < 0) == (f0 < 0) ? lo : hi) = mid;
      }
      found(x0 + 0.5 * (lo + hi) * (x1 - x0));
      return;
    }
    double left[kLine], right[kLine];
    split_half<4>(h, deg, left, right);
    const double mid = 0.5 * (x0 + x1);
    curve_zeros(left, deg, m, x0, mid, depth + 1, found);
    curve_zeros(right, deg, m, mid, x1, depth + 1, found);
  }

  Vec3 sub_a(const Vec3& x) const { return sub(x, q_.a); }

  void report(double lam, double s, double t, bool polished) {
    if (lam < q_.lambda_lo || lam > q_.lambda_hi) return;
    out_.push_back({lam, s, t, polished});
  }

  // Newton on S(s, t) − a − λ·d = 0 from the centre of [s0, s1] × [t0, t1] of the piece
  // (at most 8 steps, stopping at a step below the rounding of the coordinates). True when
  // it ends within a quarter of the ON band of a root inside that rectangle (widened by
  // the band, in parameters: a root on the piece's side, or at a pole where S_s = 0, is
  // this piece's too); the root is reported if λ is wanted.
  bool newton(double s0, double s1, double t0, double t1) {
    double s = 0.5 * (s0 + s1), t = 0.5 * (t0 + t1);
    Vec3 Ss, St;
    Vec3 S = evaluate(piece_, s, t, &Ss, &St);
    double lam = dot(sub_a(S), d_) / dd_;
    const Vec3 minus_d = scale(d_, -1);
    for (int it = 0; it < 8; ++it) {
      const Vec3 r = sub(scale(d_, lam), sub_a(S));  // −F
      const double det = dot(Ss, cross(St, minus_d));
      if (!(std::abs(det) > 1e-14 * norm(Ss) * norm(St) * dlen_)) return false;
      const double ds = dot(r, cross(St, minus_d)) / det;
      const double dt = dot(Ss, cross(r, minus_d)) / det;
      const double dl = dot(Ss, cross(St, r)) / det;
      if (!std::isfinite(ds) || !std::isfinite(dt) || !std::isfinite(dl)) return false;
      const double step = norm(add(scale(Ss, ds), scale(St, dt))) + std::abs(dl) * dlen_;
      s += ds, t += dt, lam += dl;
      if (std::abs(s) > 2 || std::abs(t) > 2) return false;  // left the piece for good
      S = evaluate(piece_, s, t, &Ss, &St);
      if (step <= newton_step_) break;
    }
    if (!(norm(sub(sub_a(S), scale(d_, lam))) <= tolerance_ / 4)) return false;
    const double ms = 1e-9 * (s1 - s0) + 4 * kUnit + tolerance_ / std::max(norm(Ss), 1e-300);
    const double mt = 1e-9 * (t1 - t0) + 4 * kUnit + tolerance_ / std::max(norm(St), 1e-300);
    if (s < s0 - ms || s > s1 + ms || t < t0 - mt || t > t1 + mt) return false;
    report(lam, std::clamp(s, s0, s1), std::clamp(t, t0, t1), true);
    return true;
  }

  // Where Newton fails (tangency, a degenerate side such as a pole): the point of a 5 × 5
  // grid on [s0, s1] × [t0, t1] nearest to the line; reported when within τ of it, or
  // always with `force`. True when it reported (or would, but for λ out of range).
  bool nearest_point_root(double s0, double s1, double t0, double t1, bool force) {
    double best = std::numeric_limits<double>::infinity(), best_lam = 0, best_s = 0, best_t = 0;
    for (int j = 0; j <= 4; ++j)
      for (int i = 0; i <= 4; ++i) {
        const double s = s0 + (s1 - s0) * i / 4, t = t0 + (t1 - t0) * j / 4;
        const Vec3 S = evaluate(piece_, s, t);
        const double lam = dot(sub_a(S), d_) / dd_;
        const double dist = norm(sub(sub_a(S), scale(d_, lam)));
        if (dist < best) best = dist, best_lam = lam, best_s = s, best_t = t;
      }
    if (!(force || best <= tolerance_)) return false;
    report(best_lam, best_s, best_t, false);
    return true;
  }

  const BezierPatch& piece_;
  const LineQuery& q_;
  std::vector<LineRoot>& out_;
  Vec3 d_{}, dn_{};
  double dd_ = 0, dlen_ = 0, tolerance_ = 0, margin_ = 0, newton_box_ = 0, newton_step_ = 0;
};

}  // namespace

std::string extract_patch(const NurbsPatch& patch, PatchPieces& out) {
  const int p = patch.degree[0], q = patch.degree[1];
  if (p < 1 || q < 1 || p > kMaxPatchDegree || q > kMaxPatchDegree)
    return ".degree: must be in [1, " + std::to_string(kMaxPatchDegree) + "] in u and v";
  if (std::string e = knot_problem(patch.knots_u, p, "knots_u"); !e.empty()) return e;
  if (std::string e = knot_problem(patch.knots_v, q, "knots_v"); !e.empty()) return e;
  const std::size_t nu = patch.knots_u.size() - static_cast<std::size_t>(p) - 1;
  const std::size_t nv = patch.knots_v.size() - static_cast<std::size_t>(q) - 1;
  if (patch.control_points.size() != nu * nv)
    return ".control_points: the knot vectors give " + std::to_string(nu) + " × " + std::to_string(nv) + " = " +
           std::to_string(nu * nv) + " control points (u fastest), got " +
           std::to_string(patch.control_points.size());
  if (!patch.weights.empty() && patch.weights.size() != nu * nv)
    return ".weights: expected " + std::to_string(nu * nv) + " weights (one per control point), got " +
           std::to_string(patch.weights.size());
  for (double w : patch.weights)
    if (!(w > 0) || !std::isfinite(w)) return ".weights: must be positive";
  for (const Vec3& c : patch.control_points)
    if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2]))
      return ".control_points: coordinates must be finite";

  // Rows in u: every row has the same knots, hence the same pieces.
  std::vector<BezierPieces<4>> rows(nv);
  for (std::size_t j = 0; j < nv; ++j) {
    std::vector<std::array<double, 4>> P(nu);
    for (std::size_t i = 0; i < nu; ++i) {
      const Vec3& c = patch.control_points[i + nu * j];
      const double w = patch.weights.empty() ? 1.0 : patch.weights[i + nu * j];
      P[i] = {c[0] * w, c[1] * w, c[2] * w, w};
    }
    rows[j] = extract_bezier<4>(p, patch.knots_u, std::move(P));
  }
  const int mu = static_cast<int>(rows[0].points.size());
  // Columns in v, per u piece and control column.
  out = PatchPieces{};
  out.count_u = mu;
  for (int a = 0; a < mu; ++a)
    for (int i = 0; i <= p; ++i) {
      std::vector<std::array<double, 4>> P(nv);
      for (std::size_t j = 0; j < nv; ++j) std::copy_n(rows[j].points[a].data() + 4 * i, 4, P[j].begin());
      const BezierPieces<4> column = extract_bezier<4>(q, patch.knots_v, std::move(P));
      if (out.pieces.empty()) {
        out.count_v = static_cast<int>(column.points.size());
        out.pieces.resize(static_cast<std::size_t>(mu * out.count_v));
        for (int b = 0; b < out.count_v; ++b)
          for (int a2 = 0; a2 < mu; ++a2) {
            BezierPatch& piece = out.pieces[static_cast<std::size_t>(a2 + mu * b)];
            piece.degree_u = p, piece.degree_v = q;
            piece.hom.assign(static_cast<std::size_t>(4 * (p + 1) * (q + 1)), 0.0);
            piece.u0 = rows[0].spans[a2][0], piece.u1 = rows[0].spans[a2][1];
            piece.v0 = column.spans[b][0], piece.v1 = column.spans[b][1];
          }
      }
      for (int b = 0; b < out.count_v; ++b) {
        BezierPatch& piece = out.pieces[static_cast<std::size_t>(a + mu * b)];
        for (int k = 0; k <= q; ++k) std::copy_n(column.points[b].data() + 4 * k, 4, piece.hom.data() + 4 * (i + (p + 1) * k));
      }
    }
  return "";
}

Vec3 evaluate(const BezierPatch& piece, double s, double t, Vec3* ds, Vec3* dt) {
  const int p = piece.degree_u, q = piece.degree_v;
  double A[kLine], B[kLine];  // per row: the point and the u derivative at s
  for (int j = 0; j <= q; ++j) eval_hom<4>(piece.point(0, j), p, s, A + 4 * j, B + 4 * j);
  double H[4], Ht[4];
  eval_hom<4>(A, q, t, H, Ht);
  const Vec3 x{H[0] / H[3], H[1] / H[3], H[2] / H[3]};
  if (ds) {
    double Hs[4], unused[4];
    eval_hom<4>(B, q, t, Hs, unused);
    for (int k = 0; k < 3; ++k) (*ds)[k] = (Hs[k] - x[k] * Hs[3]) / H[3];
  }
  if (dt)
    for (int k = 0; k < 3; ++k) (*dt)[k] = (Ht[k] - x[k] * Ht[3]) / H[3];
  return x;
}

Vec3 evaluate(const PatchPieces& patch, double u, double v, Vec3* du, Vec3* dv) {
  int a = 0, b = 0;
  while (a + 1 < patch.count_u && u > patch.pieces[static_cast<std::size_t>(a)].u1) ++a;
  while (b + 1 < patch.count_v && v > patch.pieces[static_cast<std::size_t>(patch.count_u * b)].v1) ++b;
  const BezierPatch& piece = patch.pieces[static_cast<std::size_t>(a + patch.count_u * b)];
  const double hu = piece.u1 - piece.u0, hv = piece.v1 - piece.v0;
  const Vec3 x = evaluate(piece, (u - piece.u0) / hu, (v - piece.v0) / hv, du, dv);
  if (du) *du = scale(*du, 1 / hu);
  if (dv) *dv = scale(*dv, 1 / hv);
  return x;
}

BezierPatch restrict_patch(const BezierPatch& piece, double s0, double s1, double t0, double t1) {
  BezierPatch r = piece;
  const int p = piece.degree_u, q = piece.degree_v;
  for_each_line(r.hom, p, q, true, [&](double* h, int deg) { restrict_line(h, deg, s0, s1); });
  for_each_line(r.hom, p, q, false, [&](double* h, int deg) { restrict_line(h, deg, t0, t1); });
  const double hu = piece.u1 - piece.u0, hv = piece.v1 - piece.v0;
  r.u0 = piece.u0 + s0 * hu, r.u1 = s1 == 1 ? piece.u1 : piece.u0 + s1 * hu;
  r.v0 = piece.v0 + t0 * hv, r.v1 = t1 == 1 ? piece.v1 : piece.v0 + t1 * hv;
  return r;
}

void halve_u(const BezierPatch& piece, BezierPatch& low, BezierPatch& high) { halve(piece, true, low, high); }
void halve_v(const BezierPatch& piece, BezierPatch& low, BezierPatch& high) { halve(piece, false, low, high); }

Box3 control_box(const BezierPatch& piece) {
  Box3 b{piece.cartesian(0, 0), piece.cartesian(0, 0)};
  for (int j = 0; j <= piece.degree_v; ++j)
    for (int i = 0; i <= piece.degree_u; ++i) {
      const Vec3 c = piece.cartesian(i, j);
      for (int k = 0; k < 3; ++k) b.min[k] = std::min(b.min[k], c[k]), b.max[k] = std::max(b.max[k], c[k]);
    }
  return b;
}

std::array<double, 2> slab(const BezierPatch& piece, const Vec3& n) {
  std::array<double, 2> r{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (int j = 0; j <= piece.degree_v; ++j)
    for (int i = 0; i <= piece.degree_u; ++i) {
      const double x = dot(n, piece.cartesian(i, j));
      r[0] = std::min(r[0], x), r[1] = std::max(r[1], x);
    }
  return r;
}

void line_roots(const BezierPatch& piece, const LineQuery& query, std::vector<LineRoot>& roots) {
  const Vec3 d = sub(query.b, query.a);
  if (!(dot(d, d) > 0)) return;
  std::vector<LineRoot> found;
  LineClipper(piece, query, found).run(piece, 0, 1, 0, 1, 0);
  std::sort(found.begin(), found.end(), [](const LineRoot& x, const LineRoot& y) {
    if (x.lambda != y.lambda) return x.lambda < y.lambda;
    return x.polished > y.polished;
  });
  // One root seen from neighbouring sub-pieces: within τ, or two unpolished reports of
  // one tangency within the Newton box.
  const double len = norm(d);
  const std::size_t first = roots.size();
  for (const LineRoot& r : found) {
    if (roots.size() > first) {
      LineRoot& last = roots.back();
      const double gap = (r.lambda - last.lambda) * len;
      if (gap <= query.tolerance || (!r.polished && !last.polished && gap <= 1e-6 * query.size)) {
        if (r.polished && !last.polished) last = r;
        continue;
      }
    }
    roots.push_back(r);
  }
}

}  // namespace cisamr::geometry::nurbs
