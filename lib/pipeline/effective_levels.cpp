#include "pipeline/effective_levels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <variant>

#include "geometry/shapes.hpp"

namespace cisamr::pipeline {
namespace {

constexpr double kContactCells = 1.5;  // > √2: a cell of level l can touch two boundaries only closer than √2·h_l
constexpr double kSpreadCells = 6.5;   // R4's 5×5 block, both cells' diagonals and a 2:1 cascade

// Bounding box without evaluating NURBS curves (their control polygon bounds them).
Box2 box_of(const geometry::Shape& shape) {
  if (const auto* c = std::get_if<geometry::NurbsCurve>(&shape)) {
    Box2 b{{INFINITY, INFINITY}, {-INFINITY, -INFINITY}};
    for (const Vec2& p : c->control_points)
      for (int d = 0; d < 2; ++d) b.min[d] = std::min(b.min[d], p[d]), b.max[d] = std::max(b.max[d], p[d]);
    return b;
  }
  const Box3 b = geometry::shape_bounding_box(shape);
  return Box2{{b.min[0], b.min[1]}, {b.max[0], b.max[1]}};
}

bool is_nurbs(const geometry::Shape& s) { return std::holds_alternative<geometry::NurbsCurve>(s); }

double box_distance(const Box2& a, const Box2& b) {
  const double dx = std::max({0.0, a.min[0] - b.max[0], b.min[0] - a.max[0]});
  const double dy = std::max({0.0, a.min[1] - b.max[1], b.min[1] - a.max[1]});
  return std::hypot(dx, dy);
}

}  // namespace

std::vector<int> effective_levels2(const geometry::SceneDesc& scene, const grid::Lattice2& lattice) {
  const std::size_t n = scene.inclusions.size();
  std::vector<int> level(n);
  std::vector<Box2> box(n);
  for (std::size_t k = 0; k < n; ++k) {
    level[k] = std::min(std::max(0, scene.inclusions[k].levels), lattice.max_level);
    box[k] = box_of(scene.inclusions[k].shape);
  }
  if (n < 2) return level;

  // Candidate pairs: boxes closer than the widest reach (coarsest level), by buckets.
  int min_level = lattice.max_level;
  for (int l : level) min_level = std::min(min_level, l);
  const double reach = kSpreadCells * lattice.spacing(min_level);
  const double side = std::max(reach, 4 * lattice.h);
  const double x0 = scene.domain_min[0], y0 = scene.domain_min[1];
  const auto bucket = [&](double v, double origin) { return static_cast<std::int64_t>(std::floor((v - origin) / side)); };
  std::int64_t bx0 = INT64_MAX, by0 = INT64_MAX, bx1 = INT64_MIN, by1 = INT64_MIN;
  for (const Box2& b : box) {
    bx0 = std::min(bx0, bucket(b.min[0], x0)), by0 = std::min(by0, bucket(b.min[1], y0));
    bx1 = std::max(bx1, bucket(b.max[0], x0)), by1 = std::max(by1, bucket(b.max[1], y0));
  }
  const std::int64_t nbx = bx1 - bx0 + 1, nby = by1 - by0 + 1;
  std::vector<std::vector<std::int32_t>> buckets(static_cast<std::size_t>(nbx * nby));
  for (std::size_t k = 0; k < n; ++k)
    for (std::int64_t j = bucket(box[k].min[1], y0); j <= bucket(box[k].max[1], y0); ++j)
      for (std::int64_t i = bucket(box[k].min[0], x0); i <= bucket(box[k].max[0], x0); ++i)
        buckets[static_cast<std::size_t>((j - by0) * nbx + (i - bx0))].push_back(static_cast<std::int32_t>(k));
  // Closer than `gap`? Exact for analytic shapes; for NURBS curves (slow to bound) the
  // boxes decide, which can only over-refine.
  const auto close = [&](std::size_t i, std::size_t j, double gap) {
    const auto& a = scene.inclusions[i].shape;
    const auto& b = scene.inclusions[j].shape;
    if (is_nurbs(a) || is_nurbs(b)) return box_distance(box[i], box[j]) < gap;
    return geometry::shapes_overlap(a, b, gap);
  };
  struct Pair {
    std::int32_t a, b;
    bool union_of_one_phase;  // same phase and overlapping: one interface, no R2
  };
  std::vector<Pair> pairs;
  std::vector<std::vector<std::int32_t>> neighbours(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::int64_t i0 = bucket(box[k].min[0] - reach, x0), i1 = bucket(box[k].max[0] + reach, x0);
    const std::int64_t j0 = bucket(box[k].min[1] - reach, y0), j1 = bucket(box[k].max[1] + reach, y0);
    for (std::int64_t j = std::max(j0, by0); j <= std::min(j1, by1); ++j)
      for (std::int64_t i = std::max(i0, bx0); i <= std::min(i1, bx1); ++i)
        for (std::int32_t m : buckets[static_cast<std::size_t>((j - by0) * nbx + (i - bx0))]) {
          if (m <= static_cast<std::int32_t>(k)) continue;
          if (std::find(neighbours[k].begin(), neighbours[k].end(), m) != neighbours[k].end()) continue;
          if (box_distance(box[k], box[static_cast<std::size_t>(m)]) >= reach) continue;
          neighbours[k].push_back(m);
          const auto& a = scene.inclusions[k];
          const auto& b = scene.inclusions[static_cast<std::size_t>(m)];
          const bool same_union = a.phase == b.phase && !is_nurbs(a.shape) && !is_nurbs(b.shape) &&
                                  geometry::shapes_overlap(a.shape, b.shape, 0);
          pairs.push_back({static_cast<std::int32_t>(k), m, same_union});
        }
  }
  // Contacts (R2), at the initial levels: the first level whose cells cannot touch both.
  for (const Pair& p : pairs) {
    if (p.union_of_one_phase) continue;
    const auto a = static_cast<std::size_t>(p.a), b = static_cast<std::size_t>(p.b);
    int l = std::max(level[a], level[b]);
    while (l < lattice.max_level && close(a, b, kContactCells * lattice.spacing(l))) ++l;
    level[static_cast<std::size_t>(p.a)] = std::max(level[static_cast<std::size_t>(p.a)], l);
    level[static_cast<std::size_t>(p.b)] = std::max(level[static_cast<std::size_t>(p.b)], l);
  }
  // Spread (R4): repeat until no level changes. Each pass can only raise levels, which are
  // bounded by Lmax, so this ends; distances are tested once per pair and level.
  std::vector<std::vector<std::pair<std::int32_t, bool>>> adjacency(n);  // (other, is union pair)
  for (const Pair& p : pairs) {
    adjacency[static_cast<std::size_t>(p.a)].push_back({p.b, p.union_of_one_phase});
    adjacency[static_cast<std::size_t>(p.b)].push_back({p.a, p.union_of_one_phase});
  }
  std::vector<std::int32_t> work(n);
  for (std::size_t k = 0; k < n; ++k) work[k] = static_cast<std::int32_t>(k);
  while (!work.empty()) {
    const std::int32_t j = work.back();
    work.pop_back();
    const int lj = level[static_cast<std::size_t>(j)];
    for (const auto& [i, union_pair] : adjacency[static_cast<std::size_t>(j)]) {
      const int li = level[static_cast<std::size_t>(i)];
      if (li >= lj) continue;
      if (!union_pair && !close(static_cast<std::size_t>(i), static_cast<std::size_t>(j), kSpreadCells * lattice.spacing(li)))
        continue;
      level[static_cast<std::size_t>(i)] = lj;
      work.push_back(i);
    }
  }
  return level;
}

}  // namespace cisamr::pipeline
