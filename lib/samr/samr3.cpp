#include "samr/samr3.hpp"

#include <algorithm>
#include <stdexcept>

#include "core/check.hpp"
#include "core/error.hpp"

namespace cisamr::samr {
namespace {

using grid::LatticeKey3;
using grid::LatticePoint3;
namespace tet = grid::tet;

constexpr std::int64_t kCandidateBlock = 4;  // coarse cubes per side of one AABB-tree query

// The nodes of the forest finer than level 0 and, per node, the number of cut leaves having
// it as a vertex (rule R4: a node with a positive count may move). Nodes are the vertices of
// every tet created so far: refining keeps a tet's vertices as vertices of its children, so
// these are also the vertices of the leaves. The level-0 nodes (every background lattice
// point of the range) enter only when a cut leaf has them as a vertex: the rules ask
// whether a point is a node only for points finer than level 0. Open addressing with linear
// probing.
class NodeTable {
 public:
  explicit NodeTable(std::size_t expected) { rehash(capacity_for(expected)); }

  // Adds `cut_leaves` to the count of node `key`, inserting the node if it is absent;
  // returns the count before, -1 when it was absent.
  std::int32_t insert(LatticeKey3 key, std::int32_t cut_leaves = 0) {
    if ((size_ + 1) * 2 > entries_.size()) rehash(entries_.size() * 2);
    std::size_t i = slot(key);
    for (; entries_[i].key != kEmpty; i = (i + 1) & mask_)
      if (entries_[i].key == key) {
        const std::int32_t before = entries_[i].cut_leaves;
        entries_[i].cut_leaves += cut_leaves;
        return before;
      }
    entries_[i] = {key, cut_leaves};
    ++size_;
    return -1;
  }
  // Cut leaves having node `key` as a vertex; -1 when `key` is no node.
  std::int32_t cut_leaves(LatticeKey3 key) const {
    for (std::size_t i = slot(key);; i = (i + 1) & mask_) {
      if (entries_[i].key == key) return entries_[i].cut_leaves;
      if (entries_[i].key == kEmpty) return -1;
    }
  }
  bool contains(LatticeKey3 key) const { return cut_leaves(key) >= 0; }

 private:
  // No node has this key: coordinates take 63 bits.
  static constexpr LatticeKey3 kEmpty = ~LatticeKey3{0};
  struct Entry {
    LatticeKey3 key = kEmpty;
    std::int32_t cut_leaves = 0;
  };
  std::vector<Entry> entries_;
  std::size_t mask_ = 0, size_ = 0;

  static std::size_t capacity_for(std::size_t n) {
    std::size_t c = 16;
    while (c < 2 * n) c <<= 1;
    return c;
  }
  std::size_t slot(LatticeKey3 key) const {
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdULL;
    key ^= key >> 33;
    return static_cast<std::size_t>(key) & mask_;
  }
  void rehash(std::size_t capacity) {
    std::vector<Entry> old(capacity);
    old.swap(entries_);
    mask_ = capacity - 1;
    for (const Entry& e : old) {
      if (e.key == kEmpty) continue;
      std::size_t i = slot(e.key);
      while (entries_[i].key != kEmpty) i = (i + 1) & mask_;
      entries_[i] = e;
    }
  }
};

LatticePoint3 weighted(const std::array<LatticePoint3, 4>& v, const std::array<int, 4>& w, int denominator) {
  LatticePoint3 p{};
  for (int d = 0; d < 3; ++d) p[d] = (w[0] * v[0][d] + w[1] * v[1][d] + w[2] * v[2][d] + w[3] * v[3][d]) / denominator;
  return p;
}

// Edge midpoints of a tet, as weights /2 of its vertices.
constexpr std::array<std::array<int, 4>, 6> kMidpointWeights = [] {
  std::array<std::array<int, 4>, 6> w{};
  for (int e = 0; e < 6; ++e) w[e][tet::kEdges[e][0]] = 1, w[e][tet::kEdges[e][1]] = 1;
  return w;
}();

// Level-(l+2) lattice points on the closure of a level-l tet other than its vertices and
// edge midpoints, as weights /4 of its vertices: two quarter points per edge, three
// interior points per face. Any finer node in the closure implies one of these is a node.
constexpr std::array<std::array<int, 4>, 24> kQuarterProbes = [] {
  std::array<std::array<int, 4>, 24> p{};
  int n = 0;
  for (const auto& e : tet::kEdges) {
    p[n][e[0]] = 3, p[n][e[1]] = 1, ++n;
    p[n][e[0]] = 1, p[n][e[1]] = 3, ++n;
  }
  for (const auto& f : tet::kFaces)
    for (int i = 0; i < 3; ++i, ++n) {
      p[n][f[0]] = 1, p[n][f[1]] = 1, p[n][f[2]] = 1;
      p[n][f[i]] = 2;
    }
  return p;
}();

// The points of the refinement template of a tet with vertices v (vertices, edge
// midpoints, centre).
std::array<LatticePoint3, 11> template_points(const std::array<LatticePoint3, 4>& v) {
  std::array<LatticePoint3, 11> points{};
  for (int i = 0; i < 4; ++i) points[i] = v[i];
  for (int e = 0; e < 6; ++e)
    for (int d = 0; d < 3; ++d) points[tet::midpoint(e)][d] = (v[tet::kEdges[e][0]][d] + v[tet::kEdges[e][1]][d]) / 2;
  for (int d = 0; d < 3; ++d) points[tet::kCentroid][d] = (v[0][d] + v[1][d] + v[2][d] + v[3][d]) / 4;
  return points;
}

// Appends the cut lists of the children of t, just refined (the first at `first`; `points`:
// t's template_points): the parent's inclusions that touch the child's box. Several
// children share a box (a corner tet's 7 children have 4 boxes, a regular tet's 12 have 8),
// and boundary_touches depends only on the inclusion and the box. The sweeps and
// take_cube_refinements both make the lists this way.
void append_child_touches(const geometry::Oracle3& oracle, RefinedGrid3& g, std::int32_t t, std::int32_t first,
                          const std::array<LatticePoint3, 11>& points) {
  CISAMR_CHECK(g.touch_begin.size() == static_cast<std::size_t>(first), "SAMR: cut lists out of step with the forest");
  const bool corner = g.forest.kind(t) == tet::Kind::corner;
  const int children = g.forest.child_count(t);
  std::array<std::pair<LatticePoint3, LatticePoint3>, 12> bounds{};
  for (int c = 0; c < children; ++c) {
    const auto& child_points = corner ? tet::kCornerChildren[c] : tet::kRegularChildren[c];
    LatticePoint3 lo = points[child_points[0]], hi = lo;
    for (int i = 1; i < 4; ++i)
      for (int d = 0; d < 3; ++d)
        lo[d] = std::min(lo[d], points[child_points[i]][d]), hi[d] = std::max(hi[d], points[child_points[i]][d]);
    bounds[c] = {lo, hi};
    int same = 0;
    while (same < c && bounds[same] != bounds[c]) ++same;
    if (same < c) {  // a sibling with the same box: same list
      const std::int32_t from = g.touch_begin[static_cast<std::size_t>(first + same)];
      const std::uint16_t n = g.touch_count[static_cast<std::size_t>(first + same)];
      g.touch_begin.push_back(static_cast<std::int32_t>(g.touch_pool.size()));
      for (std::uint16_t i = 0; i < n; ++i) g.touch_pool.push_back(g.touch_pool[static_cast<std::size_t>(from + i)]);
      g.touch_count.push_back(n);
    } else {
      g.append_touching(oracle, t, Box3{g.forest.position(lo), g.forest.position(hi)});
    }
  }
}

// Synchronous sweeps (samr3.hpp) that look only at the leaves whose rules may have changed.
// Synchronous because R4 is not monotone: a node stops being a vertex of a cut leaf when
// that leaf is refined into children that are uncut at the node, so refining as soon as a
// rule fires reaches another fixed point (README.md, 3D).
// The look-ups suffice: a leaf's rules read only its cut list, the nodes on its closure and
// the cut-leaf counts of its vertices. Refining t adds nodes only at its edge midpoints and
// centre and raises counts only there (its vertices' counts can only drop: if t is cut they
// were positive, otherwise its children are uncut). So a leaf one sweep did not mark can
// be marked by the next only if it is a new child or its closure holds a midpoint that
// became a node or got its first cut leaf; the next sweep looks at those, marks what a
// sweep over all leaves would mark, and refining the marks in index order builds the same
// forest array.
class Refiner {
 public:
  Refiner(const geometry::Oracle3& oracle, RefinedGrid3& g, std::span<const int> levels)
      : oracle_(oracle), g_(g), levels_(levels), nodes_(g.touch_pool.size()) {}

  // Progress: `roots` units per level, the first for the roots' set-up (refine3), one more
  // for each level the sweeps have refined to (they refine finer and finer, up to max_level).
  void run(Progress* progress) {
    const int max_level = g_.forest.lattice().max_level;
    const std::int32_t roots = g_.forest.root_count();
    const std::int64_t total = std::int64_t{roots} * (max_level + 1);
    int reached = 0;
    queued_.assign(static_cast<std::size_t>(roots), 0);
    finest_.assign(static_cast<std::size_t>(roots / 5), 0);
    finest_near_.assign(static_cast<std::size_t>(roots / 5), 0);
    for (std::int32_t r = 0; r < roots; ++r) {
      if (!g_.is_cut(r)) continue;
      for (const LatticePoint3& p : g_.forest.fine_vertices(r)) nodes_.insert(key_of(p), 1);
      // First sweep: only the cut roots can fire (R1, R2); B and R4 need nodes finer than
      // level 0, and there are none yet.
      queue_.push_back(r);
    }
    // Within a sweep, its share of the next level's units: marking the first half, refining
    // the second; a later sweep that reaches no new level reports nothing below the last.
    std::int64_t reported = 0;
    const auto report = [&](std::int64_t at) {
      at = std::min(at, total);
      if (at > reported) progress->advance(reported = at, total);
    };
    const auto report_in_sweep = [&](std::size_t i, std::size_t n, std::size_t half) {
      if (progress != nullptr && (i & 4095) == 0)
        report(std::int64_t{roots} * (1 + reached) +
               std::int64_t{roots} * static_cast<std::int64_t>(half * n + i) / static_cast<std::int64_t>(2 * n));
    };
    std::vector<std::int32_t> marked;
    while (true) {
      ++g_.sweeps;
      marked.clear();
      for (std::size_t i = 0; i < queue_.size(); ++i) {
        report_in_sweep(i, queue_.size(), 0);
        const std::int32_t t = queue_[i];
        if (g_.forest.is_leaf(t) && must_refine(t)) marked.push_back(t);
      }
      if (marked.empty()) break;
      std::sort(marked.begin(), marked.end());
      ++sweep_;
      queue_.clear();
      for (std::size_t i = 0; i < marked.size(); ++i) {
        report_in_sweep(i, marked.size(), 1);
        const std::int32_t t = marked[i];
        const int level = g_.forest.tet(t).level;
        if (level >= max_level) throw MeshingError("SAMR rules ask for a level beyond the finest one (3D)");
        reached = std::max(reached, level + 1);
        refine(t);
      }
      if (progress != nullptr) report(std::int64_t{roots} * (1 + reached));
    }
    if (progress != nullptr) report(total);
  }

 private:
  const geometry::Oracle3& oracle_;
  RefinedGrid3& g_;
  std::span<const int> levels_;
  NodeTable nodes_;
  std::vector<int> groups_;
  // The leaves the next sweep looks at, each once: queued_[t] is the last sweep t was
  // queued for.
  std::vector<std::int32_t> queue_, around_;
  std::vector<std::int32_t> queued_;
  std::int32_t sweep_ = 0;

  // Per coarse cube of the range: the finest level of its tets (finest_) and of the tets of
  // the 3×3×3 cubes around it (finest_near_), which bounds the level of any node on the
  // closure of a tet in the cube.
  std::vector<std::uint8_t> finest_, finest_near_;

  // The node table's key of a frame point: its canonical point's (one node per point of
  // the torus on periodic axes).
  LatticeKey3 key_of(const LatticePoint3& p) const { return grid::key3(g_.forest.lattice().canonical_point(p)); }

  // Tets of `level` now exist in the coarse cube of tet t.
  void note_level(std::int32_t t, int level) {
    const auto [ci, cj, ck] = g_.forest.coarse_cell(t);
    const auto cube = static_cast<std::size_t>(g_.cube_index(ci, cj, ck));
    if (finest_[cube] >= level) return;
    finest_[cube] = static_cast<std::uint8_t>(level);
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const std::int64_t n = g_.cube_index(ci + di, cj + dj, ck + dk);
          if (n < 0) continue;
          std::uint8_t& f = finest_near_[static_cast<std::size_t>(n)];
          f = std::max(f, static_cast<std::uint8_t>(level));
        }
  }

  void enqueue(std::int32_t t) {
    std::int32_t& q = queued_[static_cast<std::size_t>(t)];
    if (q == sweep_) return;
    q = sweep_;
    queue_.push_back(t);
  }

  bool must_refine(std::int32_t t) {
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
    // Nodes finer than level l lie on t's closure only if tets finer than l exist near it.
    const int finest = finest_near_[static_cast<std::size_t>(g_.cube_of(t))];
    if (level + 1 > finest) return false;
    const auto v = g_.forest.fine_vertices(t);
    // B: no finer node in the closure than the edge midpoints.
    if (level + 2 <= finest)
      for (const auto& w : kQuarterProbes)
        if (nodes_.contains(key_of(weighted(v, w, 4)))) return true;
    // R4: a leaf around a node that may move carries no hanging midpoint.
    bool near_cut = g_.is_cut(t);
    for (int i = 0; i < 4 && !near_cut; ++i) near_cut = nodes_.cut_leaves(key_of(v[i])) > 0;
    if (near_cut)
      for (const auto& w : kMidpointWeights)
        if (nodes_.contains(key_of(weighted(v, w, 2)))) return true;
    return false;
  }

  void refine(std::int32_t t) {
    const auto v = g_.forest.fine_vertices(t);
    const int level = g_.forest.tet(t).level;
    const bool corner = g_.forest.kind(t) == tet::Kind::corner;
    const int children = g_.forest.child_count(t);
    const std::int32_t first = g_.forest.refine(t);
    ++g_.refinements;
    note_level(t, level + 1);
    queued_.resize(g_.forest.size(), 0);

    const std::array<LatticePoint3, 11> points = template_points(v);
    append_child_touches(oracle_, g_, t, first, points);
    std::array<int, 11> cut_delta{};  // change of each point's count of cut leaves
    if (g_.is_cut(t))
      for (int i = 0; i < 4; ++i) cut_delta[i] = -1;
    for (int c = 0; c < children; ++c) {
      if (g_.is_cut(first + c))
        for (std::uint8_t p : corner ? tet::kCornerChildren[c] : tet::kRegularChildren[c]) ++cut_delta[p];
      enqueue(first + c);
    }

    // New nodes (the midpoints and the centre) and the counts of cut leaves.
    for (int i = 0; i < 4; ++i)
      if (cut_delta[i] != 0) nodes_.insert(key_of(points[i]), cut_delta[i]);
    if (!corner) nodes_.insert(key_of(points[tet::kCentroid]), cut_delta[tet::kCentroid]);
    for (int e = 0; e < 6; ++e) {
      const int p = tet::midpoint(e);
      const std::int32_t before = nodes_.insert(key_of(points[p]), cut_delta[p]);
      // A midpoint that became a node, or a node that may move, changes the rules of the
      // leaves whose closure holds it. (The centre is only in the children's closures, and
      // t's vertices were nodes of a cut leaf already when a child is cut.)
      if (before >= 0 && !(before == 0 && cut_delta[p] > 0)) continue;
      around_.clear();
      g_.forest.leaves_at_midpoint(v[tet::kEdges[e][0]], v[tet::kEdges[e][1]], level, t, around_);
      for (std::int32_t u : around_) enqueue(u);
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
                     const grid::CellRange<3>& range, std::span<const int> levels, Progress* progress) {
  if (!levels.empty() && static_cast<int>(levels.size()) != oracle.inclusion_count())
    throw std::invalid_argument("refine3: one level per inclusion expected");
  RefinedGrid3 g{{}, grid::TetForest(lattice, range), {}, 0, 0};
  const std::int64_t cubes = g.forest.range().count(0) * g.forest.range().count(1) * g.forest.range().count(2);
  g.cube_candidates.begin.assign(static_cast<std::size_t>(cubes) + 1, 0);
  // Candidates per coarse cube: one AABB-tree query per block of cubes, then the same
  // closed-box test per cube (the tree's), so the lists are those of one query per cube.
  const auto cube_box = [&](std::int64_t ci, std::int64_t cj, std::int64_t ck) {
    const std::array<std::int64_t, 3> c{ci, cj, ck};
    Box3 b;
    for (int d = 0; d < 3; ++d) {
      b.min[d] = lattice.origin[d] + static_cast<double>(c[d]) * lattice.h;
      b.max[d] = lattice.origin[d] + static_cast<double>(c[d] + 1) * lattice.h;
    }
    return b;
  };
  // Blocks of up to kCandidateBlock cubes per side, one slab of cube layers at a time, then
  // the slab's cubes in order. A block never straddles a periodic face: its cubes are
  // contiguous in canonical indices, so its box is the canonical cubes' (where their
  // geometry, images included, lies).
  const grid::CellRange<3>& window = g.forest.range();
  std::array<std::vector<std::int64_t>, 3> block_of;  // per axis: window offset → block
  std::array<std::vector<std::int64_t>, 3> block_start;  // per axis: block → first window position
  for (int d = 0; d < 3; ++d) {
    for (std::int64_t b = window.lo[d], e = 0; b < window.hi[d]; b = e) {
      e = std::min(window.hi[d], b + kCandidateBlock);
      if (lattice.periodic[d]) e = std::min(e, b + lattice.coarse_cells[d] - lattice.canonical_cell(d, 0, b));
      block_start[d].push_back(b);
      block_of[d].insert(block_of[d].end(), static_cast<std::size_t>(e - b), static_cast<std::int64_t>(block_start[d].size() - 1));
    }
    block_start[d].push_back(window.hi[d]);
  }
  const auto canonical_cube_box = [&](std::int64_t ci, std::int64_t cj, std::int64_t ck) {
    return cube_box(lattice.canonical_cell(0, 0, ci), lattice.canonical_cell(1, 0, cj), lattice.canonical_cell(2, 0, ck));
  };
  const auto blocks_x = static_cast<std::int64_t>(block_start[0].size() - 1);
  const auto blocks_y = static_cast<std::int64_t>(block_start[1].size() - 1);
  std::vector<std::vector<std::int32_t>> block_candidates(static_cast<std::size_t>(blocks_x * blocks_y));
  for (std::size_t z = 0; z + 1 < block_start[2].size(); ++z) {
    const std::int64_t bk = block_start[2][z], ek = block_start[2][z + 1];
    for (std::int64_t y = 0; y < blocks_y; ++y)
      for (std::int64_t x = 0; x < blocks_x; ++x) {
        const std::int64_t bi = block_start[0][static_cast<std::size_t>(x)], ei = block_start[0][static_cast<std::size_t>(x) + 1];
        const std::int64_t bj = block_start[1][static_cast<std::size_t>(y)], ej = block_start[1][static_cast<std::size_t>(y) + 1];
        Box3 block = canonical_cube_box(bi, bj, bk);
        block.max = canonical_cube_box(ei - 1, ej - 1, ek - 1).max;
        oracle.candidates(block, block_candidates[static_cast<std::size_t>(y * blocks_x + x)]);
      }
    for (std::int64_t ck = bk; ck < ek; ++ck)
      for (std::int64_t cj = window.lo[1]; cj < window.hi[1]; ++cj)
        for (std::int64_t ci = window.lo[0]; ci < window.hi[0]; ++ci) {
          g.cube_candidates.begin[static_cast<std::size_t>(g.cube_index(ci, cj, ck))] =
              static_cast<std::int32_t>(g.cube_candidates.list.size());
          const auto& found = block_candidates[static_cast<std::size_t>(
              block_of[1][static_cast<std::size_t>(cj - window.lo[1])] * blocks_x +
              block_of[0][static_cast<std::size_t>(ci - window.lo[0])])];
          if (found.empty()) continue;
          const Box3 cube = canonical_cube_box(ci, cj, ck);
          for (std::int32_t k : found)
            if (boxes_overlap(cube, oracle.bounding_box(k))) g.cube_candidates.list.push_back(k);
        }
  }
  g.cube_candidates.begin[static_cast<std::size_t>(cubes)] = static_cast<std::int32_t>(g.cube_candidates.list.size());

  const std::int32_t roots = g.forest.root_count();
  g.touch_begin.resize(static_cast<std::size_t>(roots));
  g.touch_count.resize(static_cast<std::size_t>(roots));
  const std::int64_t total = std::int64_t{roots} * (lattice.max_level + 1);  // as Refiner::run's
  for (std::int32_t r = 0; r < roots; ++r) {
    advance_sometimes(progress, r, total);
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
  Refiner(oracle, g, levels).run(progress);
  return g;
}

std::int64_t take_cube_refinements(const geometry::Oracle3& oracle, RefinedGrid3& g,
                                   std::span<const CubeRefinement> taken) {
  const grid::CellRange<3>& range = g.forest.range();
  const std::int64_t cubes = range.count(0) * range.count(1) * range.count(2);
  std::vector<const std::vector<std::uint8_t>*> replaced(static_cast<std::size_t>(cubes), nullptr);
  std::vector<std::uint8_t> own;
  std::int64_t differing = 0;
  for (const CubeRefinement& c : taken) {
    const std::int64_t at = g.cube_index(c.cube[0], c.cube[1], c.cube[2]);
    CISAMR_CHECK(at >= 0, "SAMR: a cube refinement outside the forest's range");
    own.clear();
    for (int local = 0; local < 5; ++local) g.forest.append_refinement(static_cast<std::int32_t>(5 * at + local), own);
    if (own == c.bits) continue;
    replaced[static_cast<std::size_t>(at)] = &c.bits;
    ++differing;
  }
  if (differing == 0) return 0;

  // The replaced cubes' trees are cut down to their roots, every other tet keeping its
  // place in the order (the box's cells come out in the order the sweeps gave them, which
  // the parallel output's node numbering follows) and its cut list; then they grow again
  // from their bits in pre-order, each new tet's cut list filtered from its parent's as the
  // sweeps filter it.
  std::vector<std::int32_t> roots;
  for (std::int64_t cube = 0; cube < cubes; ++cube)
    if (replaced[static_cast<std::size_t>(cube)] != nullptr)
      for (int local = 0; local < 5; ++local) roots.push_back(static_cast<std::int32_t>(5 * cube + local));
  const std::vector<std::int32_t> index = g.forest.prune(roots);
  {
    std::int32_t at = 0;
    for (std::size_t t = 0; t < index.size(); ++t) {
      if (index[t] < 0) continue;
      CISAMR_DEBUG_CHECK(index[t] == at, "SAMR: pruning reordered the forest");
      g.touch_begin[static_cast<std::size_t>(at)] = g.touch_begin[t];
      g.touch_count[static_cast<std::size_t>(at)] = g.touch_count[t];
      ++at;
    }
    g.touch_begin.resize(static_cast<std::size_t>(at));
    g.touch_count.resize(static_cast<std::size_t>(at));
  }
  std::vector<std::int32_t> stack;
  for (std::size_t first_root = 0; first_root < roots.size(); first_root += 5) {
    const std::vector<std::uint8_t>& bits = *replaced[static_cast<std::size_t>(roots[first_root] / 5)];
    std::size_t next_bit = 0;
    for (std::size_t local = 0; local < 5; ++local) {
      stack.push_back(index[static_cast<std::size_t>(roots[first_root + local])]);
      while (!stack.empty()) {
        const std::int32_t now = stack.back();
        stack.pop_back();
        CISAMR_CHECK(next_bit < bits.size(), "SAMR: a cube refinement ends early");
        if (bits[next_bit++] == 0) continue;
        const std::int32_t first = g.forest.refine(now);
        append_child_touches(oracle, g, now, first, template_points(g.forest.fine_vertices(now)));
        for (int c = g.forest.child_count(now) - 1; c >= 0; --c) stack.push_back(first + c);
      }
    }
    CISAMR_CHECK(next_bit == bits.size(), "SAMR: a cube refinement runs past its trees");
  }
  return differing;
}

}  // namespace cisamr::samr
