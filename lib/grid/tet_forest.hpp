#pragma once
// A forest of tetrahedra over a range of coarse cubes: the 3D background grid (five tets
// per cube, tet_lattice.hpp) and its nested-honeycomb refinements. Tets live in one flat
// array; the 5 roots of coarse cube (ci, cj, ck) are consecutive (local 0..4), and the
// 7 (corner tet) or 12 (regular tet) children of a tet are consecutive, in the order of
// tet::kCornerChildren / tet::kRegularChildren. Every tet is a tet of its level's
// honeycomb, identified by its TetCode; everything here depends only on those codes
// (lattice keys), never on the order in which tets were refined.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/check.hpp"
#include "grid/tet_lattice.hpp"

namespace cisamr::grid {

class TetForest {
 public:
  struct Tet {
    std::int32_t first_child = -1;  // -1: leaf
    std::int32_t parent = -1;       // -1: root
    std::array<std::int32_t, 3> cube{};  // min corner of its cube, level coordinates
    std::uint8_t level = 0;
    std::uint8_t local = 0;  // 0: regular tet, 1..4: corner tets of the cube
  };

  // Throws MeshingError when the range is outside the domain or the lattice does not fit
  // the 64-bit key (require_key3). On a periodic axis the range may reach past either face
  // (a window that wraps; the whole circle once it spans the period): tets hold canonical
  // codes (cube coordinates in [0, N·2^level)), and every look-up takes any image.
  TetForest(const Lattice3& lattice, const CellRange<3>& range);

  const Lattice3& lattice() const { return lattice_; }
  const CellRange<3>& range() const { return range_; }
  std::size_t size() const { return tets_.size(); }
  const Tet& tet(std::int32_t t) const {
    CISAMR_DEBUG_CHECK(t >= 0 && static_cast<std::size_t>(t) < tets_.size(), "TetForest: tet index out of range");
    return tets_[static_cast<std::size_t>(t)];
  }
  bool is_leaf(std::int32_t t) const { return tets_[static_cast<std::size_t>(t)].first_child < 0; }
  // Global index of the coarse cube holding tet t.
  std::array<std::int64_t, 3> coarse_cell(std::int32_t t) const {
    const Tet& x = tet(t);
    return {x.cube[0] >> x.level, x.cube[1] >> x.level, x.cube[2] >> x.level};
  }
  tet::Kind kind(std::int32_t t) const { return kind_of_local(tet(t).local); }
  int child_count(std::int32_t t) const { return tet::child_count(kind(t)); }
  std::int32_t root_count() const { return root_count_; }
  // Where the window holds coarse index c along d: c itself, or on a periodic axis the one
  // image of c in [lo, lo + N).
  std::int64_t window_position(int d, std::int64_t c) const;
  // The code of the same honeycomb tet with its cube reduced into [0, N·2^level) on the
  // periodic axes (parity is kept: N is even on a periodic axis in 3D).
  TetCode canonical(int level, TetCode code) const {
    for (int d = 0; d < 3; ++d) code.cube[d] = lattice_.canonical_cell(d, level, code.cube[d]);
    return code;
  }
  // Root `local` (0..4) of global coarse cube (ci, cj, ck) (any image on a periodic axis),
  // or -1 outside the range.
  std::int32_t root(std::int64_t ci, std::int64_t cj, std::int64_t ck, int local) const;
  TetCode code(std::int32_t t) const {
    const Tet& x = tet(t);
    return TetCode{{x.cube[0], x.cube[1], x.cube[2]}, x.local};
  }

  // Vertices on the finest lattice, positively oriented (corner tets: right-angle apex
  // first), and their keys.
  std::array<LatticePoint3, 4> fine_vertices(std::int32_t t) const {
    // Inline, each coordinate shifted before it is stored: out of line, the caller read the
    // returned array with vector loads over scalar stores (failed store-to-load forwards,
    // 6 % of a 3D run); shifting tet_vertices' result in place did the same inside.
    const Tet& x = tet(t);
    const int shift = lattice_.max_level - x.level;
    const auto& corners = kCubeTets[static_cast<std::size_t>((x.cube[0] + x.cube[1] + x.cube[2]) & 1)][x.local];
    std::array<LatticePoint3, 4> v;
    for (int i = 0; i < 4; ++i)
      for (int d = 0; d < 3; ++d)
        v[static_cast<std::size_t>(i)][static_cast<std::size_t>(d)] =
            (std::int64_t{x.cube[static_cast<std::size_t>(d)]} + ((corners[static_cast<std::size_t>(i)] >> d) & 1)) << shift;
    return v;
  }
  std::array<LatticeKey3, 4> vertex_keys(std::int32_t t) const;
  // World coordinates of a finest-lattice point.
  Vec3 position(const LatticePoint3& p) const {
    return {lattice_.coordinate(0, p[0]), lattice_.coordinate(1, p[1]), lattice_.coordinate(2, p[2])};
  }

  // The tet on the path to honeycomb tet `code` of `level` with the largest level ≤
  // `level`: a leaf containing it (maybe coarser) or the non-leaf exactly at `level`.
  // -1 when that tet is outside the range. Point location on the nested honeycombs: the
  // descent follows the target's centroid, which lies inside exactly one tet per level.
  std::int32_t find(int level, const TetCode& target) const;
  // find(), starting from the ancestors of tet `start` instead of the roots: the same
  // answer, found faster when the target is near `start`.
  std::int32_t find_near(std::int32_t start, int level, const TetCode& target) const;
  // find() of the honeycomb tet of t's level across face f (opposite vertex f): the
  // neighbour at t's level, a coarser leaf, or -1 outside the range.
  std::int32_t face_neighbour(std::int32_t t, int face) const;
  // Appends the leaves whose closure holds the midpoint p of the edge (a, b) of the
  // level-`level` honeycomb (a, b on the finest lattice, level < max_level): the leaves of
  // that level or coarser around the edge, and the finer leaves with p as a vertex. A
  // coarse leaf may be appended more than once. Used by SAMR to find the leaves whose
  // rules can change when p becomes a node or a node that may move. `near`: a tet near
  // the edge to start the searches from (find_near), or -1.
  void leaves_at_midpoint(const LatticePoint3& a, const LatticePoint3& b, int level, std::int32_t near,
                          std::vector<std::int32_t>& out) const;

  // Splits leaf t into its 7 or 12 children; returns the index of the first child.
  std::int32_t refine(std::int32_t t);

  // Appends the refinement of the tree below tet t in pre-order, children in their table
  // order: 1 for a refined tet, 0 for a leaf. Two forests hold the same tets below two
  // tets of one code exactly when these agree (the codes follow from the tables).
  void append_refinement(std::int32_t t, std::vector<std::uint8_t>& out) const;
  // Makes each of `roots` a leaf, dropping the tets below it; the others keep their order.
  // Returns every old tet's new index, -1 for the dropped ones.
  std::vector<std::int32_t> prune(std::span<const std::int32_t> roots);

 private:
  Lattice3 lattice_;
  CellRange<3> range_;
  std::int32_t root_count_ = 0;
  std::vector<Tet> tets_;

  // find() of the level-`level` tet whose centroid (×4, level coordinates, canonical) is c4.
  std::int32_t find_centroid(int level, const LatticePoint3& c4) const;
  // The deepest tet with level ≤ `level` below t on the way to the level-`level` tet whose
  // centroid (×4, level coordinates) is c4; t must contain it.
  std::int32_t descend(std::int32_t t, int level, const LatticePoint3& c4) const;
  // Appends the leaves below non-leaf t that have the fine point p (any periodic image) as a
  // vertex; p must be a vertex or an edge midpoint of t.
  void leaves_with_vertex(std::int32_t t, const LatticePoint3& p, std::vector<std::int32_t>& out) const;
};

// The leaves a kernel stage works on in a partition (lib/parallel/README.md, "Ghost region
// (3D)"): those whose cube comes within `reach` fine lattice units of the box on every axis,
// or every leaf (reach < 0). The ghost's outer part is there for SAMR's sake; r-adaptivity
// and face swapping need only the leaves their decisions in the box can read.
struct LeafWindow {
  LatticePoint3 lo{}, hi{};  // the box, fine lattice units
  std::int64_t reach = -1;

  static LeafWindow around(const Lattice3& lattice, const CellRange<3>& box, std::int64_t reach) {
    LeafWindow w;
    for (int d = 0; d < 3; ++d) w.lo[d] = box.lo[d] * lattice.units(0), w.hi[d] = box.hi[d] * lattice.units(0);
    w.reach = reach;
    return w;
  }
  bool holds(const TetForest& forest, std::int32_t t) const {
    if (reach < 0) return true;
    const TetForest::Tet& x = forest.tet(t);
    const std::int64_t side = forest.lattice().units(x.level);
    for (int d = 0; d < 3; ++d) {
      const std::int64_t a = static_cast<std::int64_t>(x.cube[static_cast<std::size_t>(d)]) * side;
      if (lo[d] - (a + side) > reach || a - hi[d] > reach) return false;
    }
    return true;
  }
};

}  // namespace cisamr::grid
