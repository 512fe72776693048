#include "pipeline/effective_levels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <variant>

#include "geometry/shapes.hpp"

namespace cisamr::pipeline {
namespace {

// Reach of the rules in cells of a level (effective_levels.hpp).
template <int Dim>
constexpr double kContactCells = Dim == 2 ? 1.5 : 1.8;  // > √Dim: a cell touches two boundaries only closer than √Dim·h_l
template <int Dim>
constexpr double kSpreadCells = Dim == 2 ? 6.5 : 8.0;  // 2D: R4's 5×5 block, both cells' diagonals, a 2:1 cascade

// Buckets per axis of the pair search at most (about 4M buckets in 2D, 2M in 3D).
template <int Dim>
constexpr double kMaxBucketsPerAxis = Dim == 2 ? 2048 : 128;

// Shapes whose distance is judged by their boxes (exact tests too slow or not available).
bool by_box(const geometry::Shape& s) { return geometry::shape_judged_by_box(s); }

template <int Dim>
double box_distance(const Box3& a, const Box3& b) {
  double s = 0;
  for (int d = 0; d < Dim; ++d) {
    const double g = std::max({0.0, a.min[d] - b.max[d], b.min[d] - a.max[d]});
    s += g * g;
  }
  return std::sqrt(s);
}

template <int Dim>
std::vector<int> effective_levels(const geometry::SceneDesc& scene, const grid::Lattice<Dim>& lattice,
                                  std::span<const Box3> known, std::span<const SurfacePair> surface_unions) {
  const std::size_t n = scene.inclusions.size();
  std::vector<int> level(n);
  for (std::size_t k = 0; k < n; ++k) level[k] = std::min(std::max(0, scene.inclusions[k].levels), lattice.max_level);
  if (n < 2) return level;
  const std::vector<Box3> box = holding_boxes(scene, known);

  // Candidate pairs: boxes closer than the widest reach (coarsest level), by buckets over
  // the domain grown by that reach. An inclusion whose box misses the domain has no cell to
  // refine and takes part in no pair (its own level stays); clamping coordinates into the
  // grid keeps far-away boxes from blowing up the bucket indices.
  int min_level = lattice.max_level;
  for (int l : level) min_level = std::min(min_level, l);
  const double reach = kSpreadCells<Dim> * lattice.spacing(min_level);
  Vec3 grid_min{}, grid_max{};
  double side = std::max(reach, 4 * lattice.h);
  for (int d = 0; d < Dim; ++d) {
    grid_min[d] = scene.domain_min[static_cast<std::size_t>(d)] - reach;
    grid_max[d] = scene.domain_max[static_cast<std::size_t>(d)] + reach;
    // At most about kMaxBucketsPerAxis buckets per axis: the side only sets the cost of the
    // search, not which pairs it finds.
    side = std::max(side, (grid_max[d] - grid_min[d]) / kMaxBucketsPerAxis<Dim>);
  }
  using Cell = std::array<std::int64_t, Dim>;
  const auto bucket = [&](const Vec3& p) {
    Cell c{};
    for (int d = 0; d < Dim; ++d)
      c[d] = static_cast<std::int64_t>(std::floor((std::clamp(p[d], grid_min[d], grid_max[d]) - grid_min[d]) / side));
    return c;
  };
  const Cell lo{}, hi = bucket(grid_max);
  const auto in_domain = [&](const Box3& b) {
    for (int d = 0; d < Dim; ++d)
      if (!(b.max[d] >= scene.domain_min[static_cast<std::size_t>(d)] &&
            b.min[d] <= scene.domain_max[static_cast<std::size_t>(d)]))
        return false;
    return true;
  };
  // Visits the buckets of [a, c] clipped to the grid, as flat indices.
  const auto for_buckets = [&](Cell a, Cell c, auto&& f) {
    for (int d = 0; d < Dim; ++d) {
      a[d] = std::max(a[d], lo[d]), c[d] = std::min(c[d], hi[d]);
      if (a[d] > c[d]) return;
    }
    Cell at = a;
    while (true) {
      std::int64_t flat = 0;
      for (int d = Dim - 1; d >= 0; --d) flat = flat * (hi[d] - lo[d] + 1) + (at[d] - lo[d]);
      f(static_cast<std::size_t>(flat));
      int d = 0;
      while (d < Dim && at[d] == c[d]) at[d] = a[d], ++d;
      if (d == Dim) return;
      ++at[d];
    }
  };
  std::int64_t buckets = 1;
  for (int d = 0; d < Dim; ++d) buckets *= hi[d] - lo[d] + 1;
  std::vector<std::vector<std::int32_t>> members(static_cast<std::size_t>(buckets));
  for (std::size_t k = 0; k < n; ++k)
    if (in_domain(box[k]))
      for_buckets(bucket(box[k].min), bucket(box[k].max), [&](std::size_t b) { members[b].push_back(static_cast<std::int32_t>(k)); });
  // Closer than `gap`? Exact for analytic shapes; by boxes otherwise (can only over-refine).
  const auto close = [&](std::size_t i, std::size_t j, double gap) {
    const auto& a = scene.inclusions[i].shape;
    const auto& b = scene.inclusions[j].shape;
    if (by_box(a) || by_box(b)) return box_distance<Dim>(box[i], box[j]) < gap;
    return geometry::shapes_overlap(a, b, gap);
  };
  struct Pair {
    std::int32_t a, b;
    bool union_of_one_phase;  // same phase and overlapping: one interface, no R2
  };
  std::vector<Pair> pairs;
  std::vector<std::vector<std::int32_t>> neighbours(n);
  for (std::size_t k = 0; k < n; ++k) {
    if (!in_domain(box[k])) continue;
    Vec3 a = box[k].min, c = box[k].max;
    for (int d = 0; d < 3; ++d) a[d] -= reach, c[d] += reach;
    for_buckets(bucket(a), bucket(c), [&](std::size_t b) {
      for (std::int32_t m : members[b]) {
        if (m <= static_cast<std::int32_t>(k)) continue;
        if (std::find(neighbours[k].begin(), neighbours[k].end(), m) != neighbours[k].end()) continue;
        if (box_distance<Dim>(box[k], box[static_cast<std::size_t>(m)]) >= reach) continue;
        neighbours[k].push_back(m);
        const auto& x = scene.inclusions[k];
        const auto& y = scene.inclusions[static_cast<std::size_t>(m)];
        const bool surfaces = by_box(x.shape) || by_box(y.shape);
        const bool same_union =
            x.phase == y.phase && (surfaces ? std::binary_search(surface_unions.begin(), surface_unions.end(),
                                                                 SurfacePair{static_cast<std::int32_t>(k), m})
                                            : geometry::shapes_overlap(x.shape, y.shape, 0));
        pairs.push_back({static_cast<std::int32_t>(k), m, same_union});
      }
    });
  }
  // A periodic image is its inclusion seen across the period: one interface, one level.
  for (std::size_t k = 0; k < n; ++k)
    if (const std::size_t base = scene.listed(k); base != k)
      pairs.push_back({static_cast<std::int32_t>(base), static_cast<std::int32_t>(k), true});
  // Contacts (R2), at the initial levels: the first level whose cells cannot touch both.
  for (const Pair& p : pairs) {
    if (p.union_of_one_phase) continue;
    const auto a = static_cast<std::size_t>(p.a), b = static_cast<std::size_t>(p.b);
    int l = std::max(level[a], level[b]);
    while (l < lattice.max_level && close(a, b, kContactCells<Dim> * lattice.spacing(l))) ++l;
    level[a] = std::max(level[a], l);
    level[b] = std::max(level[b], l);
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
      if (!union_pair &&
          !close(static_cast<std::size_t>(i), static_cast<std::size_t>(j), kSpreadCells<Dim> * lattice.spacing(li)))
        continue;
      level[static_cast<std::size_t>(i)] = lj;
      work.push_back(i);
    }
  }
  return level;
}

}  // namespace

std::vector<Box3> holding_boxes(const geometry::SceneDesc& scene, std::span<const Box3> known) {
  std::vector<Box3> out;
  out.reserve(scene.inclusions.size());
  for (std::size_t k = 0; k < scene.inclusions.size(); ++k) {
    const geometry::Shape& shape = scene.inclusions[k].shape;
    const auto* stl = std::get_if<geometry::StlSurface>(&shape);
    if (stl != nullptr && stl->triangles.empty() && k < known.size()) {
      out.push_back(known[k]);
      continue;
    }
    out.push_back(geometry::shape_holding_box(shape));
  }
  return out;
}

std::vector<SurfacePair> surface_union_candidates(const geometry::SceneDesc& scene, std::span<const Box3> box) {
  std::vector<SurfacePair> out;
  // Sorted boxes along x: a sweep finds the pairs whose boxes meet.
  std::vector<std::int32_t> order(scene.inclusions.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<std::int32_t>(k);
  std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
    return box[static_cast<std::size_t>(a)].min[0] < box[static_cast<std::size_t>(b)].min[0];
  });
  for (std::size_t i = 0; i < order.size(); ++i) {
    const auto a = static_cast<std::size_t>(order[i]);
    for (std::size_t j = i + 1; j < order.size(); ++j) {
      const auto b = static_cast<std::size_t>(order[j]);
      if (box[b].min[0] > box[a].max[0]) break;
      const auto& x = scene.inclusions[a];
      const auto& y = scene.inclusions[b];
      if (x.phase != y.phase || !(by_box(x.shape) || by_box(y.shape))) continue;
      if (!boxes_overlap(box[a], box[b])) continue;
      out.push_back({static_cast<std::int32_t>(std::min(a, b)), static_cast<std::int32_t>(std::max(a, b))});
    }
  }
  return out;
}

std::vector<SurfacePair> surface_unions(const geometry::SceneDesc& scene) {
  const std::vector<Box3> box = holding_boxes(scene);
  std::vector<SurfacePair> out;
  for (const SurfacePair& p : surface_union_candidates(scene, box))
    if (geometry::shapes_overlap(scene.inclusions[static_cast<std::size_t>(p.a)].shape,
                                 scene.inclusions[static_cast<std::size_t>(p.b)].shape, 0))
      out.push_back(p);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<int> effective_levels2(const geometry::SceneDesc& scene, const grid::Lattice2& lattice) {
  return effective_levels<2>(scene, lattice, {}, {});
}

std::vector<int> effective_levels3(const geometry::SceneDesc& scene, const grid::Lattice<3>& lattice,
                                   std::span<const Box3> known, std::span<const SurfacePair> unions) {
  return effective_levels<3>(scene, lattice, known, unions);
}

}  // namespace cisamr::pipeline
