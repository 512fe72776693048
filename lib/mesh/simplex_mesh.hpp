#pragma once
// The flat simplex mesh (structure of arrays): the output of the mesher and the input of
// writers and checks. Triangles in 2D, tetrahedra in 3D, positively oriented.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace cisamr::mesh {

template <int Dim>
struct SimplexMesh {
  static constexpr int dim = Dim;
  static constexpr int nodes_per_cell = Dim + 1;

  std::vector<double> coords;            // Dim per node
  std::vector<LocalId> cell_nodes;       // Dim+1 per cell, positive orientation
  std::vector<std::int32_t> cell_phase;  // phase id (as in the scene), per cell
  std::vector<std::int32_t> cell_partition;  // partition that produced the cell (0 if one)
  std::vector<GlobalId> node_global_id;  // per node

  std::size_t node_count() const { return coords.size() / Dim; }
  std::size_t cell_count() const { return cell_phase.size(); }
  Vec<Dim> point(LocalId n) const {
    Vec<Dim> p;
    for (int d = 0; d < Dim; ++d) p[d] = coords[static_cast<std::size_t>(n) * Dim + d];
    return p;
  }
  const LocalId* cell(std::size_t c) const { return &cell_nodes[c * (Dim + 1)]; }
};

using Mesh2 = SimplexMesh<2>;
using Mesh3 = SimplexMesh<3>;

}  // namespace cisamr::mesh
