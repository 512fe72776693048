#pragma once
// Closed triangle surfaces from STL (private to lib/geometry): the transformed,
// deduplicated mesh, a flat bounding-volume hierarchy over its faces, validation, and
// the exact queries of README.md (ray parity with a symbolically perturbed axis ray,
// exact orientation predicates). No CGAL here: predicates3 and box_index supply it.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "geometry/flat_bvh.hpp"
#include "geometry/scene.hpp"

namespace cisamr::geometry::stl {

struct Mesh {
  std::vector<Vec3> vertices;                      // after scale, rotation, translation
  std::vector<std::array<std::int32_t, 3>> faces;  // in file order
  FlatBvh<3> bvh;                                  // over the faces
  Box3 box;
  double size = 0;  // box diagonal
};

// Transforms, merges identical vertices and builds the hierarchy. With `validate`,
// returns "" or the problem ("surface is not closed (face 3)"); without, never fails.
std::string build(const StlSurface& surface, Mesh& out, bool validate);

// The same from a mesh that is already indexed and placed (vertices used as given, faces
// referring to them, no merging): the tessellations of NURBS and STEP bodies. Problems
// name faces by their index in `faces`.
std::string build_indexed(std::vector<Vec3> vertices, std::vector<std::array<std::int32_t, 3>> faces, Mesh& out,
                          bool validate);

// +1 inside, 0 on a face (exact), -1 outside.
int side(const Mesh& m, const Vec3& p);

// Parameters t in (0,1) where the open segment a→b crosses a face plane transversally
// inside the closed face (exact decision, rounded t), unsorted, with duplicates.
void segment_hits(const Mesh& m, const Vec3& a, const Vec3& b, std::vector<double>& ts);

// Does some face meet the closed box (exact)?
bool touches_box(const Mesh& m, const Box3& box);

double volume(const Mesh& m);        // |Σ signed tetrahedra| (divergence theorem)
double surface_area(const Mesh& m);
double distance_to_surface(const Mesh& m, const Vec3& p);

// y where the mesh edges cross the plane x = x0 (the kinks of chord lengths in y).
void edge_crossings_at_x(const Mesh& m, double x0, std::vector<double>& ys);

}  // namespace cisamr::geometry::stl
