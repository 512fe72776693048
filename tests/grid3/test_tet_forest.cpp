// The tet forest: roots, uniform refinement conformity, find and face neighbours
// against brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>

#include "core/error.hpp"
#include "exact_mesh3.hpp"
#include "grid/tet_forest.hpp"

namespace cisamr::grid {
namespace {

Lattice3 lattice(std::array<std::int64_t, 3> cells, int levels) {
  Lattice3 l;
  l.origin = {-1.0, 0.5, 2.0};
  l.h = 0.25;
  l.max_level = levels;
  l.coarse_cells = cells;
  return l;
}

testing::ExactMesh3 leaves_mesh(const TetForest& f) {
  testing::ExactMesh3 m;
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(f.size()); ++t)
    if (f.is_leaf(t)) {
      const auto v = f.fine_vertices(t);
      m.add(v[0], v[1], v[2], v[3]);
    }
  return m;
}

TEST(TetForest, RootsAreFiveTetsPerCube) {
  const Lattice3 l = lattice({4, 3, 2}, 2);
  CellRange<3> r;
  r.lo = {1, 0, 0};
  r.hi = {3, 3, 2};
  TetForest f(l, r);
  EXPECT_EQ(f.root_count(), 5 * 12);
  EXPECT_EQ(f.root(0, 0, 0, 0), -1);
  EXPECT_EQ(f.root(3, 0, 0, 0), -1);
  const std::int32_t t = f.root(2, 1, 1, 3);
  ASSERT_GE(t, 0);
  EXPECT_EQ(f.tet(t).cube, (std::array<std::int32_t, 3>{2, 1, 1}));
  EXPECT_EQ(f.tet(t).local, 3);
  EXPECT_EQ(f.kind(t), tet::Kind::corner);
  EXPECT_EQ(f.kind(f.root(2, 1, 1, 0)), tet::Kind::regular);
  // Vertices on the finest lattice (4 units per coarse cube) and their keys.
  const auto v = f.fine_vertices(t);
  for (const auto& p : v) {
    EXPECT_TRUE(p[0] == 8 || p[0] == 12);
    EXPECT_TRUE(p[1] == 4 || p[1] == 8);
    EXPECT_TRUE(p[2] == 4 || p[2] == 8);
  }
  EXPECT_EQ(f.vertex_keys(t)[2], key3(v[2]));
  const Vec3 x = f.position({4, 0, 8});
  EXPECT_DOUBLE_EQ(x[0], -0.75);
  EXPECT_DOUBLE_EQ(x[2], 2.5);
  // A range beyond the lattice, and a lattice beyond the key.
  r.hi[0] = 5;
  EXPECT_THROW(TetForest(l, r), MeshingError);
  EXPECT_THROW(TetForest(lattice({1 << 20, 1, 1}, 2), CellRange<3>{{0, 0, 0}, {1, 1, 1}}), MeshingError);
}

TEST(TetForest, UniformRefinementIsConforming) {
  const Lattice3 l = lattice({2, 1, 1}, 2);
  TetForest f(l, l.whole_domain());
  for (int level = 1; level <= 2; ++level) {
    const auto n = static_cast<std::int32_t>(f.size());
    for (std::int32_t t = 0; t < n; ++t)
      if (f.is_leaf(t)) f.refine(t);
    const auto m = leaves_mesh(f);
    EXPECT_EQ(m.tets.size(), 2u * 5 * (1u << (3 * level)));  // the level's honeycomb: 5 tets per cube
    const std::int64_t s = l.units(0);
    const auto r = testing::check_conformity(m, {0, 0, 0}, {2 * s, s, s});
    EXPECT_TRUE(r.ok(6 * 2 * s * s * s)) << "level " << level << ": " << r.first_problem;
  }
  EXPECT_THROW(f.refine(static_cast<std::int32_t>(f.size()) - 1), MeshingError);  // beyond Lmax
  EXPECT_THROW(f.refine(0), InternalError);                                      // not a leaf
}

// Random refinement; find() and face_neighbour() against a brute-force search by vertex
// keys over all tets of the forest.
TEST(TetForest, FindAndFaceNeighboursMatchBruteForce) {
  const Lattice3 l = lattice({2, 2, 2}, 3);
  TetForest f(l, l.whole_domain());
  std::mt19937 rng(11);
  std::bernoulli_distribution pick(0.3);
  for (int level = 0; level < 3; ++level) {
    const auto n = static_cast<std::int32_t>(f.size());
    for (std::int32_t t = 0; t < n; ++t)
      if (f.is_leaf(t) && f.tet(t).level == level && pick(rng)) f.refine(t);
  }
  // Every tet is found from its own code, and children point to their parent.
  std::map<std::pair<int, std::array<LatticeKey3, 4>>, std::int32_t> by_keys;
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(f.size()); ++t) {
    EXPECT_EQ(f.find(f.tet(t).level, f.code(t)), t);
    if (f.tet(t).parent >= 0) {
      const auto& p = f.tet(f.tet(t).parent);
      EXPECT_GE(t, p.first_child);
      EXPECT_LT(t, p.first_child + tet::child_count(kind_of_local(p.local)));
    }
    auto k = f.vertex_keys(t);
    std::sort(k.begin(), k.end());
    by_keys[{f.tet(t).level, k}] = t;
  }
  // The deepest tet at or above `level` containing a fine point strictly inside.
  const auto contains = [&](std::int32_t t, const LatticePoint3& p4) {
    auto v = f.fine_vertices(t);
    for (auto& q : v)
      for (auto& c : q) c *= 8;
    for (int i = 0; i < 4; ++i) {
      auto w = v;
      w[i] = p4;
      if (tet::orient(w[0], w[1], w[2], w[3]) <= 0) return false;
    }
    return true;
  };
  std::size_t checked_same = 0, checked_coarser = 0, outside = 0;
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(f.size()); ++t) {
    const auto v = f.fine_vertices(t);
    const int level = f.tet(t).level;
    for (int face = 0; face < 4; ++face) {
      const std::int32_t got = f.face_neighbour(t, face);
      // Brute force: a point just across the face centroid, ×8 fine units.
      LatticePoint3 p8{};
      for (int d = 0; d < 3; ++d) {
        std::int64_t s = 0;
        for (int i = 0; i < 4; ++i)
          if (i != face) s += v[i][d];
        p8[d] = 3 * s - v[face][d];
      }
      std::int32_t expect = -1;
      for (std::int32_t u = 0; u < static_cast<std::int32_t>(f.size()); ++u)
        if (f.tet(u).level <= level && contains(u, p8) &&
            (expect < 0 || f.tet(u).level > f.tet(expect).level))
          expect = u;
      EXPECT_EQ(got, expect) << "tet " << t << " face " << face;
      if (got < 0) {
        ++outside;
        continue;
      }
      if (f.tet(got).level == level) {
        ++checked_same;
        // Same level: shares the three face keys.
        auto k = f.vertex_keys(got);
        const auto mine = f.vertex_keys(t);
        int shared = 0;
        for (int i = 0; i < 4; ++i)
          if (i != face) shared += std::count(k.begin(), k.end(), mine[i]) > 0 ? 1 : 0;
        EXPECT_EQ(shared, 3);
        std::sort(k.begin(), k.end());
        EXPECT_EQ(by_keys.at({level, k}), got);
      } else {
        ++checked_coarser;
        EXPECT_TRUE(f.is_leaf(got));
      }
    }
  }
  EXPECT_GT(checked_same, 100u);
  EXPECT_GT(checked_coarser, 10u);
  EXPECT_GT(outside, 10u);
  // refine() takes children from a table by cube parity and local index: the same codes,
  // in the same order, as children_codes() of the parent's code.
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(f.size()); ++t) {
    if (f.is_leaf(t)) continue;
    std::array<TetCode, 12> expect{};
    const int n = children_codes(f.code(t), expect);
    ASSERT_EQ(n, f.child_count(t));
    for (int c = 0; c < n; ++c) EXPECT_EQ(f.code(f.tet(t).first_child + c), expect[c]) << "tet " << t << " child " << c;
  }
}

// leaves_at_midpoint() and find_near() against brute force on a randomly refined block:
// every leaf whose closed tet holds the midpoint, by orientation tests over all leaves.
TEST(TetForest, LeavesAtMidpointMatchBruteForce) {
  const Lattice3 l = lattice({3, 2, 2}, 3);
  TetForest f(l, CellRange<3>{{0, 0, 0}, {3, 2, 2}});
  std::mt19937 rng(5);
  std::bernoulli_distribution pick(0.35);
  for (int level = 0; level < 3; ++level) {
    const auto n = static_cast<std::int32_t>(f.size());
    for (std::int32_t t = 0; t < n; ++t)
      if (f.is_leaf(t) && f.tet(t).level == level && pick(rng)) f.refine(t);
  }
  const auto holds = [&](std::int32_t u, const LatticePoint3& p) {
    const auto v = f.fine_vertices(u);
    for (int i = 0; i < 4; ++i) {
      auto w = v;
      w[i] = p;
      if (tet::orient(w[0], w[1], w[2], w[3]) < 0) return false;
    }
    return true;
  };
  std::vector<std::int32_t> got;
  std::size_t edges = 0, with_finer = 0, with_coarser = 0;
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(f.size()); ++t) {
    const int level = f.tet(t).level;
    if (level >= l.max_level) continue;
    const auto v = f.fine_vertices(t);
    for (const auto& e : tet::kEdges) {
      const LatticePoint3 &a = v[e[0]], &b = v[e[1]];
      const LatticePoint3 p{(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
      got.clear();
      f.leaves_at_midpoint(a, b, level, t, got);
      std::sort(got.begin(), got.end());
      got.erase(std::unique(got.begin(), got.end()), got.end());
      std::vector<std::int32_t> expect;
      for (std::int32_t u = 0; u < static_cast<std::int32_t>(f.size()); ++u)
        if (f.is_leaf(u) && holds(u, p)) expect.push_back(u);
      EXPECT_EQ(got, expect) << "tet " << t << " edge " << int{e[0]} << "-" << int{e[1]};
      std::vector<std::int32_t> from_roots;
      f.leaves_at_midpoint(b, a, level, -1, from_roots);  // either orientation, no start
      std::sort(from_roots.begin(), from_roots.end());
      from_roots.erase(std::unique(from_roots.begin(), from_roots.end()), from_roots.end());
      EXPECT_EQ(from_roots, expect);
      ++edges;
      for (std::int32_t u : expect) {
        with_finer += f.tet(u).level > level ? 1 : 0;
        with_coarser += f.tet(u).level < level ? 1 : 0;
      }
    }
  }
  EXPECT_GT(edges, 1000u);
  EXPECT_GT(with_finer, 100u);
  EXPECT_GT(with_coarser, 100u);
  // find_near from any start agrees with find.
  std::uniform_int_distribution<std::int32_t> any(0, static_cast<std::int32_t>(f.size()) - 1);
  for (int i = 0; i < 2000; ++i) {
    const std::int32_t target = any(rng), start = any(rng);
    EXPECT_EQ(f.find_near(start, f.tet(target).level, f.code(target)), target);
    // A level below the target's: the leaf or tet on its path, as find() says.
    const int level = std::max(0, f.tet(target).level - 1);
    const TetCode parent_code = f.code(f.tet(target).parent >= 0 ? f.tet(target).parent : target);
    if (f.tet(target).parent >= 0) {
      EXPECT_EQ(f.find_near(start, level, parent_code), f.find(level, parent_code));
    }
  }
}

}  // namespace
}  // namespace cisamr::grid
