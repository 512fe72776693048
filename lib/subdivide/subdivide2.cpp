#include "subdivide/subdivide2.hpp"

#include <algorithm>
#include <bit>
#include <limits>

#include "core/check.hpp"
#include "core/error.hpp"
#include "mesh/metrics.hpp"
#include "subdivide/templates2.hpp"

namespace cisamr::subdivide {
namespace {

using Tri = std::array<std::uint8_t, 3>;

// The points of one leaf, in the leaf's frame: id is the canonical node (or a point made
// here), shift the periodic image it is seen at (bit d: + the period along d; lattice.hpp).
struct QuadPoints {
  Vec2 p[10];
  PhaseMask m[10];
  std::int32_t id[10];
  std::uint8_t shift[10] = {};
  grid::LatticeKey key[4];  // the corners' keys in the leaf's frame
};

// Phase of a triangle: the phase whose closure holds all three vertices; when several
// do (all three on one interface), the phase at the centroid decides.
int triangle_phase(const geometry::Oracle2& oracle, std::span<const std::int32_t> candidates,
                   PhaseMask common, const Vec2& a, const Vec2& b, const Vec2& c) {
  if (std::popcount(common) == 1) return std::countr_zero(common);
  const Vec2 centroid{(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0};
  const int phase = oracle.phase_at(centroid, candidates);
  if (common & (PhaseMask{1} << phase)) return phase;
  return std::countr_zero(common);
}

// Worst aspect ratio of a split, or +inf if a triangle is inverted or spans no common phase.
template <std::size_t N>
double split_quality(const QuadPoints& q, const std::array<Tri, N>& tris) {
  double worst = 0;
  for (const Tri& t : tris) {
    if ((q.m[t[0]] & q.m[t[1]] & q.m[t[2]]) == 0) return std::numeric_limits<double>::infinity();
    if (!(mesh::signed_area(q.p[t[0]], q.p[t[1]], q.p[t[2]]) > 0)) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, mesh::aspect_ratio(q.p[t[0]], q.p[t[1]], q.p[t[2]]));
  }
  return worst;
}

class Subdivider {
 public:
  Subdivider(const geometry::Oracle2& oracle, const samr::RefinedGrid2& g, const radapt::Nodes2& nodes,
             double collapse_fraction, double bound)
      : oracle_(oracle), g_(g), forest_(g.forest), nodes_(nodes), collapse_fraction_(collapse_fraction),
        bound_(bound) {}

  Triangles2 run(const grid::CellRange<2>& owned, Progress* progress) {
    const auto cells = static_cast<std::int64_t>(forest_.size());
    // About two triangles per leaf, more at hanging midpoints and cuts: reserved with room
    // to spare, the arrays do not grow by copying while the forest and the nodes are alive
    // (the mesher's peak), and capacity never written costs no memory.
    const std::size_t most = forest_.size() * 5 / 2 + 16;
    out_.triangles.reserve(3 * most);
    out_.phase.reserve(most);
    for (std::int32_t c = 0; c < static_cast<std::int32_t>(forest_.size()); ++c) {
      advance_sometimes(progress, c, cells);
      if (!forest_.is_leaf(c)) continue;
      if (!owned.contains(forest_.coarse_cell(c))) continue;
      leaf(c);
    }
    advance(progress, cells, cells);
    return std::move(out_);
  }

 private:
  const geometry::Oracle2& oracle_;
  const PhaseMask void_phases_ = geometry::void_phase_mask(oracle_.scene());
  const samr::RefinedGrid2& g_;
  const grid::QuadForest& forest_;
  const radapt::Nodes2& nodes_;
  const double collapse_fraction_;
  const double bound_;
  Triangles2 out_;
  std::vector<geometry::Crossing> crossings_;

  grid::KeyMap images_{16};  // (canonical node, shift) → output point, for periodic images
  bool images_made_ = false;  // extra_identity is kept once the first image is made

  std::int32_t node(std::int64_t x, std::int64_t y) const {
    const std::int32_t id = nodes_.id(x, y);
    CISAMR_CHECK(id >= 0, "subdivide2: missing lattice node");
    return id;
  }
  std::uint8_t shift_of(std::int64_t x, std::int64_t y) const { return forest_.lattice().image_shift({x, y}); }
  Vec2 shifted(const Vec2& p, std::uint8_t shift) const { return forest_.lattice().shifted(p, shift); }
  std::int32_t add_point(const Vec2& p) {
    out_.extra_points.push_back(p);
    if (images_made_) out_.extra_identity.push_back(Triangles2::kNoKey);
    return static_cast<std::int32_t>(nodes_.key.size() + out_.extra_points.size() - 1);
  }
  // The output point of canonical node `id` seen as its image `shift`: the node itself, or
  // a point of the max face made once, at its position plus the periods, with the lattice
  // key of the image (so that partitions merge it like any lattice node).
  std::int32_t output_id(std::int32_t id, std::uint8_t shift) {
    if (shift == 0 || static_cast<std::size_t>(id) >= nodes_.key.size()) return id;
    const std::uint64_t image_key = (static_cast<std::uint64_t>(id) << 2) | shift;
    if (const std::int32_t known = images_.find(image_key); known >= 0) return known;
    if (!images_made_) out_.extra_identity.assign(out_.extra_points.size(), Triangles2::kNoKey), images_made_ = true;
    const grid::Lattice2& l = forest_.lattice();
    const grid::LatticeKey k = nodes_.key[static_cast<std::size_t>(id)];
    const std::int64_t x = grid::key2_x(k) + ((shift & 1) ? l.fine_period(0) : 0);
    const std::int64_t y = grid::key2_y(k) + ((shift & 2) ? l.fine_period(1) : 0);
    const std::int32_t out = add_point(shifted(nodes_.position[static_cast<std::size_t>(id)], shift));
    out_.extra_identity.back() = grid::key2(x, y);
    bool inserted = false;
    images_.insert(image_key, out, inserted);
    return out;
  }
  void emit(const QuadPoints& q, int a, int b, int c, int phase) {
    // Cells of a void phase are not part of the mesh (assembly dropped them): not emitted,
    // they do not hold output memory at the mesher's peak.
    if ((void_phases_ >> phase) & 1) return;
    out_.triangles.insert(out_.triangles.end(), {output_id(q.id[a], q.shift[a]), output_id(q.id[b], q.shift[b]),
                                                 output_id(q.id[c], q.shift[c])});
    out_.phase.push_back(static_cast<std::uint8_t>(phase));
  }

  void leaf(std::int32_t c) {
    const auto& cell = forest_.cell(c);
    const int level = cell.level;
    const std::int64_t x = forest_.fine_x(c), y = forest_.fine_y(c), s = forest_.fine_size(c);
    QuadPoints q;
    const std::int64_t cx[4] = {x, x + s, x + s, x}, cy[4] = {y, y, y + s, y + s};
    const auto& corner_ids = nodes_.cell_corners[static_cast<std::size_t>(c)];
    for (int k = 0; k < 4; ++k) {
      q.id[k] = corner_ids[static_cast<std::size_t>(k)];
      q.shift[k] = shift_of(cx[k], cy[k]);
      q.key[k] = grid::key2(cx[k], cy[k]);
      q.p[k] = shifted(nodes_.position[static_cast<std::size_t>(q.id[k])], q.shift[k]);
      q.m[k] = nodes_.mask[static_cast<std::size_t>(q.id[k])];
    }
    // Hanging nodes: an edge neighbour refined beyond this leaf's level.
    static constexpr int kEdgeDir[4][2] = {{0, -1}, {1, 0}, {0, 1}, {-1, 0}};
    int hanging = 0;
    for (int e = 0; e < 4; ++e) {
      const std::int32_t n = forest_.find(level, cell.i + kEdgeDir[e][0], cell.j + kEdgeDir[e][1]);
      if (n >= 0 && !forest_.is_leaf(n)) hanging |= 1 << e;
    }
    const auto candidates = g_.candidates_of_root(g_.root_of(c));
    if (hanging) {
      closure(q, hanging, cx, cy, s);
      return;
    }
    const bool moved = nodes_.snapped[static_cast<std::size_t>(q.id[0])] | nodes_.snapped[static_cast<std::size_t>(q.id[1])] |
                       nodes_.snapped[static_cast<std::size_t>(q.id[2])] | nodes_.snapped[static_cast<std::size_t>(q.id[3])];
    const PhaseMask common = q.m[0] & q.m[1] & q.m[2] & q.m[3];
    if (!moved && std::popcount(common) == 1) {  // the common case: an untouched square
      const int phase = std::countr_zero(common);
      emit(q, 0, 1, 2, phase);
      emit(q, 0, 2, 3, phase);
      return;
    }
    split_quad(q, candidates, level);
  }

  void closure(QuadPoints& q, int hanging, const std::int64_t* cx, const std::int64_t* cy, std::int64_t s) {
    ++out_.hanging_cells;
    const PhaseMask common = q.m[0] & q.m[1] & q.m[2] & q.m[3];
    for (int k = 0; k < 4; ++k)
      CISAMR_CHECK(!nodes_.snapped[static_cast<std::size_t>(q.id[k])],
                   "subdivide2: a cell with hanging nodes has a moved corner (rule R4 broken)");
    CISAMR_CHECK(std::popcount(common) == 1, "subdivide2: a cell with hanging nodes is cut (rule R4 broken)");
    const int phase = std::countr_zero(common);
    for (int e = 0; e < 4; ++e)
      if ((hanging >> e) & 1) {
        const int a = e, b = (e + 1) % 4;
        const std::int64_t mx = (cx[a] + cx[b]) / 2, my = (cy[a] + cy[b]) / 2;
        q.id[templates2::mid(e)] = node(mx, my);
        q.shift[templates2::mid(e)] = shift_of(mx, my);
      }
    const auto& t = templates2::kHangingClosure[static_cast<std::size_t>(hanging)];
    bool needs_centre = false;
    for (int k = 0; k < t.count; ++k)
      for (int v : t.tri[static_cast<std::size_t>(k)]) needs_centre |= v == templates2::kCentre;
    if (needs_centre) {
      const grid::Lattice2& l = forest_.lattice();
      q.id[templates2::kCentre] = add_point({l.coordinate(0, cx[0] + s / 2), l.coordinate(1, cy[0] + s / 2)});
    }
    for (int k = 0; k < t.count; ++k) {
      const auto& tri = t.tri[static_cast<std::size_t>(k)];
      emit(q, tri[0], tri[1], tri[2], phase);
    }
  }

  struct SplitChoice {
    double worst = std::numeric_limits<double>::infinity();
    int kind = 0;  // 0: diagonal 0-2, 1: diagonal 1-3, 2: double diagonal
    Vec2 point{};
    PhaseMask point_mask = 0;
  };

  // The admissible split of lowest worst aspect ratio (worst = +inf when none is).
  SplitChoice best_split(QuadPoints& q, std::span<const std::int32_t> candidates) {
    SplitChoice best;
    best.worst = split_quality(q, templates2::kDiagonal02);
    const double d13 = split_quality(q, templates2::kDiagonal13);
    if (d13 < best.worst) best.worst = d13, best.kind = 1;
    // Double diagonal: a point of the interface on the diagonal the interface crosses.
    for (int diag = 0; diag < 2; ++diag) {
      const int a = diag == 0 ? 1 : 0, b = diag == 0 ? 3 : 2;  // the crossed diagonal
      if (q.m[a] & q.m[b]) continue;
      const bool a_first = q.key[a] < q.key[b];  // keys in the leaf's frame
      const Vec2 pa = q.p[a_first ? a : b], pb = q.p[a_first ? b : a];
      oracle_.crossings(pa, pb, candidates, crossings_);
      for (const auto& cr : crossings_) {
        q.p[templates2::kDiagonalPoint] = {pa[0] + cr.t * (pb[0] - pa[0]), pa[1] + cr.t * (pb[1] - pa[1])};
        q.m[templates2::kDiagonalPoint] = (PhaseMask{1} << cr.from_phase) | (PhaseMask{1} << cr.to_phase);
        const double quality = split_quality(q, templates2::kDoubleDiagonal);
        if (quality < best.worst) {
          best.worst = quality, best.kind = 2;
          best.point = q.p[templates2::kDiagonalPoint];
          best.point_mask = q.m[templates2::kDiagonalPoint];
        }
      }
    }
    return best;
  }

  void split_quad(QuadPoints& q, std::span<const std::int32_t> candidates, int level) {
    constexpr double kNone = std::numeric_limits<double>::infinity();
    const bool cut = (q.m[0] & q.m[1] & q.m[2] & q.m[3]) == 0;
    if (cut) ++out_.cut_quads;
    SplitChoice choice = best_split(q, candidates);
    if (!(choice.worst <= bound_)) {
      // A feature below this level's resolution (a tangency, a wedge sharper than the
      // quality bound allows, two interfaces in one cell): collapse it. Each corner also
      // counts as lying in the phases whose closure is within reach of it, reach growing
      // from alpha·h_l to 3·alpha·h_l until a split is admissible and within the bound;
      // the largest distance used is reported. Without such a split, the best admissible
      // one is kept (the uncollapsed split first: it is faithful to the geometry).
      const PhaseMask present = q.m[0] | q.m[1] | q.m[2] | q.m[3];
      double distance[4][64];
      for (int k = 0; k < 4; ++k)
        for (PhaseMask rest = present & ~q.m[k]; rest; rest &= rest - 1)
          distance[k][std::countr_zero(rest)] = oracle_.distance_to_phase(q.p[k], std::countr_zero(rest));
      const PhaseMask original[4] = {q.m[0], q.m[1], q.m[2], q.m[3]};
      SplitChoice collapsed;  // the first within the bound, else the first admissible
      PhaseMask collapsed_masks[4] = {};
      double deviation = 0;
      for (int step = 1; step <= 3 && !(collapsed.worst <= bound_); ++step) {
        const double reach = step * collapse_fraction_ * forest_.lattice().spacing(level);
        double step_deviation = 0;
        for (int k = 0; k < 4; ++k) {
          q.m[k] = original[k];
          for (PhaseMask rest = present & ~original[k]; rest; rest &= rest - 1) {
            const int phase = std::countr_zero(rest);
            if (distance[k][phase] <= reach) {
              q.m[k] |= PhaseMask{1} << phase;
              step_deviation = std::max(step_deviation, distance[k][phase]);
            }
          }
        }
        const SplitChoice attempt = best_split(q, candidates);
        if (attempt.worst <= bound_ || (attempt.worst < kNone && !(collapsed.worst < kNone))) {
          collapsed = attempt, deviation = step_deviation;
          std::copy(q.m, q.m + 4, collapsed_masks);
        }
      }
      if (collapsed.worst <= bound_ || (collapsed.worst < kNone && !(choice.worst < kNone))) {
        choice = collapsed;
        std::copy(collapsed_masks, collapsed_masks + 4, q.m);
        ++out_.collapsed;
        out_.max_collapse_deviation = std::max(out_.max_collapse_deviation, deviation);
        out_.max_collapse_ratio = std::max(out_.max_collapse_ratio, deviation / forest_.lattice().spacing(level));
        out_.min_collapse_level = std::min(out_.min_collapse_level, level);
        if (out_.collapsed_at.size() < 16)
          out_.collapsed_at.push_back({0.25 * (q.p[0][0] + q.p[1][0] + q.p[2][0] + q.p[3][0]),
                                       0.25 * (q.p[0][1] + q.p[1][1] + q.p[2][1] + q.p[3][1])});
      } else {
        std::copy(original, original + 4, q.m);
      }
    }
    if (!(choice.worst < std::numeric_limits<double>::infinity())) {
      ++out_.unresolved;
      if (out_.unresolved_at.size() < 16)
        out_.unresolved_at.push_back({0.25 * (q.p[0][0] + q.p[1][0] + q.p[2][0] + q.p[3][0]),
                                      0.25 * (q.p[0][1] + q.p[1][1] + q.p[2][1] + q.p[3][1])});
      emit_split(q, templates2::kDiagonal02, candidates, true);
      return;
    }
    if (choice.kind == 0) emit_split(q, templates2::kDiagonal02, candidates, false);
    else if (choice.kind == 1) emit_split(q, templates2::kDiagonal13, candidates, false);
    else {
      ++out_.double_diagonal;
      q.p[templates2::kDiagonalPoint] = choice.point;
      q.m[templates2::kDiagonalPoint] = choice.point_mask;
      q.id[templates2::kDiagonalPoint] = add_point(choice.point);
      emit_split(q, templates2::kDoubleDiagonal, candidates, false);
    }
  }

  template <std::size_t N>
  void emit_split(const QuadPoints& q, const std::array<Tri, N>& tris, std::span<const std::int32_t> candidates,
                  bool unresolved) {
    for (const Tri& t : tris) {
      PhaseMask common = q.m[t[0]] & q.m[t[1]] & q.m[t[2]];
      if (common == 0 && unresolved) common = ~PhaseMask{0};
      emit(q, t[0], t[1], t[2], triangle_phase(oracle_, candidates, common, q.p[t[0]], q.p[t[1]], q.p[t[2]]));
    }
  }
};

}  // namespace

Triangles2 subdivide2(const geometry::Oracle2& oracle, const samr::RefinedGrid2& grid,
                      const radapt::Nodes2& nodes, const grid::CellRange<2>& owned, double collapse_fraction,
                      Progress* progress, double bound) {
  return Subdivider(oracle, grid, nodes, collapse_fraction, bound).run(owned, progress);
}

}  // namespace cisamr::subdivide
