#include "radapt/radapt3.hpp"

#include <bit>
#include <cmath>
#include <limits>

namespace cisamr::radapt {
namespace {

int single_phase(PhaseMask m) { return std::popcount(m) == 1 ? std::countr_zero(m) : -1; }

}  // namespace

Nodes3 snap3(const geometry::Oracle3& oracle, const samr::RefinedGrid3& g, const Options3& options) {
  const grid::TetForest& forest = g.forest;
  const grid::Lattice3& lattice = forest.lattice();
  Nodes3 nodes;
  nodes.registry = grid::KeyMap(forest.size() / 2 + 16);
  nodes.tet_nodes.resize(forest.size());

  const auto add_node = [&](const grid::LatticePoint3& p) -> std::int32_t {
    bool inserted = false;
    const auto next = static_cast<std::int32_t>(nodes.key.size());
    const grid::LatticeKey3 k = grid::key3(p);
    const std::int32_t id = nodes.registry.insert(k, next, inserted);
    if (inserted) {
      nodes.key.push_back(k);
      nodes.position.push_back(forest.position(p));
      nodes.mask.push_back(0);
    }
    return id;
  };

  // 1. Vertices of every leaf and their phases. A leaf that no boundary meets lies inside
  //    one phase, so its vertices take that phase without asking the oracle per vertex.
  const PhaseMask matrix_bit = PhaseMask{1} << oracle.matrix_phase();
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(forest.size()); ++t) {
    if (!forest.is_leaf(t)) continue;
    const auto v = forest.fine_vertices(t);
    auto& ids = nodes.tet_nodes[static_cast<std::size_t>(t)];
    for (int i = 0; i < 4; ++i) ids[static_cast<std::size_t>(i)] = add_node(v[i]);
    const auto candidates = g.candidates_of_tet(t);
    if (g.is_cut(t)) {
      for (std::int32_t id : ids)
        if (nodes.mask[static_cast<std::size_t>(id)] == 0)
          nodes.mask[static_cast<std::size_t>(id)] =
              oracle.closure_phases(nodes.position[static_cast<std::size_t>(id)], candidates);
    } else {
      PhaseMask bit = matrix_bit;
      if (!candidates.empty()) {
        Vec3 centre{0, 0, 0};
        for (std::int32_t id : ids)
          for (int d = 0; d < 3; ++d) centre[d] += 0.25 * nodes.position[static_cast<std::size_t>(id)][d];
        bit = PhaseMask{1} << oracle.phase_at(centre, candidates);
      }
      for (std::int32_t id : ids)
        if (nodes.mask[static_cast<std::size_t>(id)] == 0) nodes.mask[static_cast<std::size_t>(id)] = bit;
    }
  }
  const std::size_t n = nodes.key.size();
  nodes.snapped.assign(n, 0);

  // 2. Snap decisions, from original positions and masks only.
  struct Snap {
    std::int32_t node;
    Vec3 position;
    PhaseMask mask;
  };
  std::vector<std::int64_t> fine_max(3);
  for (int d = 0; d < 3; ++d) fine_max[static_cast<std::size_t>(d)] = grid::fine_extent(lattice, d);
  std::vector<std::uint8_t> visited(n, 0);
  std::vector<Snap> snaps;
  std::vector<geometry::Crossing> crossings;
  const auto& range = forest.range();

  // The crossing of edge v→w nearest v, in units of the edge length, or +inf. The
  // segment is oriented from the smaller key so both ends get the same doubles.
  const auto nearest_crossing = [&](const grid::LatticePoint3& pv, const grid::LatticePoint3& pw, std::int32_t v,
                                    std::int32_t w, Snap& out) -> double {
    const bool v_first = nodes.key[static_cast<std::size_t>(v)] < nodes.key[static_cast<std::size_t>(w)];
    const std::int32_t a = v_first ? v : w, b = v_first ? w : v;
    const Vec3 pa = nodes.position[static_cast<std::size_t>(a)], pb = nodes.position[static_cast<std::size_t>(b)];
    // The coarse cube holding the segment (it never crosses a coarse cube face).
    std::int64_t c[3];
    const std::int64_t coarse_units = lattice.units(0);
    for (int d = 0; d < 3; ++d)
      c[d] = std::min((pv[d] + pw[d]) / 2 / coarse_units, range.hi[d] - 1);
    const std::int64_t cube = g.cube_index(c[0], c[1], c[2]);
    if (cube < 0) return std::numeric_limits<double>::infinity();
    oracle.crossings(pa, pb, g.candidates_of_cube(cube), crossings);
    if (crossings.empty()) return std::numeric_limits<double>::infinity();
    const geometry::Crossing& cross = v_first ? crossings.front() : crossings.back();
    for (int d = 0; d < 3; ++d) out.position[d] = pa[d] + cross.t * (pb[d] - pa[d]);
    out.mask = (PhaseMask{1} << cross.from_phase) | (PhaseMask{1} << cross.to_phase);
    // A crossing exactly half-way belongs to the endpoint with the smaller key.
    const double dist = v_first ? cross.t : 1.0 - cross.t;
    return (dist == options.alpha && !v_first) ? std::nextafter(dist, 1.0) : dist;
  };

  static constexpr int kDirections[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(forest.size()); ++t) {
    if (!forest.is_leaf(t) || !g.is_cut(t)) continue;
    // Rule R4: every leaf around a vertex of a cut leaf has this leaf's level, so the
    // six axis edges of the vertex have length h_l.
    const std::int64_t s = lattice.units(forest.tet(t).level);
    const auto verts = forest.fine_vertices(t);
    for (int i = 0; i < 4; ++i) {
      const std::int32_t v = nodes.tet_nodes[static_cast<std::size_t>(t)][static_cast<std::size_t>(i)];
      if (visited[static_cast<std::size_t>(v)]) continue;
      visited[static_cast<std::size_t>(v)] = 1;
      const int phase = single_phase(nodes.mask[static_cast<std::size_t>(v)]);
      if (phase < 0) continue;  // already on an interface
      const grid::LatticePoint3& pv = verts[i];
      double best = std::numeric_limits<double>::infinity();
      Snap snap{v, {}, 0}, candidate{v, {}, 0};
      for (const auto& dir : kDirections) {
        const int axis = dir[0] != 0 ? 0 : dir[1] != 0 ? 1 : 2;
        // On the domain boundary a node may only slide along it.
        if (pv[axis] == 0 || pv[axis] == fine_max[static_cast<std::size_t>(axis)]) continue;
        const grid::LatticePoint3 pw{pv[0] + dir[0] * s, pv[1] + dir[1] * s, pv[2] + dir[2] * s};
        const std::int32_t w = nodes.id(grid::key3(pw));
        if (w < 0) continue;  // beyond the range
        if (nodes.mask[static_cast<std::size_t>(w)] & (PhaseMask{1} << phase)) continue;  // no phase change
        const double distance = nearest_crossing(pv, pw, v, w, candidate);
        if (distance <= options.alpha && distance < best) best = distance, snap = candidate;
      }
      if (snap.mask != 0) snaps.push_back(snap);
    }
  }
  // 3. Apply all moves at once.
  for (const Snap& s : snaps) {
    nodes.position[static_cast<std::size_t>(s.node)] = s.position;
    nodes.mask[static_cast<std::size_t>(s.node)] = s.mask;
    nodes.snapped[static_cast<std::size_t>(s.node)] = 1;
  }
  nodes.snapped_count = static_cast<std::int64_t>(snaps.size());
  return nodes;
}

}  // namespace cisamr::radapt
