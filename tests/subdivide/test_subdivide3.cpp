// Subdivision in 3D as a stage (subdivide/subdivide3.hpp): subdivide3 run cube by cube on
// small snapped forests. The tets of each coarse cube fill exactly its leaves (as the
// snapped vertices deform them), are positively oriented and lie in the phase they are
// given; the cube-by-cube runs, each splitting the quads of its faces by the key rule on
// its own, fit together conformingly, hanging midpoints closed.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

#include "faceswap/faceswap3.hpp"
#include "subdivide/subdivide3.hpp"
#include "support/stage_setup.hpp"

namespace cisamr {
namespace {

using geometry::SceneDesc;
using Identity = std::array<grid::LatticeKey3, 2>;

struct Soup3 {
  std::vector<Vec3> points;        // by node id
  std::vector<Identity> identity;  // by node id: (key, key), a cut node's edge, or interior
  std::vector<std::int32_t> tets;  // 4 ids each
  std::vector<std::int32_t> phase;
  double volume(std::size_t t) const {
    const auto p = [&](int k) { return points[static_cast<std::size_t>(tets[4 * t + static_cast<std::size_t>(k)])]; };
    return mesh::signed_volume(p(0), p(1), p(2), p(3));
  }
};

Soup3 subdivide(const testing::Stage3& s, const grid::CellRange<3>& owned, const faceswap::Swaps3* swaps = nullptr) {
  const subdivide::Tets3 t = subdivide::subdivide3(s.oracle, s.grid, s.nodes, owned, swaps);
  EXPECT_EQ(t.unresolved, 0);
  EXPECT_EQ(t.inverted, 0);
  Soup3 out;
  out.points = s.nodes.position;
  out.points.insert(out.points.end(), t.extra_points.begin(), t.extra_points.end());
  for (grid::LatticeKey3 k : s.nodes.key) out.identity.push_back({k, k});
  out.identity.insert(out.identity.end(), t.extra_identity.begin(), t.extra_identity.end());
  out.tets = t.tets;
  out.phase.assign(t.phase.begin(), t.phase.end());
  return out;
}

struct PhaseCheck {
  std::size_t non_positive = 0, vertex_outside = 0, centroid_elsewhere = 0;
  bool ok() const { return non_positive == 0 && vertex_outside == 0 && centroid_elsewhere == 0; }
};

// Every tet positive, its vertices in its phase's closure (within the guard's reported
// collapse deviation) and its centroid in its phase, or off it by at most the sagitta of
// its longest edge on the sphere of radius `radius` (the interface's curvature) plus that
// deviation (a collapsed vertex stands off the phase it joined).
PhaseCheck check_phases(const testing::Stage3& s, const Soup3& m, double radius) {
  PhaseCheck c;
  const auto all = testing::all_inclusions(s.oracle);
  const double tolerance = std::max(1e-12, s.nodes.max_collapse_deviation * (1 + 1e-9));
  for (std::size_t t = 0; t < m.phase.size(); ++t) {
    const int phase = m.phase[t];
    if (!(m.volume(t) > 0)) ++c.non_positive;
    Vec3 centroid{0, 0, 0};
    std::array<Vec3, 4> p{};
    for (std::size_t k = 0; k < 4; ++k) {
      p[k] = m.points[static_cast<std::size_t>(m.tets[4 * t + k])];
      if (s.oracle.distance_to_phase(p[k], phase) > tolerance) ++c.vertex_outside;
      for (std::size_t d = 0; d < 3; ++d) centroid[d] += p[k][d] / 4;
    }
    if (s.oracle.phase_at(centroid, all) == phase) continue;
    double longest = 0;
    for (const auto& e : grid::tet::kEdges) longest = std::max(longest, mesh::distance<3>(p[e[0]], p[e[1]]));
    const double sagitta = longest < 2 * radius ? radius - std::sqrt(radius * radius - longest * longest / 4) : 0;
    if (s.oracle.distance_to_phase(centroid, phase) > sagitta + s.nodes.max_collapse_deviation) ++c.centroid_elsewhere;
  }
  return c;
}

// Σ volume of the tets − Σ volume of the leaves of coarse cube `cube` (their vertices at
// their final positions).
double cover_error(const testing::Stage3& s, const Soup3& m, std::int64_t cube) {
  double tets = 0, leaves = 0;
  for (std::size_t t = 0; t < m.phase.size(); ++t) tets += m.volume(t);
  for (std::int32_t t = 0; t < static_cast<std::int32_t>(s.grid.forest.size()); ++t) {
    if (!s.grid.forest.is_leaf(t) || s.grid.cube_of(t) != cube) continue;
    const auto& ids = s.nodes.tet_nodes[static_cast<std::size_t>(t)];
    const auto p = [&](int k) { return s.nodes.position[static_cast<std::size_t>(ids[static_cast<std::size_t>(k)])]; };
    leaves += mesh::signed_volume(p(0), p(1), p(2), p(3));
  }
  return tets - leaves;
}

testing::Conformity conformity(const SceneDesc& scene, const Soup3& m) {
  return testing::check_conformity<3>(m.tets, [&](const std::array<std::int32_t, 3>& f) {
    return testing::on_box_face<3>(std::array{m.points[static_cast<std::size_t>(f[0])], m.points[static_cast<std::size_t>(f[1])],
                                              m.points[static_cast<std::size_t>(f[2])]},
                                   scene.domain_min, scene.domain_max);
  });
}

// Appends `part` to `whole`, merging points by identity (interior points never merge).
void join(Soup3& whole, const Soup3& part, std::map<Identity, std::int32_t>& index) {
  std::vector<std::int32_t> id(part.points.size());
  for (std::size_t n = 0; n < part.points.size(); ++n) {
    const Identity& key = part.identity[n];
    const bool interior = key[0] == subdivide::Tets3::kInteriorPoint;
    const auto next = static_cast<std::int32_t>(whole.points.size());
    if (!interior) {
      auto [it, inserted] = index.try_emplace(key, next);
      id[n] = it->second;
      if (!inserted) continue;
    } else {
      id[n] = next;
    }
    whole.points.push_back(part.points[n]);
    whole.identity.push_back(key);
  }
  for (std::int32_t v : part.tets) whole.tets.push_back(id[static_cast<std::size_t>(v)]);
  whole.phase.insert(whole.phase.end(), part.phase.begin(), part.phase.end());
}

// Scenes in a box of 6³ cubes of 0.25: a sphere of radius 1000 whose surface crosses the box
// as an almost flat, tilted plane, and a sphere of radius 0.3; levels 0 and 1 (hanging
// midpoints around the refined region).
struct Scene3 {
  SceneDesc scene;
  double radius = 0;
};

std::vector<Scene3> scenes3() {
  std::vector<Scene3> out;
  for (int levels : {0, 1}) {
    SceneDesc plane = testing::box_scene(3, {0, 0, 0}, {1.5, 1.5, 1.5}, 0.25, levels);
    const double n = std::sqrt(0.3 * 0.3 + 0.2 * 0.2 + 1.0);
    const double r = 1000;
    plane.inclusions = {{geometry::Sphere{{0.61 - r * 0.3 / n, 0.58 - r * 0.2 / n, 0.43 - r / n}, r}, 2, levels}};
    out.push_back({plane, r});
    SceneDesc ball = testing::box_scene(3, {0, 0, 0}, {1.5, 1.5, 1.5}, 0.25, levels);
    ball.inclusions = {{geometry::Sphere{{0.51, 0.48, 0.53}, 0.3}, 2, levels}};
    out.push_back({ball, 0.3});
  }
  return out;
}

std::string name(const Scene3& sc) {
  return "levels " + std::to_string(sc.scene.levels) + ", radius " + std::to_string(sc.radius);
}

TEST(Subdivide3, EachCubeIsFilledByPositiveTetsOfItsPhase) {
  for (const Scene3& sc : scenes3()) {
    SCOPED_TRACE(name(sc));
    const testing::Stage3 s(sc.scene);
    const auto& range = s.grid.forest.range();
    std::int64_t cut = 0, closed = 0;
    for (std::int64_t k = range.lo[2]; k < range.hi[2]; ++k)
      for (std::int64_t j = range.lo[1]; j < range.hi[1]; ++j)
        for (std::int64_t i = range.lo[0]; i < range.hi[0]; ++i) {
          const grid::CellRange<3> owned{{i, j, k}, {i + 1, j + 1, k + 1}};
          const Soup3 m = subdivide(s, owned);
          const auto cube = s.grid.cube_index(i, j, k);
          EXPECT_NEAR(cover_error(s, m, cube), 0.0, 1e-15) << "cube " << i << ", " << j << ", " << k;
          const PhaseCheck c = check_phases(s, m, sc.radius);
          EXPECT_TRUE(c.ok()) << "cube " << i << ", " << j << ", " << k << ": " << c.non_positive << " not positive, "
                              << c.vertex_outside << " vertices outside, " << c.centroid_elsewhere
                              << " centroids elsewhere";
          const auto t = subdivide::subdivide3(s.oracle, s.grid, s.nodes, owned);
          cut += t.cut_tets, closed += t.closed_tets;
        }
    EXPECT_GT(cut, 8);
    if (sc.scene.levels == 1) {
      EXPECT_GT(closed, 0);
    }
    std::printf("[subdivide3] %s: %lld cut leaves, %lld closed leaves, %lld snapped, %lld collapsed\n", name(sc).c_str(),
                static_cast<long long>(cut), static_cast<long long>(closed), static_cast<long long>(s.nodes.snapped_count),
                static_cast<long long>(s.nodes.collapsed_count));
  }
}

// Each cube split on its own (as a partition would): cut nodes merged by their edge's key
// pair, the union conforms, so every face quad was split alike from both sides (the key
// rule), and no hanging midpoint is left. The whole-domain run, with and without face
// swaps, conforms and fills the box.
TEST(Subdivide3, CubeByCubeRunsFitTogether) {
  std::int64_t swapped = 0;
  for (const Scene3& sc : scenes3()) {
    SCOPED_TRACE(name(sc));
    const testing::Stage3 s(sc.scene);
    const auto& range = s.grid.forest.range();
    Soup3 joined;
    std::map<Identity, std::int32_t> index;
    for (std::int64_t k = range.lo[2]; k < range.hi[2]; ++k)
      for (std::int64_t j = range.lo[1]; j < range.hi[1]; ++j)
        for (std::int64_t i = range.lo[0]; i < range.hi[0]; ++i) join(joined, subdivide(s, {{i, j, k}, {i + 1, j + 1, k + 1}}), index);
    const auto c = conformity(sc.scene, joined);
    EXPECT_TRUE(c.ok()) << c.unmatched << " unmatched, " << c.same_orientation << " same orientation, " << c.over_used
                        << " over used";

    const faceswap::Swaps3 swaps = faceswap::swap3(s.oracle, s.grid, s.nodes);
    swapped += swaps.swaps;
    for (const faceswap::Swaps3* with : {static_cast<const faceswap::Swaps3*>(nullptr), &swaps}) {
      const Soup3 whole = subdivide(s, s.lattice.whole_domain(), with);
      EXPECT_TRUE(conformity(sc.scene, whole).ok()) << (with ? "with" : "without") << " swaps";
      double volume = 0;
      for (std::size_t t = 0; t < whole.phase.size(); ++t) volume += whole.volume(t);
      EXPECT_NEAR(volume, 1.5 * 1.5 * 1.5, 1e-12);
      EXPECT_TRUE(check_phases(s, whole, sc.radius).ok());
      if (with == nullptr) {
        EXPECT_EQ(whole.tets.size(), joined.tets.size());
      }
    }
  }
  EXPECT_GT(swapped, 0) << "no face swap: the swapped cubes' tets are not exercised";
}

// The checks catch what they are for: a dropped tet (cover), a tet given the other phase,
// and a square face split along one diagonal on one side and the other diagonal on the
// other (two pyramids on the unit square).
TEST(Subdivide3, ChecksCatchBrokenOutput) {
  const Scene3 sc = scenes3()[1];
  const testing::Stage3 s(sc.scene);
  const Soup3 m = subdivide(s, {{1, 1, 1}, {2, 2, 2}});  // a cube the sphere cuts
  ASSERT_TRUE(check_phases(s, m, sc.radius).ok());
  const auto cube = s.grid.cube_index(1, 1, 1);
  ASSERT_NEAR(cover_error(s, m, cube), 0.0, 1e-15);
  Soup3 relabelled = m;
  for (auto& p : relabelled.phase) p = 1 - p;
  EXPECT_GT(check_phases(s, relabelled, sc.radius).vertex_outside, 0u);
  Soup3 dropped = m;
  dropped.tets.resize(dropped.tets.size() - 4);
  dropped.phase.pop_back();
  EXPECT_GT(std::abs(cover_error(s, dropped, cube)), 1e-9);

  Soup3 pyramids;
  pyramids.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}, {0.5, 0.5, -1}};
  pyramids.tets = {0, 1, 2, 4, 0, 2, 3, 4,   // above, base split along 0–2
                   1, 0, 3, 5, 1, 3, 2, 5};  // below, base split along 1–3
  SceneDesc far = sc.scene;
  far.domain_min = {-5, -5, -5};
  far.domain_max = {5, 5, 5};
  const auto c = conformity(far, pyramids);
  EXPECT_FALSE(c.ok());
  EXPECT_EQ(c.unmatched, 12u);  // 8 lateral faces + 4 base triangles

  Soup3 agreeing = pyramids;
  agreeing.tets = {0, 1, 2, 4, 0, 2, 3, 4, 1, 0, 2, 5, 0, 3, 2, 5};  // both along 0–2
  EXPECT_EQ(conformity(far, agreeing).unmatched, 8u);  // only the lateral faces
}

}  // namespace
}  // namespace cisamr
