#pragma once
// Single-particle geometry for the packer (self-contained, analytic where possible):
// bounding boxes, measures, convex bodies for the exact check, secondary-box covers,
// containment for union rasters, and a small STL reader. Shapes here are geometry::Shape
// values; only the kinds the packer creates are supported.
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"
#include "pack/convex.hpp"

namespace cisamr::pack {

// Tight axis-aligned box (geometry::shape_bounding_box; for NURBS: the box of the control
// points, which contains the curve).
Box3 particle_box(const geometry::Shape& s);

// Area (2D) or volume (3D): geometry::shape_measure (NURBS blobs: of their polyline).
double particle_measure(const geometry::Shape& s);

// The convex body used by the exact check (hull of points for non-convex shapes).
ConvexBody particle_body(const geometry::Shape& s);

// Is the point inside the closed particle? (circle, ellipse, polygon, nurbs, sphere,
// ellipsoid, cylinder; STL answers false).
bool particle_contains(const geometry::Shape& s, const Vec3& p);

// Closed polyline of a uniform periodic cubic B-spline (the packer's NURBS blobs: the first
// three control points repeated at the end), `per_span` points per span.
std::vector<Vec3> periodic_cubic_polyline(const std::vector<Vec2>& control_points, int per_span);

// Secondary boxes: bit c of the result is set when cell c of an n×n (2D) or n×n×n (3D)
// sub-grid of `box` (n = 8 in 2D, 4 in 3D) may touch the particle. Conservative: every
// cell that touches it is set.
constexpr int secondary_cells_per_axis(int dim) { return dim == 2 ? 8 : 4; }
std::uint64_t secondary_cover(const geometry::Shape& s, const Box3& box, int dim);

// The same shape scaled by `factor` about the origin (moving it: geometry::translated).
geometry::Shape scaled_about_origin(const geometry::Shape& s, double factor);

// STL triangles (ASCII or binary), 9 coordinates per triangle.
std::vector<double> read_stl_triangles(const std::string& path);

}  // namespace cisamr::pack
