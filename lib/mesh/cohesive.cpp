#include "mesh/cohesive.hpp"

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <tuple>

#include "mesh/boundary.hpp"

namespace cisamr::mesh {
namespace {

constexpr std::int32_t kNoPhase = std::numeric_limits<std::int32_t>::min();

// A corner whose cell's phase is not its node's first phase: it gets the node's copy for
// that phase.
struct CopyNeed {
  LocalId node;
  std::int32_t phase;
  std::int64_t corner;  // index into cell_nodes
  auto operator<=>(const CopyNeed&) const = default;
};

// A facet of a cell all of whose nodes are split, named by its nodes' original ids, sorted.
template <int Dim>
struct InterfaceFacet {
  std::array<LocalId, Dim> key;
  std::int64_t cell;
  int opposite;
  auto operator<=>(const InterfaceFacet&) const = default;
};

}  // namespace

template <int Dim>
std::vector<LocalId> insert_cohesive(SimplexMesh<Dim>& m, std::int32_t partition, CohesiveCounts* counts) {
  constexpr int K = Dim + 1;
  if (m.cohesive.count() > 0 || !m.node_phase.empty())
    throw std::logic_error("insert_cohesive: the mesh already has cohesive cells");
  const std::size_t nodes = m.node_count(), cells = m.cell_count();

  // Each node keeps the phase of its first cell; other phases' corners need copies.
  std::vector<std::int32_t> first_phase(nodes, kNoPhase);
  std::vector<CopyNeed> needs;
  for (std::size_t c = 0; c < cells; ++c)
    for (int k = 0; k < K; ++k) {
      const std::int64_t corner = static_cast<std::int64_t>(c) * K + k;
      const LocalId n = m.cell_nodes[static_cast<std::size_t>(corner)];
      std::int32_t& first = first_phase[static_cast<std::size_t>(n)];
      if (first == kNoPhase) first = m.cell_phase[c];
      else if (first != m.cell_phase[c]) needs.push_back({n, m.cell_phase[c], corner});
    }
  std::sort(needs.begin(), needs.end());

  std::vector<LocalId> origin(nodes);
  std::iota(origin.begin(), origin.end(), LocalId{0});
  m.node_phase.assign(first_phase.begin(), first_phase.end());
  for (std::int32_t& p : m.node_phase)
    if (p == kNoPhase) p = 0;  // a node no cell uses (none in the mesher's output)
  std::vector<char> split(nodes, 0);
  LocalId copy = -1;
  for (std::size_t i = 0; i < needs.size(); ++i) {
    const CopyNeed& need = needs[i];
    if (i == 0 || need.node != needs[i - 1].node || need.phase != needs[i - 1].phase) {
      copy = static_cast<LocalId>(m.node_count());
      for (int d = 0; d < Dim; ++d) m.coords.push_back(m.coords[static_cast<std::size_t>(need.node) * Dim + d]);
      m.node_phase.push_back(need.phase);
      origin.push_back(need.node);
      if (!m.node_global_id.empty()) m.node_global_id.push_back(copy);  // one process: id = index
      split[static_cast<std::size_t>(need.node)] = 1;
    }
    m.cell_nodes[static_cast<std::size_t>(need.corner)] = copy;
  }

  // Facets whose every node is split, paired by their original node ids. In a conforming
  // mesh a facet has one or two cells; two of different phases make a cohesive cell.
  std::vector<InterfaceFacet<Dim>> facets;
  for (std::size_t c = 0; c < cells; ++c)
    for (int f = 0; f < K; ++f) {
      InterfaceFacet<Dim> facet{{}, static_cast<std::int64_t>(c), f};
      bool all_split = true;
      for (int k = 0; k < Dim && all_split; ++k) {
        const LocalId o = origin[static_cast<std::size_t>(m.cell_nodes[c * K + FacetVertices<Dim>::local[f][k]])];
        all_split = split[static_cast<std::size_t>(o)] != 0;
        facet.key[static_cast<std::size_t>(k)] = o;
      }
      if (!all_split) continue;
      std::sort(facet.key.begin(), facet.key.end());
      facets.push_back(facet);
    }
  std::sort(facets.begin(), facets.end());

  std::int64_t inserted = 0;
  for (std::size_t i = 0; i < facets.size();) {
    std::size_t j = i + 1;
    while (j < facets.size() && facets[j].key == facets[i].key) ++j;
    if (j - i > 2) throw std::logic_error("insert_cohesive: a facet shared by more than two cells");
    if (j - i == 2) {
      const InterfaceFacet<Dim>* lower = &facets[i];
      const InterfaceFacet<Dim>* upper = &facets[i + 1];
      std::int32_t p = m.cell_phase[static_cast<std::size_t>(lower->cell)];
      std::int32_t q = m.cell_phase[static_cast<std::size_t>(upper->cell)];
      if (p > q) std::swap(lower, upper), std::swap(p, q);
      if (p != q) {
        const std::array<LocalId, Dim> bottom =
            cohesive_facet_order<Dim>(m, static_cast<std::size_t>(lower->cell), lower->opposite, true);
        const LocalId* uc = &m.cell_nodes[static_cast<std::size_t>(upper->cell) * K];
        std::array<LocalId, Dim> top;
        for (int k = 0; k < Dim; ++k) {
          const LocalId b = bottom[static_cast<std::size_t>(k)];
          for (int u_k = 0; u_k < Dim; ++u_k) {
            const LocalId u = uc[FacetVertices<Dim>::local[upper->opposite][u_k]];
            if (origin[static_cast<std::size_t>(u)] == origin[static_cast<std::size_t>(b)]) top[static_cast<std::size_t>(k)] = u;
          }
        }
        append_cohesive_cell<Dim>(m, bottom, top, p, q, partition);
        ++inserted;
      }
    }
    i = j;
  }
  if (counts != nullptr) {
    counts->cells += inserted;
    counts->copies += static_cast<std::int64_t>(m.node_count() - nodes);
  }
  return origin;
}

template <int Dim>
std::array<LocalId, Dim> cohesive_facet_order(const SimplexMesh<Dim>& m, std::size_t cell, int opposite, bool cell_is_lower) {
  // FacetVertices order has its right-hand normal out of the cell in 3D and into it in 2D
  // (a counter-clockwise boundary), so it is reversed for a lower 2D cell and an upper 3D one.
  const LocalId* c = &m.cell_nodes[cell * (Dim + 1)];
  const bool reverse = cell_is_lower == (Dim == 2);
  std::array<LocalId, Dim> out;
  for (int k = 0; k < Dim; ++k)
    out[static_cast<std::size_t>(k)] = c[FacetVertices<Dim>::local[opposite][reverse ? Dim - 1 - k : k]];
  return out;
}

template <int Dim>
void append_cohesive_cell(SimplexMesh<Dim>& m, std::array<LocalId, Dim> bottom, std::array<LocalId, Dim> top,
                          std::int32_t lower_phase, std::int32_t upper_phase, std::int32_t partition) {
  if constexpr (Dim == 3) {
    const auto position = [&](LocalId n) {
      std::array<double, 3> p;
      for (int d = 0; d < 3; ++d) p[static_cast<std::size_t>(d)] = m.coords[static_cast<std::size_t>(n) * 3 + d] + 0.0;
      return p;
    };
    int first = 0;
    for (int k = 1; k < 3; ++k)
      if (position(bottom[static_cast<std::size_t>(k)]) < position(bottom[static_cast<std::size_t>(first)])) first = k;
    std::rotate(bottom.begin(), bottom.begin() + first, bottom.end());
    std::rotate(top.begin(), top.begin() + first, top.end());
  }
  for (LocalId b : bottom) m.cohesive.nodes.push_back(b);
  for (LocalId t : top) m.cohesive.nodes.push_back(t);
  m.cohesive.phase.push_back(lower_phase);
  m.cohesive.phase.push_back(upper_phase);
  m.cohesive.partition.push_back(partition);
}

template std::array<LocalId, 2> cohesive_facet_order<2>(const SimplexMesh<2>&, std::size_t, int, bool);
template std::array<LocalId, 3> cohesive_facet_order<3>(const SimplexMesh<3>&, std::size_t, int, bool);
template void append_cohesive_cell<2>(SimplexMesh<2>&, std::array<LocalId, 2>, std::array<LocalId, 2>, std::int32_t,
                                      std::int32_t, std::int32_t);
template void append_cohesive_cell<3>(SimplexMesh<3>&, std::array<LocalId, 3>, std::array<LocalId, 3>, std::int32_t,
                                      std::int32_t, std::int32_t);
template std::vector<LocalId> insert_cohesive<2>(SimplexMesh<2>&, std::int32_t, CohesiveCounts*);
template std::vector<LocalId> insert_cohesive<3>(SimplexMesh<3>&, std::int32_t, CohesiveCounts*);

}  // namespace cisamr::mesh
