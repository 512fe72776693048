#include "subdivide/subdivide3.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <utility>

#include "core/check.hpp"
#include "grid/key_map.hpp"
#include "grid/cut_stencil3.hpp"
#include "mesh/metrics.hpp"
#include "subdivide/templates3.hpp"

namespace cisamr::subdivide {
namespace {

namespace tet = grid::tet;
constexpr double kHoneycombWorst = 1.3660254037844386;  // the trirectangular corner tet (regular: 1)
using grid::LatticeKey3;

class Subdivider3 {
 public:
  Subdivider3(const geometry::Oracle3& oracle, const samr::RefinedGrid3& g, const radapt::Nodes3& nodes,
              const faceswap::Swaps3* swaps)
      : oracle_(oracle), g_(g), forest_(g.forest), nodes_(nodes), swaps_(swaps), edge_point_(nodes.edges.size(), -1) {}

  Tets3 run(const grid::CellRange<3>& owned, Progress* progress) {
    const auto tets = static_cast<std::int64_t>(forest_.size());
    // More than the output can hold (a leaf gives one tet, a cut leaf at most a few): the
    // arrays then never grow by copying while the forest and the node tables are alive (the
    // mesher's peak), and capacity never written costs no memory.
    const std::size_t most = forest_.size() + 6 * nodes_.leaf_edges.size();
    out_.tets.reserve(4 * most);
    out_.phase.reserve(most);
    for (std::int32_t t = 0; t < static_cast<std::int32_t>(forest_.size()); ++t) {
      advance_sometimes(progress, t, tets);
      if (!forest_.is_leaf(t)) continue;
      if (!owned.contains(forest_.coarse_cell(t))) continue;
      leaf(t);
    }
    advance(progress, tets, tets);
    return std::move(out_);
  }

 private:
  const geometry::Oracle3& oracle_;
  const PhaseMask void_phases_ = geometry::void_phase_mask(oracle_.scene());
  const samr::RefinedGrid3& g_;
  const grid::TetForest& forest_;
  const radapt::Nodes3& nodes_;
  const faceswap::Swaps3* swaps_;
  Tets3 out_;
  std::vector<PhaseMask> extra_mask_;
  std::vector<std::int32_t> edge_point_;  // output node of each phase-changing edge, -1 until used
  std::vector<std::int32_t> swap_point_;  // output node of each new edge cut of a swap, -1 until used
  std::vector<std::int32_t> candidates_;
  grid::KeyMap images_{16};  // (output point, shift) → its periodic image, made once

  const grid::Lattice3& lattice() const { return forest_.lattice(); }
  // The output point of point `id` (a lattice node, or a cut node in its edge's frame) seen
  // as its image `shift` (lattice.hpp): the point itself, or a point made once at its
  // position plus the periods, whose identity is the image's unwrapped keys, so that
  // partitions merge it like any node. Closure Steiner points are interior: never shifted.
  std::int32_t output_id(std::int32_t id, std::uint8_t shift) {
    if (shift == 0) return id;
    const std::uint64_t image_key = (static_cast<std::uint64_t>(id) << 3) | shift;
    if (const std::int32_t known = images_.find(image_key); known >= 0) return known;
    const auto n = static_cast<std::int32_t>(nodes_.key.size());
    std::array<LatticeKey3, 2> identity{};
    if (id < n) {
      identity = {nodes_.key[static_cast<std::size_t>(id)], nodes_.key[static_cast<std::size_t>(id)]};
    } else {
      identity = out_.extra_identity[static_cast<std::size_t>(id - n)];
      CISAMR_CHECK(identity[0] != Tets3::kInteriorPoint, "subdivide3: an interior point seen across the period");
    }
    for (auto& k : identity) k = grid::key3(lattice().shifted_point(grid::key3_point(k), shift));
    const std::int32_t out = add_point(lattice().shifted(position(id), shift), mask_of(id), identity[0], identity[1]);
    bool inserted = false;
    images_.insert(image_key, out, inserted);
    return out;
  }

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
    if (single_bit(common)) return std::countr_zero(common);
    Vec3 c{0, 0, 0};
    for (std::int32_t id : v)
      for (int d = 0; d < 3; ++d) c[d] += 0.25 * position(id)[d];
    oracle_.candidates(box_of({position(v[0]), position(v[1]), position(v[2]), position(v[3])}), candidates_);
    const int phase = oracle_.phase_at(c, candidates_);
    if (common == 0 || (common & (PhaseMask{1} << phase))) return phase;
    return std::countr_zero(common);
  }

  enum class Origin { closure, kept, split, swapped };
  // `honeycomb`: a closure tet or an undeformed leaf, whose shape (and aspect ratio, `known`)
  // the tables give: no need to measure it.
  [[gnu::always_inline]] void emit(const std::array<std::int32_t, 4>& v, int phase, Origin origin, double known = -1) {
    // Cells of a void phase are not part of the mesh (assembly dropped them, and the guard
    // does not bound them): not emitted, not counted.
    if ((void_phases_ >> phase) & 1) return;
    out_.tets.insert(out_.tets.end(), v.begin(), v.end());
    out_.phase.push_back(static_cast<std::uint8_t>(phase));
    if (known >= 0) {
      if (origin == Origin::closure) out_.worst_closure = std::max(out_.worst_closure, known);
      if (origin == Origin::kept) out_.worst_kept = std::max(out_.worst_kept, known);
      return;
    }
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
      case Origin::swapped: out_.worst_swapped = std::max(out_.worst_swapped, aspect); break;
    }
  }

  void leaf(std::int32_t t) {
    if (swaps_ != nullptr && swaps_->block_of[static_cast<std::size_t>(t)] >= 0) {
      const auto& block = swaps_->blocks[static_cast<std::size_t>(swaps_->block_of[static_cast<std::size_t>(t)])];
      if (block.emitter == t)
        for (const auto& nt : block.tets) tetrahedron(nt.node, nt.lattice, nullptr, Origin::swapped);
      return;
    }
    const auto& ids = nodes_.tet_nodes[static_cast<std::size_t>(t)];
    const auto v = forest_.fine_vertices(t);
    const int level = forest_.tet(t).level;
    const std::array<std::int32_t, 4> vid{ids[0], ids[1], ids[2], ids[3]};
    // Hanging midpoints: edge midpoints that are nodes (vertices of finer leaves). Points 0-9
    // by their frame points (`frame`) and canonical keys (`keys`, for node look-ups and the
    // key rules, so both sides of a periodic plane decide alike): all ten set here, and only
    // for a leaf that may hang (most leaves go on to tetrahedron(), which needs neither).
    if (level < forest_.lattice().max_level && nodes_.may_hang(ids, level)) {
      unsigned hanging = 0;
      std::array<std::int32_t, 6> mid_id;
      std::array<LatticeKey3, 10> keys;
      std::array<grid::LatticePoint3, 10> frame;
      for (int i = 0; i < 4; ++i) {
        frame[static_cast<std::size_t>(i)] = v[i];
        keys[static_cast<std::size_t>(i)] = grid::key3(lattice().canonical_point(v[i]));
      }
      for (int e = 0; e < 6; ++e) {
        const auto& a = v[tet::kEdges[e][0]];
        const auto& b = v[tet::kEdges[e][1]];
        const grid::LatticePoint3 m{(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
        const LatticeKey3 k = grid::key3(lattice().canonical_point(m));
        frame[static_cast<std::size_t>(tet::midpoint(e))] = m;
        keys[static_cast<std::size_t>(tet::midpoint(e))] = k;
        mid_id[static_cast<std::size_t>(e)] = nodes_.id(k);
        if (mid_id[static_cast<std::size_t>(e)] >= 0) hanging |= 1u << e;
      }
      if (hanging) {
        close(t, vid, keys, frame, mid_id, hanging);
        return;
      }
    }
    tetrahedron(vid, v, nodes_.edges_of(t), Origin::kept);
  }

  // Emits a leaf, or a tet of a swapped cube, kept whole or split along the interface, as
  // the snapping guard evaluated it (grid::stencil3::outcome). `leaf_edges`: the leaf's
  // phase-changing edges (null: look them up by their keys, for swapped cubes' tets).
  void tetrahedron(const std::array<std::int32_t, 4>& vid, const std::array<grid::LatticePoint3, 4>& lattice,
                   const std::array<std::int32_t, 6>* leaf_edges, Origin whole) {
    // Positions in the tet's frame (`lattice`: its frame points), node ids canonical; the
    // output points are the images the frame sees.
    std::array<Vec3, 4> pos{};
    std::array<PhaseMask, 4> mask{};
    std::array<grid::stencil3::PointId, 4> id{};
    std::array<std::uint8_t, 4> shift{};
    for (int i = 0; i < 4; ++i) {
      const auto k = static_cast<std::size_t>(i);
      shift[k] = this->lattice().image_shift(lattice[k]);
      pos[k] = this->lattice().shifted(position(vid[k]), shift[k]);
      mask[k] = mask_of(vid[k]);
      const LatticeKey3 key = nodes_.key[static_cast<std::size_t>(vid[k])];
      id[k] = {key, key};
    }
    std::array<std::int32_t, 10> point{vid[0], vid[1], vid[2], vid[3], -1, -1, -1, -1, -1, -1};
    const auto o = grid::stencil3::outcome(lattice, pos, mask, id, [&](int e, Vec3& p, grid::stencil3::PointId& pid) {
      const auto ea = tet::kEdges[e][0], eb = tet::kEdges[e][1];
      const auto m = static_cast<std::size_t>(tet::midpoint(e));
      const std::uint8_t edge_shift = shift[ea] & shift[eb];
      const auto take = [&](const radapt::EdgeCut& cut, std::int32_t node) {
        p = this->lattice().shifted(cut.point, edge_shift), pid = {cut.lo, cut.hi}, point[m] = output_id(node, edge_shift);
        return true;
      };
      if (leaf_edges != nullptr) {
        const std::int32_t ei = (*leaf_edges)[static_cast<std::size_t>(e)];
        if (ei < 0) return false;
        return take(nodes_.edges[static_cast<std::size_t>(ei)], cut_node(ei));
      }
      const radapt::EdgeFrame frame = radapt::edge_frame(this->lattice(), lattice[ea], lattice[eb]);
      if (const std::int32_t ei = nodes_.edge(frame.lo(), frame.hi()); ei >= 0)
        return take(nodes_.edges[static_cast<std::size_t>(ei)], cut_node(ei));
      if (const std::int32_t si = swaps_ == nullptr ? -1 : swaps_->new_cut(frame.lo(), frame.hi()); si >= 0)
        return take(swaps_->new_cuts[static_cast<std::size_t>(si)], swap_cut_node(si));
      return false;
    });
    for (int i = 0; i < 4; ++i) point[static_cast<std::size_t>(i)] = output_id(vid[static_cast<std::size_t>(i)], shift[static_cast<std::size_t>(i)]);
    const std::array<std::int32_t, 4> out{point[0], point[1], point[2], point[3]};
    using Kind = grid::stencil3::Outcome::Kind;
    if (o.kind == Kind::kept) {
      // A leaf with no moved vertex is a honeycomb tet (aspect ratio 1, or 1.366 for a
      // corner tet), and the guard checked every deformed one.
      bool moved = whole != Origin::kept;
      for (std::int32_t n : vid) moved = moved || nodes_.moved(n);
      emit(out, tet_phase(out), whole, moved ? -1.0 : kHoneycombWorst);
      return;
    }
    ++out_.cut_tets;
    if (o.kind == Kind::unsplittable) {  // three or more phases meet: kept whole (counted)
      ++out_.unresolved;
      emit(out, tet_phase(out), Origin::split);
      return;
    }
    for (int k = 0; k < o.split.count; ++k) {
      const auto& l = o.split.tet[static_cast<std::size_t>(k)];
      emit({point[l[0]], point[l[1]], point[l[2]], point[l[3]]}, o.phase_of(k),
           whole == Origin::swapped ? Origin::swapped : Origin::split);
    }
  }

  void close(std::int32_t t, const std::array<std::int32_t, 4>& vid, const std::array<LatticeKey3, 10>& keys,
             const std::array<grid::LatticePoint3, 10>& frame, const std::array<std::int32_t, 6>& mid_id,
             unsigned hanging) {
    ++out_.closed_tets;
    for (std::int32_t id : vid)
      CISAMR_CHECK(nodes_.state[static_cast<std::size_t>(id)] == radapt::NodeState::stayed,
                   "subdivide3: a tet with hanging midpoints has a moved or collapsed vertex (rule R4 broken)");
    const PhaseMask common = mask_of(vid[0]) & mask_of(vid[1]) & mask_of(vid[2]) & mask_of(vid[3]);
    CISAMR_CHECK(single_bit(common), "subdivide3: a tet with hanging midpoints is cut (rule R4 broken)");
    const int phase = std::countr_zero(common);
    const auto& c = templates3::closure(forest_.kind(t), hanging, keys);
    // Output points: the images the leaf's frame sees (lattice nodes only; unused
    // midpoints stay -1).
    std::array<std::int32_t, 11> point{};
    for (int i = 0; i < 4; ++i)
      point[static_cast<std::size_t>(i)] =
          output_id(vid[static_cast<std::size_t>(i)], lattice().image_shift(frame[static_cast<std::size_t>(i)]));
    for (int e = 0; e < 6; ++e) {
      const std::int32_t m = mid_id[static_cast<std::size_t>(e)];
      point[static_cast<std::size_t>(tet::midpoint(e))] =
          m < 0 ? m : output_id(m, lattice().image_shift(frame[static_cast<std::size_t>(tet::midpoint(e))]));
    }
    if (c.uses_steiner) {
      const std::array<Vec3, 4> corners{position(point[0]), position(point[1]), position(point[2]), position(point[3])};
      point[templates3::kSteiner] = add_point(templates3::steiner_position(c, corners), common);
      ++out_.steiner_points;
    }
    for (int i = 0; i < c.count; ++i) {
      const auto& s = c.tet[static_cast<std::size_t>(i)];
      emit({point[s[0]], point[s[1]], point[s[2]], point[s[3]]}, phase, Origin::closure, c.max_aspect);
    }
  }

  // The output node of phase-changing edge `e` (radapt's cut point), created once.
  std::int32_t cut_node(std::int32_t e) {
    std::int32_t& id = edge_point_[static_cast<std::size_t>(e)];
    if (id >= 0) return id;
    const radapt::EdgeCut& cut = nodes_.edges[static_cast<std::size_t>(e)];
    id = add_point(cut.point, cut.mask, cut.lo, cut.hi);
    ++out_.cut_nodes;
    return id;
  }
  // The same for the cut points of the new edges of swapped cubes.
  std::int32_t swap_cut_node(std::int32_t e) {
    if (swap_point_.empty()) swap_point_.assign(swaps_->new_cuts.size(), -1);
    std::int32_t& id = swap_point_[static_cast<std::size_t>(e)];
    if (id >= 0) return id;
    const radapt::EdgeCut& cut = swaps_->new_cuts[static_cast<std::size_t>(e)];
    id = add_point(cut.point, cut.mask, cut.lo, cut.hi);
    ++out_.cut_nodes;
    return id;
  }
};

}  // namespace

Tets3 subdivide3(const geometry::Oracle3& oracle, const samr::RefinedGrid3& grid, const radapt::Nodes3& nodes,
                 const grid::CellRange<3>& owned, const faceswap::Swaps3* swaps,
                 Progress* progress) {
  return Subdivider3(oracle, grid, nodes, swaps).run(owned, progress);
}

}  // namespace cisamr::subdivide
