#pragma once
// Circles (exact) and ellipses (tolerant: the unit circle in a rotated, scaled frame).
#include "geometry/shape_family.hpp"

namespace cisamr::geometry {

const ShapeFamily& circle_family();
const ShapeFamily& ellipse_family();

}  // namespace cisamr::geometry
