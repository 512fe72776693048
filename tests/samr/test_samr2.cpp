// The SAMR rules hold on the refined grid of random scenes (lib/samr/samr2.hpp).
#include <gtest/gtest.h>

#include <cstdlib>

#include "pipeline/pipeline.hpp"
#include "samr/samr2.hpp"
#include "support/random_scenes.hpp"

namespace cisamr {
namespace {

TEST(Samr2, RulesHoldOnRandomScenes) {
  for (unsigned seed = 1; seed <= 40; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const auto scene = testing::RandomScene2(seed).make();
    const geometry::Oracle2 oracle(scene);
    const auto lattice = pipeline::make_lattice<2>(oracle.scene(), {});
    const auto g = samr::refine2(oracle, lattice, lattice.whole_domain());
    const auto& f = g.forest;
    std::size_t cut = 0;
    for (std::int32_t c = 0; c < static_cast<std::int32_t>(f.size()); ++c) {
      if (!f.is_leaf(c)) continue;
      const auto cell = f.cell(c);
      const int level = cell.level;
      // R3: edge neighbours differ by at most one level.
      const int dirs[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
      for (const auto& d : dirs) {
        const std::int32_t n = f.find(level, cell.i + d[0], cell.j + d[1]);
        if (n < 0) continue;
        if (f.is_leaf(n)) {
          EXPECT_GE(f.cell(n).level, level - 1);
        } else {  // finer neighbour: its children touching this cell must be leaves
          const std::int32_t m = f.find(level + 1, 2 * (cell.i + d[0]) + (d[0] < 0 ? 1 : 0),
                                        2 * (cell.j + d[1]) + (d[1] < 0 ? 1 : 0));
          EXPECT_TRUE(f.is_leaf(m));
        }
      }
      if (!g.is_cut(c)) continue;
      ++cut;
      // R1: cut cells reach the requested level of every inclusion that cuts them.
      for (std::int32_t k : g.touched(c)) EXPECT_GE(level, oracle.levels_of(k));
      // R4: the 3×3 block has this level and the 5×5 block (less corners) nothing finer.
      for (int dj = -2; dj <= 2; ++dj)
        for (int di = -2; di <= 2; ++di) {
          if (std::abs(di) == 2 && std::abs(dj) == 2) continue;
          const std::int32_t n = f.find(level, cell.i + di, cell.j + dj);
          if (n < 0) continue;
          EXPECT_TRUE(f.is_leaf(n)) << "finer cell near a cut cell";
          if (std::abs(di) <= 1 && std::abs(dj) <= 1) {
            EXPECT_EQ(f.cell(n).level, level);
          }
        }
    }
    EXPECT_GT(cut, 0u);
  }
}

}  // namespace
}  // namespace cisamr
