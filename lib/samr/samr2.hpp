#pragma once
// SAMR in 2D: refine the quad forest near interfaces until the rules hold
// (lib/samr/README.md):
//   R1  a cell whose closure meets the boundary of inclusion k, at level < R_k, is refined;
//   R2  a cell met by the boundaries of two interface groups, at level < Lmax, is refined;
//   R3  2:1 balance across edges (at most one hanging node per edge);
//   R4  buffer: every cell sharing a vertex with a cut cell of level l has level l and no
//       finer edge neighbour (refine the coarser one, or the cut cell).
// Each rule only ever asks for more refinement, so the result is the least fixed point:
// unique, whatever the order in which cells are visited (hence partition-invariant when the
// ghost layer is wide enough).
#include <cstdint>
#include <span>
#include <vector>

#include "core/progress.hpp"
#include "geometry/oracle.hpp"
#include "grid/quad_forest.hpp"
#include "samr/touch_lists.hpp"

namespace cisamr::samr {

// Reach: how far beyond a cell the rules' decisions about it look, in cells of the cell's
// level. R4's buffer refines the cells sharing a vertex with a cut cell and their edge
// neighbours (2 cells); an R3 cascade travels less than one coarse cell. With the levels of
// pipeline::effective_levels2 passed in, no rule carries a level from one inclusion to
// another, so this bounds what a partition's ghost must hold (lib/parallel/ghost.hpp).
inline constexpr int kReachCells2 = 2;
// Where a run over part of the domain (a partition's range, its cells beyond missing) can
// refine differently from the whole-domain run, in coarse cells from the range's edge. With
// those levels no cut cell ends finer than its inclusion's level in either run (R2 and R4's
// "no finer edge neighbour" never fire there), and the range's cut lists are exact, so the
// differences are the cells refined because of cut cells beyond the edge: R4's band around
// them (1 cell of their level L) and R3's cascade from that band (h_{L-1} + … + h_1), in
// all h_L + … + h_1 < 1 coarse cell: inside the first coarse layer of the range. (The
// partition refines a subset of the whole run's cells: missing cells trigger nothing.)
inline constexpr int kReachCoarseCells2 = 1;

// Per cell (TouchLists): inclusions whose boundary meets the closed cell.
struct RefinedGrid2 : TouchLists {
  grid::QuadForest forest;
  CellCandidates root_candidates;  // per root (root_count of them)
  std::int64_t refinements = 0;

  std::span<const std::int32_t> candidates_of_root(std::int32_t root) const { return root_candidates.of(root); }
  // Root cell containing cell c.
  std::int32_t root_of(std::int32_t c) const {
    const auto coarse = forest.coarse_cell(c);
    return forest.root(coarse[0], coarse[1]);
  }
};

// Refines the coarse cells of `range` (the partition box plus its ghost layer).
// `levels[k]` is the level rule R1 asks of inclusion k (the oracle's inclusion index);
// pipeline::effective_levels2 computes them so that rule R4 never has to carry a level
// from one inclusion to another. Empty: the inclusions' own levels. `progress` (may be null)
// is advanced over the roots, then over the cut roots whose refinement is finished.
RefinedGrid2 refine2(const geometry::Oracle2& oracle, const grid::Lattice2& lattice,
                     const grid::CellRange<2>& range, std::span<const int> levels = {},
                     Progress* progress = nullptr);

}  // namespace cisamr::samr
