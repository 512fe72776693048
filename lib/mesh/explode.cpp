// The exploded view of a cohesive mesh (explode.hpp).
#include "mesh/explode.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "mesh/metrics.hpp"

namespace cisamr::mesh {
namespace {

// The root of n's component, halving the path on the way.
LocalId find_root(std::vector<LocalId>& parent, LocalId n) {
  while (parent[n] != n) {
    parent[n] = parent[parent[n]];
    n = parent[n];
  }
  return n;
}

template <int Dim>
double cell_measure(const SimplexMesh<Dim>& m, std::size_t c) {
  const LocalId* v = m.cell(c);
  if constexpr (Dim == 2)
    return std::abs(signed_area(m.point(v[0]), m.point(v[1]), m.point(v[2])));
  else
    return std::abs(signed_volume(m.point(v[0]), m.point(v[1]), m.point(v[2]), m.point(v[3])));
}

}  // namespace

template <int Dim>
std::vector<double> exploded_coords(const SimplexMesh<Dim>& m, double factor) {
  std::vector<double> coords = m.coords;
  const std::size_t nodes = m.node_count(), cells = m.cell_count();
  if (cells == 0 || factor == 1) return coords;
  std::vector<LocalId> parent(nodes);
  std::iota(parent.begin(), parent.end(), LocalId{0});
  for (std::size_t c = 0; c < cells; ++c)
    for (int k = 1; k <= Dim; ++k) {
      const LocalId a = find_root(parent, m.cell(c)[0]), b = find_root(parent, m.cell(c)[k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the lowest node names the region
    }
  // Per region (indexed by its root node): measure and measure-weighted centroid sums.
  std::vector<double> measure(nodes, 0.0), moment(nodes * Dim, 0.0);
  double total = 0;
  Vec<Dim> domain_moment{};
  for (std::size_t c = 0; c < cells; ++c) {
    const double w = cell_measure(m, c);
    const auto root = static_cast<std::size_t>(find_root(parent, m.cell(c)[0]));
    measure[root] += w;
    total += w;
    for (int d = 0; d < Dim; ++d) {
      double centroid = 0;
      for (int k = 0; k <= Dim; ++k) centroid += m.point(m.cell(c)[k])[d];
      centroid /= Dim + 1;
      moment[root * Dim + d] += w * centroid;
      domain_moment[d] += w * centroid;
    }
  }
  if (!(total > 0)) return coords;  // only degenerate cells: no centre to move away from
  std::vector<bool> in_cell(nodes, false);
  for (const LocalId n : m.cell_nodes) in_cell[static_cast<std::size_t>(n)] = true;
  for (std::size_t n = 0; n < nodes; ++n) {
    if (!in_cell[n]) continue;
    const auto root = static_cast<std::size_t>(find_root(parent, static_cast<LocalId>(n)));
    if (!(measure[root] > 0)) continue;  // a region of degenerate cells has no centroid
    for (int d = 0; d < Dim; ++d)
      coords[n * Dim + d] += (factor - 1) * (moment[root * Dim + d] / measure[root] - domain_moment[d] / total);
  }
  return coords;
}

template std::vector<double> exploded_coords<2>(const SimplexMesh<2>&, double);
template std::vector<double> exploded_coords<3>(const SimplexMesh<3>&, double);

}  // namespace cisamr::mesh
