#pragma once
// Pictures of meshes, coloured by phase: a 2D mesh's triangles, or the slice of a 3D mesh by
// an axis-aligned plane (each tetrahedron the plane cuts drawn as its cross-section polygon).
// For the README's example and quick looks; ParaView is the tool for anything serious.
#include <optional>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::io {

// The plane x[axis] = at of a 3D slice; without `at`, the domain's centre along that axis.
struct SlicePlane {
  int axis = 2;
  std::optional<double> at;
};

// The cross-sections of a 3D mesh's tetrahedra by a plane: convex polygons in the plane's
// coordinates (the other two axes, in increasing order), counter-clockwise, with the phase of
// their tetrahedron. A tetrahedron counts when it has a vertex below the plane and one on or
// above it, so a face lying in the plane is drawn once, by the tetrahedron below it.
struct SlicePolygons {
  std::vector<Vec2> points;
  std::vector<std::size_t> offsets{0};  // polygon i: points[offsets[i], offsets[i + 1])
  std::vector<int> phase;
  std::size_t size() const { return phase.size(); }
};
SlicePolygons slice_mesh(const mesh::Mesh3& m, int axis, double at);

// Writes an SVG (through AtomicFile). Large meshes are drawn without edges, which would
// only blacken the picture. width_px: the width of the drawing.
void write_mesh_svg(const std::string& path, const mesh::Mesh2& m, const geometry::SceneDesc& scene,
                    int width_px = 1600);
// The slice of a 3D mesh; InputError (naming the option) when the plane misses the domain.
void write_mesh_svg(const std::string& path, const mesh::Mesh3& m, const geometry::SceneDesc& scene,
                    const SlicePlane& plane, int width_px = 1600);

}  // namespace cisamr::io
