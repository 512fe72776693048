// r-adaptivity in 3D as a stage (radapt/radapt3.hpp): snap3 on small hand-built scenes.
// Without the guard, every node snaps to exactly the crossing a brute-force reference
// finds; with it, no leaf emits a tetrahedron above the bound, where the same scene
// without it does.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <tuple>
#include <vector>

#include "geometry/oracle.hpp"
#include "radapt/radapt3.hpp"
#include "samr/samr3.hpp"
#include "support/stage_setup.hpp"

namespace cisamr {
namespace {

using geometry::Oracle3;
using geometry::SceneDesc;
namespace tet = grid::tet;

struct Snapped3 : testing::Stage3 {
  using Stage3::Stage3;

  // The worst aspect ratio over what every leaf emits (grid/cut_stencil3.hpp), with the
  // nodes' final positions and masks.
  double worst_emitted() const {
    double worst = 0;
    for (std::int32_t t = 0; t < static_cast<std::int32_t>(grid.forest.size()); ++t) {
      if (!grid.forest.is_leaf(t)) continue;
      const auto o = testing::emitted(nodes, nodes.tet_nodes[static_cast<std::size_t>(t)], grid.forest.fine_vertices(t));
      worst = std::max(worst, testing::worst_aspect(o, oracle.scene()));
    }
    return worst;
  }
};

radapt::Options3 unguarded_axis_only() {
  return radapt::Options3{.alpha = 0.5, .alpha_diagonal = 0, .max_candidates = 2, .bound = 0};
}

SceneDesc sphere_scene(const Vec3& centre, double radius, int levels) {
  SceneDesc s = testing::box_scene(3, {0, 0, 0}, {1, 1, 1}, 0.25, levels);
  s.inclusions = {{geometry::Sphere{centre, radius}, 2, levels}};
  return s;
}

// Brute force over the phase-changing axis edges of the cut leaves, from the original
// lattice positions and the oracle's closure masks: each node whose nearest crossing on
// such an edge lies within alpha of the edge goes to the nearest of them (ties: the edge's
// other end with the smaller key); every other node stays.
TEST(Snap3, UnguardedAxisSnapsMatchABruteForceReference) {
  const radapt::Options3 options = unguarded_axis_only();
  for (int levels : {0, 1}) {
    SCOPED_TRACE("levels " + std::to_string(levels));
    const Snapped3 s(sphere_scene({0.52, 0.47, 0.55}, 0.27, levels), options);
    const auto all = testing::all_inclusions(s.oracle);
    std::vector<PhaseMask> original(s.nodes.key.size());
    for (std::size_t n = 0; n < original.size(); ++n) original[n] = s.oracle.closure_phases(s.lattice_position(n), all);

    // Per node: (distance, other key, position) of the best candidate.
    std::map<std::int32_t, std::tuple<double, grid::LatticeKey3, Vec3>> best;
    std::set<std::pair<std::int32_t, std::int32_t>> seen;
    std::vector<geometry::Crossing> crossings;
    const auto& forest = s.grid.forest;
    for (std::int32_t t = 0; t < static_cast<std::int32_t>(forest.size()); ++t) {
      if (!forest.is_leaf(t) || !s.grid.is_cut(t)) continue;
      const auto& ids = s.nodes.tet_nodes[static_cast<std::size_t>(t)];
      const auto v = forest.fine_vertices(t);
      for (const auto& e : tet::kEdges) {
        std::int32_t lo = ids[e[0]], hi = ids[e[1]];
        const auto& pa = v[e[0]];
        const auto& pb = v[e[1]];
        const int differing = (pa[0] != pb[0]) + (pa[1] != pb[1]) + (pa[2] != pb[2]);
        if (differing != 1) continue;
        if (original[static_cast<std::size_t>(lo)] & original[static_cast<std::size_t>(hi)]) continue;
        if (s.nodes.key[static_cast<std::size_t>(hi)] < s.nodes.key[static_cast<std::size_t>(lo)]) std::swap(lo, hi);
        if (!seen.insert({lo, hi}).second) continue;
        const Vec3 a = s.lattice_position(static_cast<std::size_t>(lo)), b = s.lattice_position(static_cast<std::size_t>(hi));
        s.oracle.crossings(a, b, all, crossings);
        ASSERT_FALSE(crossings.empty());
        const double length = mesh::distance<3>(a, b);
        for (const std::int32_t end : {lo, hi}) {
          if (!single_bit(original[static_cast<std::size_t>(end)])) continue;
          const double t_near = end == lo ? crossings.front().t : crossings.back().t;
          const double fraction = end == lo ? t_near : 1.0 - t_near;
          if (fraction > options.alpha) continue;
          const Vec3 p{a[0] + t_near * (b[0] - a[0]), a[1] + t_near * (b[1] - a[1]), a[2] + t_near * (b[2] - a[2])};
          const auto candidate = std::tuple{fraction * length, s.nodes.key[static_cast<std::size_t>(end == lo ? hi : lo)], p};
          auto [it, inserted] = best.try_emplace(end, candidate);
          if (!inserted && std::tie(std::get<0>(candidate), std::get<1>(candidate)) <
                               std::tie(std::get<0>(it->second), std::get<1>(it->second)))
            it->second = candidate;
        }
      }
    }
    EXPECT_GT(best.size(), levels == 0 ? 8u : 40u);
    EXPECT_EQ(s.nodes.snapped_count, static_cast<std::int64_t>(best.size()));
    EXPECT_EQ(s.nodes.refused_count, 0);
    EXPECT_EQ(s.nodes.collapsed_count, 0);
    for (std::size_t n = 0; n < s.nodes.key.size(); ++n) {
      const auto it = best.find(static_cast<std::int32_t>(n));
      const Vec3 home = s.lattice_position(n);
      const Vec3& p = s.nodes.position[n];
      if (it == best.end()) {
        EXPECT_EQ(s.nodes.state[n], radapt::NodeState::stayed) << "node " << n;
        EXPECT_EQ(p, home) << "node " << n;
        continue;
      }
      EXPECT_EQ(s.nodes.state[n], radapt::NodeState::snapped) << "node " << n;
      EXPECT_EQ(p, std::get<2>(it->second)) << "node " << n;  // bit-equal to the oracle's crossing
      EXPECT_EQ((p[0] != home[0]) + (p[1] != home[1]) + (p[2] != home[2]), 1) << "node " << n << " left its axis";
      EXPECT_EQ(std::popcount(s.nodes.mask[n]), 2);
    }
  }
}

// The reach along face diagonals is an option: with it, some nodes move along a diagonal
// (two coordinates change); without it, none does.
TEST(Snap3, DiagonalReachIsTheOnlyWayOffTheAxes) {
  const SceneDesc scene = sphere_scene({0.52, 0.47, 0.55}, 0.27, 1);
  const auto off_axis = [&](const radapt::Options3& options) {
    const Snapped3 s(scene, options);
    int count = 0;
    for (std::size_t n = 0; n < s.nodes.key.size(); ++n) {
      const Vec3 home = s.lattice_position(n);
      const Vec3& p = s.nodes.position[n];
      count += (p[0] != home[0]) + (p[1] != home[1]) + (p[2] != home[2]) > 1 ? 1 : 0;
    }
    return count;
  };
  EXPECT_EQ(off_axis(unguarded_axis_only()), 0);
  radapt::Options3 diagonal = unguarded_axis_only();
  diagonal.alpha_diagonal = 0.2;
  EXPECT_GT(off_axis(diagonal), 0);
}

// A sphere barely poking through the top face of the box: a wedge of matrix between the
// sphere and the face, thinner than a cell, where nodes on the face may not move along its
// normal. Unguarded snapping leaves tetrahedra above 5 there; the guard refuses those
// moves, collapses the nodes where no option keeps the bound, and every leaf then emits
// only tetrahedra within 5. Each collapsed node lies within the reported deviation of the
// phases it joined.
TEST(Snap3, GuardRefusesAndCollapsesWhereSnappingBreaksTheBound) {
  SceneDesc scene = testing::box_scene(3, {0.2, 0.2, 0.6}, {0.8, 0.8, 1.0}, 0.1, 1);
  scene.inclusions = {{geometry::Sphere{{0.5, 0.5, 1.247}, 0.25}, 2, 1}};

  radapt::Options3 off;
  off.bound = 0;
  const Snapped3 bare(scene, off);
  EXPECT_EQ(bare.nodes.refused_count, 0);
  EXPECT_EQ(bare.nodes.collapsed_count, 0);
  EXPECT_EQ(bare.nodes.guarded_leaves, 0);
  const double bare_worst = bare.worst_emitted();
  EXPECT_GT(bare_worst, 5.0) << "the scene no longer breaks the bound without the guard";

  const Snapped3 guarded(scene, radapt::Options3{});
  const double guarded_worst = guarded.worst_emitted();
  std::printf("[snap3] wedge: worst %.2f unguarded, %.3f guarded; %lld refused, %lld collapsed (deviation %.4f)\n",
              bare_worst, guarded_worst, static_cast<long long>(guarded.nodes.refused_count),
              static_cast<long long>(guarded.nodes.collapsed_count), guarded.nodes.max_collapse_deviation);
  EXPECT_LE(guarded_worst, 5.0);
  EXPECT_GT(guarded.nodes.guarded_leaves, 0);
  EXPECT_GT(guarded.nodes.refused_count, 0);
  EXPECT_GT(guarded.nodes.collapsed_count, 0);
  EXPECT_LE(guarded.nodes.collapsed_count, guarded.nodes.refused_count);  // a collapse is a refused first option
  EXPECT_EQ(guarded.nodes.missing_crossings, 0);

  // The refused options are moves the unguarded run made: the same lattice nodes end
  // elsewhere.
  std::int64_t differ = 0;
  for (std::size_t n = 0; n < bare.nodes.key.size(); ++n) {
    ASSERT_EQ(bare.nodes.key[n], guarded.nodes.key[n]);
    differ += bare.nodes.position[n] != guarded.nodes.position[n] || bare.nodes.mask[n] != guarded.nodes.mask[n];
  }
  EXPECT_GE(differ, guarded.nodes.refused_count);

  const auto all = testing::all_inclusions(guarded.oracle);
  std::int64_t collapsed = 0;
  for (std::size_t n = 0; n < guarded.nodes.key.size(); ++n) {
    if (guarded.nodes.state[n] != radapt::NodeState::collapsed) continue;
    ++collapsed;
    const Vec3& p = guarded.nodes.position[n];
    EXPECT_EQ(p, guarded.lattice_position(n)) << "a collapsed node stays where it is";
    const PhaseMask own = guarded.oracle.closure_phases(p, all);
    const PhaseMask joined = guarded.nodes.mask[n] & ~own;
    EXPECT_NE(joined, 0u);
    for (PhaseMask rest = joined; rest != 0; rest &= rest - 1)
      EXPECT_LE(guarded.oracle.distance_to_phase(p, std::countr_zero(rest)),
                guarded.nodes.max_collapse_deviation * (1 + 1e-12) + 1e-15);
  }
  EXPECT_EQ(collapsed, guarded.nodes.collapsed_count);
  EXPECT_LE(guarded.nodes.max_collapse_deviation, scene.h);
}

// Two tangent spheres of different phases: the gap of matrix between them is thinner than
// any cell. The guard still certifies every leaf; unguarded snapping does not.
TEST(Snap3, GuardHoldsTheBoundAtATangency) {
  SceneDesc scene = testing::box_scene(3, {0, 0, 0}, {1, 1, 1}, 0.125, 1);
  scene.phases.push_back({3, "other", false});
  scene.inclusions = {{geometry::Sphere{{0.3, 0.5, 0.5}, 0.2}, 2, 1}, {geometry::Sphere{{0.7, 0.5, 0.5}, 0.2}, 3, 1}};
  radapt::Options3 off;
  off.bound = 0;
  const Snapped3 bare(scene, off), guarded(scene, radapt::Options3{});
  const double bare_worst = bare.worst_emitted(), guarded_worst = guarded.worst_emitted();
  std::printf("[snap3] tangency: worst %.3g unguarded, %.3f guarded; %lld refused, %lld collapsed, %lld collapsed cut points\n",
              bare_worst, guarded_worst, static_cast<long long>(guarded.nodes.refused_count),
              static_cast<long long>(guarded.nodes.collapsed_count),
              static_cast<long long>(guarded.nodes.collapsed_cut_points));
  EXPECT_GT(bare_worst, 5.0);  // here even inverted tets
  EXPECT_LE(guarded_worst, 5.0);
  EXPECT_GT(guarded.nodes.refused_count, 0);
  EXPECT_GT(guarded.nodes.collapsed_count, 0);
  EXPECT_LE(guarded.nodes.collapsed_count, guarded.nodes.refused_count);
}

// The result does not depend on the order of the inclusions nor on running twice:
// bit-equal positions, masks and states per lattice key.
TEST(Snap3, OrderFree) {
  SceneDesc scene = testing::box_scene(3, {0, 0, 0}, {1, 1, 1}, 0.25, 1);
  scene.inclusions = {{geometry::Sphere{{0.31, 0.36, 0.42}, 0.19}, 2, 1},
                      {geometry::Sphere{{0.69, 0.62, 0.58}, 0.21}, 2, 1},
                      {geometry::Sphere{{0.34, 0.71, 0.73}, 0.14}, 2, 1}};
  const Snapped3 first(scene, radapt::Options3{}), again(scene, radapt::Options3{});
  std::reverse(scene.inclusions.begin(), scene.inclusions.end());
  const Snapped3 reversed(scene, radapt::Options3{});
  EXPECT_GT(first.nodes.snapped_count, 20);
  const auto table = [](const Snapped3& s) {
    std::map<grid::LatticeKey3, std::tuple<Vec3, PhaseMask, radapt::NodeState>> t;
    for (std::size_t n = 0; n < s.nodes.key.size(); ++n)
      t[s.nodes.key[n]] = {s.nodes.position[n], s.nodes.mask[n], s.nodes.state[n]};
    return t;
  };
  EXPECT_EQ(table(first), table(again));
  EXPECT_EQ(table(first), table(reversed));
  EXPECT_EQ(first.nodes.refused_count, reversed.nodes.refused_count);
  EXPECT_EQ(first.nodes.collapsed_count, reversed.nodes.collapsed_count);
}

// The node and edge look-ups the later stages use: every node by its key, every
// phase-changing edge by its keys in either order (the same index as the cut leaves'
// slots), and -1 for pairs that are no such edge.
TEST(Snap3, NodesAndEdgesFoundByTheirKeys) {
  SceneDesc scene = testing::box_scene(3, {0, 0, 0}, {1, 1, 1}, 0.25, 1);
  scene.inclusions = {{geometry::Sphere{{0.31, 0.36, 0.42}, 0.19}, 2, 1},
                      {geometry::Sphere{{0.69, 0.62, 0.58}, 0.21}, 2, 1}};
  const Snapped3 s(scene, radapt::Options3{});
  for (std::size_t n = 0; n < s.nodes.key.size(); ++n) EXPECT_EQ(s.nodes.id(s.nodes.key[n]), static_cast<std::int32_t>(n));
  ASSERT_GT(s.nodes.edges.size(), 100u);
  for (std::size_t e = 0; e < s.nodes.edges.size(); ++e) {
    const radapt::EdgeCut& c = s.nodes.edges[e];
    EXPECT_EQ(s.nodes.edge(c.lo, c.hi), static_cast<std::int32_t>(e));
    EXPECT_EQ(s.nodes.edge(c.hi, c.lo), static_cast<std::int32_t>(e));
    EXPECT_EQ(s.nodes.edge(c.lo, c.lo), -1);
  }
  std::size_t slots = 0;
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(s.grid.forest.size()); ++t) {
    const auto* edges = s.nodes.edges_of(t);
    if (edges == nullptr) continue;
    const auto& ids = s.nodes.tet_nodes[static_cast<std::size_t>(t)];
    for (int e = 0; e < 6; ++e) {
      const std::int32_t slot = (*edges)[static_cast<std::size_t>(e)];
      const grid::LatticeKey3 a = s.nodes.key[static_cast<std::size_t>(ids[tet::kEdges[e][0]])];
      const grid::LatticeKey3 b = s.nodes.key[static_cast<std::size_t>(ids[tet::kEdges[e][1]])];
      EXPECT_EQ(s.nodes.edge(a, b), slot);
      slots += slot >= 0 ? 1 : 0;
    }
  }
  EXPECT_GE(slots, s.nodes.edges.size());
  EXPECT_EQ(s.nodes.id(grid::key3(1000000, 1000000, 1000000)), -1);  // beyond the lattice
}

}  // namespace
}  // namespace cisamr
