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

// x modulo n in [0, n) for n > 0, any sign of x. Periodic look-ups call it in the hot loops
// (every forest find, node id): values within one period of the range take no division.
inline std::int64_t wrap(std::int64_t x, std::int64_t n) {
  if (x >= 0) {
    if (x < n) [[likely]] return x;
    if (x < 2 * n) return x - n;
  } else if (x >= -n) {
    return x + n;
  }
  x %= n;
  return x < 0 ? x + n : x;
}

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
  // Whether the two ranges share a cell.
  bool meets(const CellRange& o) const {
    for (int d = 0; d < Dim; ++d)
      if (o.hi[d] <= lo[d] || hi[d] <= o.lo[d]) return false;
    return true;
  }
};

template <int Dim>
struct Lattice {
  Vec<Dim> origin{};   // domain min
  double h = 1;        // coarse cell size
  int max_level = 0;   // Lmax: finest level anywhere in the domain
  std::array<std::int64_t, Dim> coarse_cells{};  // whole domain, per axis
  // Periodic axes (docs/periodic-design.md): the lattice is a torus along them. A lattice
  // point exists once, under its canonical coordinate in [0, P) (P = fine_period(d)); a cell
  // sees a neighbour across the period at canonical + P, and its position at + period(d).
  std::array<bool, Dim> periodic{};

  bool any_periodic() const {
    for (int d = 0; d < Dim; ++d)
      if (periodic[d]) return true;
    return false;
  }
  // Fine-lattice units of the whole domain along d (the period on a periodic axis).
  std::int64_t fine_period(int d) const { return coarse_cells[d] * units(0); }
  // The period in world units: exactly coordinate(d, P) − origin's N·h, the one number added
  // to a min-face coordinate to give the max face's.
  double period(int d) const { return static_cast<double>(coarse_cells[d]) * h; }
  // A fine coordinate reduced into [0, P) on a periodic axis; unchanged on the others.
  std::int64_t canonical(int d, std::int64_t x) const {
    return periodic[d] ? wrap(x, fine_period(d)) : x;
  }
  // Which image of its canonical point a frame point ∈ [0, P] per axis is: bit d set where
  // the point is at P on a periodic axis (the canonical 0 seen from the cell before it).
  std::uint8_t image_shift(const std::array<std::int64_t, Dim>& frame) const {
    std::uint8_t shift = 0;
    for (int d = 0; d < Dim; ++d)
      if (periodic[d] && frame[d] == fine_period(d)) shift |= static_cast<std::uint8_t>(1u << d);
    return shift;
  }
  // A canonical position seen as image `shift`: + the period on each axis of the shift (the
  // one formula, so a min-face coordinate becomes exactly the max face's).
  Vec<Dim> shifted(Vec<Dim> p, std::uint8_t shift) const {
    for (int d = 0; d < Dim; ++d)
      if (shift & (1u << d)) p[d] += period(d);
    return p;
  }
  // A fine point reduced into [0, P) on the periodic axes: the one point a key names.
  std::array<std::int64_t, Dim> canonical_point(std::array<std::int64_t, Dim> p) const {
    for (int d = 0; d < Dim; ++d) p[d] = canonical(d, p[d]);
    return p;
  }
  // A point moved by the period on the axes of `shift` (an image's unwrapped point).
  std::array<std::int64_t, Dim> shifted_point(std::array<std::int64_t, Dim> p, std::uint8_t shift) const {
    for (int d = 0; d < Dim; ++d)
      if (shift & (1u << d)) p[d] += fine_period(d);
    return p;
  }
  // A frame point moved back by the period on the axes of `shift`.
  std::array<std::int64_t, Dim> unshifted(std::array<std::int64_t, Dim> p, std::uint8_t shift) const {
    for (int d = 0; d < Dim; ++d)
      if (shift & (1u << d)) p[d] -= fine_period(d);
    return p;
  }
  // A cell index at `level` reduced into [0, N·2^level) on a periodic axis.
  std::int64_t canonical_cell(int d, int level, std::int64_t i) const {
    return periodic[d] ? wrap(i, coarse_cells[d] << level) : i;
  }

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
