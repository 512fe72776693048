#include "samr/samr2.hpp"

#include <algorithm>

#include <stdexcept>

#include "core/error.hpp"

namespace cisamr::samr {
namespace {

constexpr std::int64_t kCandidateBlock = 8;  // roots per side of one AABB-tree query

class Refiner {
 public:
  Refiner(const geometry::Oracle2& oracle, RefinedGrid2& g, std::span<const int> levels)
      : oracle_(oracle), g_(g), levels_(levels) {}

  // Progress in units of 2 × roots: the roots set up (refine2), then the share of the cut
  // roots whose refinement is finished. The stack is last in, first out, so the cut roots
  // pushed first stay below all later work: once the stack is shorter than k, the cut
  // roots above position k are finished.
  void run(Progress* progress) {
    const std::int32_t roots = g_.forest.root_count();
    for (std::int32_t c = 0; c < roots; ++c)
      if (g_.is_cut(c)) stack_.push_back(c);
    const auto cut_roots = static_cast<std::int64_t>(stack_.size());
    const std::int64_t total = 2 * std::int64_t{roots};
    std::int64_t unfinished = cut_roots;
    for (std::int64_t visits = 1; !stack_.empty(); ++visits) {
      const std::int32_t c = stack_.back();
      stack_.pop_back();
      unfinished = std::min(unfinished, static_cast<std::int64_t>(stack_.size()));
      if (g_.forest.is_leaf(c)) visit(c);
      if (progress != nullptr && (visits & 4095) == 0)
        progress->advance(roots + (cut_roots - unfinished) * roots / cut_roots, total);
    }
    advance(progress, total, total);
  }

 private:
  const geometry::Oracle2& oracle_;
  RefinedGrid2& g_;
  std::span<const int> levels_;
  std::vector<std::int32_t> stack_;
  std::vector<int> groups_;

  int max_level() const { return g_.forest.lattice().max_level; }


  void visit(std::int32_t c) {
    const auto cell = g_.forest.cell(c);
    const int level = cell.level;
    // R3: edge neighbours at most one level coarser.
    if (level >= 2) {
      static constexpr int kEdge[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
      for (const auto& e : kEdge) {
        // Refine the neighbour until it is at most one level coarser (it may start
        // several levels coarser; each refinement creates the next level down).
        while (true) {
          const std::int32_t n = g_.forest.find(level, cell.i + e[0], cell.j + e[1]);
          if (n < 0 || !g_.forest.is_leaf(n) || g_.forest.cell(n).level >= level - 1) break;
          refine(n);
        }
      }
    }
    if (!g_.is_cut(c)) return;
    // R1 and R2.
    bool split = false;
    groups_.clear();
    for (std::int32_t k : g_.touched(c)) {
      if (level < (levels_.empty() ? oracle_.levels_of(k) : levels_[static_cast<std::size_t>(k)])) split = true;
      const int group = oracle_.interface_group(k);
      if (std::find(groups_.begin(), groups_.end(), group) == groups_.end()) groups_.push_back(group);
    }
    // R2: two interface groups in one cell, separated down to the finest level if need be.
    if (level < max_level() && groups_.size() >= 2) split = true;
    // R4: the 3x3 block around a cut cell has its level; the 5x5 block (less corners)
    // holds no finer cell, so neighbours of the cut cell carry no hanging node.
    if (!split) {
      for (int dj = -2; dj <= 2 && !split; ++dj)
        for (int di = -2; di <= 2; ++di) {
          if ((di == 0 && dj == 0) || (std::abs(di) == 2 && std::abs(dj) == 2)) continue;
          const std::int32_t n = g_.forest.find(level, cell.i + di, cell.j + dj);
          if (n < 0) continue;
          if (!g_.forest.is_leaf(n)) {  // a finer cell: refine the cut cell
            split = true;
            break;
          }
          if (std::abs(di) <= 1 && std::abs(dj) <= 1)
            for (std::int32_t m = n; g_.forest.is_leaf(m) && g_.forest.cell(m).level < level;
                 m = g_.forest.find(level, cell.i + di, cell.j + dj))
              refine(m);
        }
    }
    if (split) refine(c);
  }

  void refine(std::int32_t c) {
    if (g_.forest.cell(c).level >= max_level())
      throw MeshingError("SAMR rules ask for a level beyond the finest one");
    const std::int32_t first = g_.forest.refine(c);
    ++g_.refinements;
    for (int k = 0; k < 4; ++k) {
      const std::int32_t child = first + k;
      g_.append_touching(oracle_, c, g_.forest.box(child));
      stack_.push_back(child);
    }
    // Cut cells near c may now see a finer neighbour (R4): visit them again.
    const auto cell = g_.forest.cell(c);
    for (int dj = -2; dj <= 2; ++dj)
      for (int di = -2; di <= 2; ++di) {
        if (di == 0 && dj == 0) continue;
        const std::int32_t n = g_.forest.find(cell.level, cell.i + di, cell.j + dj);
        if (n >= 0 && g_.forest.is_leaf(n) && g_.is_cut(n)) stack_.push_back(n);
      }
  }
};

}  // namespace

RefinedGrid2 refine2(const geometry::Oracle2& oracle, const grid::Lattice2& lattice,
                     const grid::CellRange<2>& range, std::span<const int> levels, Progress* progress) {
  if (!levels.empty() && static_cast<int>(levels.size()) != oracle.inclusion_count())
    throw std::invalid_argument("refine2: one level per inclusion expected");
  RefinedGrid2 g{{}, grid::QuadForest(lattice, range), {}, 0};
  const std::int32_t roots = g.forest.root_count();
  const std::int64_t nx = g.forest.range().count(0), ny = g.forest.range().count(1);

  // Candidates per root: one AABB-tree query per block of roots, then a box filter.
  std::vector<std::vector<std::int32_t>> per_root(static_cast<std::size_t>(roots));
  std::vector<std::int32_t> block_candidates;
  const double h = lattice.h;
  // A block never straddles a periodic face: its roots are contiguous in canonical indices,
  // so its box is the canonical cells' (where their geometry, images included, lies).
  const grid::CellRange<2>& window = g.forest.range();
  const auto block_end = [&](int d, std::int64_t b, std::int64_t n) {
    const std::int64_t start = lattice.canonical_cell(d, 0, window.lo[d] + b);
    std::int64_t e = std::min(n, b + kCandidateBlock);
    if (lattice.periodic[d]) e = std::min(e, b + lattice.coarse_cells[d] - start);
    return e;
  };
  for (std::int64_t bj = 0, ej = 0; bj < ny; bj = ej)
    for (std::int64_t bi = 0, ei = 0; bi < nx; bi = ei) {
      ei = block_end(0, bi, nx);
      ej = block_end(1, bj, ny);
      // Window position bi holds canonical cell ci0 (likewise j).
      const std::int64_t ci0 = lattice.canonical_cell(0, 0, window.lo[0] + bi);
      const std::int64_t cj0 = lattice.canonical_cell(1, 0, window.lo[1] + bj);
      const Box2 block{{lattice.origin[0] + static_cast<double>(ci0) * h, lattice.origin[1] + static_cast<double>(cj0) * h},
                       {lattice.origin[0] + static_cast<double>(ci0 + ei - bi) * h,
                        lattice.origin[1] + static_cast<double>(cj0 + ej - bj) * h}};
      oracle.candidates(block, block_candidates);
      for (std::int32_t k : block_candidates) {
        const Box2 b = oracle.bounding_box(k);
        // Coarse cells whose closed box meets the inclusion's box.
        const auto first = [&](double lo, int d) {
          return static_cast<std::int64_t>(std::floor((lo - lattice.origin[d]) / h)) - 1;
        };
        const std::int64_t i0 = std::max(bi, first(b.min[0], 0) - ci0 + bi);
        const std::int64_t j0 = std::max(bj, first(b.min[1], 1) - cj0 + bj);
        const std::int64_t i1 = std::min(ei - 1, first(b.max[0], 0) + 2 - ci0 + bi);
        const std::int64_t j1 = std::min(ej - 1, first(b.max[1], 1) + 2 - cj0 + bj);
        for (std::int64_t j = j0; j <= j1; ++j)
          for (std::int64_t i = i0; i <= i1; ++i) {
            const std::int32_t r = static_cast<std::int32_t>(j * nx + i);
            if (boxes_overlap(g.forest.box(r), b)) per_root[static_cast<std::size_t>(r)].push_back(k);
          }
      }
    }
  g.root_candidates.begin.resize(static_cast<std::size_t>(roots) + 1);
  g.touch_begin.resize(static_cast<std::size_t>(roots));
  g.touch_count.resize(static_cast<std::size_t>(roots));
  for (std::int32_t r = 0; r < roots; ++r) {
    advance_sometimes(progress, r, 2 * std::int64_t{roots});  // as Refiner::run's
    auto& list = per_root[static_cast<std::size_t>(r)];
    std::sort(list.begin(), list.end());
    g.root_candidates.begin[static_cast<std::size_t>(r)] = static_cast<std::int32_t>(g.root_candidates.list.size());
    g.touch_begin[static_cast<std::size_t>(r)] = static_cast<std::int32_t>(g.touch_pool.size());
    const Box2 box = g.forest.box(r);
    std::uint16_t count = 0;
    for (std::int32_t k : list) {
      g.root_candidates.list.push_back(k);
      if (oracle.boundary_touches(k, box)) {
        g.touch_pool.push_back(k);
        ++count;
      }
    }
    g.touch_count[static_cast<std::size_t>(r)] = count;
    std::vector<std::int32_t>().swap(list);
  }
  g.root_candidates.begin[static_cast<std::size_t>(roots)] = static_cast<std::int32_t>(g.root_candidates.list.size());

  Refiner(oracle, g, levels).run(progress);
  return g;
}

}  // namespace cisamr::samr
