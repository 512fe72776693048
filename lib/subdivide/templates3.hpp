#pragma once
// 3D closure templates (lib/subdivide/README.md, 3D part): tetrahedra of the nested honeycomb
// (grid/tet_lattice.hpp) whose edges carry hanging midpoints are split into sub-tets that
// match, face by face, whatever the neighbour does.
//
// Points of a tet are numbered as in grid::tet: 0-3 vertices (corner tet: apex 0), 4-9
// the midpoints of edges 0-5 ({0,1},{0,2},{0,3},{1,2},{1,3},{2,3}), 10 the centroid
// (the closure's Steiner point, see Closure::steiner). Faces: f opposite vertex f.
//
// Face rules (each depends only on the face's own midpoints and lattice keys, so both
// tets of a face agree, on every partition):
//   0 midpoints  the face itself;
//   1 midpoint   bisected through the midpoint;
//   2 midpoints  corner triangle at the vertex S shared by the two split edges, and the
//                remaining quad (m_SP, P, Q, m_SQ) split along the diagonal through the
//                quad vertex with the smallest lattice key (the *key rule*);
//   3 midpoints  the pattern of a refined neighbour: red split (4 triangles) on
//                equilateral faces, fan from the hypotenuse midpoint on right-isosceles
//                faces (the faces through a corner tet's apex, lying on cube faces).
// Interior: for every (kind, edge mask, quad diagonals) the triangulation with the lowest
// worst aspect ratio among all triangulations that use only the tet's points, found by an
// exhaustive search once (first use); with one interior Steiner point (the centroid or a
// point of kSteinerCandidates) when that is strictly better or no Steiner-free
// triangulation exists (Schönhardt-like prisms of cyclic quad diagonals).
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <vector>

#include "grid/tet_lattice.hpp"
#include "mesh/metrics.hpp"

namespace cisamr::subdivide::templates3 {

namespace tet = grid::tet;
using Kind = grid::tet::Kind;
inline constexpr int kSteiner = tet::kCentroid;  // point 10 of a closure: its Steiner point
inline constexpr int kMaxClosureTets = 16;

using Triangle = std::array<std::uint8_t, 3>;
using Tetra = std::array<std::uint8_t, 4>;

constexpr bool has_midpoint(unsigned edge_mask, int edge) { return ((edge_mask >> edge) & 1u) != 0; }

// A face of a corner tet through its apex lies on a cube face (right isosceles); every
// other face is equilateral.
constexpr bool is_right_face(Kind kind, int face) { return kind == Kind::corner && face != 0; }

// Number of midpoints on face f.
constexpr int face_midpoints(unsigned edge_mask, int face) {
  int n = 0;
  for (int i = 0; i < 3; ++i) n += has_midpoint(edge_mask, tet::kFaceEdges[face][i]) ? 1 : 0;
  return n;
}
// Faces with exactly two midpoints, whose quad needs the key rule (bit f = face f).
constexpr unsigned quad_faces(unsigned edge_mask) {
  unsigned m = 0;
  for (int f = 0; f < 4; ++f)
    if (face_midpoints(edge_mask, f) == 2) m |= 1u << f;
  return m;
}

// The quad of a face with two midpoints, counter-clockwise seen from outside:
// (m_SP, P, Q, m_SQ), S the vertex shared by the split edges. Diagonal 0 joins quad
// vertices 0-2 (m_SP-Q), diagonal 1 joins 1-3 (P-m_SQ).
struct FaceQuad {
  std::uint8_t s, p, q, m_sp, m_sq;
};
constexpr FaceQuad face_quad(unsigned edge_mask, int face) {
  const auto& v = tet::kFaces[face];
  for (int i = 0; i < 3; ++i)
    if (!has_midpoint(edge_mask, tet::kFaceEdges[face][i])) {
      // Edge opposite v[i] is whole: S = v[i].
      const std::uint8_t s = v[i], p = v[(i + 1) % 3], q = v[(i + 2) % 3];
      return {s, p, q, static_cast<std::uint8_t>(tet::midpoint(tet::edge_of(s, p))),
              static_cast<std::uint8_t>(tet::midpoint(tet::edge_of(s, q)))};
    }
  return {};
}

struct FacePattern {
  std::uint8_t count = 0;
  std::array<Triangle, 4> tri{};  // counter-clockwise seen from outside the tet
};

// The triangulation of face f prescribed by the face rules. `diagonal` (0 or 1) is used
// for faces with two midpoints only.
constexpr FacePattern face_pattern(Kind kind, unsigned edge_mask, int face, int diagonal) {
  FacePattern fp;
  const auto add = [&](int a, int b, int c) {
    fp.tri[fp.count++] = {static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(b), static_cast<std::uint8_t>(c)};
  };
  const auto& v = tet::kFaces[face];
  const auto mid = [](int a, int b) { return tet::midpoint(tet::edge_of(a, b)); };
  const int n = face_midpoints(edge_mask, face);
  if (n == 0) {
    add(v[0], v[1], v[2]);
  } else if (n == 1) {
    for (int i = 0; i < 3; ++i)
      if (has_midpoint(edge_mask, tet::kFaceEdges[face][i])) {
        const int x = v[i], y = v[(i + 1) % 3], z = v[(i + 2) % 3], m = mid(y, z);
        add(x, y, m), add(x, m, z);
      }
  } else if (n == 2) {
    const FaceQuad q = face_quad(edge_mask, face);
    add(q.s, q.m_sp, q.m_sq);
    if (diagonal == 0)
      add(q.m_sp, q.p, q.q), add(q.m_sp, q.q, q.m_sq);
    else
      add(q.m_sp, q.p, q.m_sq), add(q.p, q.q, q.m_sq);
  } else if (is_right_face(kind, face)) {
    // Fan from the hypotenuse midpoint; the apex (vertex 0) is the right-angle corner.
    int i0 = 0;
    while (v[i0] != 0) ++i0;
    const int o = v[i0], y = v[(i0 + 1) % 3], z = v[(i0 + 2) % 3];
    const int hyp = mid(y, z), my = mid(o, y), mz = mid(o, z);
    add(hyp, o, my), add(hyp, my, y), add(hyp, z, mz), add(hyp, mz, o);
  } else {
    const int a = v[0], b = v[1], c = v[2];
    add(a, mid(a, b), mid(c, a)), add(b, mid(b, c), mid(a, b)), add(c, mid(c, a), mid(b, c));
    add(mid(a, b), mid(b, c), mid(c, a));
  }
  return fp;
}

// The quad diagonals chosen by the key rule, as a variant index (bit f = diagonal of face
// f; 0 for faces without a quad). `keys` are the lattice keys of points 0-9 (those of
// absent midpoints are ignored).
template <class Key>
constexpr unsigned quad_variant(unsigned edge_mask, const std::array<Key, 10>& keys) {
  unsigned variant = 0;
  const unsigned quads = quad_faces(edge_mask);
  for (int f = 0; f < 4; ++f) {
    if (!((quads >> f) & 1u)) continue;
    const FaceQuad q = face_quad(edge_mask, f);
    const Key k0 = std::min(keys[q.m_sp], keys[q.q]), k1 = std::min(keys[q.p], keys[q.m_sq]);
    if (k1 < k0) variant |= 1u << f;
  }
  return variant;
}

// One closure: sub-tets in the points of the tet, positively oriented. Point 10, when
// used, is the Steiner point Σ steiner[i]·vertex[i] / kSteinerDenominator.
inline constexpr int kSteinerDenominator = 16;
using SteinerWeights = std::array<std::uint8_t, 4>;
struct Closure {
  std::uint8_t count = 0;
  bool uses_steiner = false;
  SteinerWeights steiner{};  // all zero when unused
  double max_aspect = 0;     // on the undeformed honeycomb tet
  std::array<Tetra, kMaxClosureTets> tet{};
};

// Steiner positions tried, in order (ties keep the earlier one): the centroid, then points
// nearer the apex of a corner tet. The shortlist holds every winner of a search over all
// interior points with weights in sixteenths (README.md), so it gives the same table.
inline constexpr std::array<SteinerWeights, 13> kSteinerCandidates = {{{4, 4, 4, 4},
                                                                       {5, 3, 3, 5}, {5, 3, 5, 3}, {5, 5, 3, 3},
                                                                       {5, 4, 4, 3}, {5, 4, 3, 4}, {5, 3, 4, 4},
                                                                       {5, 4, 5, 2}, {5, 4, 2, 5}, {5, 2, 4, 5},
                                                                       {5, 5, 4, 2}, {5, 2, 5, 4}, {5, 5, 2, 4}}};

// Where the Steiner point of a closure goes, for the tet's actual (maybe moved) vertices.
inline Vec3 steiner_position(const Closure& c, const std::array<Vec3, 4>& vertices) {
  Vec3 x{0, 0, 0};
  for (int i = 0; i < 4; ++i)
    for (int d = 0; d < 3; ++d) x[d] += c.steiner[i] * vertices[i][d];
  for (int d = 0; d < 3; ++d) x[d] /= kSteinerDenominator;
  return x;
}

namespace detail {

using IPoint = std::array<std::int64_t, 3>;

inline double reference_aspect(const std::array<IPoint, 11>& p, const Tetra& t) {
  const auto v = [&](int i) {
    return Vec3{static_cast<double>(p[t[i]][0]), static_cast<double>(p[t[i]][1]), static_cast<double>(p[t[i]][2])};
  };
  return mesh::aspect_ratio(v(0), v(1), v(2), v(3));
}

// Canonical code of an oriented triangle: rotated so the smallest point comes first.
constexpr int triangle_code(int a, int b, int c) {
  if (b < a && b < c) return triangle_code(b, c, a);
  if (c < a && c < b) return triangle_code(c, a, b);
  return (a * 11 + b) * 11 + c;
}
constexpr int reversed_code(int code) {
  const int a = code / 121, b = (code / 11) % 11, c = code % 11;
  return triangle_code(a, c, b);
}

// Exhaustive search for the triangulation of one tet, boundary fixed, that minimises the
// worst aspect ratio (then the number of tets). Every open face (a face with a tet on
// one side only) is closed by trying each point as the apex of the tet on its empty
// side. A tet is admissible when it is positively oriented and holds no other point of
// the set in its closure. When no face is open, the tets form a 3-chain whose boundary is
// the tet's boundary triangulation; all being positive, they cover the tet exactly once,
// face to face: a conforming triangulation.
class ClosureSearch {
 public:
  ClosureSearch(const std::array<IPoint, 11>& points, unsigned point_set, const std::vector<Triangle>& boundary)
      : points_(points), point_set_(point_set) {
    for (int f = 0; f < 4; ++f) {
      face_points_[f] = 0;
      for (int i = 0; i < 3; ++i) face_points_[f] |= 1u << tet::kFaces[f][i];
      for (int i = 0; i < 3; ++i) face_points_[f] |= 1u << tet::midpoint(tet::kFaceEdges[f][i]);
    }
    total_volume_ = tet::orient(points_[0], points_[1], points_[2], points_[3]);
    for (const Triangle& t : boundary) {
      // The tet on the inner side of an outward face (a,b,c) is (p,a,b,c): the required
      // face is the triangle itself.
      open_.push_back(triangle_code(t[0], t[1], t[2]));
      boundary_codes_.push_back(triangle_code(t[0], t[1], t[2]));
    }
  }

  bool run(Closure& out) {
    best_ = 1e300;
    best_count_ = 1000;
    found_ = false;
    search(0.0);
    if (!found_) return false;
    out.count = static_cast<std::uint8_t>(best_tets_.size());
    out.max_aspect = best_;
    for (std::size_t i = 0; i < best_tets_.size(); ++i) out.tet[i] = best_tets_[i];
    return true;
  }

 private:
  std::array<IPoint, 11> points_;
  unsigned point_set_;
  std::array<unsigned, 4> face_points_{};
  std::int64_t total_volume_ = 0, volume_ = 0;
  std::vector<int> open_, closed_, boundary_codes_;
  std::vector<Tetra> tets_, best_tets_;
  double best_ = 0;
  std::size_t best_count_ = 0;
  bool found_ = false;
  mutable std::array<std::int8_t, 2048> empty_ = [] {
    std::array<std::int8_t, 2048> a{};
    a.fill(-1);
    return a;
  }();
  mutable std::array<double, 2048> aspect_{};

  bool on_boundary(int a, int b, int c) const {
    const unsigned s = (1u << a) | (1u << b) | (1u << c);
    for (unsigned f : face_points_)
      if ((s & f) == s) return true;
    return false;
  }
  // Positive, and no other point of the set in the closed tet (memoised per vertex set,
  // with the aspect ratio).
  bool admissible(const Tetra& t, double& aspect) const {
    if (tet::orient(points_[t[0]], points_[t[1]], points_[t[2]], points_[t[3]]) <= 0) return false;
    const unsigned bits = (1u << t[0]) | (1u << t[1]) | (1u << t[2]) | (1u << t[3]);
    if (empty_[bits] < 0) {
      empty_[bits] = empty(t) ? 1 : 0;
      aspect_[bits] = reference_aspect(points_, t);
    }
    aspect = aspect_[bits];
    return empty_[bits] == 1;
  }
  bool empty(const Tetra& t) const {
    for (int q = 0; q < 11; ++q) {
      if (!((point_set_ >> q) & 1u) || q == t[0] || q == t[1] || q == t[2] || q == t[3]) continue;
      bool inside = true;
      for (int i = 0; i < 4 && inside; ++i) {
        Tetra s = t;
        s[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(q);
        inside = tet::orient(points_[s[0]], points_[s[1]], points_[s[2]], points_[s[3]]) >= 0;
      }
      if (inside) return false;
    }
    return true;
  }
  static bool contains(const std::vector<int>& v, int x) { return std::find(v.begin(), v.end(), x) != v.end(); }
  static void erase(std::vector<int>& v, int x) { v.erase(std::find(v.begin(), v.end(), x)); }

  // Candidate apexes for the open face `code`, with their tets' aspect ratios.
  void candidates(int code, std::vector<std::pair<double, Tetra>>& out) const {
    out.clear();
    const int a = code / 121, b = (code / 11) % 11, c = code % 11;
    for (int p = 0; p < 11; ++p) {
      if (!((point_set_ >> p) & 1u) || p == a || p == b || p == c) continue;
      const Tetra t{static_cast<std::uint8_t>(p), static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(b),
                    static_cast<std::uint8_t>(c)};
      double aspect = 0;
      if (admissible(t, aspect)) out.emplace_back(aspect, t);
    }
    std::sort(out.begin(), out.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  }

  void search(double worst) {
    if (open_.empty()) {
      if (worst < best_ - 1e-9 || (worst <= best_ + 1e-9 && tets_.size() < best_count_)) {
        best_ = worst;
        best_count_ = tets_.size();
        best_tets_ = tets_;
        found_ = true;
      }
      return;
    }
    if (tets_.size() + 1 > static_cast<std::size_t>(kMaxClosureTets)) return;
    // Branch on the open face with the fewest candidates (ties: first in the list).
    std::vector<std::pair<double, Tetra>> cand, fewest;
    int chosen = -1;
    for (int code : open_) {
      candidates(code, cand);
      if (chosen < 0 || cand.size() < fewest.size()) chosen = code, fewest = cand;
      if (fewest.empty()) return;
    }
    for (const auto& [aspect, t] : fewest) {
      if (aspect > best_ + 1e-9) break;
      const std::int64_t vol = tet::orient(points_[t[0]], points_[t[1]], points_[t[2]], points_[t[3]]);
      if (volume_ + vol > total_volume_) continue;
      // Place t: close its faces that were open, open the others.
      std::vector<int> opened, closed;
      bool ok = true;
      const int faces[4] = {triangle_code(t[1], t[2], t[3]), triangle_code(t[0], t[3], t[2]),
                            triangle_code(t[0], t[1], t[3]), triangle_code(t[0], t[2], t[1])};
      for (int code : faces) {
        if (contains(open_, code)) {
          closed.push_back(code);
        } else {
          const int rev = reversed_code(code);
          const int a = code / 121, b = (code / 11) % 11, c = code % 11;
          if (contains(open_, rev) || contains(closed_, code) || contains(closed_, rev) || on_boundary(a, b, c) ||
              contains(opened, rev)) {
            ok = false;
            break;
          }
          opened.push_back(rev);
        }
      }
      if (!ok) continue;
      for (int code : closed) erase(open_, code), closed_.push_back(code);
      for (int code : opened) open_.push_back(code);
      tets_.push_back(t);
      volume_ += vol;
      search(std::max(worst, aspect));
      volume_ -= vol;
      tets_.pop_back();
      for (int code : opened) erase(open_, code);
      for (int code : closed) erase(closed_, code), open_.push_back(code);
    }
  }
};

inline std::vector<Triangle> boundary_of(Kind kind, unsigned edge_mask, unsigned variant) {
  std::vector<Triangle> b;
  for (int f = 0; f < 4; ++f) {
    const FacePattern fp = face_pattern(kind, edge_mask, f, static_cast<int>((variant >> f) & 1u));
    for (int i = 0; i < fp.count; ++i) b.push_back(fp.tri[i]);
  }
  return b;
}

// Reference points ×16 with point 10 at the Steiner position `w`.
inline std::array<IPoint, 11> points_with_steiner(Kind kind, const SteinerWeights& w) {
  std::array<IPoint, 11> p = tet::reference_points(kind);
  const std::array<IPoint, 11> ref = p;
  for (auto& q : p)
    for (auto& c : q) c *= kSteinerDenominator;
  for (int d = 0; d < 3; ++d) p[kSteiner][d] = w[0] * ref[0][d] + w[1] * ref[1][d] + w[2] * ref[2][d] + w[3] * ref[3][d];
  return p;
}

inline Closure centroid_star(Kind kind, unsigned edge_mask, unsigned variant) {
  Closure c;
  c.uses_steiner = true;
  c.steiner = kSteinerCandidates[0];
  const auto p = points_with_steiner(kind, c.steiner);
  for (const Triangle& t : boundary_of(kind, edge_mask, variant)) {
    c.tet[c.count] = {static_cast<std::uint8_t>(kSteiner), t[0], t[1], t[2]};
    c.max_aspect = std::max(c.max_aspect, reference_aspect(p, c.tet[c.count]));
    ++c.count;
  }
  return c;
}

// The Steiner-free optimum; the optimum with the centroid when that is strictly better
// (or the only one), and then the best of the other Steiner candidates.
inline Closure best_closure(Kind kind, unsigned edge_mask, unsigned variant) {
  unsigned points = 0xfu;
  for (int e = 0; e < 6; ++e)
    if (has_midpoint(edge_mask, e)) points |= 1u << tet::midpoint(e);
  const std::vector<Triangle> boundary = boundary_of(kind, edge_mask, variant);
  Closure plain, best;
  const bool have_plain = ClosureSearch(tet::reference_points(kind), points, boundary).run(plain);
  bool have_best = false;
  for (std::size_t i = 0; i < kSteinerCandidates.size(); ++i) {
    Closure c;
    if (!ClosureSearch(points_with_steiner(kind, kSteinerCandidates[i]), points | (1u << kSteiner), boundary).run(c))
      continue;
    if (!have_best || c.max_aspect < best.max_aspect - 1e-9) {
      best = c;
      best.uses_steiner = true;
      best.steiner = kSteinerCandidates[i];
      have_best = true;
    }
    if (i == 0 && have_plain && plain.max_aspect <= best.max_aspect + 1e-9) return plain;
  }
  if (have_plain && (!have_best || plain.max_aspect <= best.max_aspect + 1e-9)) return plain;
  return have_best ? best : centroid_star(kind, edge_mask, variant);
}

}  // namespace detail

// Index of a closure: kind, 6-bit edge mask (bit e: edge e carries a midpoint), 4-bit
// quad variant (quad_variant; bits of faces without a quad are ignored).
constexpr std::size_t closure_index(Kind kind, unsigned edge_mask, unsigned variant) {
  return (static_cast<std::size_t>(kind) * 64 + edge_mask) * 16 + (variant & quad_faces(edge_mask));
}

struct ClosureTables {
  std::array<Closure, 2 * 64 * 16> best{};  // the optimal closures (Steiner point if better)
  std::array<Closure, 2 * 64 * 16> star{};  // centroid stars (valid for any tet star-shaped from its centroid)
};

// The optimal closure of a tet of `kind` with midpoints on `edge_mask` and quad `variant`,
// searched the first time any caller asks for it and kept (the whole table, 478 searches,
// took 46 ms in every 3D process; a mesh uses a fraction of it). Deterministic, the same on
// every rank; thread-safe: an entry is published once, under a lock, and read after an
// acquire load.
inline const Closure& best_closure_on_first_use(Kind kind, unsigned edge_mask, unsigned variant) {
  static constexpr std::size_t kEntries = 2 * 64 * 16;
  static std::array<Closure, kEntries> cache{};
  static std::array<std::atomic<bool>, kEntries> ready{};
  static std::mutex searching;
  variant &= quad_faces(edge_mask);
  const std::size_t i = closure_index(kind, edge_mask, variant);
  if (!ready[i].load(std::memory_order_acquire)) {
    const std::lock_guard<std::mutex> lock(searching);
    if (!ready[i].load(std::memory_order_relaxed)) {
      cache[i] = detail::best_closure(kind, edge_mask, variant);
      ready[i].store(true, std::memory_order_release);
    }
  }
  return cache[i];
}

// Every entry at once (the tests); `best` from the same searches as closure() uses.
inline const ClosureTables& closure_tables() {
  static const ClosureTables tables = [] {
    ClosureTables t;
    for (int k = 0; k < 2; ++k)
      for (unsigned mask = 0; mask < 64; ++mask) {
        const unsigned quads = quad_faces(mask);
        for (unsigned variant = 0; variant < 16; ++variant) {
          if ((variant & ~quads) != 0) continue;
          const Kind kind = static_cast<Kind>(k);
          const std::size_t i = closure_index(kind, mask, variant);
          t.best[i] = best_closure_on_first_use(kind, mask, variant);
          t.star[i] = detail::centroid_star(kind, mask, variant);
        }
      }
    // Entries of ignored variant bits alias the canonical ones through closure_index.
    return t;
  }();
  return tables;
}

// The closure of a tet of `kind` whose edges in `edge_mask` carry midpoints; `keys` are
// the lattice keys of points 0-9 (vertices, then edge midpoints) for the key rule.
template <class Key>
inline const Closure& closure(Kind kind, unsigned edge_mask, const std::array<Key, 10>& keys) {
  return best_closure_on_first_use(kind, edge_mask, quad_variant(edge_mask, keys));
}

}  // namespace cisamr::subdivide::templates3
