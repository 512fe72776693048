// Subdivision in 2D as a stage (subdivide/subdivide2.hpp): subdivide2 run cell by cell on
// small snapped grids. The triangles of each coarse cell cover exactly its leaves (as the
// snapped corners deform them), are positively oriented, lie in the phase they are given,
// and conform to the neighbours' triangles, hanging nodes closed.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

#include "subdivide/subdivide2.hpp"
#include "subdivide/templates2.hpp"
#include "support/stage_setup.hpp"

namespace cisamr {
namespace {

using geometry::SceneDesc;

struct Soup2 {
  std::vector<Vec2> points;             // by global node id
  std::vector<std::int32_t> triangles;  // 3 ids each
  std::vector<std::int32_t> phase;
};

// The triangles subdivide2 emits for the leaves of `owned`, with their points.
Soup2 subdivide(const testing::Stage2& s, const grid::CellRange<2>& owned) {
  const subdivide::Triangles2 t = subdivide::subdivide2(s.oracle, s.grid, s.nodes, owned);
  EXPECT_EQ(t.unresolved, 0);
  EXPECT_EQ(t.collapsed, 0);
  Soup2 out;
  out.points = s.nodes.position;
  out.points.insert(out.points.end(), t.extra_points.begin(), t.extra_points.end());
  out.triangles = t.triangles;
  out.phase.assign(t.phase.begin(), t.phase.end());
  return out;
}

double area(const Soup2& m, std::size_t t) {
  const auto p = [&](int k) { return m.points[static_cast<std::size_t>(m.triangles[3 * t + static_cast<std::size_t>(k)])]; };
  return mesh::signed_area(p(0), p(1), p(2));
}

// Triangles that are not positive, or whose vertices or centroid are not in their phase.
struct PhaseCheck {
  std::size_t non_positive = 0, vertex_outside = 0, centroid_elsewhere = 0;
  bool ok() const { return non_positive == 0 && vertex_outside == 0 && centroid_elsewhere == 0; }
};

// `radius`: the smallest radius of curvature of the scene's interfaces (0: straight). A
// triangle with its vertices outside a disc of that radius meets it only within circular
// segments cut off by its edges, so its centroid lies within the sagitta of its longest
// edge of its phase; with straight interfaces, in its phase.
PhaseCheck check_phases(const testing::Stage2& s, const Soup2& m, double radius) {
  PhaseCheck c;
  const auto all = testing::all_inclusions(s.oracle);
  for (std::size_t t = 0; t < m.phase.size(); ++t) {
    const int phase = m.phase[t];
    if (!(area(m, t) > 0)) ++c.non_positive;
    Vec2 centroid{0, 0};
    for (int k = 0; k < 3; ++k) {
      const Vec2& p = m.points[static_cast<std::size_t>(m.triangles[3 * t + static_cast<std::size_t>(k)])];
      if (s.oracle.distance_to_phase(p, phase) > 1e-12) ++c.vertex_outside;
      centroid[0] += p[0] / 3, centroid[1] += p[1] / 3;
    }
    if (s.oracle.phase_at(centroid, all) == phase) continue;
    // Off a curved interface by the sagitta of its longest edge at most (see scenes below).
    double longest = 0;
    for (int k = 0; k < 3; ++k)
      longest = std::max(longest, mesh::distance<2>(m.points[static_cast<std::size_t>(m.triangles[3 * t + static_cast<std::size_t>(k)])],
                                                    m.points[static_cast<std::size_t>(m.triangles[3 * t + static_cast<std::size_t>((k + 1) % 3)])]));
    const double sagitta = radius > 0 && longest < 2 * radius ? radius - std::sqrt(radius * radius - longest * longest / 4) : 0;
    if (s.oracle.distance_to_phase(centroid, phase) > sagitta) ++c.centroid_elsewhere;
  }
  return c;
}

// Σ area of the triangles − Σ area of the leaves of coarse cell (ci, cj), the leaves taken
// as the quads of their (maybe snapped) corners.
double cover_error(const testing::Stage2& s, const Soup2& m, std::int64_t ci, std::int64_t cj) {
  double triangles = 0, leaves = 0;
  for (std::size_t t = 0; t < m.phase.size(); ++t) triangles += area(m, t);
  const auto& f = s.grid.forest;
  for (std::int32_t c = 0; c < static_cast<std::int32_t>(f.size()); ++c) {
    const auto& cell = f.cell(c);
    if (!f.is_leaf(c) || (cell.i >> cell.level) != ci || (cell.j >> cell.level) != cj) continue;
    const auto& ids = s.nodes.cell_corners[static_cast<std::size_t>(c)];
    const auto p = [&](int k) { return s.nodes.position[static_cast<std::size_t>(ids[static_cast<std::size_t>(k)])]; };
    leaves += mesh::signed_area(p(0), p(1), p(2)) + mesh::signed_area(p(0), p(2), p(3));
  }
  return triangles - leaves;
}

testing::Conformity conformity(const SceneDesc& scene, const Soup2& m) {
  return testing::check_conformity<2>(m.triangles, [&](const std::array<std::int32_t, 2>& e) {
    return testing::on_box_face<2>(std::array{m.points[static_cast<std::size_t>(e[0])], m.points[static_cast<std::size_t>(e[1])]},
                                   scene.domain_min, scene.domain_max);
  });
}

// Scenes in a 6 × 4 or 8 × 6 box, with levels = 0 (every leaf a coarse cell) or 1 (closures of
// hanging nodes too): a straight interface (a polygon whose only edge inside the box runs
// from (0, 3) to (6, 1.05)), or two circles (radius 0.9 and 1.14).
struct Scene2 {
  SceneDesc scene;
  double radius = 0;  // smallest radius of curvature, 0: straight
};

Scene2 straight(int levels) {
  SceneDesc s = testing::box_scene(2, {0, 0, 0}, {6, 4, 0}, 1.0, levels);
  s.inclusions = {{geometry::Polygon{{{-1, -1}, {7, -1}, {7, 0.725}, {-1, 3.325}}}, 2, levels}};
  return {s, 0};
}

Scene2 circles(int levels) {
  SceneDesc s = testing::box_scene(2, {0, 0, 0}, {8, 6, 0}, 1.0, levels);
  s.inclusions = {{geometry::Circle{{1.93, 2.08}, 1.14}, 2, levels}, {geometry::Circle{{4.4, 1.9}, 0.9}, 2, levels}};
  return {s, 0.9};
}

std::vector<Scene2> scenes2() { return {straight(0), straight(1), circles(0), circles(1)}; }

TEST(Subdivide2, EachCellIsCoveredByPositiveTrianglesOfItsPhase) {
  for (const Scene2& sc : scenes2()) {
    const int levels = sc.scene.levels;
    SCOPED_TRACE("levels " + std::to_string(levels) + ", radius " + std::to_string(sc.radius));
    const testing::Stage2 s(sc.scene);
    std::int64_t cut = 0, double_diagonal = 0, hanging = 0;
    for (std::int64_t cj = 0; cj < s.lattice.coarse_cells[1]; ++cj)
      for (std::int64_t ci = 0; ci < s.lattice.coarse_cells[0]; ++ci) {
        SCOPED_TRACE("cell " + std::to_string(ci) + ", " + std::to_string(cj));
        const grid::CellRange<2> owned{{ci, cj}, {ci + 1, cj + 1}};
        const Soup2 m = subdivide(s, owned);
        EXPECT_NEAR(cover_error(s, m, ci, cj), 0.0, 1e-13);
        const PhaseCheck c = check_phases(s, m, sc.radius);
        EXPECT_TRUE(c.ok()) << c.non_positive << " not positive, " << c.vertex_outside << " vertices outside, "
                            << c.centroid_elsewhere << " centroids elsewhere";
        const auto t = subdivide::subdivide2(s.oracle, s.grid, s.nodes, owned);
        cut += t.cut_quads, double_diagonal += t.double_diagonal, hanging += t.hanging_cells;
      }
    EXPECT_GT(s.nodes.snapped_count, 4);
    if (levels == 1) {
      EXPECT_GT(hanging, 0);
    }
    std::printf("[subdivide2] levels %d, radius %.2f: %lld snapped nodes, %lld cut quads, %lld double diagonals, "
                "%lld closed cells\n", levels, sc.radius, static_cast<long long>(s.nodes.snapped_count),
                static_cast<long long>(cut), static_cast<long long>(double_diagonal), static_cast<long long>(hanging));
  }
}

// The whole domain at once, and the union of the cell-by-cell runs (extra points are
// interior to their cell, so lattice node ids suffice): every interior edge shared by two
// triangles with opposite orientations, no hanging node left, the box covered.
TEST(Subdivide2, ConformsAcrossCellsAndClosesHangingNodes) {
  for (const Scene2& sc : scenes2()) {
    SCOPED_TRACE("levels " + std::to_string(sc.scene.levels) + ", radius " + std::to_string(sc.radius));
    const SceneDesc& scene = sc.scene;
    const testing::Stage2 s(scene);
    const Soup2 whole = subdivide(s, s.lattice.whole_domain());
    const auto c = conformity(scene, whole);
    EXPECT_TRUE(c.ok()) << c.unmatched << " unmatched, " << c.same_orientation << " same orientation, " << c.over_used
                        << " over used";
    double total = 0;
    for (std::size_t t = 0; t < whole.phase.size(); ++t) total += area(whole, t);
    EXPECT_NEAR(total, (scene.domain_max[0] - scene.domain_min[0]) * (scene.domain_max[1] - scene.domain_min[1]), 1e-12);

    Soup2 joined;
    joined.points = s.nodes.position;
    for (std::int64_t cj = 0; cj < s.lattice.coarse_cells[1]; ++cj)
      for (std::int64_t ci = 0; ci < s.lattice.coarse_cells[0]; ++ci) {
        const Soup2 m = subdivide(s, {{ci, cj}, {ci + 1, cj + 1}});
        const auto base = static_cast<std::int32_t>(joined.points.size()) - static_cast<std::int32_t>(s.nodes.key.size());
        for (std::int32_t id : m.triangles)
          joined.triangles.push_back(id < static_cast<std::int32_t>(s.nodes.key.size()) ? id : id + base);
        joined.points.insert(joined.points.end(), m.points.begin() + static_cast<std::ptrdiff_t>(s.nodes.key.size()),
                             m.points.end());
        joined.phase.insert(joined.phase.end(), m.phase.begin(), m.phase.end());
      }
    EXPECT_EQ(joined.phase.size(), whole.phase.size());
    EXPECT_TRUE(conformity(scene, joined).ok());
  }
}

// The checks catch what they are for: a dropped triangle (cover, conformity), a triangle
// given the other phase, and a hanging node (a unit square split through the midpoint of
// the edge it shares with an unsplit neighbour).
TEST(Subdivide2, ChecksCatchBrokenOutput) {
  const SceneDesc scene = straight(0).scene;
  const testing::Stage2 s(scene);
  Soup2 m = subdivide(s, {{2, 2}, {3, 3}});  // a cell the line crosses
  ASSERT_TRUE(check_phases(s, m, 0).ok());
  ASSERT_GE(m.phase.size(), 2u);
  Soup2 relabelled = m;
  relabelled.phase[0] = 1 - relabelled.phase[0];
  EXPECT_FALSE(check_phases(s, relabelled, 0).ok());
  Soup2 dropped = m;
  dropped.triangles.resize(dropped.triangles.size() - 3);
  dropped.phase.pop_back();
  EXPECT_GT(std::abs(cover_error(s, dropped, 2, 2)), 1e-3);

  Soup2 hanging;
  hanging.points = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {2, 0}, {2, 1}, {1, 0.5}};
  hanging.triangles = {0, 1, 2, 0, 2, 3,              // left square, whole
                       1, 4, 6, 4, 5, 6, 6, 5, 2};    // right square, through (1, 0.5)
  SceneDesc box = scene;
  box.domain_max = {2, 1, 0};
  const auto c = conformity(box, hanging);
  EXPECT_FALSE(c.ok());
  EXPECT_GT(c.unmatched, 0u);
}

}  // namespace
}  // namespace cisamr
