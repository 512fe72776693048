// The cut stencils (grid/cut_stencil3.hpp), exactly: blocks of honeycomb cubes with random
// signs per node and cut points at integer fractions of their edges (the same point for
// every tet sharing the edge), each tet split on its own, must form a conforming mesh (faces
// matched exactly, opposite orientations, volume of the block), every sub-tet positive and
// on one side of the interface. This is what lets neighbouring leaves, and neighbouring
// partitions, split independently.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <map>
#include <random>

#include "exact_mesh3.hpp"
#include "grid/cut_stencil3.hpp"

namespace cisamr::grid {
namespace {

using stencil3::PointId;

constexpr std::int64_t kScale = 8;  // lattice unit in exact coordinates: cut fractions k/8

struct Block {
  int cubes = 2;
  std::map<LatticePoint3, int> sign;                                   // per lattice node
  std::map<std::pair<LatticeKey3, LatticeKey3>, int> fraction;        // per cut edge, in 1..kScale-1
};

LatticePoint3 scaled(const LatticePoint3& p) { return {p[0] * kScale, p[1] * kScale, p[2] * kScale}; }

// Splits every tet of the block and checks the union.
void check_block(const Block& b, std::mt19937_64& rng, int& splits_seen) {
  testing::ExactMesh3 mesh;
  std::size_t wrong_side = 0;
  for (std::int64_t i = 0; i < b.cubes; ++i)
    for (std::int64_t j = 0; j < b.cubes; ++j)
      for (std::int64_t k = 0; k < b.cubes; ++k)
        for (std::uint8_t local = 0; local < 5; ++local) {
          const auto v = tet_vertices(TetCode{{i, j, k}, local});
          std::array<int, 4> sign{};
          std::array<PointId, 10> id{};
          std::array<Vec3, 10> p{};
          std::array<LatticePoint3, 10> exact{};
          int plus = 0, minus = 0;
          for (int a = 0; a < 4; ++a) {
            sign[static_cast<std::size_t>(a)] = b.sign.at(v[static_cast<std::size_t>(a)]);
            plus += sign[static_cast<std::size_t>(a)] > 0, minus += sign[static_cast<std::size_t>(a)] < 0;
            const LatticeKey3 key = key3(v[static_cast<std::size_t>(a)]);
            id[static_cast<std::size_t>(a)] = {key, key};
            exact[static_cast<std::size_t>(a)] = scaled(v[static_cast<std::size_t>(a)]);
          }
          for (int e = 0; e < 6; ++e) {
            const int a = tet::kEdges[e][0], c = tet::kEdges[e][1];
            if (sign[static_cast<std::size_t>(a)] * sign[static_cast<std::size_t>(c)] >= 0) continue;
            LatticePoint3 lo = v[static_cast<std::size_t>(a)], hi = v[static_cast<std::size_t>(c)];
            if (key3(hi) < key3(lo)) std::swap(lo, hi);
            const int f = b.fraction.at({key3(lo), key3(hi)});
            LatticePoint3 x{};
            for (int d = 0; d < 3; ++d) x[d] = lo[d] * kScale + f * (hi[d] - lo[d]);
            const auto m = static_cast<std::size_t>(tet::midpoint(e));
            exact[m] = x;
            id[m] = {key3(lo), key3(hi)};
          }
          for (std::size_t q = 0; q < 10; ++q)
            for (int d = 0; d < 3; ++d) p[q][static_cast<std::size_t>(d)] = static_cast<double>(exact[q][static_cast<std::size_t>(d)]);
          if (plus == 0 || minus == 0) {  // not cut: kept whole
            mesh.add(exact[0], exact[1], exact[2], exact[3]);
            continue;
          }
          ++splits_seen;
          const auto s = stencil3::split(v, sign, id, p);
          ASSERT_GT(s.count, 0);
          for (int t = 0; t < s.count; ++t) {
            const auto& l = s.tet[static_cast<std::size_t>(t)];
            mesh.add(exact[l[0]], exact[l[1]], exact[l[2]], exact[l[3]]);
            for (std::uint8_t q : l)
              if (q < 4 && sign[q] != 0 && sign[q] != s.side[static_cast<std::size_t>(t)]) ++wrong_side;
          }
        }
  (void)rng;
  const std::int64_t side = b.cubes * kScale;
  const auto r = testing::check_conformity(mesh, {0, 0, 0}, {side, side, side});
  EXPECT_TRUE(r.ok(6 * side * side * side)) << r.first_problem << " (non-positive " << r.non_positive << ", unmatched "
                                            << r.interior_unmatched << ", same orientation " << r.same_orientation
                                            << ", volume6 " << r.volume6 << ")";
  EXPECT_EQ(wrong_side, 0u);
}

Block random_block(std::mt19937_64& rng, int zero_percent) {
  Block b;
  std::uniform_int_distribution<int> pct(0, 99), frac(1, kScale - 1), coin(0, 1);
  for (std::int64_t i = 0; i <= b.cubes; ++i)
    for (std::int64_t j = 0; j <= b.cubes; ++j)
      for (std::int64_t k = 0; k <= b.cubes; ++k)
        b.sign[{i, j, k}] = pct(rng) < zero_percent ? 0 : (coin(rng) ? 1 : -1);
  // A fraction for every possible edge of the block (axis edges and face diagonals).
  for (const auto& [a, sa] : b.sign)
    for (const auto& [c, sc] : b.sign) {
      if (!(key3(a) < key3(c))) continue;
      std::int64_t l1 = 0;
      for (int d = 0; d < 3; ++d) l1 += std::abs(a[d] - c[d]);
      if (l1 <= 2) b.fraction[{key3(a), key3(c)}] = frac(rng);
    }
  return b;
}

TEST(CutStencil3, RandomBlocksSplitConformingly) {
  std::mt19937_64 rng(20261123);
  int splits = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Block b = random_block(rng, trial % 4 == 0 ? 0 : 25);
    check_block(b, rng, splits);
    if (::testing::Test::HasFailure()) {
      ADD_FAILURE() << "trial " << trial;
      break;
    }
  }
  EXPECT_GT(splits, 10000);  // every sign pattern occurs many times
}

// The signs of sign pattern `pattern` (base 3, vertex 0 the lowest digit: -1, 0, +1) into
// `sign`; false when the tet is not cut (no vertex strictly on one of the two sides).
bool cut_signs(int pattern, std::array<int, 4>& sign) {
  int plus = 0, minus = 0;
  for (int a = 0, x = pattern; a < 4; ++a, x /= 3) {
    sign[static_cast<std::size_t>(a)] = x % 3 - 1;
    plus += sign[static_cast<std::size_t>(a)] > 0, minus += sign[static_cast<std::size_t>(a)] < 0;
  }
  return plus > 0 && minus > 0;
}

// Every sign pattern of a lone tet of either kind, with every combination of cut fractions
// in {1, 4, 7}/8: positive sub-tets that fill the tet, each on one side.
TEST(CutStencil3, EverySignPatternFillsTheTet) {
  for (std::uint8_t local : {std::uint8_t{0}, std::uint8_t{1}}) {
    const auto v = tet_vertices(TetCode{{0, 0, 0}, local});
    for (int pattern = 0; pattern < 81; ++pattern) {
      std::array<int, 4> sign{};
      if (!cut_signs(pattern, sign)) continue;
      for (int combo = 0; combo < 729; ++combo) {
        std::array<PointId, 10> id{};
        std::array<LatticePoint3, 10> exact{};
        std::array<Vec3, 10> p{};
        for (int a = 0; a < 4; ++a) {
          const LatticeKey3 key = key3(v[static_cast<std::size_t>(a)]);
          id[static_cast<std::size_t>(a)] = {key, key};
          exact[static_cast<std::size_t>(a)] = scaled(v[static_cast<std::size_t>(a)]);
        }
        int c = combo;
        for (int e = 0; e < 6; ++e, c /= 3) {
          const int a = tet::kEdges[e][0], b = tet::kEdges[e][1];
          const int f = 1 + 3 * (c % 3);
          const auto m = static_cast<std::size_t>(tet::midpoint(e));
          for (int d = 0; d < 3; ++d)
            exact[m][d] = exact[static_cast<std::size_t>(a)][d] + f * (v[static_cast<std::size_t>(b)][d] - v[static_cast<std::size_t>(a)][d]);
          id[m] = {std::min(key3(v[static_cast<std::size_t>(a)]), key3(v[static_cast<std::size_t>(b)])),
                   std::max(key3(v[static_cast<std::size_t>(a)]), key3(v[static_cast<std::size_t>(b)]))};
        }
        for (std::size_t q = 0; q < 10; ++q)
          for (int d = 0; d < 3; ++d) p[q][static_cast<std::size_t>(d)] = static_cast<double>(exact[q][static_cast<std::size_t>(d)]);
        const auto s = stencil3::split(v, sign, id, p);
        testing::ExactMesh3 mesh;
        for (int t = 0; t < s.count; ++t) {
          const auto& l = s.tet[static_cast<std::size_t>(t)];
          mesh.add(exact[l[0]], exact[l[1]], exact[l[2]], exact[l[3]]);
          for (std::uint8_t q : l) {
            if (q < 4) {
              ASSERT_FALSE(sign[q] != 0 && sign[q] != s.side[static_cast<std::size_t>(t)]) << "pattern " << pattern;
            }
          }
        }
        std::int64_t volume6 = 0;
        for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
          ASSERT_GT(mesh.orient(t), 0) << "kind " << int(local) << " pattern " << pattern << " combo " << combo;
          volume6 += mesh.orient(t);
        }
        ASSERT_EQ(volume6, tet::orient(exact[0], exact[1], exact[2], exact[3]));
      }
    }
  }
}

// split() orients its sub-tets from a table of the reference tet's orientations times the
// tet's own: for every tet of a cube, given in its order and with two vertices swapped
// (negatively oriented), every sign pattern's sub-tets are positive by the exact
// determinant of their lattice points (edge midpoints for the cut points).
TEST(CutStencil3, SubTetsArePositiveForEitherOrientationOfTheTet) {
  int checked = 0;
  for (std::uint8_t local = 0; local < 5; ++local)
    for (bool swapped : {false, true}) {
      auto v = tet_vertices(TetCode{{0, 0, 0}, local});
      if (swapped) std::swap(v[2], v[3]);
      std::array<LatticePoint3, 10> twice{};  // 2·v and the edge midpoints, exactly
      for (int a = 0; a < 4; ++a)
        for (int d = 0; d < 3; ++d) twice[static_cast<std::size_t>(a)][static_cast<std::size_t>(d)] = 2 * v[static_cast<std::size_t>(a)][static_cast<std::size_t>(d)];
      for (int e = 0; e < 6; ++e)
        for (int d = 0; d < 3; ++d)
          twice[static_cast<std::size_t>(tet::midpoint(e))][static_cast<std::size_t>(d)] =
              v[tet::kEdges[e][0]][static_cast<std::size_t>(d)] + v[tet::kEdges[e][1]][static_cast<std::size_t>(d)];
      std::array<PointId, 10> id{};
      std::array<Vec3, 10> p{};
      for (std::size_t q = 0; q < 10; ++q) {
        id[q] = {static_cast<LatticeKey3>(q), static_cast<LatticeKey3>(q)};
        for (int d = 0; d < 3; ++d) p[q][static_cast<std::size_t>(d)] = 0.5 * static_cast<double>(twice[q][static_cast<std::size_t>(d)]);
      }
      for (int pattern = 0; pattern < 81; ++pattern) {
        std::array<int, 4> sign{};
        if (!cut_signs(pattern, sign)) continue;
        const auto s = stencil3::split(v, sign, id, p);
        ASSERT_GT(s.count, 0);
        for (int t = 0; t < s.count; ++t) {
          const auto& l = s.tet[static_cast<std::size_t>(t)];
          ASSERT_GT(tet::orient(twice[l[0]], twice[l[1]], twice[l[2]], twice[l[3]]), 0)
              << "tet " << int(local) << (swapped ? " swapped" : "") << ", pattern " << pattern << ", sub-tet " << t;
          ++checked;
        }
      }
    }
  EXPECT_GT(checked, 1000);
}

// The outcome wrapper: kept when the masks share a phase, split with cut points asked for
// exactly the strictly cut edges, unsplittable with three phases.
TEST(CutStencil3, OutcomeClassifiesAndAsksForStrictCutsOnly) {
  const auto v = tet_vertices(TetCode{{0, 0, 0}, 0});
  std::array<Vec3, 4> pos{};
  std::array<PointId, 4> id{};
  for (int a = 0; a < 4; ++a) {
    for (int d = 0; d < 3; ++d) pos[static_cast<std::size_t>(a)][static_cast<std::size_t>(d)] = double(v[static_cast<std::size_t>(a)][static_cast<std::size_t>(d)]);
    id[static_cast<std::size_t>(a)] = {key3(v[static_cast<std::size_t>(a)]), key3(v[static_cast<std::size_t>(a)])};
  }
  int asked = 0;
  const auto cut = [&](int e, Vec3& point, PointId& pid) {
    ++asked;
    const auto a = static_cast<std::size_t>(tet::kEdges[e][0]), b = static_cast<std::size_t>(tet::kEdges[e][1]);
    for (int d = 0; d < 3; ++d) point[static_cast<std::size_t>(d)] = 0.5 * (pos[a][static_cast<std::size_t>(d)] + pos[b][static_cast<std::size_t>(d)]);
    pid = {id[a].a, id[b].a};
    return true;
  };
  using Kind = stencil3::Outcome::Kind;
  EXPECT_EQ(stencil3::outcome(v, pos, {1, 3, 1, 1}, id, cut).kind, Kind::kept);
  EXPECT_EQ(asked, 0);
  const auto split = stencil3::outcome(v, pos, {1, 2, 3, 2}, id, cut);  // +, -, 0, -
  EXPECT_EQ(split.kind, Kind::split);
  EXPECT_EQ(asked, 2);  // edges 0-1 and 0-3
  EXPECT_EQ(split.split.count, 3);
  EXPECT_EQ(stencil3::outcome(v, pos, {1, 2, 4, 1}, id, cut).kind, Kind::unsplittable);
  const auto missing = stencil3::outcome(v, pos, {1, 2, 2, 2}, id, [](int, Vec3&, PointId&) { return false; });
  EXPECT_EQ(missing.kind, Kind::unsplittable);
}

}  // namespace
}  // namespace cisamr::grid
