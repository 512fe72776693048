// pipeline::Counters: the one table of counters (names, reductions) and accumulate.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "pipeline/counters.hpp"

namespace cisamr {
namespace {

template <int Dim>
std::set<std::string> names_of() {
  std::set<std::string> names;
  int visits = 0;
  pipeline::Counters<Dim>::for_each([&](const char* name, auto, pipeline::Reduction) {
    names.insert(name);
    ++visits;
  });
  EXPECT_EQ(names.size(), static_cast<std::size_t>(visits)) << "a report name used twice";
  return names;
}

TEST(Counters, EveryCounterHasOneReportName) {
  const auto two = names_of<2>(), three = names_of<3>();
  // Keys the reports have always had (tests/e2e, scripts, validation read some).
  for (const char* key : {"coarse_cells", "leaves", "refinements", "finest_level", "lattice_nodes", "snapped_nodes",
                          "cut_quads", "double_diagonal_splits", "hanging_node_cells", "unresolved_quads",
                          "collapsed_features", "max_collapse_deviation"})
    EXPECT_TRUE(two.count(key)) << key;
  for (const char* key : {"coarse_cubes", "leaves", "refinements", "finest_level", "lattice_nodes", "snapped_nodes",
                          "guarded_leaves", "guard_combinations", "nodes_refused_first_option", "collapsed_nodes",
                          "collapsed_cut_points", "max_collapse_deviation", "face_swaps", "cut_tets", "cut_nodes",
                          "closed_tets", "steiner_points", "unresolved", "inverted", "missing_crossings"})
    EXPECT_TRUE(three.count(key)) << key;
}

TEST(Counters, AccumulateCombinesEachCounterByItsReduction) {
  pipeline::Counters<2> total, a, b;
  a.leaves = 5, b.leaves = 7;                                  // sum
  a.max_collapse_deviation = 0.5, b.max_collapse_deviation = 0.25;  // max
  a.min_collapse_level = -1, b.min_collapse_level = 3;         // min of the set values
  pipeline::accumulate(total, a);
  EXPECT_EQ(total.min_collapse_level, -1);
  pipeline::accumulate(total, b);
  EXPECT_EQ(total.leaves, 12);
  EXPECT_EQ(total.max_collapse_deviation, 0.5);
  EXPECT_EQ(total.min_collapse_level, 3);
  pipeline::Counters<2> c;
  c.min_collapse_level = 1;
  pipeline::accumulate(total, c);
  EXPECT_EQ(total.min_collapse_level, 1);

  pipeline::Counters<3> t3, p3;
  p3.samr_sweeps = 4, p3.face_swaps = 2, p3.worst_kept = 4.5;
  pipeline::accumulate(t3, p3);
  pipeline::accumulate(t3, p3);
  EXPECT_EQ(t3.samr_sweeps, 4);
  EXPECT_EQ(t3.face_swaps, 4);
  EXPECT_EQ(t3.worst_kept, 4.5);
}

}  // namespace
}  // namespace cisamr
