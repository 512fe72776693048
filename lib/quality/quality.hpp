#pragma once
// Quality metrics and mesh checks (DESIGN.md §2 invariants 1-3): aspect-ratio statistics,
// conformity (topology + measure) and phase fidelity against the scene's geometry.
// Pure functions: they read a mesh and return a report; nothing is printed or thrown for a
// bad mesh (a bad mesh is the answer, not an error). See lib/quality/README.md.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "geometry/oracle.hpp"
#include "geometry/scene.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::quality {

// ---------------------------------------------------------------------------------------
// Aspect ratio (Verdict definition, mesh/metrics.hpp) and angles.
// ---------------------------------------------------------------------------------------

// Width of the fixed histogram bins; edges are 1.0, 1.1, 1.2, ...
inline constexpr double kHistogramBinWidth = 0.1;
// The regular bins stop at this aspect ratio at the latest; anything above goes to the
// overflow bin (so a mesh with a 1e9 sliver does not produce 1e10 bins).
inline constexpr double kHistogramMaxEdge = 100.0;

struct AspectStats {
  double max = 0;   // +inf when a cell is degenerate
  double mean = 0;  // over the cells with a finite aspect ratio
  std::size_t count = 0;        // cells
  std::size_t above_bound = 0;  // cells with aspect ratio > bound (degenerate ones included)
  double bound = 0;
  // Regular bin i counts [bin_edges[i], bin_edges[i+1]); the last entry of `histogram`
  // (index bin_edges.size()-1) is the overflow bin: aspect ratio >= bin_edges.back(),
  // +inf included. bin_edges.back() > max(bound, max) unless max exceeds kHistogramMaxEdge.
  // Values below 1 (round-off on equilateral cells) count in the first bin.
  std::vector<double> bin_edges;
  std::vector<std::size_t> histogram;  // bin_edges.size() entries
  struct Worst {
    std::size_t cell = 0;
    double aspect_ratio = 0;
    std::array<double, 3> centroid{};  // z = 0 in 2D
    int phase = 0;                     // phase id
  };
  std::vector<Worst> worst;  // worst first; ties broken by smaller cell id
  // 2D: the smallest and largest triangle angle; 3D: the smallest and largest dihedral
  // angle. Cells with a zero-length edge are skipped. 0/0 for an empty mesh.
  double min_angle_deg = 0, max_angle_deg = 0;
};

// One pass over the cells; O(cells), no allocation proportional to the mesh unless
// `cell_aspect_ratio` is given: then it receives every cell's ratio (mesh::aspect_ratio's
// value, +inf for a cell naming a missing node), for a writer's per-cell array.
template <int Dim>
AspectStats aspect_statistics(const mesh::SimplexMesh<Dim>& m, double bound, int worst_count = 20,
                              std::vector<double>* cell_aspect_ratio = nullptr);

// Adds histogram `hist` over `edges` to `total`'s, bin by bin. Every statistics' edges are a
// prefix of the same sequence (1.0, 1.1, ...), so the longer list is kept and the overflow
// bin of the shorter moves to its new end.
void add_histogram(AspectStats& total, const std::vector<double>& edges, const std::vector<std::size_t>& hist);
// The statistics of the union of two cell sets (partitions meshed one after another):
// max, counts, mean weighted by count, angles, histograms. `worst` is cleared (cell ids are
// per set).
void merge_into(AspectStats& total, const AspectStats& part);

// ---------------------------------------------------------------------------------------
// Conformity (DESIGN.md §2.1).
// ---------------------------------------------------------------------------------------

// Relative tolerances, documented in README.md.
inline constexpr double kNearDuplicateTolerance = 1e-12;  // × domain diagonal
inline constexpr double kOnBoxTolerance = 1e-10;          // × domain diagonal
inline constexpr double kDegenerateTolerance = 1e-12;     // |measure| <= this × l_max^Dim
inline constexpr double kOnFacetTolerance = 1e-9;         // × facet's longest edge
inline constexpr double kDefaultMeasureTolerance = 1e-9;  // relative measure error

struct ConformityReport {
  bool ok = false;
  std::size_t duplicate_nodes = 0;   // nodes within 1e-12·diagonal of a lower-numbered node
  std::size_t degenerate_cells = 0;  // |signed measure| <= 1e-12 · l_max^Dim
  std::size_t inverted_cells = 0;    // signed measure < 0 (and not degenerate)
  std::size_t bad_node_references = 0;  // cells naming a node id out of range (skipped)
  std::size_t non_manifold_facets = 0;  // shared by > 2 cells
  std::size_t mismatched_orientation_facets = 0;  // shared by 2 cells with the same orientation
  std::size_t open_facets_inside = 0;  // shared by one cell, not on the domain box (error)
  // Open facets not on the domain box when allow_inner_boundary: void interfaces. Not an
  // error here; check_fidelity verifies they lie on a void.
  std::size_t inner_boundary_facets = 0;
  std::size_t boundary_facets = 0;  // open facets on the domain box (fine)
  std::size_t hanging_nodes = 0;    // nodes lying inside another open facet (T-junctions)
  std::size_t unused_nodes = 0;     // referenced by no cell
  double measure = 0;               // Σ |cell measure|
  double expected_measure = -1;     // < 0: not checked
  double measure_error = 0;         // |measure - expected| / expected (0 if not checked)
  double measure_tolerance = kDefaultMeasureTolerance;
  std::vector<std::string> examples;  // first few problems, with ids and coordinates
};

// expected_measure: the domain's measure minus the voids' (< 0: do not check).
// allow_inner_boundary: the scene has voids, so open facets inside the box are expected.
// measure_tolerance: relative; a mesh of curved voids differs from the exact void measure
// by its discretisation error, so callers with voids pass a looser one.
template <int Dim>
ConformityReport check_conformity(const mesh::SimplexMesh<Dim>& m, const Box<Dim>& domain,
                                  double expected_measure, bool allow_inner_boundary,
                                  double measure_tolerance = kDefaultMeasureTolerance);

// ---------------------------------------------------------------------------------------
// Phase fidelity (DESIGN.md §2.3), one check for 2D and 3D.
// ---------------------------------------------------------------------------------------

// Centroid check (README.md, "Phase fidelity"), run in 3D: the centroid of a phase-k
// tetrahedron may lie outside phase k by at most max(tol, slack · l_max), l_max its
// longest edge. A tet whose vertices all lie on phase k's boundary (every vertex's
// closure holds another phase) hugs a curved surface: its centroid is off by the
// surface's sagitta, which only the curvature bounds, hence the larger slack. A tet with a
// vertex strictly inside phase k reaches at most a few per cent of l_max outside it. A tet
// of the wrong phase is off by a sizeable fraction of its size.
inline constexpr double kCentroidSlack = 0.1;
inline constexpr double kInterfaceCentroidSlack = 0.25;
// A centroid farther than this fraction of the tet's longest edge from the tet's phase
// (beyond tol) means the tet lies in another phase: that fails the check. Between the
// slack above and this, the tet straddles an interface more than a smooth, resolved
// interface explains (a crease, a collapsed node, a feature below the resolution): it is
// counted and reported, not failed.
inline constexpr double kWrongPhaseRatio = 0.5;

struct FidelityReport {
  bool ok = false;
  double tolerance = 0;
  // Node whose cells are all of one phase k, farther than tol from phase k's closure.
  std::size_t nodes_off_phase = 0;
  // Node shared by cells of two or more phases, farther than tol from one of them.
  std::size_t interface_nodes_off_interface = 0;
  // Node of an open facet inside the domain box (void interface) farther than tol from
  // every void phase.
  std::size_t boundary_nodes_off_void = 0;
  std::size_t cells_unknown_phase = 0;  // cell phase id not in the scene, or a void phase
  double max_deviation = 0;             // largest distance found in the node checks above
  // With strict_tol ≥ 0: nodes of the checks above farther than strict_tol (≤ tol) from a
  // phase they serve, e.g. the nodes a collapse moved off, checked against tol.
  std::size_t nodes_beyond_strict = 0;
  // Whether the centroid check ran (3D); without it the three fields below stay 0: cells
  // whose centroid lies farther from their phase than the slack (kCentroidSlack,
  // kInterfaceCentroidSlack; reported), cells whose centroid lies beyond kWrongPhaseRatio
  // of their longest edge (a failure), and the largest ratio (centroid's distance to the
  // cell's phase) / (cell's longest edge) found.
  bool centroids_checked = false;
  std::size_t cells_off_phase = 0;
  std::size_t cells_wrong_phase = 0;
  double max_centroid_ratio = 0;
  // Indexed by the scene's phase index. Void phases are not meshed: their phase_measure
  // is 0 and their relative_error NaN.
  std::vector<int> phase_id;
  std::vector<std::string> phase_name;
  std::vector<bool> phase_is_void;
  std::vector<double> phase_measure, exact_phase_measure, relative_error;
  std::vector<std::string> examples;
};

// 1e-9 × the domain diagonal (DESIGN.md §2.3, analytic shapes).
double default_fidelity_tolerance(const geometry::SceneDesc& scene);

// Every node within tol of the closure of each phase of its cells, the nodes of open
// facets inside the domain (void interfaces) within tol of a void, every cell of a known,
// non-void phase; in 3D the centroid check above. Per-phase measures against the oracle's
// (areas of circles, ellipses, polygons, NURBS; volumes of spheres, ellipsoids, cylinders
// and closed STL surfaces, clipped by the box, overlapping unions included), reported,
// not judged.
// `exact_measures`: the oracle's per-phase measures when the caller has them already (they
// are integrated for clipped or overlapping inclusions); empty: computed here.
// `strict_tol` (optional, ≤ tol): also count the nodes beyond it (nodes_beyond_strict).
template <int Dim>
FidelityReport check_fidelity(const mesh::SimplexMesh<Dim>& m, const geometry::Oracle<Dim>& oracle, double tol,
                              std::span<const double> exact_measures = {}, double strict_tol = -1);

// ---------------------------------------------------------------------------------------
// Small helpers shared by the certificate and the command.
// ---------------------------------------------------------------------------------------

template <int Dim>
Box<Dim> bounding_box(const mesh::SimplexMesh<Dim>& m);  // {0,0} box for an empty mesh

template <int Dim>
double box_diagonal(const Box<Dim>& b);

}  // namespace cisamr::quality
