#pragma once
// Subdivision in 2D: every leaf of the refined, snapped grid becomes triangles.
// Squares with hanging nodes use the closure table; cut quads are split along the
// diagonal that approximates the interface, or around a point of the interface on the
// other diagonal (double diagonal), whichever gives the lower worst aspect ratio; uncut,
// deformed quads are split along their better diagonal (lib/subdivide/README.md).
#include <cstdint>
#include <vector>

#include "core/progress.hpp"
#include "geometry/oracle.hpp"
#include "grid/lattice.hpp"
#include "radapt/radapt2.hpp"
#include "samr/samr2.hpp"

namespace cisamr::subdivide {

// Reach, in cells of the cell's level: a cell reads its corners' final positions and masks
// and the crossings on its own edges, so no more than r-adaptivity's.
inline constexpr int kReachCells2 = radapt::kReachCells2;

struct Triangles2 {
  std::vector<Vec2> extra_points;  // points created here; node id = nodes.size() + index
  // Periodic scenes: per extra point its lattice key when it is the image across the period
  // of a lattice node (a node of the max face, key with X = P), else kNoKey. Empty when
  // no point is such an image.
  std::vector<std::uint64_t> extra_identity;
  static constexpr std::uint64_t kNoKey = ~std::uint64_t{0};
  std::vector<std::int32_t> triangles;  // 3 node ids per triangle, counter-clockwise
  std::vector<std::uint8_t> phase;      // phase index per triangle (at most 64 phases: PhaseMask)
  std::int64_t cut_quads = 0, double_diagonal = 0, hanging_cells = 0;
  std::int64_t unresolved = 0;          // quads no template could split phase-consistently
  std::vector<Vec2> unresolved_at;      // centres of the first few unresolved quads
  // Features below the resolution of their cell, collapsed (see README.md).
  std::int64_t collapsed = 0;
  double max_collapse_deviation = 0;    // largest distance of a node from a phase it serves
  double max_collapse_ratio = 0;        // the same, relative to the collapsed cell's size
  int min_collapse_level = 1 << 20;     // coarsest level at which a collapse happened
  std::vector<Vec2> collapsed_at;
};

// Triangulates the leaves whose coarse ancestor lies in `owned` (the partition box).
// `progress` (may be null) is advanced over the forest's cells. A quad whose best split
// exceeds `bound` (DESIGN.md §2.2: 3 in 2D) is collapsed when that brings it within.
Triangles2 subdivide2(const geometry::Oracle2& oracle, const samr::RefinedGrid2& grid,
                      const radapt::Nodes2& nodes, const grid::CellRange<2>& owned,
                      double collapse_fraction = 0.5, Progress* progress = nullptr, double bound = 3.0);

}  // namespace cisamr::subdivide
