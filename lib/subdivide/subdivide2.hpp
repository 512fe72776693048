#pragma once
// Subdivision in 2D: every leaf of the refined, snapped grid becomes triangles.
// Squares with hanging nodes use the closure table; cut quads are split along the
// diagonal that approximates the interface, or around a point of the interface on the
// other diagonal (double diagonal), whichever gives the lower worst aspect ratio; uncut,
// deformed quads are split along their better diagonal (lib/subdivide/README.md).
#include <cstdint>
#include <vector>

#include "geometry/oracle2.hpp"
#include "grid/lattice.hpp"
#include "radapt/radapt2.hpp"
#include "samr/samr2.hpp"

namespace cisamr::subdivide {

struct Triangles2 {
  std::vector<Vec2> extra_points;  // points created here; node id = nodes.size() + index
  std::vector<std::int32_t> triangles;  // 3 node ids per triangle, counter-clockwise
  std::vector<std::int32_t> phase;      // phase index per triangle
  std::int64_t cut_quads = 0, double_diagonal = 0, hanging_cells = 0;
  std::int64_t unresolved = 0;          // quads no template could split phase-consistently
};

// Triangulates the leaves whose coarse ancestor lies in `owned` (the partition box).
Triangles2 subdivide2(const geometry::Oracle2& oracle, const samr::RefinedGrid2& grid,
                      const radapt::Nodes2& nodes, const grid::CellRange<2>& owned);

}  // namespace cisamr::subdivide
