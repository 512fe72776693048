#pragma once
// Spheres (exact) and ellipsoids (tolerant: the unit sphere in a rotated, scaled frame).
#include "geometry/shape_family.hpp"

namespace cisamr::geometry {

// Half the extent of the ellipsoid along world axis d (its box is center ± this).
double ellipsoid_half_extent(const Ellipsoid& e, int d);

const ShapeFamily& sphere_family();
const ShapeFamily& ellipsoid_family();

}  // namespace cisamr::geometry
