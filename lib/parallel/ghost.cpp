#include "parallel/ghost.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/oracle2.hpp"
#include "geometry/shapes.hpp"

namespace cisamr::parallel {
namespace {

// A box that holds the shape, cheaply: for a NURBS curve the box of its control points
// (with positive weights the curve lies in their convex hull); geometry's tight box of a
// NURBS curve costs ~0.2 s per curve, far too much for a whole scene on every rank.
Box2 holding_box(const geometry::Shape& shape) {
  if (const auto* c = std::get_if<geometry::NurbsCurve>(&shape); c != nullptr && !c->control_points.empty()) {
    Box2 b{c->control_points.front(), c->control_points.front()};
    for (const Vec2& p : c->control_points)
      for (int d = 0; d < 2; ++d) b.min[d] = std::min(b.min[d], p[d]), b.max[d] = std::max(b.max[d], p[d]);
    return b;
  }
  const Box3 b = geometry::shape_bounding_box(shape);
  return {{b.min[0], b.min[1]}, {b.max[0], b.max[1]}};
}

}  // namespace

grid::Lattice2 scene_lattice2(const geometry::SceneDesc& scene, const pipeline::Options& options) {
  geometry::SceneDesc header = scene;
  header.inclusions.clear();
  grid::Lattice2 lattice = pipeline::make_lattice2(geometry::Oracle2(header), options);
  int levels = scene.levels;
  for (const auto& inc : scene.inclusions) levels = std::max(levels, inc.levels);
  lattice.max_level = levels + std::max(0, options.extra_levels);
  return lattice;
}

InclusionIndex2::InclusionIndex2(const geometry::SceneDesc& scene, const grid::Lattice2& lattice,
                                 const GhostRule& rule) {
  const double h = lattice.h;
  inflated_.reserve(scene.inclusions.size());
  double extent_sum = 0;
  for (const auto& inc : scene.inclusions) {
    const Box2 b = holding_box(inc.shape);
    const double margin = rule.level_aware ? 4.0 * std::ldexp(h, -inc.levels) : rule.fixed_cells * h;
    Box2 box{{b.min[0] - margin, b.min[1] - margin}, {b.max[0] + margin, b.max[1] + margin}};
    extent_sum += (box.max[0] - box.min[0]) + (box.max[1] - box.min[1]);
    inflated_.push_back(box);
  }
  origin_ = lattice.origin;
  const double lx = static_cast<double>(lattice.coarse_cells[0]) * h;
  const double ly = static_cast<double>(lattice.coarse_cells[1]) * h;
  const double mean_extent = inflated_.empty() ? h : extent_sum / (2.0 * static_cast<double>(inflated_.size()));
  side_ = std::max({h, mean_extent, std::max(lx, ly) / 2048.0});
  buckets_ = {std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(lx / side_))),
              std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(ly / side_)))};
  const auto nb = static_cast<std::size_t>(buckets_[0] * buckets_[1]);
  std::vector<std::int32_t> count(nb + 1, 0);
  const auto for_buckets = [&](const Box2& box, auto&& f) {
    const auto lo = bucket_of(box.min), hi = bucket_of(box.max);
    for (std::int64_t j = lo[1]; j <= hi[1]; ++j)
      for (std::int64_t i = lo[0]; i <= hi[0]; ++i) f(static_cast<std::size_t>(j * buckets_[0] + i));
  };
  for (const Box2& box : inflated_) for_buckets(box, [&](std::size_t b) { ++count[b + 1]; });
  for (std::size_t b = 0; b < nb; ++b) count[b + 1] += count[b];
  begin_ = count;
  members_.resize(static_cast<std::size_t>(count[nb]));
  for (std::int32_t k = 0; k < size(); ++k)
    for_buckets(inflated_[static_cast<std::size_t>(k)], [&](std::size_t b) {
      members_[static_cast<std::size_t>(count[b]++)] = k;
    });
}

std::array<std::int64_t, 2> InclusionIndex2::bucket_of(const Vec2& p) const {
  std::array<std::int64_t, 2> b{};
  for (int d = 0; d < 2; ++d) {
    const double t = std::floor((p[d] - origin_[d]) / side_);
    b[d] = !(t > 0) ? 0 : t >= static_cast<double>(buckets_[d] - 1) ? buckets_[d] - 1 : static_cast<std::int64_t>(t);
  }
  return b;
}

void InclusionIndex2::query(const Box2& box, std::vector<std::int32_t>& out) const {
  const std::size_t first = out.size();
  const auto lo = bucket_of(box.min), hi = bucket_of(box.max);
  for (std::int64_t j = lo[1]; j <= hi[1]; ++j)
    for (std::int64_t i = lo[0]; i <= hi[0]; ++i) {
      const auto b = static_cast<std::size_t>(j * buckets_[0] + i);
      for (std::int32_t m = begin_[b]; m < begin_[b + 1]; ++m) {
        const std::int32_t k = members_[static_cast<std::size_t>(m)];
        if (boxes_overlap(inflated_[static_cast<std::size_t>(k)], box)) out.push_back(k);
      }
    }
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end());
  out.erase(std::unique(out.begin() + static_cast<std::ptrdiff_t>(first), out.end()), out.end());
}

GhostRegion2 ghost_region2(const InclusionIndex2& index, const grid::Lattice2& lattice,
                           const grid::CellRange<2>& box, const GhostRule& rule) {
  const double h = lattice.h;
  GhostRegion2 region;
  region.box = box;
  const double m = rule.box_margin_cells * h;
  Box2 seed;
  for (int d = 0; d < 2; ++d) {
    seed.min[d] = lattice.origin[d] + static_cast<double>(box.lo[d]) * h - m;
    seed.max[d] = lattice.origin[d] + static_cast<double>(box.hi[d]) * h + m;
  }
  // Breadth-first closure over "inflated boxes meet".
  std::vector<char> loaded(static_cast<std::size_t>(index.size()), 0);
  std::vector<std::int32_t> queue, found;
  index.query(seed, found);
  Box2 hull = seed;
  const auto add = [&](std::int32_t k) {
    if (loaded[static_cast<std::size_t>(k)]) return;
    loaded[static_cast<std::size_t>(k)] = 1;
    queue.push_back(k);
    const Box2& b = index.inflated(k);
    for (int d = 0; d < 2; ++d) {
      hull.min[d] = std::min(hull.min[d], b.min[d]);
      hull.max[d] = std::max(hull.max[d], b.max[d]);
    }
  };
  for (std::int32_t k : found) add(k);
  std::size_t round_end = queue.size();
  int round = 0;
  for (std::size_t q = 0; q < queue.size(); ++q) {
    if (q == round_end) {
      round_end = queue.size();
      if (++round > rule.max_closure_rounds && rule.max_closure_rounds >= 0) break;
    }
    if (rule.max_closure_rounds == 0) break;
    found.clear();
    index.query(index.inflated(queue[q]), found);
    for (std::int32_t k : found) add(k);
  }
  region.inclusions = std::move(queue);
  std::sort(region.inclusions.begin(), region.inclusions.end());
  // Coarse cells covering the hull, clipped to the domain.
  for (int d = 0; d < 2; ++d) {
    const double lo = std::floor((hull.min[d] - lattice.origin[d]) / h);
    const double hi = std::ceil((hull.max[d] - lattice.origin[d]) / h);
    const auto cells = static_cast<double>(lattice.coarse_cells[d]);
    region.range.lo[d] = static_cast<std::int64_t>(std::clamp(lo, 0.0, cells));
    region.range.hi[d] = static_cast<std::int64_t>(std::clamp(hi, 0.0, cells));
    region.range.lo[d] = std::min(region.range.lo[d], box.lo[d]);
    region.range.hi[d] = std::max(region.range.hi[d], box.hi[d]);
    region.ghost = static_cast<int>(std::max<std::int64_t>(
        region.ghost, std::max(box.lo[d] - region.range.lo[d], region.range.hi[d] - box.hi[d])));
  }
  return region;
}

geometry::SceneDesc subset_scene(const geometry::SceneDesc& scene, const std::vector<std::int32_t>& inclusions) {
  geometry::SceneDesc out;
  out.source = scene.source;
  out.dimension = scene.dimension;
  out.domain_min = scene.domain_min;
  out.domain_max = scene.domain_max;
  out.periodic = scene.periodic;
  out.h = scene.h;
  out.levels = scene.levels;
  out.phases = scene.phases;
  out.matrix_phase = scene.matrix_phase;
  out.inclusions.reserve(inclusions.size());
  for (std::int32_t k : inclusions) out.inclusions.push_back(scene.inclusions[static_cast<std::size_t>(k)]);
  return out;
}

}  // namespace cisamr::parallel
