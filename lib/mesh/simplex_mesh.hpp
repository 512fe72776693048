#pragma once
// The flat simplex mesh (structure of arrays): the output of the mesher and the input of
// writers and checks. Triangles in 2D, tetrahedra in 3D, positively oriented.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace cisamr::mesh {

// Zero-thickness cohesive cells on the interfaces between phases (issue #13,
// docs/cohesive-design.md): per cell the bottom facet's Dim nodes, then the top facet's, top
// node k at bottom node k's position. The bottom nodes belong to the lower phase id, the
// top ones to the other phase; the right-hand normal of the bottom facet (3D: b0 b1 b2; 2D:
// b0→b1 turned by +90°) points to the top side. Writers permute to their formats' orders
// (mesh/cohesive.hpp). Empty unless cohesive cells were asked for.
template <int Dim>
struct CohesiveCells {
  static constexpr int nodes_per_cell = 2 * Dim;
  std::vector<LocalId> nodes;             // 2·Dim per cell: b0..b(Dim-1), t0..t(Dim-1)
  std::vector<std::int32_t> phase;        // 2 per cell: bottom (the lower id), top
  std::vector<std::int32_t> partition;    // the partition that made the cell
  std::size_t count() const { return partition.size(); }
  const LocalId* cell(std::size_t c) const { return &nodes[c * 2 * Dim]; }
};

template <int Dim>
struct SimplexMesh {
  static constexpr int dim = Dim;
  static constexpr int nodes_per_cell = Dim + 1;

  std::vector<double> coords;            // Dim per node
  std::vector<LocalId> cell_nodes;       // Dim+1 per cell, positive orientation
  std::vector<std::int32_t> cell_phase;  // phase id (as in the scene), per cell
  std::vector<std::int32_t> cell_partition;  // partition that produced the cell (0 if one)
  std::vector<GlobalId> node_global_id;  // per node
  // With cohesive cells: every interface node is split into one copy per phase of the bulk
  // cells around it (bit-equal coordinates); node_phase gives each node's phase id.
  CohesiveCells<Dim> cohesive;
  std::vector<std::int32_t> node_phase;  // per node, or empty (no cohesive cells)

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
