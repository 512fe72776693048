#pragma once
// The overlap check of the oracle at construction (private to lib/geometry).
#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

#include "core/error.hpp"
#include "geometry/box_index.hpp"
#include "geometry/scene.hpp"

namespace cisamr::geometry::detail {

// Throws InputError when inclusions of different phases overlap; otherwise sets
// items[k].group to the smallest id of k's group of same-phase inclusions whose closed
// regions meet (union–find). Impl is Oracle<Dim>::Impl: it has `items`,
// `boxes`, `scene` and regions_intersect(i, j, interiors).
template <class Impl>
void group_overlapping_inclusions(Impl& m) {
  const auto pairs = overlapping_box_pairs(m.boxes);
  std::vector<std::int32_t> parent(m.items.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (auto [i, j] : pairs) {
    if (m.items[i].phase != m.items[j].phase) {
      if (m.regions_intersect(i, j, true))
        throw InputError(m.scene.source, inclusion_field(m.scene, m.scene.listed(static_cast<std::size_t>(j))),
                         (m.scene.listed(static_cast<std::size_t>(j)) == static_cast<std::size_t>(j)
                              ? std::string("overlaps ")
                              : inclusion_name(m.scene, static_cast<std::size_t>(j)) + " overlaps ") +
                             inclusion_name(m.scene, static_cast<std::size_t>(i)) + ", which has a different phase");
    } else if (m.regions_intersect(i, j, false)) {
      const std::int32_t ri = find(i), rj = find(j);
      if (ri != rj) parent[std::max(ri, rj)] = std::min(ri, rj);
    }
  }
  for (std::size_t k = 0; k < m.items.size(); ++k) m.items[k].group = find(static_cast<std::int32_t>(k));
}

}  // namespace cisamr::geometry::detail
