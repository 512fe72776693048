#include "parallel/ghost.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/shapes.hpp"
#include "pipeline/effective_levels.hpp"

namespace cisamr::parallel {

template <int Dim>
grid::Lattice<Dim> scene_lattice(const geometry::SceneDesc& scene, const pipeline::Options& options) {
  return pipeline::make_lattice<Dim>(scene, options);
}

template <int Dim>
InclusionIndex<Dim>::InclusionIndex(const geometry::SceneDesc& scene, const grid::Lattice<Dim>& lattice,
                                    const GhostRule& rule, std::span<const Box3> boxes) {
  const double h = lattice.h;
  inflated_.reserve(scene.inclusions.size());
  double extent_sum = 0, longest = 0;
  for (std::size_t k = 0; k < scene.inclusions.size(); ++k) {
    const double margin = Dim == 3          ? kBoxSlack3 * h
                          : rule.level_aware ? kInclusionMarginCells2 * std::ldexp(h, -scene.inclusions[k].levels)
                                             : rule.fixed_cells * h;
    Box<Dim> box;
    for (int d = 0; d < Dim; ++d) {
      box.min[d] = boxes[k].min[d] - margin;
      box.max[d] = boxes[k].max[d] + margin;
      extent_sum += box.max[d] - box.min[d];
    }
    inflated_.push_back(box);
  }
  origin_ = lattice.origin;
  for (int d = 0; d < Dim; ++d) longest = std::max(longest, static_cast<double>(lattice.coarse_cells[d]) * h);
  const double mean_extent = inflated_.empty() ? h : extent_sum / (Dim * static_cast<double>(inflated_.size()));
  side_ = std::max({h, mean_extent, longest / (Dim == 2 ? 2048.0 : 128.0)});
  std::int64_t nb = 1;
  for (int d = 0; d < Dim; ++d) {
    buckets_[d] = std::max<std::int64_t>(
        1, static_cast<std::int64_t>(std::ceil(static_cast<double>(lattice.coarse_cells[d]) * h / side_)));
    nb *= buckets_[d];
  }
  std::vector<std::int32_t> count(static_cast<std::size_t>(nb) + 1, 0);
  for (const Box<Dim>& box : inflated_) for_buckets(box, [&](std::size_t b) { ++count[b + 1]; });
  for (std::size_t b = 0; b < static_cast<std::size_t>(nb); ++b) count[b + 1] += count[b];
  begin_ = count;
  members_.resize(static_cast<std::size_t>(count.back()));
  for (std::int32_t k = 0; k < size(); ++k)
    for_buckets(inflated_[static_cast<std::size_t>(k)], [&](std::size_t b) {
      members_[static_cast<std::size_t>(count[b]++)] = k;
    });
}

template <int Dim>
template <class F>
void InclusionIndex<Dim>::for_buckets(const Box<Dim>& box, F&& f) const {
  const auto lo = bucket_of(box.min), hi = bucket_of(box.max);
  std::array<std::int64_t, Dim> at = lo;
  while (true) {
    std::int64_t b = 0;
    for (int d = Dim - 1; d >= 0; --d) b = b * buckets_[d] + at[d];
    f(static_cast<std::size_t>(b));
    int d = 0;
    while (d < Dim && at[d] == hi[d]) at[d] = lo[d], ++d;
    if (d == Dim) return;
    ++at[d];
  }
}

template <int Dim>
std::array<std::int64_t, Dim> InclusionIndex<Dim>::bucket_of(const Vec<Dim>& p) const {
  std::array<std::int64_t, Dim> b{};
  for (int d = 0; d < Dim; ++d) {
    const double t = std::floor((p[d] - origin_[d]) / side_);
    b[d] = !(t > 0) ? 0 : t >= static_cast<double>(buckets_[d] - 1) ? buckets_[d] - 1 : static_cast<std::int64_t>(t);
  }
  return b;
}

template <int Dim>
void InclusionIndex<Dim>::query(const Box<Dim>& box, std::vector<std::int32_t>& out) const {
  const std::size_t first = out.size();
  for_buckets(box, [&](std::size_t b) {
    for (std::int32_t m = begin_[b]; m < begin_[b + 1]; ++m) {
      const std::int32_t k = members_[static_cast<std::size_t>(m)];
      if (boxes_overlap(inflated_[static_cast<std::size_t>(k)], box)) out.push_back(k);
    }
  });
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end());
  out.erase(std::unique(out.begin() + static_cast<std::ptrdiff_t>(first), out.end()), out.end());
}

namespace {

// Coarse cells of margin below ([axis][0]) and above ([axis][1]) the box on each axis.
template <int Dim>
using Margins = std::array<std::array<double, 2>, Dim>;
template <int Dim>
Margins<Dim> uniform_margins(double cells) {
  Margins<Dim> m;
  for (auto& axis : m) axis = {cells, cells};
  return m;
}

// The box grown by `margin_cells` (the seed), the inclusions whose inflated box meets it,
// then `rounds` rounds of the closure; the range covers the seed and, with `cover`, every
// added inclusion's inflated box.
template <int Dim>
GhostRegion<Dim> grow(const InclusionIndex<Dim>& index, const grid::Lattice<Dim>& lattice,
                      const grid::CellRange<Dim>& box, const Margins<Dim>& margin_cells, int rounds, bool cover) {
  const double h = lattice.h;
  GhostRegion<Dim> region;
  region.box = box;
  Box<Dim> seed;
  for (int d = 0; d < Dim; ++d) {
    seed.min[d] = lattice.origin[d] + static_cast<double>(box.lo[d]) * h - margin_cells[static_cast<std::size_t>(d)][0] * h;
    seed.max[d] = lattice.origin[d] + static_cast<double>(box.hi[d]) * h + margin_cells[static_cast<std::size_t>(d)][1] * h;
  }
  // Breadth-first closure over "inflated boxes meet".
  std::vector<char> loaded(static_cast<std::size_t>(index.size()), 0);
  std::vector<std::int32_t> queue, found;
  index.query(seed, found);
  Box<Dim> hull = seed;
  const auto add = [&](std::int32_t k) {
    if (loaded[static_cast<std::size_t>(k)]) return;
    loaded[static_cast<std::size_t>(k)] = 1;
    queue.push_back(k);
    if (!cover) return;
    const Box<Dim>& b = index.inflated(k);
    for (int d = 0; d < Dim; ++d) {
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
      if (++round > rounds && rounds >= 0) break;
    }
    if (rounds == 0) break;
    found.clear();
    index.query(index.inflated(queue[q]), found);
    for (std::int32_t k : found) add(k);
  }
  region.inclusions = std::move(queue);
  std::sort(region.inclusions.begin(), region.inclusions.end());
  // Coarse cells covering the hull, clipped to the domain (on a periodic axis: to one period
  // around the box, the window wrapping across the faces).
  for (int d = 0; d < Dim; ++d) {
    const double lo = std::floor((hull.min[d] - lattice.origin[d]) / h);
    const double hi = std::ceil((hull.max[d] - lattice.origin[d]) / h);
    const auto cells = static_cast<double>(lattice.coarse_cells[d]);
    const double low = lattice.periodic[d] ? static_cast<double>(box.lo[d]) - cells : 0.0;
    const double high = lattice.periodic[d] ? static_cast<double>(box.hi[d]) + cells : cells;
    region.range.lo[d] = static_cast<std::int64_t>(std::clamp(lo, low, high));
    region.range.hi[d] = static_cast<std::int64_t>(std::clamp(hi, low, high));
    region.range.lo[d] = std::min(region.range.lo[d], box.lo[d]);
    region.range.hi[d] = std::max(region.range.hi[d], box.hi[d]);
    region.sides[static_cast<std::size_t>(d)] = {static_cast<int>(box.lo[d] - region.range.lo[d]),
                                                 static_cast<int>(region.range.hi[d] - box.hi[d])};
    region.ghost = std::max({region.ghost, region.sides[static_cast<std::size_t>(d)][0], region.sides[static_cast<std::size_t>(d)][1]});
  }
  if (lattice.any_periodic()) {
    // The kernel evaluates every cell of the window in its canonical frame (inside the
    // domain), so it needs the inclusions (listed or images) that meet the window's cells
    // where they are, not where the unwrapped window lies: query the canonical pieces.
    const grid::CellRange<Dim> window = pipeline::ghosted_range(lattice, box, region.sides);
    std::vector<std::array<std::int64_t, 2>> pieces[Dim];  // per axis, canonical [lo, hi)
    for (int d = 0; d < Dim; ++d) {
      const std::int64_t n = lattice.coarse_cells[d];
      if (!lattice.periodic[d]) {
        pieces[d].push_back({window.lo[d], window.hi[d]});
        continue;
      }
      const std::int64_t lo = lattice.canonical_cell(d, 0, window.lo[d]);
      const std::int64_t count = window.hi[d] - window.lo[d];
      if (lo + count <= n) pieces[d].push_back({lo, lo + count});
      else pieces[d].push_back({lo, n}), pieces[d].push_back({0, lo + count - n});
    }
    std::vector<std::int32_t> inclusions;
    std::array<std::size_t, Dim> at{};
    while (true) {
      Box<Dim> piece;
      for (int d = 0; d < Dim; ++d) {
        piece.min[d] = lattice.origin[d] + static_cast<double>(pieces[d][at[d]][0]) * h;
        piece.max[d] = lattice.origin[d] + static_cast<double>(pieces[d][at[d]][1]) * h;
      }
      index.query(piece, found);
      inclusions.insert(inclusions.end(), found.begin(), found.end());
      int d = 0;
      while (d < Dim && ++at[d] == pieces[d].size()) at[d] = 0, ++d;
      if (d == Dim) break;
    }
    std::sort(inclusions.begin(), inclusions.end());
    inclusions.erase(std::unique(inclusions.begin(), inclusions.end()), inclusions.end());
    region.inclusions = std::move(inclusions);
  }
  return region;
}

}  // namespace

int ghost_margin3(int level, int max_level, bool exchanged) {
  const double samr_reach = samr::reach_coarse_cells3(max_level);
  if (exchanged)
    return static_cast<int>(std::ceil(std::max(samr_reach, std::ldexp(kExchangedKernelReach3, -std::max(0, level)))));
  return static_cast<int>(std::floor(samr_reach + std::ldexp(kKernelReach3, -std::max(0, level)))) + 1;
}

partition::PartitionOptions ghost_aware(partition::PartitionOptions options, int dimension, const GhostRule& rule) {
  if (dimension != 3) return options;
  options.ghost_cells_at_level.clear();
  for (int level = 0; level <= 3; ++level)  // ghost_margin3 is 1 from level 1 on
    options.ghost_cells_at_level.push_back(rule.margin3_cubes > 0 ? static_cast<int>(std::ceil(rule.margin3_cubes))
                                                                   : ghost_margin3(level, 64, true));
  options.ghost_weight = kGhostCostWeight3;
  return options;
}

template <int Dim>
GhostRegion<Dim> ghost_region(const InclusionIndex<Dim>& index, const grid::Lattice<Dim>& lattice,
                              const grid::CellRange<Dim>& box, const GhostRule& rule) {
  GhostRegion<Dim> region = grow<Dim>(index, lattice, box, uniform_margins<Dim>(rule.box_margin_cells), rule.max_closure_rounds,
                                      rule.max_closure_rounds != 0);
  // The kernel meshes the uniform width that covers the range (with closure rounds, the
  // range may reach further on one side).
  region.sides = pipeline::uniform_sides(region.ghost);
  return region;
}

GhostRegion3 ghost_region3(const InclusionIndex3& index, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
                           const GhostRule& rule, std::span<const int> levels) {
  // The coarsest effective level among the inclusions that could matter at all (the widest
  // margin): the windows are in cells of that level.
  const int widest_margin = ghost_margin3(0);
  const GhostRegion3 widest = grow<3>(index, lattice, box, uniform_margins<3>(widest_margin), 0, false);
  const auto coarsest_of = [&](const std::vector<std::int32_t>& inclusions) {
    int coarsest = -1;
    for (std::int32_t k : inclusions) {
      const int l = levels[static_cast<std::size_t>(k)];
      coarsest = coarsest < 0 ? l : std::min(coarsest, l);
    }
    return coarsest;
  };
  const int coarsest = coarsest_of(widest.inclusions);
  const bool exchange = exchanges_near_faces(rule, lattice.any_periodic());
  const auto margin_of = [&](int level) { return level < 0 ? 1 : ghost_margin3(level, lattice.max_level, exchange); };
  const bool forced = rule.margin3_cubes > 0;
  const bool closure = rule.max_closure_rounds != 0;
  // Each face its own margin (issue #15: "derive it per box face from what actually lies
  // within reach of that face"): the level that decides near a face is that of the cut
  // leaves near it, on either side, so the margin beyond face (axis d, side s) is that of
  // the coarsest level among the inclusions within the widest margin of the face (on both
  // sides of it, and as far beyond the box's edges). Everything a decision in the box reads
  // beyond that face lies there (README.md, "Ghost region (3D)"). A periodic lattice (its
  // ghost wraps in frame coordinates) and the comparisons keep one margin for all faces.
  Margins<3> margins = uniform_margins<3>(forced ? std::ceil(rule.margin3_cubes) : margin_of(coarsest));
  const bool per_face = !forced && !closure && !lattice.any_periodic();
  if (per_face) {
    std::vector<std::int32_t> near_face;
    for (int d = 0; d < 3; ++d)
      for (int side = 0; side < 2; ++side) {
        Box3 slab;
        for (int a = 0; a < 3; ++a) {
          slab.min[a] = lattice.origin[a] + static_cast<double>(box.lo[a] - widest_margin) * lattice.h;
          slab.max[a] = lattice.origin[a] + static_cast<double>(box.hi[a] + widest_margin) * lattice.h;
        }
        const std::int64_t face = side == 0 ? box.lo[d] : box.hi[d];
        slab.min[d] = lattice.origin[d] + static_cast<double>(face - widest_margin) * lattice.h;
        slab.max[d] = lattice.origin[d] + static_cast<double>(face + widest_margin) * lattice.h;
        near_face.clear();
        index.query(slab, near_face);
        margins[static_cast<std::size_t>(d)][static_cast<std::size_t>(side)] = margin_of(coarsest_of(near_face));
      }
  }
  GhostRegion3 region = grow<3>(index, lattice, box, margins, rule.max_closure_rounds, closure);
  if (!per_face) region.sides = pipeline::uniform_sides(region.ghost);
  for (const auto& axis : margins) region.margin = std::max({region.margin, static_cast<int>(axis[0]), static_cast<int>(axis[1])});
  // Without inclusions nearby nothing snaps or swaps: the windows stay whole. Closure
  // rounds (a comparison of the old rule) keep them whole too, and so does a periodic
  // lattice (its ghost wraps around the period in frame coordinates).
  if (coarsest >= 0 && rule.max_closure_rounds == 0 && !lattice.any_periodic()) {
    const auto reach = [&](double forced, int derived) -> std::int64_t {
      if (forced < 0) return -1;
      const double cells = forced > 0 ? forced : derived;
      return static_cast<std::int64_t>(std::ceil(cells * static_cast<double>(lattice.units(std::min(coarsest, lattice.max_level)))));
    };
    region.radapt_reach = reach(rule.radapt_window_cells3, exchange ? kExchangedRadaptWindow3 : kRadaptWindow3);
    region.swap_reach = reach(rule.swap_window3_cells(), kSwapWindow3);
    // Forced windows (comparisons) run the guard on all of r-adaptivity's, as before.
    const bool forced = rule.radapt_window_cells3 != 0 || rule.swap_window_cells3 != 0;
    region.first_pass_reach =
        forced ? region.radapt_reach : reach(0, exchange ? kExchangedFirstPassWindow3 : kFirstPassWindow3);
    region.second_pass_reach =
        forced ? region.radapt_reach : reach(0, exchange ? kExchangedSecondPassWindow3 : kSecondPassWindow3);
    region.exchange = exchange;
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
  out.images_expanded = scene.images_expanded;  // the subset's images are already there
  out.h = scene.h;
  out.levels = scene.levels;
  out.phases = scene.phases;
  out.matrix_phase = scene.matrix_phase;
  out.inclusions.reserve(inclusions.size());
  // Named as in the scene file (an image by the inclusion it is an image of).
  for (std::int32_t k : inclusions) {
    const auto at = static_cast<std::size_t>(k);
    out.inclusions.push_back(scene.inclusions[at]);
    const std::size_t base = scene.listed(at);
    out.entry.push_back(base < scene.entry.size() ? scene.entry[base] : static_cast<std::int32_t>(base));
    out.entry_solid.push_back(base < scene.entry_solid.size() ? scene.entry_solid[base] : -1);
  }
  return out;
}

template grid::Lattice<2> scene_lattice<2>(const geometry::SceneDesc&, const pipeline::Options&);
template grid::Lattice<3> scene_lattice<3>(const geometry::SceneDesc&, const pipeline::Options&);
template class InclusionIndex<2>;
template class InclusionIndex<3>;
template GhostRegion<2> ghost_region<2>(const InclusionIndex<2>&, const grid::Lattice<2>&, const grid::CellRange<2>&,
                                        const GhostRule&);
template GhostRegion<3> ghost_region<3>(const InclusionIndex<3>&, const grid::Lattice<3>&, const grid::CellRange<3>&,
                                        const GhostRule&);

}  // namespace cisamr::parallel
