#pragma once
// Helpers shared by the shape families and shapes.cpp (private to lib/geometry).
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"

namespace cisamr::geometry::detail {

// The box of a non-empty point list (z = 0).
Box3 points_box(const std::vector<Vec2>& pts);
// The closed ring through `v`, each edge cut into pieces at most `spacing` long (z = 0).
std::vector<Vec3> resampled_ring(const std::vector<Vec2>& v, double spacing);
// Distance between the segments [p0, p1] and [q0, q1] when they do not cross: the least
// of the four endpoint-to-segment distances.
double segments_distance(const Vec2& p0, const Vec2& p1, const Vec2& q0, const Vec2& q1);
// shapes_overlap for 3D shapes (shapes3.cpp).
bool overlap3(const Shape& a, const Shape& b, double gap);

}  // namespace cisamr::geometry::detail
