#include <gtest/gtest.h>

#include <random>
#include <unordered_map>

#include "grid/key_map.hpp"
#include "core/error.hpp"
#include "grid/quad_forest.hpp"

namespace cisamr::grid {
namespace {

Lattice2 small_lattice() {
  Lattice2 l;
  l.origin = {-1.0, 2.0};
  l.h = 0.5;
  l.max_level = 4;
  l.coarse_cells = {6, 4};
  return l;
}

TEST(QuadForest, RootsCoverTheRange) {
  const Lattice2 l = small_lattice();
  CellRange<2> r;
  r.lo = {1, 0};
  r.hi = {5, 3};
  QuadForest f(l, r);
  EXPECT_EQ(f.root_count(), 12);
  EXPECT_EQ(f.root(0, 0), -1);
  EXPECT_EQ(f.root(5, 0), -1);
  const std::int32_t c = f.root(2, 1);
  ASSERT_GE(c, 0);
  EXPECT_EQ(f.cell(c).i, 2);
  EXPECT_EQ(f.cell(c).j, 1);
  const Box2 b = f.box(c);
  EXPECT_DOUBLE_EQ(b.min[0], 0.0);
  EXPECT_DOUBLE_EQ(b.min[1], 2.5);
  EXPECT_DOUBLE_EQ(b.max[0], 0.5);
}

TEST(QuadForest, FindDescendsToTheDeepestCellAtOrAboveTheLevel) {
  QuadForest f(small_lattice(), small_lattice().whole_domain());
  const std::int32_t root = f.root(3, 2);
  const std::int32_t first = f.refine(root);
  // Child (1,0) of root (3,2) is (7,4) at level 1.
  EXPECT_EQ(f.find(1, 7, 4), first + 1);
  EXPECT_EQ(f.find(3, 7 * 4 + 2, 4 * 4 + 3), first + 1);  // a finer position inside that leaf
  EXPECT_EQ(f.find(0, 3, 2), root);                       // the non-leaf at the asked level
  EXPECT_FALSE(f.is_leaf(root));
  const std::int32_t grand = f.refine(first + 3);
  EXPECT_EQ(f.find(2, 15, 11), grand + 3);
  EXPECT_EQ(f.find(4, -1, 0), -1);
  // Children boxes tile the parent.
  const Box2 p = f.box(root), c0 = f.box(first), c3 = f.box(first + 3);
  EXPECT_EQ(c0.min, p.min);
  EXPECT_EQ(c3.max, p.max);
  EXPECT_EQ(c0.max, c3.min);
}

TEST(QuadForest, RejectsLatticesBeyond32Bits) {
  Lattice2 l = small_lattice();
  l.coarse_cells = {1 << 20, 4};
  l.max_level = 12;
  EXPECT_THROW(QuadForest(l, l.whole_domain()), MeshingError);
}

TEST(KeyMap, MatchesUnorderedMap) {
  std::mt19937_64 rng(3);
  KeyMap map(4);
  std::unordered_map<std::uint64_t, std::int32_t> ref;
  for (int i = 0; i < 100000; ++i) {
    const std::uint64_t key = key2(static_cast<std::int64_t>(rng() % 5000), static_cast<std::int64_t>(rng() % 5000));
    bool inserted = false;
    const std::int32_t v = map.insert(key, i, inserted);
    auto [it, fresh] = ref.emplace(key, i);
    EXPECT_EQ(inserted, fresh);
    EXPECT_EQ(v, it->second);
  }
  EXPECT_EQ(map.size(), ref.size());
  for (const auto& [k, v] : ref) EXPECT_EQ(map.find(k), v);
  EXPECT_EQ(map.find(key2(6000, 1)), KeyMap::kNone);
}

// The registry over the caller's keys: the same answers as a map, through several growths
// (started far too small), with keys that collide in the low bits.
TEST(KeyIndex, MatchesUnorderedMapOverTheCallersKeys) {
  std::mt19937_64 rng(5);
  LatticeKeyIndex index(4);
  std::vector<std::uint64_t> keys;
  std::unordered_map<std::uint64_t, std::int32_t> ref;
  for (int i = 0; i < 100000; ++i) {
    const std::uint64_t key = key2(static_cast<std::int64_t>(rng() % 4000), static_cast<std::int64_t>(rng() % 64) * 1024);
    bool inserted = false;
    const auto next = static_cast<std::int32_t>(keys.size());
    const std::int32_t v = index.insert(key, next, keys, inserted);
    if (inserted) keys.push_back(key);
    auto [it, fresh] = ref.emplace(key, next);
    EXPECT_EQ(inserted, fresh);
    EXPECT_EQ(v, it->second);
  }
  EXPECT_EQ(index.size(), ref.size());
  EXPECT_EQ(keys.size(), ref.size());
  for (const auto& [k, v] : ref) EXPECT_EQ(index.find(k, keys), v);
  EXPECT_EQ(index.find(key2(5000, 1), keys), LatticeKeyIndex::kNone);
}

TEST(Lattice, KeysRoundTrip) {
  const LatticeKey k = key2(123456, 7890123);
  EXPECT_EQ(key2_x(k), 123456);
  EXPECT_EQ(key2_y(k), 7890123);
  EXPECT_LT(key2(1, 1000000), key2(2, 0));  // x-major order
}

}  // namespace
}  // namespace cisamr::grid
