// The picture of a 3D mesh is a true slice: the cross-sections of the tetrahedra tile the
// plane's square once, and each phase's area is the sphere's section (within the mesh's
// approximation of the sphere).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "core/error.hpp"
#include "geometry/oracle.hpp"
#include "io/mesh_svg.hpp"
#include "pipeline/pipeline.hpp"

namespace {

using namespace cisamr;

geometry::SceneDesc sphere_scene() {
  geometry::SceneDesc s;
  s.dimension = 3;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1, 1, 1};
  s.h = 0.05;
  s.levels = 1;
  s.phases = {{1, "matrix", false}, {2, "sphere", false}};
  s.inclusions = {{geometry::Sphere{{0.5, 0.5, 0.5}, 0.3}, 2, 1}};
  return s;
}

// Area per phase id (1, 2) of the slice polygons.
std::array<double, 3> areas(const io::SlicePolygons& slice) {
  std::array<double, 3> area{};
  for (std::size_t i = 0; i < slice.size(); ++i) {
    double twice = 0;
    const std::size_t first = slice.offsets[i], last = slice.offsets[i + 1];
    for (std::size_t k = first; k < last; ++k) {
      const Vec2& a = slice.points[k];
      const Vec2& b = slice.points[k + 1 < last ? k + 1 : first];
      twice += a[0] * b[1] - a[1] * b[0];
    }
    EXPECT_GE(twice, 0) << "polygon " << i << " is not counter-clockwise";
    area[static_cast<std::size_t>(slice.phase[i])] += twice / 2;
  }
  return area;
}

TEST(MeshSvg, SliceOfASphereSceneHasThePlanesPhaseAreas) {
  const geometry::SceneDesc scene = sphere_scene();
  const geometry::Oracle3 oracle(scene);
  const mesh::Mesh3 mesh = pipeline::mesh(oracle).mesh;
  // z = 0.5 lies on lattice faces (each face drawn once, by the tetrahedron below it); the
  // others cut tetrahedra through their interiors, along each axis.
  for (const auto& [axis, at] : {std::pair{2, 0.5}, std::pair{2, 0.61}, std::pair{0, 0.37}, std::pair{1, 0.72}}) {
    SCOPED_TRACE(std::to_string(axis) + " at " + std::to_string(at));
    const io::SlicePolygons slice = io::slice_mesh(mesh, axis, at);
    ASSERT_GT(slice.size(), 0u);
    const std::array<double, 3> area = areas(slice);
    const double d = at - 0.5, section = M_PI * (0.3 * 0.3 - d * d);
    EXPECT_NEAR(area[1] + area[2], 1.0, 1e-9) << "the square is not tiled once";
    EXPECT_NEAR(area[2], section, 0.02 * section);
    EXPECT_NEAR(area[1], 1 - section, 0.02 * section);
  }
}

TEST(MeshSvg, WritesTheSliceAndRefusesAPlaneOutsideTheDomain) {
  const geometry::SceneDesc scene = sphere_scene();
  const geometry::Oracle3 oracle(scene);
  const mesh::Mesh3 mesh = pipeline::mesh(oracle).mesh;
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("cisamr-slice-" + std::to_string(::getpid()) + ".svg");
  io::write_mesh_svg(path.string(), mesh, scene, io::SlicePlane{});
  std::stringstream text;
  text << std::ifstream(path).rdbuf();
  std::filesystem::remove(path);
  EXPECT_EQ(text.str().rfind("<svg", 0), 0u);
  EXPECT_NE(text.str().find("<path fill=\"#d9d9d9\""), std::string::npos);  // matrix
  EXPECT_NE(text.str().find("<path fill=\"#e6550d\""), std::string::npos);  // sphere
  EXPECT_NE(text.str().find("</svg>"), std::string::npos);
  EXPECT_THROW(io::write_mesh_svg(path.string(), mesh, scene, io::SlicePlane{.axis = 2, .at = 1.5}), InputError);
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
