#include "grid/quad_forest.hpp"

#include <string>

#include "core/error.hpp"

namespace cisamr::grid {

QuadForest::QuadForest(const Lattice2& lattice, const CellRange<2>& range)
    : lattice_(lattice), range_(range) {
  for (int d = 0; d < 2; ++d) {
    // A window along a periodic axis may reach past either face (it wraps); once it spans
    // the period it is the whole circle.
    if (lattice.periodic[d] && range.count(d) >= lattice.coarse_cells[d]) range_.lo[d] = 0, range_.hi[d] = lattice.coarse_cells[d];
    if (!lattice.periodic[d] && (range.hi[d] > lattice.coarse_cells[d] || range.lo[d] < 0))
      throw MeshingError("cell range outside the domain lattice");
    if (range.hi[d] <= range.lo[d]) throw MeshingError("empty cell range");
    // Fine-lattice coordinates are packed into 32 bits per axis.
    const double fine = static_cast<double>(lattice.coarse_cells[d]) * std::ldexp(1.0, lattice.max_level);
    if (fine >= 2147483647.0)
      throw MeshingError("domain too large for the lattice: " + std::to_string(lattice.coarse_cells[d]) +
                         " cells × 2^" + std::to_string(lattice.max_level) +
                         " levels exceeds 2^31 fine units per axis; use a larger h or fewer levels");
  }
  const std::int64_t n = range_.count(0) * range_.count(1);
  root_count_ = static_cast<std::int32_t>(n);
  cells_.resize(static_cast<std::size_t>(n));
  // Roots in window order; each holds its canonical index.
  for (std::int64_t cj = range_.lo[1]; cj < range_.hi[1]; ++cj)
    for (std::int64_t ci = range_.lo[0]; ci < range_.hi[0]; ++ci) {
      Cell& c = cells_[static_cast<std::size_t>((cj - range_.lo[1]) * range_.count(0) + (ci - range_.lo[0]))];
      c.i = static_cast<std::int32_t>(lattice_.canonical_cell(0, 0, ci));
      c.j = static_cast<std::int32_t>(lattice_.canonical_cell(1, 0, cj));
    }
}

std::int64_t QuadForest::window_position(int d, std::int64_t c) const {
  if (!lattice_.periodic[d]) return c;
  return range_.lo[d] + wrap(c - range_.lo[d], lattice_.coarse_cells[d]);
}

std::int32_t QuadForest::root(std::int64_t ci, std::int64_t cj) const {
  ci = window_position(0, ci);
  cj = window_position(1, cj);
  if (ci < range_.lo[0] || ci >= range_.hi[0] || cj < range_.lo[1] || cj >= range_.hi[1]) return -1;
  return static_cast<std::int32_t>((cj - range_.lo[1]) * range_.count(0) + (ci - range_.lo[0]));
}

std::int32_t QuadForest::find(int level, std::int64_t i, std::int64_t j) const {
  i = lattice_.canonical_cell(0, level, i);
  j = lattice_.canonical_cell(1, level, j);
  if (i < 0 || j < 0) return -1;
  std::int32_t c = root(i >> level, j >> level);
  if (c < 0) return -1;
  for (int l = 1; l <= level; ++l) {
    const Cell& cc = cells_[static_cast<std::size_t>(c)];
    if (cc.first_child < 0) return c;
    const int shift = level - l;
    const int child = static_cast<int>((i >> shift) & 1) + 2 * static_cast<int>((j >> shift) & 1);
    c = cc.first_child + child;
  }
  return c;
}

std::int32_t QuadForest::refine(std::int32_t c) {
  const std::int32_t first = static_cast<std::int32_t>(cells_.size());
  const Cell parent = cells_[static_cast<std::size_t>(c)];
  if (parent.level >= lattice_.max_level) throw MeshingError("refinement beyond the finest level");
  cells_[static_cast<std::size_t>(c)].first_child = first;
  for (int k = 0; k < 4; ++k) {
    Cell child;
    child.level = static_cast<std::uint8_t>(parent.level + 1);
    child.i = 2 * parent.i + (k & 1);
    child.j = 2 * parent.j + (k >> 1);
    cells_.push_back(child);
  }
  return first;
}

Box2 QuadForest::box(std::int32_t c) const {
  const std::int64_t x = fine_x(c), y = fine_y(c), s = fine_size(c);
  return Box2{{lattice_.coordinate(0, x), lattice_.coordinate(1, y)},
              {lattice_.coordinate(0, x + s), lattice_.coordinate(1, y + s)}};
}

}  // namespace cisamr::grid
