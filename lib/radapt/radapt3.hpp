#pragma once
// r-adaptivity in 3D: every node of a cut tet either stays or snaps onto the nearest
// interface crossing along one of its six axis edges (the legs of the corner tets around
// it), when that crossing is closer than alpha·(edge length). Decisions use original
// positions only, so they are independent of visiting order and identical on every
// partition that sees the node (lib/pipeline/README3.md).
#include <array>
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "geometry/oracle3.hpp"
#include "grid/key_map.hpp"
#include "grid/tet_lattice.hpp"
#include "samr/samr3.hpp"

namespace cisamr::radapt {

struct Options3 {
  double alpha = 0.5;  // snap threshold, fraction of the edge length
};

// The nodes of the refined forest: lattice keys, positions after snapping and the phases
// whose closure holds each node (one bit inside a phase, two or more on an interface).
struct Nodes3 {
  std::vector<grid::LatticeKey3> key;
  std::vector<Vec3> position;
  std::vector<PhaseMask> mask;
  std::vector<std::uint8_t> snapped;  // 1 if moved onto an interface
  std::int64_t snapped_count = 0;
  // Node ids of each leaf's vertices (fine_vertices order), indexed by forest tet;
  // unspecified for non-leaves.
  std::vector<std::array<std::int32_t, 4>> tet_nodes;
  grid::KeyMap registry{1024};

  std::int32_t id(grid::LatticeKey3 k) const { return registry.find(k); }
};

// Registers the vertices of every leaf, classifies them and snaps nodes of cut tets.
Nodes3 snap3(const geometry::Oracle3& oracle, const samr::RefinedGrid3& grid, const Options3& options);

}  // namespace cisamr::radapt
