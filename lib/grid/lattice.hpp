#pragma once
// The global integer lattice (DESIGN.md §4). Every background and SAMR node has integer
// coordinates on the finest lattice of the whole domain, (2^Lmax / h)·(x − x_min); its key
// is those integers. Positions are computed from keys by one formula, so every partition
// gets bit-identical coordinates for the same node.
#include <cmath>
#include <cstdint>

#include "core/types.hpp"

namespace cisamr::grid {

using LatticeKey = std::uint64_t;  // 2D: (X << 32) | Y

// A half-open range of coarse cells [lo, hi) per axis, in global coarse indices.
template <int Dim>
struct CellRange {
  std::array<std::int64_t, Dim> lo{}, hi{};
  std::int64_t count(int d) const { return hi[d] - lo[d]; }
  bool contains(const std::array<std::int64_t, Dim>& c) const {
    for (int d = 0; d < Dim; ++d)
      if (c[d] < lo[d] || c[d] >= hi[d]) return false;
    return true;
  }
};

template <int Dim>
struct Lattice {
  Vec<Dim> origin{};   // domain min
  double h = 1;        // coarse cell size
  int max_level = 0;   // Lmax: finest level anywhere in the domain
  std::array<std::int64_t, Dim> coarse_cells{};  // whole domain, per axis

  // h·2^-level, exactly (a power-of-two scaling), without a libm call in hot loops.
  double spacing(int level) const { return h / static_cast<double>(std::int64_t{1} << level); }
  double fine_spacing() const { return spacing(max_level); }
  // Finest-lattice units per cell of `level`.
  std::int64_t units(int level) const { return std::int64_t{1} << (max_level - level); }
  double coordinate(int d, std::int64_t fine_index) const {
    return origin[d] + static_cast<double>(fine_index) * fine_spacing();
  }
  CellRange<Dim> whole_domain() const {
    CellRange<Dim> r;
    for (int d = 0; d < Dim; ++d) r.hi[d] = coarse_cells[d];
    return r;
  }
};

using Lattice2 = Lattice<2>;

inline LatticeKey key2(std::int64_t x, std::int64_t y) {
  return (static_cast<LatticeKey>(x) << 32) | static_cast<LatticeKey>(y);
}
inline std::int64_t key2_x(LatticeKey k) { return static_cast<std::int64_t>(k >> 32); }
inline std::int64_t key2_y(LatticeKey k) { return static_cast<std::int64_t>(k & 0xffffffffu); }

}  // namespace cisamr::grid
