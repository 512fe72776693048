#include "mesh/boundary.hpp"

#include <algorithm>
#include <bit>
#include <limits>

namespace cisamr::mesh {

template <int Dim>
BoundarySets<Dim> boundary_sets(const SimplexMesh<Dim>& m, const Box<Dim>& faces) {
  BoundarySets<Dim> sets;
  const std::size_t nodes = m.node_count(), cells = m.cell_count();
  sets.node_faces.assign(nodes, 0);
  constexpr std::uint8_t kMinCorner = Dim == 2 ? 0b0101 : 0b010101;
  for (std::size_t n = 0; n < nodes; ++n) {
    std::uint8_t bits = 0;
    for (int d = 0; d < Dim; ++d) {
      const double x = m.coords[n * Dim + static_cast<std::size_t>(d)];
      if (x == faces.min[d]) bits |= std::uint8_t(1u << (2 * d));
      if (x == faces.max[d]) bits |= std::uint8_t(1u << (2 * d + 1));
    }
    sets.node_faces[n] = bits;
    if ((bits & kMinCorner) == kMinCorner) sets.corner0 = static_cast<LocalId>(n);
  }
  for (std::size_t c = 0; c < cells; ++c) {
    const LocalId* corners = m.cell(c);
    for (int f = 0; f <= Dim; ++f) {
      unsigned common = 0xff;
      for (int k = 0; k < Dim; ++k)
        common &= sets.node_faces[static_cast<std::size_t>(corners[FacetVertices<Dim>::local[f][k]])];
      // A facet of a non-degenerate cell spans Dim-1 directions: at most one face holds it.
      for (; common != 0; common &= common - 1)
        sets.facets[static_cast<std::size_t>(std::countr_zero(common))].push_back({static_cast<std::int64_t>(c), f});
    }
  }
  return sets;
}

template <int Dim>
Box<Dim> bounding_box(const SimplexMesh<Dim>& m) {
  Box<Dim> box;
  box.min.fill(std::numeric_limits<double>::infinity());
  box.max.fill(-std::numeric_limits<double>::infinity());
  for (std::size_t n = 0; n < m.node_count(); ++n)
    for (int d = 0; d < Dim; ++d) {
      const double x = m.coords[n * Dim + static_cast<std::size_t>(d)];
      box.min[d] = std::min(box.min[d], x);
      box.max[d] = std::max(box.max[d], x);
    }
  return box;
}

template BoundarySets<2> boundary_sets<2>(const SimplexMesh<2>&, const Box<2>&);
template BoundarySets<3> boundary_sets<3>(const SimplexMesh<3>&, const Box<3>&);
template Box<2> bounding_box<2>(const SimplexMesh<2>&);
template Box<3> bounding_box<3>(const SimplexMesh<3>&);

}  // namespace cisamr::mesh
