// Effective levels (pipeline/effective_levels.hpp): inclusions far outside the domain take
// part in no pair and cost nothing, however far they are.
#include <gtest/gtest.h>

#include <chrono>

#include "geometry/scene.hpp"
#include "pipeline/effective_levels.hpp"
#include "pipeline/pipeline.hpp"

using namespace cisamr;
using namespace cisamr::geometry;

namespace {

SceneDesc two_circles(const Vec2& far_center) {
  SceneDesc s;
  s.dimension = 2;
  s.domain_min = {0, 0, 0};
  s.domain_max = {10, 10, 0};
  s.h = 1;
  s.levels = 1;
  s.phases = {{1, "matrix", false}, {2, "a", false}, {3, "b", false}};
  s.inclusions.push_back({Circle{{5, 5}, 2}, 2, 1});
  s.inclusions.push_back({Circle{far_center, 1}, 3, 3});
  return s;
}

}  // namespace

TEST(EffectiveLevels, InclusionsFarOutsideTheDomainCostNothing) {
  for (double far : {3e4, 1e5, 1e20, 1e300}) {
    const SceneDesc s = two_circles({far, far});
    const auto lattice = pipeline::make_lattice<2>(s, pipeline::Options{});
    const auto start = std::chrono::steady_clock::now();
    const std::vector<int> levels = pipeline::effective_levels2(s, lattice);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(levels, (std::vector<int>{1, 3})) << far;
    EXPECT_LT(seconds, 0.5) << far;  // the bucket grid covers the domain, not both circles
  }
}

TEST(EffectiveLevels, AnInclusionOutsideTheDomainSpreadsNothing) {
  // Just outside (2.2 from the first circle, within the spread reach of 3.25): no cell of
  // the domain holds its boundary, so it raises no level.
  SceneDesc s = two_circles({11.2, 5});
  s.inclusions[0].shape = Circle{{5, 5}, 3};
  const std::vector<int> levels = pipeline::effective_levels2(s, pipeline::make_lattice<2>(s, pipeline::Options{}));
  EXPECT_EQ(levels, (std::vector<int>{1, 3}));
  // Inside, the same pair spreads the finer level.
  SceneDesc inside = two_circles({9.5, 5});
  inside.inclusions[0].shape = Circle{{5, 5}, 3};
  const std::vector<int> near = pipeline::effective_levels2(inside, pipeline::make_lattice<2>(inside, pipeline::Options{}));
  EXPECT_EQ(near[0], 3);
}
