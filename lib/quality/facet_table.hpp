#pragma once
// Internal to lib/quality: the facets of a simplex mesh grouped by their node set.
// Facet f of a cell is the one opposite local vertex f, listed with the orientation it
// inherits from a positively oriented cell (outward normal in 3D, counter-clockwise
// boundary in 2D). Two properly oriented neighbours list their shared facet with opposite
// parity.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/types.hpp"
#include "mesh/boundary.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::quality::detail {

// The one table of facet vertices (mesh/boundary.hpp), which the writers' boundary sets use.
template <int Dim>
using FacetTable = mesh::FacetVertices<Dim>;

// One occurrence of a facet: which cell, which local facet, and whether its listed order
// is an odd permutation of the ascending one.
struct FacetUse {
  std::size_t cell = 0;
  int local = 0;
  bool odd = false;
};

template <int Dim>
using FacetNodes = std::array<LocalId, Dim>;  // ascending

// The facet's nodes, ascending, and the parity of the permutation that sorted them.
template <int Dim>
inline FacetNodes<Dim> sorted_facet(const LocalId* cell_nodes, int f, bool& odd) {
  FacetNodes<Dim> v;
  for (int k = 0; k < Dim; ++k) v[k] = cell_nodes[FacetTable<Dim>::local[f][k]];
  odd = false;
  for (int i = 0; i < Dim; ++i)  // insertion sort, counting swaps
    for (int j = i; j > 0 && v[j - 1] > v[j]; --j) {
      std::swap(v[j - 1], v[j]);
      odd = !odd;
    }
  return v;
}

// Calls visit(nodes, std::span<const FacetUse>) once per distinct facet (node set) of the
// cells whose node ids are all in [0, node_count) (`valid_cell`), in ascending order of
// the facet's nodes. Linear: a counting sort by smallest node, then a small sort inside
// each bucket. Memory: one index per facet occurrence.
// The smallest node of facet f (the cell's nodes but local vertex f): its bucket.
template <int Dim>
inline LocalId facet_min(const LocalId* cell_nodes, int f) {
  LocalId m = cell_nodes[f == 0 ? 1 : 0];
  for (int k = 0; k <= Dim; ++k)
    if (k != f) m = std::min(m, cell_nodes[k]);
  return m;
}

template <int Dim, class CellIndex, class Visit>
void for_each_facet_impl(const mesh::SimplexMesh<Dim>& m, const std::vector<bool>& valid_cell,
                         Visit&& visit) {
  constexpr int F = Dim + 1;
  const std::size_t nodes = m.node_count(), cells = m.cell_count();
  std::vector<std::size_t> offset(nodes + 1, 0);
  for (std::size_t c = 0; c < cells; ++c)
    if (valid_cell[c])
      for (int f = 0; f < F; ++f) ++offset[std::size_t(facet_min<Dim>(m.cell(c), f)) + 1];
  for (std::size_t n = 0; n < nodes; ++n) offset[n + 1] += offset[n];
  std::vector<CellIndex> bucket(offset[nodes]);
  {
    std::vector<std::size_t> fill(offset.begin(), offset.end() - 1);
    for (std::size_t c = 0; c < cells; ++c)
      if (valid_cell[c])
        for (int f = 0; f < F; ++f)
          bucket[fill[std::size_t(facet_min<Dim>(m.cell(c), f))]++] = static_cast<CellIndex>(c * F + f);
  }
  // Within a bucket the first node is the same: the others, packed in one word, order the
  // facets (node ids are valid, so non-negative), then the occurrence.
  struct Entry {
    std::uint64_t rest;
    std::size_t occurrence;  // cell · F + local facet
    FacetNodes<Dim> nodes;
    bool odd;
  };
  std::vector<Entry> entries;
  std::vector<FacetUse> uses;
  for (std::size_t n = 0; n < nodes; ++n) {
    entries.clear();
    for (std::size_t i = offset[n]; i < offset[n + 1]; ++i) {
      Entry e;
      e.occurrence = bucket[i];
      e.nodes = sorted_facet<Dim>(m.cell(e.occurrence / F), static_cast<int>(e.occurrence % F), e.odd);
      e.rest = Dim == 2 ? std::uint64_t(std::uint32_t(e.nodes[Dim - 1]))
                        : std::uint64_t(std::uint32_t(e.nodes[1])) << 32 | std::uint32_t(e.nodes[Dim - 1]);
      entries.push_back(e);
    }
    std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
      return a.rest != b.rest ? a.rest < b.rest : a.occurrence < b.occurrence;
    });
    for (std::size_t i = 0; i < entries.size();) {
      std::size_t j = i;
      uses.clear();
      while (j < entries.size() && entries[j].rest == entries[i].rest) {
        const Entry& e = entries[j++];
        uses.push_back(FacetUse{e.occurrence / F, static_cast<int>(e.occurrence % F), e.odd});
      }
      visit(entries[i].nodes, std::span<const FacetUse>(uses));
      i = j;
    }
  }
}

template <int Dim, class Visit>
void for_each_facet(const mesh::SimplexMesh<Dim>& m, const std::vector<bool>& valid_cell,
                    Visit&& visit) {
  if (m.cell_count() * (Dim + 1) <= 0xffffffffull)
    for_each_facet_impl<Dim, std::uint32_t>(m, valid_cell, visit);
  else
    for_each_facet_impl<Dim, std::uint64_t>(m, valid_cell, visit);
}

// Cells whose node ids are all in range.
template <int Dim>
inline std::vector<bool> valid_cells(const mesh::SimplexMesh<Dim>& m) {
  std::vector<bool> valid(m.cell_count(), true);
  const auto nodes = static_cast<std::size_t>(m.node_count());
  for (std::size_t c = 0; c < m.cell_count(); ++c)
    for (int k = 0; k <= Dim; ++k)
      if (m.cell(c)[k] < 0 || static_cast<std::size_t>(m.cell(c)[k]) >= nodes) valid[c] = false;
  return valid;
}

// Whether the facet lies on a face of the box (all its nodes within tol of one plane).
template <int Dim>
inline bool facet_on_box(const mesh::SimplexMesh<Dim>& m, const FacetNodes<Dim>& nodes,
                         const Box<Dim>& box, double tol) {
  for (int d = 0; d < Dim; ++d) {
    bool on_min = true, on_max = true;
    for (LocalId n : nodes) {
      const double x = m.coords[static_cast<std::size_t>(n) * Dim + d];
      on_min = on_min && std::abs(x - box.min[d]) <= tol;
      on_max = on_max && std::abs(x - box.max[d]) <= tol;
    }
    if (on_min || on_max) return true;
  }
  return false;
}

// Open facets (used by exactly one cell) that do not lie on the box.
template <int Dim>
inline std::vector<FacetNodes<Dim>> open_facets_inside_box(const mesh::SimplexMesh<Dim>& m,
                                                           const Box<Dim>& box, double tol) {
  std::vector<FacetNodes<Dim>> open;
  for_each_facet<Dim>(m, valid_cells(m), [&](const FacetNodes<Dim>& nodes, std::span<const FacetUse> uses) {
    if (uses.size() == 1 && !facet_on_box<Dim>(m, nodes, box, tol)) open.push_back(nodes);
  });
  return open;
}

// The nodes of those facets, ascending, each once (the nodes on void interfaces).
template <int Dim>
inline std::vector<LocalId> open_facet_nodes_inside_box(const mesh::SimplexMesh<Dim>& m, const Box<Dim>& box,
                                                        double tol) {
  std::vector<LocalId> nodes;
  for (const auto& f : open_facets_inside_box<Dim>(m, box, tol)) nodes.insert(nodes.end(), f.begin(), f.end());
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return nodes;
}

}  // namespace cisamr::quality::detail
