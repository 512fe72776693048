#include "radapt/radapt2.hpp"

#include <bit>
#include <cmath>
#include <limits>

namespace cisamr::radapt {
namespace {

using grid::LatticeKey;

int single_phase(PhaseMask m) { return std::popcount(m) == 1 ? std::countr_zero(m) : -1; }

}  // namespace

Nodes2 snap2(const geometry::Oracle2& oracle, const samr::RefinedGrid2& g, const Options& options) {
  const grid::QuadForest& forest = g.forest;
  const grid::Lattice2& lattice = forest.lattice();
  Nodes2 nodes;
  nodes.lattice = lattice;
  {
    auto& r = nodes.registry;
    r.unit = lattice.units(0);
    r.x0 = forest.range().lo[0];
    r.y0 = forest.range().lo[1];
    r.nx = forest.range().count(0);
    r.ny = forest.range().count(1);
    r.period_x = lattice.periodic[0] ? lattice.coarse_cells[0] : 0;
    r.period_y = lattice.periodic[1] ? lattice.coarse_cells[1] : 0;
    r.coarse.assign(static_cast<std::size_t>((r.nx + 1) * (r.ny + 1)), -1);
    // A refinement adds four cells and about three nodes off the coarse lattice (the centre,
    // four edge midpoints shared with the neighbours).
    r.fine = grid::LatticeKeyIndex((forest.size() - static_cast<std::size_t>(forest.root_count())) / 8 * 7 + 16);
  }
  // At most one node per cell (a corner of the leaves, a few more along the domain's
  // faces): reserved, the arrays never grow by copying; capacity never written costs no
  // memory.
  nodes.key.reserve(forest.size() + static_cast<std::size_t>(forest.root_count()) + 16);
  nodes.position.reserve(nodes.key.capacity());
  nodes.mask.reserve(nodes.key.capacity());

  const auto add_node = [&](std::int64_t x, std::int64_t y) -> std::int32_t {
    x = lattice.canonical(0, x), y = lattice.canonical(1, y);
    bool inserted = false;
    const auto next = static_cast<std::int32_t>(nodes.key.size());
    std::int32_t id;
    if (std::int32_t* slot = nodes.registry.coarse_slot(x, y)) {
      inserted = *slot < 0;
      if (inserted) *slot = next;
      id = *slot;
    } else {
      id = nodes.registry.fine.insert(grid::key2(x, y), next, nodes.key, inserted);
    }
    if (inserted) {
      nodes.key.push_back(grid::key2(x, y));
      nodes.position.push_back({lattice.coordinate(0, x), lattice.coordinate(1, y)});
      nodes.mask.push_back(0);
    }
    return id;
  };

  std::vector<std::int32_t> plane_candidates;
  const auto on_periodic_plane = [&](grid::LatticeKey k) {
    return (lattice.periodic[0] && grid::key2_x(k) == 0) || (lattice.periodic[1] && grid::key2_y(k) == 0);
  };
  // The position of node `id` seen at frame point (fx, fy) ∈ [0, P] (lattice.hpp).
  const auto frame_position = [&](std::int32_t id, std::int64_t fx, std::int64_t fy) {
    return lattice.shifted(nodes.position[static_cast<std::size_t>(id)], lattice.image_shift({fx, fy}));
  };
  // 1. Corners of every leaf, and their phases. A leaf that no boundary meets lies inside
  //    one phase, so its corners take that phase without asking the oracle per corner.
  nodes.cell_corners.resize(forest.size());
  const PhaseMask matrix_bit = PhaseMask{1} << oracle.matrix_phase();
  const auto cells = static_cast<std::int64_t>(forest.size());
  for (std::int32_t c = 0; c < static_cast<std::int32_t>(forest.size()); ++c) {
    advance_sometimes(options.progress, c, 2 * cells);
    if (!forest.is_leaf(c)) continue;
    const std::int64_t x = forest.fine_x(c), y = forest.fine_y(c), s = forest.fine_size(c);
    const std::int32_t ids[4] = {add_node(x, y), add_node(x + s, y), add_node(x + s, y + s), add_node(x, y + s)};
    nodes.cell_corners[static_cast<std::size_t>(c)] = {ids[0], ids[1], ids[2], ids[3]};
    const auto candidates = g.candidates_of_root(g.root_of(c));
    if (g.is_cut(c)) {
      for (std::int32_t id : ids)
        if (nodes.mask[static_cast<std::size_t>(id)] == 0) {
          const Vec2& p = nodes.position[static_cast<std::size_t>(id)];
          // A node on a periodic plane is a corner of cells on both sides of the period,
          // whose candidate lists hold the geometry in different frames: ask for its own.
          if (on_periodic_plane(nodes.key[static_cast<std::size_t>(id)])) {
            oracle.candidates(Box2{p, p}, plane_candidates);
            nodes.mask[static_cast<std::size_t>(id)] = oracle.closure_phases(p, plane_candidates);
          } else {
            nodes.mask[static_cast<std::size_t>(id)] = oracle.closure_phases(p, candidates);
          }
        }
    } else {
      PhaseMask bit = matrix_bit;
      if (!candidates.empty()) {
        const Box2 b = forest.box(c);
        const Vec2 centre{0.5 * (b.min[0] + b.max[0]), 0.5 * (b.min[1] + b.max[1])};
        bit = PhaseMask{1} << oracle.phase_at(centre, candidates);
      }
      for (std::int32_t id : ids)
        if (nodes.mask[static_cast<std::size_t>(id)] == 0) nodes.mask[static_cast<std::size_t>(id)] = bit;
    }
  }
  const std::size_t n = nodes.key.size();
  struct Snap {
    std::int32_t node;
    Vec2 position;
    PhaseMask mask;
  };
  nodes.snapped.assign(n, 0);

  // 2. Snap decisions, from original positions and masks only.
  const std::int64_t fine_max_x = lattice.fine_period(0), fine_max_y = lattice.fine_period(1);
  const auto can_move = [&](std::int64_t x, std::int64_t y, int axis) {
    // On the domain boundary a node may only slide along it.
    return axis == 0 ? !(x == 0 || x == fine_max_x) : !(y == 0 || y == fine_max_y);
  };
  std::vector<std::uint8_t> visited(n, 0);
  std::vector<Snap> snaps;
  std::vector<geometry::Crossing> crossings;
  static constexpr int kDirections[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};  // +x,-x,+y,-y

  // The crossing of edge v→w nearest v, as a distance in units of the edge length, or +inf.
  const auto nearest_crossing = [&](std::int64_t vx, std::int64_t vy, std::int64_t wx, std::int64_t wy,
                                    std::int32_t v, std::int32_t w, Snap& out) -> double {
    // Keys in the edge's frame (v is canonical; w may be the image at P of a canonical 0).
    const bool v_first = grid::key2(vx, vy) < grid::key2(wx, wy);
    const Vec2 pv = nodes.position[static_cast<std::size_t>(v)], pw = frame_position(w, wx, wy);
    const Vec2 pa = v_first ? pv : pw, pb = v_first ? pw : pv;
    const std::int64_t units = lattice.units(0);
    // The root holding the edge's midpoint (an edge on a non-periodic max face: the last).
    const auto cell = [&](int d, std::int64_t mid) {
      return lattice.periodic[d] ? mid / units : std::min(mid / units, forest.range().hi[d] - 1);
    };
    const std::int32_t root = forest.root(cell(0, (vx + wx) / 2), cell(1, (vy + wy) / 2));
    if (root < 0) return std::numeric_limits<double>::infinity();
    oracle.crossings(pa, pb, g.candidates_of_root(root), crossings);
    if (crossings.empty()) return std::numeric_limits<double>::infinity();
    const geometry::Crossing& cross = v_first ? crossings.front() : crossings.back();
    out.position = {pa[0] + cross.t * (pb[0] - pa[0]), pa[1] + cross.t * (pb[1] - pa[1])};
    out.mask = (PhaseMask{1} << cross.from_phase) | (PhaseMask{1} << cross.to_phase);
    // A crossing exactly half-way belongs to the endpoint with the smaller key.
    const double d = v_first ? cross.t : 1.0 - cross.t;
    return (d == options.alpha && !v_first) ? std::nextafter(d, 1.0) : d;
  };

  // Each node of a cut cell takes its nearest crossing closer than alpha·h_l.
  for (std::int32_t c = 0; c < static_cast<std::int32_t>(forest.size()); ++c) {
    advance_sometimes(options.progress, cells + c, 2 * cells);
    if (!forest.is_leaf(c) || !g.is_cut(c)) continue;
    const std::int64_t x0 = forest.fine_x(c), y0 = forest.fine_y(c), s = forest.fine_size(c);
    const std::int64_t corners[4][2] = {{x0, y0}, {x0 + s, y0}, {x0 + s, y0 + s}, {x0, y0 + s}};
    for (int k = 0; k < 4; ++k) {
      // The node's decision is taken in its canonical frame, whichever cell visits it first.
      const std::int64_t vx = lattice.canonical(0, corners[k][0]), vy = lattice.canonical(1, corners[k][1]);
      const std::int32_t v = nodes.cell_corners[static_cast<std::size_t>(c)][static_cast<std::size_t>(k)];
      if (visited[static_cast<std::size_t>(v)]) continue;
      visited[static_cast<std::size_t>(v)] = 1;
      const int phase = single_phase(nodes.mask[static_cast<std::size_t>(v)]);
      if (phase < 0) continue;  // already on an interface
      double best = std::numeric_limits<double>::infinity();
      Snap snap{v, {}, 0}, candidate{v, {}, 0};
      for (const auto& d : kDirections) {
        if (!can_move(vx, vy, d[0] != 0 ? 0 : 1)) continue;
        const std::int64_t wx = vx + d[0] * s, wy = vy + d[1] * s;
        const std::int32_t w = nodes.id(wx, wy);
        if (w < 0) continue;  // beyond the ghost layer
        if (nodes.mask[static_cast<std::size_t>(w)] & (PhaseMask{1} << phase)) continue;  // no phase change
        const double distance = nearest_crossing(vx, vy, wx, wy, v, w, candidate);
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
  advance(options.progress, 2 * cells, 2 * cells);
  return nodes;
}

}  // namespace cisamr::radapt
