#pragma once
// Simple polygons, either orientation (exact predicates throughout).
#include "geometry/shape_family.hpp"

namespace cisamr::geometry {

const ShapeFamily& polygon_family();

}  // namespace cisamr::geometry
