// r-adaptivity in 2D as a stage (radapt/radapt2.hpp): snap2 on hand-built scenes whose
// crossings are known, checked node by node.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <map>
#include <vector>

#include "geometry/oracle.hpp"
#include "radapt/radapt2.hpp"
#include "samr/samr2.hpp"
#include "support/stage_setup.hpp"

namespace cisamr {
namespace {

using geometry::Oracle2;
using geometry::SceneDesc;

constexpr PhaseMask kMatrix = 1, kInclusion = 2;

struct Snapped2 : testing::Stage2 {
  using Stage2::Stage2;

  std::int32_t node(std::int64_t x, std::int64_t y) const {
    const std::int64_t u = lattice.units(0);
    return nodes.id(grid::key2(x * u, y * u));
  }
  // The crossing of the edge between two lattice nodes nearest `from`, as the oracle gives
  // it on the segment oriented from the smaller key.
  Vec2 crossing_near(std::int32_t from, std::int32_t to) const {
    const bool from_first = nodes.key[static_cast<std::size_t>(from)] < nodes.key[static_cast<std::size_t>(to)];
    const Vec2 a = lattice_position(static_cast<std::size_t>(from_first ? from : to));
    const Vec2 b = lattice_position(static_cast<std::size_t>(from_first ? to : from));
    std::vector<geometry::Crossing> crossings;
    oracle.crossings(a, b, testing::all_inclusions(oracle), crossings);
    EXPECT_FALSE(crossings.empty());
    if (crossings.empty()) return a;
    const double t = from_first ? crossings.front().t : crossings.back().t;
    return {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])};
  }
};

SceneDesc circle_scene(Vec2 centre, double radius) {
  SceneDesc s = testing::box_scene(2, {0, 0, 0}, {4, 4, 0}, 1.0, 0);
  s.inclusions = {{geometry::Circle{centre, radius}, 2, 0}};
  return s;
}

// A circle of radius 0.8 around the lattice node (2, 2): its four axis neighbours lie 0.2
// edges from the circle and snap exactly onto the oracle's crossing; the centre lies 0.8
// edges from every crossing and stays.
TEST(Snap2, NodeWithinAlphaSnapsExactlyOntoTheCrossing) {
  const Snapped2 s(circle_scene({2, 2}, 0.8), 0.5);
  const std::int32_t centre = s.node(2, 2);
  ASSERT_GE(centre, 0);
  EXPECT_FALSE(s.nodes.snapped[static_cast<std::size_t>(centre)]);
  EXPECT_EQ(s.nodes.position[static_cast<std::size_t>(centre)], (Vec2{2, 2}));
  EXPECT_EQ(s.nodes.mask[static_cast<std::size_t>(centre)], kInclusion);
  const std::int64_t around[4][2] = {{3, 2}, {1, 2}, {2, 3}, {2, 1}};
  for (const auto& a : around) {
    const std::int32_t n = s.node(a[0], a[1]);
    ASSERT_GE(n, 0);
    SCOPED_TRACE("node (" + std::to_string(a[0]) + ", " + std::to_string(a[1]) + ")");
    EXPECT_TRUE(s.nodes.snapped[static_cast<std::size_t>(n)]);
    const Vec2 expected = s.crossing_near(n, centre);
    EXPECT_EQ(s.nodes.position[static_cast<std::size_t>(n)], expected);  // bit-equal
    EXPECT_NEAR(std::hypot(expected[0] - 2, expected[1] - 2), 0.8, 1e-12);
    EXPECT_EQ(s.nodes.mask[static_cast<std::size_t>(n)], kMatrix | kInclusion);
  }
  EXPECT_EQ(s.nodes.snapped_count, 4);
}

// The same circle with alpha = 0.1: the crossings lie 0.2 edges away, too far, nothing moves.
TEST(Snap2, NodeBeyondAlphaStays) {
  const Snapped2 s(circle_scene({2, 2}, 0.8), 0.1);
  EXPECT_EQ(s.nodes.snapped_count, 0);
  for (std::size_t n = 0; n < s.nodes.key.size(); ++n)
    EXPECT_EQ(s.nodes.position[n], s.lattice_position(n));
}

// An off-centre circle: every moved node moved along one axis by at most alpha·h onto the
// circle and now lies on the interface; every other node is at its lattice position.
TEST(Snap2, MovesAlongAxisEdgesOnly) {
  const Vec2 c{2.13, 1.91};
  const double r = 1.27, alpha = 0.5;
  const Snapped2 s(circle_scene(c, r), alpha);
  EXPECT_GT(s.nodes.snapped_count, 4);
  std::int64_t snapped = 0;
  for (std::size_t n = 0; n < s.nodes.key.size(); ++n) {
    const Vec2 home = s.lattice_position(n);
    const Vec2& p = s.nodes.position[n];
    if (!s.nodes.snapped[n]) {
      EXPECT_EQ(p, home);
      continue;
    }
    ++snapped;
    const int moved_axes = (p[0] != home[0] ? 1 : 0) + (p[1] != home[1] ? 1 : 0);
    EXPECT_EQ(moved_axes, 1) << "node " << n;
    EXPECT_LE(std::abs(p[0] - home[0]) + std::abs(p[1] - home[1]), alpha * s.lattice.h);
    EXPECT_NEAR(std::hypot(p[0] - c[0], p[1] - c[1]), r, 1e-12);
    EXPECT_EQ(s.nodes.mask[n], kMatrix | kInclusion);
  }
  EXPECT_EQ(snapped, s.nodes.snapped_count);
}

// All decisions are taken from the original positions and masks. In the rectangle
// [1.9, 2.7] × [1.95, 3.5], node (2, 2) snaps down onto y = 1.95 (0.05 away) and node
// (3, 2) snaps left onto x = 2.7 (0.3 away) across the edge to (2, 2). Had (2, 2) moved
// first, its new mask (matrix and inclusion) would have hidden the phase change from
// (3, 2). Node (2, 4) lies exactly half an edge from y = 3.5: the half-way crossing
// belongs to the end with the smaller key, (2, 3), so (2, 4) stays.
TEST(Snap2, DecisionsUseOriginalMasks) {
  SceneDesc scene = testing::box_scene(2, {0, 0, 0}, {4, 4, 0}, 1.0, 0);
  scene.inclusions = {{geometry::Polygon{{{1.9, 1.95}, {2.7, 1.95}, {2.7, 3.5}, {1.9, 3.5}}}, 2, 0}};
  const Snapped2 s(scene, 0.5);
  const auto at = [&](std::int64_t x, std::int64_t y) { return s.nodes.position[static_cast<std::size_t>(s.node(x, y))]; };
  const auto snapped = [&](std::int64_t x, std::int64_t y) { return s.nodes.snapped[static_cast<std::size_t>(s.node(x, y))] != 0; };
  EXPECT_TRUE(snapped(2, 2));
  EXPECT_EQ(at(2, 2), (Vec2{2, 1.95}));
  EXPECT_TRUE(snapped(3, 2));
  EXPECT_EQ(at(3, 2), (Vec2{2.7, 2}));
  EXPECT_EQ(s.nodes.mask[static_cast<std::size_t>(s.node(3, 2))], kMatrix | kInclusion);
  EXPECT_FALSE(snapped(2, 4));
  EXPECT_EQ(at(2, 4), (Vec2{2, 4}));
}

// The result does not depend on the order of the inclusions (the oracle's candidate lists
// and the order of its answers), nor on running twice: bit-equal positions per lattice key.
TEST(Snap2, OrderFree) {
  SceneDesc scene = testing::box_scene(2, {0, 0, 0}, {6, 4, 0}, 1.0, 1);
  scene.inclusions = {{geometry::Circle{{1.93, 2.08}, 1.14}, 2, 1},
                      {geometry::Ellipse{{4.4, 1.9}, {1.1, 0.7}, 0.4}, 2, 1},
                      {geometry::Polygon{{{3.2, 3.1}, {5.6, 3.3}, {4.1, 3.8}}}, 2, 1}};
  const Snapped2 first(scene, 0.5), again(scene, 0.5);
  std::reverse(scene.inclusions.begin(), scene.inclusions.end());
  const Snapped2 reversed(scene, 0.5);
  EXPECT_GT(first.nodes.snapped_count, 10);
  const auto table = [](const Snapped2& s) {
    std::map<grid::LatticeKey, std::pair<Vec2, PhaseMask>> t;
    for (std::size_t n = 0; n < s.nodes.key.size(); ++n) t[s.nodes.key[n]] = {s.nodes.position[n], s.nodes.mask[n]};
    return t;
  };
  EXPECT_EQ(table(first), table(again));
  EXPECT_EQ(table(first), table(reversed));
  EXPECT_EQ(first.nodes.snapped_count, reversed.nodes.snapped_count);
}

}  // namespace
}  // namespace cisamr
