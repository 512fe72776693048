#pragma once
// The SAMR level each inclusion's interface ends up at, decided per inclusion before
// meshing (lib/samr/README.md, "Reach of the rules").
//
// Rule R4 keeps moved nodes away from level transitions, so a level reached anywhere along
// a connected interface spreads along all of it, and from there to every interface close
// enough. Computing that spread here, from the scene alone, and handing the result to rule
// R1 makes every SAMR decision local: the mesh no longer depends on anything farther than a
// few cells, which is what lets a partition with a small ghost layer reproduce the
// whole-domain mesh. The spread is an over-approximation of what R2 and R4 would do; the
// sequential and the parallel mesher both use it, so they agree by construction.
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "geometry/scene.hpp"
#include "grid/lattice.hpp"

namespace cisamr::pipeline {

// Bounding boxes of a scene's inclusions, without evaluating expensive geometry: the box
// of a NURBS curve's control points (the curve lies in their convex hull). An STL surface
// needs its triangles, or its box in `known` (one per inclusion; used where the scene's
// StlSurface holds no triangles: a parallel rank that has not loaded that file).
std::vector<Box3> holding_boxes(const geometry::SceneDesc& scene, std::span<const Box3> known = {});

// One level per inclusion of `scene` (scene order), each ≥ the inclusion's own levels
// and ≤ lattice.max_level:
//  - contact (rule R2): inclusions that are not one same-phase union and come closer than
//    1.5·h_l get at least the first level l at which no cell can touch both;
//  - spread (rule R4): an inclusion closer than 6.5 cells of its own level to one of a
//    finer level takes that finer level; repeated until nothing changes.
std::vector<int> effective_levels2(const geometry::SceneDesc& scene, const grid::Lattice2& lattice);

// Pairs (i < j, sorted) of same-phase inclusions, one of them an STL or NURBS surface, whose
// regions overlap (geometry::shapes_overlap): one interface, a union. Needs every STL
// surface's triangles; the parallel mesher computes it where they are all read (rank 0).
struct SurfacePair {
  std::int32_t a = 0, b = 0;
  friend bool operator<(const SurfacePair& x, const SurfacePair& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; }
  friend bool operator==(const SurfacePair&, const SurfacePair&) = default;
};
std::vector<SurfacePair> surface_unions(const geometry::SceneDesc& scene);

// The pairs surface_unions asks geometry::shapes_overlap about, in the order it asks:
// same phase, one of them a surface compared by its box, boxes (holding_boxes' `box`)
// overlapping. The parallel mesher shares these questions among its ranks.
std::vector<SurfacePair> surface_union_candidates(const geometry::SceneDesc& scene, std::span<const Box3> box);

// The same in 3D (rules of samr/samr3.hpp): contact below 1.8·h_l (a tet's bounding cube
// has diagonal √3·h_l), spread below 8 cells of the coarser level (R4's star of a movable
// node: its vertex's leaves, their 2:1 closure and the next cut leaf's bounding cube).
// STL surfaces (and NURBS) are compared by their boxes, which can only over-refine; they
// form a same-phase union with another inclusion where `surface_unions` (surface_unions()
// of the scene) says so. `known` as for holding_boxes. Pass holding_boxes' result to both.
std::vector<int> effective_levels3(const geometry::SceneDesc& scene, const grid::Lattice<3>& lattice,
                                   std::span<const Box3> known = {}, std::span<const SurfacePair> surface_unions = {});

}  // namespace cisamr::pipeline
