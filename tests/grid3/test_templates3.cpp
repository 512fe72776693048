// Closure templates: every table entry, the face rules against the refinement templates,
// and closed random refinements of a 2×2×2 block of cubes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <random>
#include <set>

#include "exact_mesh3.hpp"
#include "grid/tet_forest.hpp"
#include "mesh/metrics.hpp"
#include "subdivide/templates3.hpp"

namespace cisamr::subdivide::templates3 {
namespace {

using grid::LatticePoint3;

// Integer points of a reference tet (×16) with the closure's Steiner point.
std::array<LatticePoint3, 11> points(Kind kind, const Closure& c) {
  return detail::points_with_steiner(kind, c.uses_steiner ? c.steiner : kSteinerCandidates[0]);
}

double aspect(const std::array<LatticePoint3, 11>& p, const Tetra& t) {
  const auto v = [&](int i) {
    return Vec3{static_cast<double>(p[t[i]][0]), static_cast<double>(p[t[i]][1]), static_cast<double>(p[t[i]][2])};
  };
  return mesh::aspect_ratio(v(0), v(1), v(2), v(3));
}

// Checks one closure entry: positive sub-tets, volume, no point of the set inside or on a
// sub-tet other than its vertices, boundary faces = the face rules, interior faces matched.
void check_entry(Kind kind, unsigned mask, unsigned variant, const Closure& c, bool star) {
  SCOPED_TRACE(testing::Message() << (kind == Kind::corner ? "corner" : "regular") << " mask " << mask << " variant "
                                  << variant << (star ? " star" : " best"));
  const auto p = points(kind, c);
  ASSERT_GT(c.count, 0);
  ASSERT_LE(c.count, kMaxClosureTets);
  unsigned set = 0xfu;
  for (int e = 0; e < 6; ++e)
    if (has_midpoint(mask, e)) set |= 1u << tet::midpoint(e);
  if (c.uses_steiner) {
    set |= 1u << kSteiner;
    int sum = 0;
    for (int w : c.steiner) {
      sum += w;
      EXPECT_GT(w, 0);  // strictly inside
    }
    EXPECT_EQ(sum, kSteinerDenominator);
  }
  std::int64_t volume = 0;
  double worst = 0;
  std::map<std::array<int, 3>, std::vector<int>> faces;
  for (int i = 0; i < c.count; ++i) {
    const Tetra& t = c.tet[i];
    for (int a = 0; a < 4; ++a) ASSERT_TRUE((set >> t[a]) & 1u) << "uses absent point " << int(t[a]);
    const std::int64_t o = tet::orient(p[t[0]], p[t[1]], p[t[2]], p[t[3]]);
    ASSERT_GT(o, 0);
    volume += o;
    worst = std::max(worst, aspect(p, t));
    for (int q = 0; q < 11; ++q) {
      if (!((set >> q) & 1u) || std::count(t.begin(), t.end(), q)) continue;
      bool inside = true;
      for (int a = 0; a < 4 && inside; ++a) {
        Tetra s = t;
        s[a] = static_cast<std::uint8_t>(q);
        inside = tet::orient(p[s[0]], p[s[1]], p[s[2]], p[s[3]]) >= 0;
      }
      EXPECT_FALSE(inside) << "point " << q << " in sub-tet " << i;
    }
    for (const auto& f : tet::kFaces) {
      std::array<int, 3> v = {t[f[0]], t[f[1]], t[f[2]]};
      int parity = 1;
      for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b)
          if (v[a] > v[b]) parity = -parity;
      std::sort(v.begin(), v.end());
      faces[v].push_back(parity);
    }
  }
  EXPECT_EQ(volume, tet::orient(p[0], p[1], p[2], p[3]));
  EXPECT_NEAR(worst, c.max_aspect, 1e-12);
  // Boundary: exactly the face rules, outward.
  std::map<std::array<int, 3>, int> expected;
  for (int f = 0; f < 4; ++f) {
    const FacePattern fp = face_pattern(kind, mask, f, static_cast<int>((variant >> f) & 1u));
    for (int i = 0; i < fp.count; ++i) {
      std::array<int, 3> v = {fp.tri[i][0], fp.tri[i][1], fp.tri[i][2]};
      int parity = 1;
      for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b)
          if (v[a] > v[b]) parity = -parity;
      std::sort(v.begin(), v.end());
      expected[v] = parity;
    }
  }
  for (const auto& [v, uses] : faces) {
    if (uses.size() == 1) {
      auto it = expected.find(v);
      EXPECT_TRUE(it != expected.end()) << "open face " << v[0] << " " << v[1] << " " << v[2];
      if (it != expected.end()) {
        EXPECT_EQ(it->second, uses[0]);
      }
    } else {
      ASSERT_EQ(uses.size(), 2u);
      EXPECT_NE(uses[0], uses[1]);
      EXPECT_EQ(expected.count(v), 0u);
    }
  }
  for (const auto& [v, parity] : expected) EXPECT_EQ(faces.count(v), 1u);
}

TEST(Closure3, EveryTableEntryIsAValidTriangulationWithinTheBound) {
  const ClosureTables& tables = closure_tables();
  for (int k = 0; k < 2; ++k) {
    const Kind kind = static_cast<Kind>(k);
    double worst_best = 0, worst_star = 0, worst_steiner_free = 0;
    int steiner = 0, entries = 0, worst_mask = -1;
    for (unsigned mask = 0; mask < 64; ++mask)
      for (unsigned variant = 0; variant < 16; ++variant) {
        if (variant & ~quad_faces(mask)) continue;
        const std::size_t i = closure_index(kind, mask, variant);
        check_entry(kind, mask, variant, tables.best[i], false);
        check_entry(kind, mask, variant, tables.star[i], true);
        ++entries;
        if (tables.best[i].max_aspect > worst_best) worst_best = tables.best[i].max_aspect, worst_mask = int(mask);
        worst_star = std::max(worst_star, tables.star[i].max_aspect);
        if (tables.best[i].uses_steiner) ++steiner;
        else worst_steiner_free = std::max(worst_steiner_free, tables.best[i].max_aspect);
        EXPECT_LE(tables.best[i].max_aspect, tables.star[i].max_aspect + 1e-9);
      }
    std::printf("[closure3] %s tet: %d entries, worst AR best %.4f (mask %d), %d with a Steiner point, "
                "worst Steiner-free %.4f, worst centroid star %.4f\n",
                kind == Kind::corner ? "corner" : "regular", entries, worst_best, worst_mask, steiner,
                worst_steiner_free, worst_star);
    EXPECT_LE(worst_best, 5.0);
    EXPECT_LE(worst_star, 5.0);
  }
  // No midpoint: the tet itself. All six: the refinement template's quality.
  const auto& none = tables.best[closure_index(Kind::corner, 0, 0)];
  EXPECT_EQ(none.count, 1);
  EXPECT_NEAR(tables.best[closure_index(Kind::corner, 63, 0)].max_aspect, none.max_aspect, 1e-9);
  EXPECT_EQ(tables.best[closure_index(Kind::corner, 63, 0)].count, 7);
}

// The Steiner shortlist loses nothing: no interior point with weights in sixteenths gives
// a better closure for the entries that need a Steiner point.
TEST(Closure3, SteinerShortlistMatchesTheFullSearch) {
  const ClosureTables& tables = closure_tables();
  int searched = 0;
  for (int k = 0; k < 2; ++k) {
    const Kind kind = static_cast<Kind>(k);
    for (unsigned mask = 0; mask < 64; ++mask)
      for (unsigned variant = 0; variant < 16; ++variant) {
        if (variant & ~quad_faces(mask)) continue;
        const Closure& c = tables.best[closure_index(kind, mask, variant)];
        if (!c.uses_steiner) continue;
        unsigned set = 0xfu | (1u << kSteiner);
        for (int e = 0; e < 6; ++e)
          if (has_midpoint(mask, e)) set |= 1u << tet::midpoint(e);
        const auto boundary = detail::boundary_of(kind, mask, variant);
        for (int a = 1; a < 16; ++a)
          for (int b = 1; a + b < 16; ++b)
            for (int d = 1; a + b + d < 16; ++d) {
              const SteinerWeights w{std::uint8_t(a), std::uint8_t(b), std::uint8_t(d), std::uint8_t(16 - a - b - d)};
              Closure other;
              if (!detail::ClosureSearch(detail::points_with_steiner(kind, w), set, boundary).run(other)) continue;
              ++searched;
              EXPECT_GE(other.max_aspect, c.max_aspect - 1e-9) << "kind " << k << " mask " << mask << " variant "
                                                               << variant;
            }
      }
  }
  EXPECT_GT(searched, 1000);
}

// A face with three midpoints is triangulated exactly as the refined neighbour's children
// triangulate it.
TEST(Closure3, FullFacesMatchTheRefinementTemplates) {
  for (int k = 0; k < 2; ++k) {
    const Kind kind = static_cast<Kind>(k);
    const int n = tet::child_count(kind);
    for (int f = 0; f < 4; ++f) {
      std::set<std::array<int, 3>> from_children, from_rule;
      unsigned on_face = 0;
      for (int i = 0; i < 3; ++i) on_face |= 1u << tet::kFaces[f][i];
      for (int i = 0; i < 3; ++i) on_face |= 1u << tet::midpoint(tet::kFaceEdges[f][i]);
      for (int c = 0; c < n; ++c) {
        const auto& t = kind == Kind::corner ? tet::kCornerChildren[c] : tet::kRegularChildren[c];
        for (const auto& cf : tet::kFaces) {
          std::array<int, 3> v = {t[cf[0]], t[cf[1]], t[cf[2]]};
          if (((on_face >> v[0]) & (on_face >> v[1]) & (on_face >> v[2]) & 1u) == 0) continue;
          std::rotate(v.begin(), std::min_element(v.begin(), v.end()), v.end());
          from_children.insert(v);
        }
      }
      const FacePattern fp = face_pattern(kind, 63, f, 0);
      for (int i = 0; i < fp.count; ++i) {
        std::array<int, 3> v = {fp.tri[i][0], fp.tri[i][1], fp.tri[i][2]};
        std::rotate(v.begin(), std::min_element(v.begin(), v.end()), v.end());
        from_rule.insert(v);
      }
      EXPECT_EQ(from_children, from_rule) << "kind " << k << " face " << f;
      EXPECT_EQ(from_rule.size(), 4u);
    }
  }
}

TEST(Closure3, KeyRuleTakesTheDiagonalThroughTheSmallestKey) {
  // Face 0 of a tet with midpoints on edges 3 (1-2) and 4 (1-3): S = 1, quad
  // (m_12, 2, 3, m_13) — diagonal 0 joins m_12-3, diagonal 1 joins 2-m_13.
  const unsigned mask = (1u << 3) | (1u << 4);
  ASSERT_EQ(quad_faces(mask), 0b0001u);  // faces 2 and 3 hold one midpoint each
  const FaceQuad q = face_quad(mask, 0);
  EXPECT_EQ(q.s, 1);
  std::array<std::uint64_t, 10> keys{};
  for (int i = 0; i < 10; ++i) keys[i] = 100 + static_cast<std::uint64_t>(i);
  for (int smallest : {int(q.m_sp), int(q.p), int(q.q), int(q.m_sq)}) {
    auto k = keys;
    k[smallest] = 1;
    const unsigned v = quad_variant(mask, k);
    const int expect = (smallest == q.m_sp || smallest == q.q) ? 0 : 1;
    EXPECT_EQ(static_cast<int>(v & 1u), expect);
    const FacePattern fp = face_pattern(Kind::regular, mask, 0, expect);
    // The smallest-key quad vertex is on both quad triangles.
    int hits = 0;
    for (int i = 1; i < fp.count; ++i) hits += std::count(fp.tri[i].begin(), fp.tri[i].end(), smallest) ? 1 : 0;
    EXPECT_EQ(hits, 2);
  }
}

// ---------------------------------------------------------------------------------------
// Closed random refinements of a 2×2×2 block.
// ---------------------------------------------------------------------------------------

struct BlockStats {
  double worst = 0;
  std::size_t closure_tets = 0, refined_leaves = 0, tets = 0;
};

// Refines random tets of a 2×2×2 block to at most `levels`, balances (a leaf holding a
// node in its closure other than its vertices and edge midpoints is refined), closes
// every leaf with the tables, and checks the result.
BlockStats closed_random_block(unsigned seed, int levels, double p_refine, bool use_star) {
  grid::Lattice3 l;
  l.h = 1;
  l.max_level = levels + 1;
  l.coarse_cells = {2, 2, 2};
  grid::TetForest f(l, l.whole_domain());
  std::mt19937 rng(seed);
  std::bernoulli_distribution pick(p_refine);
  for (int level = 0; level < levels; ++level) {
    const auto n = static_cast<std::int32_t>(f.size());
    for (std::int32_t t = 0; t < n; ++t)
      if (f.is_leaf(t) && f.tet(t).level == level && pick(rng)) f.refine(t);
  }
  // Balance: refine until every leaf sees at most its vertices and edge midpoints.
  for (bool changed = true; changed;) {
    changed = false;
    std::set<LatticePoint3> nodes;
    for (std::int32_t t = 0; t < static_cast<std::int32_t>(f.size()); ++t)
      if (f.is_leaf(t))
        for (const auto& v : f.fine_vertices(t)) nodes.insert(v);
    const auto n = static_cast<std::int32_t>(f.size());
    for (std::int32_t t = 0; t < n; ++t) {
      if (!f.is_leaf(t)) continue;
      const auto v = f.fine_vertices(t);
      std::set<LatticePoint3> allowed(v.begin(), v.end());
      for (const auto& e : tet::kEdges)
        allowed.insert({(v[e[0]][0] + v[e[1]][0]) / 2, (v[e[0]][1] + v[e[1]][1]) / 2, (v[e[0]][2] + v[e[1]][2]) / 2});
      LatticePoint3 lo = v[0], hi = v[0];
      for (const auto& q : v)
        for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], q[d]), hi[d] = std::max(hi[d], q[d]);
      bool refine = false;
      for (auto it = nodes.lower_bound(lo); it != nodes.end() && (*it)[0] <= hi[0] && !refine; ++it) {
        const auto& q = *it;
        if (q[1] < lo[1] || q[1] > hi[1] || q[2] < lo[2] || q[2] > hi[2] || allowed.count(q)) continue;
        bool inside = true;
        for (int i = 0; i < 4 && inside; ++i) {
          auto w = v;
          w[i] = q;
          inside = tet::orient(w[0], w[1], w[2], w[3]) >= 0;
        }
        refine = inside;
      }
      if (refine) {
        f.refine(t);
        changed = true;
      }
    }
  }
  std::set<grid::LatticeKey3> node_keys;
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(f.size()); ++t)
    if (f.is_leaf(t))
      for (auto k : f.vertex_keys(t)) node_keys.insert(k);

  // Close every leaf. Exact coordinates ×16 so that Steiner points are lattice points.
  BlockStats stats;
  grid::testing::ExactMesh3 m;
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(f.size()); ++t) {
    if (!f.is_leaf(t)) continue;
    const auto v = f.fine_vertices(t);
    std::array<LatticePoint3, 11> p{};
    std::array<grid::LatticeKey3, 10> keys{};
    for (int i = 0; i < 4; ++i) p[i] = v[i];
    for (int e = 0; e < 6; ++e)
      for (int d = 0; d < 3; ++d)
        p[tet::midpoint(e)][d] = (v[tet::kEdges[e][0]][d] + v[tet::kEdges[e][1]][d]) / 2;
    unsigned mask = 0;
    for (int i = 0; i < 10; ++i) keys[i] = grid::key3(p[i]);
    for (int i = 0; i < 10; ++i)
      for (auto& x : p[i]) x *= kSteinerDenominator;
    for (int e = 0; e < 6; ++e)
      if (node_keys.count(keys[tet::midpoint(e)])) mask |= 1u << e;
    const Kind kind = f.kind(t);
    const Closure& c = use_star ? closure_tables().star[closure_index(kind, mask, quad_variant(mask, keys))]
                                : closure(kind, mask, keys);
    if (mask) {
      stats.closure_tets += c.count;
      ++stats.refined_leaves;
    }
    for (int d = 0; d < 3; ++d) {
      p[kSteiner][d] = 0;
      for (int i = 0; i < 4; ++i) p[kSteiner][d] += c.steiner[i] * v[i][d];
    }
    for (int i = 0; i < c.count; ++i) {
      const Tetra& s = c.tet[i];
      m.add(p[s[0]], p[s[1]], p[s[2]], p[s[3]]);
      const auto x = [&](int a) {
        return Vec3{static_cast<double>(p[s[a]][0]), static_cast<double>(p[s[a]][1]), static_cast<double>(p[s[a]][2])};
      };
      stats.worst = std::max(stats.worst, mesh::aspect_ratio(x(0), x(1), x(2), x(3)));
    }
  }
  stats.tets = m.tets.size();
  const std::int64_t side = kSteinerDenominator * 2 * l.units(0);
  const auto r = grid::testing::check_conformity(m, {0, 0, 0}, {side, side, side});
  EXPECT_TRUE(r.ok(6 * side * side * side)) << "seed " << seed << ": " << r.first_problem << " (non-positive "
                                            << r.non_positive << ", unmatched " << r.interior_unmatched << ")";
  return stats;
}

TEST(Closure3, RandomRefinementsOfABlockCloseConformingly) {
  BlockStats all;
  for (unsigned seed = 1; seed <= 60; ++seed) {
    const int levels = seed % 3 == 0 ? 2 : 1;
    const double p = 0.05 + 0.1 * (seed % 5);
    const BlockStats s = closed_random_block(seed, levels, p, false);
    all.worst = std::max(all.worst, s.worst);
    all.closure_tets += s.closure_tets;
    all.refined_leaves += s.refined_leaves;
  }
  std::printf("[closure3] 60 random blocks: %zu leaves with hanging midpoints closed by %zu tets, worst AR %.4f\n",
              all.refined_leaves, all.closure_tets, all.worst);
  EXPECT_GT(all.refined_leaves, 500u);
  EXPECT_LE(all.worst, 5.0);
}

TEST(Closure3, CentroidStarsAlsoCloseConformingly) {
  for (unsigned seed = 100; seed < 110; ++seed) {
    const BlockStats s = closed_random_block(seed, 1 + seed % 2, 0.3, true);
    EXPECT_LE(s.worst, 5.0);
  }
}

}  // namespace
}  // namespace cisamr::subdivide::templates3
