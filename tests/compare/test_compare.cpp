// The TetGen reference and the comparison (lib/compare): surfaces, PLC, regions, volumes,
// and the side-by-side comparison on a small scene.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <utility>

#include "core/error.hpp"
#include "mesh/metrics.hpp"
#include "quality/quality.hpp"
#include "compare/compare3.hpp"
#include "compare/tetgen_mesh.hpp"

using namespace cisamr;
using namespace cisamr::compare;

namespace {

geometry::SceneDesc unit_cube_scene() {
  geometry::SceneDesc s;
  s.source = "test.json";
  s.dimension = 3;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1, 1, 1};
  s.h = 0.1;
  s.levels = 1;
  s.phases = {{1, "matrix", false}, {2, "sphere", false}, {3, "grain", false}};
  s.matrix_phase = 1;
  return s;
}

geometry::SceneDesc three_inclusions() {
  geometry::SceneDesc s = unit_cube_scene();
  s.inclusions.push_back({geometry::Sphere{{0.3, 0.3, 0.3}, 0.2}, 2, 1});
  s.inclusions.push_back({geometry::Sphere{{0.72, 0.7, 0.68}, 0.15}, 2, 1});
  // Rotated 30° about z.
  const double c = std::cos(M_PI / 6), n = std::sin(M_PI / 6);
  s.inclusions.push_back(
      {geometry::Ellipsoid{{0.7, 0.25, 0.5}, {0.18, 0.09, 0.07}, {{{c, -n, 0}, {n, c, 0}, {0, 0, 1}}}}, 3, 1});
  return s;
}

double sphere_volume(double r) { return 4.0 / 3.0 * M_PI * r * r * r; }

}  // namespace

TEST(InclusionSurface, GeodesicSphereIsClosedOutwardAndOnTheSurface) {
  for (int f : {1, 2, 5}) {
    const Surface s = inclusion_surface(geometry::Sphere{{1, 2, 3}, 0.5}, f);
    EXPECT_EQ(s.points.size(), static_cast<std::size_t>(10 * f * f + 2));
    EXPECT_EQ(s.triangles.size(), static_cast<std::size_t>(20 * f * f));
    for (const Vec3& p : s.points) EXPECT_NEAR(mesh::distance<3>(p, Vec3{1, 2, 3}), 0.5, 1e-12);
    // Closed and consistently oriented: each directed edge once, its reverse once.
    std::map<std::pair<int, int>, int> directed;
    double volume = 0;
    for (const auto& t : s.triangles) {
      for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
      volume += mesh::signed_volume(Vec3{1, 2, 3}, s.points[t[0]], s.points[t[1]], s.points[t[2]]);
    }
    for (const auto& [edge, count] : directed) {
      EXPECT_EQ(count, 1);
      EXPECT_EQ(directed.count({edge.second, edge.first}), 1u);
    }
    // Outward and inscribed: positive, below the ball's volume, approaching it with f.
    EXPECT_GT(volume, 0);
    EXPECT_LT(volume, sphere_volume(0.5));
    if (f == 5) {
      EXPECT_GT(volume, 0.96 * sphere_volume(0.5));
    }
  }
  EXPECT_EQ(geodesic_frequency(0.05, 0.01, 2), 6);  // ceil(1.0515 · 5)
  EXPECT_EQ(geodesic_frequency(0.05, 1.0, 2), 2);   // the minimum
}

TEST(TetgenMesh, ConformingWithRegionVolumesNearTheExactOnes) {
  const geometry::SceneDesc scene = three_inclusions();
  TetgenOptions options;
  options.max_volume = 2e-4;
  options.surface_edge = 0.03;
  const TetgenMesh t = mesh_scene_with_tetgen(scene, options);
  const mesh::Mesh3& m = t.mesh;
  ASSERT_GT(m.cell_count(), 5000u);
  EXPECT_EQ(t.switches, "pq1.4a0.0002AQ");

  const quality::ConformityReport cr = quality::check_conformity<3>(m, Box<3>{{0, 0, 0}, {1, 1, 1}}, 1.0, false);
  EXPECT_TRUE(cr.ok) << (cr.examples.empty() ? "" : cr.examples[0]);
  EXPECT_EQ(cr.inverted_cells, 0u);

  std::vector<double> region_volume(scene.inclusions.size(), 0.0);
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    const LocalId* n = m.cell(c);
    const double v = mesh::signed_volume(m.point(n[0]), m.point(n[1]), m.point(n[2]), m.point(n[3]));
    EXPECT_GT(v, 0);
    const int region = t.cell_region[c];
    ASSERT_GE(region, -1);
    ASSERT_LT(region, 3);
    EXPECT_EQ(m.cell_phase[c], region < 0 ? 1 : scene.inclusions[static_cast<std::size_t>(region)].phase);
    if (region < 0) continue;
    region_volume[static_cast<std::size_t>(region)] += v;
    // Nodes of an inclusion's tets lie in its closed sphere (checked for the spheres).
    if (const auto* s = std::get_if<geometry::Sphere>(&scene.inclusions[static_cast<std::size_t>(region)].shape)) {
      for (int k = 0; k < 4; ++k) EXPECT_LE(mesh::distance<3>(m.point(n[k]), s->center), s->radius * (1 + 1e-9));
    }
  }
  const double exact[3] = {sphere_volume(0.2), sphere_volume(0.15), 4.0 / 3.0 * M_PI * 0.18 * 0.09 * 0.07};
  for (int i = 0; i < 3; ++i) {
    const double error = (region_volume[i] - exact[i]) / exact[i];
    EXPECT_LT(error, 0) << "inscribed surfaces lose volume, inclusion " << i;
    EXPECT_GT(error, -0.03) << "inclusion " << i;
  }

  // The comparison's measurement assigns tets by centroid: the same volumes.
  const MesherReport r = measure_mesh(m, scene, true);
  EXPECT_TRUE(r.conforming);
  EXPECT_EQ(r.tets_outside_inclusions, 0);
  EXPECT_EQ(r.inclusions_measured, 3);
  double worst = 0;
  for (int i = 0; i < 3; ++i) worst = std::max(worst, std::abs(region_volume[i] - exact[i]) / exact[i]);
  EXPECT_NEAR(std::abs(r.inclusion_error_worst), worst, 1e-12);
  EXPECT_LT(r.inclusion_error_worst, 0);
  std::int64_t binned = 0;
  for (std::int64_t b : r.aspect_bins) binned += b;
  EXPECT_EQ(binned, r.tets);
  EXPECT_GE(r.aspect_max, 1.0);
  EXPECT_GT(r.min_dihedral_deg, 0.0);
  EXPECT_LT(r.max_dihedral_deg, 180.0);
}

TEST(TetgenMesh, VoidInclusionsAreHoles) {
  geometry::SceneDesc scene = unit_cube_scene();
  scene.phases[1].is_void = true;
  scene.inclusions.push_back({geometry::Sphere{{0.5, 0.5, 0.5}, 0.25}, 2, 1});
  TetgenOptions options;
  options.max_volume = 1e-3;
  const TetgenMesh t = mesh_scene_with_tetgen(scene, options);
  double volume = 0;
  for (std::size_t c = 0; c < t.mesh.cell_count(); ++c) {
    EXPECT_EQ(t.mesh.cell_phase[c], 1);
    const LocalId* n = t.mesh.cell(c);
    volume += mesh::signed_volume(t.mesh.point(n[0]), t.mesh.point(n[1]), t.mesh.point(n[2]), t.mesh.point(n[3]));
  }
  const double hole = sphere_volume(0.25);
  EXPECT_GT(volume, 1 - hole);  // the inscribed hole is smaller than the ball
  EXPECT_LT(volume, 1 - 0.95 * hole);
}

TEST(TetgenMesh, RefusesWhatItCannotMesh) {
  const auto field_of = [](const geometry::SceneDesc& s) {
    try {
      check_tetgen_scene(s);
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "test.json");
      return e.field();
    }
    return std::string("accepted");
  };
  geometry::SceneDesc two_d = unit_cube_scene();
  two_d.dimension = 2;
  EXPECT_EQ(field_of(two_d), "dimension");

  geometry::SceneDesc overlap = unit_cube_scene();
  overlap.inclusions.push_back({geometry::Sphere{{0.3, 0.5, 0.5}, 0.2}, 2, 1});
  overlap.inclusions.push_back({geometry::Sphere{{0.6, 0.5, 0.5}, 0.15}, 2, 1});
  EXPECT_EQ(field_of(overlap), "inclusions[1]");
  overlap.inclusions[1].shape = geometry::Sphere{{0.6, 0.5, 0.5}, 0.09};
  EXPECT_EQ(field_of(overlap), "accepted");

  geometry::SceneDesc touching = unit_cube_scene();
  touching.inclusions.push_back({geometry::Sphere{{0.9, 0.5, 0.5}, 0.1}, 2, 1});
  EXPECT_EQ(field_of(touching), "inclusions[0]");

  geometry::SceneDesc cylinder = unit_cube_scene();
  cylinder.inclusions.push_back({geometry::Cylinder{{0.2, 0.5, 0.5}, {0.8, 0.5, 0.5}, 0.1}, 2, 1});
  EXPECT_EQ(field_of(cylinder), "inclusions[0].shape");
}

TEST(Compare3, BothMeshersMeasuredInChildProcesses) {
  geometry::SceneDesc scene = unit_cube_scene();
  scene.inclusions.push_back({geometry::Sphere{{0.35, 0.4, 0.45}, 0.2}, 2, 1});
  scene.inclusions.push_back({geometry::Sphere{{0.75, 0.7, 0.7}, 0.15}, 2, 1});
  CompareOptions options;
  const Comparison c = compare3(scene, options);
  ASSERT_TRUE(c.has_tetgen);
  for (const MesherReport* r : {&c.ours, &c.tetgen}) {
    EXPECT_TRUE(r->isolated);
    EXPECT_GT(r->tets, 1000);
    EXPECT_GT(r->seconds, 0);
    EXPECT_TRUE(r->conformity_checked);
    EXPECT_TRUE(r->conforming) << r->name << ": " << r->conformity_problems;
    EXPECT_EQ(r->inclusions_measured, 2);
    EXPECT_LT(std::abs(r->inclusion_error_worst), 0.1) << r->name;
    EXPECT_LT(r->inclusion_error_worst, 0) << r->name << ": inscribed surfaces lose volume";
    ASSERT_EQ(r->phases.size(), 3u);
    EXPECT_NEAR(r->phases[0].exact, 1 - sphere_volume(0.2) - sphere_volume(0.15), 1e-12);
  }
  // -a matched to our count by measured runs: the reported run is the last one, within
  // the tolerance (or the closest after match_runs runs).
  ASSERT_FALSE(c.tetgen_matching.empty());
  EXPECT_LE(static_cast<int>(c.tetgen_matching.size()), options.match_runs);
  EXPECT_GT(c.tetgen.tets, c.ours.tets * 3 / 4);
  EXPECT_LT(c.tetgen.tets, c.ours.tets * 5 / 4);
  std::int64_t closest = c.tetgen_matching[0].tets;
  for (const MatchingRun& m : c.tetgen_matching)
    if (std::abs(m.tets - c.ours.tets) < std::abs(closest - c.ours.tets)) closest = m.tets;
  EXPECT_EQ(c.tetgen.tets, closest);
  ASSERT_EQ(c.ours.run_seconds.size(), 1u);
  ASSERT_EQ(c.tetgen.run_seconds.size(), 1u);
  EXPECT_NE(comparison_table(c).find("TetGen"), std::string::npos);
  EXPECT_NE(comparison_json(c).find("\"cisamr-compare/1\""), std::string::npos);
}
