#pragma once
// NURBS surfaces: read and written by scene files, not meshed yet (the oracle refuses them).
#include "geometry/shape_family.hpp"

namespace cisamr::geometry {

const ShapeFamily& nurbs_surface_family();

}  // namespace cisamr::geometry
