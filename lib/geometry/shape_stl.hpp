#pragma once
// Closed triangulated surfaces read from STL files (exact on the transformed vertices;
// the machinery is stl_mesh.cpp).
#include "geometry/shape_family.hpp"

namespace cisamr::geometry {

const ShapeFamily& stl_family();

}  // namespace cisamr::geometry
