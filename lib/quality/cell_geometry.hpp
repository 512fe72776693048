#pragma once
// Internal to lib/quality: measures of a cell shared by the conformity and fidelity checks.
#include <algorithm>
#include <array>

#include "core/types.hpp"
#include "mesh/metrics.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::quality::detail {

// Signed area (2D) or volume (3D) of the simplex on nodes n[0..Dim].
template <int Dim>
inline double signed_measure(const mesh::SimplexMesh<Dim>& m, const LocalId* n) {
  if constexpr (Dim == 2)
    return mesh::signed_area(m.point(n[0]), m.point(n[1]), m.point(n[2]));
  else
    return mesh::signed_volume(m.point(n[0]), m.point(n[1]), m.point(n[2]), m.point(n[3]));
}

// Longest distance between two of the `count` nodes n[0..count).
template <int Dim>
inline double longest_edge(const mesh::SimplexMesh<Dim>& m, const LocalId* n, int count) {
  double l = 0;
  for (int i = 0; i < count; ++i)
    for (int j = i + 1; j < count; ++j) l = std::max(l, mesh::distance<Dim>(m.point(n[i]), m.point(n[j])));
  return l;
}

// Mean of the cell's vertices, summed in local order.
template <int Dim>
inline Vec<Dim> centroid(const mesh::SimplexMesh<Dim>& m, const LocalId* n) {
  Vec<Dim> g = m.point(n[0]);
  for (int k = 1; k <= Dim; ++k)
    for (int d = 0; d < Dim; ++d) g[d] += m.point(n[k])[d];
  for (int d = 0; d < Dim; ++d) g[d] /= Dim + 1;
  return g;
}

}  // namespace cisamr::quality::detail
