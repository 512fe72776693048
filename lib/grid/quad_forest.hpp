#pragma once
// A forest of quadtrees over a range of coarse cells: the 2D structured background grid
// and its SAMR refinements. Cells live in one flat array; the four children of a cell
// are consecutive (order: (0,0), (1,0), (0,1), (1,1) in x-then-y). Cell coordinates are
// global integer indices at the cell's own level.
#include <array>
#include <cstdint>
#include <vector>

#include "core/check.hpp"
#include "grid/lattice.hpp"

namespace cisamr::grid {

class QuadForest {
 public:
  struct Cell {
    std::int32_t first_child = -1;  // -1: leaf
    std::int32_t i = 0, j = 0;      // global index at `level`
    std::uint8_t level = 0;
  };

  // Throws MeshingError when the range at max_level does not fit 32-bit indices.
  QuadForest(const Lattice2& lattice, const CellRange<2>& range);

  const Lattice2& lattice() const { return lattice_; }
  const CellRange<2>& range() const { return range_; }
  std::size_t size() const { return cells_.size(); }
  const Cell& cell(std::int32_t c) const {
    CISAMR_DEBUG_CHECK(c >= 0 && static_cast<std::size_t>(c) < cells_.size(), "QuadForest: cell index out of range");
    return cells_[static_cast<std::size_t>(c)];
  }
  bool is_leaf(std::int32_t c) const { return cells_[static_cast<std::size_t>(c)].first_child < 0; }
  // Global index of the coarse cell holding cell c.
  std::array<std::int64_t, 2> coarse_cell(std::int32_t c) const {
    const Cell& x = cell(c);
    return {x.i >> x.level, x.j >> x.level};
  }
  std::int32_t root_count() const { return root_count_; }
  // Where the window holds coarse index c along d: c itself, or on a periodic axis the one
  // image of c in [lo, lo + N).
  std::int64_t window_position(int d, std::int64_t c) const;
  // Root of global coarse cell (ci, cj), or -1 outside the range. On a periodic axis any
  // image of the cell's index finds it.
  // Cell indices are canonical: in [0, N·2^level) per axis; `find` takes any image.
  std::int32_t root(std::int64_t ci, std::int64_t cj) const;

  // The cell on the path to (level, i, j) with the largest level ≤ `level`: either a leaf
  // covering that position (maybe coarser) or the non-leaf cell exactly at `level`.
  // -1 when the position is outside the range.
  std::int32_t find(int level, std::int64_t i, std::int64_t j) const;

  // Splits leaf c into four children; returns the index of the first child.
  std::int32_t refine(std::int32_t c);

  // Box of a cell in world coordinates.
  Box2 box(std::int32_t c) const;
  // Finest-lattice coordinates of the cell's lower-left corner and its size in fine units.
  std::int64_t fine_x(std::int32_t c) const {
    return static_cast<std::int64_t>(cell(c).i) * lattice_.units(cell(c).level);
  }
  std::int64_t fine_y(std::int32_t c) const {
    return static_cast<std::int64_t>(cell(c).j) * lattice_.units(cell(c).level);
  }
  std::int64_t fine_size(std::int32_t c) const { return lattice_.units(cell(c).level); }

 private:
  Lattice2 lattice_;
  CellRange<2> range_;
  std::int32_t root_count_ = 0;
  std::vector<Cell> cells_;
};

}  // namespace cisamr::grid
