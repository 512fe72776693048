#pragma once
// The TetGen 1.5 reference mesher (for comparison only, DESIGN.md §1: TetGen is never
// the product's mesh). Builds a piecewise linear complex from a scene of spheres and
// ellipsoids: the domain box's 6 faces plus every inclusion as a closed triangulated
// surface (a geodesic icosphere, vertices on the exact surface), one region seed per
// inclusion and one for the matrix, then runs `tetrahedralize` with -pq<ratio>a<volume>AQ.
// TetGen headers stay inside tetgen_mesh.cpp.
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "geometry/scene.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::compare {

struct TetgenOptions {
  double radius_edge_ratio = 1.4;  // -q: TetGen's quality bound (radius-edge ratio)
  double max_volume = 0;           // -a: largest tetrahedron volume; <= 0: no constraint
  // Target edge length of the inclusion surfaces; <= 0: the scene's finest interface
  // size h / 2^levels (what our mesher puts on the interfaces).
  double surface_edge = 0;
  int min_frequency = 2;           // geodesic subdivisions per icosahedron edge, at least
  std::string extra_switches;      // appended to the switches (e.g. "V" for statistics)
  // Called right after tetrahedralize returns, before its output is copied into the Mesh3
  // (the benchmark reads the peak memory there). Optional.
  std::function<void()> on_tetrahedralized;
};

struct TetgenMesh {
  mesh::Mesh3 mesh;                       // positively oriented, cell_phase = phase id
  std::vector<std::int32_t> cell_region;  // per tet: inclusion index, -1 for the matrix
  std::int64_t surface_points = 0, surface_triangles = 0;  // size of the input PLC
  std::string switches;                   // what tetrahedralize was given
  double plc_seconds = 0;                 // building the surfaces and region seeds
  double tetgen_seconds = 0;              // tetrahedralize itself
  double copy_seconds = 0;                // TetGen's output into the Mesh3
};

// The polyhedral surface of one sphere or ellipsoid: a geodesic icosphere of `frequency`
// subdivisions per icosahedron edge (10·f²+2 points, 20·f² outward-oriented triangles),
// every vertex on the exact surface, so the polyhedron is inscribed.
struct Surface {
  std::vector<Vec3> points;
  std::vector<std::array<std::int32_t, 3>> triangles;
};
Surface inclusion_surface(const geometry::Shape& shape, int frequency);

// The geodesic frequency giving edges of about `edge` on a shape of largest radius
// `radius` (at least min_frequency).
int geodesic_frequency(double radius, double edge, int min_frequency);

// Throws InputError naming the field unless the scene is one TetGen can mesh here:
// 3D, not periodic, spheres and ellipsoids strictly inside the domain, disjoint spheres.
void check_tetgen_scene(const geometry::SceneDesc& scene);

// Meshes the scene with TetGen. Supported: 3D scenes whose inclusions are spheres and
// ellipsoids strictly inside the domain, not overlapping (periodic scenes are not).
// Void phases become TetGen holes. Throws InputError(scene.source, "inclusions[i]...", ...)
// for anything else, and std::runtime_error when TetGen stops with an error code.
TetgenMesh mesh_scene_with_tetgen(const geometry::SceneDesc& scene, const TetgenOptions& options);

}  // namespace cisamr::compare
