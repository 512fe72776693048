#pragma once
// The ghost region of a partition box: which inclusions and which coarse cells a partition
// must see so that every decision inside its box equals the whole-domain run's
// (DESIGN.md §8). One template for 2D and 3D; see README.md for the derivation of the
// margins.
#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "core/types.hpp"
#include "faceswap/faceswap3.hpp"
#include "geometry/scene.hpp"
#include "grid/lattice.hpp"
#include "partition/partition.hpp"
#include "pipeline/effective_levels.hpp"
#include "pipeline/pipeline.hpp"
#include "radapt/radapt2.hpp"
#include "radapt/radapt3.hpp"
#include "samr/samr2.hpp"
#include "samr/samr3.hpp"
#include "subdivide/subdivide2.hpp"
#include "subdivide/subdivide3.hpp"

namespace cisamr::parallel {

// The ghost widths derive from the reach each stage declares in its header: how far beyond
// a cell the decisions about it look (README.md, "Ghost region").

// 2D (README.md, "Ghost region (2D)"): the forest is right beyond the first coarse layer of
// the range (samr::kReachCoarseCells2), and a decision about a box cell reads cells at most
// kKernelReach2 cells of its level beyond it (r-adaptivity: the cells around a node;
// subdivision: its corners' final positions), at most one coarse cell.
inline constexpr int kKernelReach2 = std::max(radapt::kReachCells2, subdivide::kReachCells2);
// Coarse cells around a partition box that its kernel also meshes in 2D: 2, at any level
// (the sweep of README.md: 702 runs the whole-domain mesh with 2, 635 not with 1).
inline constexpr int kGhostMargin2 = samr::kReachCoarseCells2 + kKernelReach2;
// 2D, in cells of an inclusion's own level, the margin around its bounding box within which
// a partition loads it (rule level_aware, 4·h_R; the range's cut lists need only the
// inclusions that meet it).
inline constexpr double kInclusionMarginCells2 = 2 * samr::kReachCells2;

// 3D (README.md, "Ghost region (3D)"): how far a decision about a cell of the box can look
// beyond the box's face, on data the partition must hold exactly as the whole-domain run
// holds it: the SAMR forest is right beyond the first coarse cube inside the region
// (samr::reach_coarse_cells3: 1, 0 when nothing refines; tested by SamrReach3), and on top
// of it the snapping guard (3), face swapping (5) and subdivision (3) read cells of the
// level of the leaves that decide (tested by KernelReach3).
inline constexpr double kKernelReach3 =                          // cells of the deciding level
    std::max({radapt::kReachCells3, faceswap::kReachCells3, subdivide::kReachCells3});

// 3D windows of the later stages inside that ghost, in cells of the deciding level (README.md,
// "Ghost region (3D)"): the forest is needed on the whole ghost for SAMR's sake, but a
// decision in the box reads the final positions and masks of nodes at most
// kCompetitorCells3 cells out (the far corners of a competing face swap's cubes: a swap of
// box cube C with D beats every candidate sharing C or D, and a competitor (D, Y) reads D and
// Y only). Such a node's position is decided by the guard's second-pass refusals of the leaves
// around it (radapt::kSecondPassCells3), their vertices' first-pass refusals
// (kFirstPassCells3) and those leaves' vertices' options (radapt::kReachCells3). A window
// holds the leaves that *start* within it (grid::LeafWindow), and a leaf of the deciding
// level that reaches d cells out starts d − 1 out (finer leaves' chains are shorter): hence
// the − 1. Face swapping looks for candidates from the corner tets of the competitors' cubes.
// No safety on top: KernelReach3 checks these windows directly.
inline constexpr int kSwapWindow3 = faceswap::kCompetitorCells3 - 1;
inline constexpr int kRadaptWindow3 = faceswap::kCompetitorCells3 + radapt::kReachCells3 - 1;
inline constexpr int kFirstPassWindow3 = faceswap::kCompetitorCells3 + radapt::kFirstPassCells3 - 1;
inline constexpr int kSecondPassWindow3 = faceswap::kCompetitorCells3 + radapt::kSecondPassCells3 - 1;
static_assert(kSwapWindow3 == 1 && kRadaptWindow3 == 4 && kFirstPassWindow3 == 3 && kSecondPassWindow3 == 2);

// The same with the decisions near faces exchanged (GhostRule::exchange, README.md, "Decisions
// exchanged near faces"). Between the guard's passes each partition takes the first-pass
// refusals of the nodes its second pass reads outside its closed box, and after r-adaptivity
// the final position, mask, state and finest level around of every node outside it, from
// the partition whose closed box holds the node (which decided it on its own data). What a
// partition decides itself are then the nodes of its closed box: the second pass on the
// leaves around them (kSecondPassCells3 − 1 = 0), the first pass there too (its refusals of
// the other nodes come from their owners), and options for those leaves' vertices, read from
// the leaves around them (one cell further: 1). The forest must be right where those leaves
// and face swapping's competitors lie: 2 cells.
inline constexpr int kExchangedSecondPassWindow3 = radapt::kSecondPassCells3 - 1;
inline constexpr int kExchangedFirstPassWindow3 = kExchangedSecondPassWindow3;
inline constexpr int kExchangedRadaptWindow3 = radapt::kSecondPassCells3;
inline constexpr double kExchangedKernelReach3 = std::max(kExchangedRadaptWindow3 + 1, faceswap::kCompetitorCells3);
static_assert(kExchangedRadaptWindow3 == 1 && kExchangedFirstPassWindow3 == 0 && kExchangedSecondPassWindow3 == 0 &&
              kExchangedKernelReach3 == 2);

// Coarse cubes of ghost a 3D box needs when the coarsest effective level among the
// inclusions near it is `level` and the lattice's finest is `max_level`: the least whole
// number greater than samr::reach_coarse_cells3(max_level) + kKernelReach3 / 2^level (greater:
// the first layer's far face may hold midpoints the partition lacks), the kernel's reach
// counted in cells of its level (level 2: 1 + 1.25 → 3): 7 at level 0, 4 at level 1, 3 at
// level 2, 2 from level 3 on; 6 when nothing refines (Lmax 0). With the forest and the
// decisions near faces exchanged, SAMR's reach and the kernel's no longer add up: the box's
// forest is right with samr::reach_coarse_cells3(max_level) cubes around it, the ghost's
// cubes then take their owners' trees, and the kernel reads kExchangedKernelReach3 / 2^level
// cubes out (up to the region's outer face: what it reads there, the nodes' decisions and the
// finest level around them, comes from their owners). The least whole number not below
// either: 2 at level 0, 1 from level 1 on; 2 when nothing refines.
int ghost_margin3(int level, int max_level = 64, bool exchanged = false);

struct GhostRule {
  // 2D: margin around every inclusion's bounding box. Level-aware (default):
  // kInclusionMarginCells2·h_R = 4·h_R, h_R = h/2^R, R the inclusion's SAMR levels; two
  // inclusions whose inflated boxes do not meet cannot change each other's refinement. Fixed: `fixed_cells`·h for every inclusion.
  // (3D inflates by kBoxSlack3 only.)
  bool level_aware = true;
  double fixed_cells = 3;
  // 2D: coarse cells around the box itself (kGhostMargin2).
  double box_margin_cells = kGhostMargin2;
  // 3D: coarse cubes around the box, meshed, whose inclusions are all loaded. 0 (default):
  // ghost_margin3 of the coarsest effective level among the inclusions within
  // ghost_margin3(0) cubes of the box and of the lattice's Lmax (1 when there is no
  // inclusion there); > 0: that many (comparisons,
  // and the tests that show a too small ghost breaks invariance). In 3D inclusion boxes
  // are not inflated (level_aware and fixed_cells are 2D rules): the margin covers that.
  double margin3_cubes = 0;
  // 3D: the windows of r-adaptivity and face swapping, in cells of the deciding level
  // (pipeline::Ghost). 0 (default): kRadaptWindow3 and kSwapWindow3, the guard's passes on
  // kFirstPassWindow3 and kSecondPassWindow3; > 0: that many, the guard on all of
  // r-adaptivity's (comparisons, and the tests that show a too small window breaks
  // invariance); < 0: every leaf of the ghost (as before the windows). Face swapping's at 0
  // follows a forced r-adaptivity's (swap_window3_cells()).
  double radapt_window_cells3 = 0, swap_window_cells3 = 0;
  // Face swapping's window in use when r-adaptivity's is forced and its own is not: that
  // less the cells between them (kRadaptWindow3 − kSwapWindow3 = 3), at least ½; -1 with -1.
  double swap_window3_cells() const {
    if (swap_window_cells3 != 0 || radapt_window_cells3 == 0) return swap_window_cells3;
    if (radapt_window_cells3 < 0) return -1;
    return std::max(0.5, radapt_window_cells3 - (kRadaptWindow3 - kSwapWindow3));
  }
  // Rounds of the closure "add every inclusion whose inflated box meets an added one's".
  // 0 (default): none. pipeline::effective_levels2/3 settle every level that rule R4 could
  // carry from one inclusion to another before meshing, so what decides a cell lies within
  // a few coarse cells of it (README.md, "Ghost region"). -1: the full closure, for
  // comparison.
  int max_closure_rounds = 0;
  // 3D: the caller exchanges the forest and r-adaptivity's decisions near faces (README.md,
  // "Decisions exchanged near faces"), so the margins and windows are the narrower
  // kExchanged* ones. In effect only where exchanges_near_faces() says so: not with a forced
  // margin, windows or closure rounds (comparisons keep their meaning), not on a periodic
  // lattice (its windows are the whole ghost).
  bool exchange = false;
};

// Whether a 3D run with this rule exchanges its decisions near faces.
inline bool exchanges_near_faces(const GhostRule& rule, bool periodic) {
  return rule.exchange && !periodic && rule.margin3_cubes == 0 && rule.radapt_window_cells3 == 0 &&
         rule.swap_window_cells3 == 0 && rule.max_closure_rounds == 0;
}

// What a cube of 3D ghost costs the partitioner, as a fraction of a box cube's work, with the
// ghost of an in-memory run (the forest and the decisions near faces exchanged:
// ghost_margin3(l, Lmax, true), 1 or 2 cubes): SAMR refines it, r-adaptivity works on its
// first cell only, subdivision, quality and output not at all. Chosen by measurement
// (validation/bench/SCALING.md, "The forest exchanged near faces too"): 0.15 gave a lower
// slowest partition than 0.35 at 16 partitions of spheres300 and E4 and as low at 64. (0.35
// with the recomputing margins, 7, 4, 3, 2, before: they left the boxes inside the domain
// under-loaded once the ghost was exchanged.) Streamed and --no-ghost-exchange runs, whose
// ghost is wider, take the same boxes: one set of boxes per scene and count, so that their
// outputs are the in-memory run's node for node.
inline constexpr double kGhostCostWeight3 = 0.15;

// `options` with the 3D ghost for the partitioner to balance (partition::PartitionOptions::
// ghost_cells_at_level, ghost_weight): the exchanged ghost_margin3 by level, or the forced
// margin; 2D partitions balance their loads only (their ghost is 2 cells: 1.15 times the
// domain at 64). Both `cisamr mesh` and `cisamr partition` partition with it, so they give
// the same boxes.
partition::PartitionOptions ghost_aware(partition::PartitionOptions options, int dimension, const GhostRule& rule = {});

// The full scene's lattice (every inclusion's levels count for Lmax), built from the
// description alone, without geometry.
template <int Dim>
grid::Lattice<Dim> scene_lattice(const geometry::SceneDesc& scene, const pipeline::Options& options);
inline grid::Lattice2 scene_lattice2(const geometry::SceneDesc& scene, const pipeline::Options& options) {
  return scene_lattice<2>(scene, options);
}

// 3D inclusion boxes are inflated by this many coarse cells only: more than the geometry
// oracle's own boxes exceed the exact ones (relative 1e-12), so an inclusion whose oracle
// box meets a cube of the region is always loaded.
inline constexpr double kBoxSlack3 = 1e-6;

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
  // Ghost cells beyond each face of the box that the kernel meshes (pipeline::Ghost): 3D,
  // `range` side by side; 2D, the uniform `ghost` on every side.
  pipeline::GhostSides sides{};
  int ghost = 0;               // uniform width that covers `range` (the widest side)
  int margin = 0;              // 3D: the widest side's margin (coarse cubes)
  // 3D: r-adaptivity's, its guard's passes' and face swapping's windows, fine lattice units
  // (-1: every leaf).
  std::int64_t radapt_reach = -1, swap_reach = -1, first_pass_reach = -1, second_pass_reach = -1;
  // 3D: the margins and windows count on the forest and the decisions near faces being
  // exchanged (exchanges_near_faces); the kernel must then run in parts with the exchanges
  // between them: pipeline::refine3_part, exchange_forests (and take_cube_refinements),
  // snap3_first, exchange_first_pass_refusals, snap3_second, exchange_decisions, finish3.
  bool exchange = false;
  std::vector<std::int32_t> inclusions;  // scene indices, ascending
};
template <int Dim>
pipeline::Ghost kernel_ghost(const GhostRegion<Dim>& region) {
  return {region.sides, region.radapt_reach, region.swap_reach, region.first_pass_reach, region.second_pass_reach};
}
using GhostRegion2 = GhostRegion<2>;
using GhostRegion3 = GhostRegion<3>;

// The coarse cells of the box grown by rule.box_margin_cells (clipped to the domain) and the
// inclusions whose inflated box meets them. With closure rounds (a comparison only):
// `rule.max_closure_rounds` rounds of "add every inclusion whose inflated box meets an
// added one's", and the range also covers every added inflated box (as before effective
// levels settled what the closure carried).
template <int Dim>
GhostRegion<Dim> ghost_region(const InclusionIndex<Dim>& index, const grid::Lattice<Dim>& lattice,
                              const grid::CellRange<Dim>& box, const GhostRule& rule);
inline GhostRegion2 ghost_region2(const InclusionIndex2& index, const grid::Lattice2& lattice,
                                  const grid::CellRange<2>& box, const GhostRule& rule) {
  return ghost_region<2>(index, lattice, box, rule);
}

// 3D: the coarse cubes of `box` grown by the margin (clipped to the domain) and every
// inclusion whose box meets them; `levels` are the scene's effective levels
// (pipeline::effective_levels3, scene order), which choose the margin
// (GhostRule::margin3_cubes). With closure rounds (a comparison only) the range also
// covers the added inclusions' boxes, as in 2D.
GhostRegion3 ghost_region3(const InclusionIndex3& index, const grid::Lattice<3>& lattice, const grid::CellRange<3>& box,
                           const GhostRule& rule, std::span<const int> levels);

// The scene restricted to `inclusions` (ascending scene indices), original order kept:
// the oracle's ties go to the lowest index, so relative order must not change.
geometry::SceneDesc subset_scene(const geometry::SceneDesc& scene, const std::vector<std::int32_t>& inclusions);

}  // namespace cisamr::parallel
