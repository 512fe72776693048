#pragma once
// Free functions on single shapes (no scene, no CGAL in this header): what packing,
// partitioning and validation need. 2D shapes answer with areas/perimeters, 3D shapes
// with volumes/surface areas. Each asks the shape's family (shape_family.hpp, one per
// shape_<family>.cpp); shapes.cpp and shapes3.cpp combine two families for the overlaps.
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"

namespace cisamr::geometry {

int shape_dimension(const Shape& s);  // 2 or 3

// Tight axis-aligned bounding box (z components unused in 2D).
Box3 shape_bounding_box(const Shape& s);

// A box that holds the shape, without evaluating expensive geometry: the tight box,
// except for NURBS curves and surfaces (the box of their control points, which holds them;
// a curve's tight box costs ~0.2 s). For scenes of many inclusions.
Box3 shape_holding_box(const Shape& s);

// Are distances to this shape judged by its box (exact tests too slow or not available:
// NURBS, STL surfaces)?
bool shape_judged_by_box(const Shape& s);

// Area (2D) or volume (3D) of the closed region.
double shape_measure(const Shape& s);

// Perimeter (2D) or surface area (3D).
double shape_boundary_measure(const Shape& s);

// Points on the boundary, at most `spacing` apart along it (2D: a closed polyline in
// order; 3D: a roughly uniform point cloud). For load measures and drawings.
std::vector<Vec3> shape_boundary_samples(const Shape& s, double spacing);

// The boundary samples of a 3D shape that lie in `clip`, with the area each stands for
// (their sum approximates the area of the boundary inside `clip`). Spheres and ellipsoids
// halve their parametrisation and skip the pieces that miss `clip`, so the cost follows
// the part inside, not the whole surface; other families filter
// shape_boundary_samples, each sample an equal share of the boundary measure.
void shape_boundary_samples_within(const Shape& s, double spacing, const Box3& clip, std::vector<Vec3>& points,
                                   std::vector<double>& areas);

// Is a point inside the closed region (z ignored in 2D)?
bool shape_contains(const Shape& s, const Vec3& p);

// Do the two closed regions, each inflated by gap/2, intersect? Exact for circle/circle,
// sphere/sphere, polygon/polygon; exact up to 1e-12 relative for ellipses, ellipsoids,
// cylinders; conservative (may say true when within 1e-9 relative) for NURBS and STL.
bool shapes_overlap(const Shape& a, const Shape& b, double gap = 0);

// The same shape moved by `offset` (periodic images, packing moves).
Shape translated(const Shape& s, const Vec3& offset);

}  // namespace cisamr::geometry
