#pragma once
// The independent checker of cohesive meshes (issue #13, docs/cohesive-design.md §6.2).
// It shares no code with the insertion (lib/mesh/cohesive.*): it welds the copies back by
// exact coordinates and checks the rules of mesh::CohesiveCells against the welded bulk
// mesh. Non-periodic meshes. No tolerance: positions are compared bit for bit (−0 as +0,
// the one rule the weld and every check here use), and the orientation signs come from
// bulk cells that check_conformity requires to be far from degenerate.
#include <cstddef>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::quality {

// The bulk cells of a mesh with every set of bit-equal nodes merged into one, so that the
// checks of certify (conformity, fidelity, aspect) run unchanged on a cohesive mesh.
// Welded node w is the class of nodes at one position, numbered in order of its lowest
// node id and placed at that node's coordinates: a mesh without coincident nodes welds to
// itself, and a mesh whose copies were appended after the original nodes welds to the
// unsplit mesh. Cells keep their index, phase and partition; a node id out of range
// becomes -1 (check_conformity reports it). No cohesive cells, node_phase empty.
template <int Dim>
struct WeldedMesh {
  mesh::SimplexMesh<Dim> mesh;
  std::vector<LocalId> class_of;  // per node of the input: its welded node
};

template <int Dim>
WeldedMesh<Dim> weld_view(const mesh::SimplexMesh<Dim>& m);

inline constexpr std::size_t kCohesiveExamples = 8;

// One kind of failure: how many, and the first few (deterministic order) with a point to
// find them at.
template <int Dim>
struct CohesiveFinding {
  std::size_t count = 0;
  std::vector<std::int64_t> ids;  // node, cohesive cell or bulk cell id (see the field)
  std::vector<Vec<Dim>> points;   // per id: the node, or the centroid of the facet
  void add(std::int64_t id, const Vec<Dim>& at) {
    if (count++ < kCohesiveExamples) {
      ids.push_back(id);
      points.push_back(at);
    }
  }
};

template <int Dim>
struct CohesiveReport {
  std::size_t cohesive_cells = 0;
  // Welded facets shared by two bulk cells of different phases: each needs one cohesive
  // cell.
  std::size_t interface_facets = 0;

  // Cohesive cells with missing array entries or node ids out of range (skipped by the
  // checks below); id -1 for extra entries in the arrays. Ids: cohesive cells.
  CohesiveFinding<Dim> malformed;
  // Nodes used by bulk cells of two or more phases: the phases' bulk meshes must share no
  // node id. Ids: nodes.
  CohesiveFinding<Dim> phase_mixed_nodes;
  // Nodes at the position of a lower-numbered node that cells of the same phase use too:
  // a crack inside a phase. Ids: the higher node.
  CohesiveFinding<Dim> duplicate_copies;
  // Interface facets that are the welded bottom of no cohesive cell, and of two or more.
  // Ids: the lower-phase bulk cell; points: the facet's centroid.
  CohesiveFinding<Dim> uncovered;
  CohesiveFinding<Dim> covered_twice;
  // Cohesive cells whose welded bottom is not a facet between two bulk cells of its two
  // phases: a same-phase facet, a boundary or void facet, a non-manifold one, no facet.
  // Ids of this and the three below: cohesive cells; points: the bottom's centroid.
  CohesiveFinding<Dim> misplaced;
  // Top node k not at bottom node k's position.
  CohesiveFinding<Dim> not_coincident;
  // Phases not ordered (phase[0] must be the lower one), or bottom ids other than the
  // lower-phase cell's nodes on the facet, or top ids other than the other cell's.
  CohesiveFinding<Dim> wrong_sides;
  // Not orient(b, apex of the upper cell) > 0 and orient(b, apex of the lower cell) < 0,
  // orient(b, x) = det[b1 − b0, (b2 − b0,) x − b0]: the bottom's right-hand normal must
  // point to the top phase (mesh::CohesiveCells).
  CohesiveFinding<Dim> wrong_orientation;
  // With node_phase set: nodes whose node_phase is not the phase of their bulk cells
  // (nodes of no bulk cell and phase-mixed nodes are not judged here), or the array has
  // the wrong size (each missing or extra entry counts, id -1). Ids: nodes.
  CohesiveFinding<Dim> node_phase_mismatch;

  bool ok() const {
    return malformed.count + phase_mixed_nodes.count + duplicate_copies.count + uncovered.count +
               covered_twice.count + misplaced.count + not_coincident.count + wrong_sides.count +
               wrong_orientation.count + node_phase_mismatch.count ==
           0;
  }
  // One line: "cohesive: 3 cells on 3 interface facets; every interface facet covered
  // once" or the counts that fail.
  std::string summary() const;
};

// A periodic mesh's frame: the exact coordinates of its faces and its periodic axes.
template <int Dim>
struct CohesivePeriodicity {
  Box<Dim> faces;
  std::array<bool, Dim> axes{};
};

// Checks the cohesive cells and the node copies of a mesh (any mesh: one without cohesive
// cells passes when no two phases meet). O(n log n) in the mesh size: one sort of the nodes
// by position, the facet table of the welded mesh, one sort of the cohesive cells by their
// welded bottom.
//
// With `periodic`, facets are also matched across the periodic planes: a node on a max face
// is welded with its translate on the min face (the max-face coordinate replaced by the
// min face's, exactly), so a facet on a periodic plane has a cell on each side and is an
// interface when their phases differ. Its cohesive cell must sit at one side's facet
// (that side's node ids, as everywhere) with, for the cell across the plane, the copies of
// that cell's phase at the translates of its facet nodes (its periodic masters; node_phase
// says a copy's phase when no bulk cell uses it); the orientation rule uses that cell's apex
// moved back by the period.
template <int Dim>
CohesiveReport<Dim> check_cohesive(const mesh::SimplexMesh<Dim>& m, const CohesivePeriodicity<Dim>* periodic = nullptr);

}  // namespace cisamr::quality
