#include "samr/samr3.hpp"

#include <algorithm>
#include <stdexcept>

#include "core/error.hpp"
#include "grid/key_map.hpp"

namespace cisamr::samr {
namespace {

using grid::LatticeKey3;
using grid::LatticePoint3;
namespace tet = grid::tet;

// A set of lattice keys on top of the open-addressing map.
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

// Level-(l+2) lattice points on the closure of a level-l tet other than its vertices and
// edge midpoints, as weights /4 of its vertices: two quarter points per edge, three
// interior points per face. Any finer node in the closure implies one of these is a node.
const std::vector<std::array<int, 4>>& quarter_probes() {
  static const std::vector<std::array<int, 4>> probes = [] {
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
  }();
  return probes;
}

class Refiner {
 public:
  Refiner(const geometry::Oracle3& oracle, RefinedGrid3& g, std::span<const int> levels)
      : oracle_(oracle), g_(g), levels_(levels) {}

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
  RefinedGrid3& g_;
  std::span<const int> levels_;
  std::vector<int> groups_;

  bool must_refine(std::int32_t t, const KeySet& nodes, const KeySet& movable) {
    const int level = g_.forest.tet(t).level;
    const int max_level = g_.forest.lattice().max_level;
    if (g_.is_cut(t)) {
      groups_.clear();
      for (std::int32_t k : g_.touched(t)) {
        if (level < (levels_.empty() ? oracle_.levels_of(k) : levels_[static_cast<std::size_t>(k)]))
          return true;  // R1
        const int group = oracle_.interface_group(k);
        if (std::find(groups_.begin(), groups_.end(), group) == groups_.end()) groups_.push_back(group);
      }
      if (level < max_level && groups_.size() >= 2) return true;  // R2
    }
    if (level + 1 > max_level) return false;  // nothing finer can exist
    const auto v = g_.forest.fine_vertices(t);
    // B: no finer node in the closure than the edge midpoints.
    if (level + 2 <= max_level)
      for (const auto& w : quarter_probes())
        if (nodes.contains(grid::key3(weighted(v, w, 4)))) return true;
    // R4: a leaf around a node that may move carries no hanging midpoint.
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

}  // namespace

Box3 RefinedGrid3::box(std::int32_t t) const {
  const auto v = forest.fine_vertices(t);
  LatticePoint3 lo = v[0], hi = v[0];
  for (const auto& p : v)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], p[d]), hi[d] = std::max(hi[d], p[d]);
  return {forest.position(lo), forest.position(hi)};
}

RefinedGrid3 refine3(const geometry::Oracle3& oracle, const grid::Lattice3& lattice,
                     const grid::CellRange<3>& range, std::span<const int> levels) {
  if (!levels.empty() && static_cast<int>(levels.size()) != oracle.inclusion_count())
    throw std::invalid_argument("refine3: one level per inclusion expected");
  RefinedGrid3 g{grid::TetForest(lattice, range), {}, {}, {}, {}, {}, 0, 0};
  const std::int64_t cubes = range.count(0) * range.count(1) * range.count(2);
  g.cube_candidate_begin.reserve(static_cast<std::size_t>(cubes) + 1);
  std::vector<std::int32_t> found;
  const double h = lattice.h;
  for (std::int64_t ck = range.lo[2]; ck < range.hi[2]; ++ck)
    for (std::int64_t cj = range.lo[1]; cj < range.hi[1]; ++cj)
      for (std::int64_t ci = range.lo[0]; ci < range.hi[0]; ++ci) {
        g.cube_candidate_begin.push_back(static_cast<std::int32_t>(g.cube_candidates.size()));
        const Box3 cube{{lattice.origin[0] + static_cast<double>(ci) * h, lattice.origin[1] + static_cast<double>(cj) * h,
                         lattice.origin[2] + static_cast<double>(ck) * h},
                        {lattice.origin[0] + static_cast<double>(ci + 1) * h,
                         lattice.origin[1] + static_cast<double>(cj + 1) * h,
                         lattice.origin[2] + static_cast<double>(ck + 1) * h}};
        oracle.candidates(cube, found);
        g.cube_candidates.insert(g.cube_candidates.end(), found.begin(), found.end());
      }
  g.cube_candidate_begin.push_back(static_cast<std::int32_t>(g.cube_candidates.size()));

  const std::int32_t roots = g.forest.root_count();
  g.touch_begin.resize(static_cast<std::size_t>(roots));
  g.touch_count.resize(static_cast<std::size_t>(roots));
  for (std::int32_t r = 0; r < roots; ++r) {
    g.touch_begin[static_cast<std::size_t>(r)] = static_cast<std::int32_t>(g.touch_pool.size());
    const Box3 box = g.box(r);
    std::uint16_t n = 0;
    for (std::int32_t k : g.candidates_of_tet(r))
      if (oracle.boundary_touches(k, box)) {
        g.touch_pool.push_back(k);
        ++n;
      }
    g.touch_count[static_cast<std::size_t>(r)] = n;
  }
  Refiner(oracle, g, levels).run();
  return g;
}

}  // namespace cisamr::samr
