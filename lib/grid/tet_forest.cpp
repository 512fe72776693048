#include "grid/tet_forest.hpp"

#include <algorithm>

#include "core/check.hpp"
#include "core/error.hpp"

namespace cisamr::grid {
namespace {

// Children of a tet by its cube parity and local index: a child's cube is 2·cube + offset
// (offset bits x, y, z in {0, 1}, the child lies in the parent's cube) and its local index
// depend on nothing else (the honeycomb is invariant under even translations).
struct ChildTable {
  // code[parity][local][c]: offset bits | child local << 3, in template order.
  std::array<std::array<std::array<std::uint8_t, 12>, 5>, 2> code{};
  // index[parity][local][offset bits][child local]: template index, -1 when no child.
  std::array<std::array<std::array<std::array<std::int8_t, 5>, 8>, 5>, 2> index{};
};
constexpr ChildTable make_child_table() {
  ChildTable t;
  for (int parity = 0; parity < 2; ++parity)
    for (int local = 0; local < 5; ++local) {
      for (auto& o : t.index[parity][local]) o.fill(-1);
      const TetCode parent{{parity, 0, 0}, static_cast<std::uint8_t>(local)};
      std::array<TetCode, 12> children{};
      const int n = children_codes(parent, children);
      for (int c = 0; c < n; ++c) {
        int offset = 0;
        for (int d = 0; d < 3; ++d) offset |= static_cast<int>(children[c].cube[d] - 2 * parent.cube[d]) << d;
        t.code[parity][local][c] = static_cast<std::uint8_t>(offset | children[c].local << 3);
        t.index[parity][local][offset][children[c].local] = static_cast<std::int8_t>(c);
      }
    }
  return t;
}
constexpr ChildTable kChildTable = make_child_table();

}  // namespace

TetForest::TetForest(const Lattice3& lattice, const CellRange<3>& range) : lattice_(lattice), range_(range) {
  for (int d = 0; d < 3; ++d) {
    // A window along a periodic axis may reach past either face (it wraps); once it spans
    // the period it is the whole circle.
    if (lattice.periodic[d] && range.count(d) >= lattice.coarse_cells[d]) range_.lo[d] = 0, range_.hi[d] = lattice.coarse_cells[d];
    if (!lattice.periodic[d] && (range.hi[d] > lattice.coarse_cells[d] || range.lo[d] < 0))
      throw MeshingError("cell range outside the domain lattice");
    if (range.hi[d] <= range.lo[d]) throw MeshingError("cell range outside the domain lattice");
  }
  require_key3(lattice);  // also keeps every level coordinate within 32 bits
  const std::int64_t n = range_.count(0) * range_.count(1) * range_.count(2);
  if (5 * n > 2147483647) throw MeshingError("too many coarse cubes in one tet forest");
  root_count_ = static_cast<std::int32_t>(5 * n);
  tets_.resize(static_cast<std::size_t>(root_count_));
  // Roots in window order; each holds its canonical cube.
  for (std::int64_t ck = range_.lo[2]; ck < range_.hi[2]; ++ck)
    for (std::int64_t cj = range_.lo[1]; cj < range_.hi[1]; ++cj)
      for (std::int64_t ci = range_.lo[0]; ci < range_.hi[0]; ++ci)
        for (int local = 0; local < 5; ++local) {
          Tet& t = tets_[static_cast<std::size_t>(root(ci, cj, ck, local))];
          t.cube = {static_cast<std::int32_t>(lattice_.canonical_cell(0, 0, ci)),
                    static_cast<std::int32_t>(lattice_.canonical_cell(1, 0, cj)),
                    static_cast<std::int32_t>(lattice_.canonical_cell(2, 0, ck))};
          t.local = static_cast<std::uint8_t>(local);
        }
}

std::int64_t TetForest::window_position(int d, std::int64_t c) const {
  if (!lattice_.periodic[d]) return c;
  return range_.lo[d] + wrap(c - range_.lo[d], lattice_.coarse_cells[d]);
}

std::int32_t TetForest::root(std::int64_t ci, std::int64_t cj, std::int64_t ck, int local) const {
  ci = window_position(0, ci);
  cj = window_position(1, cj);
  ck = window_position(2, ck);
  if (ci < range_.lo[0] || ci >= range_.hi[0] || cj < range_.lo[1] || cj >= range_.hi[1] || ck < range_.lo[2] ||
      ck >= range_.hi[2])
    return -1;
  const std::int64_t cube =
      ((ck - range_.lo[2]) * range_.count(1) + (cj - range_.lo[1])) * range_.count(0) + (ci - range_.lo[0]);
  return static_cast<std::int32_t>(5 * cube + local);
}

std::array<LatticeKey3, 4> TetForest::vertex_keys(std::int32_t t) const {
  const auto v = fine_vertices(t);
  return {key3(v[0]), key3(v[1]), key3(v[2]), key3(v[3])};
}

std::int32_t TetForest::find(int level, const TetCode& target) const {
  return find_centroid(level, centroid4(canonical(level, target)));  // level coordinates × 4
}

std::int32_t TetForest::find_centroid(int level, const LatticePoint3& c4) const {
  for (int d = 0; d < 3; ++d)
    if (c4[d] < 0) return -1;
  const TetCode top = locate(c4, 2 + level);
  const std::int32_t t = root(top.cube[0], top.cube[1], top.cube[2], top.local);
  if (t < 0) return -1;
  return descend(t, level, c4);
}

std::int32_t TetForest::find_near(std::int32_t start, int level, const TetCode& target) const {
  const LatticePoint3 c4 = centroid4(canonical(level, target));
  for (std::int32_t t = start; t >= 0; t = tets_[static_cast<std::size_t>(t)].parent) {
    const Tet& x = tets_[static_cast<std::size_t>(t)];
    if (x.level > level) continue;
    // The cube first: most ancestors fail there, without locate's search of the cube's tets.
    const int shift = 2 + level - x.level;
    if ((c4[0] >> shift) != x.cube[0] || (c4[1] >> shift) != x.cube[1] || (c4[2] >> shift) != x.cube[2]) continue;
    if (locate(c4, shift).local == x.local) return descend(t, level, c4);
  }
  return find_centroid(level, c4);
}

std::int32_t TetForest::descend(std::int32_t t, int level, const LatticePoint3& c4) const {
  for (int l = tets_[static_cast<std::size_t>(t)].level + 1; l <= level; ++l) {
    const Tet& x = tets_[static_cast<std::size_t>(t)];
    if (x.first_child < 0) return t;
    const TetCode want = locate(c4, 2 + level - l);
    int offset = 0;
    for (int d = 0; d < 3; ++d) {
      const std::int64_t o = want.cube[d] - 2 * std::int64_t{x.cube[d]};
      if (o < 0 || o > 1) return -1;  // unreachable for a consistent forest
      offset |= static_cast<int>(o) << d;
    }
    const int parity = (x.cube[0] + x.cube[1] + x.cube[2]) & 1;
    const int c = kChildTable.index[parity][x.local][offset][want.local];
    if (c < 0) return -1;  // unreachable for a consistent forest
    t = x.first_child + c;
  }
  return t;
}

std::int32_t TetForest::face_neighbour(std::int32_t t, int face) const {
  return find(tet(t).level, grid::face_neighbour(code(t), face));
}

void TetForest::leaves_at_midpoint(const LatticePoint3& a, const LatticePoint3& b, int level, std::int32_t near,
                                   std::vector<std::int32_t>& out) const {
  const int shift = lattice_.max_level - level;
  LatticePoint3 p{}, lo{}, hi{};
  for (int d = 0; d < 3; ++d) {
    p[d] = (a[d] + b[d]) / 2;
    lo[d] = std::min(a[d], b[d]) >> shift;
    hi[d] = std::max(a[d], b[d]) >> shift;
  }
  // The level's tets around the edge: in every cube holding both ends (one or two choices
  // per axis), the tets with both ends as vertices.
  for (int s = 0; s < 8; ++s) {
    TetCode code;
    bool holds_edge = true;
    for (int d = 0; d < 3 && holds_edge; ++d) {
      const bool below = (s >> d) & 1;
      holds_edge = !below || lo[d] == hi[d];
      code.cube[d] = lo[d] - (below ? 1 : 0);
    }
    if (!holds_edge) continue;
    int corner_a = 0, corner_b = 0;
    for (int d = 0; d < 3; ++d) {
      corner_a |= static_cast<int>((a[d] >> shift) - code.cube[d]) << d;
      corner_b |= static_cast<int>((b[d] >> shift) - code.cube[d]) << d;
    }
    const auto& tets = kCubeTets[static_cast<std::size_t>(cube_parity(code.cube))];
    for (int local = 0; local < 5; ++local) {
      const auto& v = tets[static_cast<std::size_t>(local)];
      const bool has_a = v[0] == corner_a || v[1] == corner_a || v[2] == corner_a || v[3] == corner_a;
      const bool has_b = v[0] == corner_b || v[1] == corner_b || v[2] == corner_b || v[3] == corner_b;
      if (!has_a || !has_b) continue;
      code.local = static_cast<std::uint8_t>(local);
      const std::int32_t t = find_near(near, level, code);
      if (t < 0) continue;
      if (is_leaf(t)) out.push_back(t);
      else leaves_with_vertex(t, p, out);
    }
  }
}

void TetForest::leaves_with_vertex(std::int32_t t, const LatticePoint3& p, std::vector<std::int32_t>& out) const {
  // p as a point of t's refinement templates: a vertex or an edge midpoint.
  // Compared modulo the period: t holds its canonical frame, p may be another image.
  const auto same = [&](const LatticePoint3& a, const LatticePoint3& b) {
    for (int d = 0; d < 3; ++d)
      if (lattice_.canonical(d, a[d]) != lattice_.canonical(d, b[d])) return false;
    return true;
  };
  const auto v = fine_vertices(t);
  int point = -1;
  for (int i = 0; i < 4 && point < 0; ++i)
    if (same(v[i], p)) point = i;
  for (int e = 0; e < 6 && point < 0; ++e) {
    const auto& a = v[tet::kEdges[e][0]];
    const auto& b = v[tet::kEdges[e][1]];
    // t is not a leaf, so its vertices have even coordinates and the midpoint is a point.
    if (same({(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2}, p)) point = tet::midpoint(e);
  }
  const std::int32_t first = tet(t).first_child;
  const bool corner = kind(t) == tet::Kind::corner;
  const int n = child_count(t);
  for (int c = 0; c < n; ++c) {
    const auto& points = corner ? tet::kCornerChildren[c] : tet::kRegularChildren[c];
    if (points[0] != point && points[1] != point && points[2] != point && points[3] != point) continue;
    if (is_leaf(first + c)) out.push_back(first + c);
    else leaves_with_vertex(first + c, p, out);
  }
}

std::int32_t TetForest::refine(std::int32_t t) {
  const Tet parent = tets_[static_cast<std::size_t>(t)];
  CISAMR_CHECK(parent.first_child < 0, "refining a tet that is not a leaf");
  if (parent.level >= lattice_.max_level) throw MeshingError("refinement beyond the finest level");
  const int n = tet::child_count(kind_of_local(parent.local));
  if (tets_.size() + static_cast<std::size_t>(n) > 2147483647u) throw MeshingError("tet forest exceeds 2^31 tets");
  const auto first = static_cast<std::int32_t>(tets_.size());
  tets_[static_cast<std::size_t>(t)].first_child = first;
  const auto& codes = kChildTable.code[(parent.cube[0] + parent.cube[1] + parent.cube[2]) & 1][parent.local];
  for (int c = 0; c < n; ++c) {
    Tet child;
    child.parent = t;
    child.level = static_cast<std::uint8_t>(parent.level + 1);
    child.local = static_cast<std::uint8_t>(codes[c] >> 3);
    for (int d = 0; d < 3; ++d) child.cube[d] = 2 * parent.cube[d] + ((codes[c] >> d) & 1);
    tets_.push_back(child);
  }
  return first;
}

void TetForest::append_refinement(std::int32_t t, std::vector<std::uint8_t>& out) const {
  std::vector<std::int32_t> stack{t};
  while (!stack.empty()) {
    const std::int32_t u = stack.back();
    stack.pop_back();
    const Tet& x = tets_[static_cast<std::size_t>(u)];
    out.push_back(x.first_child < 0 ? 0 : 1);
    if (x.first_child < 0) continue;
    for (int c = tet::child_count(kind_of_local(x.local)) - 1; c >= 0; --c) stack.push_back(x.first_child + c);
  }
}

std::vector<std::int32_t> TetForest::prune(std::span<const std::int32_t> roots) {
  std::vector<std::int32_t> index(tets_.size(), 0);  // first 1 for the dropped tets
  std::vector<std::int32_t> stack;
  for (const std::int32_t r : roots) {
    stack.push_back(r);
    while (!stack.empty()) {
      const std::int32_t u = stack.back();
      stack.pop_back();
      if (u != r) index[static_cast<std::size_t>(u)] = 1;
      const Tet& y = tets_[static_cast<std::size_t>(u)];
      if (y.first_child >= 0)
        for (int c = 0; c < tet::child_count(kind_of_local(y.local)); ++c) stack.push_back(y.first_child + c);
    }
  }
  std::int32_t kept = 0;
  for (auto& i : index) i = i != 0 ? -1 : kept++;
  for (std::size_t t = 0; t < tets_.size(); ++t) {
    const std::int32_t to = index[t];
    if (to < 0) continue;
    Tet x = tets_[t];
    if (x.parent >= 0) x.parent = index[static_cast<std::size_t>(x.parent)];
    if (x.first_child >= 0) x.first_child = index[static_cast<std::size_t>(x.first_child)];  // -1 when dropped
    tets_[static_cast<std::size_t>(to)] = x;
  }
  tets_.resize(static_cast<std::size_t>(kept));
  return index;
}

}  // namespace cisamr::grid
