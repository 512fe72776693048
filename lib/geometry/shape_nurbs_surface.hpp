#pragma once
// NURBS surfaces (closed sets of rational B-spline patches) as 3D inclusions.
#include "geometry/shape_family.hpp"

namespace cisamr::geometry {

const ShapeFamily& nurbs_surface_family();

}  // namespace cisamr::geometry
