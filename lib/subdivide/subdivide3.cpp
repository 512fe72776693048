#include "subdivide/subdivide3.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include "mesh/metrics.hpp"
#include "subdivide/templates3.hpp"

namespace cisamr::subdivide {
namespace {

namespace tet = grid::tet;
using grid::LatticeKey3;
using Local = std::array<std::uint8_t, 4>;

// Identity of a point, the same on every tet and partition that sees it: a lattice node
// is (key, key), a cut node (smaller key, larger key) of its edge. Quads are split along
// the diagonal through their smallest identity (key rule).
struct PointId {
  LatticeKey3 a = 0, b = 0;
  friend bool operator<(const PointId& x, const PointId& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; }
};

struct PairHash {
  std::size_t operator()(const std::pair<LatticeKey3, LatticeKey3>& p) const {
    std::uint64_t h = p.first * 0x9e3779b97f4a7c15ULL;
    h ^= p.second + 0x7f4a7c159e3779b9ULL + (h << 6) + (h >> 2);
    h ^= h >> 31;
    return static_cast<std::size_t>(h * 0xff51afd7ed558ccdULL);
  }
};

// Points of one leaf being split: 0-3 its vertices, 4-9 cut nodes on edges 0-5.
struct LeafPoints {
  std::array<std::int32_t, 10> id{};
  std::array<PointId, 10> key{};
  std::array<PhaseMask, 10> mask{};
  std::array<Vec3, 10> p{};
};

class Subdivider3 {
 public:
  Subdivider3(const geometry::Oracle3& oracle, const samr::RefinedGrid3& g, const radapt::Nodes3& nodes)
      : oracle_(oracle), g_(g), forest_(g.forest), nodes_(nodes) {}

  Tets3 run(const grid::CellRange<3>& owned) {
    for (std::int32_t t = 0; t < static_cast<std::int32_t>(forest_.size()); ++t) {
      if (!forest_.is_leaf(t)) continue;
      const auto& x = forest_.tet(t);
      if (!owned.contains({x.cube[0] >> x.level, x.cube[1] >> x.level, x.cube[2] >> x.level})) continue;
      leaf(t);
    }
    return std::move(out_);
  }

 private:
  const geometry::Oracle3& oracle_;
  const samr::RefinedGrid3& g_;
  const grid::TetForest& forest_;
  const radapt::Nodes3& nodes_;
  Tets3 out_;
  std::vector<PhaseMask> extra_mask_;
  std::unordered_map<std::pair<LatticeKey3, LatticeKey3>, std::int32_t, PairHash> cut_node_;
  std::vector<geometry::Crossing> crossings_;
  std::vector<std::int32_t> candidates_;

  const Vec3& position(std::int32_t id) const {
    const auto n = static_cast<std::int32_t>(nodes_.key.size());
    return id < n ? nodes_.position[static_cast<std::size_t>(id)] : out_.extra_points[static_cast<std::size_t>(id - n)];
  }
  PhaseMask mask_of(std::int32_t id) const {
    const auto n = static_cast<std::int32_t>(nodes_.key.size());
    return id < n ? nodes_.mask[static_cast<std::size_t>(id)] : extra_mask_[static_cast<std::size_t>(id - n)];
  }
  std::int32_t add_point(const Vec3& p, PhaseMask mask, LatticeKey3 key_lo = Tets3::kInteriorPoint,
                         LatticeKey3 key_hi = Tets3::kInteriorPoint) {
    out_.extra_points.push_back(p);
    out_.extra_identity.push_back({key_lo, key_hi});
    extra_mask_.push_back(mask);
    return static_cast<std::int32_t>(nodes_.key.size() + out_.extra_points.size() - 1);
  }

  static Box3 box_of(std::initializer_list<Vec3> points) {
    Box3 b{*points.begin(), *points.begin()};
    for (const Vec3& p : points)
      for (int d = 0; d < 3; ++d) b.min[d] = std::min(b.min[d], p[d]), b.max[d] = std::max(b.max[d], p[d]);
    return b;
  }

  // Phase of an output tet: the phase whose closure holds its four vertices; when several
  // do (all four on one interface) or none (unresolved leaves), the phase at the centroid.
  int tet_phase(const std::array<std::int32_t, 4>& v) {
    const PhaseMask common = mask_of(v[0]) & mask_of(v[1]) & mask_of(v[2]) & mask_of(v[3]);
    if (std::popcount(common) == 1) return std::countr_zero(common);
    Vec3 c{0, 0, 0};
    for (std::int32_t id : v)
      for (int d = 0; d < 3; ++d) c[d] += 0.25 * position(id)[d];
    oracle_.candidates(box_of({position(v[0]), position(v[1]), position(v[2]), position(v[3])}), candidates_);
    const int phase = oracle_.phase_at(c, candidates_);
    if (common == 0 || (common & (PhaseMask{1} << phase))) return phase;
    return std::countr_zero(common);
  }

  enum class Origin { closure, kept, split };
  void emit(const std::array<std::int32_t, 4>& v, int phase, Origin origin) {
    out_.tets.insert(out_.tets.end(), v.begin(), v.end());
    out_.phase.push_back(phase);
    const Vec3 &a = position(v[0]), &b = position(v[1]), &c = position(v[2]), &d = position(v[3]);
    if (!(mesh::signed_volume(a, b, c, d) > 0)) ++out_.inverted;
    const double aspect = mesh::aspect_ratio(a, b, c, d);
    switch (origin) {
      case Origin::closure: out_.worst_closure = std::max(out_.worst_closure, aspect); break;
      case Origin::kept:
        out_.worst_kept = std::max(out_.worst_kept, aspect);
        out_.kept_above_5 += aspect > 5 ? 1 : 0;
        break;
      case Origin::split:
        out_.worst_split = std::max(out_.worst_split, aspect);
        out_.split_above_5 += aspect > 5 ? 1 : 0;
        break;
    }
  }

  void leaf(std::int32_t t) {
    const auto& ids = nodes_.tet_nodes[static_cast<std::size_t>(t)];
    const auto v = forest_.fine_vertices(t);
    const int level = forest_.tet(t).level;
    // Hanging midpoints: edge midpoints that are nodes (vertices of finer leaves).
    unsigned hanging = 0;
    std::array<std::int32_t, 6> mid_id{};
    std::array<LatticeKey3, 10> keys{};
    for (int i = 0; i < 4; ++i) keys[static_cast<std::size_t>(i)] = grid::key3(v[i]);
    if (level < forest_.lattice().max_level)
      for (int e = 0; e < 6; ++e) {
        const LatticeKey3 k = grid::midpoint_key3(keys[tet::kEdges[e][0]], keys[tet::kEdges[e][1]]);
        keys[static_cast<std::size_t>(tet::midpoint(e))] = k;
        mid_id[static_cast<std::size_t>(e)] = nodes_.id(k);
        if (mid_id[static_cast<std::size_t>(e)] >= 0) hanging |= 1u << e;
      }
    const std::array<std::int32_t, 4> vid{ids[0], ids[1], ids[2], ids[3]};
    if (hanging) {
      close(t, vid, keys, mid_id, hanging);
      return;
    }
    const PhaseMask common = mask_of(vid[0]) & mask_of(vid[1]) & mask_of(vid[2]) & mask_of(vid[3]);
    if (common != 0) {
      emit(vid, tet_phase(vid), Origin::kept);
      return;
    }
    split(t, vid);
  }

  void close(std::int32_t t, const std::array<std::int32_t, 4>& vid, const std::array<LatticeKey3, 10>& keys,
             const std::array<std::int32_t, 6>& mid_id, unsigned hanging) {
    ++out_.closed_tets;
    for (std::int32_t id : vid)
      if (nodes_.snapped[static_cast<std::size_t>(id)])
        throw std::logic_error("subdivide3: a tet with hanging midpoints has a moved vertex (rule R4 broken)");
    const PhaseMask common = mask_of(vid[0]) & mask_of(vid[1]) & mask_of(vid[2]) & mask_of(vid[3]);
    if (std::popcount(common) != 1)
      throw std::logic_error("subdivide3: a tet with hanging midpoints is cut (rule R4 broken)");
    const int phase = std::countr_zero(common);
    const auto& c = templates3::closure(forest_.kind(t), hanging, keys);
    std::array<std::int32_t, 11> point{};
    for (int i = 0; i < 4; ++i) point[static_cast<std::size_t>(i)] = vid[static_cast<std::size_t>(i)];
    for (int e = 0; e < 6; ++e) point[static_cast<std::size_t>(tet::midpoint(e))] = mid_id[static_cast<std::size_t>(e)];
    if (c.uses_steiner) {
      const std::array<Vec3, 4> corners{position(vid[0]), position(vid[1]), position(vid[2]), position(vid[3])};
      point[templates3::kSteiner] = add_point(templates3::steiner_position(c, corners), common);
      ++out_.steiner_points;
    }
    for (int i = 0; i < c.count; ++i) {
      const auto& s = c.tet[static_cast<std::size_t>(i)];
      emit({point[s[0]], point[s[1]], point[s[2]], point[s[3]]}, phase, Origin::closure);
    }
  }

  // The node where the interface between phases p and q crosses the edge a-b (strictly
  // different phases at its ends). One per edge: keyed by the two lattice keys, computed
  // on the segment from the smaller key, so every tet and partition gets the same point.
  std::int32_t cut_node(std::int32_t a, std::int32_t b, PhaseMask pq) {
    if (nodes_.key[static_cast<std::size_t>(b)] < nodes_.key[static_cast<std::size_t>(a)]) std::swap(a, b);
    const std::pair<LatticeKey3, LatticeKey3> k{nodes_.key[static_cast<std::size_t>(a)],
                                                 nodes_.key[static_cast<std::size_t>(b)]};
    const auto it = cut_node_.find(k);
    if (it != cut_node_.end()) return it->second;
    const Vec3 pa = position(a), pb = position(b);
    oracle_.candidates(box_of({pa, pb}), candidates_);
    oracle_.crossings(pa, pb, candidates_, crossings_);
    Vec3 x{};
    PhaseMask mask = pq;
    const geometry::Crossing* chosen = nullptr;
    for (const auto& c : crossings_)
      if (((PhaseMask{1} << c.from_phase) | (PhaseMask{1} << c.to_phase)) == pq) {
        chosen = &c;
        break;
      }
    if (chosen == nullptr && !crossings_.empty()) chosen = &crossings_.front();
    if (chosen != nullptr) {
      for (int d = 0; d < 3; ++d) x[d] = pa[d] + chosen->t * (pb[d] - pa[d]);
      mask = (PhaseMask{1} << chosen->from_phase) | (PhaseMask{1} << chosen->to_phase);
    } else {
      for (int d = 0; d < 3; ++d) x[d] = 0.5 * (pa[d] + pb[d]);
      ++out_.missing_crossings;
    }
    const std::int32_t id = add_point(x, mask, k.first, k.second);
    ++out_.cut_nodes;
    cut_node_.emplace(k, id);
    return id;
  }

  // ---- Sub-tetrahedralisation of a cut leaf, in local point indices ----

  // Quad (cyclic q0..q3) split along the diagonal through its smallest point identity:
  // returns the diagonal's first corner index (0: diagonal 0-2, 1: diagonal 1-3).
  static int quad_diagonal(const LeafPoints& lp, const std::array<std::uint8_t, 4>& q) {
    int smallest = 0;
    for (int i = 1; i < 4; ++i)
      if (lp.key[q[i]] < lp.key[q[smallest]]) smallest = i;
    return smallest % 2;
  }
  static void pyramid(const LeafPoints& lp, std::uint8_t apex, const std::array<std::uint8_t, 4>& q,
                      std::vector<Local>& out) {
    if (quad_diagonal(lp, q) == 0)
      out.push_back({apex, q[0], q[1], q[2]}), out.push_back({apex, q[0], q[2], q[3]});
    else
      out.push_back({apex, q[1], q[2], q[3]}), out.push_back({apex, q[1], q[3], q[0]});
  }
  // Prism with triangles (p0,p1,p2), (q0,q1,q2) and lateral edges pi-qi; every lateral quad
  // split by the key rule. The smallest of the six points is on two of the quads'
  // diagonals, so the split is never cyclic: tet (hub, opposite triangle) + pyramid.
  static void prism(const LeafPoints& lp, std::array<std::uint8_t, 3> p, std::array<std::uint8_t, 3> q,
                    std::vector<Local>& out) {
    int hub = 0;
    for (int i = 1; i < 6; ++i) {
      const std::uint8_t a = i < 3 ? p[i] : q[i - 3], b = hub < 3 ? p[hub] : q[hub - 3];
      if (lp.key[a] < lp.key[b]) hub = i;
    }
    if (hub >= 3) std::swap(p, q), hub -= 3;
    std::rotate(p.begin(), p.begin() + hub, p.end());
    std::rotate(q.begin(), q.begin() + hub, q.end());
    out.push_back({p[0], q[0], q[1], q[2]});
    pyramid(lp, p[0], {p[1], p[2], q[2], q[1]}, out);
  }

  void split(std::int32_t t, const std::array<std::int32_t, 4>& vid) {
    ++out_.cut_tets;
    PhaseMask all = 0;
    for (std::int32_t id : vid) all |= mask_of(id);
    if (std::popcount(all) != 2) {  // more than one interface in one leaf: not handled
      ++out_.unresolved;
      emit(vid, tet_phase(vid), Origin::split);
      return;
    }
    const PhaseMask p = all & (~all + 1), q = all & ~p;
    LeafPoints lp;
    int sign[4];
    for (int i = 0; i < 4; ++i) {
      const std::int32_t id = vid[static_cast<std::size_t>(i)];
      const PhaseMask m = mask_of(id);
      sign[i] = (m & p) && (m & q) ? 0 : (m & p) ? 1 : -1;
      lp.id[static_cast<std::size_t>(i)] = id;
      const LatticeKey3 k = nodes_.key[static_cast<std::size_t>(id)];
      lp.key[static_cast<std::size_t>(i)] = {k, k};
    }
    for (int e = 0; e < 6; ++e) {
      const int i = tet::kEdges[e][0], j = tet::kEdges[e][1];
      if (sign[i] * sign[j] >= 0) continue;
      const std::int32_t c = cut_node(vid[static_cast<std::size_t>(i)], vid[static_cast<std::size_t>(j)], all);
      const LatticeKey3 ki = nodes_.key[static_cast<std::size_t>(vid[static_cast<std::size_t>(i)])];
      const LatticeKey3 kj = nodes_.key[static_cast<std::size_t>(vid[static_cast<std::size_t>(j)])];
      lp.id[static_cast<std::size_t>(tet::midpoint(e))] = c;
      lp.key[static_cast<std::size_t>(tet::midpoint(e))] = {std::min(ki, kj), std::max(ki, kj)};
    }
    const auto cut = [](int i, int j) { return static_cast<std::uint8_t>(tet::midpoint(tet::edge_of(i, j))); };
    std::vector<std::uint8_t> plus, minus, zero;
    for (int i = 0; i < 4; ++i) (sign[i] > 0 ? plus : sign[i] < 0 ? minus : zero).push_back(static_cast<std::uint8_t>(i));
    if (plus.size() > minus.size() || (plus.size() == minus.size() && plus[0] > minus[0])) std::swap(plus, minus);
    std::vector<Local> local;
    if (plus.size() == 1 && minus.size() == 1) {  // (0, 0, +, −): one cut edge
      const std::uint8_t a = plus[0], b = minus[0], c = cut(a, b);
      local.push_back({zero[0], zero[1], a, c});
      local.push_back({zero[0], zero[1], c, b});
    } else if (plus.size() == 1 && minus.size() == 2) {  // (0, +, −, −)
      const std::uint8_t a = plus[0], z = zero[0], b1 = minus[0], b2 = minus[1];
      const std::uint8_t c1 = cut(a, b1), c2 = cut(a, b2);
      local.push_back({a, c1, c2, z});
      pyramid(lp, z, {c1, b1, b2, c2}, local);
    } else if (plus.size() == 1 && minus.size() == 3) {  // (+, −, −, −)
      const std::uint8_t a = plus[0];
      const std::uint8_t c0 = cut(a, minus[0]), c1 = cut(a, minus[1]), c2 = cut(a, minus[2]);
      local.push_back({a, c0, c1, c2});
      prism(lp, {c0, c1, c2}, {minus[0], minus[1], minus[2]}, local);
    } else {  // (+, +, −, −): two prisms sharing the interface quad
      const std::uint8_t a = plus[0], b = plus[1], c = minus[0], d = minus[1];
      prism(lp, {a, cut(a, c), cut(a, d)}, {b, cut(b, c), cut(b, d)}, local);
      prism(lp, {c, cut(a, c), cut(b, c)}, {d, cut(a, d), cut(b, d)}, local);
    }
    // Orientation from the reference tet (midpoints stand for the cut nodes): the
    // combinatorial orientation, which the deformed tet keeps unless it inverts.
    const auto ref = tet::reference_points(forest_.kind(t));
    for (Local s : local) {
      const std::int64_t o = tet::orient(ref[s[0]], ref[s[1]], ref[s[2]], ref[s[3]]);
      if (o == 0) throw std::logic_error("subdivide3: degenerate stencil tet");
      if (o < 0) std::swap(s[2], s[3]);
      const std::array<std::int32_t, 4> v{lp.id[s[0]], lp.id[s[1]], lp.id[s[2]], lp.id[s[3]]};
      emit(v, tet_phase(v), Origin::split);
    }
  }
};

}  // namespace

Tets3 subdivide3(const geometry::Oracle3& oracle, const samr::RefinedGrid3& grid, const radapt::Nodes3& nodes,
                 const grid::CellRange<3>& owned) {
  return Subdivider3(oracle, grid, nodes).run(owned);
}

}  // namespace cisamr::subdivide
