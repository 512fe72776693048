#pragma once
// r-adaptivity in 2D: every node of a cut cell either stays or snaps onto the nearest
// interface crossing along one of its four axis edges, when that crossing is closer than
// alpha·(edge length). Decisions use original positions only, so they are independent of
// visiting order and identical on every partition that sees the node (lib/radapt/README.md).
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "geometry/oracle2.hpp"
#include "grid/key_map.hpp"
#include "grid/lattice.hpp"
#include "samr/samr2.hpp"

namespace cisamr::radapt {

struct Options {
  double alpha = 0.5;  // snap threshold, fraction of the edge length
};

// The nodes of the refined grid: lattice keys, positions after snapping and the phases
// whose closure holds each node (one bit inside a phase, two or more on an interface).
struct Nodes2 {
  std::vector<grid::LatticeKey> key;
  std::vector<Vec2> position;
  std::vector<PhaseMask> mask;
  std::vector<std::uint8_t> snapped;  // 1 if moved onto an interface
  grid::KeyMap index{1024};           // key -> node id
  std::int64_t snapped_count = 0;

  std::int32_t id(grid::LatticeKey k) const { return index.find(k); }
};

// Registers the corners of every leaf, classifies them and snaps nodes of cut cells.
Nodes2 snap2(const geometry::Oracle2& oracle, const samr::RefinedGrid2& grid, const Options& options);

}  // namespace cisamr::radapt
