#include "pipeline/cohesive.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>

#include "grid/tet_lattice.hpp"
#include "mesh/boundary.hpp"
#include "mesh/cohesive.hpp"

namespace cisamr::pipeline {
namespace {

// A node identity as lattice points: the node itself (2D, 3D lattice node twice) or the
// two ends of its edge (3D cut node).
template <int Dim>
constexpr int kEnds = Dim == 2 ? 1 : 2;
template <int Dim>
using Ends = std::array<std::array<std::int64_t, Dim>, kEnds<Dim>>;

template <int Dim>
Ends<Dim> ends_of(const NodeIdentity<Dim>& id) {
  if constexpr (Dim == 2)
    return {{{grid::key2_x(id), grid::key2_y(id)}}};
  else
    return {grid::key3_point(id[0]), grid::key3_point(id[1])};
}

template <int Dim>
NodeIdentity<Dim> identity_of(const Ends<Dim>& ends) {
  if constexpr (Dim == 2) {
    return grid::key2(ends[0][0], ends[0][1]);
  } else {
    std::array<std::uint64_t, 2> id{grid::key3(ends[0]), grid::key3(ends[1])};
    if (id[1] < id[0]) std::swap(id[0], id[1]);
    return id;
  }
}

// Bit d: every end lies at the period on periodic axis d (the node is on that max face).
template <int Dim>
std::uint8_t image_of(const grid::Lattice<Dim>& lattice, const Ends<Dim>& ends) {
  std::uint8_t image = 0;
  for (int d = 0; d < Dim; ++d) {
    if (!lattice.periodic[d]) continue;
    bool all = true;
    for (const auto& e : ends) all = all && e[static_cast<std::size_t>(d)] == lattice.fine_period(d);
    if (all) image |= static_cast<std::uint8_t>(1u << d);
  }
  return image;
}

// The identity moved by `sign` periods along the axes of `image`.
template <int Dim>
NodeIdentity<Dim> moved(const grid::Lattice<Dim>& lattice, Ends<Dim> ends, std::uint8_t image, int sign) {
  for (auto& e : ends)
    for (int d = 0; d < Dim; ++d)
      if ((image >> d) & 1) e[static_cast<std::size_t>(d)] += sign * lattice.fine_period(d);
  return identity_of<Dim>(ends);
}

template <int Dim>
bool on_periodic_plane(const grid::Lattice<Dim>& lattice, const Ends<Dim>& ends) {
  for (int d = 0; d < Dim; ++d) {
    if (!lattice.periodic[d]) continue;
    bool at_min = true, at_max = true;
    for (const auto& e : ends) {
      at_min = at_min && e[static_cast<std::size_t>(d)] == 0;
      at_max = at_max && e[static_cast<std::size_t>(d)] == lattice.fine_period(d);
    }
    if (at_min || at_max) return true;
  }
  return false;
}

// Bit 2d (lo) or 2d+1 (hi): the node lies on that plane of the box, and the plane is an
// inner partition face or a periodic plane (a facet there may have its other cell elsewhere).
template <int Dim>
unsigned open_planes(const grid::Lattice<Dim>& lattice, const grid::CellRange<Dim>& box, const NodeIdentity<Dim>& id) {
  if (id == Result<Dim>::kUnshared) return 0;
  const Ends<Dim> ends = ends_of<Dim>(id);
  const std::int64_t unit = lattice.units(0);
  unsigned mask = 0;
  for (int d = 0; d < Dim; ++d) {
    const std::int64_t lo = box.lo[d] * unit, hi = box.hi[d] * unit;
    bool at_lo = box.lo[d] != 0 || lattice.periodic[d], at_hi = box.hi[d] != lattice.coarse_cells[d] || lattice.periodic[d];
    for (const auto& e : ends) {
      at_lo = at_lo && e[static_cast<std::size_t>(d)] == lo;
      at_hi = at_hi && e[static_cast<std::size_t>(d)] == hi;
    }
    if (at_lo) mask |= 1u << (2 * d);
    if (at_hi) mask |= 1u << (2 * d + 1);
  }
  return mask;
}

// The copies of some identities in a result: (identity, phase) → node, sorted for lookup.
template <int Dim>
class CopyIndex {
 public:
  CopyIndex(const Result<Dim>& result, std::vector<NodeIdentity<Dim>> wanted) {
    std::sort(wanted.begin(), wanted.end());
    wanted.erase(std::unique(wanted.begin(), wanted.end()), wanted.end());
    const auto& m = result.mesh;
    for (std::size_t n = 0; n < m.node_count(); ++n) {
      const NodeIdentity<Dim>& id = result.node_identity[n];
      if (std::binary_search(wanted.begin(), wanted.end(), id))
        entries_.push_back({id, m.node_phase[n], static_cast<LocalId>(n)});
    }
    std::sort(entries_.begin(), entries_.end());
  }
  // The copy of phase `phase`, or -1.
  LocalId find(const NodeIdentity<Dim>& id, std::int32_t phase) const {
    const auto it = std::lower_bound(entries_.begin(), entries_.end(), Entry{id, phase, -1});
    return it != entries_.end() && it->id == id && it->phase == phase ? it->node : -1;
  }
  // Any copy, or -1.
  LocalId any(const NodeIdentity<Dim>& id) const {
    const auto it = std::lower_bound(entries_.begin(), entries_.end(), Entry{id, std::numeric_limits<std::int32_t>::min(), -1});
    return it != entries_.end() && it->id == id ? it->node : -1;
  }
  void add(const NodeIdentity<Dim>& id, std::int32_t phase, LocalId node) {
    const Entry e{id, phase, node};
    entries_.insert(std::lower_bound(entries_.begin(), entries_.end(), e), e);
  }

 private:
  struct Entry {
    NodeIdentity<Dim> id;
    std::int32_t phase;
    LocalId node;
    auto operator<=>(const Entry&) const = default;
  };
  std::vector<Entry> entries_;
};

// Appends the copy of `source` for `phase` (same coordinate bits and identity).
template <int Dim>
LocalId append_copy(Result<Dim>& result, LocalId source, std::int32_t phase) {
  auto& m = result.mesh;
  const auto node = static_cast<LocalId>(m.node_count());
  for (int d = 0; d < Dim; ++d) m.coords.push_back(m.coords[static_cast<std::size_t>(source) * Dim + d]);
  m.node_phase.push_back(phase);
  if (!m.node_global_id.empty()) m.node_global_id.push_back(node);
  result.node_identity.push_back(result.node_identity[static_cast<std::size_t>(source)]);
  return node;
}

}  // namespace

template <int Dim>
std::uint64_t identity_hash(const NodeIdentity<Dim>& id) {
  const auto mix = [](std::uint64_t x) {  // splitmix64 finaliser
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
  };
  if constexpr (Dim == 2)
    return mix(id);
  else
    return mix(mix(id[0]) ^ id[1]);
}

template <int Dim>
std::vector<FacetClaim<Dim>> split_and_claim(Result<Dim>& result, const grid::Lattice<Dim>& lattice,
                                             const grid::CellRange<Dim>& box, std::int32_t partition) {
  constexpr int K = Dim + 1;
  auto& m = result.mesh;
  const std::vector<LocalId> origin = mesh::insert_cohesive(m, partition);
  result.node_identity.resize(origin.size());
  for (std::size_t n = 0; n < origin.size(); ++n)
    result.node_identity[n] = result.node_identity[static_cast<std::size_t>(origin[n])];

  std::vector<unsigned> planes(m.node_count());
  for (std::size_t n = 0; n < planes.size(); ++n) planes[n] = open_planes(lattice, box, result.node_identity[n]);
  std::vector<FacetClaim<Dim>> claims;
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    const LocalId* cell = &m.cell_nodes[c * K];
    for (int f = 0; f < K; ++f) {
      unsigned common = ~0u;
      for (int k = 0; k < Dim; ++k) common &= planes[static_cast<std::size_t>(cell[mesh::FacetVertices<Dim>::local[f][k]])];
      if (common == 0) continue;
      FacetClaim<Dim> claim;
      for (int k = 0; k < Dim; ++k) {
        const Ends<Dim> ends = ends_of<Dim>(result.node_identity[static_cast<std::size_t>(cell[mesh::FacetVertices<Dim>::local[f][k]])]);
        claim.key[static_cast<std::size_t>(k)] = moved<Dim>(lattice, ends, image_of<Dim>(lattice, ends), -1);
      }
      std::sort(claim.key.begin(), claim.key.end());
      claim.phase = m.cell_phase[c];
      claim.partition = partition;
      claim.cell = static_cast<std::int64_t>(c);
      claim.opposite = f;
      claim.lo_side = (common & 0x15u) != 0;  // bits 0, 2, 4: the lo planes
      claims.push_back(claim);
    }
  }
  return claims;
}

template <int Dim>
std::vector<FacetJoin> pair_facet_claims(std::vector<FacetClaim<Dim>> claims) {
  std::sort(claims.begin(), claims.end(), [](const FacetClaim<Dim>& a, const FacetClaim<Dim>& b) {
    return std::tie(a.key, a.partition, a.cell, a.opposite) < std::tie(b.key, b.partition, b.cell, b.opposite);
  });
  std::vector<FacetJoin> joins;
  for (std::size_t i = 0; i < claims.size();) {
    std::size_t j = i + 1;
    while (j < claims.size() && claims[j].key == claims[i].key) ++j;
    if (j - i > 2) throw std::logic_error("cohesive: a facet on a partition face or periodic plane claimed " +
                                          std::to_string(j - i) + " times");
    if (j - i == 2 && claims[i].phase != claims[i + 1].phase) {
      const FacetClaim<Dim>& a = claims[i];
      const FacetClaim<Dim>& b = claims[i + 1];
      if (a.lo_side == b.lo_side)
        throw std::logic_error("cohesive: a facet on partitions " + std::to_string(a.partition) + " and " +
                               std::to_string(b.partition) + " is on the lo plane of both boxes or of neither");
      const FacetClaim<Dim>& emitter = a.lo_side ? a : b;
      const FacetClaim<Dim>& other = a.lo_side ? b : a;
      joins.push_back({emitter.partition, emitter.rank, emitter.cell, emitter.opposite, other.phase});
    }
    i = j;
  }
  std::sort(joins.begin(), joins.end());
  return joins;
}

template <int Dim>
void apply_facet_joins(Result<Dim>& result, std::span<const FacetJoin> joins) {
  if (joins.empty()) return;
  auto& m = result.mesh;
  std::vector<NodeIdentity<Dim>> wanted;
  for (const FacetJoin& j : joins)
    for (int k = 0; k < Dim; ++k)
      wanted.push_back(result.node_identity[static_cast<std::size_t>(
          m.cell_nodes[static_cast<std::size_t>(j.cell) * (Dim + 1) + mesh::FacetVertices<Dim>::local[j.opposite][k]])]);
  CopyIndex<Dim> copies(result, std::move(wanted));
  for (const FacetJoin& j : joins) {
    const std::int32_t own = m.cell_phase[static_cast<std::size_t>(j.cell)];
    const bool own_is_lower = own < j.other_phase;
    const std::array<LocalId, Dim> mine = mesh::cohesive_facet_order<Dim>(m, static_cast<std::size_t>(j.cell), j.opposite, own_is_lower);
    std::array<LocalId, Dim> theirs;
    for (int k = 0; k < Dim; ++k) {
      const LocalId n = mine[static_cast<std::size_t>(k)];
      const NodeIdentity<Dim> id = result.node_identity[static_cast<std::size_t>(n)];
      LocalId copy = copies.find(id, j.other_phase);
      if (copy < 0) {
        copy = append_copy(result, n, j.other_phase);
        copies.add(id, j.other_phase, copy);
      }
      theirs[static_cast<std::size_t>(k)] = copy;
    }
    if (own_is_lower)
      mesh::append_cohesive_cell<Dim>(m, mine, theirs, own, j.other_phase, j.partition);
    else
      mesh::append_cohesive_cell<Dim>(m, theirs, mine, j.other_phase, own, j.partition);
  }
}

template <int Dim>
std::vector<CopyClaim<Dim>> copy_claims(const Result<Dim>& result, const grid::Lattice<Dim>& lattice,
                                        std::int32_t partition) {
  std::vector<CopyClaim<Dim>> claims;
  if (!lattice.any_periodic()) return claims;
  for (std::size_t n = 0; n < result.node_identity.size(); ++n) {
    const NodeIdentity<Dim>& id = result.node_identity[n];
    if (id == Result<Dim>::kUnshared) continue;
    const Ends<Dim> ends = ends_of<Dim>(id);
    if (!on_periodic_plane<Dim>(lattice, ends)) continue;
    const std::uint8_t image = image_of<Dim>(lattice, ends);
    claims.push_back({moved<Dim>(lattice, ends, image, -1), image, result.mesh.node_phase[n], partition, 0});
  }
  return claims;
}

template <int Dim>
std::vector<CopyNeed<Dim>> missing_copies(std::vector<CopyClaim<Dim>> claims) {
  std::sort(claims.begin(), claims.end(), [](const CopyClaim<Dim>& a, const CopyClaim<Dim>& b) {
    return std::tie(a.canonical, a.image, a.phase, a.partition) < std::tie(b.canonical, b.image, b.phase, b.partition);
  });
  std::vector<CopyNeed<Dim>> needs;
  for (std::size_t i = 0; i < claims.size();) {
    std::size_t j = i + 1;
    while (j < claims.size() && claims[j].canonical == claims[i].canonical) ++j;
    const std::span<const CopyClaim<Dim>> group(claims.data() + i, j - i);
    const auto used = [&](std::uint8_t image, std::int32_t phase) {
      return std::ranges::any_of(group, [&](const CopyClaim<Dim>& c) { return c.image == image && c.phase == phase; });
    };
    for (const CopyClaim<Dim>& far : group)  // a copy at image J of phase r
      for (const CopyClaim<Dim>& holder : group) {  // a partition holding image I ⊂ J
        const std::uint8_t near = holder.image;
        if (near == far.image || (near & far.image) != near || used(near, far.phase)) continue;
        needs.push_back({holder.partition, holder.rank, far.canonical, near, far.phase});
      }
    i = j;
  }
  std::sort(needs.begin(), needs.end());
  needs.erase(std::unique(needs.begin(), needs.end()), needs.end());
  return needs;
}

template <int Dim>
void apply_copy_needs(Result<Dim>& result, const grid::Lattice<Dim>& lattice, std::span<const CopyNeed<Dim>> needs) {
  if (needs.empty()) return;
  std::vector<NodeIdentity<Dim>> wanted;
  for (const CopyNeed<Dim>& need : needs) wanted.push_back(moved<Dim>(lattice, ends_of<Dim>(need.canonical), need.image, +1));
  CopyIndex<Dim> copies(result, wanted);
  for (std::size_t i = 0; i < needs.size(); ++i) {
    const NodeIdentity<Dim>& id = wanted[i];
    if (copies.find(id, needs[i].phase) >= 0) continue;
    const LocalId source = copies.any(id);
    if (source < 0) throw std::logic_error("cohesive: partition " + std::to_string(needs[i].partition) +
                                           " was asked for a copy of a node it does not hold");
    copies.add(id, needs[i].phase, append_copy(result, source, needs[i].phase));
  }
}

template <int Dim>
void insert_cohesive_whole(Result<Dim>& result, const grid::Lattice<Dim>& lattice) {
  const std::vector<FacetJoin> joins = pair_facet_claims(split_and_claim(result, lattice, lattice.whole_domain(), 0));
  apply_facet_joins<Dim>(result, joins);
  const std::vector<CopyNeed<Dim>> needs = missing_copies(copy_claims(result, lattice, 0));
  apply_copy_needs<Dim>(result, lattice, needs);
}

#define CISAMR_COHESIVE(D)                                                                                         \
  template std::vector<FacetClaim<D>> split_and_claim<D>(Result<D>&, const grid::Lattice<D>&,                      \
                                                         const grid::CellRange<D>&, std::int32_t);                 \
  template std::vector<FacetJoin> pair_facet_claims<D>(std::vector<FacetClaim<D>>);                                \
  template void apply_facet_joins<D>(Result<D>&, std::span<const FacetJoin>);                                      \
  template std::vector<CopyClaim<D>> copy_claims<D>(const Result<D>&, const grid::Lattice<D>&, std::int32_t);      \
  template std::vector<CopyNeed<D>> missing_copies<D>(std::vector<CopyClaim<D>>);                                  \
  template void apply_copy_needs<D>(Result<D>&, const grid::Lattice<D>&, std::span<const CopyNeed<D>>);            \
  template void insert_cohesive_whole<D>(Result<D>&, const grid::Lattice<D>&);                                     \
  template std::uint64_t identity_hash<D>(const NodeIdentity<D>&);
CISAMR_COHESIVE(2)
CISAMR_COHESIVE(3)
#undef CISAMR_COHESIVE

}  // namespace cisamr::pipeline
