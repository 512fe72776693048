// Closed rational NURBS curves as chains of rational Bézier pieces (see nurbs2.hpp and
// README.md "NURBS curves"). Every decision subdivides pieces (de Casteljau in
// homogeneous coordinates) only where the query needs it: the curve is replaced by a
// chord chain that is refined around the query point, and exact orientation predicates
// decide on that chain.
#include "geometry/nurbs2.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "geometry/box_tests.hpp"
#include "geometry/nurbs_bezier.hpp"
#include "geometry/predicates2.hpp"

namespace cisamr::geometry::nurbs {
namespace {

constexpr int kMaxDegree = 31;
constexpr int kMaxHom = 3 * (kMaxDegree + 1);
using HomBuf = std::array<double, kMaxHom>;

Vec2 cart(const double* h) { return {h[0] / h[2], h[1] / h[2]}; }

Box2 control_box(const double* h, int p) {
  Box2 b{cart(h), cart(h)};
  for (int i = 1; i <= p; ++i) {
    const Vec2 q = cart(h + 3 * i);
    b.min = {std::min(b.min[0], q[0]), std::min(b.min[1], q[1])};
    b.max = {std::max(b.max[0], q[0]), std::max(b.max[1], q[1])};
  }
  return b;
}

Box2 inflate(const Box2& b, double e) { return {{b.min[0] - e, b.min[1] - e}, {b.max[0] + e, b.max[1] + e}}; }
bool in_box(const Vec2& p, const Box2& b) {
  return p[0] >= b.min[0] && p[0] <= b.max[0] && p[1] >= b.min[1] && p[1] <= b.max[1];
}
// sqrt of the sum of squares: std::hypot's overflow guard costs a third of the subdivision
// time, and coordinates here are far from overflow.
double norm2d(double dx, double dy) { return std::sqrt(dx * dx + dy * dy); }
double diag(const Box2& b) { return norm2d(b.max[0] - b.min[0], b.max[1] - b.min[1]); }

// Largest distance of a control point from the chord (control polygon flatness).
double flatness(const double* h, int p) {
  const Vec2 u = cart(h), v = cart(h + 3 * p);
  const double dx = v[0] - u[0], dy = v[1] - u[1], len = norm2d(dx, dy);
  double f = 0;
  for (int i = 1; i < p; ++i) {
    const Vec2 q = cart(h + 3 * i);
    f = std::max(f, len > 0 ? std::abs((q[0] - u[0]) * dy - (q[1] - u[1]) * dx) / len
                            : norm2d(q[0] - u[0], q[1] - u[1]));
  }
  return f;
}

// Point and derivative at s (homogeneous de Casteljau).
void eval(const double* h, int p, double s, Vec2& c, Vec2& dc) {
  double H[3], D[3];
  eval_hom<3>(h, p, s, H, D);
  c = {H[0] / H[2], H[1] / H[2]};
  dc = {(D[0] - c[0] * D[2]) / H[2], (D[1] - c[1] * D[2]) / H[2]};
}

// Does the horizontal ray from p to +x cross the chord u→v (half-open rule on y)?
bool ray_crosses(const Vec2& u, const Vec2& v, const Vec2& p) {
  if ((u[1] > p[1]) == (v[1] > p[1])) return false;
  if (p[0] > std::max(u[0], v[0])) return false;
  if (p[0] < std::min(u[0], v[0])) return true;
  const int o = exact::orientation(u, v, p);
  return (o > 0) == (v[1] > u[1]);
}

// Parity contribution of one piece, refined around p; -1 when p is ON.
int piece_parity(const Region& r, const double* h, const Vec2& p, int depth) {
  const int deg = r.degree;
  const Box2 b = inflate(control_box(h, deg), 1e-14 * r.size);
  if (!in_box(p, b)) return ray_crosses(cart(h), cart(h + 3 * deg), p) ? 1 : 0;
  if (diag(b) <= r.on_tolerance || depth > 80) return -1;
  double left[kMaxHom], right[kMaxHom];
  split_half<3>(h, deg, left, right);
  const int a = piece_parity(r, left, p, depth + 1);
  if (a < 0) return -1;
  const int c = piece_parity(r, right, p, depth + 1);
  if (c < 0) return -1;
  return a ^ c;
}

void piece_hits(const Region& r, const double* h, const Vec2& a, const Vec2& b, int depth,
                std::vector<double>& ts) {
  const int deg = r.degree;
  const Box2 bx = inflate(control_box(h, deg), 1e-14 * r.size);
  if (!detail::segment_meets_box(a, b, bx)) return;
  if (flatness(h, deg) <= 1e-15 * r.size || diag(bx) <= 1e-15 * r.size || depth > 80) {
    const Vec2 u = cart(h), v = cart(h + 3 * deg);
    if (!exact::segments_intersect(a, b, u, v)) return;
    const double dx = b[0] - a[0], dy = b[1] - a[1];
    const double ex = v[0] - u[0], ey = v[1] - u[1];
    const double den = dx * ey - dy * ex;
    double t;
    if (den != 0) t = ((u[0] - a[0]) * ey - (u[1] - a[1]) * ex) / den;
    else t = ((0.5 * (u[0] + v[0]) - a[0]) * dx + (0.5 * (u[1] + v[1]) - a[1]) * dy) / (dx * dx + dy * dy);
    if (t > 0 && t < 1) ts.push_back(t);
    return;
  }
  double left[kMaxHom], right[kMaxHom];
  split_half<3>(h, deg, left, right);
  piece_hits(r, left, a, b, depth + 1, ts);
  piece_hits(r, right, a, b, depth + 1, ts);
}

void piece_distance(const Region& r, const double* h, const Vec2& p, int depth, double& best) {
  const int deg = r.degree;
  const Box2 bx = control_box(h, deg);
  const double dx = std::max({bx.min[0] - p[0], 0.0, p[0] - bx.max[0]});
  const double dy = std::max({bx.min[1] - p[1], 0.0, p[1] - bx.max[1]});
  if (norm2d(dx, dy) >= best) return;
  const Vec2 u = cart(h), v = cart(h + 3 * deg);
  if (flatness(h, deg) <= 1e-14 * r.size || depth > 80) {
    const double ex = v[0] - u[0], ey = v[1] - u[1], ee = ex * ex + ey * ey;
    double t = ee > 0 ? ((p[0] - u[0]) * ex + (p[1] - u[1]) * ey) / ee : 0;
    t = std::clamp(t, 0.0, 1.0);
    best = std::min(best, norm2d(p[0] - u[0] - t * ex, p[1] - u[1] - t * ey));
    return;
  }
  best = std::min({best, norm2d(p[0] - u[0], p[1] - u[1]), norm2d(p[0] - v[0], p[1] - v[1])});
  double left[kMaxHom], right[kMaxHom];
  split_half<3>(h, deg, left, right);
  // Nearer half first: better pruning.
  const Vec2 m = cart(left + 3 * deg);
  const bool left_first = norm2d(p[0] - u[0], p[1] - u[1]) + norm2d(p[0] - m[0], p[1] - m[1]) <=
                          norm2d(p[0] - v[0], p[1] - v[1]) + norm2d(p[0] - m[0], p[1] - m[1]);
  piece_distance(r, left_first ? left : right, p, depth + 1, best);
  piece_distance(r, left_first ? right : left, p, depth + 1, best);
}

bool piece_touches(const Region& r, const double* h, const Box2& box, int depth) {
  const int deg = r.degree;
  const Box2 bx = inflate(control_box(h, deg), 1e-14 * r.size);
  if (bx.max[0] < box.min[0] || bx.min[0] > box.max[0] || bx.max[1] < box.min[1] || bx.min[1] > box.max[1])
    return false;
  if (in_box(cart(h), box) || in_box(cart(h + 3 * deg), box)) return true;
  if (diag(bx) <= 1e-12 * r.size || depth > 80) return true;
  double left[kMaxHom], right[kMaxHom];
  split_half<3>(h, deg, left, right);
  return piece_touches(r, left, box, depth + 1) || piece_touches(r, right, box, depth + 1);
}

void piece_flatten(const Region& r, const double* h, double tol, int depth, std::vector<Vec2>& out) {
  if (flatness(h, r.degree) <= tol || depth > 60) {
    out.push_back(cart(h));
    return;
  }
  double left[kMaxHom], right[kMaxHom];
  split_half<3>(h, r.degree, left, right);
  piece_flatten(r, left, tol, depth + 1, out);
  piece_flatten(r, right, tol, depth + 1, out);
}

Piece make_piece(const double* h, int p) {
  Piece pc;
  pc.hom.assign(h, h + 3 * (p + 1));
  pc.box = control_box(h, p);
  pc.start = cart(h);
  pc.end = cart(h + 3 * p);
  return pc;
}

void coarse_split(const double* h, int p, double tol, int depth, std::vector<Piece>& out) {
  if (flatness(h, p) <= tol || depth > 20) {
    out.push_back(make_piece(h, p));
    return;
  }
  double left[kMaxHom], right[kMaxHom];
  split_half<3>(h, p, left, right);
  coarse_split(left, p, tol, depth + 1, out);
  coarse_split(right, p, tol, depth + 1, out);
}

}  // namespace

std::string build_region(const NurbsCurve& curve, Region& out) {
  const int p = curve.degree;
  const std::size_t n = curve.control_points.size();
  if (p < 1) return ".degree: must be at least 1";
  if (p > kMaxDegree) return ".degree: at most 31 is supported";
  if (n < static_cast<std::size_t>(p) + 1) return ".control_points: a curve of degree " + std::to_string(p) + " needs at least " + std::to_string(p + 1) + " control points";
  if (curve.knots.size() != n + p + 1)
    return ".knots: expected " + std::to_string(n + p + 1) + " knots (control points + degree + 1), got " + std::to_string(curve.knots.size());
  for (std::size_t i = 0; i < curve.knots.size(); ++i) {
    if (!std::isfinite(curve.knots[i])) return ".knots: must be finite";
    if (i > 0 && curve.knots[i] < curve.knots[i - 1]) return ".knots: must be non-decreasing (knot " + std::to_string(i) + ")";
  }
  if (!curve.weights.empty() && curve.weights.size() != n)
    return ".weights: expected " + std::to_string(n) + " weights (one per control point), got " + std::to_string(curve.weights.size());
  for (double w : curve.weights)
    if (!(w > 0) || !std::isfinite(w)) return ".weights: must be positive";
  for (const Vec2& q : curve.control_points)
    if (!std::isfinite(q[0]) || !std::isfinite(q[1])) return ".control_points: coordinates must be finite";
  const double u_lo = curve.knots[p], u_hi = curve.knots[n];
  if (!(u_lo < u_hi)) return ".knots: the curve's parameter range is empty";
  // Homogeneous control points.
  std::vector<std::array<double, 3>> P(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double w = curve.weights.empty() ? 1.0 : curve.weights[i];
    P[i] = {curve.control_points[i][0] * w, curve.control_points[i][1] * w, w};
  }
  // Bézier extraction: every knot value in [u_lo, u_hi] raised to multiplicity ≥ p.
  std::vector<std::vector<double>> beziers = extract_bezier<3>(p, curve.knots, std::move(P)).points;
  if (beziers.empty()) return ".knots: the curve has no non-empty knot span";
  // Size, closedness.
  Box2 box = control_box(beziers[0].data(), p);
  for (const auto& h : beziers) {
    const Box2 b = control_box(h.data(), p);
    box.min = {std::min(box.min[0], b.min[0]), std::min(box.min[1], b.min[1])};
    box.max = {std::max(box.max[0], b.max[0]), std::max(box.max[1], b.max[1])};
  }
  const double size = diag(box);
  if (!(size > 0)) return ".control_points: the curve is a single point";
  const Vec2 first = cart(beziers.front().data()), last = cart(beziers.back().data() + 3 * p);
  if (std::hypot(first[0] - last[0], first[1] - last[1]) > 1e-9 * size)
    return ".control_points: curve is not closed (C(start) != C(end))";
  // Close the chain exactly: the last piece ends on the very triple the first starts with.
  std::copy(beziers.front().begin(), beziers.front().begin() + 3, beziers.back().end() - 3);
  // Consecutive pieces must share their joint triple (same control point after
  // extraction); enforce it against rounding in the insertion.
  for (std::size_t i = 0; i + 1 < beziers.size(); ++i)
    std::copy(beziers[i + 1].begin(), beziers[i + 1].begin() + 3, beziers[i].end() - 3);
  out = Region{};
  out.degree = p;
  out.box = box;
  out.size = size;
  out.on_tolerance = 1e-12 * size;
  for (const auto& h : beziers) coarse_split(h.data(), p, 2e-3 * size, 0, out.pieces);
  // Simple-curve check: no two non-adjacent coarse chords may cross properly.
  // (Cheap necessary check; see README.md.)
  const std::size_t m = out.pieces.size();
  for (std::size_t i = 0; i < m; ++i)
    for (std::size_t j = i + 2; j < m; ++j) {
      if (i == 0 && j == m - 1) continue;
      const Piece &a = out.pieces[i], &b = out.pieces[j];
      if (a.box.max[0] < b.box.min[0] || b.box.max[0] < a.box.min[0] || a.box.max[1] < b.box.min[1] || b.box.max[1] < a.box.min[1])
        continue;
      if (exact::segments_cross_properly(a.start, a.end, b.start, b.end))
        return ".control_points: curve is self-intersecting";
    }
  return "";
}

int side(const Region& r, const Vec2& p) {
  if (!in_box(p, inflate(r.box, 1e-14 * r.size))) return -1;
  int parity = 0;
  for (const Piece& pc : r.pieces) {
    const int c = piece_parity(r, pc.hom.data(), p, 0);
    if (c < 0) return 0;
    parity ^= c;
  }
  return parity ? 1 : -1;
}

void segment_hits(const Region& r, const Vec2& a, const Vec2& b, std::vector<double>& ts) {
  for (const Piece& pc : r.pieces) piece_hits(r, pc.hom.data(), a, b, 0, ts);
}

double distance_to_curve(const Region& r, const Vec2& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Piece& pc : r.pieces) best = std::min(best, std::hypot(p[0] - pc.start[0], p[1] - pc.start[1]));
  for (const Piece& pc : r.pieces) piece_distance(r, pc.hom.data(), p, 0, best);
  return best;
}

bool touches_box(const Region& r, const Box2& box) {
  for (const Piece& pc : r.pieces)
    if (piece_touches(r, pc.hom.data(), box, 0)) return true;
  return false;
}

namespace {
// Σ over the pieces of ∫₀¹ f(C(s), C'(s)) ds, 16-point Gauss–Legendre per piece.
template <class F>
double chain_integral(const Region& r, F&& f) {
  double sum = 0;
  for (const Piece& pc : r.pieces)
    sum += gauss16([&](double s) {
      Vec2 c, d;
      eval(pc.hom.data(), r.degree, s, c, d);
      return f(c, d);
    });
  return sum;
}
}  // namespace

double area(const Region& r) {
  return std::abs(chain_integral(r, [](const Vec2& c, const Vec2& d) { return 0.5 * (c[0] * d[1] - c[1] * d[0]); }));
}

double length(const Region& r) {
  return chain_integral(r, [](const Vec2&, const Vec2& d) { return std::hypot(d[0], d[1]); });
}

Vec2 point(const Piece& piece, int degree, double s) {
  Vec2 c, d;
  eval(piece.hom.data(), degree, s, c, d);
  return c;
}

void x_breakpoints(const Region& r, std::vector<double>& xs) {
  for (const Piece& pc : r.pieces) {
    xs.push_back(pc.start[0]);
    constexpr int n = 16;
    Vec2 c, d;
    eval(pc.hom.data(), r.degree, 0, c, d);
    double s_prev = 0, dx_prev = d[0];
    for (int i = 1; i <= n; ++i) {
      const double s = double(i) / n;
      eval(pc.hom.data(), r.degree, s, c, d);
      if ((dx_prev < 0) != (d[0] < 0)) {
        double lo = s_prev, hi = s;
        for (int it = 0; it < 60; ++it) {
          const double mid = 0.5 * (lo + hi);
          Vec2 cm, dm;
          eval(pc.hom.data(), r.degree, mid, cm, dm);
          if ((dm[0] < 0) == (dx_prev < 0)) lo = mid;
          else hi = mid;
        }
        eval(pc.hom.data(), r.degree, 0.5 * (lo + hi), c, d);
        xs.push_back(c[0]);
        eval(pc.hom.data(), r.degree, s, c, d);
      }
      s_prev = s;
      dx_prev = d[0];
    }
  }
}

// Branch and bound: a piece whose control box lies in the box found so far adds nothing
// (the curve stays in its control polygon's hull); others split until their control box
// is within tol, then join whole. Contains the curve, at most tol larger; a few dozen
// splits per extremum where flattening to tol would take ~1/sqrt(tol) points.
Box2 tight_box(const Region& r, double tol) {
  Box2 b{r.pieces.front().start, r.pieces.front().start};
  auto join = [&b](const Box2& c) {
    for (int d = 0; d < 2; ++d) b.min[d] = std::min(b.min[d], c.min[d]), b.max[d] = std::max(b.max[d], c.max[d]);
  };
  for (const Piece& pc : r.pieces) join({pc.start, pc.start}), join({pc.end, pc.end});
  const int n = 3 * (r.degree + 1);
  std::vector<double> stack;
  for (const Piece& pc : r.pieces) stack.insert(stack.end(), pc.hom.begin(), pc.hom.end());
  std::vector<int> depth(r.pieces.size(), 0);
  while (!depth.empty()) {
    double h[kMaxHom];
    std::copy(stack.end() - n, stack.end(), h);
    stack.resize(stack.size() - static_cast<std::size_t>(n));
    const int level = depth.back();
    depth.pop_back();
    const Box2 c = control_box(h, r.degree);
    if (in_box(c.min, b) && in_box(c.max, b)) continue;
    if (diag(c) <= tol || level > 80) {
      join(c);
      continue;
    }
    double left[kMaxHom], right[kMaxHom];
    split_half<3>(h, r.degree, left, right);
    const Vec2 mid = cart(right);
    join({mid, mid});
    stack.insert(stack.end(), left, left + n), depth.push_back(level + 1);
    stack.insert(stack.end(), right, right + n), depth.push_back(level + 1);
  }
  return b;
}

std::vector<Vec2> flatten(const Region& r, double tol) {
  std::vector<Vec2> out;
  for (const Piece& pc : r.pieces) piece_flatten(r, pc.hom.data(), tol, 0, out);
  return out;
}

}  // namespace cisamr::geometry::nurbs
