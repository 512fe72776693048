#pragma once
// r-adaptivity in 3D with a quality guard (lib/radapt/README.md, 3D part).
//
// Every node of a cut leaf gets an ordered list of options, decided from original positions
// only: snap onto the nearest interface crossings along its leaf edges (axis edges within
// alpha, face diagonals within alpha_diagonal of their length, nearest first), stay where
// it is, and, last, *collapse*: stay but count as lying on the interface with the phases
// of its neighbours across a phase change (a bounded, reported deviation from the true
// interface). Every leaf then enumerates the combinations of its vertices' options, splits
// each as subdivide3 would (grid/cut_stencil3.hpp), and for each combination that would emit
// a tetrahedron above `bound` (or an inverted one, or a leaf it cannot split) refuses one
// option used in it. A node ends at its first option no leaf refused. Each leaf decides from
// its own data, so the result does not depend on any visiting order and is the same on every
// partition whose window (Options3::window) holds the leaf and a few cells around it; the
// combination that happens in a leaf is one the leaf
// checked, so no emitted tetrahedron exceeds `bound`. The last options of all vertices (all
// staying, collapsed where they touch a phase change) keep the leaf whole and undeformed, so
// every bad combination holds an option that can be refused.
#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/progress.hpp"
#include "core/types.hpp"
#include "geometry/oracle.hpp"
#include "grid/key_map.hpp"
#include "grid/tet_forest.hpp"
#include "grid/tet_lattice.hpp"
#include "samr/samr3.hpp"

namespace cisamr::radapt {

// Reach, in cells of the level of the leaves around a node (R4 gives them one level): a
// node takes its first option no leaf refused, so it depends on the leaves around it (1),
// their vertices' options and pass-1 refusals (2), and those leaves' vertices' first
// options (3). Final positions and masks of a node read leaves up to 3 cells away.
inline constexpr int kReachCells3 = 3;
// Its parts, for the windows of a partition (lib/parallel/README.md, "Windows"): the leaves
// whose second-pass refusals decide a node lie within 1 cell of it, those whose first-pass
// refusals they read within 2; options are built from leaves within kReachCells3.
inline constexpr int kSecondPassCells3 = 1;
inline constexpr int kFirstPassCells3 = 2;
static_assert(kSecondPassCells3 < kFirstPassCells3 && kFirstPassCells3 < kReachCells3);

struct Options3 {
  double alpha = 0.5;           // snap reach along axis edges, fraction of the edge length
  double alpha_diagonal = 0.2;  // along face diagonals (0: axis edges only, as in the paper)
  int max_candidates = 2;       // snap candidates kept per node (nearest first), at most 6
  double bound = 5.0;           // the guard's aspect-ratio bound; 0 disables the guard
  // The leaves worked on (a partition's: those within reach of its box); the others get no
  // nodes (Nodes3::registered is false) and refuse nothing. Default: every leaf.
  grid::LeafWindow window{};
  // The guard's passes run on the leaves of `window` that these hold too (a partition's: the
  // leaves whose refusals can reach the final positions read in its box; default: all).
  grid::LeafWindow first_pass_window{}, second_pass_window{};
  Progress* progress = nullptr;  // advanced over the forest's tets, once per pass (may be null)
};

// How a node ended.
enum class NodeState : std::uint8_t { stayed = 0, snapped = 1, collapsed = 2 };

// A phase-changing edge of a cut leaf (its ends' closure masks are disjoint) and the point
// where the interface between its ends' phases crosses it, computed on the original segment
// oriented from the smaller key (the same doubles on every partition). On a periodic
// lattice the keys and the point are those of the edge's frame (EdgeFrame).
struct EdgeCut {
  grid::LatticeKey3 lo = 0, hi = 0;
  Vec3 point{};
  PhaseMask mask = 0;  // the two phases of the crossing
  bool found = false;  // false: the oracle saw no crossing (point = midpoint)
};

// The first of `crossings` (ascending along a segment) that leaves a phase of `from` for a
// phase of `to`, or null: the interface between the ends of a phase-changing edge.
inline const geometry::Crossing* crossing_between(const std::vector<geometry::Crossing>& crossings, PhaseMask from,
                                                  PhaseMask to) {
  for (const auto& c : crossings)
    if ((from & (PhaseMask{1} << c.from_phase)) && (to & (PhaseMask{1} << c.to_phase))) return &c;
  return nullptr;
}

// A periodic lattice (docs/periodic-design.md §3.2): the canonical key of a frame key (one
// node per point of the torus), and the key pair and frame of an edge seen from a leaf. A
// leaf's frame points lie in [0, P] per axis; an edge lying in a periodic plane is seen at
// 0 from one side and at P from the other, so its own frame moves both ends back to 0 (its
// `shift`: the axes where both ends are at P). One edge then has one key pair and one frame
// (its cut point is computed once, there), and a leaf sees it at + the period on `shift`.
inline grid::LatticeKey3 canonical_key(const grid::Lattice3& lattice, grid::LatticeKey3 k) {
  if (!lattice.any_periodic()) return k;
  return grid::key3(lattice.canonical_point(grid::key3_point(k)));
}
struct EdgeFrame {
  grid::LatticePoint3 a{}, b{};  // the ends in the edge's frame
  std::uint8_t shift = 0;        // the leaf's frame is the edge's + the period on these axes
  grid::LatticeKey3 lo() const { return std::min(grid::key3(a), grid::key3(b)); }
  grid::LatticeKey3 hi() const { return std::max(grid::key3(a), grid::key3(b)); }
  // On a periodic plane (both ends at the canonical 0 of a periodic axis): seen from two frames.
  bool on_periodic_plane(const grid::Lattice3& lattice) const {
    for (int d = 0; d < 3; ++d)
      if (lattice.periodic[d] && a[d] == 0 && b[d] == 0) return true;
    return false;
  }
};
inline EdgeFrame edge_frame(const grid::Lattice3& lattice, const grid::LatticePoint3& a, const grid::LatticePoint3& b) {
  EdgeFrame f;
  f.shift = static_cast<std::uint8_t>(lattice.image_shift(a) & lattice.image_shift(b));
  f.a = lattice.unshifted(a, f.shift);
  f.b = lattice.unshifted(b, f.shift);
  return f;
}
// The closed box of a segment: the region whose inclusions a segment's crossings need.
inline Box3 segment_box(const Vec3& a, const Vec3& b) {
  Box3 box{a, a};
  for (int d = 0; d < 3; ++d) box.min[d] = std::min(a[d], b[d]), box.max[d] = std::max(a[d], b[d]);
  return box;
}

struct KeyPairHash {
  std::size_t operator()(const std::pair<grid::LatticeKey3, grid::LatticeKey3>& p) const {
    std::uint64_t h = p.first * 0x9e3779b97f4a7c15ULL;
    h ^= p.second + 0x7f4a7c159e3779b9ULL + (h << 6) + (h >> 2);
    h ^= h >> 31;
    return static_cast<std::size_t>(h * 0xff51afd7ed558ccdULL);
  }
};
using EdgeIndex = std::unordered_map<std::pair<grid::LatticeKey3, grid::LatticeKey3>, std::int32_t, KeyPairHash>;

// The nodes of the refined forest's leaves (in the window): lattice keys, final positions and closure masks (one
// bit inside a phase, two or more on an interface, or for a collapsed node).
struct Nodes3 {
  std::vector<grid::LatticeKey3> key;  // canonical keys (lattice.hpp)
  std::vector<Vec3> position;
  std::vector<PhaseMask> mask;
  std::vector<NodeState> state;
  // Per node, the finest level of the (registered) leaves around it. A leaf of level l can hold a node at
  // an edge's midpoint only if a finer leaf touches one of the edge's ends.
  std::vector<std::uint8_t> finest_level;
  // Node ids of each leaf's vertices (fine_vertices order), indexed by forest tet;
  // unspecified for non-leaves, -1 for leaves outside Options3::window.
  std::vector<std::array<std::int32_t, 4>> tet_nodes;
  grid::LatticeKeyIndex registry{1024};  // lattice key → node id, over `key`

  // Phase-changing edges of cut leaves, and per cut leaf its six edges' indices into
  // `edges` (-1: no phase change). `cut_leaf_slot[t]` indexes `leaf_edges` (-1: not cut).
  std::vector<EdgeCut> edges;
  // Indices into `edges` in ascending (lo, hi): edge() by binary search. (A hash map of the
  // pairs held 60 bytes per edge at the mesher's peak; the look-ups are few: new edges of
  // face swaps and closures, the cut leaves read their edges from leaf_edges.)
  std::vector<std::int32_t> edge_order;
  std::vector<std::int32_t> cut_leaf_slot;
  std::vector<std::array<std::int32_t, 6>> leaf_edges;

  std::int64_t snapped_count = 0;
  std::int64_t collapsed_count = 0;      // nodes that ended collapsed
  std::int64_t collapsed_cut_points = 0; // cut points standing for a gap thinner than their edge
  std::int64_t refused_count = 0;        // nodes that did not get their first option
  std::int64_t missing_crossings = 0;    // phase-changing edges without an oracle crossing
  std::int64_t window_leaves = 0;        // leaves inside Options3::window (all of them by default)
  std::int64_t guarded_leaves = 0;       // leaves whose option combinations were checked
  std::int64_t combinations = 0;         // combinations checked
  double max_collapse_deviation = 0;     // largest distance of a collapsed node (or cut point) from a phase it serves

  std::int32_t id(grid::LatticeKey3 k) const { return registry.find(k, key); }
  // The phase-changing edge between two lattice keys (either order; an edge's frame keys on
  // a periodic lattice), or -1.
  std::int32_t edge(grid::LatticeKey3 a, grid::LatticeKey3 b) const {
    const std::pair<grid::LatticeKey3, grid::LatticeKey3> k = a < b ? std::pair{a, b} : std::pair{b, a};
    const auto ends = [&](std::int32_t e) {
      const EdgeCut& c = edges[static_cast<std::size_t>(e)];
      return std::pair{c.lo, c.hi};
    };
    const auto it = std::lower_bound(edge_order.begin(), edge_order.end(), k,
                                     [&](std::int32_t e, const auto& key) { return ends(e) < key; });
    return it != edge_order.end() && ends(*it) == k ? *it : -1;
  }
  // Was leaf t inside Options3::window (its vertices have nodes)? Meaningless for non-leaves.
  bool registered(std::int32_t t) const { return tet_nodes[static_cast<std::size_t>(t)][0] >= 0; }
  bool moved(std::int32_t n) const { return state[static_cast<std::size_t>(n)] == NodeState::snapped; }
  // Could leaf `t` (level `level`, vertices `ids`) carry a node at one of its edge midpoints?
  bool may_hang(const std::array<std::int32_t, 4>& ids, int level) const {
    for (std::int32_t n : ids)
      if (finest_level[static_cast<std::size_t>(n)] > level) return true;
    return false;
  }
  const std::array<std::int32_t, 6>* edges_of(std::int32_t t) const {
    const std::int32_t slot = cut_leaf_slot[static_cast<std::size_t>(t)];
    return slot < 0 ? nullptr : &leaf_edges[static_cast<std::size_t>(slot)];
  }
};

// Registers the vertices of every leaf in the window (every leaf by default), classifies them
// and decides every node's fate.
Nodes3 snap3(const geometry::Oracle3& oracle, const samr::RefinedGrid3& grid, const Options3& options);

// snap3 in two halves, for a parallel mesher that exchanges the guard's first-pass refusals
// between them (lib/parallel/README.md, "Decisions exchanged near faces"): the constructor
// registers the nodes, builds their options and runs the guard's first pass; finish() runs
// the second pass and decides every node. snap3 is the two in a row.
class Snapper;
class Snapping3 {
 public:
  Snapping3(const geometry::Oracle3& oracle, const samr::RefinedGrid3& grid, const Options3& options);
  ~Snapping3();
  Snapping3(Snapping3&&) noexcept;
  Snapping3& operator=(Snapping3&&) noexcept;
  const Nodes3& nodes() const;  // keys, original positions and masks (decisions not yet made)
  int option_count(std::int32_t node) const;
  // Bit j: the first pass refused the node's j-th option (every bit 0 without the guard).
  std::uint32_t first_pass_refusals(std::int32_t node) const;
  void set_first_pass_refusals(std::int32_t node, std::uint32_t bits);
  Nodes3 finish();  // once

 private:
  std::unique_ptr<Snapper> snapper_;
};

}  // namespace cisamr::radapt
