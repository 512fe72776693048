#pragma once
// Every 2D template, drawn once as tables (DESIGN.md §10).
//
// Reference quad, corners counter-clockwise from the lower-left one, edges after their
// first corner:
//
//      3 ---- e2 ---- 2
//      |              |
//      e3             e1
//      |              |
//      0 ---- e0 ---- 1
//
// Points of a quad are numbered 0-3 (corners), 4-7 (midpoint of edge 0-3, present only
// where a finer neighbour put a hanging node) and 8 (centre).
#include <array>
#include <cstdint>

namespace cisamr::subdivide::templates2 {

constexpr int kCentre = 8;
constexpr int mid(int edge) { return 4 + edge; }

struct Template {
  std::uint8_t count;                       // number of triangles
  std::array<std::array<std::uint8_t, 3>, 8> tri;  // counter-clockwise
};

// Closure of a square whose edges carry hanging nodes, by the 4-bit mask of those edges
// (bit e = edge e). The square is never deformed (rule R4). Worst aspect ratio over the
// table: 1.69 (the 1:2 right triangles); 3 or 4 hanging edges use a centre fan (1.207).
constexpr std::array<Template, 16> kHangingClosure = [] {
  std::array<Template, 16> t{};
  for (int m = 0; m < 16; ++m) {
    Template& tp = t[m];
    tp.count = 0;
    const auto add = [&](int a, int b, int c) {
      tp.tri[tp.count++] = {static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(b),
                            static_cast<std::uint8_t>(c)};
    };
    const int bits = ((m >> 0) & 1) + ((m >> 1) & 1) + ((m >> 2) & 1) + ((m >> 3) & 1);
    if (bits == 0) {
      add(0, 1, 2), add(0, 2, 3);
    } else if (bits == 1) {
      int e = 0;
      while (!((m >> e) & 1)) ++e;
      const int b = (e + 1) % 4, c = (e + 2) % 4, d = (e + 3) % 4, a = e;
      add(mid(e), b, c), add(mid(e), c, d), add(mid(e), d, a);
    } else if (bits == 2 && (m == 0b0101 || m == 0b1010)) {
      const int e = (m == 0b0101) ? 0 : 1;  // edges e and e+2
      const int a = e, b = (e + 1) % 4, c = (e + 2) % 4, d = (e + 3) % 4;
      add(a, mid(e), mid(e + 2)), add(a, mid(e + 2), d);
      add(mid(e), b, c), add(mid(e), c, mid(e + 2));
    } else if (bits == 2) {
      int e = 0;  // first of two adjacent edges e, e+1 (mod 4)
      while (!(((m >> e) & 1) && ((m >> ((e + 1) % 4)) & 1))) ++e;
      const int a = e, b = (e + 1) % 4, c = (e + 2) % 4, d = (e + 3) % 4;
      const int m1 = mid(e), m2 = mid((e + 1) % 4);
      add(m1, b, m2), add(m1, m2, d), add(m2, c, d), add(a, m1, d);
    } else {
      // Centre fan over the boundary ring.
      int ring[8], n = 0;
      for (int e = 0; e < 4; ++e) {
        ring[n++] = e;
        if ((m >> e) & 1) ring[n++] = mid(e);
      }
      for (int i = 0; i < n; ++i) add(kCentre, ring[i], ring[(i + 1) % n]);
    }
  }
  return t;
}();

// Splits of a quad without hanging nodes (corners possibly moved by r-adaptivity).
// kDiagonal02/13: two triangles along that diagonal. The double-diagonal split puts an
// extra point P (index 9) on the other diagonal: four triangles around P.
constexpr int kDiagonalPoint = 9;
constexpr std::array<std::array<std::uint8_t, 3>, 2> kDiagonal02 = {{{0, 1, 2}, {0, 2, 3}}};
constexpr std::array<std::array<std::uint8_t, 3>, 2> kDiagonal13 = {{{0, 1, 3}, {1, 2, 3}}};
constexpr std::array<std::array<std::uint8_t, 3>, 4> kDoubleDiagonal = {
    {{0, 1, kDiagonalPoint}, {1, 2, kDiagonalPoint}, {2, 3, kDiagonalPoint}, {3, 0, kDiagonalPoint}}};

}  // namespace cisamr::subdivide::templates2
