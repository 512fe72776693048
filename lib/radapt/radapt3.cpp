#include "radapt/radapt3.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/check.hpp"
#include "core/memory.hpp"
#include "grid/cut_stencil3.hpp"
#include "mesh/metrics.hpp"

namespace cisamr::radapt {
namespace {

namespace tet = grid::tet;
using grid::LatticeKey3;
using grid::LatticePoint3;

int single_phase(PhaseMask m) { return single_bit(m) ? std::countr_zero(m) : -1; }

// An edge's two keys mixed into 64 bits whose low bits (the open-addressing slot) depend on
// every bit of both.
struct EdgeKeyHash {
  std::uint64_t operator()(const std::pair<LatticeKey3, LatticeKey3>& k) const {
    return grid::LatticeKeyHash{}(grid::LatticeKeyHash{}(k.first) ^ (k.second * 0x9e3779b97f4a7c15ULL));
  }
};

enum class OptionKind : std::uint8_t { snap, stay, collapse };
constexpr int kMaxMenu = 8;  // options of one node: at most max_candidates snaps, stay, collapse

struct Option {
  Vec3 position{};
  PhaseMask mask = 0;
  double score = 0;  // refusal priority: the guard refuses the highest first
  OptionKind kind = OptionKind::stay;
};

// A snap candidate before the options are assembled.
struct Candidate {
  std::int32_t node = 0;
  std::int32_t edge = 0;   // the phase-changing edge it snaps along (its position, mask)
  double distance = 0;     // length of the move
  double fraction = 0;     // of its edge's length
  LatticeKey3 other = 0;   // the edge's other end: a fixed tie-break
};

// What build_options needs of a phase-changing edge besides its cut: its ends' node ids
// (looking them up by the cut's keys was two fifths of build_options' time, cache misses in
// the registry) and the crossings nearest each end, for snap candidates. The ends' frame
// points and positions are not kept (they were two thirds of the record, the largest table
// alive at the mesher's peak): build_options derives them from the cut's keys.
struct EdgeEnds {
  std::int32_t lo = -1, hi = -1;  // nodes at the cut's keys lo and hi
  double t_front = 0, t_back = 0;  // along lo → hi
  PhaseMask mask_front = 0, mask_back = 0;  // 0: no crossing
  bool any() const { return mask_front != 0; }
};

// What the guard reads of a vertex's menu entry in the leaf being guarded (take_menu): its
// position in the leaf's frame, its closure mask, and `where` (0: the lattice position,
// 1 + j: the node's j-th snap).
struct MenuEntry {
  Vec3 p{};
  PhaseMask mask = 0;
  std::uint32_t where = 0;
};

// An edge's ends in its frame (radapt3.hpp, EdgeFrame): lattice points, positions, length.
struct EdgeGeometry {
  LatticePoint3 qa{}, qb{};
  Vec3 pa{}, pb{};
  bool axis = true;
  double length = 0;
};

}  // namespace

// (Outside the anonymous namespace: Snapping3 holds one.)
class Snapper {
 public:
  Snapper(const geometry::Oracle3& oracle, const samr::RefinedGrid3& g, const Options3& options)
      : oracle_(oracle), g_(g), forest_(g.forest), lattice_(g.forest.lattice()), options_(options) {}

  // Nodes, edges, options and the guard's first pass (Snapping3's constructor).
  void first_half() {
    register_nodes();
    find_edges();
    release_free_memory();  // the edge search's hash map
    build_options();
    if (options_.bound > 0) {
      summarise_menus();
      guard_first_pass();
    }
  }
  // The guard's second pass and every node's decision (Snapping3::finish).
  Nodes3 second_half() {
    if (options_.bound > 0) guard_second_pass();
    apply();
    advance(options_.progress, passes() * tets(), passes() * tets());
    return std::move(nodes_);
  }

  const Nodes3& nodes() const { return nodes_; }
  int option_count(std::int32_t node) const {
    return option_begin_[static_cast<std::size_t>(node) + 1] - option_begin_[static_cast<std::size_t>(node)];
  }
  // Bit j: the first pass refused the node's j-th option.
  std::uint32_t first_pass_refusals(std::int32_t node) const {
    std::uint32_t bits = 0;
    if (likely_.empty()) return bits;
    const std::int32_t begin = option_begin_[static_cast<std::size_t>(node)];
    for (int j = 0; j < option_count(node); ++j) bits |= likely_[static_cast<std::size_t>(begin + j)] ? 1u << j : 0u;
    return bits;
  }
  void set_first_pass_refusals(std::int32_t node, std::uint32_t bits) {
    if (likely_.empty()) return;
    const std::int32_t begin = option_begin_[static_cast<std::size_t>(node)];
    for (int j = 0; j < option_count(node); ++j) likely_[static_cast<std::size_t>(begin + j)] = (bits >> j) & 1;
  }

 private:
  const geometry::Oracle3& oracle_;
  const samr::RefinedGrid3& g_;
  const grid::TetForest& forest_;
  const grid::Lattice3& lattice_;
  const Options3 options_;
  Nodes3 nodes_;
  std::vector<EdgeEnds> ends_;        // per edge of nodes_.edges
  // Options per node (CSR); nodes without a phase change nearby have none (they stay).
  std::vector<std::int32_t> option_begin_;
  std::vector<Option> option_;
  // Per node, what build_menu asks of its options before it lists them (summarise_menus):
  // the AND of their masks (the node's own mask when it has none) and kMenuChoice /
  // kMenuFirstSnaps. The guard asks for every leaf of its windows, twice; dense arrays
  // instead of each vertex's option range: most leaves stop at the first question.
  std::vector<PhaseMask> menu_always_;
  std::vector<std::uint8_t> menu_flags_;
  static constexpr std::uint8_t kMenuChoice = 1, kMenuFirstSnaps = 2;
  std::vector<std::uint8_t> refused_;
  std::vector<PhaseMask> collapse_mask_;
  // Per node and phase joined by a collapse: the distance to the nearest point known to lie
  // on that phase's boundary (a crossing on a phase-changing edge, or the neighbour itself),
  // an upper bound of the collapse's deviation tighter than the oracle's for STL unions.
  // Keyed by node · 64 + phase (reach_index_: key → index into reach_).
  grid::KeyMap reach_index_;
  std::vector<double> reach_;
  std::vector<geometry::Crossing> crossings_;
  std::vector<std::int32_t> plane_candidates_;

  std::size_t node_count() const { return nodes_.key.size(); }

  // Progress: one unit per tet of the forest in each pass over it (nodes, edges, and the
  // guard's two), in that order.
  std::int64_t tets() const { return static_cast<std::int64_t>(forest_.size()); }
  std::int64_t passes() const { return options_.bound > 0 ? 4 : 2; }
  void tet_done(int pass, std::int32_t t) const {
    advance_sometimes(options_.progress, pass * tets() + t, passes() * tets());
  }

  // 1. Vertices of every leaf in the window and their closure masks. A leaf that no boundary meets lies
  //    inside one phase, so its vertices take that phase without asking the oracle per vertex.
  void register_nodes() {
    // About one node per four forest tets (five tets per cube at level 0, fewer with
    // refinement): sized for that, the registry and the per-node arrays never grow by
    // copying at the mesher's peak, and capacity never touched costs no memory.
    const std::size_t expected_nodes = forest_.size() / 4 + 16;
    nodes_.registry = grid::LatticeKeyIndex(expected_nodes);
    nodes_.key.reserve(expected_nodes);
    nodes_.position.reserve(expected_nodes);
    nodes_.mask.reserve(expected_nodes);
    nodes_.finest_level.reserve(expected_nodes);
    nodes_.tet_nodes.resize(forest_.size());
    const PhaseMask matrix_bit = PhaseMask{1} << oracle_.matrix_phase();
    for (std::int32_t t = 0; t < static_cast<std::int32_t>(forest_.size()); ++t) {
      tet_done(0, t);
      if (!forest_.is_leaf(t)) continue;
      auto& ids = nodes_.tet_nodes[static_cast<std::size_t>(t)];
      if (!options_.window.holds(forest_, t)) {
        ids = {-1, -1, -1, -1};
        continue;
      }
      ++nodes_.window_leaves;
      const auto v = forest_.fine_vertices(t);
      const std::uint8_t level = forest_.tet(t).level;
      for (int i = 0; i < 4; ++i) {
        ids[static_cast<std::size_t>(i)] = add_node(v[i]);
        std::uint8_t& finest = nodes_.finest_level[static_cast<std::size_t>(ids[static_cast<std::size_t>(i)])];
        finest = std::max(finest, level);
      }
      const auto candidates = g_.candidates_of_tet(t);
      if (g_.is_cut(t)) {
        for (std::int32_t id : ids) {
          if (nodes_.mask[static_cast<std::size_t>(id)] != 0) continue;
          const Vec3& p = nodes_.position[static_cast<std::size_t>(id)];
          // A node on a periodic plane is a vertex of leaves on both sides of the period,
          // whose candidate lists hold the geometry in different frames: ask for its own.
          if (lattice_.any_periodic() && on_periodic_plane(grid::key3_point(nodes_.key[static_cast<std::size_t>(id)]))) {
            oracle_.candidates(Box3{p, p}, plane_candidates_);
            nodes_.mask[static_cast<std::size_t>(id)] = oracle_.closure_phases(p, plane_candidates_);
          } else {
            nodes_.mask[static_cast<std::size_t>(id)] = oracle_.closure_phases(p, candidates);
          }
        }
      } else {
        // No boundary meets the leaf: its vertices lie strictly inside its phase, so one
        // already classified (by a neighbour) tells it without asking the oracle.
        PhaseMask bit = matrix_bit;
        PhaseMask known = 0;
        for (std::int32_t id : ids) known = known != 0 ? known : nodes_.mask[static_cast<std::size_t>(id)];
        if (known != 0) {
          bit = known;
        } else if (!candidates.empty()) {
          Vec3 centre{0, 0, 0};
          for (int i = 0; i < 4; ++i) {
            const Vec3 p = frame_position(ids[static_cast<std::size_t>(i)], v[i]);
            for (int d = 0; d < 3; ++d) centre[d] += 0.25 * p[d];
          }
          bit = PhaseMask{1} << oracle_.phase_at(centre, candidates);
        }
        for (std::int32_t id : ids)
          if (nodes_.mask[static_cast<std::size_t>(id)] == 0) nodes_.mask[static_cast<std::size_t>(id)] = bit;
      }
    }
    nodes_.state.assign(node_count(), NodeState::stayed);
  }

  // On a periodic plane: a canonical coordinate 0 on a periodic axis.
  bool on_periodic_plane(const LatticePoint3& canonical) const {
    for (int d = 0; d < 3; ++d)
      if (lattice_.periodic[d] && canonical[d] == 0) return true;
    return false;
  }
  // The position of node `id` seen at frame point `frame` ∈ [0, P] (lattice.hpp).
  Vec3 frame_position(std::int32_t id, const LatticePoint3& frame) const {
    return lattice_.shifted(nodes_.position[static_cast<std::size_t>(id)], lattice_.image_shift(frame));
  }

  // Nodes registered lately, by key (direct-mapped on the key's hash): a leaf's vertices were
  // mostly registered by the leaves just before it (forest order is spatially coherent), and
  // each probe of the registry's slots is a cache miss (two thirds of register_nodes' time).
  // An entry stays true once made: ids never change.
  struct RecentNode {
    LatticeKey3 key = 0;
    std::int32_t id = -1;
  };
  static constexpr int kRecentNodeBits = 12;
  std::vector<RecentNode> recent_nodes_ = std::vector<RecentNode>(std::size_t{1} << kRecentNodeBits);

  // Registers the node at frame point `frame` under its canonical point.
  std::int32_t add_node(const LatticePoint3& frame) {
    const LatticePoint3 p = lattice_.canonical_point(frame);
    const LatticeKey3 k = grid::key3(p);
    RecentNode& recent = recent_nodes_[grid::LatticeKeyHash{}(k) >> (64 - kRecentNodeBits)];
    if (recent.id >= 0 && recent.key == k) return recent.id;
    bool inserted = false;
    const auto next = static_cast<std::int32_t>(nodes_.key.size());
    const std::int32_t id = nodes_.registry.insert(k, next, nodes_.key, inserted);
    recent = {k, id};
    if (inserted) {
      nodes_.key.push_back(k);
      nodes_.position.push_back(forest_.position(p));
      nodes_.mask.push_back(0);
      nodes_.finest_level.push_back(0);
    }
    return id;
  }

  // 2. The phase-changing edges of cut leaves (disjoint closure masks at the ends): the
  //    crossings of each, once, on the segment oriented from the smaller key.
  void find_edges() {
    nodes_.cut_leaf_slot.assign(forest_.size(), -1);
    // (lo, hi) → index into nodes_.edges, while they are found. Open addressing: a
    // std::unordered_map allocated a node per edge and rehashed them as it grew.
    grid::OpenKeyMap<std::pair<LatticeKey3, LatticeKey3>, EdgeKeyHash> index(forest_.size() / 32 + 16);
    for (std::int32_t t = 0; t < static_cast<std::int32_t>(forest_.size()); ++t) {
      tet_done(1, t);
      if (!forest_.is_leaf(t) || !g_.is_cut(t) || !nodes_.registered(t)) continue;
      const auto& ids = nodes_.tet_nodes[static_cast<std::size_t>(t)];
      const auto v = forest_.fine_vertices(t);
      std::array<std::int32_t, 6> slots{-1, -1, -1, -1, -1, -1};
      bool any = false;
      for (int e = 0; e < 6; ++e) {
        std::int32_t a = ids[tet::kEdges[e][0]], b = ids[tet::kEdges[e][1]];
        if (nodes_.mask[static_cast<std::size_t>(a)] & nodes_.mask[static_cast<std::size_t>(b)]) continue;
        EdgeFrame frame = edge_frame(lattice_, v[tet::kEdges[e][0]], v[tet::kEdges[e][1]]);
        if (grid::key3(frame.b) < grid::key3(frame.a)) std::swap(a, b), std::swap(frame.a, frame.b);
        const std::pair<LatticeKey3, LatticeKey3> k{grid::key3(frame.a), grid::key3(frame.b)};
        bool inserted = false;
        slots[static_cast<std::size_t>(e)] = index.insert(k, static_cast<std::int32_t>(nodes_.edges.size()), inserted);
        if (inserted) add_edge(a, b, frame, t);
        any = true;
      }
      if (!any) continue;
      nodes_.cut_leaf_slot[static_cast<std::size_t>(t)] = static_cast<std::int32_t>(nodes_.leaf_edges.size());
      nodes_.leaf_edges.push_back(slots);
    }
    nodes_.edge_order.resize(nodes_.edges.size());
    for (std::size_t e = 0; e < nodes_.edges.size(); ++e) nodes_.edge_order[e] = static_cast<std::int32_t>(e);
    std::ranges::sort(nodes_.edge_order, [&](std::int32_t x, std::int32_t y) {
      const EdgeCut &a = nodes_.edges[static_cast<std::size_t>(x)], &b = nodes_.edges[static_cast<std::size_t>(y)];
      return std::pair{a.lo, a.hi} < std::pair{b.lo, b.hi};
    });
  }

  // The crossings of the edge from node `lo` to node `hi`, in the edge's frame (its ends
  // frame.a and frame.b, lo's key the smaller there).
  void add_edge(std::int32_t lo, std::int32_t hi, const EdgeFrame& frame, std::int32_t leaf) {
    EdgeEnds ends;
    ends.lo = lo, ends.hi = hi;
    const Vec3 pa = frame_position(lo, frame.a), pb = frame_position(hi, frame.b);
    if (frame.on_periodic_plane(lattice_)) {  // seen from two frames: its own candidates
      oracle_.candidates(segment_box(pa, pb), plane_candidates_);
      oracle_.crossings(pa, pb, plane_candidates_, crossings_);
    } else {
      oracle_.crossings(pa, pb, g_.candidates_of_tet(leaf), crossings_);
    }
    EdgeCut cut;
    cut.lo = grid::key3(frame.a);
    cut.hi = grid::key3(frame.b);
    // build_options finds the frame again from the keys.
    CISAMR_CHECK(grid::key3_point(cut.lo) == frame.a && grid::key3_point(cut.hi) == frame.b, "radapt3: an edge frame its keys do not give back");
    const PhaseMask ma = nodes_.mask[static_cast<std::size_t>(lo)], mb = nodes_.mask[static_cast<std::size_t>(hi)];
    const geometry::Crossing* chosen = crossing_between(crossings_, ma, mb);
    if (chosen == nullptr && !crossings_.empty()) {
      // No crossing goes straight from one end's phase to the other's: a third phase lies
      // in between, thinner than the edge (a gap at a contact). Its first crossing stands
      // for the interface, a collapse of that gap, off the far phase by at most the
      // distance to the crossing that enters it.
      chosen = &crossings_.front();
      double enter = 1.0;
      for (const auto& c : crossings_)
        if (mb & (PhaseMask{1} << c.to_phase)) {
          enter = c.t;
          break;
        }
      ++nodes_.collapsed_cut_points;
      nodes_.max_collapse_deviation =
          std::max(nodes_.max_collapse_deviation, (enter - chosen->t) * mesh::distance<3>(pa, pb));
    }
    if (chosen != nullptr) {
      for (int d = 0; d < 3; ++d) cut.point[d] = pa[d] + chosen->t * (pb[d] - pa[d]);
      cut.mask = (PhaseMask{1} << chosen->from_phase) | (PhaseMask{1} << chosen->to_phase);
      cut.found = true;
      const auto& f = crossings_.front();
      const auto& l = crossings_.back();
      ends.t_front = f.t, ends.mask_front = (PhaseMask{1} << f.from_phase) | (PhaseMask{1} << f.to_phase);
      ends.t_back = l.t, ends.mask_back = (PhaseMask{1} << l.from_phase) | (PhaseMask{1} << l.to_phase);
    } else {
      for (int d = 0; d < 3; ++d) cut.point[d] = 0.5 * (pa[d] + pb[d]);
      cut.mask = ma | mb;
      ++nodes_.missing_crossings;
    }
    nodes_.edges.push_back(cut);
    ends_.push_back(ends);
  }

  // A node on the domain boundary may only move within it: along an edge that keeps every
  // boundary coordinate of the node. Domain corners never move.
  bool slides_within_domain(const LatticePoint3& pv, const LatticePoint3& pw) const {
    for (int d = 0; d < 3; ++d) {
      const std::int64_t top = grid::fine_extent(lattice_, d);
      if ((pv[d] == 0 || pv[d] == top) && pw[d] != pv[d]) return false;
    }
    return true;
  }

  // 3. Options per node: snap candidates (nearest first, at most max_candidates), stay,
  //    collapse. Refusal scores: a long snap is refused before a short one (its node then
  //    takes its next option, usually harmless); staying next to a crossing (which would
  //    leave a sliver in the split) is refused before any snap, since collapsing there moves
  //    the interface by almost nothing; staying far from every crossing comes last.
  // What add_edge had in hand: the edge's frame points from its cut's keys, their positions.
  EdgeGeometry edge_geometry(const EdgeCut& cut, std::int32_t lo, std::int32_t hi) const {
    EdgeGeometry g;
    g.qa = grid::key3_point(cut.lo), g.qb = grid::key3_point(cut.hi);
    g.pa = frame_position(lo, g.qa), g.pb = frame_position(hi, g.qb);
    int differing = 0;
    for (int d = 0; d < 3; ++d) differing += g.qa[d] != g.qb[d] ? 1 : 0;
    g.axis = differing == 1;
    g.length = mesh::distance<3>(g.pa, g.pb);
    return g;
  }

  void build_options() {
    const std::size_t n = node_count();
    collapse_mask_.assign(n, 0);
    std::vector<double> nearest(n, std::numeric_limits<double>::infinity());
    std::vector<Candidate> candidates;
    for (std::size_t e = 0; e < nodes_.edges.size(); ++e) {
      const EdgeCut& cut = nodes_.edges[e];
      const EdgeEnds& ends = ends_[e];
      const std::int32_t lo = ends.lo, hi = ends.hi;
      const EdgeGeometry geo = edge_geometry(cut, lo, hi);
      for (int side = 0; side < 2; ++side) {
        const std::int32_t v = side == 0 ? lo : hi, w = side == 0 ? hi : lo;
        const auto uv = static_cast<std::size_t>(v), uw = static_cast<std::size_t>(w);
        collapse_mask_[uv] |= nodes_.mask[uw];
        {
          const double to_crossing = ends.any() ? (side == 0 ? ends.t_front : 1.0 - ends.t_back) * geo.length : geo.length;
          const PhaseMask beyond = ends.any() ? (side == 0 ? ends.mask_front : ends.mask_back) & ~nodes_.mask[uv] : 0;
          for (PhaseMask rest = nodes_.mask[uw]; rest != 0; rest &= rest - 1) {
            const int phase = std::countr_zero(rest);
            const double d = (beyond >> phase) & 1 ? to_crossing : geo.length;
            bool inserted = false;
            const std::int32_t at = reach_index_.insert(static_cast<std::uint64_t>(v) * 64 + static_cast<std::uint64_t>(phase),
                                                        static_cast<std::int32_t>(reach_.size()), inserted);
            if (inserted) reach_.push_back(d);
            else reach_[static_cast<std::size_t>(at)] = std::min(reach_[static_cast<std::size_t>(at)], d);
          }
        }
        if (!ends.any()) continue;
        const double fraction = side == 0 ? ends.t_front : 1.0 - ends.t_back;
        nearest[uv] = std::min(nearest[uv], fraction);
        if (single_phase(nodes_.mask[uv]) < 0) continue;  // already on an interface
        if (fraction > (geo.axis ? options_.alpha : options_.alpha_diagonal)) continue;
        // In the edge's frame (on a periodic plane a node slides within it, so its frame is
        // then its canonical one and the snapped position needs no shift).
        if (!slides_within_domain(side == 0 ? geo.qa : geo.qb, side == 0 ? geo.qb : geo.qa)) continue;
        Candidate c;
        c.node = v;
        c.edge = static_cast<std::int32_t>(e);
        c.fraction = fraction;
        c.distance = fraction * geo.length;
        c.other = nodes_.key[uw];
        candidates.push_back(c);
      }
    }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
      if (a.node != b.node) return a.node < b.node;
      if (a.distance != b.distance) return a.distance < b.distance;
      return a.other < b.other;
    });
    // Options per node: counted first, so that the table is allocated once at its size (it is
    // alive at the mesher's peak).
    option_begin_.assign(n + 1, 0);
    {
      std::size_t c = 0;
      for (std::size_t v = 0; v < n; ++v) {
        std::int32_t count = 0;
        for (; c < candidates.size() && candidates[c].node == static_cast<std::int32_t>(v); ++c) ++count;
        option_begin_[v + 1] = option_begin_[v] + std::min(count, options_.max_candidates) + (collapse_mask_[v] != 0 ? 2 : 0);
      }
    }
    option_.reserve(static_cast<std::size_t>(option_begin_[n]));
    std::size_t c = 0;
    for (std::size_t v = 0; v < n; ++v) {
      int kept = 0;
      for (; c < candidates.size() && candidates[c].node == static_cast<std::int32_t>(v); ++c) {
        if (kept >= options_.max_candidates) continue;
        ++kept;
        option_.push_back(snap_option(candidates[c]));
      }
      if (collapse_mask_[v] == 0) continue;  // no phase change at this node
      const double near = nearest[v];
      option_.push_back({nodes_.position[v], nodes_.mask[v], near < 0.15 ? 2.0 - near : 0.5 - std::min(near, 1.0),
                         OptionKind::stay});
      option_.push_back({nodes_.position[v], nodes_.mask[v] | collapse_mask_[v], 0.0, OptionKind::collapse});
    }
    CISAMR_CHECK(option_.size() == static_cast<std::size_t>(option_begin_[n]), "radapt3: options miscounted");
    refused_.assign(option_.size(), 0);
  }

  // The snap of candidate `c`: onto its edge's crossing nearest its node, in the edge's frame.
  Option snap_option(const Candidate& c) const {
    const EdgeCut& cut = nodes_.edges[static_cast<std::size_t>(c.edge)];
    const EdgeEnds& ends = ends_[static_cast<std::size_t>(c.edge)];
    const std::int32_t lo = ends.lo, hi = ends.hi;
    const EdgeGeometry geo = edge_geometry(cut, lo, hi);
    const bool front = c.node == lo;
    const double t = front ? ends.t_front : ends.t_back;
    Option o;
    for (int d = 0; d < 3; ++d) o.position[d] = geo.pa[d] + t * (geo.pb[d] - geo.pa[d]);
    o.mask = front ? ends.mask_front : ends.mask_back;
    o.score = 1.0 + c.fraction;
    o.kind = OptionKind::snap;
    return o;
  }

  // 4. The guard, leaf by leaf (see the header).
  // Per vertex of a leaf: the options to enumerate (the last one is never refused), -1 for
  // a node without options. False when no vertex has a choice.
  using Menu = std::array<std::array<std::int32_t, kMaxMenu>, 4>;
  bool build_menu(std::int32_t t, Menu& menu, std::array<int, 4>& count) const {
    const auto& ids = nodes_.tet_nodes[static_cast<std::size_t>(t)];
    std::uint8_t flags = 0;
    for (int i = 0; i < 4; ++i) flags |= menu_flags_[static_cast<std::size_t>(ids[static_cast<std::size_t>(i)])];
    if (!(flags & kMenuChoice)) return false;
    // A leaf where some phase is in every option of every vertex is kept whole whatever
    // happens: only positions matter, and staying or collapsing is the same position.
    // Enumerate its snaps and one unmoved entry (the collapse, whose mask holds the stay's:
    // if even it leaves the leaf in a void only, nothing is emitted).
    PhaseMask always = ~PhaseMask{0};
    for (int i = 0; i < 4; ++i) always &= menu_always_[static_cast<std::size_t>(ids[static_cast<std::size_t>(i)])];
    // Undeformed unless a vertex may snap: nothing to check then.
    if (always != 0 && !(flags & kMenuFirstSnaps)) return false;
    for (int i = 0; i < 4; ++i) {
      const std::int32_t v = ids[static_cast<std::size_t>(i)];
      auto& m = menu[static_cast<std::size_t>(i)];
      int& n = count[static_cast<std::size_t>(i)];
      n = 0;
      const std::int32_t begin = option_begin_[static_cast<std::size_t>(v)], end = option_begin_[static_cast<std::size_t>(v) + 1];
      if (begin == end) {
        m[static_cast<std::size_t>(n++)] = -1;
        continue;
      }
      for (std::int32_t o = begin; o < end; ++o) {
        if (always != 0 && o + 1 < end && option_[static_cast<std::size_t>(o)].kind != OptionKind::snap) continue;
        m[static_cast<std::size_t>(n++)] = o;
      }
    }
    return true;
  }

  // The option of a bad combination to refuse: the deepest fallback first (a combination
  // happens only if every earlier option of its vertices was refused), then the highest
  // score. Depth counts the earlier options not known to be refused (`gone(i, j)`: vertex
  // i's j-th menu entry): once an option is refused, the node's next one is what is expected
  // to happen. -1 when every vertex is at its last option.
  template <class Gone>
  std::int32_t pick_refusal(const Menu& menu, const std::array<int, 4>& count, const std::array<int, 4>& at,
                            const std::array<std::int32_t, 4>& chosen, Gone&& gone) const {
    std::int32_t pick = -1;
    int pick_rank = -1;
    for (int i = 0; i < 4; ++i) {
      const std::int32_t o = chosen[static_cast<std::size_t>(i)];
      if (o < 0 || at[static_cast<std::size_t>(i)] + 1 == count[static_cast<std::size_t>(i)]) continue;
      int rank = 0;
      for (int j = 0; j < at[static_cast<std::size_t>(i)]; ++j)
        rank += gone(i, j) ? 0 : 1;
      if (pick < 0 || rank > pick_rank ||
          (rank == pick_rank && option_[static_cast<std::size_t>(o)].score > option_[static_cast<std::size_t>(pick)].score))
        pick = o, pick_rank = rank;
    }
    return pick;
  }

  // The per-node summary build_menu reads (menu_always_, menu_flags_), once the options are built.
  void summarise_menus() {
    const std::size_t n = node_count();
    menu_always_.assign(n, 0);
    menu_flags_.assign(n, 0);
    for (std::size_t v = 0; v < n; ++v) {
      const std::int32_t begin = option_begin_[v], end = option_begin_[v + 1];
      PhaseMask always = begin == end ? nodes_.mask[v] : ~PhaseMask{0};
      for (std::int32_t o = begin; o < end; ++o) always &= option_[static_cast<std::size_t>(o)].mask;
      menu_always_[v] = always;
      menu_flags_[v] = static_cast<std::uint8_t>((end - begin > 1 ? kMenuChoice : 0) |
                                                 (end > begin && option_[static_cast<std::size_t>(begin)].kind == OptionKind::snap
                                                      ? kMenuFirstSnaps
                                                      : 0));
    }
  }

  // The guard, in two passes over the leaves, each leaf deciding from its own data and
  // what the previous pass decided (so order-free):
  //  1. every leaf checks the combination of its vertices' first options, the one expected
  //     to happen, and refuses one option if it is bad: refusals almost sure to be needed;
  //  2. every leaf checks every combination of the options not refused in pass 1, refusing
  //     (see pick_refusal) until none of them is bad.
  // A node ends at its first option not refused; the combination that happens in a leaf
  // avoids every refused option, so the leaf checked it in pass 2. Between the passes a
  // caller may replace some nodes' pass-1 refusals (Snapping3): the parallel mesher takes
  // those of nodes outside a box from the partition that owns them.
  std::vector<std::uint8_t> likely_;       // pass 1's refusals, per option
  std::vector<std::int32_t> with_menu_;    // the leaves of either pass's window with a menu, ascending
  void guard_first_pass() {
    Menu menu{};
    std::array<int, 4> count{};
    std::array<std::int32_t, 4> chosen{};
    const std::array<int, 4> first{0, 0, 0, 0};
    likely_.assign(option_.size(), 0);
    std::vector<std::uint8_t>& likely = likely_;
    // Pass 1's scan also lists the leaves of pass 2's window that have a menu, in ascending
    // order, so that pass 2 visits only those (in the kernel its window lies within pass 1's).
    const auto& first_window = options_.first_pass_window;
    const auto& second_window = options_.second_pass_window;
    std::vector<std::int32_t>& with_menu = with_menu_;
    with_menu.clear();
    for (std::int32_t t = 0; t < static_cast<std::int32_t>(forest_.size()); ++t) {
      tet_done(2, t);
      if (!forest_.is_leaf(t) || !nodes_.registered(t)) continue;
      const bool in_first = first_window.holds(forest_, t);
      if (!(in_first || second_window.holds(forest_, t)) || !build_menu(t, menu, count)) continue;
      with_menu.push_back(t);
      if (!in_first) continue;
      memo_leaf(t);
      for (int i = 0; i < 4; ++i) chosen[static_cast<std::size_t>(i)] = menu[static_cast<std::size_t>(i)][0];
      take_menu(t, menu, {1, 1, 1, 1});
      ++nodes_.combinations;
      if (acceptable(first)) continue;
      const std::int32_t pick = pick_refusal(menu, count, first, chosen, [](int, int) { return false; });
      if (pick >= 0) likely[static_cast<std::size_t>(pick)] = 1;
    }
  }

  void guard_second_pass() {
    Menu menu{};
    std::array<int, 4> count{};
    const std::vector<std::uint8_t>& likely = likely_;
    const auto& first_window = options_.first_pass_window;
    const auto& second_window = options_.second_pass_window;
    for (std::size_t o = 0; o < likely.size(); ++o) refused_[o] = likely[o];

    for (const std::int32_t t : with_menu_) {
      tet_done(3, t);
      if (!second_window.holds(forest_, t)) continue;
      build_menu(t, menu, count);  // pass 1 found one
      ++nodes_.guarded_leaves;
      memo_leaf(t);
      // Pass 1's refusals leave the menus (their combinations cannot happen). When every
      // vertex keeps its first option, this leaf's pass 1 found their combination good
      // (had it been bad, the leaf would have refused one of them): it is not checked again.
      // (Only if pass 1 ran on this leaf: the windows nest in the kernel, not in every caller.)
      bool firsts_good = first_window.holds(forest_, t);
      for (int i = 0; i < 4; ++i) {
        auto& m = menu[static_cast<std::size_t>(i)];
        int& n = count[static_cast<std::size_t>(i)];
        int kept = 0;
        for (int j = 0; j < n; ++j) {
          const std::int32_t o = m[static_cast<std::size_t>(j)];
          if (o < 0 || !likely[static_cast<std::size_t>(o)]) m[static_cast<std::size_t>(kept++)] = o;
          else if (j == 0) firsts_good = false;
        }
        n = kept;
      }
      take_menu(t, menu, count);
      nodes_.combinations += guard_leaf(menu, count, firsts_good);
    }
    std::vector<std::int32_t>().swap(with_menu_);
    std::vector<std::uint8_t>().swap(likely_);
  }

  // Pass 2 in one leaf whose menus take_menu has read: every combination (but the first when
  // `firsts_good`: pass 1 found it good), vertex 0's entry changing fastest, refusing
  // (pick_refusal) until none is bad. Returns the combinations checked. Nested loops with the
  // three outer vertices' share of acceptable() hoisted: most leaves refuse nothing, and the
  // odometer's per-combination bookkeeping was a third of the guard's instructions.
  std::int64_t guard_leaf(const Menu& menu, const std::array<int, 4>& count, bool firsts_good) {
    // Bit j of gone_entries[i]: this leaf refused vertex i's j-th entry (each option is
    // one node's, and a node is one vertex of the leaf: one bit per refusal).
    std::array<std::uint8_t, 4> gone_entries{};
    static_assert(kMaxMenu <= 8);
    const auto gone = [&](int i, int j) { return (gone_entries[static_cast<std::size_t>(i)] >> j) & 1; };
    bool any_gone = false;
    std::int64_t checked = 0;
    const auto& entry = leaf_.entry;
    std::array<int, 4> at{0, 0, 0, 0};
    for (at[3] = 0; at[3] < count[3]; ++at[3])
      for (at[2] = 0; at[2] < count[2]; ++at[2])
        for (at[1] = 0; at[1] < count[1]; ++at[1]) {
          const auto& e1 = entry[1][static_cast<std::size_t>(at[1])];
          const auto& e2 = entry[2][static_cast<std::size_t>(at[2])];
          const auto& e3 = entry[3][static_cast<std::size_t>(at[3])];
          const PhaseMask rest_mask = e1.mask & e2.mask & e3.mask;
          const std::size_t rest_slot = e1.where << 3 | e2.where << 6 | e3.where << 9;
          // The first row starts past the first combination (all entries 0) when pass 1 found
          // it good; every later row starts at 0.
          for (at[0] = std::exchange(firsts_good, false) ? 1 : 0; at[0] < count[0]; ++at[0]) {
            if (any_gone && (gone(0, at[0]) || gone(1, at[1]) || gone(2, at[2]) || gone(3, at[3]))) continue;
            ++checked;
            if (acceptable_with(entry[0][static_cast<std::size_t>(at[0])], rest_mask, rest_slot, at)) continue;
            // No refusable option: every vertex at its last option, which keeps the leaf
            // whole and undeformed; only a leaf no two phases can split ends here.
            std::array<std::int32_t, 4> chosen{};
            for (int i = 0; i < 4; ++i)
              chosen[static_cast<std::size_t>(i)] = menu[static_cast<std::size_t>(i)][static_cast<std::size_t>(at[static_cast<std::size_t>(i)])];
            const std::int32_t pick = pick_refusal(menu, count, at, chosen, gone);
            if (pick < 0) continue;
            for (int k = 0; k < 4; ++k)
              if (chosen[static_cast<std::size_t>(k)] == pick)
                gone_entries[static_cast<std::size_t>(k)] |= static_cast<std::uint8_t>(1u << at[static_cast<std::size_t>(k)]);
            refused_[static_cast<std::size_t>(pick)] = 1;
            any_gone = true;
          }
        }
    return checked;
  }

  bool is_void(int phase) const { return (void_phases_ >> phase) & 1; }
  // The scene's void phases as a mask (is_void runs for every tet the guard emits).
  const PhaseMask void_phases_ = geometry::void_phase_mask(oracle_.scene());

  // What acceptable() reads of the first count[i] entries of vertex i's menu (-1: the node
  // has none, it stays), in the leaf's frame: once per leaf, not once per combination.
  void take_menu(std::int32_t t, const Menu& menu, const std::array<int, 4>& count) {
    const auto& ids = nodes_.tet_nodes[static_cast<std::size_t>(t)];
    for (int i = 0; i < 4; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const auto v = static_cast<std::size_t>(ids[k]);
      for (int j = 0; j < count[k]; ++j) {
        const std::int32_t o = menu[k][static_cast<std::size_t>(j)];
        const bool snap = o >= 0 && option_[static_cast<std::size_t>(o)].kind == OptionKind::snap;
        auto& entry = leaf_.entry[k][static_cast<std::size_t>(j)];
        entry.p = lattice_.shifted(o < 0 ? nodes_.position[v] : option_[static_cast<std::size_t>(o)].position, leaf_.shift[k]);
        entry.mask = o < 0 ? nodes_.mask[v] : option_[static_cast<std::size_t>(o)].mask;
        entry.where = snap ? static_cast<std::uint32_t>(1 + o - option_begin_[v]) : 0;
      }
    }
  }

  // Would the leaf, with vertex i at entry at[i] of its menu (take_menu), emit only
  // positive tetrahedra within the bound, and could it be split?
  [[gnu::always_inline]] bool acceptable(const std::array<int, 4>& at) {
    const auto& e1 = leaf_.entry[1][static_cast<std::size_t>(at[1])];
    const auto& e2 = leaf_.entry[2][static_cast<std::size_t>(at[2])];
    const auto& e3 = leaf_.entry[3][static_cast<std::size_t>(at[3])];
    return acceptable_with(leaf_.entry[0][static_cast<std::size_t>(at[0])], e1.mask & e2.mask & e3.mask,
                           e1.where << 3 | e2.where << 6 | e3.where << 9, at);
  }
  // acceptable() given vertex 0's entry and the other three's masks ANDed and `where`s
  // shifted into a slot (constant while vertex 0's entry changes).
  [[gnu::always_inline]] bool acceptable_with(const MenuEntry& e0, PhaseMask rest_mask, std::size_t rest_slot,
                                              const std::array<int, 4>& at) {
    const PhaseMask common = e0.mask & rest_mask;
    if (common != 0) {  // kept whole (grid::stencil3::outcome): the four positions decide
      if (single_bit(common) && is_void(std::countr_zero(common))) return true;
      // Most combinations end here: a table indexed by the positions' `where`s, no hashing.
      const std::size_t slot = e0.where | rest_slot;
      if (whole_stamp_[slot] != memo_generation_) {
        whole_stamp_[slot] = memo_generation_;
        const auto& e = leaf_.entry;
        whole_value_[slot] = good(e0.p, e[1][static_cast<std::size_t>(at[1])].p, e[2][static_cast<std::size_t>(at[2])].p,
                                  e[3][static_cast<std::size_t>(at[3])].p)
                                 ? 1
                                 : 0;
      }
      return whole_value_[slot] != 0;
    }
    return split_acceptable(at);
  }

  // acceptable() for a leaf the combination splits (kept out of line, so that the common
  // case above inlines into the guard's loops).
  [[gnu::noinline]] bool split_acceptable(const std::array<int, 4>& at) {
    std::array<PhaseMask, 4> mask{};
    std::array<std::uint32_t, 4> where{};  // 0: the lattice position, 1 + j: the node's j-th snap
    for (int i = 0; i < 4; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const auto& entry = leaf_.entry[k][static_cast<std::size_t>(at[k])];
      leaf_.p[k] = entry.p;
      mask[k] = entry.mask;
      where[k] = entry.where;
    }
    // A tet of the leaf is determined by its local points and, for the leaf's vertices, the
    // positions they take: its verdict is kept for the leaf's other combinations (most
    // differ in one vertex, and staying or collapsing is one position).
    const auto key = [&](std::uint8_t a, std::uint8_t b, std::uint8_t c, std::uint8_t d) {
      std::uint32_t k = 0;
      for (std::uint8_t q : {a, b, c, d}) k = (k << 7) | (std::uint32_t{q} << 3) | (q < 4 ? where[q] : 0u);
      return k;
    };
    const auto& p = leaf_.p;
    const PhaseMask all = mask[0] | mask[1] | mask[2] | mask[3];
    if (!two_bits(all)) return false;  // three phases: no stencil
    const PhaseMask plus = all & (~all + 1), minus = all & ~plus;
    std::array<int, 4> sign{};
    int pattern = 0;
    for (int i = 3; i >= 0; --i) {
      const PhaseMask m = mask[static_cast<std::size_t>(i)];
      sign[static_cast<std::size_t>(i)] = (m & plus) && (m & minus) ? 0 : (m & plus) ? 1 : -1;
      pattern = 3 * pattern + sign[static_cast<std::size_t>(i)] + 1;
    }
    // A strictly cut edge has both ends staying strictly inside different phases: it is a
    // phase-changing edge of this (cut) leaf, whose cut point radapt computed.
    for (int e = 0; e < 6; ++e)
      if (sign[tet::kEdges[e][0]] * sign[tet::kEdges[e][1]] < 0 && !leaf_.has_cut[static_cast<std::size_t>(e)])
        return false;
    // The split's structure depends on the signs and on the cut points only (the interface
    // quad takes its shorter diagonal), so one per sign pattern and phase pair.
    auto& cached = leaf_.split[static_cast<std::size_t>(pattern)];
    if (leaf_.stamp[static_cast<std::size_t>(pattern)] != memo_generation_ || leaf_.pair[static_cast<std::size_t>(pattern)] != all) {
      cached = grid::stencil3::split(leaf_.lattice, sign, leaf_.id, p);
      leaf_.stamp[static_cast<std::size_t>(pattern)] = memo_generation_;
      leaf_.pair[static_cast<std::size_t>(pattern)] = all;
    }
    const int phase_plus = std::countr_zero(plus), phase_minus = std::countr_zero(minus);
    // The sub-tets whose verdicts this leaf has not seen yet are evaluated two at a time (most
    // combinations bring two to four); a memoised bad one decides as well, once every slot
    // this call claimed holds its verdict.
    std::array<std::size_t, grid::stencil3::kMaxSplitTets> fresh_slot{};
    std::array<const grid::stencil3::LocalTet*, grid::stencil3::kMaxSplitTets> fresh_tet{};
    int fresh = 0;
    bool all_good = true;
    for (int k = 0; k < cached.count; ++k) {
      if (is_void(cached.side[static_cast<std::size_t>(k)] > 0 ? phase_plus : phase_minus)) continue;
      const auto& s = cached.tet[static_cast<std::size_t>(k)];
      bool known = false;
      const std::size_t slot = memo_slot(key(s[0], s[1], s[2], s[3]), known);
      if (known) {
        all_good = all_good && memo_value_[slot] != 0;
        continue;
      }
      fresh_slot[static_cast<std::size_t>(fresh)] = slot, fresh_tet[static_cast<std::size_t>(fresh)] = &s, ++fresh;
    }
    const auto points = [&](const grid::stencil3::LocalTet& t) {
      return std::array<const Vec3*, 4>{&p[t[0]], &p[t[1]], &p[t[2]], &p[t[3]]};
    };
    for (int i = 0; i < fresh; i += 2) {
      const auto& s = *fresh_tet[static_cast<std::size_t>(i)];
      std::array<bool, 2> verdict{};
      if (i + 1 < fresh)
        verdict = mesh::positive_within_pair(points(s), points(*fresh_tet[static_cast<std::size_t>(i) + 1]), options_.bound);
      else
        verdict[0] = good(p[s[0]], p[s[1]], p[s[2]], p[s[3]]);
      for (int j = 0; j < 2 && i + j < fresh; ++j) {
        const std::size_t slot = fresh_slot[static_cast<std::size_t>(i + j)];
        if (slot < kMemoSize) memo_value_[slot] = verdict[static_cast<std::size_t>(j)] ? 1 : 0;
        all_good = all_good && verdict[static_cast<std::size_t>(j)];
      }
    }
    return all_good;
  }

  // The leaf being guarded: its lattice points, point identities and cut points (points
  // 0-3 are set per combination), and its splits by sign pattern.
  struct LeafData {
    std::array<LatticePoint3, 4> lattice{};  // frame points
    std::array<std::uint8_t, 4> shift{};     // each vertex's image in the leaf's frame
    std::array<grid::stencil3::PointId, 10> id{};
    std::array<Vec3, 10> p{};
    std::array<bool, 6> has_cut{};
    std::array<grid::stencil3::Split, 81> split;
    std::array<std::uint32_t, 81> stamp{};
    std::array<PhaseMask, 81> pair{};
    std::array<std::array<MenuEntry, kMaxMenu>, 4> entry{};
  };
  LeafData leaf_;

  // Verdicts of good() within the current leaf (memo_leaf() starts a new leaf): of the whole
  // leaf by its vertices' `where`s (3 bits each), of the split's tetrahedra by key.
  static_assert(kMaxMenu <= 8);
  std::array<std::uint32_t, 4096> whole_stamp_{};
  std::array<std::uint8_t, 4096> whole_value_{};
  static constexpr std::size_t kMemoSize = 512;
  std::array<std::uint32_t, kMemoSize> memo_key_{};
  std::array<std::uint32_t, kMemoSize> memo_stamp_{};
  std::array<std::uint8_t, kMemoSize> memo_value_{};
  std::uint32_t memo_generation_ = 0;
  void memo_leaf(std::int32_t t) {
    ++memo_generation_;
    const auto& ids = nodes_.tet_nodes[static_cast<std::size_t>(t)];
    leaf_.lattice = forest_.fine_vertices(t);
    for (int i = 0; i < 4; ++i) {
      const auto v = static_cast<std::size_t>(ids[static_cast<std::size_t>(i)]);
      leaf_.shift[static_cast<std::size_t>(i)] = lattice_.image_shift(leaf_.lattice[static_cast<std::size_t>(i)]);
      leaf_.id[static_cast<std::size_t>(i)] = {nodes_.key[v], nodes_.key[v]};
    }
    const auto* edges = nodes_.edges_of(t);
    for (int e = 0; e < 6; ++e) {
      const std::int32_t ei = edges == nullptr ? -1 : (*edges)[static_cast<std::size_t>(e)];
      leaf_.has_cut[static_cast<std::size_t>(e)] = ei >= 0;
      if (ei < 0) continue;
      const EdgeCut& cut = nodes_.edges[static_cast<std::size_t>(ei)];
      const std::uint8_t shift = leaf_.shift[tet::kEdges[e][0]] & leaf_.shift[tet::kEdges[e][1]];
      leaf_.p[static_cast<std::size_t>(tet::midpoint(e))] = lattice_.shifted(cut.point, shift);
      leaf_.id[static_cast<std::size_t>(tet::midpoint(e))] = {cut.lo, cut.hi};
    }
  }
  // The memo's slot of `key` in the current leaf: `known` when it holds the key's verdict,
  // else claimed for it (the caller stores the verdict before the next look-up);
  // kMemoSize when the table is full (never with four vertices of four options).
  std::size_t memo_slot(std::uint32_t key, bool& known) {
    std::size_t slot = (key * 2654435761u) >> 23 & (kMemoSize - 1);
    for (std::size_t probe = 0; probe < kMemoSize; ++probe, slot = (slot + 1) & (kMemoSize - 1)) {
      if (memo_stamp_[slot] != memo_generation_) {
        memo_stamp_[slot] = memo_generation_;
        memo_key_[slot] = key;
        known = false;
        return slot;
      }
      if (memo_key_[slot] == key) {
        known = true;
        return slot;
      }
    }
    known = false;
    return kMemoSize;
  }

  bool good(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) const {
    return mesh::positive_within(a, b, c, d, options_.bound);
  }

  // 5. Every node takes its first option no leaf refused (its last one is never refused).
  void apply() {
    const std::size_t n = node_count();
    std::vector<std::int32_t> candidates;
    for (std::size_t v = 0; v < n; ++v) {
      const std::int32_t begin = option_begin_[v], end = option_begin_[v + 1];
      if (begin == end) continue;
      std::int32_t o = begin;
      while (o + 1 < end && refused_[static_cast<std::size_t>(o)]) ++o;
      if (o > begin) ++nodes_.refused_count;
      const Option& option = option_[static_cast<std::size_t>(o)];
      switch (option.kind) {
        case OptionKind::snap:
          nodes_.position[v] = option.position;
          nodes_.mask[v] = option.mask;
          nodes_.state[v] = NodeState::snapped;
          ++nodes_.snapped_count;
          break;
        case OptionKind::stay: break;
        case OptionKind::collapse: {
          const PhaseMask added = option.mask & ~nodes_.mask[v];
          for (PhaseMask rest = added; rest != 0; rest &= rest - 1) {
            const int phase = std::countr_zero(rest);
            double d = oracle_.distance_to_phase(nodes_.position[v], phase);
            if (const std::int32_t at = reach_index_.find(static_cast<std::uint64_t>(v) * 64 + static_cast<std::uint64_t>(phase));
                at != grid::KeyMap::kNone)
              d = std::min(d, reach_[static_cast<std::size_t>(at)]);
            nodes_.max_collapse_deviation = std::max(nodes_.max_collapse_deviation, d);
          }
          nodes_.mask[v] = option.mask;
          nodes_.state[v] = NodeState::collapsed;
          ++nodes_.collapsed_count;
          break;
        }
      }
    }
  }
};

Snapping3::Snapping3(const geometry::Oracle3& oracle, const samr::RefinedGrid3& g, const Options3& options) {
  if (options.max_candidates < 0 || options.max_candidates + 2 > kMaxMenu)
    throw std::invalid_argument("snap3: max_candidates must lie in [0, " + std::to_string(kMaxMenu - 2) + "]");
  snapper_ = std::make_unique<Snapper>(oracle, g, options);
  snapper_->first_half();
}
Snapping3::~Snapping3() = default;
Snapping3::Snapping3(Snapping3&&) noexcept = default;
Snapping3& Snapping3::operator=(Snapping3&&) noexcept = default;
const Nodes3& Snapping3::nodes() const { return snapper_->nodes(); }
int Snapping3::option_count(std::int32_t node) const { return snapper_->option_count(node); }
std::uint32_t Snapping3::first_pass_refusals(std::int32_t node) const { return snapper_->first_pass_refusals(node); }
void Snapping3::set_first_pass_refusals(std::int32_t node, std::uint32_t bits) {
  snapper_->set_first_pass_refusals(node, bits);
}
Nodes3 Snapping3::finish() {
  Nodes3 nodes = snapper_->second_half();
  snapper_.reset();
  return nodes;
}

Nodes3 snap3(const geometry::Oracle3& oracle, const samr::RefinedGrid3& g, const Options3& options) {
  return Snapping3(oracle, g, options).finish();
}

}  // namespace cisamr::radapt
