#pragma once
// r-adaptivity in 2D: every node of a cut cell either stays or snaps onto the nearest
// interface crossing along one of its four axis edges, when that crossing is closer than
// alpha·(edge length). Decisions use original positions only, so they are independent of
// visiting order and identical on every partition that sees the node (lib/radapt/README.md).
#include <array>
#include <cstdint>
#include <vector>

#include "core/progress.hpp"
#include "core/types.hpp"
#include "geometry/oracle.hpp"
#include "grid/key_map.hpp"
#include "grid/lattice.hpp"
#include "samr/samr2.hpp"

namespace cisamr::radapt {

// Reach, in cells of the level of the cells around a node: a node's decision reads the
// crossings on its four axis edges, i.e. the cells around it (1 cell).
inline constexpr int kReachCells2 = 1;

struct Options {
  double alpha = 0.5;  // snap threshold, fraction of the edge length
  Progress* progress = nullptr;  // advanced over the forest's cells, twice (may be null)
};

// The nodes of the refined grid: lattice keys, positions after snapping and the phases
// whose closure holds each node (one bit inside a phase, two or more on an interface).
struct Nodes2 {
  std::vector<grid::LatticeKey> key;
  std::vector<Vec2> position;
  std::vector<PhaseMask> mask;
  std::vector<std::uint8_t> snapped;  // 1 if moved onto an interface
  std::int64_t snapped_count = 0;
  // Node ids of each leaf's corners (counter-clockwise from the lower left), indexed by
  // forest cell; saves the hash lookups of later phases.
  std::vector<std::array<std::int32_t, 4>> cell_corners;

  // Node registry: nodes on the coarse lattice by direct index, the others (created by
  // SAMR) in a hash index over `key`.
  // Keys are canonical (lattice.hpp): on a periodic axis a point and its images across the
  // period are one node, registered at its coordinate in [0, P).
  struct Registry {
    std::int64_t x0 = 0, y0 = 0, nx = 0, ny = 0, unit = 1;  // coarse node range, fine units per cell
    std::int64_t period_x = 0, period_y = 0;                 // coarse cells per period (0: not periodic)
    std::vector<std::int32_t> coarse;                        // (nx+1)·(ny+1), -1 = none
    grid::LatticeKeyIndex fine{1024};

    // The window offset of canonical coarse node c along an axis starting at c0.
    static std::int64_t offset(std::int64_t c, std::int64_t c0, std::int64_t period) {
      return period == 0 ? c - c0 : grid::wrap(c - c0, period);
    }
    std::int32_t* coarse_slot(std::int64_t x, std::int64_t y) {
      return const_cast<std::int32_t*>(static_cast<const Registry*>(this)->coarse_slot(x, y));
    }
    const std::int32_t* coarse_slot(std::int64_t x, std::int64_t y) const {
      if (x % unit || y % unit) return nullptr;
      const std::int64_t i = offset(x / unit, x0, period_x), j = offset(y / unit, y0, period_y);
      if (i < 0 || j < 0 || i > nx || j > ny) return nullptr;
      return &coarse[static_cast<std::size_t>(j * (nx + 1) + i)];
    }
  } registry;

  // Id of the node at lattice point (x, y), any image of it on a periodic axis; -1 if none.
  std::int32_t id(std::int64_t x, std::int64_t y) const {
    x = lattice.canonical(0, x), y = lattice.canonical(1, y);
    if (const std::int32_t* slot = registry.coarse_slot(x, y)) return *slot;
    return registry.fine.find(grid::key2(x, y), key);
  }
  std::int32_t id(grid::LatticeKey k) const { return id(grid::key2_x(k), grid::key2_y(k)); }
  grid::Lattice2 lattice;  // the forest's: which axes wrap
};

// Registers the corners of every leaf, classifies them and snaps nodes of cut cells.
Nodes2 snap2(const geometry::Oracle2& oracle, const samr::RefinedGrid2& grid, const Options& options);

}  // namespace cisamr::radapt
