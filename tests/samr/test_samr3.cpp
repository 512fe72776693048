// 3D SAMR (lib/samr/samr3.hpp) on seeded random scenes: the rules hold on the result,
// checked by brute force, and the work-list refiner gives the same forest as the plain
// synchronous sweeps it replaced (kept below as the reference), on whole domains and on
// partition boxes with a ghost layer.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <unordered_set>
#include <vector>

#include "core/error.hpp"
#include "geometry/oracle.hpp"
#include "grid/key_map.hpp"
#include "samr/samr3.hpp"

namespace cisamr {
namespace {

using grid::LatticeKey3;
using grid::LatticePoint3;
namespace tet = grid::tet;

// ---------------------------------------------------------------------------------------
// Reference: the synchronous sweeps (every sweep rebuilds the node sets from all leaves,
// marks every leaf a rule fires on, then refines the marked leaves in index order).
// ---------------------------------------------------------------------------------------

struct KeySet {
  grid::KeyMap map;
  explicit KeySet(std::size_t expected) : map(expected) {}
  void insert(LatticeKey3 k) {
    bool inserted = false;
    map.insert(k, 1, inserted);
  }
  bool contains(LatticeKey3 k) const { return map.find(k) != grid::KeyMap::kNone; }
};

LatticePoint3 weighted(const std::array<LatticePoint3, 4>& v, const std::array<int, 4>& w, int denominator) {
  LatticePoint3 p{};
  for (int d = 0; d < 3; ++d) p[d] = (w[0] * v[0][d] + w[1] * v[1][d] + w[2] * v[2][d] + w[3] * v[3][d]) / denominator;
  return p;
}

std::vector<std::array<int, 4>> quarter_probes() {
  std::vector<std::array<int, 4>> p;
  for (const auto& e : tet::kEdges) {
    std::array<int, 4> w{};
    w[e[0]] = 3, w[e[1]] = 1;
    p.push_back(w);
    w[e[0]] = 1, w[e[1]] = 3;
    p.push_back(w);
  }
  for (const auto& f : tet::kFaces)
    for (int i = 0; i < 3; ++i) {
      std::array<int, 4> w{};
      w[f[0]] = 1, w[f[1]] = 1, w[f[2]] = 1;
      w[f[i]] = 2;
      p.push_back(w);
    }
  return p;
}

class ReferenceRefiner {
 public:
  ReferenceRefiner(const geometry::Oracle3& oracle, samr::RefinedGrid3& g, std::span<const int> levels)
      : oracle_(oracle), g_(g), levels_(levels), probes_(quarter_probes()) {}

  void run() {
    const int max_level = g_.forest.lattice().max_level;
    std::vector<std::int32_t> marked;
    while (true) {
      ++g_.sweeps;
      const std::size_t n = g_.forest.size();
      KeySet nodes(n), movable(n / 4 + 16);
      for (std::int32_t t = 0; t < static_cast<std::int32_t>(n); ++t) {
        if (!g_.forest.is_leaf(t)) continue;
        const auto keys = g_.forest.vertex_keys(t);
        for (LatticeKey3 k : keys) nodes.insert(k);
        if (g_.is_cut(t))
          for (LatticeKey3 k : keys) movable.insert(k);
      }
      marked.clear();
      for (std::int32_t t = 0; t < static_cast<std::int32_t>(n); ++t)
        if (g_.forest.is_leaf(t) && must_refine(t, nodes, movable)) marked.push_back(t);
      if (marked.empty()) break;
      for (std::int32_t t : marked) {
        if (g_.forest.tet(t).level >= max_level)
          throw MeshingError("SAMR rules ask for a level beyond the finest one (3D)");
        refine(t);
      }
    }
  }

 private:
  const geometry::Oracle3& oracle_;
  samr::RefinedGrid3& g_;
  std::span<const int> levels_;
  std::vector<std::array<int, 4>> probes_;

  bool must_refine(std::int32_t t, const KeySet& nodes, const KeySet& movable) const {
    const int level = g_.forest.tet(t).level;
    const int max_level = g_.forest.lattice().max_level;
    if (g_.is_cut(t)) {
      std::vector<int> groups;
      for (std::int32_t k : g_.touched(t)) {
        if (level < (levels_.empty() ? oracle_.levels_of(k) : levels_[static_cast<std::size_t>(k)])) return true;
        const int group = oracle_.interface_group(k);
        if (std::find(groups.begin(), groups.end(), group) == groups.end()) groups.push_back(group);
      }
      if (level < max_level && groups.size() >= 2) return true;
    }
    if (level + 1 > max_level) return false;
    const auto v = g_.forest.fine_vertices(t);
    if (level + 2 <= max_level)
      for (const auto& w : probes_)
        if (nodes.contains(grid::key3(weighted(v, w, 4)))) return true;
    bool near_cut = g_.is_cut(t);
    for (int i = 0; i < 4 && !near_cut; ++i) near_cut = movable.contains(grid::key3(v[i]));
    if (near_cut)
      for (const auto& e : tet::kEdges) {
        std::array<int, 4> w{};
        w[e[0]] = 1, w[e[1]] = 1;
        if (nodes.contains(grid::key3(weighted(v, w, 2)))) return true;
      }
    return false;
  }

  void refine(std::int32_t t) {
    const std::int32_t first = g_.forest.refine(t);
    ++g_.refinements;
    const std::int32_t begin = g_.touch_begin[static_cast<std::size_t>(t)];
    const std::uint16_t count = g_.touch_count[static_cast<std::size_t>(t)];
    for (int c = 0; c < g_.forest.child_count(t); ++c) {
      const Box3 box = g_.box(first + c);
      g_.touch_begin.push_back(static_cast<std::int32_t>(g_.touch_pool.size()));
      std::uint16_t n = 0;
      for (std::uint16_t i = 0; i < count; ++i) {
        const std::int32_t k = g_.touch_pool[static_cast<std::size_t>(begin + i)];
        if (oracle_.boundary_touches(k, box)) {
          g_.touch_pool.push_back(k);
          ++n;
        }
      }
      g_.touch_count.push_back(n);
    }
  }
};

samr::RefinedGrid3 reference_refine3(const geometry::Oracle3& oracle, const grid::Lattice3& lattice,
                                     const grid::CellRange<3>& range, std::span<const int> levels) {
  samr::RefinedGrid3 g{{}, grid::TetForest(lattice, range), {}, 0, 0};
  std::vector<std::int32_t> found;
  const double h = lattice.h;
  for (std::int64_t ck = range.lo[2]; ck < range.hi[2]; ++ck)
    for (std::int64_t cj = range.lo[1]; cj < range.hi[1]; ++cj)
      for (std::int64_t ci = range.lo[0]; ci < range.hi[0]; ++ci) {
        g.cube_candidates.begin.push_back(static_cast<std::int32_t>(g.cube_candidates.list.size()));
        const std::array<std::int64_t, 3> c{ci, cj, ck};
        Box3 cube;
        for (int d = 0; d < 3; ++d) {
          cube.min[d] = lattice.origin[d] + static_cast<double>(c[d]) * h;
          cube.max[d] = lattice.origin[d] + static_cast<double>(c[d] + 1) * h;
        }
        oracle.candidates(cube, found);
        g.cube_candidates.list.insert(g.cube_candidates.list.end(), found.begin(), found.end());
      }
  g.cube_candidates.begin.push_back(static_cast<std::int32_t>(g.cube_candidates.list.size()));
  for (std::int32_t r = 0; r < g.forest.root_count(); ++r) {
    g.touch_begin.push_back(static_cast<std::int32_t>(g.touch_pool.size()));
    std::uint16_t n = 0;
    for (std::int32_t k : g.candidates_of_tet(r))
      if (oracle.boundary_touches(k, g.box(r))) {
        g.touch_pool.push_back(k);
        ++n;
      }
    g.touch_count.push_back(n);
  }
  ReferenceRefiner(oracle, g, levels).run();
  return g;
}

// ---------------------------------------------------------------------------------------
// Random scenes: spheres, rotated ellipsoids and cylinders in the unit cube, some crossing
// the box, same-phase ones may overlap (one interface group), different phases apart;
// levels 0-2 per inclusion.
// ---------------------------------------------------------------------------------------

geometry::Rotation3 random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  std::array<double, 4> q{};
  double len = 0;
  for (double& x : q) x = n(rng), len += x * x;
  len = std::sqrt(len);
  for (double& x : q) x /= len;
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  return {{{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
           {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
           {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}}};
}

geometry::SceneDesc random_scene(std::uint64_t seed) {
  using namespace geometry;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  SceneDesc s;
  s.source = "random-scene-" + std::to_string(seed);
  s.dimension = 3;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1, 1, 1};
  s.h = 0.25;
  s.levels = static_cast<int>(seed % 3);
  s.phases = {{1, "matrix", false}, {2, "particle", false}, {3, "fibre", false}};
  s.matrix_phase = 1;
  struct Placed {
    Vec3 c;
    double r;  // bounding radius
    int phase;
  };
  std::vector<Placed> placed;
  const int count = 1 + static_cast<int>(u(rng) * 4);
  for (int tries = 0; static_cast<int>(placed.size()) < count && tries < 200; ++tries) {
    // Centres from -0.05 to 1.05: some inclusions cross the box.
    const Vec3 c{-0.05 + 1.1 * u(rng), -0.05 + 1.1 * u(rng), -0.05 + 1.1 * u(rng)};
    const int phase = u(rng) < 0.6 ? 2 : 3;
    const double kind = u(rng);
    Shape shape;
    double bound = 0;
    if (kind < 0.4) {
      const double r = 0.06 + 0.2 * u(rng);
      shape = Sphere{c, r};
      bound = r;
    } else if (kind < 0.75) {
      const double a = 0.1 + 0.2 * u(rng);
      shape = Ellipsoid{c, {a, a / (1 + 3 * u(rng)), a / (1 + 3 * u(rng))}, random_rotation(rng)};
      bound = a;
    } else {
      const Vec3 d{u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5};
      const double len = 0.15 + 0.3 * u(rng), r = 0.04 + 0.08 * u(rng);
      shape = Cylinder{{c[0] - len * d[0], c[1] - len * d[1], c[2] - len * d[2]},
                       {c[0] + len * d[0], c[1] + len * d[1], c[2] + len * d[2]}, r};
      bound = len * std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) + r;
    }
    bool apart = true;
    for (const auto& p : placed) {
      const double dx = p.c[0] - c[0], dy = p.c[1] - c[1], dz = p.c[2] - c[2];
      if (p.phase != phase && std::sqrt(dx * dx + dy * dy + dz * dz) < p.r + bound + 1e-3) apart = false;
    }
    if (!apart) continue;
    placed.push_back({c, bound, phase});
    s.inclusions.push_back({shape, phase, static_cast<int>(u(rng) * 3)});
  }
  return s;
}

grid::Lattice3 make_lattice(const geometry::Oracle3& oracle, int extra_levels = 3) {
  const auto& scene = oracle.scene();
  grid::Lattice3 lattice;
  lattice.h = scene.h;
  int levels = scene.levels;
  for (int k = 0; k < oracle.inclusion_count(); ++k) levels = std::max(levels, oracle.levels_of(k));
  lattice.max_level = levels + extra_levels;
  for (int d = 0; d < 3; ++d) {
    lattice.origin[d] = scene.domain_min[static_cast<std::size_t>(d)];
    lattice.coarse_cells[d] = std::llround((scene.domain_max[static_cast<std::size_t>(d)] -
                                            scene.domain_min[static_cast<std::size_t>(d)]) /
                                           scene.h);
  }
  return lattice;
}

// ---------------------------------------------------------------------------------------
// The rules, by brute force
// ---------------------------------------------------------------------------------------

std::array<LatticePoint3, 6> edge_midpoints(const std::array<LatticePoint3, 4>& v) {
  std::array<LatticePoint3, 6> m{};
  for (int e = 0; e < 6; ++e)
    for (int d = 0; d < 3; ++d) m[e][d] = (v[tet::kEdges[e][0]][d] + v[tet::kEdges[e][1]][d]) / 2;
  return m;
}

// Every leaf whose closure holds the finest-lattice point p: the leaves holding a tet of
// the finest honeycomb with p as a vertex (every leaf is a union of such tets).
std::vector<std::int32_t> leaves_at(const grid::TetForest& f, const LatticePoint3& p) {
  std::vector<std::int32_t> out;
  const int max_level = f.lattice().max_level;
  for (int b = 0; b < 8; ++b) {
    grid::TetCode code;
    for (int d = 0; d < 3; ++d) code.cube[d] = p[d] - ((b >> d) & 1);
    for (int local = 0; local < 5; ++local) {
      code.local = static_cast<std::uint8_t>(local);
      const auto v = grid::tet_vertices(code);
      if (std::find(v.begin(), v.end(), p) == v.end()) continue;
      const std::int32_t t = f.find(max_level, code);
      if (t < 0) continue;
      EXPECT_TRUE(f.is_leaf(t));
      if (std::find(out.begin(), out.end(), t) == out.end()) out.push_back(t);
    }
  }
  return out;
}

// R1, R2, B and R4 (samr3.hpp) on every leaf. Cut lists are recomputed from the oracle
// over all inclusions; they must be within the refiner's (conservative) lists.
// Returns the number of cut leaves.
std::size_t expect_rules_hold(const geometry::Oracle3& oracle, const samr::RefinedGrid3& g,
                              std::span<const int> levels) {
  const auto& f = g.forest;
  const int max_level = f.lattice().max_level;
  std::vector<std::vector<std::int32_t>> cut(f.size());
  std::unordered_set<LatticeKey3> nodes, movable;
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(f.size()); ++t) {
    if (!f.is_leaf(t)) continue;
    const Box3 box = g.box(t);
    for (std::int32_t k = 0; k < oracle.inclusion_count(); ++k)
      if (oracle.boundary_touches(k, box)) cut[static_cast<std::size_t>(t)].push_back(k);
    const auto listed = g.touched(t);
    for (std::int32_t k : cut[static_cast<std::size_t>(t)])
      EXPECT_NE(std::find(listed.begin(), listed.end(), k), listed.end()) << "leaf " << t << " misses inclusion " << k;
    for (LatticeKey3 k : f.vertex_keys(t)) {
      nodes.insert(k);
      if (!cut[static_cast<std::size_t>(t)].empty()) movable.insert(k);
    }
  }
  std::size_t cut_leaves = 0;
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(f.size()); ++t) {
    if (!f.is_leaf(t)) continue;
    const int level = f.tet(t).level;
    const auto& list = cut[static_cast<std::size_t>(t)];
    cut_leaves += list.empty() ? 0 : 1;
    std::vector<int> groups;
    for (std::int32_t k : list) {
      EXPECT_GE(level, levels.empty() ? oracle.levels_of(k) : levels[static_cast<std::size_t>(k)]) << "R1, leaf " << t;
      if (std::find(groups.begin(), groups.end(), oracle.interface_group(k)) == groups.end())
        groups.push_back(oracle.interface_group(k));
    }
    if (groups.size() >= 2) {
      EXPECT_EQ(level, max_level) << "R2, leaf " << t;
    }
    const auto v = f.fine_vertices(t);
    bool near_cut = !list.empty();
    for (const auto& p : v) near_cut = near_cut || movable.count(grid::key3(p)) > 0;
    if (near_cut && level < max_level) {  // (a finest leaf's edge midpoints are no lattice points)
      for (const auto& m : edge_midpoints(v)) EXPECT_EQ(nodes.count(grid::key3(m)), 0u) << "R4, leaf " << t;
    }
  }
  // B: a node in the closure of a leaf is one of its vertices or edge midpoints.
  for (LatticeKey3 k : nodes) {
    const LatticePoint3 p = grid::key3_point(k);
    for (std::int32_t t : leaves_at(f, p)) {
      const auto v = f.fine_vertices(t);
      const auto m = edge_midpoints(v);
      const bool allowed = std::find(v.begin(), v.end(), p) != v.end() || std::find(m.begin(), m.end(), p) != m.end();
      EXPECT_TRUE(allowed) << "B, leaf " << t << " holds node " << p[0] << "," << p[1] << "," << p[2];
    }
  }
  return cut_leaves;
}

// Leaves as (level, cube, local), sorted.
std::vector<std::tuple<int, std::array<std::int32_t, 3>, int>> leaf_set(const grid::TetForest& f) {
  std::vector<std::tuple<int, std::array<std::int32_t, 3>, int>> s;
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(f.size()); ++t)
    if (f.is_leaf(t)) s.emplace_back(f.tet(t).level, f.tet(t).cube, f.tet(t).local);
  std::sort(s.begin(), s.end());
  return s;
}

void expect_same_as_reference(const geometry::Oracle3& oracle, const grid::Lattice3& lattice,
                              const grid::CellRange<3>& range, std::span<const int> levels) {
  const auto fast = samr::refine3(oracle, lattice, range, levels);
  const auto reference = reference_refine3(oracle, lattice, range, levels);
  EXPECT_EQ(leaf_set(fast.forest), leaf_set(reference.forest));
  EXPECT_EQ(fast.cube_candidates.begin, reference.cube_candidates.begin);
  EXPECT_EQ(fast.cube_candidates.list, reference.cube_candidates.list);
  EXPECT_EQ(fast.refinements, reference.refinements);
  EXPECT_EQ(fast.sweeps, reference.sweeps);
  // The forest arrays and cut lists are the same too (a sweep refines its marked leaves in
  // index order), so everything downstream numbers alike.
  ASSERT_EQ(fast.forest.size(), reference.forest.size());
  std::size_t differ = 0;
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(fast.forest.size()); ++t) {
    const auto &a = fast.forest.tet(t), &b = reference.forest.tet(t);
    const auto ta = fast.touched(t), tb = reference.touched(t);
    if (a.first_child != b.first_child || a.parent != b.parent || a.cube != b.cube || a.level != b.level ||
        a.local != b.local || !std::equal(ta.begin(), ta.end(), tb.begin(), tb.end()))
      ++differ;
  }
  EXPECT_EQ(differ, 0u);
}

constexpr int kScenes = 36;
// Lmax − the finest requested level. Two interface groups that come close are refined to
// Lmax (R2) and R4 carries that level along both interfaces, so Lmax sets the test's cost.
int extra_levels(std::uint64_t seed) { return 1 + static_cast<int>(seed % 3); }

TEST(Samr3, RulesHoldOnRandomScenes) {
  std::size_t refined_scenes = 0;
  for (std::uint64_t seed = 1; seed <= kScenes; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const geometry::Oracle3 oracle(random_scene(seed));
    const auto lattice = make_lattice(oracle, extra_levels(seed));
    const auto g = samr::refine3(oracle, lattice, lattice.whole_domain());
    EXPECT_GT(expect_rules_hold(oracle, g, {}), 0u);
    refined_scenes += g.refinements > 0 ? 1 : 0;
  }
  EXPECT_GT(refined_scenes, kScenes / 2u);
}

TEST(Samr3, SameForestAsSynchronousSweeps) {
  for (std::uint64_t seed = 1; seed <= kScenes; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const geometry::Oracle3 oracle(random_scene(seed));
    const auto lattice = make_lattice(oracle, extra_levels(seed));
    expect_same_as_reference(oracle, lattice, lattice.whole_domain(), {});
  }
}

// Partition boxes with a ghost layer, and levels passed in (as partitions get them from
// the whole scene), some above the inclusions' own.
TEST(Samr3, SameForestAsSynchronousSweepsOnPartitionRanges) {
  std::mt19937_64 rng(7);
  for (std::uint64_t seed = 1; seed <= kScenes; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const geometry::Oracle3 oracle(random_scene(seed));
    const auto lattice = make_lattice(oracle, extra_levels(seed));
    std::vector<int> levels;
    for (int k = 0; k < oracle.inclusion_count(); ++k)
      levels.push_back(std::min(lattice.max_level, oracle.levels_of(k) + static_cast<int>(rng() % 2)));
    for (int box = 0; box < 2; ++box) {
      grid::CellRange<3> range;
      const int ghost = 1 + static_cast<int>(rng() % 2);
      for (int d = 0; d < 3; ++d) {
        const std::int64_t n = lattice.coarse_cells[d];
        const std::int64_t lo = static_cast<std::int64_t>(rng() % static_cast<std::uint64_t>(n));
        const std::int64_t hi = lo + 1 + static_cast<std::int64_t>(rng() % static_cast<std::uint64_t>(n - lo));
        range.lo[d] = std::max<std::int64_t>(0, lo - ghost);
        range.hi[d] = std::min(n, hi + ghost);
      }
      SCOPED_TRACE("range " + std::to_string(range.lo[0]) + "," + std::to_string(range.lo[1]) + "," +
                   std::to_string(range.lo[2]) + " - " + std::to_string(range.hi[0]) + "," +
                   std::to_string(range.hi[1]) + "," + std::to_string(range.hi[2]));
      expect_same_as_reference(oracle, lattice, range, levels);
      expect_rules_hold(oracle, samr::refine3(oracle, lattice, range, levels), levels);
    }
  }
}

TEST(Samr3, RuleBeyondTheFinestLevelThrows) {
  geometry::SceneDesc s;
  s.dimension = 3;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1, 1, 1};
  s.h = 0.25;
  s.levels = 2;
  s.phases = {{1, "matrix", false}, {2, "particle", false}};
  s.inclusions.push_back({geometry::Sphere{{0.5, 0.5, 0.5}, 0.3}, 2, 2});
  const geometry::Oracle3 oracle(s);
  const auto lattice = make_lattice(oracle, -1);  // Lmax = 1 < R_k = 2
  EXPECT_THROW(samr::refine3(oracle, lattice, lattice.whole_domain()), MeshingError);
  EXPECT_THROW(reference_refine3(oracle, lattice, lattice.whole_domain(), {}), MeshingError);
  const std::vector<int> wrong_count{1, 1};
  EXPECT_THROW(samr::refine3(oracle, lattice, lattice.whole_domain(), wrong_count), std::invalid_argument);
}

}  // namespace
}  // namespace cisamr
