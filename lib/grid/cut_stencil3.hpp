#pragma once
// Sub-tetrahedralisation of a leaf tet cut by one interface (the stencils of the algorithm
// note §6.2). One function, used twice: the snapping guard (radapt3) evaluates every
// outcome it may allow with it, and subdivide3 emits the outcome that happens, so the
// tetrahedra the guard certified are exactly the ones written.
//
// Local points: 0-3 the leaf's vertices (tet::reference_points order), 4 + e the cut point
// of edge e (tet::kEdges), present where the signs of the edge's ends are strictly
// opposite. sign[i] is +1 or -1 for a vertex strictly inside one of the leaf's two phases,
// 0 for a vertex on their interface.
//
// Quads on the leaf's faces (shared with a neighbour, maybe on another partition) are
// split along the diagonal through their smallest point identity (key rule): both sides
// agree without talking. The interface quad of a (+,+,−,−) leaf is interior: it takes its
// shorter diagonal (the key rule's on a tie), which gives sub-tets as good as choosing by
// their aspect ratios at a fraction of the cost (measured on 80 random scenes). Prisms are
// split from a vertex lying on two of their lateral diagonals, which exists for every
// choice made here.
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>

#include "core/check.hpp"
#include "core/types.hpp"
#include "grid/tet_lattice.hpp"

namespace cisamr::grid::stencil3 {

// Identity of a point, the same on every leaf and partition that sees it: a lattice node
// is (key, key), a cut node (smaller key, larger key) of its edge.
struct PointId {
  LatticeKey3 a = 0, b = 0;
  friend bool operator<(const PointId& x, const PointId& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; }
  friend bool operator==(const PointId& x, const PointId& y) { return x.a == y.a && x.b == y.b; }
};

using LocalTet = std::array<std::uint8_t, 4>;
inline constexpr int kMaxSplitTets = 6;

// Entries beyond `count` are unspecified (left uninitialised: the snapping guard builds
// millions of these).
struct Split {
  int count = 0;
  std::array<LocalTet, kMaxSplitTets> tet;
  // Side of each tet: +1 (the phase of the + vertices) or -1.
  std::array<std::int8_t, kMaxSplitTets> side;
};

namespace detail {

using Diagonal = std::array<std::uint8_t, 2>;

inline bool on(const Diagonal& d, std::uint8_t v) { return d[0] == v || d[1] == v; }

// Key rule: the diagonal of quad q (cyclic) through its smallest identity.
inline Diagonal key_diagonal(const std::array<PointId, 10>& id, const std::array<std::uint8_t, 4>& q) {
  int smallest = 0;
  for (int i = 1; i < 4; ++i)
    if (id[q[static_cast<std::size_t>(i)]] < id[q[static_cast<std::size_t>(smallest)]]) smallest = i;
  return smallest % 2 == 0 ? Diagonal{q[0], q[2]} : Diagonal{q[1], q[3]};
}

struct Builder {
  Split out;
  void tet(std::uint8_t a, std::uint8_t b, std::uint8_t c, std::uint8_t d, int side) {
    out.tet[static_cast<std::size_t>(out.count)] = {a, b, c, d};
    out.side[static_cast<std::size_t>(out.count)] = static_cast<std::int8_t>(side);
    ++out.count;
  }
  void pyramid(std::uint8_t apex, const std::array<std::uint8_t, 4>& q, const Diagonal& d, int side) {
    if (on(d, q[0]))
      tet(apex, q[0], q[1], q[2], side), tet(apex, q[0], q[2], q[3], side);
    else
      tet(apex, q[1], q[2], q[3], side), tet(apex, q[1], q[3], q[0], side);
  }
  // Prism (p0,p1,p2)-(q0,q1,q2), lateral quad i = (p_i, p_i+1, q_i+1, q_i) split along d[i].
  // False when the three diagonals are cyclic (no vertex lies on two of them).
  bool prism(const std::array<std::uint8_t, 3>& p, const std::array<std::uint8_t, 3>& q,
             const std::array<Diagonal, 3>& d, int side) {
    for (int i = 0; i < 3; ++i) {
      const int before = (i + 2) % 3, after = (i + 1) % 3;
      const std::array<std::uint8_t, 4> opposite{p[static_cast<std::size_t>(after)], p[static_cast<std::size_t>(before)],
                                                 q[static_cast<std::size_t>(before)], q[static_cast<std::size_t>(after)]};
      const auto ui = static_cast<std::size_t>(i), ub = static_cast<std::size_t>(before),
                 ua = static_cast<std::size_t>(after);
      if (on(d[ui], p[ui]) && on(d[ub], p[ui])) {
        tet(p[ui], q[0], q[1], q[2], side);
        pyramid(p[ui], opposite, d[ua], side);
        return true;
      }
      if (on(d[ui], q[ui]) && on(d[ub], q[ui])) {
        tet(q[ui], p[0], p[1], p[2], side);
        pyramid(q[ui], opposite, d[ua], side);
        return true;
      }
    }
    return false;
  }
};

inline std::uint8_t cut(int a, int b) { return static_cast<std::uint8_t>(tet::midpoint(tet::edge_of(a, b))); }

// Orientation of a tet of local points (0-3 a tet's vertices, 4 + e the midpoint of its
// edge e) in the reference corner tet: bit ((a·10 + b)·10 + c)·10 + d set when (a, b, c, d)
// is negative there. The local points of any tet with integer vertices (edge midpoints
// standing for the cut points) are an affine image of the reference's, so a sub-tet's
// orientation there is this one times the tet's own: one table lookup per sub-tet instead of
// an integer determinant on points rebuilt per split (the snapping guard splits millions).
inline constexpr auto kNegativeInReference = [] {
  constexpr auto r = tet::reference_points(tet::Kind::corner);
  std::array<std::uint64_t, (10000 + 63) / 64> bits{};
  for (int a = 0; a < 10; ++a)
    for (int b = 0; b < 10; ++b)
      for (int c = 0; c < 10; ++c)
        for (int d = 0; d < 10; ++d)
          if (tet::orient(r[static_cast<std::size_t>(a)], r[static_cast<std::size_t>(b)], r[static_cast<std::size_t>(c)],
                          r[static_cast<std::size_t>(d)]) < 0) {
            const int at = ((a * 10 + b) * 10 + c) * 10 + d;
            bits[static_cast<std::size_t>(at / 64)] |= std::uint64_t{1} << (at % 64);
          }
  return bits;
}();

inline bool negative_in_reference(const LocalTet& t) {
  const int at = ((t[0] * 10 + t[1]) * 10 + t[2]) * 10 + t[3];
  return (kNegativeInReference[static_cast<std::size_t>(at / 64)] >> (at % 64)) & 1;
}

inline bool flat_in_reference(const LocalTet& t) {
  constexpr auto r = tet::reference_points(tet::Kind::corner);
  return tet::orient(r[t[0]], r[t[1]], r[t[2]], r[t[3]]) == 0;
}

// Orients every tet positively with respect to the undeformed tet `v` (cut points at edge
// midpoints): the combinatorial orientation, which a deformed tet keeps unless a sub-tet
// inverts (the guard refuses such outcomes).
inline void orient(const std::array<LatticePoint3, 4>& v, Split& s) {
  const std::int64_t own = tet::orient(v[0], v[1], v[2], v[3]);
  CISAMR_DEBUG_CHECK(own != 0, "cut_stencil3: degenerate tet");
  const bool flip = own < 0;
  for (int i = 0; i < s.count; ++i) {
    LocalTet& t = s.tet[static_cast<std::size_t>(i)];
    // The stencils are fixed tables (tests/grid3 splits every sign pattern) and this runs for
    // every combination the snapping guard tries: a debug check.
    CISAMR_DEBUG_CHECK(!flat_in_reference(t), "cut_stencil3: degenerate stencil tet");
    if (negative_in_reference(t) != flip) std::swap(t[2], t[3]);
  }
}

}  // namespace detail

// `lattice`: the tet's vertices as integer lattice points, whose orientation (the forest's
// are positive) the sub-tets take.
inline Split split(const std::array<LatticePoint3, 4>& lattice, const std::array<int, 4>& sign,
                   const std::array<PointId, 10>& id, const std::array<Vec3, 10>& p) {
  using detail::cut;
  std::array<std::uint8_t, 4> plus{}, minus{}, zero{};
  int np = 0, nm = 0, nz = 0;
  for (int i = 0; i < 4; ++i) {
    const auto v = static_cast<std::uint8_t>(i);
    if (sign[static_cast<std::size_t>(i)] > 0)
      plus[static_cast<std::size_t>(np++)] = v;
    else if (sign[static_cast<std::size_t>(i)] < 0)
      minus[static_cast<std::size_t>(nm++)] = v;
    else
      zero[static_cast<std::size_t>(nz++)] = v;
  }
  CISAMR_CHECK(np > 0 && nm > 0, "cut_stencil3: the leaf is not cut");
  // Name the smaller side "plus"; `side` maps back to the caller's signs.
  int plus_side = 1;
  if (np > nm || (np == nm && plus[0] > minus[0])) std::swap(plus, minus), std::swap(np, nm), plus_side = -1;
  const int minus_side = -plus_side;

  detail::Builder b;
  b.out.count = 0;
  if (np == 1 && nm == 1) {  // (0, 0, +, −): one cut edge
    const std::uint8_t a = plus[0], m = minus[0], c = cut(a, m);
    b.tet(zero[0], zero[1], a, c, plus_side);
    b.tet(zero[0], zero[1], c, m, minus_side);
  } else if (np == 1 && nm == 2) {  // (0, +, −, −): tet + pyramid on a face quad
    const std::uint8_t a = plus[0], z = zero[0], m1 = minus[0], m2 = minus[1];
    const std::uint8_t c1 = cut(a, m1), c2 = cut(a, m2);
    b.tet(a, c1, c2, z, plus_side);
    const std::array<std::uint8_t, 4> quad{c1, m1, m2, c2};
    b.pyramid(z, quad, detail::key_diagonal(id, quad), minus_side);
  } else if (np == 1 && nm == 3) {  // (+, −, −, −): tet + prism of face quads
    const std::uint8_t a = plus[0];
    const std::array<std::uint8_t, 3> c{cut(a, minus[0]), cut(a, minus[1]), cut(a, minus[2])};
    const std::array<std::uint8_t, 3> m{minus[0], minus[1], minus[2]};
    b.tet(a, c[0], c[1], c[2], plus_side);
    std::array<detail::Diagonal, 3> d{};
    for (std::size_t i = 0; i < 3; ++i) d[i] = detail::key_diagonal(id, {c[i], c[(i + 1) % 3], m[(i + 1) % 3], m[i]});
    CISAMR_CHECK(b.prism(c, m, d, minus_side), "cut_stencil3: cyclic key-rule prism");
  } else {  // (+, +, −, −): two prisms sharing the interface quad
    const std::uint8_t a = plus[0], bb = plus[1], c = minus[0], d = minus[1];
    const std::uint8_t ac = cut(a, c), ad = cut(a, d), bc = cut(bb, c), bd = cut(bb, d);
    const auto d_abc = detail::key_diagonal(id, {a, ac, bc, bb});
    const auto d_abd = detail::key_diagonal(id, {ad, a, bb, bd});
    const auto d_acd = detail::key_diagonal(id, {c, ac, ad, d});
    const auto d_bcd = detail::key_diagonal(id, {bc, c, d, bd});
    const std::array<std::uint8_t, 4> interface{ac, ad, bd, bc};
    const detail::Diagonal by_key = detail::key_diagonal(id, interface);
    const std::array<detail::Diagonal, 2> options{by_key, detail::on(by_key, ac) ? detail::Diagonal{ad, bc}
                                                                                 : detail::Diagonal{ac, bd}};
    // The shorter diagonal of the interface quad first (the key rule's on a tie), unless it
    // makes a prism cyclic.
    const auto length2 = [&](const detail::Diagonal& dg) {
      double l = 0;
      for (int k = 0; k < 3; ++k) l += (p[dg[0]][static_cast<std::size_t>(k)] - p[dg[1]][static_cast<std::size_t>(k)]) *
                                       (p[dg[0]][static_cast<std::size_t>(k)] - p[dg[1]][static_cast<std::size_t>(k)]);
      return l;
    };
    std::array<detail::Diagonal, 2> order = options;
    if (length2(options[1]) < length2(options[0])) std::swap(order[0], order[1]);
    Split best;
    for (const auto& di : order) {
      detail::Builder trial;
      if (!trial.prism({a, ac, ad}, {bb, bc, bd}, {d_abc, di, d_abd}, plus_side)) continue;
      if (!trial.prism({c, ac, bc}, {d, ad, bd}, {d_acd, di, d_bcd}, minus_side)) continue;
      detail::orient(lattice, trial.out);
      best = trial.out;
      break;
    }
    CISAMR_CHECK(best.count > 0, "cut_stencil3: no acyclic split of a (+,+,-,-) leaf");
    return best;
  }
  detail::orient(lattice, b.out);
  return b.out;
}

// What becomes of a tet whose vertices have final positions `pos` and closure masks `mask`:
//  - kept whole when the four masks share a phase (`common`; one bit, or several when every
//    vertex lies on one interface);
//  - split along one interface when exactly two phases occur and none is common: signs +1
//    (phase_plus only), -1 (phase_minus only), 0 (both); every edge with strictly opposite
//    signs needs its cut point, which `cut_of(e, point, id)` supplies (false: unknown, and
//    the outcome is reported as unsplittable);
//  - unsplittable otherwise (three or more phases meet in the tet).
// Points 4 + e exist only for strictly cut edges; other entries are unspecified.
struct Outcome {
  enum class Kind : std::uint8_t { kept, split, unsplittable };
  Kind kind = Kind::kept;
  PhaseMask common = 0;
  int phase_plus = -1, phase_minus = -1;
  Split split;
  std::array<Vec3, 10> p;        // 0-3 the vertices, 4 + e the cut point of edge e
  std::array<PointId, 10> id;
  std::array<int, 4> sign;
  int phase_of(int k) const { return split.side[static_cast<std::size_t>(k)] > 0 ? phase_plus : phase_minus; }
};

template <class CutOf>
Outcome outcome(const std::array<LatticePoint3, 4>& lattice, const std::array<Vec3, 4>& pos,
                const std::array<PhaseMask, 4>& mask, const std::array<PointId, 4>& vertex_id, CutOf&& cut_of) {
  Outcome o;
  for (int i = 0; i < 4; ++i) {
    o.p[static_cast<std::size_t>(i)] = pos[static_cast<std::size_t>(i)];
    o.id[static_cast<std::size_t>(i)] = vertex_id[static_cast<std::size_t>(i)];
  }
  o.common = mask[0] & mask[1] & mask[2] & mask[3];
  if (o.common != 0) return o;
  const PhaseMask all = mask[0] | mask[1] | mask[2] | mask[3];
  if (!two_bits(all)) {
    o.kind = Outcome::Kind::unsplittable;
    return o;
  }
  const PhaseMask plus = all & (~all + 1), minus = all & ~plus;
  o.phase_plus = std::countr_zero(plus);
  o.phase_minus = std::countr_zero(minus);
  for (int i = 0; i < 4; ++i) {
    const PhaseMask m = mask[static_cast<std::size_t>(i)];
    o.sign[static_cast<std::size_t>(i)] = (m & plus) && (m & minus) ? 0 : (m & plus) ? 1 : -1;
  }
  for (int e = 0; e < 6; ++e) {
    const auto i = static_cast<std::size_t>(tet::kEdges[e][0]), j = static_cast<std::size_t>(tet::kEdges[e][1]);
    if (o.sign[i] * o.sign[j] >= 0) continue;
    const auto m = static_cast<std::size_t>(tet::midpoint(e));
    if (!cut_of(e, o.p[m], o.id[m])) {
      o.kind = Outcome::Kind::unsplittable;
      return o;
    }
  }
  o.kind = Outcome::Kind::split;
  o.split = split(lattice, o.sign, o.id, o.p);
  return o;
}

}  // namespace cisamr::grid::stencil3
