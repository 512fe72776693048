#pragma once
// The sequential mesher (README.md), 2D and 3D:
//   2D: box (+ghost) → quad forest → SAMR → r-adaptivity → subdivision → mesh
//   3D: box (+ghost) → tet forest → SAMR → r-adaptivity with the quality guard → face
//       swapping → subdivision → mesh
// The same call meshes the whole domain (one box, no ghost) or one partition's box with
// its ghost layer; the parallel mesher runs it unchanged on every partition (DESIGN.md §3).
#include <array>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include "core/progress.hpp"
#include "core/timer.hpp"
#include "geometry/oracle.hpp"
#include "geometry/scene.hpp"
#include "grid/lattice.hpp"
#include "mesh/simplex_mesh.hpp"
#include "pipeline/counters.hpp"

namespace cisamr::pipeline {

struct Options {
  double alpha = 0.5;    // r-adaptivity threshold (fraction of the edge length)
  int extra_levels = 3;  // levels beyond the largest requested one that rule R2 may use
  // 3D only (radapt::Options3): snap reach along face diagonals, and the aspect-ratio bound
  // the snapping guard enforces on every tetrahedron (0: no guard).
  double alpha_diagonal3 = 0.2;
  int max_candidates3 = 2;  // snap candidates per node the 3D guard considers
  double bound3 = 5.0;
  double swap_trigger3 = 3.0;  // corner tets above this aspect ratio look for a face swap (0: none)
  // Cohesive cells on every interface between phases, interface nodes split per phase
  // (mesh/cohesive.hpp). `mesh` only: the whole domain of a scene that is not periodic.
  bool cohesive = false;
  // Told of the stages (levels, samr, radapt, ...) as they begin, and advanced within each.
  Progress* progress = nullptr;
};

// The phases `run` begins on its Progress, in this order: samr, radapt, (faceswap in 3D,)
// subdivide, assemble; a caller that runs it on many partitions measures each run by them.
template <int Dim>
inline constexpr int kRunPhases = Dim == 2 ? 4 : 5;

// What identifies an output node across partitions. 2D: its lattice key (grid::key2).
// 3D: (key, key) for a lattice node, its edge's (smaller key, larger key) for a cut node.
template <int Dim>
using NodeIdentity = std::conditional_t<Dim == 2, std::uint64_t, std::array<std::uint64_t, 2>>;

template <int Dim>
struct Result {
  mesh::SimplexMesh<Dim> mesh;
  // Per output node, its identity, computed alike by every partition: partitions merge
  // nodes by it. kUnshared for points interior to one cell (2D points added by subdivision,
  // 3D closure Steiner points), never on a partition face.
  std::vector<NodeIdentity<Dim>> node_identity;
  static constexpr NodeIdentity<Dim> kUnshared = [] {
    if constexpr (Dim == 2)
      return ~std::uint64_t{0};
    else
      return std::array<std::uint64_t, 2>{~std::uint64_t{0}, ~std::uint64_t{0}};
  }();
  Counters<Dim> counters;
  PhaseTimes times;  // per stage: samr, radapt, (faceswap,) subdivide, assemble
};

// The scene's coarse cells: the domain's extent over mesh.h, per axis rounded, multiplied.
template <int Dim>
double coarse_cells(const geometry::SceneDesc& scene);

// The global lattice of a scene: coarse cells of size h over the domain and
// Lmax = max(requested levels) + extra_levels. Throws InputError when h exceeds the
// domain, and (3D) MeshingError when the lattice does not fit the 64-bit key.
template <int Dim>
grid::Lattice<Dim> make_lattice(const geometry::SceneDesc& scene, const Options& options);

// Coarse cells of ghost below ([axis][0]) and above ([axis][1]) a box on each axis.
using GhostSides = std::array<std::array<int, 2>, 3>;
inline GhostSides uniform_sides(int cells) { return {{{cells, cells}, {cells, cells}, {cells, cells}}}; }

// The coarse cells a kernel builds its forest on: `box` grown by `ghost` cells beyond each
// face, clipped to the domain; on a periodic axis not clipped but wrapping (the whole
// period once it spans it).
template <int Dim>
grid::CellRange<Dim> ghosted_range(const grid::Lattice<Dim>& lattice, const grid::CellRange<Dim>& box, const GhostSides& ghost);

// A rough count of the elements a scene's mesh will have, before any memory is taken: the
// background cells, and per inclusion a band along its interface at its requested level
// (the interface's size taken from its box clipped to the domain; an STL surface whose
// triangles are not loaded is left out). An estimate for refusing requests beyond the
// machine, not a bound: rule R2 may refine further, empty boxes less.
struct MeshEstimate {
  double background = 0;  // elements of the unrefined lattice
  double refined = 0;     // elements the inclusions' refinement adds
  std::int64_t largest_inclusion = -1;  // the inclusion adding the most (-1: none)
  double total() const { return background + refined; }
};
template <int Dim>
MeshEstimate estimate_mesh(const geometry::SceneDesc& scene);

// What a partition's kernel takes around its box (lib/parallel/README.md, "Ghost region").
// SAMR builds its forest on `sides` coarse cells beyond each face of the box (3D: each
// face's own, from what lies near it); in 3D r-adaptivity and face swapping then work only
// on the leaves within their reach of the box (fine lattice units, grid::LeafWindow; -1:
// every leaf), which is all their decisions in the box read, and r-adaptivity's guard runs
// its first and second pass on narrower windows still. Windows need the box and the forest
// in one frame: not on a periodic lattice (-1 there).
struct Ghost {
  GhostSides sides{};
  std::int64_t radapt_reach = -1;
  std::int64_t swap_reach = -1;
  std::int64_t first_pass_reach = -1;
  std::int64_t second_pass_reach = -1;
};

// Meshes the coarse cells of `box` (global coarse indices), using the `ghost` around it
// (clipped to the domain) so that decisions inside the box are those of the whole-domain
// run. Cells of void phases are dropped; unused nodes removed.
// `levels`: the level rule R1 asks of each of the oracle's inclusions, from
// effective_levels2/3 over the whole scene (a partition's oracle holds a subset of it).
template <int Dim>
Result<Dim> run(const geometry::Oracle<Dim>& oracle, const grid::Lattice<Dim>& lattice, const grid::CellRange<Dim>& box,
                const Ghost& ghost, const Options& options, int partition_id, std::span<const int> levels);

// The whole domain in one box, with the levels effective_levels2/3 settle over the whole
// scene (as every partition of the parallel mesher uses, so that one process and any
// number of partitions mesh alike).
Result<2> mesh(const geometry::Oracle2& oracle, const Options& options = {});
Result<3> mesh(const geometry::Oracle3& oracle, const Options& options = {});

}  // namespace cisamr::pipeline
