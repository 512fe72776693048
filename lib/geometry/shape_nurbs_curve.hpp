#pragma once
// Closed rational NURBS curves, as the chain of rational Bézier pieces of nurbs2.hpp.
#include "geometry/shape_family.hpp"

namespace cisamr::geometry {

const ShapeFamily& nurbs_curve_family();

}  // namespace cisamr::geometry
