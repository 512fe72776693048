#pragma once
// The sequential mesher: box (+ghost) → grid → SAMR → r-adaptivity → subdivision → mesh.
// The same call meshes the whole domain (one box, no ghost) or one partition's box with
// its ghost layer; the parallel mesher runs it unchanged on every partition (DESIGN.md §3).
#include <cstdint>
#include <span>
#include <vector>

#include "core/timer.hpp"
#include "geometry/oracle.hpp"
#include "grid/lattice.hpp"
#include "mesh/simplex_mesh.hpp"

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
};

struct Stats {
  std::int64_t coarse_cells = 0, leaves = 0, refinements = 0;
  std::int64_t lattice_nodes = 0, snapped_nodes = 0;
  std::int64_t cut_quads = 0, double_diagonal = 0, hanging_cells = 0, unresolved = 0;
  std::int64_t collapsed = 0;          // quads holding a feature below their resolution
  double max_collapse_deviation = 0;   // largest node distance from a phase it serves
  double max_collapse_ratio = 0;       // the same relative to the size of the collapsed cell
  int min_collapse_level = -1;         // coarsest level of a collapse (-1: none)
  int max_level = 0;                   // Lmax of the lattice
  PhaseTimes times;
};

struct Result2 {
  mesh::Mesh2 mesh;
  // Per output node: its lattice key (grid/lattice.hpp key2), or kInteriorNode for points
  // created inside a cell (never on a partition face). Partitions merge nodes by key.
  std::vector<std::uint64_t> node_key;
  static constexpr std::uint64_t kInteriorNode = ~std::uint64_t{0};
  Stats stats;
};

// The global lattice of a 2D scene: coarse cells of size h over the domain and
// Lmax = max(requested levels) + extra_levels.
grid::Lattice2 make_lattice2(const geometry::Oracle2& oracle, const Options& options);

// Meshes the coarse cells of `box` (global coarse indices), using `ghost` extra coarse
// cells on each side (clipped to the domain) so that decisions inside the box are those
// of the whole-domain run. Cells of void phases are dropped; unused nodes removed.
// `levels`: the level rule R1 asks of each of the oracle's inclusions, from
// effective_levels2 over the whole scene (a partition's oracle holds a subset of it).
Result2 run2(const geometry::Oracle2& oracle, const grid::Lattice2& lattice, const grid::CellRange<2>& box,
             int ghost, const Options& options, int partition_id, std::span<const int> levels);

// The whole domain in one box.
Result2 mesh2(const geometry::Oracle2& oracle, const Options& options = {});

}  // namespace cisamr::pipeline
