#pragma once
// SAMR in 3D: refine the tet forest (nested honeycomb, grid/README.md 3D part) near
// interfaces until the rules hold (lib/pipeline/README.md):
//   R1  a tet whose closed bounding box meets the boundary of inclusion k, at level < R_k,
//       is refined;
//   R2  a tet met by the boundaries of two interface groups, at level < Lmax, is refined;
//   B   balance (face rule of the closure tables): a leaf whose closure holds a node
//       other than its vertices and edge midpoints is refined (this implies 2:1 edge
//       balance and keeps finer nodes out of coarse faces);
//   R4  buffer: a leaf with a vertex on a cut leaf carries no hanging midpoint (refined
//       otherwise). So cut leaves and every leaf around a node that may move are closed by
//       nothing, and all leaves around such a node have one level.
// The rules are applied in synchronous sweeps until none fires: a sweep marks every leaf a
// rule fires on, judged on the forest as the previous sweep left it, then refines the
// marked leaves, so the result depends only on the scene, the lattice and the range, never
// on a visiting order. A sweep looks only at the leaves whose rules may have changed (the
// children of the last refinements and the leaves around their new nodes), which gives
// the same marks as looking at every leaf (lib/samr/README.md, 3D).
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/progress.hpp"
#include "geometry/oracle.hpp"
#include "grid/tet_forest.hpp"
#include "samr/touch_lists.hpp"

namespace cisamr::samr {

// Reach, in coarse cells: how far a difference in the refinement (one an inclusion outside
// a region starts, or, missing there, does not start) can travel into the region. Rule B
// moves it by one leaf one level coarser per step, R4 only along the one-cell band around
// cut leaves of one level (the effective levels keep it from reaching another interface's
// band). From level-L cut leaves beyond the region's face the band and the B steps down to
// level 1 reach h_{L-1} + ... + h_1 < 1 cube deep, so the last step refines a level-0 tet
// of a cube of the region's first layer (cubes are aligned with the face), which ends 1
// cube deep; the level-1 midpoints it leaves on that layer's far face trigger no rule in
// the second layer (B needs a node two levels finer, R4 a cut leaf whose level the
// effective levels would have raised). So differences stay within the first cube, whatever
// the number of sweeps (lib/parallel/README.md, "Ghost region (3D)").
inline constexpr int kReachCoarseCells3 = 1;
// The reach for a forest no finer than `max_level` (its lattice's Lmax): 0 at Lmax = 0
// (nothing refines), kReachCoarseCells3 otherwise.
constexpr double reach_coarse_cells3(int max_level) { return max_level > 0 ? kReachCoarseCells3 : 0; }

// Per tet (TouchLists): inclusions whose boundary meets the tet's closed bounding box.
// Conservative: a tet with an empty list lies inside one phase.
struct RefinedGrid3 : TouchLists {
  grid::TetForest forest;
  CellCandidates cube_candidates;  // per coarse cube of the range (cube_index)
  std::int64_t refinements = 0;
  int sweeps = 0;  // synchronous sweeps, the last one marking nothing

  // Index of the coarse cube (global coarse indices, any image on a periodic axis) in the
  // range, or -1 outside.
  std::int64_t cube_index(std::int64_t ci, std::int64_t cj, std::int64_t ck) const {
    const auto& r = forest.range();
    ci = forest.window_position(0, ci), cj = forest.window_position(1, cj), ck = forest.window_position(2, ck);
    if (ci < r.lo[0] || ci >= r.hi[0] || cj < r.lo[1] || cj >= r.hi[1] || ck < r.lo[2] || ck >= r.hi[2]) return -1;
    return ((ck - r.lo[2]) * r.count(1) + (cj - r.lo[1])) * r.count(0) + (ci - r.lo[0]);
  }
  // Coarse cube holding tet t.
  std::int64_t cube_of(std::int32_t t) const {
    const auto coarse = forest.coarse_cell(t);
    return cube_index(coarse[0], coarse[1], coarse[2]);
  }
  std::span<const std::int32_t> candidates_of_cube(std::int64_t cube) const { return cube_candidates.of(cube); }
  std::span<const std::int32_t> candidates_of_tet(std::int32_t t) const { return candidates_of_cube(cube_of(t)); }

  // Closed axis-aligned bounding box of tet t, world coordinates.
  Box3 box(std::int32_t t) const;
};

// Refines the coarse cubes of `range` (a partition box plus its ghost layer). Throws
// MeshingError when the rules ask for a level beyond lattice.max_level. `levels[k]` is the
// level rule R1 asks of inclusion k (the oracle's index), as pipeline::effective_levels
// computes them for partitions; empty: the inclusions' own levels. `progress` (may be null)
// is advanced over the roots, then by the finest level the sweeps have refined to and
// within each sweep.
RefinedGrid3 refine3(const geometry::Oracle3& oracle, const grid::Lattice3& lattice,
                     const grid::CellRange<3>& range, std::span<const int> levels = {},
                     Progress* progress = nullptr);

// A coarse cube's refinement as another forest holds it: TetForest::append_refinement of its
// five roots in order (global coarse indices).
struct CubeRefinement {
  std::array<std::int64_t, 3> cube{};
  std::vector<std::uint8_t> bits;
};

// Gives the cubes of `taken` (in g's range) the refinement listed there: the parallel
// mesher's partitions take the forest near their boxes from the partitions that own it
// (lib/parallel/README.md, "Decisions exchanged near faces"). The cubes whose trees differ
// from g's own are pruned to their roots in place (every other tet keeps its order and cut
// list) and grown again from the bits, a new tet's list its parent's filtered as the sweeps
// filter it, so g must still hold its lists (before release_lists). Returns the cubes that
// differed.
std::int64_t take_cube_refinements(const geometry::Oracle3& oracle, RefinedGrid3& g,
                                   std::span<const CubeRefinement> taken);

}  // namespace cisamr::samr
