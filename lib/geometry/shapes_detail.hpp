#pragma once
// 3D halves of the shapes.hpp functions (shapes3.cpp), private to lib/geometry.
#include <vector>

#include "geometry/scene.hpp"

namespace cisamr::geometry::detail {
Box3 bounding_box3(const Shape& s);
double measure3(const Shape& s);
double boundary_measure3(const Shape& s);
std::vector<Vec3> boundary_samples3(const Shape& s, double spacing);
void boundary_samples_within3(const Shape& s, double spacing, const Box3& clip, std::vector<Vec3>& points,
                              std::vector<double>& areas);
bool contains3(const Shape& s, const Vec3& p);
bool overlap3(const Shape& a, const Shape& b, double gap);
}  // namespace cisamr::geometry::detail
