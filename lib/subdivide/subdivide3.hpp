#pragma once
// Subdivision in 3D: every leaf of the refined, snapped tet forest becomes tetrahedra
// (lib/pipeline/README.md):
//   - a leaf with hanging edge midpoints (never cut, never deformed: rule R4) is closed
//     by the optimal case tables of templates3.hpp;
//   - a leaf whose vertices share a phase is kept;
//   - a cut leaf (two vertices strictly in different phases) is split along the
//     interface by grid/cut_stencil3.hpp, with the cut points radapt computed (keyed by
//     the edge's two lattice keys, on the segment oriented from the smaller key), exactly
//     as the snapping guard evaluated it; face quads split by the key rule, so neighbours
//     agree without communication.
#include <array>
#include <cstdint>
#include <vector>

#include "core/progress.hpp"
#include "faceswap/faceswap3.hpp"
#include "geometry/oracle.hpp"
#include "grid/lattice.hpp"
#include "radapt/radapt3.hpp"
#include "samr/samr3.hpp"

namespace cisamr::subdivide {

// Reach, in cells of the leaf's level: a leaf reads its vertices' final positions and
// masks, cut points keyed by edges and computed from their ends' final positions, and its
// own closure, so no more than r-adaptivity's (swapped cubes bring faceswap's reach).
inline constexpr int kReachCells3 = radapt::kReachCells3;

struct Tets3 {
  std::vector<Vec3> extra_points;       // points created here; node id = nodes.size() + index
  // Per extra point, the identity every partition computes alike: a cut node is its edge's
  // (smaller key, larger key); a closure Steiner point, interior to one leaf, is
  // (kInteriorPoint, kInteriorPoint) and never shared.
  std::vector<std::array<grid::LatticeKey3, 2>> extra_identity;
  static constexpr grid::LatticeKey3 kInteriorPoint = ~grid::LatticeKey3{0};
  std::vector<std::int32_t> tets;       // 4 node ids per tet, positively oriented
  std::vector<std::uint8_t> phase;      // phase index per tet (at most 64 phases: PhaseMask)
  std::int64_t cut_tets = 0;            // leaves split along an interface
  std::int64_t cut_nodes = 0;           // nodes created on cut edges
  std::int64_t closed_tets = 0;         // leaves closed by the hanging-midpoint tables
  std::int64_t steiner_points = 0;      // interior points of those closures
  std::int64_t unresolved = 0;          // cut leaves with more than two phases (kept whole)
  std::int64_t inverted = 0;            // output tets with non-positive volume
  // Worst aspect ratio of the output tets by origin: closures of hanging midpoints, leaves
  // kept whole (maybe deformed by snapping), sub-tets of cut leaves, tets of swapped cubes.
  double worst_closure = 0, worst_kept = 0, worst_split = 0, worst_swapped = 0;
  std::int64_t kept_above_5 = 0, split_above_5 = 0;
};

// Tetrahedralises the leaves whose coarse cube lies in `owned` (the partition box); cubes
// that `swaps` re-tetrahedralised give their new tets instead of their leaves. `progress`
// (may be null) is advanced over the forest's tets.
Tets3 subdivide3(const geometry::Oracle3& oracle, const samr::RefinedGrid3& grid, const radapt::Nodes3& nodes,
                 const grid::CellRange<3>& owned, const faceswap::Swaps3* swaps = nullptr,
                 Progress* progress = nullptr);

}  // namespace cisamr::subdivide
