#pragma once
// STEP solids (read through OpenCASCADE at scene-read time) as 3D inclusions.
#include "geometry/shape_family.hpp"

namespace cisamr::geometry {

const ShapeFamily& step_family();

}  // namespace cisamr::geometry
