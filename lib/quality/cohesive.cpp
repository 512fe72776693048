// The independent checker of cohesive meshes (cohesive.hpp, docs/cohesive-design.md §6.2).
// Written against the rules of mesh::CohesiveCells only; it shares nothing with the
// insertion, so a bug there cannot hide behind the same bug here.
#include "quality/cohesive.hpp"

#include <algorithm>
#include <bit>
#include <compare>
#include <limits>
#include <numeric>
#include <span>

#include "quality/facet_table.hpp"

namespace cisamr::quality {
namespace {

// The bits of a coordinate, −0 as +0: the one meaning of "same position" in this file.
std::uint64_t position_bits(double x) { return std::bit_cast<std::uint64_t>(x == 0 ? 0.0 : x); }

// orient(b, x) = det[b1 − b0, (b2 − b0,) x − b0] (mesh::CohesiveCells): in 2D
// rot+90(b1 − b0)·(x − b0), in 3D ((b1 − b0) × (b2 − b0))·(x − b0). Evaluated in doubles:
// b is a facet of two bulk cells and x their apexes, cells that check_conformity requires
// to be far from degenerate (1e-12 relative), so rounding cannot flip the sign.
template <int Dim>
double orient(const mesh::SimplexMesh<Dim>& m, const LocalId* b, const Vec<Dim>& x) {
  const Vec<Dim> b0 = m.point(b[0]), b1 = m.point(b[1]);
  if constexpr (Dim == 2) {
    const double ex = b1[0] - b0[0], ey = b1[1] - b0[1];
    return -ey * (x[0] - b0[0]) + ex * (x[1] - b0[1]);
  } else {
    const Vec3 b2 = m.point(b[2]);
    const double u[3] = {b1[0] - b0[0], b1[1] - b0[1], b1[2] - b0[2]};
    const double v[3] = {b2[0] - b0[0], b2[1] - b0[1], b2[2] - b0[2]};
    const double w[3] = {x[0] - b0[0], x[1] - b0[1], x[2] - b0[2]};
    return (u[1] * v[2] - u[2] * v[1]) * w[0] + (u[2] * v[0] - u[0] * v[2]) * w[1] +
           (u[0] * v[1] - u[1] * v[0]) * w[2];
  }
}

template <int Dim>
Vec<Dim> centroid_of(const mesh::SimplexMesh<Dim>& m, const LocalId* n, int count) {
  Vec<Dim> g{};
  for (int k = 0; k < count; ++k)
    for (int d = 0; d < Dim; ++d) g[d] += m.point(n[k])[d];
  for (int d = 0; d < Dim; ++d) g[d] /= count;
  return g;
}

// The original node ids of facet `local` of bulk cell `cell`, ascending.
template <int Dim>
detail::FacetNodes<Dim> facet_ids(const mesh::SimplexMesh<Dim>& m, std::size_t cell, int local) {
  detail::FacetNodes<Dim> v;
  for (int k = 0; k < Dim; ++k) v[k] = m.cell(cell)[detail::FacetTable<Dim>::local[local][k]];
  std::sort(v.begin(), v.end());
  return v;
}

template <int Dim>
detail::FacetNodes<Dim> sorted_ids(const LocalId* n) {
  detail::FacetNodes<Dim> v;
  std::copy(n, n + Dim, v.begin());
  std::sort(v.begin(), v.end());
  return v;
}

// Per-cohesive-cell verdicts, gathered while the facets are visited and reported in cell
// order afterwards, so the examples do not depend on the facet order.
enum CellFlag : std::uint8_t {
  kMalformed = 1,
  kPlaced = 2,  // its welded bottom is an interface facet
  kMisplaced = 4,
  kNotCoincident = 8,
  kWrongSides = 16,
  kWrongOrientation = 32,
};

}  // namespace

namespace {

// Welds the nodes whose `key`s (Dim per node) are equal; weld_view's contract.
template <int Dim>
WeldedMesh<Dim> weld_by(const mesh::SimplexMesh<Dim>& m, const std::vector<std::uint64_t>& key) {
  const std::size_t nodes = m.node_count();
  std::vector<LocalId> order(nodes);
  std::iota(order.begin(), order.end(), LocalId{0});
  std::sort(order.begin(), order.end(), [&](LocalId a, LocalId b) {
    const auto ka = key.begin() + std::ptrdiff_t(a) * Dim, kb = key.begin() + std::ptrdiff_t(b) * Dim;
    const auto c = std::lexicographical_compare_three_way(ka, ka + Dim, kb, kb + Dim);
    return c != 0 ? c < 0 : a < b;
  });
  // lowest[n]: the lowest id at n's position (the first of its run, ties being by id).
  std::vector<LocalId> lowest(nodes);
  for (std::size_t i = 0; i < nodes; ++i) {
    const bool same = i > 0 && std::equal(key.begin() + std::ptrdiff_t(order[i]) * Dim,
                                          key.begin() + std::ptrdiff_t(order[i] + 1) * Dim,
                                          key.begin() + std::ptrdiff_t(order[i - 1]) * Dim);
    lowest[order[i]] = same ? lowest[order[i - 1]] : order[i];
  }
  WeldedMesh<Dim> w;
  w.class_of.resize(nodes);
  const bool global = m.node_global_id.size() == nodes;
  LocalId next = 0;
  for (std::size_t n = 0; n < nodes; ++n) {
    if (lowest[n] != static_cast<LocalId>(n)) {
      w.class_of[n] = w.class_of[lowest[n]];  // lowest[n] < n: numbered already
      continue;
    }
    w.class_of[n] = next++;
    w.mesh.coords.insert(w.mesh.coords.end(), m.coords.begin() + std::ptrdiff_t(n) * Dim,
                         m.coords.begin() + std::ptrdiff_t(n + 1) * Dim);
    if (global) w.mesh.node_global_id.push_back(m.node_global_id[n]);
  }
  w.mesh.cell_nodes.resize(m.cell_nodes.size());
  for (std::size_t i = 0; i < m.cell_nodes.size(); ++i) {
    const LocalId n = m.cell_nodes[i];
    w.mesh.cell_nodes[i] = n >= 0 && static_cast<std::size_t>(n) < nodes ? w.class_of[n] : -1;
  }
  w.mesh.cell_phase = m.cell_phase;
  w.mesh.cell_partition = m.cell_partition;
  return w;
}

}  // namespace

template <int Dim>
WeldedMesh<Dim> weld_view(const mesh::SimplexMesh<Dim>& m) {
  std::vector<std::uint64_t> key(m.coords.size());
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = position_bits(m.coords[i]);
  return weld_by(m, key);
}

template <int Dim>
CohesiveReport<Dim> check_cohesive(const mesh::SimplexMesh<Dim>& m, const CohesivePeriodicity<Dim>* periodic) {
  constexpr int C = 2 * Dim;
  CohesiveReport<Dim> r;
  const std::size_t nodes = m.node_count();
  const WeldedMesh<Dim> welded = weld_view(m);
  const std::vector<LocalId>& cls = welded.class_of;
  // The torus: max-face positions welded with their min-face translates (periodic only).
  bool any_axis = false;
  if (periodic != nullptr)
    for (bool a : periodic->axes) any_axis = any_axis || a;
  const auto max_face_axes = [&](LocalId n) {  // bit a: n lies on the max face of periodic axis a
    unsigned bits = 0;
    if (any_axis)
      for (int a = 0; a < Dim; ++a)
        if (periodic->axes[static_cast<std::size_t>(a)] && m.point(n)[a] == periodic->faces.max[a]) bits |= 1u << a;
    return bits;
  };
  WeldedMesh<Dim> torus_weld;
  if (any_axis) {
    std::vector<std::uint64_t> key(m.coords.size());
    for (std::size_t n = 0; n < nodes; ++n) {
      const unsigned on_max = max_face_axes(LocalId(n));
      for (int a = 0; a < Dim; ++a)
        key[n * Dim + a] = position_bits((on_max >> a) & 1 ? periodic->faces.min[a] : m.coords[n * Dim + a]);
    }
    torus_weld = weld_by(m, key);
  }
  const WeldedMesh<Dim>& torus = any_axis ? torus_weld : welded;
  const std::vector<LocalId>& tcls = torus.class_of;
  const std::vector<bool> valid = detail::valid_cells(torus.mesh);  // same cells as in m

  // ---- the phases of each node's bulk cells ----------------------------------------------
  enum : std::uint8_t { kUnused, kOnePhase, kMixed };
  std::vector<std::int32_t> phase_of(nodes, 0);  // the phase of its first cell
  std::vector<std::uint8_t> state(nodes, kUnused);
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    if (!valid[c]) continue;
    for (int k = 0; k <= Dim; ++k) {
      const LocalId n = m.cell(c)[k];
      if (state[n] == kUnused) {
        state[n] = kOnePhase;
        phase_of[n] = m.cell_phase[c];
      } else if (phase_of[n] != m.cell_phase[c]) {
        state[n] = kMixed;
      }
    }
  }
  for (std::size_t n = 0; n < nodes; ++n)
    if (state[n] == kMixed) r.phase_mixed_nodes.add(static_cast<std::int64_t>(n), m.point(LocalId(n)));

  // ---- copies: one node per (position, phase) ----------------------------------------------
  // Only positions held by two or more nodes can repeat a copy; a mixed node counts once
  // for each of its phases.
  {
    std::vector<LocalId> class_size(welded.mesh.node_count(), 0);
    for (LocalId w : cls) ++class_size[w];
    struct Copy {
      LocalId position;
      std::int32_t phase;
      LocalId node;
      auto operator<=>(const Copy&) const = default;
    };
    std::vector<Copy> copies;
    for (std::size_t n = 0; n < nodes; ++n)
      if (state[n] == kOnePhase && class_size[cls[n]] > 1) copies.push_back({cls[n], phase_of[n], LocalId(n)});
    for (std::size_t c = 0; c < m.cell_count(); ++c) {
      if (!valid[c]) continue;
      for (int k = 0; k <= Dim; ++k) {
        const LocalId n = m.cell(c)[k];
        if (state[n] == kMixed && class_size[cls[n]] > 1) copies.push_back({cls[n], m.cell_phase[c], n});
      }
    }
    std::sort(copies.begin(), copies.end());
    copies.erase(std::unique(copies.begin(), copies.end()), copies.end());
    for (std::size_t i = 1; i < copies.size(); ++i)
      if (copies[i].position == copies[i - 1].position && copies[i].phase == copies[i - 1].phase)
        r.duplicate_copies.add(copies[i].node, m.point(copies[i].node));
  }

  // ---- node_phase ------------------------------------------------------------------------
  if (!m.node_phase.empty()) {
    const std::size_t common = std::min(m.node_phase.size(), nodes);
    for (std::size_t n = 0; n < common; ++n)
      if (state[n] == kOnePhase && m.node_phase[n] != phase_of[n])
        r.node_phase_mismatch.add(static_cast<std::int64_t>(n), m.point(LocalId(n)));
    for (std::size_t i = common; i < std::max(m.node_phase.size(), nodes); ++i) r.node_phase_mismatch.add(-1, {});
  }

  // ---- cohesive cells, keyed by their welded bottom -----------------------------------------
  const auto& coh = m.cohesive;
  const std::size_t count = coh.count();
  r.cohesive_cells = count;
  std::vector<std::uint8_t> flags(count, 0);
  struct Bottom {
    detail::FacetNodes<Dim> key;  // the welded nodes of the bottom, ascending
    std::size_t cell;
  };
  std::vector<Bottom> bottoms;
  bottoms.reserve(count);
  for (std::size_t c = 0; c < count; ++c) {
    bool ok = (c + 1) * C <= coh.nodes.size() && 2 * c + 2 <= coh.phase.size();
    for (int k = 0; ok && k < C; ++k) {
      const LocalId n = coh.nodes[c * C + k];
      ok = n >= 0 && static_cast<std::size_t>(n) < nodes;
    }
    if (!ok) {
      flags[c] = kMalformed;
      continue;
    }
    const LocalId* b = coh.cell(c);
    const LocalId* t = b + Dim;
    Bottom e{{}, c};
    for (int k = 0; k < Dim; ++k) {
      e.key[k] = tcls[b[k]];
      if (cls[t[k]] != cls[b[k]]) flags[c] |= kNotCoincident;
    }
    std::sort(e.key.begin(), e.key.end());
    bottoms.push_back(e);
  }
  std::sort(bottoms.begin(), bottoms.end(), [](const Bottom& a, const Bottom& b) {
    return a.key != b.key ? a.key < b.key : a.cell < b.cell;
  });

  // The rules for cohesive cell c on the interface facet between `lower` (the lower phase)
  // and `upper`.
  auto judge = [&](std::size_t c, const detail::FacetUse& lower, const detail::FacetUse& upper) {
    const std::int32_t p = m.cell_phase[lower.cell], q = m.cell_phase[upper.cell];
    const std::int32_t ph0 = coh.phase[2 * c], ph1 = coh.phase[2 * c + 1];
    if (!((ph0 == p && ph1 == q) || (ph0 == q && ph1 == p))) {
      flags[c] |= kMisplaced;  // between other phases than its own
      return;
    }
    const LocalId* b = coh.cell(c);
    // A side is right when its ids are its cell's facet nodes, or (periodic) when that
    // cell's facet lies on a max face and the side holds the copies of that cell's phase at
    // the translates: then the apex is moved back by the period. One side must be the former.
    const auto phase_of_node = [&](LocalId n) {
      if (!m.node_phase.empty() && static_cast<std::size_t>(n) < m.node_phase.size()) return m.node_phase[n];
      return state[n] == kOnePhase ? phase_of[n] : std::numeric_limits<std::int32_t>::min();
    };
    const auto side = [&](const LocalId* ids, const detail::FacetUse& use, Vec<Dim>& apex) {
      apex = m.point(m.cell(use.cell)[use.local]);
      if (sorted_ids<Dim>(ids) == facet_ids(m, use.cell, use.local)) return 1;  // near
      if (!any_axis) return 0;
      unsigned shift = ~0u;
      for (int k = 0; k < Dim; ++k) shift &= max_face_axes(m.cell(use.cell)[detail::FacetTable<Dim>::local[use.local][k]]);
      if (shift == 0) return 0;
      for (int k = 0; k < Dim; ++k) {
        const LocalId n = ids[k];
        if (phase_of_node(n) != m.cell_phase[use.cell] || (max_face_axes(n) & shift) != 0) return 0;
      }
      for (int a = 0; a < Dim; ++a)
        if ((shift >> a) & 1) apex[a] -= periodic->faces.max[a] - periodic->faces.min[a];
      return 2;  // across the plane
    };
    Vec<Dim> apex_lower, apex_upper;
    const int bottom_side = ph0 == p ? side(b, lower, apex_lower) : 0;
    const int top_side = ph0 == p ? side(b + Dim, upper, apex_upper) : 0;
    if (bottom_side == 0 || top_side == 0 || (bottom_side == 2 && top_side == 2)) {
      flags[c] |= kWrongSides;
      return;
    }
    if (!(orient<Dim>(m, b, apex_upper) > 0 && orient<Dim>(m, b, apex_lower) < 0)) flags[c] |= kWrongOrientation;
  };

  const auto by_key = [](const Bottom& e, const detail::FacetNodes<Dim>& k) { return e.key < k; };
  detail::for_each_facet<Dim>(
      torus.mesh, valid, [&](const detail::FacetNodes<Dim>& key, std::span<const detail::FacetUse> uses) {
        const auto first = std::lower_bound(bottoms.begin(), bottoms.end(), key, by_key);
        auto last = first;
        while (last != bottoms.end() && last->key == key) ++last;
        const bool interface = uses.size() == 2 && m.cell_phase[uses[0].cell] != m.cell_phase[uses[1].cell];
        if (!interface) {  // a same-phase, boundary, void or non-manifold facet
          for (auto e = first; e != last; ++e) flags[e->cell] |= kPlaced | kMisplaced;
          return;
        }
        ++r.interface_facets;
        const bool swap = m.cell_phase[uses[0].cell] > m.cell_phase[uses[1].cell];
        const detail::FacetUse& lower = uses[swap ? 1 : 0];
        const detail::FacetUse& upper = uses[swap ? 0 : 1];
        const std::size_t covering = static_cast<std::size_t>(last - first);
        if (covering != 1) {
          LocalId ids[Dim];
          for (int k = 0; k < Dim; ++k) ids[k] = m.cell(lower.cell)[detail::FacetTable<Dim>::local[lower.local][k]];
          (covering == 0 ? r.uncovered : r.covered_twice)
              .add(static_cast<std::int64_t>(lower.cell), centroid_of(m, ids, Dim));
        }
        for (auto e = first; e != last; ++e) {
          flags[e->cell] |= kPlaced;
          judge(e->cell, lower, upper);
        }
      });

  for (std::size_t c = 0; c < count; ++c) {
    const auto id = static_cast<std::int64_t>(c);
    if (flags[c] & kMalformed) {
      r.malformed.add(id, {});
      continue;
    }
    const Vec<Dim> at = centroid_of(m, coh.cell(c), Dim);
    if (!(flags[c] & kPlaced) || (flags[c] & kMisplaced)) r.misplaced.add(id, at);
    if (flags[c] & kNotCoincident) r.not_coincident.add(id, at);
    if (flags[c] & kWrongSides) r.wrong_sides.add(id, at);
    if (flags[c] & kWrongOrientation) r.wrong_orientation.add(id, at);
  }
  // Entries beyond count() cells: arrays of inconsistent sizes.
  if (coh.nodes.size() > count * C || coh.phase.size() > 2 * count) r.malformed.add(-1, {});
  return r;
}

template <int Dim>
std::string CohesiveReport<Dim>::summary() const {
  std::string s = "cohesive: " + std::to_string(cohesive_cells) + " cells on " + std::to_string(interface_facets) +
                  " interface facets; ";
  if (ok()) return s + "every interface facet covered once";
  const std::pair<const char*, std::size_t> failures[] = {
      {"malformed", malformed.count},
      {"phase-mixed nodes", phase_mixed_nodes.count},
      {"duplicate copies", duplicate_copies.count},
      {"uncovered facets", uncovered.count},
      {"facets covered twice", covered_twice.count},
      {"misplaced", misplaced.count},
      {"not coincident", not_coincident.count},
      {"wrong sides", wrong_sides.count},
      {"wrong orientation", wrong_orientation.count},
      {"node_phase mismatches", node_phase_mismatch.count}};
  std::string list;
  for (const auto& [name, n] : failures)
    if (n > 0) list += (list.empty() ? "" : ", ") + std::to_string(n) + " " + name;
  return s + "FAILED: " + list;
}

template struct CohesiveReport<2>;
template struct CohesiveReport<3>;
template WeldedMesh<2> weld_view<2>(const mesh::SimplexMesh<2>&);
template WeldedMesh<3> weld_view<3>(const mesh::SimplexMesh<3>&);
template CohesiveReport<2> check_cohesive<2>(const mesh::SimplexMesh<2>&, const CohesivePeriodicity<2>*);
template CohesiveReport<3> check_cohesive<3>(const mesh::SimplexMesh<3>&, const CohesivePeriodicity<3>*);

}  // namespace cisamr::quality
