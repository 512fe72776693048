#pragma once
// Scenes with one inclusion whose meshes conform to it exactly (structured grids whose
// lines run along the inclusion), for the fidelity and certificate tests.
#include <string>
#include <utility>

#include "geometry/scene.hpp"
#include "mesh_builders.hpp"

namespace cisamr::quality::testing {

// [0, size]^dimension with one inclusion of phase 2, named `name` or, when asked, a void.
inline geometry::SceneDesc one_inclusion_scene(int dimension, double size, geometry::Shape shape, const std::string& name,
                                        bool inclusion_is_void) {
  geometry::SceneDesc s;
  s.source = name + "-scene.json";
  s.dimension = dimension;
  s.domain_min = {0, 0, 0};
  s.domain_max = {size, size, dimension == 3 ? size : 0};
  s.h = dimension == 3 ? 1 : 0.25;
  s.phases = {{1, "matrix", false}, {2, inclusion_is_void ? "pore" : name, inclusion_is_void}};
  s.matrix_phase = 1;
  geometry::Inclusion inc;
  inc.shape = std::move(shape);
  inc.phase = 2;
  s.inclusions.push_back(inc);
  return s;
}

// [0,1]² with the square [0.25,0.75]² as phase 2 (a void when asked).
inline geometry::SceneDesc square_scene(bool inclusion_is_void) {
  return one_inclusion_scene(2, 1, geometry::Polygon{{{0.25, 0.25}, {0.75, 0.25}, {0.75, 0.75}, {0.25, 0.75}}},
                             "square", inclusion_is_void);
}

inline bool in_square(const Vec2& p) { return p[0] > 0.25 && p[0] < 0.75 && p[1] > 0.25 && p[1] < 0.75; }

inline Vec2 centroid(const mesh::Mesh2& m, std::size_t c) {
  Vec2 g{0, 0};
  for (int k = 0; k < 3; ++k)
    for (int d = 0; d < 2; ++d) g[d] += m.point(m.cell(c)[k])[d] / 3;
  return g;
}

// 4×4 grid of h = 0.25, phase 2 where the centroid is in the square.
inline mesh::Mesh2 square_mesh() {
  mesh::Mesh2 m = structured_triangles(4, 4, 0.25);
  for (std::size_t c = 0; c < m.cell_count(); ++c) m.cell_phase[c] = in_square(centroid(m, c)) ? 2 : 1;
  return m;
}

// [0,6]³ of unit cubes with the cube [1,5]³ as phase 2 (a void when asked), given as a
// closed surface of 12 outward triangles: the mesh conforms to it exactly.
inline geometry::SceneDesc cube_scene(bool inclusion_is_void) {
  auto corner = [](int i) { return Vec3{i & 1 ? 5.0 : 1.0, i & 2 ? 5.0 : 1.0, i & 4 ? 5.0 : 1.0}; };
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  geometry::StlSurface surface;
  surface.file = "cube.stl";
  for (const auto& q : quads) {
    surface.triangles.push_back({corner(q[0]), corner(q[1]), corner(q[2])});
    surface.triangles.push_back({corner(q[0]), corner(q[2]), corner(q[3])});
  }
  return one_inclusion_scene(3, 6, surface, "cube", inclusion_is_void);
}

inline Vec3 centroid(const mesh::Mesh3& m, std::size_t c) {
  Vec3 g{0, 0, 0};
  for (int k = 0; k < 4; ++k)
    for (int d = 0; d < 3; ++d) g[d] += m.point(m.cell(c)[k])[d] / 4;
  return g;
}

inline bool in_cube(const Vec3& p) {
  for (int d = 0; d < 3; ++d)
    if (!(p[d] > 1 && p[d] < 5)) return false;
  return true;
}

inline mesh::Mesh3 cube_mesh() {
  mesh::Mesh3 m = structured_tets(6, 6, 6);
  for (std::size_t c = 0; c < m.cell_count(); ++c) m.cell_phase[c] = in_cube(centroid(m, c)) ? 2 : 1;
  return m;
}

}  // namespace cisamr::quality::testing
