#pragma once
// Small hand-built inputs for the unit tests of the meshing stages (radapt, faceswap,
// subdivide): a scene in a box, its lattice and refined forest built as the pipeline does,
// the leaves' emitted tetrahedra evaluated as the snapping guard and subdivide3 do
// (grid/cut_stencil3.hpp), and exact conformity checks by node ids.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "geometry/oracle.hpp"
#include "geometry/scene.hpp"
#include "grid/cut_stencil3.hpp"
#include "grid/lattice.hpp"
#include "grid/tet_lattice.hpp"
#include "mesh/metrics.hpp"
#include "radapt/radapt2.hpp"
#include "radapt/radapt3.hpp"
#include "samr/samr2.hpp"
#include "samr/samr3.hpp"

namespace cisamr::testing {

// A box [lo, hi] with a matrix (id 1) and an inclusion phase (id 2), no inclusions yet.
inline geometry::SceneDesc box_scene(int dimension, const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                                     double h, int levels) {
  geometry::SceneDesc s;
  s.dimension = dimension;
  s.domain_min = lo;
  s.domain_max = hi;
  s.h = h;
  s.levels = levels;
  s.phases = {{1, "matrix", false}, {2, "inclusion", false}};
  s.matrix_phase = 1;
  return s;
}

// The lattice of a scene as the pipeline builds it: coarse cells of size h over the domain,
// finest level = the largest level any inclusion asks for.
template <int Dim>
grid::Lattice<Dim> lattice_of(const geometry::SceneDesc& scene) {
  grid::Lattice<Dim> lattice;
  lattice.h = scene.h;
  lattice.max_level = scene.levels;
  for (const auto& inclusion : scene.inclusions) lattice.max_level = std::max(lattice.max_level, inclusion.levels);
  for (int d = 0; d < Dim; ++d) {
    const auto k = static_cast<std::size_t>(d);
    lattice.origin[k] = scene.domain_min[k];
    lattice.coarse_cells[k] = std::llround((scene.domain_max[k] - scene.domain_min[k]) / scene.h);
  }
  return lattice;
}

// The stages up to r-adaptivity, run on the whole domain as the pipeline runs them.
struct Stage2 {
  geometry::Oracle2 oracle;
  grid::Lattice2 lattice;
  samr::RefinedGrid2 grid;
  radapt::Nodes2 nodes;
  explicit Stage2(const geometry::SceneDesc& scene, double alpha = 0.5)
      : oracle(scene),
        lattice(lattice_of<2>(scene)),
        grid(samr::refine2(oracle, lattice, lattice.whole_domain())),
        nodes(radapt::snap2(oracle, grid, radapt::Options{alpha})) {}
  Vec2 lattice_position(std::size_t n) const {
    return {lattice.coordinate(0, grid::key2_x(nodes.key[n])), lattice.coordinate(1, grid::key2_y(nodes.key[n]))};
  }
};

struct Stage3 {
  geometry::Oracle3 oracle;
  grid::Lattice3 lattice;
  samr::RefinedGrid3 grid;
  radapt::Nodes3 nodes;
  explicit Stage3(const geometry::SceneDesc& scene, const radapt::Options3& options = {})
      : oracle(scene),
        lattice(lattice_of<3>(scene)),
        grid(samr::refine3(oracle, lattice, lattice.whole_domain())),
        nodes(radapt::snap3(oracle, grid, options)) {}
  Vec3 lattice_position(std::size_t n) const { return grid.forest.position(grid::key3_point(nodes.key[n])); }
};

// Every inclusion of an oracle, as a candidate list.
template <class Oracle>
std::vector<std::int32_t> all_inclusions(const Oracle& oracle) {
  std::vector<std::int32_t> all(static_cast<std::size_t>(oracle.inclusion_count()));
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = static_cast<std::int32_t>(k);
  return all;
}

// ---- 3D leaves as the guard and subdivide3 see them ----

// What a leaf (or a new tet of a swapped cube) emits: its stencil outcome with the final
// positions and masks of its nodes and the cut points radapt3 computed, or `extra_cut`
// (a new edge of face swapping) where radapt3 has none.
template <class ExtraCut>
grid::stencil3::Outcome emitted(const radapt::Nodes3& nodes, const std::array<std::int32_t, 4>& ids,
                                const std::array<grid::LatticePoint3, 4>& lattice, ExtraCut&& extra_cut) {
  std::array<Vec3, 4> p{};
  std::array<PhaseMask, 4> m{};
  std::array<grid::stencil3::PointId, 4> id{};
  for (std::size_t i = 0; i < 4; ++i) {
    const auto n = static_cast<std::size_t>(ids[i]);
    p[i] = nodes.position[n], m[i] = nodes.mask[n], id[i] = {nodes.key[n], nodes.key[n]};
  }
  return grid::stencil3::outcome(lattice, p, m, id, [&](int e, Vec3& point, grid::stencil3::PointId& pid) {
    const auto a = static_cast<std::size_t>(ids[grid::tet::kEdges[e][0]]);
    const auto b = static_cast<std::size_t>(ids[grid::tet::kEdges[e][1]]);
    const radapt::EdgeCut* cut = nullptr;
    if (const std::int32_t k = nodes.edge(nodes.key[a], nodes.key[b]); k >= 0)
      cut = &nodes.edges[static_cast<std::size_t>(k)];
    else
      cut = extra_cut(nodes.key[a], nodes.key[b]);
    if (cut == nullptr || !cut->found) return false;
    point = cut->point, pid = {cut->lo, cut->hi};
    return true;
  });
}

inline grid::stencil3::Outcome emitted(const radapt::Nodes3& nodes, const std::array<std::int32_t, 4>& ids,
                                       const std::array<grid::LatticePoint3, 4>& lattice) {
  return emitted(nodes, ids, lattice, [](grid::LatticeKey3, grid::LatticeKey3) -> const radapt::EdgeCut* { return nullptr; });
}

// The worst aspect ratio among the non-void tets of an outcome; +inf for an inverted tet
// or an outcome that cannot be split.
inline double worst_aspect(const grid::stencil3::Outcome& o, const geometry::SceneDesc& scene) {
  using Kind = grid::stencil3::Outcome::Kind;
  constexpr double kInf = 1e300;
  const auto is_void = [&](int phase) { return scene.phases[static_cast<std::size_t>(phase)].is_void; };
  const auto measure = [&](const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    return mesh::signed_volume(a, b, c, d) > 0 ? mesh::aspect_ratio(a, b, c, d) : kInf;
  };
  if (o.kind == Kind::unsplittable) return kInf;
  if (o.kind == Kind::kept) {
    if (single_bit(o.common) && is_void(std::countr_zero(o.common))) return 0;
    return measure(o.p[0], o.p[1], o.p[2], o.p[3]);
  }
  double worst = 0;
  for (int k = 0; k < o.split.count; ++k) {
    if (is_void(o.phase_of(k))) continue;
    const auto& s = o.split.tet[static_cast<std::size_t>(k)];
    worst = std::max(worst, measure(o.p[s[0]], o.p[s[1]], o.p[s[2]], o.p[s[3]]));
  }
  return worst;
}

// ---- Exact conformity of a simplex soup, by node ids ----

struct Conformity {
  std::size_t unmatched = 0;         // facets used once, not on the domain boundary
  std::size_t same_orientation = 0;  // facets used twice the same way round
  std::size_t over_used = 0;         // facets used three times or more
  std::size_t boundary = 0;          // facets on the domain boundary
  bool ok() const { return unmatched == 0 && same_orientation == 0 && over_used == 0; }
};

// `simplices`: Dim + 1 node ids each, positively oriented. A facet must be shared by two
// simplices with opposite orientations, or lie on the boundary (`on_boundary(ids)`). A
// hanging node (a node inside a neighbour's facet) leaves facets used once.
template <int Dim, class OnBoundary>
Conformity check_conformity(const std::vector<std::int32_t>& simplices, OnBoundary&& on_boundary) {
  constexpr int kVerts = Dim + 1;
  std::map<std::array<std::int32_t, Dim>, std::vector<int>> facets;
  for (std::size_t s = 0; s + kVerts <= simplices.size(); s += kVerts) {
    for (int skip = 0; skip < kVerts; ++skip) {
      // The facet opposite vertex `skip`, oriented as the boundary of the simplex.
      std::array<std::int32_t, Dim> f{};
      int n = 0;
      for (int k = 0; k < kVerts; ++k)
        if (k != skip) f[static_cast<std::size_t>(n++)] = simplices[s + static_cast<std::size_t>(k)];
      int parity = (skip % 2 == 0) ? 1 : -1;
      for (int i = 0; i < Dim; ++i)
        for (int j = i + 1; j < Dim; ++j)
          if (f[static_cast<std::size_t>(i)] > f[static_cast<std::size_t>(j)]) parity = -parity;
      std::sort(f.begin(), f.end());
      facets[f].push_back(parity);
    }
  }
  Conformity c;
  for (const auto& [f, uses] : facets) {
    if (uses.size() == 1) {
      (on_boundary(f) ? c.boundary : c.unmatched) += 1;
    } else if (uses.size() == 2) {
      if (uses[0] == uses[1]) ++c.same_orientation;
    } else {
      ++c.over_used;
    }
  }
  return c;
}

// Do all points lie on one face of the box [lo, hi] (exact coordinates)?
template <int Dim, std::size_t N>
bool on_box_face(const std::array<Vec<Dim>, N>& p, const std::array<double, 3>& lo, const std::array<double, 3>& hi) {
  for (int d = 0; d < Dim; ++d)
    for (double plane : {lo[static_cast<std::size_t>(d)], hi[static_cast<std::size_t>(d)]}) {
      bool all = true;
      for (const auto& q : p) all = all && q[static_cast<std::size_t>(d)] == plane;
      if (all) return true;
    }
  return false;
}

}  // namespace cisamr::testing
