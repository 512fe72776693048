#pragma once
// The ghost region of a partition box: which inclusions and which coarse cells a partition
// must see so that every decision inside its box equals the whole-domain run's
// (DESIGN.md §8). One template for 2D and 3D; see README.md for the derivation of the
// margins.
#include <cstdint>
#include <span>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"
#include "grid/lattice.hpp"
#include "pipeline/effective_levels.hpp"
#include "pipeline/pipeline.hpp"

namespace cisamr::parallel {

// Coarse cells around a partition box that its kernel also meshes, by default. 2D: its
// cells look one cell (r-adaptivity, hanging nodes) or two cells (rule R4 at level 0)
// beyond it, and a 2:1 cascade reaches < h: the tests pass with 2, fail with 0. 3D: the
// same tests pass from 1 cell on, fail with 0; the face swap (decisions on the 12 nodes of
// two neighbouring cubes) and the snapping guard (a node's neighbours' moves) being added
// to the 3D kernel reach 2 cells. 4 is twice what any of them needs.
inline constexpr double kDefaultGhostCells = 4;

struct GhostRule {
  // Margin around every inclusion's bounding box. Level-aware (default): 4·h_R, h_R = h/2^R,
  // R the inclusion's SAMR levels; two inclusions whose inflated boxes do not meet cannot
  // change each other's refinement. Fixed: `fixed_cells`·h for every inclusion.
  bool level_aware = true;
  double fixed_cells = 3;
  // Coarse cells around the box itself (kDefaultGhostCells).
  double box_margin_cells = kDefaultGhostCells;
  // Rounds of the closure "add every inclusion whose inflated box meets an added one's".
  // 0 (default): none. pipeline::effective_levels2/3 settle every level that rule R4 could
  // carry from one inclusion to another before meshing, so what decides a cell lies within
  // a few coarse cells of it (README.md, "Ghost region"). -1: the full closure, for
  // comparison.
  int max_closure_rounds = 0;
};

// The full scene's lattice (every inclusion's levels count for Lmax), built from the
// description alone, without geometry.
template <int Dim>
grid::Lattice<Dim> scene_lattice(const geometry::SceneDesc& scene, const pipeline::Options& options);
inline grid::Lattice2 scene_lattice2(const geometry::SceneDesc& scene, const pipeline::Options& options) {
  return scene_lattice<2>(scene, options);
}

// Inflated bounding boxes of all inclusions of a scene in a uniform bucket grid.
template <int Dim>
class InclusionIndex {
 public:
  // `boxes`: pipeline::holding_boxes(scene) (one per inclusion).
  InclusionIndex(const geometry::SceneDesc& scene, const grid::Lattice<Dim>& lattice, const GhostRule& rule,
                 std::span<const Box3> boxes);
  InclusionIndex(const geometry::SceneDesc& scene, const grid::Lattice<Dim>& lattice, const GhostRule& rule)
      : InclusionIndex(scene, lattice, rule, pipeline::holding_boxes(scene)) {}
  std::int32_t size() const { return static_cast<std::int32_t>(inflated_.size()); }
  const Box<Dim>& inflated(std::int32_t k) const { return inflated_[static_cast<std::size_t>(k)]; }
  // Inclusions whose inflated box meets the closed `box`, ascending, appended to `out`.
  void query(const Box<Dim>& box, std::vector<std::int32_t>& out) const;

 private:
  std::array<std::int64_t, Dim> bucket_of(const Vec<Dim>& p) const;
  template <class F>
  void for_buckets(const Box<Dim>& box, F&& f) const;
  std::vector<Box<Dim>> inflated_;
  Vec<Dim> origin_{};
  double side_ = 1;
  std::array<std::int64_t, Dim> buckets_{};
  std::vector<std::int32_t> begin_, members_;  // CSR: bucket -> inclusions
};
using InclusionIndex2 = InclusionIndex<2>;
using InclusionIndex3 = InclusionIndex<3>;

template <int Dim>
struct GhostRegion {
  grid::CellRange<Dim> box;    // the partition's coarse cells
  grid::CellRange<Dim> range;  // coarse cells whose state decides the box (clipped to the domain)
  int ghost = 0;               // uniform width that covers `range` (what pipeline::run2/run3 take)
  std::vector<std::int32_t> inclusions;  // scene indices, ascending
};
using GhostRegion2 = GhostRegion<2>;
using GhostRegion3 = GhostRegion<3>;

// The inclusions whose inflated box meets the box grown by rule.box_margin_cells, then
// `rule.max_closure_rounds` rounds of "add every inclusion whose inflated box meets an
// added one's". The range covers the grown box and every added inflated box.
template <int Dim>
GhostRegion<Dim> ghost_region(const InclusionIndex<Dim>& index, const grid::Lattice<Dim>& lattice,
                              const grid::CellRange<Dim>& box, const GhostRule& rule);
inline GhostRegion2 ghost_region2(const InclusionIndex2& index, const grid::Lattice2& lattice,
                                  const grid::CellRange<2>& box, const GhostRule& rule) {
  return ghost_region<2>(index, lattice, box, rule);
}

// The scene restricted to `inclusions` (ascending scene indices), original order kept:
// the oracle's ties go to the lowest index, so relative order must not change.
geometry::SceneDesc subset_scene(const geometry::SceneDesc& scene, const std::vector<std::int32_t>& inclusions);

}  // namespace cisamr::parallel
