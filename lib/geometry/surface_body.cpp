// Closed exact surfaces of rational Bézier pieces (contract in surface_body.hpp; design in
// docs/nurbs-step-design.md §2).
#include "geometry/surface_body.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <initializer_list>
#include <map>
#include <mutex>
#include <numeric>
#include <set>

#include "core/vec_math.hpp"
#include "geometry/nurbs_bezier.hpp"
#include "geometry/shape_model.hpp"

namespace cisamr::geometry::surface {
namespace {

constexpr double kUnit = std::numeric_limits<double>::epsilon() / 2;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::size_t kMaxTriangles = std::size_t{1} << 20;
// Shells at most about this thick (× size): thin enough that few queries need the exact
// surface, coarse enough that a sphere takes about 1,500 triangles.
constexpr double kThicknessTarget = 1e-3;

const char* const kSideName[4] = {"v_min", "u_max", "v_max", "u_min"};

// ---------------------------------------------------------------- sides

// The boundary curve of a patch on one side, as its Bézier spans: side 0 is v = v_min
// (along u), 1 u = u_max (along v), 2 v = v_max (along u), 3 u = u_min (along v).
struct SideCurve {
  int degree = 0;
  std::vector<std::vector<double>> spans;  // homogeneous points of each span, in parameter order
};

SideCurve side_curve(const nurbs::PatchPieces& pp, int side) {
  SideCurve c;
  const bool along_u = side == 0 || side == 2;
  const int spans = along_u ? pp.count_u : pp.count_v;
  const nurbs::BezierPatch& first = pp.pieces[0];
  c.degree = along_u ? first.degree_u : first.degree_v;
  for (int k = 0; k < spans; ++k) {
    const int a = along_u ? k : (side == 1 ? pp.count_u - 1 : 0);
    const int b = along_u ? (side == 2 ? pp.count_v - 1 : 0) : k;
    const nurbs::BezierPatch& piece = pp.pieces[static_cast<std::size_t>(a + pp.count_u * b)];
    std::vector<double> h;
    for (int m = 0; m <= c.degree; ++m) {
      const int i = along_u ? m : (side == 1 ? piece.degree_u : 0);
      const int j = along_u ? (side == 2 ? piece.degree_v : 0) : m;
      h.insert(h.end(), piece.point(i, j), piece.point(i, j) + 4);
    }
    c.spans.push_back(std::move(h));
  }
  return c;
}

Vec3 cart(const double* h) { return {h[0] / h[3], h[1] / h[3], h[2] / h[3]}; }

// ---------------------------------------------------------------- shared breakpoints

// Normalised breakpoints of a patch along u (dir 0) or v (dir 1): the inner span ends
// mapped to (0, 1).
std::vector<double> breakpoints(const nurbs::PatchPieces& pp, int dir) {
  std::vector<double> out;
  const int n = dir == 0 ? pp.count_u : pp.count_v;
  const nurbs::BezierPatch& first = pp.pieces.front();
  const nurbs::BezierPatch& last = pp.pieces[dir == 0 ? static_cast<std::size_t>(pp.count_u - 1) : pp.pieces.size() - 1];
  const double lo = dir == 0 ? first.u0 : first.v0, hi = dir == 0 ? last.u1 : last.v1;
  for (int k = 1; k < n; ++k) {
    const nurbs::BezierPatch& piece = pp.pieces[dir == 0 ? static_cast<std::size_t>(k) : static_cast<std::size_t>(k * pp.count_u)];
    out.push_back(((dir == 0 ? piece.u0 : piece.v0) - lo) / (hi - lo));
  }
  return out;
}

// The point of a patch's side at normalised parameter tau along it (sides as side_curve).
Vec3 side_point_at(const nurbs::PatchPieces& pp, int side, double tau) {
  const bool along_u = side == 0 || side == 2;
  const std::vector<double> b = breakpoints(pp, along_u ? 0 : 1);
  const int k = static_cast<int>(std::upper_bound(b.begin(), b.end(), tau) - b.begin());
  const double a0 = k == 0 ? 0.0 : b[static_cast<std::size_t>(k - 1)], a1 = k == static_cast<int>(b.size()) ? 1.0 : b[static_cast<std::size_t>(k)];
  const double local = std::clamp((tau - a0) / (a1 - a0), 0.0, 1.0);
  const int a = along_u ? k : (side == 1 ? pp.count_u - 1 : 0);
  const int c = along_u ? (side == 2 ? pp.count_v - 1 : 0) : k;
  const nurbs::BezierPatch& piece = pp.pieces[static_cast<std::size_t>(a + pp.count_u * c)];
  return along_u ? nurbs::evaluate(piece, local, side == 2 ? 1.0 : 0.0) : nurbs::evaluate(piece, side == 1 ? 1.0 : 0.0, local);
}

// Splits every piece of the patch at the normalised parameters `at` along dir (exact: the
// surface is unchanged, each span becomes two rational Bézier pieces by de Casteljau).
void split_at(nurbs::PatchPieces& pp, int dir, const std::vector<double>& at) {
  for (double tau : at) {
    const std::vector<double> b = breakpoints(pp, dir);
    const int k = static_cast<int>(std::upper_bound(b.begin(), b.end(), tau) - b.begin());
    const double a0 = k == 0 ? 0.0 : b[static_cast<std::size_t>(k - 1)], a1 = k == static_cast<int>(b.size()) ? 1.0 : b[static_cast<std::size_t>(k)];
    const double local = (tau - a0) / (a1 - a0);
    nurbs::PatchPieces out;
    out.count_u = pp.count_u + (dir == 0 ? 1 : 0);
    out.count_v = pp.count_v + (dir == 1 ? 1 : 0);
    for (int j = 0; j < pp.count_v; ++j)
      for (int half = 0; half < (dir == 1 && j == k ? 2 : 1); ++half)
        for (int i = 0; i < pp.count_u; ++i) {
          const nurbs::BezierPatch& piece = pp.pieces[static_cast<std::size_t>(i + pp.count_u * j)];
          if (dir == 0 && i == k) {
            for (int h = 0; h < 2; ++h) {
              nurbs::BezierPatch part = nurbs::restrict_patch(piece, h == 0 ? 0.0 : local, h == 0 ? local : 1.0, 0.0, 1.0);
              const double mid = piece.u0 + local * (piece.u1 - piece.u0);
              part.u0 = h == 0 ? piece.u0 : mid, part.u1 = h == 0 ? mid : piece.u1, part.v0 = piece.v0, part.v1 = piece.v1;
              out.pieces.push_back(std::move(part));
            }
          } else if (dir == 1 && j == k) {
            nurbs::BezierPatch part = nurbs::restrict_patch(piece, 0.0, 1.0, half == 0 ? 0.0 : local, half == 0 ? local : 1.0);
            const double mid = piece.v0 + local * (piece.v1 - piece.v0);
            part.u0 = piece.u0, part.u1 = piece.u1, part.v0 = half == 0 ? piece.v0 : mid, part.v1 = half == 0 ? mid : piece.v1;
            out.pieces.push_back(std::move(part));
          } else {
            out.pieces.push_back(piece);
          }
        }
    pp = std::move(out);
  }
}

// Neighbouring patches whose shared side is the same curve (17 points along it agree within
// kappa, in either direction) but broken at different knots: each is split at the other's
// breakpoints, and those at its opposite side's partner's, until every matched pair has
// the same spans; the exact match then compares control points as for conforming patches.
void share_breakpoints(std::vector<nurbs::PatchPieces>& patches, double kappa) {
  const int np = static_cast<int>(patches.size());
  struct Pair {
    int a, b;  // sides 4k + s
    bool reversed;
  };
  std::vector<Pair> pairs;
  auto degree_along = [&](int side) {
    const nurbs::BezierPatch& p = patches[static_cast<std::size_t>(side / 4)].pieces.front();
    return side % 4 == 0 || side % 4 == 2 ? p.degree_u : p.degree_v;
  };
  std::vector<std::array<Vec3, 3>> ends(static_cast<std::size_t>(4 * np));  // start, middle, end
  for (int a = 0; a < 4 * np; ++a)
    for (int i = 0; i < 3; ++i)
      ends[static_cast<std::size_t>(a)][static_cast<std::size_t>(i)] = side_point_at(patches[static_cast<std::size_t>(a / 4)], a % 4, 0.5 * i);
  const auto near = [kappa](const Vec3& x, const Vec3& y) { return norm(sub(x, y)) <= kappa; };
  for (int a = 0; a < 4 * np; ++a) {
    const nurbs::PatchPieces& pa = patches[static_cast<std::size_t>(a / 4)];
    const auto& ea = ends[static_cast<std::size_t>(a)];
    if (near(ea[0], ea[2]) && near(ea[0], ea[1])) continue;  // a pole (one point) pairs with nothing
    for (int b = a + 1; b < 4 * np; ++b) {
      if (degree_along(a) != degree_along(b)) continue;
      const auto& eb = ends[static_cast<std::size_t>(b)];
      const nurbs::PatchPieces& pb = patches[static_cast<std::size_t>(b / 4)];
      for (bool rev : {false, true}) {
        if (!near(ea[0], eb[rev ? 2 : 0]) || !near(ea[2], eb[rev ? 0 : 2]) || !near(ea[1], eb[1])) continue;
        bool same = true;
        for (int i = 0; i <= 16 && same; ++i) {
          const double tau = i / 16.0;
          same = norm(sub(side_point_at(pa, a % 4, tau), side_point_at(pb, b % 4, rev ? 1 - tau : tau))) <= kappa;
        }
        if (same) {
          pairs.push_back({a, b, rev});
          break;
        }
      }
    }
  }
  if (pairs.empty()) return;
  const auto dir_of = [](int side) { return side % 4 == 0 || side % 4 == 2 ? 0 : 1; };
  std::vector<std::vector<double>> wanted(static_cast<std::size_t>(2 * np));
  for (int k = 0; k < np; ++k)
    for (int d = 0; d < 2; ++d) wanted[static_cast<std::size_t>(2 * k + d)] = breakpoints(patches[static_cast<std::size_t>(k)], d);
  const auto add = [](std::vector<double>& set, double tau) {
    for (double x : set)
      if (std::abs(x - tau) <= 1e-12) return false;
    if (tau <= 1e-12 || tau >= 1 - 1e-12) return false;
    set.insert(std::upper_bound(set.begin(), set.end(), tau), tau);
    return true;
  };
  for (bool changed = true; changed;) {
    changed = false;
    for (const Pair& p : pairs)
      for (int w = 0; w < 2; ++w) {
        const int from = w == 0 ? p.b : p.a, to = w == 0 ? p.a : p.b;
        std::vector<double>& target = wanted[static_cast<std::size_t>(2 * (to / 4) + dir_of(to))];
        for (double tau : std::vector<double>(wanted[static_cast<std::size_t>(2 * (from / 4) + dir_of(from))]))
          changed = add(target, p.reversed ? 1 - tau : tau) || changed;
        if (target.size() > 4096) return;  // runaway: leave it to the exact match to refuse
      }
  }
  for (int k = 0; k < np; ++k)
    for (int d = 0; d < 2; ++d) {
      const std::vector<double> have = breakpoints(patches[static_cast<std::size_t>(k)], d);
      std::vector<double> extra;
      for (double tau : wanted[static_cast<std::size_t>(2 * k + d)]) {
        bool present = false;
        for (double x : have) present = present || std::abs(x - tau) <= 1e-12;
        if (!present) extra.push_back(tau);
      }
      split_at(patches[static_cast<std::size_t>(k)], d, extra);
    }
}

// Largest distance of the curve's control points from its first one.
double pole_spread(const SideCurve& c) {
  const Vec3 p0 = cart(c.spans[0].data());
  double d = 0;
  for (const auto& s : c.spans)
    for (int m = 0; m <= c.degree; ++m) d = std::max(d, norm(sub(cart(s.data() + 4 * m), p0)));
  return d;
}

// Largest control-point distance between two curves taken as the same rational Bézier
// spans (reversed: b run backwards), or infinity when they cannot be (counts, degrees,
// weights not proportional).
double curve_gap(const SideCurve& a, const SideCurve& b, bool reversed) {
  if (a.degree != b.degree || a.spans.size() != b.spans.size()) return kInf;
  const std::size_t n = a.spans.size();
  const int p = a.degree;
  double gap = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const std::vector<double>& sa = a.spans[k];
    const std::vector<double>& sb = b.spans[reversed ? n - 1 - k : k];
    for (int m = 0; m <= p; ++m) {
      const double* ha = sa.data() + 4 * m;
      const double* hb = sb.data() + 4 * (reversed ? p - m : m);
      const double* ha0 = sa.data();
      const double* hb0 = sb.data() + 4 * (reversed ? p : 0);
      if (std::abs(ha[3] / ha0[3] - hb[3] / hb0[3]) > 1e-12 * (ha[3] / ha0[3])) return kInf;
      gap = std::max(gap, norm(sub(cart(ha), cart(hb))));
    }
  }
  return gap;
}

// FNV-1a over bytes, and over every number of a set of patches.
void fnv1a(std::uint64_t& h, const void* data, std::size_t n) {
  const auto* b = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
}

std::uint64_t patches_hash(const std::vector<NurbsPatch>& patches) {
  std::uint64_t h = 1469598103934665603ull;
  for (const NurbsPatch& p : patches) {
    fnv1a(h, p.degree.data(), sizeof p.degree);
    for (const auto* v : {&p.knots_u, &p.knots_v, &p.weights}) {
      const std::size_t n = v->size();
      fnv1a(h, &n, sizeof n);
      fnv1a(h, v->data(), n * sizeof(double));
    }
    const std::size_t n = p.control_points.size();
    fnv1a(h, &n, sizeof n);
    fnv1a(h, p.control_points.data(), n * sizeof(Vec3));
  }
  return h;
}

// ---------------------------------------------------------------- small helpers

struct UnionFind {
  std::vector<std::int32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::int32_t find(std::int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::int32_t a, std::int32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the smaller id represents
  }
};

void grow(Box3& b, const Vec3& p) {
  for (int k = 0; k < 3; ++k) b.min[k] = std::min(b.min[k], p[k]), b.max[k] = std::max(b.max[k], p[k]);
}

Box3 empty_box() { return {{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}}; }

Vec3 unit(const Vec3& v) {
  const double n = norm(v);
  return n > 0 ? scale(v, 1 / n) : Vec3{0, 0, 0};
}

// Halves a piece across its longer parameter direction (by the lengths of its corner-to-
// corner sides): the split of every subdivision search here.
void halve_longer(const nurbs::BezierPatch& piece, nurbs::BezierPatch& lo, nurbs::BezierPatch& hi) {
  const int p = piece.degree_u, q = piece.degree_v;
  const Vec3 c00 = piece.cartesian(0, 0), c10 = piece.cartesian(p, 0), c01 = piece.cartesian(0, q), c11 = piece.cartesian(p, q);
  if (norm(sub(c10, c00)) + norm(sub(c11, c01)) >= norm(sub(c01, c00)) + norm(sub(c11, c10)))
    nurbs::halve_u(piece, lo, hi);
  else
    nurbs::halve_v(piece, lo, hi);
}

double max_abs(const Box3& b) {
  double m = 0;
  for (int k = 0; k < 3; ++k) m = std::max({m, std::abs(b.min[k]), std::abs(b.max[k])});
  return m;
}

// Fits a cell's shell: the box of the restricted piece's control points and `points` (its
// triangles' corners), and the slab of both along the normal (the given one; where it is
// zero, the piece's at its centre), widened by `widen`, rounding and τ.
void fit_shell(Cell& c, const nurbs::BezierPatch& sub_piece, std::initializer_list<const Vec3*> points, double widen,
               double tolerance) {
  if (c.normal == Vec3{0, 0, 0}) {
    Vec3 ds, dt;
    nurbs::evaluate(sub_piece, 0.5, 0.5, &ds, &dt);
    c.normal = unit(cross(ds, dt));
    if (c.normal == Vec3{0, 0, 0}) c.normal = {1, 0, 0};
  }
  c.box = nurbs::control_box(sub_piece);
  const std::array<double, 2> slab = nurbs::slab(sub_piece, c.normal);
  c.lo = slab[0], c.hi = slab[1];
  for (const Vec3* p : points) {
    grow(c.box, *p);
    c.lo = std::min(c.lo, dot(c.normal, *p)), c.hi = std::max(c.hi, dot(c.normal, *p));
  }
  const double w = widen + 8 * kUnit * max_abs(c.box) + tolerance;
  for (int d = 0; d < 3; ++d) c.box.min[d] -= w, c.box.max[d] += w;
  c.lo -= w, c.hi += w;
}

// Samples per Bézier span in one direction so that a cell deviates from its chords by
// about target: the second differences of the control net bound the second derivative.
int samples_per_span(const nurbs::BezierPatch& piece, bool along_u, double target) {
  const int p = along_u ? piece.degree_u : piece.degree_v;
  if (p < 2) return 1;
  const int q = along_u ? piece.degree_v : piece.degree_u;
  double second = 0;
  for (int r = 0; r <= q; ++r)
    for (int m = 1; m < p; ++m) {
      auto at = [&](int k) { return along_u ? piece.cartesian(k, r) : piece.cartesian(r, k); };
      second = std::max(second, norm(add(sub(at(m - 1), scale(at(m), 2)), at(m + 1))));
    }
  const double bound = p * (p - 1) * second;
  return std::clamp(static_cast<int>(std::ceil(std::sqrt(bound / (8 * target)))), 1, 64);
}

// Face indices named in stl's problem text: "(face 12)" or "(faces 3 and 7)".
std::vector<std::int64_t> faces_named(const std::string& problem) {
  std::vector<std::int64_t> out;
  for (const char* key : {"(face ", "(faces "}) {
    std::size_t at = problem.find(key);
    if (at == std::string::npos) continue;
    at += std::strlen(key);
    while (at < problem.size()) {
      std::size_t end = at;
      while (end < problem.size() && std::isdigit(static_cast<unsigned char>(problem[end]))) ++end;
      if (end == at) break;
      out.push_back(std::stoll(problem.substr(at, end - at)));
      at = problem.find_first_of("0123456789)", end);
      if (at == std::string::npos || problem[at] == ')') break;
    }
  }
  return out;
}

std::string format_point(const Vec3& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.6g, %.6g, %.6g)", p[0], p[1], p[2]);
  return buf;
}

// ∫∫ f(S, S_s, S_t) over the square [s0, s1] × [t0, t1] of a piece, tensor Gauss–Legendre.
template <class F>
double square_integral(const nurbs::BezierPatch& piece, double s0, double s1, double t0, double t1, F&& f) {
  return (s1 - s0) * (t1 - t0) * nurbs::gauss16([&](double y) {
           return nurbs::gauss16([&](double x) {
             Vec3 ds, dt;
             const Vec3 p = nurbs::evaluate(piece, s0 + x * (s1 - s0), t0 + y * (t1 - t0), &ds, &dt);
             return f(p, ds, dt);
           });
         });
}

// The integral over the whole piece, on 2^k × 2^k squares until two refinements agree to
// 1e-14 relative (rational integrands are smooth but not polynomial).
template <class F>
double piece_integral(const nurbs::BezierPatch& piece, F&& f) {
  auto at_level = [&](int n) {
    double sum = 0;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        sum += square_integral(piece, double(i) / n, double(i + 1) / n, double(j) / n, double(j + 1) / n, f);
    return sum;
  };
  double prev = at_level(1);
  for (int n = 2; n <= 16; n *= 2) {
    const double cur = at_level(n);
    if (std::abs(cur - prev) <= 1e-14 * std::max(std::abs(cur), 1e-300)) return cur;
    prev = cur;
  }
  return prev;
}

}  // namespace

Vec3 place(const NurbsSurface& s, const Vec3& v) {
  Vec3 w{};
  for (int r = 0; r < 3; ++r)
    w[r] = s.rotation[r][0] * (s.scale * v[0]) + s.rotation[r][1] * (s.scale * v[1]) +
           s.rotation[r][2] * (s.scale * v[2]) + s.translate[r];
  return w;
}

Stats& stats() {
  thread_local Stats s;
  return s;
}

// ---------------------------------------------------------------- build

std::string build(const NurbsSurface& surface, Body& body) {
  body = Body{};
  if (!(surface.scale > 0) || !std::isfinite(surface.scale)) return ".scale: must be positive";
  if (!orthonormal(surface.rotation)) return ".rotation: must be orthonormal";
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(surface.translate[k])) return ".translate: must be finite";
  if (surface.patches.empty()) return ".patches: needs at least one patch";
  const int np = static_cast<int>(surface.patches.size());
  auto patch_field = [](int k) { return ".patches[" + std::to_string(k) + "]"; };

  // Placed pieces.
  body.patches.resize(static_cast<std::size_t>(np));
  Box3 box = empty_box();
  for (int k = 0; k < np; ++k) {
    NurbsPatch placed = surface.patches[static_cast<std::size_t>(k)];
    for (Vec3& v : placed.control_points) {
      if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
        return patch_field(k) + ".control_points: must be finite";
      v = place(surface, v);
    }
    const std::string problem = nurbs::extract_patch(placed, body.patches[static_cast<std::size_t>(k)]);
    if (!problem.empty()) return patch_field(k) + problem;
    for (const nurbs::BezierPatch& piece : body.patches[static_cast<std::size_t>(k)].pieces) {
      const Box3 cb = nurbs::control_box(piece);
      grow(box, cb.min), grow(box, cb.max);
    }
  }
  body.box = box;
  body.size = norm(sub(box.max, box.min));
  if (!(body.size > 0)) return ".patches: all control points coincide";
  body.tolerance = 1e-12 * body.size;
  const double kappa = 1e-9 * body.size;  // sides closer than this are one curve
  share_breakpoints(body.patches, kappa);

  // Sides: poles, then every other side matched with exactly one other side.
  std::vector<SideCurve> curves(static_cast<std::size_t>(4 * np));
  std::vector<char> pole(curves.size(), 0);
  for (int k = 0; k < np; ++k)
    for (int s = 0; s < 4; ++s) {
      curves[static_cast<std::size_t>(4 * k + s)] = side_curve(body.patches[static_cast<std::size_t>(k)], s);
      pole[static_cast<std::size_t>(4 * k + s)] = pole_spread(curves[static_cast<std::size_t>(4 * k + s)]) <= kappa;
    }
  for (int k = 0; k < np; ++k) {
    bool all_poles = true;
    for (int s = 0; s < 4; ++s) all_poles = all_poles && pole[static_cast<std::size_t>(4 * k + s)];
    if (all_poles) return patch_field(k) + ": all control points of its boundary coincide";
  }
  struct Match {
    int other = -1;
    bool reversed = false;
    double gap = 0;
  };
  std::vector<Match> match(curves.size());
  for (std::size_t a = 0; a < curves.size(); ++a) {
    if (pole[a]) continue;
    int count = 0;
    std::string names;
    double nearest = kInf;
    for (std::size_t b = 0; b < curves.size(); ++b) {
      if (b == a || pole[b]) continue;
      for (bool rev : {false, true}) {
        const double g = curve_gap(curves[a], curves[b], rev);
        if (g <= kappa) {
          if (count == 0 || match[a].other != static_cast<int>(b)) {
            ++count;
            names += std::string(names.empty() ? "" : ", ") + "patches[" + std::to_string(b / 4) + "]." +
                     kSideName[b % 4];
          }
          match[a] = {static_cast<int>(b), rev, g};
          break;
        }
        // How far the nearest candidate is: its end points.
        const SideCurve &ca = curves[a], &cb = curves[b];
        const Vec3 a0 = cart(ca.spans.front().data()), b0 = cart(cb.spans.front().data());
        const Vec3 b1 = cart(cb.spans.back().data() + 4 * cb.degree);
        nearest = std::min({nearest, norm(sub(a0, b0)), norm(sub(a0, b1))});
      }
    }
    const std::string field = patch_field(static_cast<int>(a / 4)) + "." + kSideName[a % 4];
    if (count == 0) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.3g", nearest);
      return field + ": meets no other patch boundary within 1e-9 of the size " +
             "(patches meet along shared boundary curves, the same curve split at each other's knots; nearest end point " +
             buf + " away, at " +
             format_point(cart(curves[a].spans.front().data())) + ")";
    }
    if (count > 1) return field + ": meets " + std::to_string(count) + " boundaries (" + names + ")";
  }

  // Orientation: matched sides must be traversed oppositely in the patches' own
  // counter-clockwise (u, v) order; flip patches to make them so.
  const int ccw[4] = {1, 1, -1, -1};
  std::vector<int> flip(static_cast<std::size_t>(np), -1);
  for (int start = 0; start < np; ++start) {
    if (flip[static_cast<std::size_t>(start)] >= 0) continue;
    flip[static_cast<std::size_t>(start)] = 0;
    std::vector<int> stack{start};
    while (!stack.empty()) {
      const int k = stack.back();
      stack.pop_back();
      for (int s = 0; s < 4; ++s) {
        const Match& m = match[static_cast<std::size_t>(4 * k + s)];
        if (m.other < 0) continue;
        const int o = m.other / 4, os = m.other % 4;
        const bool opposite = ccw[s] * ccw[os] * (m.reversed ? -1 : 1) < 0;
        const int want = flip[static_cast<std::size_t>(k)] ^ (opposite ? 0 : 1);
        if (flip[static_cast<std::size_t>(o)] < 0) {
          flip[static_cast<std::size_t>(o)] = want;
          stack.push_back(o);
        } else if (flip[static_cast<std::size_t>(o)] != want) {
          return ".patches: the patches cannot be oriented consistently (patches[" + std::to_string(k) + "]." +
                 kSideName[s] + " meets patches[" + std::to_string(o) + "]." + kSideName[os] + ")";
        }
      }
    }
  }

  // Samples per span: one count per class of directions linked through matched sides.
  UnionFind dirs(static_cast<std::size_t>(2 * np));
  for (std::size_t a = 0; a < curves.size(); ++a)
    if (match[a].other >= 0) {
      const int da = (a % 4 == 0 || a % 4 == 2) ? 0 : 1;
      const int b = match[a].other;
      const int db = (b % 4 == 0 || b % 4 == 2) ? 0 : 1;
      dirs.unite(static_cast<std::int32_t>(2 * (a / 4) + da), static_cast<std::int32_t>(2 * (b / 4) + db));
    }
  std::vector<int> n_class(static_cast<std::size_t>(2 * np), 1);
  for (int k = 0; k < np; ++k)
    for (const nurbs::BezierPatch& piece : body.patches[static_cast<std::size_t>(k)].pieces)
      for (int d = 0; d < 2; ++d) {
        const std::int32_t c = dirs.find(2 * k + d);
        n_class[static_cast<std::size_t>(c)] =
            std::max(n_class[static_cast<std::size_t>(c)], samples_per_span(piece, d == 0, kThicknessTarget * body.size));
      }

  // Grids: patch k has (Nu + 1) × (Nv + 1) points from base[k].
  std::vector<int> nu(np), nv(np), per_u(np), per_v(np);
  std::vector<std::int64_t> base(static_cast<std::size_t>(np) + 1, 0);
  for (int k = 0; k < np; ++k) {
    const nurbs::PatchPieces& pp = body.patches[static_cast<std::size_t>(k)];
    per_u[k] = n_class[static_cast<std::size_t>(dirs.find(2 * k))];
    per_v[k] = n_class[static_cast<std::size_t>(dirs.find(2 * k + 1))];
    nu[k] = pp.count_u * per_u[k];
    nv[k] = pp.count_v * per_v[k];
    base[k + 1] = base[k] + std::int64_t{nu[k] + 1} * (nv[k] + 1);
    if (2 * std::size_t(nu[k]) * nv[k] > kMaxTriangles)
      return patch_field(k) + ": needs more than " + std::to_string(kMaxTriangles) + " triangles";
  }
  if (base[np] > std::int64_t{1} << 30) return ".patches: too many tessellation points";
  auto grid_id = [&](int k, int i, int j) { return static_cast<std::int32_t>(base[k] + i + std::int64_t{nu[k] + 1} * j); };
  // Local (piece, s, t) of grid point (i, j).
  auto locate = [&](int k, int i, int j, int& piece, double& s, double& t) {
    const nurbs::PatchPieces& pp = body.patches[static_cast<std::size_t>(k)];
    const int a = std::min(i / per_u[k], pp.count_u - 1), b = std::min(j / per_v[k], pp.count_v - 1);
    piece = a + pp.count_u * b;
    s = double(i - a * per_u[k]) / per_u[k];
    t = double(j - b * per_v[k]) / per_v[k];
  };
  auto side_point = [&](int k, int s, int m) {
    switch (s) {
      case 0: return grid_id(k, m, 0);
      case 1: return grid_id(k, nu[k], m);
      case 2: return grid_id(k, m, nv[k]);
      default: return grid_id(k, 0, m);
    }
  };
  auto side_length = [&](int k, int s) { return (s == 0 || s == 2) ? nu[k] : nv[k]; };

  const std::size_t npoints = static_cast<std::size_t>(base[np]);
  std::vector<Vec3> surface_at(npoints);
  for (int k = 0; k < np; ++k) {
    const nurbs::PatchPieces& pp = body.patches[static_cast<std::size_t>(k)];
    for (int j = 0; j <= nv[k]; ++j)
      for (int i = 0; i <= nu[k]; ++i) {
        int piece;
        double s, t;
        locate(k, i, j, piece, s, t);
        surface_at[static_cast<std::size_t>(grid_id(k, i, j))] = nurbs::evaluate(pp.pieces[static_cast<std::size_t>(piece)], s, t);
      }
  }
  // Weld: matched sides point to point, poles to one point.
  UnionFind weld(npoints);
  std::vector<Vec3> position = surface_at;
  for (int k = 0; k < np; ++k)
    for (int s = 0; s < 4; ++s) {
      const std::size_t a = static_cast<std::size_t>(4 * k + s);
      const int len = side_length(k, s);
      if (pole[a]) {
        const Vec3 p0 = cart(curves[a].spans[0].data());
        for (int m = 0; m <= len; ++m) {
          weld.unite(side_point(k, s, 0), side_point(k, s, m));
          position[static_cast<std::size_t>(side_point(k, s, m))] = p0;
        }
        continue;
      }
      const Match& mt = match[a];
      const int o = mt.other / 4, os = mt.other % 4;
      if (side_length(o, os) != len) return ".patches: internal error (side sample counts differ)";
      for (int m = 0; m <= len; ++m) weld.unite(side_point(k, s, m), side_point(o, os, mt.reversed ? len - m : m));
    }
  std::vector<std::int32_t> vertex_of(npoints, -1);
  std::vector<Vec3> vertices;
  for (std::size_t g = 0; g < npoints; ++g) {
    const std::int32_t r = weld.find(static_cast<std::int32_t>(g));
    if (vertex_of[static_cast<std::size_t>(r)] < 0) {
      vertex_of[static_cast<std::size_t>(r)] = static_cast<std::int32_t>(vertices.size());
      vertices.push_back(position[static_cast<std::size_t>(r)]);
    }
    vertex_of[g] = vertex_of[static_cast<std::size_t>(r)];
  }
  // How far each grid point's own surface point lies from its welded vertex.
  std::vector<double> gap(npoints);
  for (std::size_t g = 0; g < npoints; ++g)
    gap[g] = norm(sub(surface_at[g], vertices[static_cast<std::size_t>(vertex_of[g])]));

  // Cells and triangles.
  std::vector<std::array<std::int32_t, 3>> faces;
  std::vector<std::int32_t> face_cell;
  for (int k = 0; k < np; ++k) {
    const nurbs::PatchPieces& pp = body.patches[static_cast<std::size_t>(k)];
    const bool flipped = flip[static_cast<std::size_t>(k)] == 1;
    for (int j = 0; j < nv[k]; ++j)
      for (int i = 0; i < nu[k]; ++i) {
        Cell c;
        c.patch = k;
        double s0, t0;
        locate(k, i, j, c.piece, s0, t0);
        c.s0 = s0, c.t0 = t0;
        c.s1 = double(i + 1 - (c.piece % pp.count_u) * per_u[k]) / per_u[k];
        c.t1 = double(j + 1 - (c.piece / pp.count_u) * per_v[k]) / per_v[k];
        c.outward = flipped ? -1 : 1;
        const std::int32_t g[4] = {grid_id(k, i, j), grid_id(k, i + 1, j), grid_id(k, i + 1, j + 1), grid_id(k, i, j + 1)};
        std::int32_t v[4];
        double widen = 0;
        for (int q = 0; q < 4; ++q) {
          v[q] = vertex_of[static_cast<std::size_t>(g[q])];
          widen = std::max(widen, gap[static_cast<std::size_t>(g[q])]);
        }
        const nurbs::BezierPatch sub_piece =
            nurbs::restrict_patch(pp.pieces[static_cast<std::size_t>(c.piece)], c.s0, c.s1, c.t0, c.t1);
        const Vec3 &p0 = vertices[static_cast<std::size_t>(v[0])], &p1 = vertices[static_cast<std::size_t>(v[1])],
                   &p2 = vertices[static_cast<std::size_t>(v[2])], &p3 = vertices[static_cast<std::size_t>(v[3])];
        c.normal = unit(cross(sub(p2, p0), sub(p3, p1)));
        fit_shell(c, sub_piece, {&p0, &p1, &p2, &p3}, widen, body.tolerance);
        body.max_thickness = std::max(body.max_thickness, c.hi - c.lo);
        const auto cell_id = static_cast<std::int32_t>(body.cells.size());
        body.cells.push_back(c);
        body.cell_pieces.push_back(sub_piece);
        // Triangles: the quad split along its shorter diagonal; corners welded into one
        // (a pole) leave one triangle or none.
        auto emit = [&](std::int32_t a, std::int32_t b, std::int32_t d) {
          if (a == b || b == d || a == d) return;
          faces.push_back(flipped ? std::array<std::int32_t, 3>{a, d, b} : std::array<std::int32_t, 3>{a, b, d});
          face_cell.push_back(cell_id);
        };
        const double d02 = norm(sub(p2, p0)), d13 = norm(sub(p3, p1));
        if (v[0] == v[1] || v[2] == v[3] || v[1] == v[2] || v[3] == v[0]) {
          emit(v[0], v[1], v[2]);
          emit(v[0], v[2], v[3]);
        } else if (d02 <= d13) {
          emit(v[0], v[1], v[2]);
          emit(v[0], v[2], v[3]);
        } else {
          emit(v[0], v[1], v[3]);
          emit(v[1], v[2], v[3]);
        }
      }
  }
  if (faces.size() > kMaxTriangles) return ".patches: needs more than " + std::to_string(kMaxTriangles) + " triangles";

  // The whole surface may face either way: make the tessellation (and every cell's
  // outward sign) face out.
  double six_volume = 0;
  for (const auto& f : faces) {
    const Vec3 &a = vertices[static_cast<std::size_t>(f[0])], &b = vertices[static_cast<std::size_t>(f[1])],
               &c = vertices[static_cast<std::size_t>(f[2])];
    six_volume += dot(a, cross(b, c));
  }
  if (six_volume < 0) {
    for (auto& f : faces) std::swap(f[1], f[2]);
    for (Cell& c : body.cells) c.outward = static_cast<std::int8_t>(-c.outward);
  }

  // The checks of the tessellation (closed, manifold, oriented, no self-intersection) hold
  // under a similarity: the same unplaced patches on the same grid give the same
  // tessellation placed by scale, rotation and translation. So one shape placed many times
  // (a packing of one particle) is checked once per process.
  std::uint64_t shape_key = patches_hash(surface.patches);
  for (int k = 0; k < np; ++k) fnv1a(shape_key, &nu[k], sizeof nu[k]), fnv1a(shape_key, &nv[k], sizeof nv[k]);
  static std::mutex checked_mutex;
  static std::set<std::uint64_t> checked;
  bool known = false;
  {
    std::lock_guard<std::mutex> lock(checked_mutex);
    known = checked.count(shape_key) > 0;
  }
  const std::string problem = stl::build_indexed(vertices, faces, body.mesh, !known);
  if (problem.empty() && !known) {
    std::lock_guard<std::mutex> lock(checked_mutex);
    if (checked.size() >= 4096) checked.clear();
    checked.insert(shape_key);
  }
  if (!problem.empty()) {
    const std::vector<std::int64_t> named = faces_named(problem);
    auto patch_of = [&](std::int64_t f) { return body.cells[static_cast<std::size_t>(face_cell[static_cast<std::size_t>(f)])].patch; };
    if (problem.rfind("self-intersecting", 0) == 0 && named.size() == 2) {
      const auto& f = faces[static_cast<std::size_t>(named[0])];
      const int pa = patch_of(named[0]), pb = patch_of(named[1]);
      const std::string where = format_point(vertices[static_cast<std::size_t>(f[0])]);
      if (pa == pb) return patch_field(pa) + ": intersects itself (tessellation, near " + where + ")";
      return ".patches: patches[" + std::to_string(std::min(pa, pb)) + "] and patches[" +
             std::to_string(std::max(pa, pb)) + "] intersect (tessellation, near " + where + ")";
    }
    if (!named.empty()) return patch_field(patch_of(named[0])) + ": tessellation: " + problem;
    return ".patches: tessellation: " + problem;
  }
  std::vector<Box3> boxes(body.cells.size());
  for (std::size_t c = 0; c < boxes.size(); ++c) boxes[c] = body.cells[c].box;
  body.cell_bvh.build(boxes);
  for (const Box3& b : boxes) grow(body.box, b.min), grow(body.box, b.max);
  return "";
}


namespace {

Vec3 place_point(const Placement& pl, const Vec3& v) {
  Vec3 w{};
  for (int r = 0; r < 3; ++r)
    w[r] = pl.rotation[r][0] * (pl.scale * v[0]) + pl.rotation[r][1] * (pl.scale * v[1]) +
           pl.rotation[r][2] * (pl.scale * v[2]) + pl.translate[r];
  return w;
}

// A trimming curve as a polyline in (u, v): each Bézier span at 32 points.
// The curve's points at a chord error within tol (a span's control polygon, within tol of
// its chord, holds the span): the start of every chord, the curve's end left to the next.
void polygonize_span(const std::vector<double>& h, int p, double tol, int depth, std::vector<Vec2>& out) {
  const Vec2 a{h[0] / h[2], h[1] / h[2]};
  const Vec2 b{h[3 * static_cast<std::size_t>(p)] / h[3 * static_cast<std::size_t>(p) + 2],
               h[3 * static_cast<std::size_t>(p) + 1] / h[3 * static_cast<std::size_t>(p) + 2]};
  double flat = 0;
  const double ex = b[0] - a[0], ey = b[1] - a[1], len2 = ex * ex + ey * ey;
  for (int k = 1; k < p; ++k) {
    const double x = h[3 * static_cast<std::size_t>(k)] / h[3 * static_cast<std::size_t>(k) + 2] - a[0];
    const double y = h[3 * static_cast<std::size_t>(k) + 1] / h[3 * static_cast<std::size_t>(k) + 2] - a[1];
    const double t = len2 > 0 ? std::clamp((x * ex + y * ey) / len2, 0.0, 1.0) : 0.0;
    flat = std::max(flat, std::hypot(x - t * ex, y - t * ey));
  }
  if (flat <= tol || depth >= 40) {
    out.push_back(a);
    return;
  }
  std::vector<double> left(h.size()), right(h.size());
  nurbs::split_half<3>(h.data(), p, left.data(), right.data());
  polygonize_span(left, p, tol, depth + 1, out);
  polygonize_span(right, p, tol, depth + 1, out);
}

void polygonize(const BrepCurve2& c, double tol, std::vector<Vec2>& out) {
  std::vector<std::array<double, 3>> hom;
  for (std::size_t i = 0; i < c.control_points.size(); ++i) {
    const double w = i < c.weights.size() ? c.weights[i] : 1.0;
    hom.push_back({w * c.control_points[i][0], w * c.control_points[i][1], w});
  }
  const nurbs::BezierPieces<3> pieces = nurbs::extract_bezier<3>(c.degree, c.knots, hom);
  for (const std::vector<double>& h : pieces.points) polygonize_span(h, c.degree, tol, 0, out);
}

// The bands of in_trim: about four edges per band on average.
Body::TrimBands trim_bands(const std::vector<std::vector<Vec2>>& loops, double slack) {
  Body::TrimBands bands;
  if (loops.empty()) return bands;
  double v0 = kInf, v1 = -kInf;
  std::size_t edges = 0;
  for (const auto& loop : loops) {
    for (const Vec2& q : loop) v0 = std::min(v0, q[1]), v1 = std::max(v1, q[1]);
    edges += loop.size();
  }
  v0 -= slack, v1 += slack;
  const std::size_t n = std::max<std::size_t>(1, edges / 4);
  bands.v0 = v0;
  bands.inv_height = static_cast<double>(n) / (v1 - v0);
  std::vector<std::vector<std::array<std::int32_t, 2>>> in_band(n);
  const auto band_of = [&](double v) {
    return std::min(n - 1, static_cast<std::size_t>(std::max(0.0, (v - v0) * bands.inv_height)));
  };
  for (std::size_t l = 0; l < loops.size(); ++l)
    for (std::size_t i = 0, j = loops[l].size() - 1; i < loops[l].size(); j = i++) {
      const double lo = std::min(loops[l][i][1], loops[l][j][1]) - slack, hi = std::max(loops[l][i][1], loops[l][j][1]) + slack;
      for (std::size_t b = band_of(lo); b <= band_of(hi); ++b)
        in_band[b].push_back({static_cast<std::int32_t>(l), static_cast<std::int32_t>(i)});
    }
  bands.start.push_back(0);
  for (const auto& e : in_band) {
    bands.edges.insert(bands.edges.end(), e.begin(), e.end());
    bands.start.push_back(static_cast<std::int32_t>(bands.edges.size()));
  }
  return bands;
}

// The uv boxes of a trimming curve's Bézier spans (their control points).
void span_boxes(const BrepCurve2& c, std::vector<std::array<double, 4>>& out) {
  std::vector<std::array<double, 3>> hom;
  for (std::size_t i = 0; i < c.control_points.size(); ++i) {
    const double w = i < c.weights.size() ? c.weights[i] : 1.0;
    hom.push_back({w * c.control_points[i][0], w * c.control_points[i][1], w});
  }
  const nurbs::BezierPieces<3> pieces = nurbs::extract_bezier<3>(c.degree, c.knots, hom);
  for (const std::vector<double>& h : pieces.points) {
    std::array<double, 4> b{kInf, -kInf, kInf, -kInf};
    for (int k = 0; k <= c.degree; ++k) {
      const double u = h[3 * k] / h[3 * k + 2], v = h[3 * k + 1] / h[3 * k + 2];
      b[0] = std::min(b[0], u), b[1] = std::max(b[1], u), b[2] = std::min(b[2], v), b[3] = std::max(b[3], v);
    }
    out.push_back(b);
  }
}

}  // namespace

std::string build_brep(const BrepData& data, const std::vector<int>& solids, const Placement& pl, Body& body) {
  body = Body{};
  std::vector<int> chosen = solids;
  if (chosen.empty())
    for (std::size_t k = 0; k < data.solids.size(); ++k) chosen.push_back(static_cast<int>(k));
  if (chosen.empty()) return ": no solid";
  std::vector<Vec3> vertices;
  std::vector<std::array<std::int32_t, 3>> faces;
  std::vector<std::int32_t> face_patch, face_solid;
  std::vector<std::array<Vec2, 3>> face_uv;
  std::vector<std::int8_t> patch_outward;
  double volume = 0;
  bool any_trimmed = false;
  for (int si : chosen) {
    if (si < 0 || static_cast<std::size_t>(si) >= data.solids.size()) return ": no solid " + std::to_string(si);
    const BrepSolid& solid = data.solids[static_cast<std::size_t>(si)];
    const auto patch_base = static_cast<std::int32_t>(body.patches.size());
    const auto vertex_base = static_cast<std::int32_t>(vertices.size());
    for (std::size_t f = 0; f < solid.faces.size(); ++f) {
      const BrepFace& face = solid.faces[f];
      NurbsPatch placed = face.surface;
      for (Vec3& v : placed.control_points) v = place_point(pl, v);
      body.patches.emplace_back();
      const std::string problem = nurbs::extract_patch(placed, body.patches.back());
      if (!problem.empty()) return ": solid " + std::to_string(si) + " face " + std::to_string(f) + problem;
      patch_outward.push_back(face.reversed ? -1 : 1);
      // Trims: none where the loops run along the parameter rectangle.
      const nurbs::PatchPieces& pp = body.patches.back();
      const double u0 = pp.pieces.front().u0, u1 = pp.pieces.back().u1;
      const double v0 = pp.pieces.front().v0, v1 = pp.pieces.back().v1;
      const double slack = 1e-6 * std::max(u1 - u0, v1 - v0);
      std::vector<std::vector<Vec2>> loops;
      bool rectangle = true;
      for (const auto& loop : face.loops) {
        std::vector<Vec2> poly;
        for (const BrepCurve2& c : loop) polygonize(c, 0.25 * slack, poly);
        for (const Vec2& q : poly)
          rectangle = rectangle && (std::abs(q[0] - u0) <= slack || std::abs(q[0] - u1) <= slack ||
                                    std::abs(q[1] - v0) <= slack || std::abs(q[1] - v1) <= slack);
        loops.push_back(std::move(poly));
      }
      if (rectangle) loops.clear();
      any_trimmed = any_trimmed || !loops.empty();
      body.trim_bands.push_back(trim_bands(loops, slack));
      body.trims.push_back(std::move(loops));
      body.trim_slack.push_back(slack);
    }
    for (const Vec3& v : solid.vertices) vertices.push_back(place_point(pl, v));
    for (std::size_t t = 0; t < solid.triangles.size(); ++t) {
      const auto& tri = solid.triangles[t];
      faces.push_back({tri[0] + vertex_base, tri[1] + vertex_base, tri[2] + vertex_base});
      face_patch.push_back(patch_base + solid.triangle_face[t]);
      face_solid.push_back(si);
      face_uv.push_back(solid.triangle_uv[t]);
    }
    volume += solid.volume * pl.scale * pl.scale * pl.scale;
  }
  if (faces.empty()) return ": no triangles";
  Box3 box = empty_box();
  for (const Vec3& v : vertices) grow(box, v);
  body.size = norm(sub(box.max, box.min));
  body.tolerance = 1e-12 * body.size;

  // Cells: per triangle, per piece its (u, v) box meets; per trimming-curve span likewise.
  const auto add_cells = [&](std::int32_t k, double ua, double ub, double va, double vb, const Vec3* tri) {
    const nurbs::PatchPieces& pp = body.patches[static_cast<std::size_t>(k)];
    for (std::size_t q = 0; q < pp.pieces.size(); ++q) {
      const nurbs::BezierPatch& piece = pp.pieces[q];
      if (piece.u1 < ua || piece.u0 > ub || piece.v1 < va || piece.v0 > vb) continue;
      Cell c;
      c.patch = k;
      c.piece = static_cast<std::int32_t>(q);
      const double hu = piece.u1 - piece.u0, hv = piece.v1 - piece.v0;
      c.s0 = std::clamp((ua - piece.u0) / hu, 0.0, 1.0), c.s1 = std::clamp((ub - piece.u0) / hu, 0.0, 1.0);
      c.t0 = std::clamp((va - piece.v0) / hv, 0.0, 1.0), c.t1 = std::clamp((vb - piece.v0) / hv, 0.0, 1.0);
      c.outward = patch_outward[static_cast<std::size_t>(k)];
      const nurbs::BezierPatch sub_piece = nurbs::restrict_patch(piece, c.s0, c.s1, c.t0, c.t1);
      // Widened below, once the triangle's gap to its face is known.
      if (tri) c.normal = unit(cross(sub(tri[1], tri[0]), sub(tri[2], tri[0])));
      if (tri)
        fit_shell(c, sub_piece, {&tri[0], &tri[1], &tri[2]}, 0, 0);
      else
        fit_shell(c, sub_piece, {}, 0, 0);
      body.cells.push_back(c);
      body.cell_pieces.push_back(sub_piece);
    }
  };
  std::vector<double> edge_gap(body.patches.size(), 0);
  {
    std::size_t k = 0;
    for (int si : chosen)
      for (const BrepFace& face : data.solids[static_cast<std::size_t>(si)].faces)
        edge_gap[k++] = std::max(face.edge_tolerance, face.tolerance) * pl.scale;
  }
  for (std::size_t t = 0; t < faces.size(); ++t) {
    const Vec3 tri[3] = {vertices[static_cast<std::size_t>(faces[t][0])], vertices[static_cast<std::size_t>(faces[t][1])],
                         vertices[static_cast<std::size_t>(faces[t][2])]};
    double ua = kInf, ub = -kInf, va = kInf, vb = -kInf;
    for (const Vec2& q : face_uv[t]) ua = std::min(ua, q[0]), ub = std::max(ub, q[0]), va = std::min(va, q[1]), vb = std::max(vb, q[1]);
    const std::size_t first = body.cells.size();
    add_cells(face_patch[t], ua, ub, va, vb, tri);
    // The triangle's corners lie on its face within the face's tolerance, and neighbouring
    // faces meet within their edges' tolerances.
    double gap = edge_gap[static_cast<std::size_t>(face_patch[t])];
    for (int i = 0; i < 3; ++i) {
      const Vec3 s = nurbs::evaluate(body.patches[static_cast<std::size_t>(face_patch[t])], face_uv[t][i][0], face_uv[t][i][1]);
      gap = std::max(gap, norm(sub(s, tri[i])));
    }
    for (std::size_t c = first; c < body.cells.size(); ++c) {
      Cell& cell = body.cells[c];
      const double w = gap + 8 * kUnit * max_abs(cell.box) + body.tolerance;
      for (int d = 0; d < 3; ++d) cell.box.min[d] -= w, cell.box.max[d] += w;
      cell.lo -= w, cell.hi += w;
      body.max_thickness = std::max(body.max_thickness, cell.hi - cell.lo);
    }
  }
  // Trimmed faces: the surface between a boundary triangle's chord and its trimming curve.
  for (std::size_t k = 0; k < body.patches.size(); ++k) {
    if (body.trims[k].empty()) continue;
    std::size_t at = 0;
    const BrepFace* face = nullptr;
    for (int si : chosen)
      for (const BrepFace& f : data.solids[static_cast<std::size_t>(si)].faces)
        if (at++ == k) face = &f;
    std::vector<std::array<double, 4>> boxes;
    for (const auto& loop : face->loops)
      for (const BrepCurve2& c : loop) span_boxes(c, boxes);
    const std::size_t n = boxes.size();
    for (std::size_t i = 0; i < n; ++i) {
      // Each span's box, and the box of it and the next (a chord across two spans).
      const std::array<double, 4>& a = boxes[i];
      const std::array<double, 4>& b = boxes[(i + 1) % n];
      for (const auto& r : {a, std::array<double, 4>{std::min(a[0], b[0]), std::max(a[1], b[1]), std::min(a[2], b[2]),
                                                      std::max(a[3], b[3])}}) {
        const std::size_t first = body.cells.size();
        add_cells(static_cast<std::int32_t>(k), r[0], r[1], r[2], r[3], nullptr);
        for (std::size_t c = first; c < body.cells.size(); ++c) {
          Cell& cell = body.cells[c];
          const double w = edge_gap[k] + 8 * kUnit * max_abs(cell.box) + body.tolerance;
          for (int d = 0; d < 3; ++d) cell.box.min[d] -= w, cell.box.max[d] += w;
          cell.lo -= w, cell.hi += w;
          body.max_thickness = std::max(body.max_thickness, cell.hi - cell.lo);
        }
      }
    }
  }
  const std::string problem = stl::build_indexed(vertices, faces, body.mesh, true);
  if (!problem.empty()) {
    const std::vector<std::int64_t> named = faces_named(problem);
    if (problem.rfind("self-intersecting", 0) == 0 && named.size() == 2) {
      const auto fa = static_cast<std::size_t>(named[0]), fb = static_cast<std::size_t>(named[1]);
      const std::string where = format_point(vertices[static_cast<std::size_t>(faces[fa][0])]);
      if (face_solid[fa] == face_solid[fb])
        return ": solid " + std::to_string(face_solid[fa]) + " intersects itself (tessellation, near " + where + ")";
      return ": solids " + std::to_string(face_solid[fa]) + " and " + std::to_string(face_solid[fb]) +
             " intersect (tessellation, near " + where + ")";
    }
    return ": tessellation: " + problem;
  }
  std::vector<Box3> boxes(body.cells.size());
  for (std::size_t c = 0; c < boxes.size(); ++c) boxes[c] = body.cells[c].box;
  body.cell_bvh.build(boxes);
  // The box of the solids, not of the cells: a trimmed face's cells hold its untrimmed
  // pieces, which may reach far beyond the solid (a plane's whole rectangle), and the
  // oracle takes this box for the inclusion's (measures integrate by sections when it leaves
  // the domain). The imported boxes hold the exact faces and the mesh; placed by their
  // corners and widened by the edge tolerances and rounding.
  body.box = box;
  double widen = 0;
  for (double g : edge_gap) widen = std::max(widen, g);
  for (int si : chosen) {
    const Box3& sb = data.solids[static_cast<std::size_t>(si)].box;
    for (int c = 0; c < 8; ++c)
      grow(body.box, place_point(pl, {(c & 1) ? sb.max[0] : sb.min[0], (c & 2) ? sb.max[1] : sb.min[1], (c & 4) ? sb.max[2] : sb.min[2]}));
  }
  widen += 8 * kUnit * max_abs(body.box) + body.tolerance;
  for (int d = 0; d < 3; ++d) body.box.min[d] -= widen, body.box.max[d] += widen;
  body.exact_volume = volume;
  if (any_trimmed) body.exact_area = stl::surface_area(body.mesh);
  return "";
}

std::shared_ptr<const Body> cached_body(const NurbsSurface& surface, std::string* problem) {
  std::uint64_t h = patches_hash(surface.patches);
  fnv1a(h, &surface.scale, sizeof surface.scale);
  fnv1a(h, &surface.rotation, sizeof surface.rotation);
  fnv1a(h, &surface.translate, sizeof surface.translate);
  return cached(h, [&](Body& body) { return build(surface, body); }, problem);
}

// ---------------------------------------------------------------- queries

namespace {

struct Root {
  double lambda;
  std::int32_t cell;
  double s, t;  // local to the cell's restricted piece
};

const nurbs::BezierPatch& cell_piece(const Body& body, const Cell& c) {
  return body.cell_pieces[static_cast<std::size_t>(&c - body.cells.data())];
}

// Does (u, v) lie in patch k's trimmed region, or within its slack of a loop?
bool in_trim(const Body& body, std::int32_t k, double u, double v) {
  if (body.trims.empty()) return true;
  const auto& loops = body.trims[static_cast<std::size_t>(k)];
  if (loops.empty()) return true;
  const double slack = body.trim_slack[static_cast<std::size_t>(k)];
  const Body::TrimBands& bands = body.trim_bands[static_cast<std::size_t>(k)];
  const double at = (v - bands.v0) * bands.inv_height;
  const auto n = static_cast<double>(bands.start.size() - 1);
  if (!(at >= 0 && at < n)) return false;  // beyond every loop's v range and its slack
  const auto b = static_cast<std::size_t>(at);
  bool inside = false;
  // A +u ray from (u, v) crosses only edges whose v range holds v, and an edge within the
  // slack has its v range within the slack of v: both are in v's band.
  for (std::int32_t e = bands.start[b]; e < bands.start[b + 1]; ++e) {
    const std::vector<Vec2>& loop = loops[static_cast<std::size_t>(bands.edges[static_cast<std::size_t>(e)][0])];
    const auto i = static_cast<std::size_t>(bands.edges[static_cast<std::size_t>(e)][1]);
    const Vec2 &a = loop[i == 0 ? loop.size() - 1 : i - 1], &c = loop[i];
    if ((a[1] > v) != (c[1] > v) && u < a[0] + (v - a[1]) * (c[0] - a[0]) / (c[1] - a[1])) inside = !inside;
    // Distance to the edge a-c.
    const double ex = c[0] - a[0], ey = c[1] - a[1];
    const double len2 = ex * ex + ey * ey;
    const double t = len2 > 0 ? std::clamp(((u - a[0]) * ex + (v - a[1]) * ey) / len2, 0.0, 1.0) : 0.0;
    const double dx = u - (a[0] + t * ex), dy = v - (a[1] + t * ey);
    if (dx * dx + dy * dy <= slack * slack) return true;
  }
  return inside;
}

bool in_shell(const Cell& c, const Vec3& p) {
  for (int k = 0; k < 3; ++k)
    if (!(p[k] >= c.box.min[k] && p[k] <= c.box.max[k])) return false;
  const double x = dot(c.normal, p);
  return x >= c.lo && x <= c.hi;
}

bool in_box(const Box3& b, const Vec3& p) {
  for (int k = 0; k < 3; ++k)
    if (!(p[k] >= b.min[k] && p[k] <= b.max[k])) return false;
  return true;
}

bool in_any_shell(const Body& body, const Vec3& p) {
  bool found = false;
  body.cell_bvh.traverse([&](const Box3& b) { return in_box(b, p); },
                         [&](std::int32_t c) { return found = in_shell(body.cells[static_cast<std::size_t>(c)], p); });
  return found;
}

// Does the segment a + λ(b − a), λ ∈ [l0, l1], meet the box (slab method)?
bool segment_meets_box(const Vec3& a, const Vec3& d, double l0, double l1, const Box3& b) {
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (a[k] < b.min[k] || a[k] > b.max[k]) return false;
      continue;
    }
    double e0 = (b.min[k] - a[k]) / d[k], e1 = (b.max[k] - a[k]) / d[k];
    if (e0 > e1) std::swap(e0, e1);
    // Rounding of the divisions: a hair of slack keeps the test conservative.
    e0 -= 1e-12 * (std::abs(e0) + 1), e1 += 1e-12 * (std::abs(e1) + 1);
    l0 = std::max(l0, e0), l1 = std::min(l1, e1);
    if (l0 > l1) return false;
  }
  return true;
}

// Roots of the line a + λ(b − a) with λ in [l0, l1] on the surface, ascending in λ, those
// closer than τ merged (one root seen from two neighbouring cells).
void line_roots(const Body& body, const Vec3& a, const Vec3& b, double l0, double l1, std::vector<Root>& out) {
  out.clear();
  const Vec3 d = sub(b, a);
  const double len = norm(d);
  if (!(len > 0)) return;
  Box3 seg{a, a};
  grow(seg, add(a, scale(d, l0)));
  grow(seg, add(a, scale(d, l1)));
  thread_local std::vector<nurbs::LineRoot> found;
  nurbs::LineQuery query{a, b, l0, l1, body.size, body.tolerance};
  body.cell_bvh.traverse([&](const Box3& nb) { return boxes_overlap(nb, seg) && segment_meets_box(a, d, l0, l1, nb); },
                         [&](std::int32_t ci) {
                           const Cell& c = body.cells[static_cast<std::size_t>(ci)];
                           if (!segment_meets_box(a, d, l0, l1, c.box)) return false;
                           const double x0 = dot(c.normal, a), dx = dot(c.normal, d);
                           const double y0 = x0 + l0 * dx, y1 = x0 + l1 * dx;
                           if ((y0 < c.lo && y1 < c.lo) || (y0 > c.hi && y1 > c.hi)) return false;
                           found.clear();
                           nurbs::line_roots(cell_piece(body, c), query, found);
                           const nurbs::BezierPatch& piece = cell_piece(body, c);
                           for (const nurbs::LineRoot& r : found)
                             if (in_trim(body, c.patch, piece.u0 + r.s * (piece.u1 - piece.u0),
                                         piece.v0 + r.t * (piece.v1 - piece.v0)))
                               out.push_back({r.lambda, ci, r.s, r.t});
                           return false;
                         });
  std::sort(out.begin(), out.end(), [](const Root& x, const Root& y) {
    return x.lambda != y.lambda ? x.lambda < y.lambda : x.cell < y.cell;
  });
  std::size_t w = 0;
  for (std::size_t i = 0; i < out.size(); ++i)
    if (w == 0 || (out[i].lambda - out[w - 1].lambda) * len > body.tolerance) out[w++] = out[i];
  out.resize(w);
  stats().roots += static_cast<std::int64_t>(w);
}

// The outward normal (not unit) of the surface at a root.
Vec3 normal_at(const Body& body, const Root& r) {
  const Cell& c = body.cells[static_cast<std::size_t>(r.cell)];
  Vec3 ds, dt;
  nurbs::evaluate(cell_piece(body, c), r.s, r.t, &ds, &dt);
  return scale(cross(ds, dt), c.outward);
}

// Inside/outside of p from the first root on the segment p → p + L·d (d unit): ON when
// it lies within τ, else the normal there says whether the segment leaves or enters.
// 2 when the first root is too grazing to tell; 3 when there is no root (the answer is q's).
int side_along(const Body& body, const Vec3& p, const Vec3& d, double L, std::vector<Root>& roots) {
  const Vec3 q = add(p, scale(d, L));
  line_roots(body, p, q, -body.tolerance / L, 1, roots);
  if (roots.empty()) return 3;
  const Root& r = roots.front();
  if (std::abs(r.lambda) * L <= body.tolerance) return 0;
  const Vec3 n = normal_at(body, r);
  const double nn = norm(n);
  if (!(nn > 0)) return 2;
  const double c = dot(n, d) / nn;
  if (std::abs(c) < 1e-3) return 2;
  return c > 0 ? 1 : -1;
}

}  // namespace

int side(const Body& body, const Vec3& p) {
  Stats& st = stats();
  ++st.side_calls;
  std::int32_t first = -1;
  double thick = 0;
  body.cell_bvh.traverse([&](const Box3& b) { return in_box(b, p); },
                         [&](std::int32_t ci) {
                           const Cell& c = body.cells[static_cast<std::size_t>(ci)];
                           if (in_shell(c, p)) {
                             if (first < 0 || ci < first) first = ci;
                             thick = std::max(thick, c.hi - c.lo);
                           }
                           return false;
                         });
  if (first < 0) {
    const int s = stl::side(body.mesh, p);
    if (s != 0) return s;
  }
  ++st.side_in_shell;
  thread_local std::vector<Root> roots;
  const Vec3 n = first >= 0 ? body.cells[static_cast<std::size_t>(first)].normal : Vec3{1, 0, 0};
  const Vec3 dirs[8] = {n, scale(n, -1), {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  const double start = 2 * thick + 8 * body.tolerance;
  for (const Vec3& d : dirs) {
    double L = start;
    bool escaped = false;
    for (int tries = 0; tries < 5 && !escaped; ++tries, L *= 4) {
      const Vec3 q = add(p, scale(d, L));
      if (!in_any_shell(body, q)) {
        escaped = true;
        break;
      }
    }
    if (!escaped) continue;
    const int s = side_along(body, p, d, L, roots);
    if (s == 3) {
      const int sq = stl::side(body.mesh, add(p, scale(d, L)));
      if (sq != 0) return sq;
      continue;
    }
    if (s != 2) return s;
  }
  // No short escape: rays to beyond the body's box, the first transversal one decides.
  ++st.side_fallback;
  const double far = 2 * body.size + norm(sub(p, body.box.min)) + norm(sub(p, body.box.max));
  for (const Vec3& d : dirs) {
    const int s = side_along(body, p, d, far, roots);
    if (s == 3) return -1;
    if (s != 2) return s;
  }
  const int s = stl::side(body.mesh, p);
  return s;
}

void segment_roots(const Body& body, const Vec3& a, const Vec3& b, std::vector<double>& ts) {
  thread_local std::vector<Root> roots;
  ++stats().segment_calls;
  line_roots(body, a, b, 0, 1, roots);
  for (const Root& r : roots)
    if (r.lambda > 0 && r.lambda < 1) ts.push_back(r.lambda);
}

namespace {

bool piece_touches(const nurbs::BezierPatch& piece, const Box3& box, double tol, int depth) {
  const Box3 cb = nurbs::control_box(piece);
  if (!boxes_overlap(cb, box)) return false;
  const int p = piece.degree_u, q = piece.degree_v;
  for (const Vec3& corner : {piece.cartesian(0, 0), piece.cartesian(p, 0), piece.cartesian(0, q), piece.cartesian(p, q)})
    if (in_box(box, corner)) return true;
  if (norm(sub(cb.max, cb.min)) <= tol || depth >= 40) return true;
  ++stats().touch_refinements;
  nurbs::BezierPatch lo, hi;
  halve_longer(piece, lo, hi);
  return piece_touches(lo, box, tol, depth + 1) || piece_touches(hi, box, tol, depth + 1);
}

}  // namespace

bool touches_box(const Body& body, const Box3& box) {
  bool touches = false;
  body.cell_bvh.traverse([&](const Box3& b) { return boxes_overlap(b, box); },
                         [&](std::int32_t ci) {
                           const Cell& c = body.cells[static_cast<std::size_t>(ci)];
                           if (!boxes_overlap(c.box, box)) return false;
                           double lo = 0, hi = 0;
                           for (int k = 0; k < 3; ++k) {
                             const double x0 = c.normal[k] * box.min[k], x1 = c.normal[k] * box.max[k];
                             lo += std::min(x0, x1), hi += std::max(x0, x1);
                           }
                           if (hi < c.lo || lo > c.hi) return false;
                           return touches = piece_touches(cell_piece(body, c), box, body.tolerance, 0);
                         });
  return touches;
}

namespace {

double box_distance_boxes(const Box3& a, const Box3& b) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double e = std::max({a.min[k] - b.max[k], 0.0, b.min[k] - a.max[k]});
    d2 += e * e;
  }
  return std::sqrt(d2);
}


// The point of the piece nearest to p, by Gauss–Newton from the best of a 5 × 5 sample,
// kept in [0, 1]².
double nearest_on_piece(const nurbs::BezierPatch& piece, const Vec3& p, double& s, double& t) {
  s = t = 0.5;
  double best = kInf;
  for (int j = 0; j <= 4; ++j)
    for (int i = 0; i <= 4; ++i) {
      const double d = norm(sub(nurbs::evaluate(piece, i / 4.0, j / 4.0), p));
      if (d < best) best = d, s = i / 4.0, t = j / 4.0;
    }
  for (int it = 0; it < 64; ++it) {
    Vec3 ds, dt;
    const Vec3 x = nurbs::evaluate(piece, s, t, &ds, &dt);
    const Vec3 r = sub(x, p);
    const double a11 = dot(ds, ds), a12 = dot(ds, dt), a22 = dot(dt, dt);
    const double b1 = -dot(ds, r), b2 = -dot(dt, r);
    const double det = a11 * a22 - a12 * a12;
    double hs, ht;
    if (std::abs(det) > 1e-30 * (a11 * a22 + 1e-300)) {
      hs = (b1 * a22 - b2 * a12) / det, ht = (a11 * b2 - a12 * b1) / det;
    } else {
      hs = a11 > 0 ? b1 / a11 : 0, ht = a22 > 0 ? b2 / a22 : 0;
    }
    // Damped: halve the step until the distance drops (far from the surface the
    // Gauss–Newton step overshoots).
    bool improved = false;
    for (double lam = 1; lam > 1e-9 && !improved; lam *= 0.5) {
      const double ns = std::clamp(s + lam * hs, 0.0, 1.0), nt = std::clamp(t + lam * ht, 0.0, 1.0);
      const double d = norm(sub(nurbs::evaluate(piece, ns, nt), p));
      if (d < best) {
        improved = true;
        const double moved = std::abs(ns - s) + std::abs(nt - t);
        best = d, s = ns, t = nt;
        if (moved < 1e-15) return best;
      }
    }
    if (!improved) break;
  }
  return best;
}

}  // namespace

double distance(const Body& body, const Vec3& p, Vec3* normal) {
  double best = kInf;
  std::int32_t best_cell = -1;
  double bs = 0, bt = 0;
  // Cells in order of their box distance, within the distance of the nearest vertex.
  thread_local std::vector<std::pair<double, std::int32_t>> order;
  order.clear();
  double bound = kInf;
  for (const Vec3& v : body.mesh.vertices) bound = std::min(bound, norm(sub(v, p)));
  body.cell_bvh.traverse([&](const Box3& b) { return box_distance(b, p) <= bound; },
                         [&](std::int32_t ci) {
                           const double d = box_distance(body.cells[static_cast<std::size_t>(ci)].box, p);
                           if (d <= bound) order.push_back({d, ci});
                           return false;
                         });
  std::sort(order.begin(), order.end());
  for (const auto& [lower, ci] : order) {
    if (lower > best) break;
    double s, t;
    const double d = nearest_on_piece(cell_piece(body, body.cells[static_cast<std::size_t>(ci)]), p, s, t);
    if (d < best) best = d, best_cell = ci, bs = s, bt = t;
  }
  if (normal) {
    *normal = {0, 0, 0};
    if (best_cell >= 0) *normal = normal_at(body, {0, best_cell, bs, bt});
  }
  return best;
}

namespace {

// Do two pieces come within gap? Control boxes farther apart than gap: no; two corner
// points (surface points) within gap: yes; else the larger piece is halved (conservative
// past the depth limit).
bool pieces_within(const nurbs::BezierPatch& a, const nurbs::BezierPatch& b, double gap, int depth) {
  const Box3 ba = nurbs::control_box(a), bb = nurbs::control_box(b);
  if (box_distance_boxes(ba, bb) > gap) return false;
  const auto corners = [](const nurbs::BezierPatch& q) {
    const int p = q.degree_u, r = q.degree_v;
    return std::array<Vec3, 4>{q.cartesian(0, 0), q.cartesian(p, 0), q.cartesian(0, r), q.cartesian(p, r)};
  };
  const std::array<Vec3, 4> ca = corners(a), cb = corners(b);
  for (const Vec3& x : ca)
    for (const Vec3& y : cb)
      if (norm(sub(x, y)) <= gap) return true;
  if (depth >= 12) return true;
  const double da = norm(sub(ba.max, ba.min)), db = norm(sub(bb.max, bb.min));
  const nurbs::BezierPatch& big = da >= db ? a : b;
  const nurbs::BezierPatch& other = da >= db ? b : a;
  nurbs::BezierPatch lo, hi;
  halve_longer(big, lo, hi);
  return pieces_within(lo, other, gap, depth + 1) || pieces_within(hi, other, gap, depth + 1);
}

// Is the piece within gap of the convex region? False when a direction separates its
// control box from the region by more than gap (the axes, and the direction from the
// region's centre to the box's nearest point, exact for a sphere); true when a corner of
// the piece is within gap (the region's support along the corner's direction), or when the
// piece is smaller than `resolution` (over-refinement only).
bool piece_within_convex(const nurbs::BezierPatch& piece, const std::function<double(const Vec3&)>& support,
                         const Vec3& centre, double gap, double resolution, int depth) {
  const Box3 b = nurbs::control_box(piece);
  const auto separated_along = [&](const Vec3& d) {
    double lowest = 0;  // min over the box of d·y
    for (int k = 0; k < 3; ++k) lowest += std::min(d[k] * b.min[k], d[k] * b.max[k]);
    return support(d) < lowest - gap;
  };
  for (int k = 0; k < 3; ++k) {
    Vec3 e{0, 0, 0};
    e[k] = 1;
    if (separated_along(e) || separated_along(scale(e, -1))) return false;
  }
  Vec3 nearest;
  for (int k = 0; k < 3; ++k) nearest[k] = std::clamp(centre[k], b.min[k], b.max[k]);
  const Vec3 towards = sub(nearest, centre);
  if (norm(towards) > 0 && separated_along(scale(towards, 1 / norm(towards)))) return false;
  if (norm(sub(b.max, b.min)) <= resolution || depth >= 24) return true;
  nurbs::BezierPatch lo, hi;
  halve_longer(piece, lo, hi);
  return piece_within_convex(lo, support, centre, gap, resolution, depth + 1) ||
         piece_within_convex(hi, support, centre, gap, resolution, depth + 1);
}

}  // namespace

bool within_convex(const Body& a, const std::function<double(const Vec3&)>& support,
                   const std::function<bool(const Vec3&)>& contains, double gap) {
  Vec3 centre;  // of the region's box: inside a centrally symmetric convex region
  for (int k = 0; k < 3; ++k) {
    Vec3 e{0, 0, 0};
    e[k] = 1;
    centre[k] = 0.5 * (support(e) - support(scale(e, -1)));
  }
  // One inside the other (a tessellation vertex is a surface point).
  if (contains(a.mesh.vertices.front()) || side(a, centre) >= 0) return true;
  const double resolution = 1e-3 * a.size;
  for (std::size_t c = 0; c < a.cells.size(); ++c)
    if (piece_within_convex(a.cell_pieces[c], support, centre, gap, resolution, 0)) return true;
  return false;
}

namespace {

}  // namespace

bool within(const Body& a, const Body& b, double gap) {
  if (box_distance_boxes(a.box, b.box) > gap) return false;
  // One inside the other (a tessellation vertex is a surface point).
  if (side(b, a.mesh.vertices.front()) >= 0 || side(a, b.mesh.vertices.front()) >= 0) return true;
  for (const Cell& ca : a.cells) {
    if (box_distance_boxes(ca.box, b.box) > gap) continue;
    bool close = false;
    b.cell_bvh.traverse([&](const Box3& nb) { return box_distance_boxes(nb, ca.box) <= gap; },
                        [&](std::int32_t ci) {
                          const Cell& cb = b.cells[static_cast<std::size_t>(ci)];
                          if (box_distance_boxes(cb.box, ca.box) > gap) return false;
                          return close = pieces_within(cell_piece(a, ca), cell_piece(b, cb), gap, 0);
                        });
    if (close) return true;
  }
  return false;
}

namespace {

// The smallest value of sign·x[axis] over the surface (with plane_axis >= 0: over its
// section by x[plane_axis] = plane), to about eps: best-first halving of the cells' pieces,
// ordered by their control boxes' lower bound, until the best box is smaller than eps.
double surface_extreme(const Body& body, int axis, double sign, int plane_axis, double plane, double eps, bool& found) {
  struct Item {
    double key;
    nurbs::BezierPatch piece;
  };
  const auto worse = [](const Item& x, const Item& y) { return x.key > y.key; };
  std::vector<Item> heap;
  const auto push = [&](nurbs::BezierPatch piece) {
    const Box3 b = nurbs::control_box(piece);
    if (plane_axis >= 0 && !(b.min[plane_axis] <= plane && plane <= b.max[plane_axis])) return;
    heap.push_back({sign > 0 ? b.min[axis] : -b.max[axis], std::move(piece)});
    std::push_heap(heap.begin(), heap.end(), worse);
  };
  for (const nurbs::BezierPatch& piece : body.cell_pieces) push(piece);
  found = false;
  for (int step = 0; step < 100000 && !heap.empty(); ++step) {
    std::pop_heap(heap.begin(), heap.end(), worse);
    Item best = std::move(heap.back());
    heap.pop_back();
    const Box3 b = nurbs::control_box(best.piece);
    if (norm(sub(b.max, b.min)) <= eps || step == 99999) {
      found = true;
      return best.key;
    }
    const nurbs::BezierPatch& q = best.piece;
    nurbs::BezierPatch lo, hi;
    halve_longer(q, lo, hi);
    push(std::move(lo));
    push(std::move(hi));
  }
  return 0;
}

}  // namespace

void x_extremes(const Body& body, std::vector<double>& out) {
  bool found = false;
  const double eps = 1e-12 * body.size;
  const double lo = surface_extreme(body, 0, 1, -1, 0, eps, found);
  if (found) out.push_back(lo);
  const double hi = -surface_extreme(body, 0, -1, -1, 0, eps, found);
  if (found) out.push_back(hi);
}

void y_extremes_at(const Body& body, double x, std::vector<double>& out) {
  if (!(x >= body.box.min[0] && x <= body.box.max[0])) return;
  bool found = false;
  // Coarser than x_extremes: along a section the boxes below the extreme multiply as they
  // shrink (≈ eps^(-1/2)); a kink displaced by 1e-6 of the size costs the quadrature a
  // few halvings.
  const double eps = 1e-6 * body.size;
  const double lo = surface_extreme(body, 1, 1, 0, x, eps, found);
  if (found) out.push_back(lo);
  const double hi = -surface_extreme(body, 1, -1, 0, x, eps, found);
  if (found) out.push_back(hi);
}

double volume(const Body& body) {
  if (body.exact_volume >= 0) return body.exact_volume;
  double v = 0;
  for (std::size_t k = 0; k < body.patches.size(); ++k) {
    // A patch's orientation: that of any of its cells.
    int outward = 1;
    for (const Cell& c : body.cells)
      if (c.patch == static_cast<std::int32_t>(k)) {
        outward = c.outward;
        break;
      }
    for (const nurbs::BezierPatch& piece : body.patches[k].pieces)
      v += outward * piece_integral(piece, [](const Vec3& x, const Vec3& ds, const Vec3& dt) {
             return dot(x, cross(ds, dt)) / 3;
           });
  }
  return v;
}

double area(const Body& body) {
  if (body.exact_area >= 0) return body.exact_area;
  double a = 0;
  for (const nurbs::PatchPieces& pp : body.patches)
    for (const nurbs::BezierPatch& piece : pp.pieces)
      a += piece_integral(piece, [](const Vec3&, const Vec3& ds, const Vec3& dt) { return norm(cross(ds, dt)); });
  return a;
}

std::vector<Vec3> surface_points(const Body& body, double spacing) {
  std::vector<Vec3> out = body.mesh.vertices;
  for (const Cell& c : body.cells) {
    const double diag = norm(sub(c.box.max, c.box.min));
    const int n = std::clamp(static_cast<int>(std::ceil(diag / std::max(spacing, 1e-300))), 1, 64);
    const nurbs::BezierPatch& piece = cell_piece(body, c);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) out.push_back(nurbs::evaluate(piece, (i + 0.5) / n, (j + 0.5) / n));
  }
  return out;
}

}  // namespace cisamr::geometry::surface
