// shapes_overlap for 3D shapes (shapes_detail.hpp): what two families answer, combined.
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

#include "core/vec_math.hpp"
#include "geometry/shape_family.hpp"
#include "geometry/shapes_detail.hpp"

namespace cisamr::geometry::detail {
namespace {

Vec3 direction(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

}  // namespace

bool overlap3(const Shape& a, const Shape& b, double gap) {
  const ShapeFamily& fa = shape_family(a);
  const ShapeFamily& fb = shape_family(b);
  if (&fa == &fb)
    if (const std::optional<bool> exact = fa.overlap_same_family(a, b, gap)) return *exact;
  const Box3 ba = fa.bounding_box(a), bb = fb.bounding_box(b);
  for (int k = 0; k < 3; ++k)
    if (ba.max[k] + gap < bb.min[k] || bb.max[k] + gap < ba.min[k]) return false;
  if (gap > 0 && &fa != &fb) {  // a body (NURBS, STEP) and a convex shape: the body's pieces
    if (fb.convex(b))
      if (const std::optional<bool> r = fa.overlap_convex(a, b, gap)) return *r;
    if (fa.convex(a))
      if (const std::optional<bool> r = fb.overlap_convex(b, a, gap)) return *r;
  }
  if (!fa.convex(a) || !fb.convex(b)) {
    // Conservative: with a positive gap, overlapping inflated boxes already count; else
    // points of either boundary inside the other, or mesh edges piercing the other mesh.
    if (gap > 0) return true;
    const double size = std::max(norm(Vec3{ba.max[0] - ba.min[0], ba.max[1] - ba.min[1], ba.max[2] - ba.min[2]}),
                                 norm(Vec3{bb.max[0] - bb.min[0], bb.max[1] - bb.min[1], bb.max[2] - bb.min[2]}));
    if (fb.contains_any(b, fa.boundary_samples(a, size / 64))) return true;
    if (fa.contains_any(a, fb.boundary_samples(b, size / 64))) return true;
    return &fa == &fb && fa.edges_pierce(a, b);
  }
  // Convex bodies are apart by more than gap iff some unit d has h_a(d) + h_b(−d) < −gap.
  const auto gap_along = [&](const Vec3& d) { return fa.support(a, d) + fb.support(b, Vec3{-d[0], -d[1], -d[2]}); };
  // Cheap answers first (most pairs the level rules ask about): the line through the
  // centres of the two boxes separates them, or a point lies in both (centrally symmetric
  // families: a box's centre is in its shape).
  const Vec3 centre_a = scale(add(ba.min, ba.max), 0.5), centre_b = scale(add(bb.min, bb.max), 0.5);
  const Vec3 between = sub(centre_b, centre_a);
  if (norm(between) > 0 && gap_along(scale(between, 1 / norm(between))) < -gap) return false;
  if (gap >= 0 && (fb.contains(b, centre_a) || fa.contains(a, centre_b))) return true;
  // Search: Fibonacci directions (a table built once), then a shrinking pattern search in
  // (θ, φ) from the best.
  auto g = [&](double th, double ph) { return gap_along(direction(th, ph)); };
  constexpr int n = 1500;
  struct Start {
    double v, th, ph;
  };
  static const std::vector<std::array<double, 5>> fibonacci = [] {  // θ, φ, d
    std::vector<std::array<double, 5>> t;
    const double golden = M_PI * (3 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
      const double z = 1 - 2 * (i + 0.5) / n;
      const double th = std::acos(z), ph = std::fmod(golden * i, 2 * M_PI);
      const Vec3 d = direction(th, ph);
      t.push_back({th, ph, d[0], d[1], d[2]});
    }
    return t;
  }();
  std::vector<Start> starts;
  starts.reserve(n);
  for (const auto& f : fibonacci) {
    const double v = gap_along(Vec3{f[2], f[3], f[4]});
    if (v < -gap) return false;  // a separating direction already
    starts.push_back({v, f[0], f[1]});
  }
  std::partial_sort(starts.begin(), starts.begin() + 4, starts.end(), [](const Start& x, const Start& y) { return x.v < y.v; });
  double best = starts[0].v;
  for (int s = 0; s < 4; ++s) {
    double th = starts[s].th, ph = starts[s].ph, v = starts[s].v, step = 0.1;
    // Rotate the frame so that the start is not near a pole of (θ, φ).
    while (step > 1e-13) {
      bool moved = false;
      const double cand[8][2] = {{step, 0}, {-step, 0}, {0, step}, {0, -step}, {step, step}, {-step, -step}, {step, -step}, {-step, step}};
      for (const auto& c : cand) {
        const double w = g(th + c[0], ph + c[1]);
        if (w < v) {
          v = w, th += c[0], ph += c[1], moved = true;
          break;
        }
      }
      if (!moved) step *= 0.5;
    }
    best = std::min(best, v);
    if (best < -gap) return false;
  }
  return best >= -gap;
}

}  // namespace cisamr::geometry::detail
