// Phase fidelity against the 2D and 3D oracles, and certification against a scene.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <utility>

#include "geometry/oracle.hpp"
#include "geometry/scene.hpp"
#include "mesh_builders.hpp"
#include "scene_builders.hpp"
#include "quality/certificate.hpp"
#include "quality/quality.hpp"

namespace cisamr::quality {
namespace {
using namespace testing;


TEST(Fidelity, ConformingSquareInclusionPasses) {
  const geometry::Oracle2 oracle(square_scene(false));
  const mesh::Mesh2 m = square_mesh();
  const auto f = check_fidelity(m, oracle, 1e-9);
  EXPECT_TRUE(f.ok);
  EXPECT_EQ(f.nodes_off_phase, 0u);
  EXPECT_EQ(f.interface_nodes_off_interface, 0u);
  EXPECT_EQ(f.boundary_nodes_off_void, 0u);
  EXPECT_EQ(f.max_deviation, 0.0);
  ASSERT_EQ(f.phase_measure.size(), 2u);
  EXPECT_NEAR(f.phase_measure[0], 0.75, 1e-14);
  EXPECT_NEAR(f.phase_measure[1], 0.25, 1e-14);
  EXPECT_NEAR(f.exact_phase_measure[1], 0.25, 1e-12);
  EXPECT_LT(f.relative_error[0], 1e-12);
  EXPECT_LT(f.relative_error[1], 1e-12);
}

TEST(Fidelity, CellsOfTheWrongPhaseAreCaught) {
  const geometry::Oracle2 oracle(square_scene(false));
  mesh::Mesh2 m = square_mesh();
  m.cell_phase[0] = m.cell_phase[1] = 2;  // the corner square [0,0.25]²
  const auto f = check_fidelity(m, oracle, 1e-9);
  EXPECT_FALSE(f.ok);
  EXPECT_EQ(f.nodes_off_phase, 1u);                // (0,0): only phase-2 cells around it
  EXPECT_EQ(f.interface_nodes_off_interface, 2u);  // (0.25,0) and (0,0.25)
  EXPECT_NEAR(f.max_deviation, 0.25 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(f.relative_error[1], 0.25, 1e-12);  // 0.3125 meshed for 0.25
  EXPECT_FALSE(f.examples.empty());
}

TEST(Fidelity, InterfaceNodeOffByMoreThanTheTolerance) {
  const geometry::Oracle2 oracle(square_scene(false));
  mesh::Mesh2 m = square_mesh();
  const std::size_t node = 2 * 5 + 1;  // (0.25, 0.5), on the square's left side
  ASSERT_EQ(m.point(LocalId(node))[0], 0.25);
  ASSERT_EQ(m.point(LocalId(node))[1], 0.5);
  const double tol = default_fidelity_tolerance(oracle.scene());
  EXPECT_NEAR(tol, 1e-9 * std::sqrt(2.0), 1e-20);

  m.coords[2 * node] = 0.25 + 1e-12;  // within the tolerance
  EXPECT_TRUE(check_fidelity(m, oracle, tol).ok);
  m.coords[2 * node] = 0.25 + 1e-6;   // into the square: 1e-6 from the matrix
  const auto f = check_fidelity(m, oracle, tol);
  EXPECT_FALSE(f.ok);
  EXPECT_EQ(f.interface_nodes_off_interface, 1u);
  EXPECT_EQ(f.nodes_off_phase, 0u);
  EXPECT_NEAR(f.max_deviation, 1e-6, 1e-12);
}

TEST(Fidelity, VoidBoundaryMustLieOnTheVoid) {
  const geometry::Oracle2 oracle(square_scene(true));
  const mesh::Mesh2 full = square_mesh();
  const mesh::Mesh2 m = filtered(full, [&](std::size_t c) { return full.cell_phase[c] == 1; });
  const auto f = check_fidelity(m, oracle, 1e-9);
  EXPECT_TRUE(f.ok);
  EXPECT_TRUE(f.phase_is_void[1]);
  EXPECT_TRUE(std::isnan(f.relative_error[1]));
  EXPECT_NEAR(f.phase_measure[0], 0.75, 1e-14);

  // A hole in the matrix looks like a void boundary to the conformity check; here it is
  // caught: (0.25, 0) and (0, 0.25) are far from the void.
  const mesh::Mesh2 holed = filtered(full, [&](std::size_t c) { return full.cell_phase[c] == 1 && c > 1; });
  const auto h = check_fidelity(holed, oracle, 1e-9);
  EXPECT_FALSE(h.ok);
  EXPECT_EQ(h.boundary_nodes_off_void, 2u);
  EXPECT_TRUE(check_conformity<2>(holed, Box2{{0, 0}, {1, 1}}, 0.75, true, 0.1).ok);
}

TEST(Fidelity, UnknownPhaseIdIsReported) {
  const geometry::Oracle2 oracle(square_scene(false));
  mesh::Mesh2 m = square_mesh();
  m.cell_phase[5] = 9;
  const auto f = check_fidelity(m, oracle, 1e-9);
  EXPECT_FALSE(f.ok);
  EXPECT_EQ(f.cells_unknown_phase, 1u);
}

TEST(CertifyWithScene, SquareInclusionAndVoid) {
  {
    const geometry::Oracle2 oracle(square_scene(false));
    const Certificate c = certify(square_mesh(), oracle, CertifyOptions{});
    EXPECT_TRUE(c.passed());
    ASSERT_TRUE(c.fidelity.has_value());
    EXPECT_TRUE(c.domain_from_scene);
    EXPECT_NEAR(c.conformity.expected_measure, 1.0, 1e-14);
    EXPECT_EQ(c.scene_source, "square-scene.json");
    const auto j = nlohmann::json::parse(certificate_json(c));
    EXPECT_EQ(j["fidelity"]["ok"], true);
    EXPECT_EQ(j["fidelity"]["phases"][1]["name"], "square");
    EXPECT_NE(certificate_html(c).find("Phase fidelity"), std::string::npos);
    EXPECT_NE(certificate_summary(c).find("fidelity: ok"), std::string::npos);
  }
  {
    const geometry::Oracle2 oracle(square_scene(true));
    const mesh::Mesh2 full = square_mesh();
    const mesh::Mesh2 m = filtered(full, [&](std::size_t c) { return full.cell_phase[c] == 1; });
    const Certificate c = certify(m, oracle, CertifyOptions{});
    EXPECT_TRUE(c.passed());
    EXPECT_NEAR(c.conformity.expected_measure, 0.75, 1e-12);
    EXPECT_EQ(c.conformity.inner_boundary_facets, 8u);
    const mesh::Mesh2 holed = filtered(full, [&](std::size_t c) { return full.cell_phase[c] == 1 && c > 1; });
    const Certificate h = certify(holed, oracle, CertifyOptions{});
    EXPECT_FALSE(h.passed());
    EXPECT_FALSE(h.fidelity->ok);
  }
}

TEST(Fidelity3, ConformingCubeInclusionPasses) {
  const geometry::Oracle3 oracle(cube_scene(false));
  const auto f = check_fidelity(cube_mesh(), oracle, 1e-9);
  EXPECT_TRUE(f.ok);
  EXPECT_TRUE(f.centroids_checked);
  EXPECT_EQ(f.cells_off_phase, 0u);
  EXPECT_EQ(f.max_centroid_ratio, 0.0);
  EXPECT_EQ(f.max_deviation, 0.0);
  ASSERT_EQ(f.phase_measure.size(), 2u);
  EXPECT_NEAR(f.phase_measure[1], 64.0, 1e-12);
  EXPECT_NEAR(f.exact_phase_measure[1], 64.0, 1e-12);
  EXPECT_NEAR(f.phase_measure[0], 216.0 - 64.0, 1e-12);
}

TEST(Fidelity3, CellDeepInsideAnotherPhaseFails) {
  const geometry::Oracle3 oracle(cube_scene(false));
  mesh::Mesh3 m = cube_mesh();
  std::size_t deep = m.cell_count();
  for (std::size_t c = 0; c < m.cell_count() && deep == m.cell_count(); ++c) {
    const Vec3 g = centroid(m, c);
    if (g[0] > 2 && g[0] < 3 && g[1] > 2 && g[1] < 3 && g[2] > 2 && g[2] < 3) deep = c;
  }
  ASSERT_LT(deep, m.cell_count());
  m.cell_phase[deep] = 1;  // matrix, 1.5 below the cube's surface
  const auto f = check_fidelity(m, oracle, 1e-9);
  EXPECT_FALSE(f.ok);
  EXPECT_EQ(f.cells_wrong_phase, 1u);
  EXPECT_EQ(f.cells_off_phase, 1u);
  EXPECT_GT(f.max_centroid_ratio, kWrongPhaseRatio);
  EXPECT_GT(f.nodes_off_phase + f.interface_nodes_off_interface, 0u);
}

TEST(Fidelity3, TwoDimensionalCheckHasNoCentroidCheck) {
  const geometry::Oracle2 oracle(square_scene(false));
  EXPECT_FALSE(check_fidelity(square_mesh(), oracle, 1e-9).centroids_checked);
}

TEST(CertifyWithScene, CubeInclusionAndVoid) {
  {
    const geometry::Oracle3 oracle(cube_scene(false));
    const Certificate c = certify(cube_mesh(), oracle, CertifyOptions{});
    EXPECT_TRUE(c.passed());
    EXPECT_EQ(c.dimension, 3);
    EXPECT_NEAR(c.conformity.expected_measure, 216.0, 1e-12);
    const auto j = nlohmann::json::parse(certificate_json(c));
    EXPECT_EQ(j["fidelity"]["ok"], true);
    EXPECT_EQ(j["fidelity"]["cells_wrong_phase"], 0);
    EXPECT_TRUE(j["fidelity"].contains("max_centroid_ratio"));
    EXPECT_EQ(j["fidelity"]["phases"][1]["name"], "cube");
    EXPECT_NE(certificate_summary(c).find("phase 2 (cube): volume 64"), std::string::npos);
  }
  {
    const geometry::Oracle3 oracle(cube_scene(true));
    const mesh::Mesh3 full = cube_mesh();
    const mesh::Mesh3 m = filtered(full, [&](std::size_t c) { return full.cell_phase[c] == 1; });
    const Certificate c = certify(m, oracle, CertifyOptions{});
    EXPECT_TRUE(c.passed());
    EXPECT_NEAR(c.conformity.expected_measure, 216.0 - 64.0, 1e-12);
    EXPECT_EQ(c.conformity.inner_boundary_facets, 6u * 16u * 2u);
    ASSERT_FALSE(c.notes.empty());
    EXPECT_NE(c.notes.back().find("total volume checked to 0.05 only (void boundaries are polyhedral)"),
              std::string::npos);
    const mesh::Mesh3 holed = filtered(full, [&](std::size_t c) { return full.cell_phase[c] == 1 && c > 1; });
    const Certificate h = certify(holed, oracle, CertifyOptions{});
    EXPECT_FALSE(h.passed());
    EXPECT_FALSE(h.fidelity->ok);
    EXPECT_GT(h.fidelity->boundary_nodes_off_void, 0u);
  }
}

}  // namespace
}  // namespace cisamr::quality
