#pragma once
// Face swapping in 3D (the algorithm note §5). After snapping, a corner tet whose aspect
// ratio exceeds `trigger` (itself, or one of its sub-tets if the interface cuts it) is
// usually one of a sliver/cap pair: the corner tets of one apex p in two neighbouring cubes
// A and B of one level. Swapping the diagonal of their shared cube face F (even–even → the
// odd–odd diagonal p–q) and re-tetrahedralising, in each cube, the octahedron
// C_p ∪ R ∪ C_q (3 tets → 4 around a body diagonal) repairs the pair without touching any
// other face. The new tets are then split along the interface like any leaf (cut points on
// the new edges p–q and the body diagonal come from the oracle, on the segment oriented
// from the smaller key, so both cubes and both partitions get the same point)
// (lib/faceswap/README.md).
//
// Applied only where the six tets are leaves of one level without hanging midpoints, and
// only when the pair's worst aspect ratio (over everything the six leaves would emit)
// decreases: swapping improves quality and never breaks the bound the snapping guard
// certified. A cube takes part in at most one swap; competing swaps are settled by a fixed
// priority (worst tets first, then the better result, then the apex key and axis), each
// swap applied iff it beats every swap it competes with, so the outcome is order-free and
// the same on every partition whose windows (Options3::window, and r-adaptivity's) hold the two
// cubes and their neighbours.
#include <array>
#include <cstdint>
#include <vector>

#include "core/progress.hpp"
#include "geometry/oracle.hpp"
#include "grid/tet_forest.hpp"
#include "grid/tet_lattice.hpp"
#include "radapt/radapt3.hpp"
#include "samr/samr3.hpp"

namespace cisamr::faceswap {

// Reach, in cells of the level of the swapped cubes: a swap of cubes (C, D) must beat every
// candidate sharing C or D; a competitor (D, Y) has Y up to 2 cells from C, and its value
// reads the final positions and masks of Y's corners, each radapt::kReachCells3 deep.
inline constexpr int kCompetitorCells3 = 2;
inline constexpr int kReachCells3 = kCompetitorCells3 + radapt::kReachCells3;

struct Options3 {
  double trigger = 3.0;  // corner tets above this aspect ratio look for a swap (0: no swapping)
  // The corner tets that look for a swap (a partition's: those within reach of its box);
  // a candidate whose cubes r-adaptivity did not register (outside its window) is dropped.
  grid::LeafWindow window{};
  Progress* progress = nullptr;  // advanced over the forest's tets (may be null)
};

struct Swaps3 {
  struct NewTet {
    std::array<std::int32_t, 4> node{};            // node ids, positively oriented
    std::array<grid::LatticePoint3, 4> lattice{};  // their lattice points (orientation reference)
  };
  struct Block {
    std::int32_t emitter = -1;  // the cube's regular tet: the new tets are emitted in its place
    std::array<NewTet, 4> tets{};
  };
  // Per forest tet: the index into `blocks` of the swapped cube it belongs to (the tet is
  // replaced), or -1.
  std::vector<std::int32_t> block_of;
  std::vector<Block> blocks;
  // Cut points on the new edges (the swapped face diagonals and the body diagonals).
  std::vector<radapt::EdgeCut> new_cuts;
  radapt::EdgeIndex new_cut_index;
  std::int64_t swaps = 0;       // pairs of cubes whose shared face was swapped
  std::int64_t candidates = 0;  // pairs that would have improved (before conflicts)

  std::int32_t new_cut(grid::LatticeKey3 a, grid::LatticeKey3 b) const {
    const auto it = new_cut_index.find(a < b ? std::pair{a, b} : std::pair{b, a});
    return it == new_cut_index.end() ? -1 : it->second;
  }
};

Swaps3 swap3(const geometry::Oracle3& oracle, const samr::RefinedGrid3& grid, const radapt::Nodes3& nodes,
             const Options3& options = {});

}  // namespace cisamr::faceswap
