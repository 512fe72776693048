#pragma once
// Finite cylinders with flat caps (exact side; convex).
#include "geometry/shape_family.hpp"

namespace cisamr::geometry {

const ShapeFamily& cylinder_family();

}  // namespace cisamr::geometry
