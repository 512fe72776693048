#pragma once
// The ghost region of a partition box: which inclusions and which coarse cells a partition
// must see so that every decision inside its box equals the whole-domain run's
// (DESIGN.md §8). See README.md for the derivation of the margins.
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"
#include "grid/lattice.hpp"
#include "pipeline/pipeline.hpp"

namespace cisamr::parallel {

struct GhostRule {
  // Margin around every inclusion's bounding box. Level-aware (default): 4·h_R, h_R = h/2^R,
  // R the inclusion's SAMR levels; two inclusions whose inflated boxes do not meet cannot
  // change each other's refinement. Fixed: `fixed_cells`·h for every inclusion.
  bool level_aware = true;
  double fixed_cells = 3;
  // Coarse cells around the box itself: its cells look one cell (r-adaptivity, hanging
  // nodes) or two cells (rule R4 at level 0) beyond it, and a 2:1 cascade reaches < h.
  double box_margin_cells = 4;
  // Rounds of the closure "add every inclusion whose inflated box meets an added one's".
  // 0 (default): none. pipeline::effective_levels2 settles every level that rule R4 could
  // carry from one inclusion to another before meshing, so what decides a cell lies within
  // a few coarse cells of it (README.md, "Ghost region"). -1: the full closure, for
  // comparison.
  int max_closure_rounds = 0;
};

// The full scene's lattice (every inclusion's levels count for Lmax), built from the
// description alone, without geometry.
grid::Lattice2 scene_lattice2(const geometry::SceneDesc& scene, const pipeline::Options& options);

// Inflated bounding boxes of all inclusions of a scene in a uniform bucket grid.
class InclusionIndex2 {
 public:
  InclusionIndex2(const geometry::SceneDesc& scene, const grid::Lattice2& lattice, const GhostRule& rule);
  std::int32_t size() const { return static_cast<std::int32_t>(inflated_.size()); }
  const Box2& inflated(std::int32_t k) const { return inflated_[static_cast<std::size_t>(k)]; }
  // Inclusions whose inflated box meets the closed `box`, ascending, appended to `out`.
  void query(const Box2& box, std::vector<std::int32_t>& out) const;

 private:
  std::array<std::int64_t, 2> bucket_of(const Vec2& p) const;
  std::vector<Box2> inflated_;
  Vec2 origin_{};
  double side_ = 1;
  std::array<std::int64_t, 2> buckets_{1, 1};
  std::vector<std::int32_t> begin_, members_;  // CSR: bucket -> inclusions
};

struct GhostRegion2 {
  grid::CellRange<2> box;    // the partition's coarse cells
  grid::CellRange<2> range;  // coarse cells whose state decides the box (clipped to the domain)
  int ghost = 0;             // uniform width that covers `range` (what pipeline::run2 takes)
  std::vector<std::int32_t> inclusions;  // scene indices, ascending
};

// The closure: start from the inclusions whose inflated box meets the box grown by
// rule.box_margin_cells; add every inclusion whose inflated box meets an added one's,
// until nothing changes. The range covers the grown box and every added inflated box.
GhostRegion2 ghost_region2(const InclusionIndex2& index, const grid::Lattice2& lattice,
                           const grid::CellRange<2>& box, const GhostRule& rule);

// The scene restricted to `inclusions` (ascending scene indices), original order kept:
// the oracle's ties go to the lowest index, so relative order must not change.
geometry::SceneDesc subset_scene(const geometry::SceneDesc& scene, const std::vector<std::int32_t>& inclusions);

}  // namespace cisamr::parallel
