#pragma once
// The sequential 3D mesher: box (+ghost) → tet forest → SAMR → r-adaptivity with the
// quality guard → face swapping → subdivision → mesh (lib/pipeline/README3.md).
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/timer.hpp"
#include "geometry/oracle.hpp"
#include "grid/tet_lattice.hpp"
#include "mesh/simplex_mesh.hpp"
#include "pipeline/pipeline.hpp"  // Options (alpha, extra_levels), shared with 2D

namespace cisamr::pipeline {

struct Stats3 {
  std::int64_t coarse_cubes = 0, leaves = 0, refinements = 0;
  int samr_sweeps = 0;
  std::int64_t lattice_nodes = 0, snapped_nodes = 0;
  std::int64_t cut_tets = 0, cut_nodes = 0, closed_tets = 0, steiner_points = 0;
  std::int64_t unresolved = 0;         // cut leaves holding more than one interface (kept whole)
  std::int64_t inverted = 0;           // output tets with non-positive volume
  std::int64_t missing_crossings = 0;  // phase-changing edges without an oracle crossing (midpoint used)
  int max_level = 0;                   // Lmax of the lattice
  // Worst aspect ratio by origin (before dropping voids): closures of hanging midpoints,
  // leaves kept whole (maybe deformed by snapping), sub-tets of cut leaves; counts above 5.
  double worst_closure = 0, worst_kept = 0, worst_split = 0, worst_swapped = 0;
  std::int64_t kept_above_5 = 0, split_above_5 = 0;
  std::int64_t face_swaps = 0;         // pairs of cubes whose shared face was swapped
  // The snapping guard (radapt/radapt3.hpp): nodes that did not get their first option,
  // nodes collapsed onto an interface they do not lie on, cut points standing for a gap
  // thinner than their edge, and the largest distance of either from a phase it serves;
  // leaves and option combinations checked.
  std::int64_t refused_nodes = 0, collapsed_nodes = 0, collapsed_cut_points = 0;
  double max_collapse_deviation = 0;
  std::int64_t guarded_leaves = 0, guard_combinations = 0;
  PhaseTimes times;
};

struct Result3 {
  mesh::Mesh3 mesh;
  // Per output node: its lattice key (grid::key3), or kNotLatticeNode for cut nodes and
  // closure Steiner points.
  std::vector<std::uint64_t> node_key;
  static constexpr std::uint64_t kNotLatticeNode = ~std::uint64_t{0};
  // Per output node, an identity that every partition computes alike, for merging: a
  // lattice node is (key, key), a cut node its edge's (smaller key, larger key), a closure
  // Steiner point (kNotLatticeNode, kNotLatticeNode) (interior to one leaf, never shared).
  std::vector<std::array<std::uint64_t, 2>> node_identity;
  Stats3 stats;
};

// The global lattice of a 3D scene: coarse cubes of size h over the domain and
// Lmax = max(requested levels) + extra_levels. Throws MeshingError when it does not fit
// the 64-bit key.
grid::Lattice3 make_lattice3(const geometry::Oracle3& oracle, const Options& options);

// Meshes the coarse cubes of `box`, using `ghost` extra cubes on each side (clipped to
// the domain). Tets of void phases are dropped; unused nodes removed. `levels`: the level
// rule R1 asks of each of the oracle's inclusions (empty: their own levels); a partition
// passes the levels computed over the whole scene.
Result3 run3(const geometry::Oracle3& oracle, const grid::Lattice3& lattice, const grid::CellRange<3>& box,
             int ghost, const Options& options, int partition_id = 0, std::span<const int> levels = {});

// The whole domain in one box, with the levels effective_levels3 settles (as every
// partition of the parallel mesher uses).
Result3 mesh3_with_stats(const geometry::Oracle3& oracle, const Options& options = {});
mesh::Mesh3 mesh3(const geometry::Oracle3& oracle, const Options& options = {});

}  // namespace cisamr::pipeline
