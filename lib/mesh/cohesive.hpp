#pragma once
// Cohesive interface elements (issue #13, docs/cohesive-design.md): the interface nodes of
// a mesh split into one copy per phase, one zero-thickness cell per facet between bulk
// cells of two different phases, and the node orders the file formats use.
//
// Conventions (SimplexMesh::cohesive): bottom b0..b(Dim-1) on the lower phase id, top
// t0..t(Dim-1) on the other, t_k at b_k's position; the right-hand normal of the bottom
// (3D: (b1-b0)×(b2-b0); 2D: b1-b0 turned by +90°) points into the top phase, so an Abaqus
// *COHESIVE SECTION needs no STACK DIRECTION and no per-element fix.
#include <array>
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::mesh {

// File orders: position i of an element in the file holds internal node order[i]
// (internal: b0 b1 [b2] t0 t1 [t2]).
//   Abaqus COH2D4: bottom edge 1-2, top edge 3-4 with 4 over 1 and 3 over 2.
//   Abaqus COH3D6: bottom 1-2-3, top 4-5-6, node k+3 over node k.
//   Gmsh quadrangle (3) / prism (6): the same as Abaqus.
//   VTK quad (9): the same; VTK wedge (13): (0,1,2) is a base whose normal points away from
//   (3,4,5), so both triangles are reversed.
template <int Dim>
struct CohesiveOrder;
template <>
struct CohesiveOrder<2> {
  static constexpr std::array<int, 4> abaqus = {0, 1, 3, 2};
  static constexpr std::array<int, 4> gmsh = {0, 1, 3, 2};
  static constexpr std::array<int, 4> vtk = {0, 1, 3, 2};
  static constexpr int vtk_type = 9;    // VTK_QUAD
  static constexpr int gmsh_type = 3;   // 4-node quadrangle
  static constexpr const char* abaqus_type = "COH2D4";
};
template <>
struct CohesiveOrder<3> {
  static constexpr std::array<int, 6> abaqus = {0, 1, 2, 3, 4, 5};
  static constexpr std::array<int, 6> gmsh = {0, 1, 2, 3, 4, 5};
  static constexpr std::array<int, 6> vtk = {0, 2, 1, 3, 5, 4};
  static constexpr int vtk_type = 13;   // VTK_WEDGE
  static constexpr int gmsh_type = 6;   // 6-node prism
  static constexpr const char* abaqus_type = "COH3D6";
};

struct CohesiveCounts {
  std::int64_t cells = 0;         // cohesive cells inserted
  std::int64_t copies = 0;        // nodes added (a node of k phases gains k - 1)
};

// Splits every node that bulk cells of several phases share into one copy per phase
// (coordinates copied bit for bit; the node keeps the phase of the first cell using it, in
// cell order, and the copies are appended in (node, phase) order), sets node_phase, and
// inserts one cohesive cell per facet whose two cells have different phases, in the order
// of their facets' sorted node ids, with `partition` as their partition. Needs a conforming
// mesh whose every interface facet has both its cells (a whole mesh). Phases meeting only
// at a node or an edge get their copies and no cell; void regions have no cells, so they
// get neither. Returns, per node of the result, the node it was copied from (itself for
// the original nodes). A mesh that already has cohesive cells is an error (std::logic_error).
template <int Dim>
std::vector<LocalId> insert_cohesive(SimplexMesh<Dim>& m, std::int32_t partition, CohesiveCounts* counts = nullptr);

// The facet opposite local vertex `opposite` of bulk cell `cell`, in an order whose
// right-hand normal points away from that cell when the cell is the upper side and into it
// when it is the lower side: the order of a cohesive cell's bottom in that cell's node ids
// (exact: from the positively oriented cell's vertex order, no floating-point normal).
template <int Dim>
std::array<LocalId, Dim> cohesive_facet_order(const SimplexMesh<Dim>& m, std::size_t cell, int opposite, bool cell_is_lower);

// Appends one cohesive cell, t_k over b_k. In 3D the three pairs are rotated so that the
// bottom node with the smallest coordinates comes first (orientation kept): a cell then
// reads the same whichever side or partition made it.
template <int Dim>
void append_cohesive_cell(SimplexMesh<Dim>& m, std::array<LocalId, Dim> bottom, std::array<LocalId, Dim> top,
                          std::int32_t lower_phase, std::int32_t upper_phase, std::int32_t partition);

}  // namespace cisamr::mesh
