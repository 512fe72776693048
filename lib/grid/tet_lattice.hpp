#pragma once
// The 3D lattice and its tetrahedral honeycomb (lib/grid/README.md, 3D part).
//
// Nodes have integer coordinates (X, Y, Z) on the finest lattice of the whole domain,
// (2^Lmax / h)·(x − x_min) (DESIGN.md §4). The key packs them in 64 bits, 21 bits per
// axis, x-major, so the numeric order of keys is the lexicographic order of (X, Y, Z):
// "the smallest key" means the same node on every partition.
//
// Honeycomb of level l (cubes of size h·2^-l, integer coordinates at that level): the cube
// with min corner (i, j, k) has local corners b = bx + 2·by + 4·bz; a corner is *even*
// when i+j+k+bx+by+bz is even. Its five tets are the regular tet R (the 4 even corners,
// edge √2·h_l) and, for each odd corner o, the corner tet C_o = (o, o⊕1, o⊕2, o⊕4)
// (trirectangular, right angle at o, legs h_l). Every cube-face diagonal joins two even
// corners, so neighbouring cubes agree on their shared faces. Local tet numbering in a
// cube: 0 = R, 1..4 = the corner tets of the odd corners in increasing b.
//
// Refinement (nested honeycomb): a corner tet has 7 children (1 regular + 6 corner), a
// regular tet 12 (4 regular + 8 corner around the cube centre); every child is a tet of
// the level-(l+1) honeycomb, so shapes and parity are the same at every level.
#include <array>
#include <cstdint>
#include <string>

#include "core/error.hpp"
#include "grid/lattice.hpp"

namespace cisamr::grid {

using Lattice3 = Lattice<3>;

// A point of an integer lattice (finest lattice, or one level's lattice, as stated).
using LatticePoint3 = std::array<std::int64_t, 3>;

// ---------------------------------------------------------------------------------------
// Keys
// ---------------------------------------------------------------------------------------

using LatticeKey3 = std::uint64_t;  // (X << 42) | (Y << 21) | Z
inline constexpr int kKey3Bits = 21;
inline constexpr std::int64_t kKey3MaxCoordinate = (std::int64_t{1} << kKey3Bits) - 1;

constexpr LatticeKey3 key3(std::int64_t x, std::int64_t y, std::int64_t z) {
  return (static_cast<LatticeKey3>(x) << (2 * kKey3Bits)) | (static_cast<LatticeKey3>(y) << kKey3Bits) |
         static_cast<LatticeKey3>(z);
}
constexpr LatticeKey3 key3(const LatticePoint3& p) { return key3(p[0], p[1], p[2]); }
constexpr LatticePoint3 key3_point(LatticeKey3 k) {
  constexpr LatticeKey3 mask = (LatticeKey3{1} << kKey3Bits) - 1;
  return {static_cast<std::int64_t>(k >> (2 * kKey3Bits)), static_cast<std::int64_t>((k >> kKey3Bits) & mask),
          static_cast<std::int64_t>(k & mask)};
}
// Key of the midpoint of the segment a-b; both ends must have even coordinate sums per
// axis (true for the vertices of any tet coarser than the finest level).
constexpr LatticeKey3 midpoint_key3(LatticeKey3 a, LatticeKey3 b) {
  const LatticePoint3 p = key3_point(a), q = key3_point(b);
  return key3((p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2);
}

// Wide keys for lattices beyond 2^21 fine units per axis: 42 bits per axis, same order.
__extension__ using WideLatticeKey3 = unsigned __int128;
inline constexpr int kWideKey3Bits = 42;
constexpr WideLatticeKey3 wide_key3(std::int64_t x, std::int64_t y, std::int64_t z) {
  return (static_cast<WideLatticeKey3>(x) << (2 * kWideKey3Bits)) |
         (static_cast<WideLatticeKey3>(y) << kWideKey3Bits) | static_cast<WideLatticeKey3>(z);
}

// Fine-lattice units per axis of the whole domain (nodes run from 0 to this, inclusive).
inline std::int64_t fine_extent(const Lattice3& lattice, int axis) {
  return lattice.coarse_cells[axis] << lattice.max_level;
}
// Does every node of the domain fit the 64-bit key?
inline bool fits_key3(const Lattice3& lattice) {
  if (lattice.max_level < 0 || lattice.max_level > kKey3Bits) return false;
  for (int d = 0; d < 3; ++d)
    if (lattice.coarse_cells[d] < 0 || lattice.coarse_cells[d] > (kKey3MaxCoordinate >> lattice.max_level))
      return false;
  return true;
}
// Throws MeshingError naming the cell counts and levels when the 64-bit key cannot hold
// the lattice.
inline void require_key3(const Lattice3& lattice) {
  if (fits_key3(lattice)) return;
  throw MeshingError("domain too large for the 64-bit lattice key: " + std::to_string(lattice.coarse_cells[0]) +
                     "x" + std::to_string(lattice.coarse_cells[1]) + "x" + std::to_string(lattice.coarse_cells[2]) +
                     " cells × 2^" + std::to_string(lattice.max_level) + " levels exceeds 2^21 - 1 fine units per " +
                     "axis; use a larger h, fewer levels or the wide key");
}

// ---------------------------------------------------------------------------------------
// Reference tetrahedron numbering (shared by the refinement and closure templates)
// ---------------------------------------------------------------------------------------
//
// Points of a tet: 0-3 its vertices (positively oriented; for a corner tet vertex 0 is the
// right-angle apex), 4-9 the midpoints of edges 0-5, 10 the centroid (for a regular tet:
// the cube centre).
namespace tet {

inline constexpr int kCentroid = 10;
inline constexpr std::array<std::array<std::uint8_t, 2>, 6> kEdges = {
    {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};
constexpr int midpoint(int edge) { return 4 + edge; }
constexpr int edge_of(int a, int b) {
  for (int e = 0; e < 6; ++e)
    if ((kEdges[e][0] == a && kEdges[e][1] == b) || (kEdges[e][0] == b && kEdges[e][1] == a)) return e;
  return -1;
}
// Face f is opposite vertex f, listed counter-clockwise seen from outside.
inline constexpr std::array<std::array<std::uint8_t, 3>, 4> kFaces = {{{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}};
// Edges of face f (the edge opposite each face vertex, in kFaces order).
inline constexpr std::array<std::array<std::uint8_t, 3>, 4> kFaceEdges = [] {
  std::array<std::array<std::uint8_t, 3>, 4> t{};
  for (int f = 0; f < 4; ++f)
    for (int i = 0; i < 3; ++i)
      t[f][i] = static_cast<std::uint8_t>(edge_of(kFaces[f][(i + 1) % 3], kFaces[f][(i + 2) % 3]));
  return t;
}();

enum class Kind : std::uint8_t { regular = 0, corner = 1 };

// Reference coordinates, scaled to integers (corner tet: legs 4 along x, y, z; regular
// tet: the even corners of the cube [0,2]^3), every point 0-10 included.
constexpr std::array<std::array<std::int64_t, 3>, 11> reference_points(Kind kind) {
  std::array<std::array<std::int64_t, 3>, 11> p{};
  if (kind == Kind::corner)
    p[0] = {0, 0, 0}, p[1] = {4, 0, 0}, p[2] = {0, 4, 0}, p[3] = {0, 0, 4};
  else
    p[0] = {0, 0, 0}, p[1] = {2, 2, 0}, p[2] = {0, 2, 2}, p[3] = {2, 0, 2};
  for (int e = 0; e < 6; ++e)
    for (int d = 0; d < 3; ++d) p[midpoint(e)][d] = (p[kEdges[e][0]][d] + p[kEdges[e][1]][d]) / 2;
  for (int d = 0; d < 3; ++d) p[kCentroid][d] = (p[0][d] + p[1][d] + p[2][d] + p[3][d]) / 4;
  return p;
}

// Six times the signed volume of (a, b, c, d), exact on integer points.
constexpr std::int64_t orient(const std::array<std::int64_t, 3>& a, const std::array<std::int64_t, 3>& b,
                              const std::array<std::int64_t, 3>& c, const std::array<std::int64_t, 3>& d) {
  const std::int64_t u0 = b[0] - a[0], u1 = b[1] - a[1], u2 = b[2] - a[2];
  const std::int64_t v0 = c[0] - a[0], v1 = c[1] - a[1], v2 = c[2] - a[2];
  const std::int64_t w0 = d[0] - a[0], w1 = d[1] - a[1], w2 = d[2] - a[2];
  return u0 * (v1 * w2 - v2 * w1) - u1 * (v0 * w2 - v2 * w0) + u2 * (v0 * w1 - v1 * w0);
}

// Refinement templates in the points of the parent, each child positively oriented.
// Corner tet (o; a, b, c) → 7: the regular tet (o, m_ab, m_ac, m_bc) and, per leg x with
// the other legs y, z, the corner tets (m_ox; o, m_xy, m_xz) and (m_ox; x, m_xy, m_xz).
// Regular tet → 12: (e_i, m_ij, m_ik, m_il) per vertex, and 8 corner tets around the
// centre with one cube-face centre per axis (opposite edges of R carry the two face
// centres of one axis: edges 0/5, 1/4, 2/3).
using ChildList = std::array<std::uint8_t, 4>;
constexpr ChildList oriented(Kind kind, ChildList t) {
  const auto p = reference_points(kind);
  if (orient(p[t[0]], p[t[1]], p[t[2]], p[t[3]]) < 0) {
    const std::uint8_t s = t[2];
    t[2] = t[3], t[3] = s;
  }
  return t;
}
inline constexpr std::array<ChildList, 7> kCornerChildren = [] {
  std::array<ChildList, 7> c{};
  c[0] = oriented(Kind::corner, {0, 7, 8, 9});
  int n = 1;
  for (int x = 1; x <= 3; ++x) {
    const int y = x == 1 ? 2 : 1, z = x == 3 ? 2 : 3;
    const auto m_ox = static_cast<std::uint8_t>(midpoint(edge_of(0, x)));
    const auto m_xy = static_cast<std::uint8_t>(midpoint(edge_of(x, y)));
    const auto m_xz = static_cast<std::uint8_t>(midpoint(edge_of(x, z)));
    c[n++] = oriented(Kind::corner, {m_ox, 0, m_xy, m_xz});
    c[n++] = oriented(Kind::corner, {m_ox, static_cast<std::uint8_t>(x), m_xy, m_xz});
  }
  return c;
}();
inline constexpr std::array<ChildList, 12> kRegularChildren = [] {
  std::array<ChildList, 12> c{};
  int n = 0;
  for (int v = 0; v < 4; ++v) {
    ChildList t{static_cast<std::uint8_t>(v), 0, 0, 0};
    int k = 1;
    for (int w = 0; w < 4; ++w)
      if (w != v) t[k++] = static_cast<std::uint8_t>(midpoint(edge_of(v, w)));
    c[n++] = oriented(Kind::regular, t);
  }
  for (int s = 0; s < 8; ++s)
    c[n++] = oriented(Kind::regular, {kCentroid, static_cast<std::uint8_t>(midpoint((s & 1) ? 5 : 0)),
                                      static_cast<std::uint8_t>(midpoint((s & 2) ? 4 : 1)),
                                      static_cast<std::uint8_t>(midpoint((s & 4) ? 3 : 2))});
  return c;
}();
constexpr int child_count(Kind kind) { return kind == Kind::corner ? 7 : 12; }

}  // namespace tet

// ---------------------------------------------------------------------------------------
// The honeycomb of one level
// ---------------------------------------------------------------------------------------

// A tet of the level-l honeycomb: its cube (min corner, level-l coordinates) and its local
// index in that cube (0 = R, 1..4 = corner tets).
struct TetCode {
  std::array<std::int64_t, 3> cube{};
  std::uint8_t local = 0;
  friend constexpr bool operator==(const TetCode&, const TetCode&) = default;
};

constexpr int cube_parity(const std::array<std::int64_t, 3>& cube) {
  return static_cast<int>((cube[0] + cube[1] + cube[2]) & 1);
}
constexpr tet::Kind kind_of_local(int local) { return local == 0 ? tet::Kind::regular : tet::Kind::corner; }

// kCubeTets[parity][local]: the local corners b of each tet of a cube whose min corner has
// coordinate-sum parity `parity`, positively oriented (corner tets: apex first).
inline constexpr std::array<std::array<std::array<std::uint8_t, 4>, 5>, 2> kCubeTets = [] {
  std::array<std::array<std::array<std::uint8_t, 4>, 5>, 2> t{};
  const auto corner = [](int b) {
    return std::array<std::int64_t, 3>{b & 1, (b >> 1) & 1, (b >> 2) & 1};
  };
  const auto fix = [&](std::array<std::uint8_t, 4>& v) {
    if (tet::orient(corner(v[0]), corner(v[1]), corner(v[2]), corner(v[3])) < 0) {
      const std::uint8_t s = v[2];
      v[2] = v[3], v[3] = s;
    }
  };
  for (int parity = 0; parity < 2; ++parity) {
    int even = 0, local = 1;
    for (int b = 0; b < 8; ++b) {
      const int bits = (b & 1) + ((b >> 1) & 1) + ((b >> 2) & 1);
      if ((parity + bits) % 2 == 0) {
        t[parity][0][even++] = static_cast<std::uint8_t>(b);
      } else {
        t[parity][local] = {static_cast<std::uint8_t>(b), static_cast<std::uint8_t>(b ^ 1),
                            static_cast<std::uint8_t>(b ^ 2), static_cast<std::uint8_t>(b ^ 4)};
        fix(t[parity][local]);
        ++local;
      }
    }
    fix(t[parity][0]);
  }
  return t;
}();

// Vertices of a honeycomb tet in its level's coordinates, positively oriented.
constexpr std::array<LatticePoint3, 4> tet_vertices(const TetCode& code) {
  std::array<LatticePoint3, 4> v{};
  const auto& corners = kCubeTets[static_cast<std::size_t>(cube_parity(code.cube))][code.local];
  for (int i = 0; i < 4; ++i)
    v[i] = {code.cube[0] + (corners[i] & 1), code.cube[1] + ((corners[i] >> 1) & 1),
            code.cube[2] + ((corners[i] >> 2) & 1)};
  return v;
}

// The honeycomb tet whose interior holds the point p / 2^shift (level coordinates). The
// point must not lie on a face of the honeycomb (callers pass interior points such as
// scaled centroids).
constexpr TetCode locate(const LatticePoint3& p, int shift) {
  TetCode code;
  std::array<std::int64_t, 3> u{};
  for (int d = 0; d < 3; ++d) {
    code.cube[d] = p[d] >> shift;  // floor, also below zero
    u[d] = p[d] - (code.cube[d] << shift);
  }
  const std::int64_t side = std::int64_t{1} << shift;
  const int parity = cube_parity(code.cube);
  // Corner tet of the odd corner o: L1 distance to o below one cube side.
  for (int local = 1; local <= 4; ++local) {
    const int o = kCubeTets[static_cast<std::size_t>(parity)][local][0];
    std::int64_t l1 = 0;
    for (int d = 0; d < 3; ++d) {
      const std::int64_t delta = u[d] - (((o >> d) & 1) ? side : 0);
      l1 += delta < 0 ? -delta : delta;
    }
    if (l1 < side) {
      code.local = static_cast<std::uint8_t>(local);
      return code;
    }
  }
  code.local = 0;
  return code;
}

// Sum of the four vertices: 4 × the centroid, in level coordinates.
constexpr LatticePoint3 centroid4(const TetCode& code) {
  const auto v = tet_vertices(code);
  return {v[0][0] + v[1][0] + v[2][0] + v[3][0], v[0][1] + v[1][1] + v[2][1] + v[3][1],
          v[0][2] + v[1][2] + v[2][2] + v[3][2]};
}

// The tet of the same level across face f (opposite vertex f). The point
// F + (F − v_f)/8, F the face centroid, lies inside the neighbour for both tet shapes.
constexpr TetCode face_neighbour(const TetCode& code, int face) {
  const auto v = tet_vertices(code);
  LatticePoint3 p{};
  for (int d = 0; d < 3; ++d) {
    std::int64_t s = 0;
    for (int i = 0; i < 4; ++i)
      if (i != face) s += v[i][d];
    p[d] = 3 * s - v[face][d];  // 8 × (F + (F − v_f)/8)
  }
  return locate(p, 3);
}

// Children of a honeycomb tet: the level-(l+1) codes, in template order.
constexpr int children_codes(const TetCode& parent, std::array<TetCode, 12>& out) {
  const tet::Kind kind = kind_of_local(parent.local);
  const auto v = tet_vertices(parent);
  std::array<LatticePoint3, 11> p{};
  for (int i = 0; i < 4; ++i)
    for (int d = 0; d < 3; ++d) p[i][d] = 2 * v[i][d];
  for (int e = 0; e < 6; ++e)
    for (int d = 0; d < 3; ++d)
      p[tet::midpoint(e)][d] = (p[tet::kEdges[e][0]][d] + p[tet::kEdges[e][1]][d]) / 2;
  if (kind == tet::Kind::regular)  // the cube centre, a lattice point of level l+1
    for (int d = 0; d < 3; ++d) p[tet::kCentroid][d] = (p[0][d] + p[1][d] + p[2][d] + p[3][d]) / 4;
  const int n = tet::child_count(kind);
  for (int c = 0; c < n; ++c) {
    const auto& t = kind == tet::Kind::corner ? tet::kCornerChildren[c] : tet::kRegularChildren[c];
    LatticePoint3 s{};
    for (int d = 0; d < 3; ++d) s[d] = p[t[0]][d] + p[t[1]][d] + p[t[2]][d] + p[t[3]][d];
    out[c] = locate(s, 2);
  }
  return n;
}

}  // namespace cisamr::grid
