#include "grid/tet_forest.hpp"

#include "core/error.hpp"

namespace cisamr::grid {

TetForest::TetForest(const Lattice3& lattice, const CellRange<3>& range) : lattice_(lattice), range_(range) {
  for (int d = 0; d < 3; ++d)
    if (range.hi[d] > lattice.coarse_cells[d] || range.lo[d] < 0 || range.hi[d] <= range.lo[d])
      throw MeshingError("cell range outside the domain lattice");
  require_key3(lattice);  // also keeps every level coordinate within 32 bits
  const std::int64_t n = range.count(0) * range.count(1) * range.count(2);
  if (5 * n > 2147483647) throw MeshingError("too many coarse cubes in one tet forest");
  root_count_ = static_cast<std::int32_t>(5 * n);
  tets_.resize(static_cast<std::size_t>(root_count_));
  for (std::int64_t ck = range.lo[2]; ck < range.hi[2]; ++ck)
    for (std::int64_t cj = range.lo[1]; cj < range.hi[1]; ++cj)
      for (std::int64_t ci = range.lo[0]; ci < range.hi[0]; ++ci)
        for (int local = 0; local < 5; ++local) {
          Tet& t = tets_[static_cast<std::size_t>(root(ci, cj, ck, local))];
          t.cube = {static_cast<std::int32_t>(ci), static_cast<std::int32_t>(cj), static_cast<std::int32_t>(ck)};
          t.local = static_cast<std::uint8_t>(local);
        }
}

std::int32_t TetForest::root(std::int64_t ci, std::int64_t cj, std::int64_t ck, int local) const {
  if (ci < range_.lo[0] || ci >= range_.hi[0] || cj < range_.lo[1] || cj >= range_.hi[1] || ck < range_.lo[2] ||
      ck >= range_.hi[2])
    return -1;
  const std::int64_t cube =
      ((ck - range_.lo[2]) * range_.count(1) + (cj - range_.lo[1])) * range_.count(0) + (ci - range_.lo[0]);
  return static_cast<std::int32_t>(5 * cube + local);
}

std::array<LatticePoint3, 4> TetForest::fine_vertices(std::int32_t t) const {
  auto v = tet_vertices(code(t));
  const int shift = lattice_.max_level - tet(t).level;
  for (auto& p : v)
    for (auto& c : p) c <<= shift;
  return v;
}

std::array<LatticeKey3, 4> TetForest::vertex_keys(std::int32_t t) const {
  const auto v = fine_vertices(t);
  return {key3(v[0]), key3(v[1]), key3(v[2]), key3(v[3])};
}

std::int32_t TetForest::find(int level, const TetCode& target) const {
  const LatticePoint3 c4 = centroid4(target);  // level coordinates × 4
  for (int d = 0; d < 3; ++d)
    if (c4[d] < 0) return -1;
  const TetCode top = locate(c4, 2 + level);
  std::int32_t t = root(top.cube[0], top.cube[1], top.cube[2], top.local);
  if (t < 0) return -1;
  for (int l = 1; l <= level; ++l) {
    const Tet& x = tets_[static_cast<std::size_t>(t)];
    if (x.first_child < 0) return t;
    const TetCode want = locate(c4, 2 + level - l);
    const int n = tet::child_count(kind_of_local(x.local));
    std::int32_t next = -1;
    for (int c = 0; c < n; ++c)
      if (code(x.first_child + c) == want) {
        next = x.first_child + c;
        break;
      }
    if (next < 0) return -1;  // unreachable for a consistent forest
    t = next;
  }
  return t;
}

std::int32_t TetForest::face_neighbour(std::int32_t t, int face) const {
  return find(tet(t).level, grid::face_neighbour(code(t), face));
}

std::int32_t TetForest::refine(std::int32_t t) {
  const Tet parent = tets_[static_cast<std::size_t>(t)];
  if (parent.first_child >= 0) throw MeshingError("refining a tet that is not a leaf");
  if (parent.level >= lattice_.max_level) throw MeshingError("refinement beyond the finest level");
  std::array<TetCode, 12> children{};
  const int n = children_codes(code(t), children);
  if (tets_.size() + static_cast<std::size_t>(n) > 2147483647u) throw MeshingError("tet forest exceeds 2^31 tets");
  const auto first = static_cast<std::int32_t>(tets_.size());
  tets_[static_cast<std::size_t>(t)].first_child = first;
  for (int c = 0; c < n; ++c) {
    Tet child;
    child.parent = t;
    child.level = static_cast<std::uint8_t>(parent.level + 1);
    child.local = children[c].local;
    for (int d = 0; d < 3; ++d) child.cube[d] = static_cast<std::int32_t>(children[c].cube[d]);
    tets_.push_back(child);
  }
  return first;
}

}  // namespace cisamr::grid
