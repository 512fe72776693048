#pragma once
// Internal to lib/quality: the parts of the conformity and fidelity checks that
// certify_pieces.cpp runs on one piece of a partitioned mesh at a time, and on the border
// between pieces once every piece has been seen (README.md, "Partitioned meshes").
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/types.hpp"
#include "geometry/oracle.hpp"
#include "mesh/simplex_mesh.hpp"
#include "quality/certificate.hpp"
#include "quality/facet_table.hpp"
#include "quality/quality.hpp"

namespace cisamr::quality::detail {

// One use of a facet whose nodes all are shared with other pieces: the nodes' global ids,
// ascending; the cell (numbered over all pieces, in their order); the parity of the cell's
// listing of the facet relative to the ascending ids.
template <int Dim>
struct GlobalFacet {
  std::array<GlobalId, Dim> ids{};
  std::size_t cell = 0;
  bool odd = false;
};

// What one piece hands to the border check.
template <int Dim>
struct PieceBorder {
  std::vector<GlobalFacet<Dim>> shared_facets;         // every use of a facet of shared nodes only
  std::vector<std::array<GlobalId, Dim>> open_facets;  // open in the piece, off the box, not all shared (counted)
  std::vector<LocalId> open_nodes;  // the nodes of open_facets the piece does not share, ascending
  std::vector<bool> used;           // per node: a cell of the piece uses it
};

// A facet of the border mesh (its local ids, ascending) and one use.
template <int Dim>
struct BorderFacetUse {
  FacetNodes<Dim> nodes{};
  FacetUse use;
};

// The conformity checks of one piece whose nodes `shared` are shared with other pieces:
// its cells, its unshared nodes (unused, near-duplicates unless both are on the border) and
// the facets no other piece can hold; the rest goes to `border`. `m.node_global_id` is set.
template <int Dim>
void check_piece_conformity(const mesh::SimplexMesh<Dim>& m, const std::vector<bool>& shared, const Box<Dim>& domain,
                            bool allow_inner_boundary, std::size_t cell_offset, ConformityReport& r,
                            PieceBorder<Dim>& border);

// The checks across pieces, on the border mesh (the shared nodes and the nodes of the
// pieces' open facets, no cells): every shared facet with all its uses, near-duplicates
// among border nodes, hanging nodes in the open facets (`open_facets`: the pieces' own,
// already counted). Returns the nodes of the open facets off the box (void interfaces).
template <int Dim>
std::vector<LocalId> check_border_conformity(const mesh::SimplexMesh<Dim>& border,
                                             std::vector<BorderFacetUse<Dim>>& shared_uses,
                                             const std::vector<FacetNodes<Dim>>& open_facets, const Box<Dim>& domain,
                                             bool allow_inner_boundary, ConformityReport& r);

// The measure against the expected one, and the verdict.
void finish_piecewise_conformity(ConformityReport& r, double expected_measure, double measure_tolerance);

// ---- against a scene ----

// What certifying against a scene takes from it: its domain; the options with the expected
// measure (domain − voids), inner boundaries allowed iff it has a void phase, and the looser
// measure tolerance then; the oracle's per-phase measures; the note on voids (or ""); the
// fidelity tolerance.
template <int Dim>
struct SceneTerms {
  Box<Dim> domain;
  CertifyOptions options;
  std::vector<double> exact_measures;
  std::string void_note;
  double fidelity_tolerance = 0;
};
template <int Dim>
SceneTerms<Dim> scene_terms(const geometry::Oracle<Dim>& oracle, const CertifyOptions& options);

// ---- fidelity ----

// "(x, y)" or "(x, y, z)", 12 significant digits: how examples give a point.
template <int Dim>
std::string point_text(const Vec<Dim>& p);

// A node's checks against the phases of its cells (`mask`): the phases whose closure holds
// it, and the worst distance to a phase of `mask` it is not in the closure of.
struct NodeVerdict {
  PhaseMask mask = 0, closure = 0;
  double worst = 0;
  int worst_phase = -1;  // phase index, -1: none
  bool beyond_strict = false;
};

// The report with the scene's phases and exact measures, nothing counted.
template <int Dim>
FidelityReport start_fidelity(const geometry::Oracle<Dim>& oracle, double tol, std::span<const double> exact_measures);

// The cells (phases, measures, 3D centroids) and the nodes of `m`, counted into `r`; with
// `shared`, the nodes it marks are not counted but handed out with their verdict (their
// phases in other pieces decide whether they are interface nodes).
template <int Dim>
void check_mesh_fidelity(const mesh::SimplexMesh<Dim>& m, const geometry::Oracle<Dim>& oracle, double tol,
                         double strict_tol, const std::vector<bool>* shared,
                         std::vector<std::pair<LocalId, NodeVerdict>>* shared_verdicts, FidelityReport& r);

// Counts a node's verdict (by its mask: one phase or an interface); `name` names it in examples.
template <int Dim>
void count_node(FidelityReport& r, const geometry::SceneDesc& scene, const NodeVerdict& v, double tol,
                const std::string& name);

// The nodes of open facets inside the domain must lie on a void.
template <int Dim>
void check_void_boundary_nodes(const mesh::SimplexMesh<Dim>& m, std::span<const LocalId> boundary_nodes,
                               const geometry::Oracle<Dim>& oracle, double tol, FidelityReport& r);

// Relative measure errors and the verdict.
template <int Dim>
void finish_fidelity(const geometry::SceneDesc& scene, FidelityReport& r);

}  // namespace cisamr::quality::detail
