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
#include <vector>

#include "geometry/scene.hpp"
#include "grid/lattice.hpp"

namespace cisamr::pipeline {

// One level per inclusion of `scene` (scene order), each ≥ the inclusion's own levels
// and ≤ lattice.max_level:
//  - contact (rule R2): inclusions that are not one same-phase union and come closer than
//    1.5·h_l get at least the first level l at which no cell can touch both;
//  - spread (rule R4): an inclusion closer than 6.5 cells of its own level to one of a
//    finer level takes that finer level; repeated until nothing changes.
std::vector<int> effective_levels2(const geometry::SceneDesc& scene, const grid::Lattice2& lattice);

}  // namespace cisamr::pipeline
