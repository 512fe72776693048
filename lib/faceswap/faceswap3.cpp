#include "faceswap/faceswap3.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <unordered_map>

#include "grid/cut_stencil3.hpp"
#include "mesh/metrics.hpp"

namespace cisamr::faceswap {
namespace {

namespace tet = grid::tet;
namespace stencil3 = grid::stencil3;
using grid::LatticeKey3;
using grid::LatticePoint3;
constexpr double kInvalid = 1e300;

// One cube's half of a swap: the octahedron C_p ∪ R ∪ C_q around the face F it shares with
// the other cube. Points: 0 p, 1 q (the odd corners of F), 2 e1, 3 e2 (its even corners),
// 4 x_p, 5 x_q (the even corners off F next to p and q).
struct Half {
  std::array<std::int32_t, 3> leaves{};  // C_p, C_q, R
  std::array<std::int32_t, 6> node{};
  std::array<LatticePoint3, 6> point{};  // fine-lattice points
  double before = 0;                     // worst tet the three leaves emit
  double after = kInvalid;               // worst tet of the chosen re-tetrahedralisation
  std::array<Swaps3::NewTet, 4> tets{};
};

struct Candidate {
  Half a, b;
  double before = 0, after = 0;
  LatticeKey3 key = 0;  // tie-break: the apex p's key, then the axis
  int axis = 0;
};

class Swapper {
 public:
  Swapper(const geometry::Oracle3& oracle, const samr::RefinedGrid3& g, const radapt::Nodes3& nodes,
          const Options3& options)
      : oracle_(oracle), g_(g), forest_(g.forest), nodes_(nodes), options_(options) {}

  Swaps3 run() {
    out_.block_of.assign(forest_.size(), -1);
    const auto tets = static_cast<std::int64_t>(forest_.size());
    if (options_.trigger > 0) {
      find_candidates();
      out_.candidates = static_cast<std::int64_t>(candidates_.size());
      select();
    }
    advance(options_.progress, tets, tets);
    return std::move(out_);
  }

 private:
  const geometry::Oracle3& oracle_;
  const samr::RefinedGrid3& g_;
  const grid::TetForest& forest_;
  const radapt::Nodes3& nodes_;
  const Options3 options_;
  Swaps3 out_;
  std::vector<Candidate> candidates_;
  // Cut points of new edges computed while evaluating candidates (some are never used).
  std::vector<radapt::EdgeCut> trial_cuts_;
  radapt::EdgeIndex trial_index_;
  std::vector<geometry::Crossing> crossings_;
  std::vector<std::int32_t> plane_candidates_;

  const grid::Lattice3& lattice() const { return forest_.lattice(); }
  const Vec3& pos(std::int32_t n) const { return nodes_.position[static_cast<std::size_t>(n)]; }
  // Node n seen at frame point `frame` (lattice.hpp): + the period where the frame is at P.
  Vec3 frame_pos(std::int32_t n, const LatticePoint3& frame) const {
    return lattice().shifted(pos(n), lattice().image_shift(frame));
  }
  PhaseMask mask(std::int32_t n) const { return nodes_.mask[static_cast<std::size_t>(n)]; }
  LatticeKey3 key(std::int32_t n) const { return nodes_.key[static_cast<std::size_t>(n)]; }
  bool is_void(int phase) const { return oracle_.scene().phases[static_cast<std::size_t>(phase)].is_void; }

  // The cut point of the edge between two nodes (seen at frame points fa, fb) whose ends
  // stay strictly inside different phases: from radapt's table (an edge of the honeycomb)
  // or computed here (a new edge), on the segment from the smaller key, in the edge's frame
  // (radapt::EdgeFrame), and returned in the caller's. `leaf` gives the coarse cube for the
  // oracle's candidates (the segment lies in its closure; an edge on a periodic plane asks
  // for its own).
  bool cut_point(std::int32_t a, std::int32_t b, const LatticePoint3& fa, const LatticePoint3& fb, std::int32_t leaf,
                 Vec3& point, stencil3::PointId& id) {
    radapt::EdgeFrame frame = radapt::edge_frame(lattice(), fa, fb);
    if (const std::int32_t e = nodes_.edge(frame.lo(), frame.hi()); e >= 0) {
      const radapt::EdgeCut& c = nodes_.edges[static_cast<std::size_t>(e)];
      point = lattice().shifted(c.point, frame.shift), id = {c.lo, c.hi};
      return true;
    }
    if (grid::key3(frame.b) < grid::key3(frame.a)) std::swap(a, b), std::swap(frame.a, frame.b);
    const std::pair<LatticeKey3, LatticeKey3> k{grid::key3(frame.a), grid::key3(frame.b)};
    auto [it, inserted] = trial_index_.try_emplace(k, static_cast<std::int32_t>(trial_cuts_.size()));
    if (inserted) {
      radapt::EdgeCut c;
      c.lo = k.first, c.hi = k.second;
      const Vec3 pa = frame_pos(a, frame.a), pb = frame_pos(b, frame.b);
      if (frame.on_periodic_plane(lattice())) {
        oracle_.candidates(radapt::segment_box(pa, pb), plane_candidates_);
        oracle_.crossings(pa, pb, plane_candidates_, crossings_);
      } else {
        oracle_.crossings(pa, pb, g_.candidates_of_tet(leaf), crossings_);
      }
      const geometry::Crossing* chosen = radapt::crossing_between(crossings_, mask(a), mask(b));
      if (chosen != nullptr) {
        for (int d = 0; d < 3; ++d) c.point[d] = pa[d] + chosen->t * (pb[d] - pa[d]);
        c.mask = (PhaseMask{1} << chosen->from_phase) | (PhaseMask{1} << chosen->to_phase);
        c.found = true;
      }
      trial_cuts_.push_back(c);
    }
    const radapt::EdgeCut& c = trial_cuts_[static_cast<std::size_t>(it->second)];
    if (!c.found) return false;  // no crossing where the signs say there is one: do not swap here
    point = lattice().shifted(c.point, frame.shift), id = {c.lo, c.hi};
    return true;
  }

  // The worst aspect ratio of what a tet (kept or split) emits, ignoring void tets; kInvalid
  // when a tet would be inverted or could not be split. `leaf_edges`: the leaf's own
  // phase-changing edges when the tet is a leaf (null: look edges up by their keys).
  double worst(const std::array<std::int32_t, 4>& node, const std::array<LatticePoint3, 4>& lattice, std::int32_t leaf,
               const std::array<std::int32_t, 6>* leaf_edges = nullptr) {
    std::array<Vec3, 4> p{};
    std::array<PhaseMask, 4> m{};
    std::array<stencil3::PointId, 4> id{};
    for (int i = 0; i < 4; ++i) {
      const auto k = static_cast<std::size_t>(i);
      p[k] = frame_pos(node[k], lattice[k]), m[k] = mask(node[k]), id[k] = {key(node[k]), key(node[k])};
    }
    const auto o = stencil3::outcome(lattice, p, m, id, [&](int e, Vec3& point, stencil3::PointId& pid) {
      if (leaf_edges != nullptr) {
        const std::int32_t ei = (*leaf_edges)[static_cast<std::size_t>(e)];
        if (ei < 0) return false;
        const radapt::EdgeCut& c = nodes_.edges[static_cast<std::size_t>(ei)];
        const auto ea = tet::kEdges[e][0], eb = tet::kEdges[e][1];
        const auto shift = static_cast<std::uint8_t>(this->lattice().image_shift(lattice[ea]) & this->lattice().image_shift(lattice[eb]));
        point = this->lattice().shifted(c.point, shift), pid = {c.lo, c.hi};
        return true;
      }
      return cut_point(node[tet::kEdges[e][0]], node[tet::kEdges[e][1]], lattice[tet::kEdges[e][0]],
                       lattice[tet::kEdges[e][1]], leaf, point, pid);
    });
    using Kind = stencil3::Outcome::Kind;
    if (o.kind == Kind::unsplittable) return kInvalid;
    const auto measure = [](const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
      return mesh::signed_volume(a, b, c, d) > 0 ? mesh::aspect_ratio(a, b, c, d) : kInvalid;
    };
    if (o.kind == Kind::kept) {
      if (single_bit(o.common) && is_void(std::countr_zero(o.common))) return 0;
      return measure(o.p[0], o.p[1], o.p[2], o.p[3]);
    }
    double w = 0;
    for (int k = 0; k < o.split.count; ++k) {
      if (is_void(o.phase_of(k))) continue;
      const auto& s = o.split.tet[static_cast<std::size_t>(k)];
      w = std::max(w, measure(o.p[s[0]], o.p[s[1]], o.p[s[2]], o.p[s[3]]));
    }
    return w;
  }

  double leaf_worst(std::int32_t t) {
    const auto& ids = nodes_.tet_nodes[static_cast<std::size_t>(t)];
    static constexpr std::array<std::int32_t, 6> kNone{-1, -1, -1, -1, -1, -1};
    const auto* edges = nodes_.edges_of(t);
    return worst({ids[0], ids[1], ids[2], ids[3]}, forest_.fine_vertices(t), t, edges != nullptr ? edges : &kNone);
  }

  bool has_hanging_midpoint(std::int32_t t) const {
    const int level = forest_.tet(t).level;
    if (level >= forest_.lattice().max_level || !nodes_.may_hang(nodes_.tet_nodes[static_cast<std::size_t>(t)], level))
      return false;
    const auto v = forest_.fine_vertices(t);
    for (const auto& e : tet::kEdges) {
      LatticePoint3 m{};
      for (int d = 0; d < 3; ++d) m[d] = (v[e[0]][d] + v[e[1]][d]) / 2;
      if (nodes_.id(grid::key3(lattice().canonical_point(m))) >= 0) return true;
    }
    return false;
  }

  // The leaf that is exactly honeycomb tet `code` of `level`, or -1.
  std::int32_t leaf_at(int level, const grid::TetCode& code) const {
    const std::int32_t t = forest_.find(level, code);
    if (t < 0 || !forest_.is_leaf(t) || forest_.tet(t).level != level) return -1;
    return t;
  }

  static int local_of_odd_corner(int parity, int corner) {
    for (int local = 1; local <= 4; ++local)
      if (grid::kCubeTets[static_cast<std::size_t>(parity)][static_cast<std::size_t>(local)][0] == corner) return local;
    return -1;
  }

  // Fills one cube's half for the face on the side of local corner bp along `axis`.
  // False when the cube does not qualify or no re-tetrahedralisation is valid.
  bool make_half(std::array<std::int64_t, 3> cube, int level, int axis, int bp, Half& h) {
    cube = forest_.canonical(level, grid::TetCode{cube, 0}).cube;  // each half in its own cube's frame
    const int parity = grid::cube_parity(cube);
    const int other1 = (axis + 1) % 3, other2 = (axis + 2) % 3;
    const int bq = bp ^ (1 << other1) ^ (1 << other2);
    const std::array<int, 6> corner{bp, bq, bp ^ (1 << other1), bp ^ (1 << other2), bp ^ (1 << axis), bq ^ (1 << axis)};
    const int lp = local_of_odd_corner(parity, bp), lq = local_of_odd_corner(parity, bq);
    if (lp < 0 || lq < 0) return false;
    const std::array<int, 3> locals{lp, lq, 0};
    h.before = 0;
    for (int i = 0; i < 3; ++i) {
      const std::int32_t t =
          leaf_at(level, grid::TetCode{cube, static_cast<std::uint8_t>(locals[static_cast<std::size_t>(i)])});
      if (t < 0 || !nodes_.registered(t) || has_hanging_midpoint(t)) return false;
      h.leaves[static_cast<std::size_t>(i)] = t;
      h.before = std::max(h.before, leaf_worst(t));
    }
    if (h.before >= kInvalid) return false;
    const int shift = forest_.lattice().max_level - level;
    for (int i = 0; i < 6; ++i) {
      const int b = corner[static_cast<std::size_t>(i)];
      LatticePoint3 p{cube[0] + (b & 1), cube[1] + ((b >> 1) & 1), cube[2] + ((b >> 2) & 1)};
      for (int d = 0; d < 3; ++d) p[d] <<= shift;
      h.point[static_cast<std::size_t>(i)] = p;
      h.node[static_cast<std::size_t>(i)] = nodes_.id(grid::key3(lattice().canonical_point(p)));
      if (h.node[static_cast<std::size_t>(i)] < 0) return false;
    }
    // The octahedron around body diagonal p–x_q (ring q, e1, x_p, e2) or q–x_p (ring p, e1, x_q, e2).
    static constexpr std::array<std::array<int, 6>, 2> kAround{{{0, 5, 1, 2, 4, 3}, {1, 4, 0, 2, 5, 3}}};
    h.after = kInvalid;
    for (const auto& a : kAround) {
      std::array<Swaps3::NewTet, 4> tets{};
      double w = 0;
      for (int m = 0; m < 4 && w < kInvalid; ++m) {
        std::array<int, 4> local{a[0], a[1], a[static_cast<std::size_t>(2 + m)], a[static_cast<std::size_t>(2 + (m + 1) % 4)]};
        const auto& P = h.point;
        if (tet::orient(P[static_cast<std::size_t>(local[0])], P[static_cast<std::size_t>(local[1])],
                        P[static_cast<std::size_t>(local[2])], P[static_cast<std::size_t>(local[3])]) < 0)
          std::swap(local[2], local[3]);
        Swaps3::NewTet& nt = tets[static_cast<std::size_t>(m)];
        for (int k = 0; k < 4; ++k) {
          nt.node[static_cast<std::size_t>(k)] = h.node[static_cast<std::size_t>(local[static_cast<std::size_t>(k)])];
          nt.lattice[static_cast<std::size_t>(k)] = h.point[static_cast<std::size_t>(local[static_cast<std::size_t>(k)])];
        }
        w = std::max(w, worst(nt.node, nt.lattice, h.leaves[2]));
      }
      if (w < h.after) h.after = w, h.tets = tets;
    }
    return h.after < kInvalid;
  }

  void find_candidates() {
    const int max_level = forest_.lattice().max_level;
    // The pairs already examined, by the face they share: (level, the lower cube, axis), in
    // canonical codes, so the candidates are those of every pair whatever the forest order.
    std::unordered_map<LatticeKey3, std::uint64_t> seen;  // lower cube's min corner → bit 3·level + axis
    for (std::int32_t t = 0; t < static_cast<std::int32_t>(forest_.size()); ++t) {
      advance_sometimes(options_.progress, t, static_cast<std::int64_t>(forest_.size()));
      if (!forest_.is_leaf(t) || forest_.kind(t) != tet::Kind::corner || !options_.window.holds(forest_, t) ||
          !nodes_.registered(t))
        continue;
      // A leaf with every vertex unmoved and no phase change keeps its honeycomb shape.
      const auto& ids = nodes_.tet_nodes[static_cast<std::size_t>(t)];
      bool touched = nodes_.edges_of(t) != nullptr;
      for (std::int32_t n : ids) touched = touched || nodes_.state[static_cast<std::size_t>(n)] != radapt::NodeState::stayed;
      if (!touched || has_hanging_midpoint(t) || leaf_worst(t) <= options_.trigger) continue;
      const grid::TetCode code = forest_.code(t);
      const int level = forest_.tet(t).level;
      const int bp = grid::kCubeTets[static_cast<std::size_t>(grid::cube_parity(code.cube))][code.local][0];
      for (int axis = 0; axis < 3; ++axis) {
        // The pair across the face F through the apex perpendicular to `axis`, named by the
        // cube below F (canonical code) and built from that name alone: its own frame, and
        // the odd corner of F with the smaller key as p, so the candidate does not depend on
        // which of its corner tets asked first.
        std::array<std::int64_t, 3> lower = code.cube;
        if (((bp >> axis) & 1) == 0) lower[static_cast<std::size_t>(axis)] -= 1;
        lower = forest_.canonical(level, grid::TetCode{lower, 0}).cube;
        std::array<std::int64_t, 3> upper = lower;
        upper[static_cast<std::size_t>(axis)] += 1;
        LatticePoint3 corner_point = lower;
        for (auto& x : corner_point) x <<= (max_level - level);
        std::uint64_t& examined = seen[grid::key3(corner_point)];
        const std::uint64_t bit = std::uint64_t{1} << (3 * level + axis);
        if (examined & bit) continue;
        examined |= bit;
        int face_p = -1;
        LatticeKey3 apex_key = 0;
        for (int b = 0; b < 8; ++b) {
          if (((b >> axis) & 1) == 0 || ((grid::cube_parity(lower) + std::popcount(static_cast<unsigned>(b))) & 1) == 0) continue;
          LatticePoint3 q{lower[0] + (b & 1), lower[1] + ((b >> 1) & 1), lower[2] + ((b >> 2) & 1)};
          for (auto& x : q) x <<= (max_level - level);
          const LatticeKey3 k = grid::key3(lattice().canonical_point(q));
          if (face_p < 0 || k < apex_key) face_p = b, apex_key = k;
        }
        Candidate c;
        c.axis = axis;
        c.key = apex_key;
        if (!make_half(lower, level, axis, face_p, c.a)) continue;
        if (!make_half(upper, level, axis, face_p ^ (1 << axis), c.b)) continue;
        c.before = std::max(c.a.before, c.b.before);
        c.after = std::max(c.a.after, c.b.after);
        if (!(c.after < c.before)) continue;
        candidates_.push_back(c);
      }
    }
  }

  // True if candidate x goes before y.
  static bool before(const Candidate& x, const Candidate& y) {
    if (x.before != y.before) return x.before > y.before;
    if (x.after != y.after) return x.after < y.after;
    if (x.key != y.key) return x.key < y.key;
    return x.axis < y.axis;
  }

  // Keeps the trial cut of the edge between frame points fa and fb, if one was computed.
  void keep_cut(const LatticePoint3& fa, const LatticePoint3& fb) {
    const radapt::EdgeFrame frame = radapt::edge_frame(lattice(), fa, fb);
    const std::pair<LatticeKey3, LatticeKey3> k{frame.lo(), frame.hi()};
    const auto it = trial_index_.find(k);
    if (it == trial_index_.end()) return;
    if (out_.new_cut_index.try_emplace(k, static_cast<std::int32_t>(out_.new_cuts.size())).second)
      out_.new_cuts.push_back(trial_cuts_[static_cast<std::size_t>(it->second)]);
  }

  void select() {
    // Candidates per cube (a cube is named by its regular tet's leaf).
    std::unordered_map<std::int32_t, std::vector<std::int32_t>> by_cube;
    for (std::int32_t i = 0; i < static_cast<std::int32_t>(candidates_.size()); ++i) {
      by_cube[candidates_[static_cast<std::size_t>(i)].a.leaves[2]].push_back(i);
      by_cube[candidates_[static_cast<std::size_t>(i)].b.leaves[2]].push_back(i);
    }
    for (std::int32_t i = 0; i < static_cast<std::int32_t>(candidates_.size()); ++i) {
      const Candidate& c = candidates_[static_cast<std::size_t>(i)];
      bool wins = true;
      for (std::int32_t cube : {c.a.leaves[2], c.b.leaves[2]})
        for (std::int32_t j : by_cube[cube])
          if (j != i && before(candidates_[static_cast<std::size_t>(j)], c)) wins = false;
      if (!wins) continue;
      ++out_.swaps;
      for (const Half* h : {&c.a, &c.b}) {
        const auto block = static_cast<std::int32_t>(out_.blocks.size());
        out_.blocks.push_back({h->leaves[2], h->tets});
        for (std::int32_t t : h->leaves) out_.block_of[static_cast<std::size_t>(t)] = block;
        for (const auto& nt : h->tets)
          for (const auto& e : tet::kEdges) keep_cut(nt.lattice[e[0]], nt.lattice[e[1]]);
      }
    }
  }
};

}  // namespace

Swaps3 swap3(const geometry::Oracle3& oracle, const samr::RefinedGrid3& grid, const radapt::Nodes3& nodes,
             const Options3& options) {
  return Swapper(oracle, grid, nodes, options).run();
}

}  // namespace cisamr::faceswap
