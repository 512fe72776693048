#pragma once
// Which nodes and facets of a mesh lie on the faces of its domain box: the boundary sets
// every writer emits (DESIGN.md §7). Membership is exact, never within a tolerance: a node
// is on a face when its coordinate equals the face's coordinate bit for bit. That holds for
// the mesher's output because every node on a face gets the one coordinate the lattice gives
// that face (grid::Lattice::coordinate of the face's lattice index), interface points on a face are interpolated between two
// nodes of that face, and r-adaptivity only slides boundary nodes within their face.
#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "core/types.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::mesh {

// Box faces in the order XMIN, XMAX, YMIN, YMAX, ZMIN, ZMAX: face 2·axis + (1 on the max
// side). Medit references are face + 1, the VTU `boundary` bit is 1 << face.
inline constexpr std::array<std::string_view, 6> kBoxFaceNames = {"XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"};
constexpr int box_face_count(int dim) { return 2 * dim; }

// Local vertices of facet f of a cell (the facet opposite local vertex f), in the order that
// gives a positively oriented cell's facet its outward orientation: counter-clockwise along
// the boundary in 2D, outward normal by the right-hand rule in 3D.
template <int Dim>
struct FacetVertices;
template <>
struct FacetVertices<2> {
  static constexpr int local[3][2] = {{1, 2}, {2, 0}, {0, 1}};
};
template <>
struct FacetVertices<3> {
  static constexpr int local[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
};

// One facet of a cell: the one opposite local vertex `opposite`.
struct CellFacet {
  std::int64_t cell = 0;
  int opposite = 0;
};

template <int Dim>
struct BoundarySets {
  std::vector<std::uint8_t> node_faces;  // per node: bit f set when the node lies on face f
  // Per face: the cell facets whose nodes all lie on it, in cell order. Such a facet is
  // used by one cell only (a cell across it would leave the box).
  std::array<std::vector<CellFacet>, 2 * Dim> facets;
  LocalId corner0 = -1;  // the node at the box's min corner; -1 when none (a void covers it)
};

// The sets of `m` for the box whose faces lie at `faces.min[d]` and `faces.max[d]`: these
// must be the exact coordinates the nodes on the faces have (driver::face_box for a mesh
// of a scene). Works on a piece of a mesh as well (the pieces' sets are the whole mesh's,
// restricted).
template <int Dim>
BoundarySets<Dim> boundary_sets(const SimplexMesh<Dim>& m, const Box<Dim>& faces);

// The smallest box holding every node: the face box of a mesh whose every face carries a
// node (true of any mesh whose voids leave a piece of each face uncovered).
template <int Dim>
Box<Dim> bounding_box(const SimplexMesh<Dim>& m);

}  // namespace cisamr::mesh
