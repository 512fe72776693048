#pragma once
// What the mesher counted, one type per dimension. Every counter is declared once, in the
// table of its struct's `for_each`, with its report name and how it combines over the
// partitions and ranks of a parallel run: the sum over partitions, the reduction across
// ranks (lib/parallel) and the report (lib/driver) all walk that table.
#include <algorithm>
#include <cstdint>

namespace cisamr::pipeline {

// How a counter of several partitions (ranks) combines into one.
enum class Reduction {
  sum,
  max,
  min,  // the smallest value that is set (≥ 0); −1 when none is
};

// Combines `part` into `into` (the reduction of a partition into a running total).
template <class T>
void combine(T& into, T part, Reduction reduction) {
  switch (reduction) {
    case Reduction::sum: into += part; break;
    case Reduction::max: into = std::max(into, part); break;
    case Reduction::min:
      if (part >= 0) into = into < 0 ? part : std::min(into, part);
      break;
  }
}

// Counters of one dimension only (specialised below).
template <int Dim>
struct DimensionCounters;

template <>
struct DimensionCounters<2> {
  std::int64_t cut_quads = 0, double_diagonal = 0, hanging_cells = 0;
  std::int64_t collapsed = 0;      // quads holding a feature below their resolution
  double max_collapse_ratio = 0;   // largest collapse deviation relative to the size of its cell
  int min_collapse_level = -1;     // coarsest level of a collapse (-1: none)

  template <class Visit>
  static void for_each(Visit&& visit) {
    using C = DimensionCounters;
    visit("cut_quads", &C::cut_quads, Reduction::sum);
    visit("double_diagonal_splits", &C::double_diagonal, Reduction::sum);
    visit("hanging_node_cells", &C::hanging_cells, Reduction::sum);
    visit("collapsed_features", &C::collapsed, Reduction::sum);
    visit("max_collapse_ratio", &C::max_collapse_ratio, Reduction::max);
    visit("coarsest_collapse_level", &C::min_collapse_level, Reduction::min);
  }
};

template <>
struct DimensionCounters<3> {
  int samr_sweeps = 0;
  std::int64_t cut_tets = 0, cut_nodes = 0, closed_tets = 0, steiner_points = 0;
  std::int64_t inverted = 0;           // output tets with non-positive volume
  std::int64_t missing_crossings = 0;  // phase-changing edges without an oracle crossing (midpoint used)
  // Worst aspect ratio by origin (before dropping voids): closures of hanging midpoints,
  // leaves kept whole (maybe deformed by snapping), sub-tets of cut leaves, tets of swapped
  // cubes; counts above 5.
  double worst_closure = 0, worst_kept = 0, worst_split = 0, worst_swapped = 0;
  std::int64_t kept_above_5 = 0, split_above_5 = 0;
  std::int64_t face_swaps = 0;  // pairs of cubes whose shared face was swapped
  // The snapping guard (radapt/radapt3.hpp): nodes that did not get their first option,
  // nodes collapsed onto an interface they do not lie on, cut points standing for a gap
  // thinner than their edge; leaves and option combinations checked.
  std::int64_t refused_nodes = 0, collapsed_nodes = 0, collapsed_cut_points = 0;
  std::int64_t guarded_leaves = 0, guard_combinations = 0;
  // Leaves r-adaptivity worked on: all of them in one box, a partition's within reach of its
  // box (pipeline::Ghost), fewer than `leaves`, which counts the whole ghost's forest.
  std::int64_t snapping_leaves = 0;

  template <class Visit>
  static void for_each(Visit&& visit) {
    using C = DimensionCounters;
    visit("samr_sweeps", &C::samr_sweeps, Reduction::max);
    visit("cut_tets", &C::cut_tets, Reduction::sum);
    visit("cut_nodes", &C::cut_nodes, Reduction::sum);
    visit("closed_tets", &C::closed_tets, Reduction::sum);
    visit("steiner_points", &C::steiner_points, Reduction::sum);
    visit("inverted", &C::inverted, Reduction::sum);
    visit("missing_crossings", &C::missing_crossings, Reduction::sum);
    visit("worst_closure", &C::worst_closure, Reduction::max);
    visit("worst_kept", &C::worst_kept, Reduction::max);
    visit("worst_split", &C::worst_split, Reduction::max);
    visit("worst_swapped", &C::worst_swapped, Reduction::max);
    visit("kept_above_5", &C::kept_above_5, Reduction::sum);
    visit("split_above_5", &C::split_above_5, Reduction::sum);
    visit("face_swaps", &C::face_swaps, Reduction::sum);
    visit("nodes_refused_first_option", &C::refused_nodes, Reduction::sum);
    visit("collapsed_nodes", &C::collapsed_nodes, Reduction::sum);
    visit("collapsed_cut_points", &C::collapsed_cut_points, Reduction::sum);
    visit("guarded_leaves", &C::guarded_leaves, Reduction::sum);
    visit("guard_combinations", &C::guard_combinations, Reduction::sum);
    visit("snapping_leaves", &C::snapping_leaves, Reduction::sum);
  }
};

template <int Dim>
struct Counters : DimensionCounters<Dim> {
  std::int64_t coarse_cells = 0;  // coarse cells (cubes) meshed, ghost included
  std::int64_t leaves = 0, refinements = 0;
  std::int64_t lattice_nodes = 0, snapped_nodes = 0;
  std::int64_t unresolved = 0;        // cut quads (leaves) no template splits phase-consistently
  double max_collapse_deviation = 0;  // largest distance of a collapsed node from a phase it serves
  int max_level = 0;                  // Lmax of the lattice

  // Calls visit(report name, member pointer, reduction) for every counter, the shared ones
  // first. The member pointers apply to any Counters<Dim>.
  template <class Visit>
  static void for_each(Visit&& visit) {
    visit(Dim == 2 ? "coarse_cells" : "coarse_cubes", &Counters::coarse_cells, Reduction::sum);
    visit("leaves", &Counters::leaves, Reduction::sum);
    visit("refinements", &Counters::refinements, Reduction::sum);
    visit("finest_level", &Counters::max_level, Reduction::max);
    visit("lattice_nodes", &Counters::lattice_nodes, Reduction::sum);
    visit("snapped_nodes", &Counters::snapped_nodes, Reduction::sum);
    visit(Dim == 2 ? "unresolved_quads" : "unresolved", &Counters::unresolved, Reduction::sum);
    visit("max_collapse_deviation", &Counters::max_collapse_deviation, Reduction::max);
    DimensionCounters<Dim>::for_each(visit);
  }
};

// Adds one partition's counters to a running total, counter by counter.
template <int Dim>
void accumulate(Counters<Dim>& into, const Counters<Dim>& part) {
  Counters<Dim>::for_each(
      [&](const char*, auto member, Reduction reduction) { combine(into.*member, part.*member, reduction); });
}

}  // namespace cisamr::pipeline
