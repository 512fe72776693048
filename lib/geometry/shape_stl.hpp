#pragma once
// Closed triangulated surfaces read from STL files (exact on the transformed vertices;
// the machinery is stl_mesh.cpp).
#include "geometry/shape_model.hpp"

namespace cisamr::geometry {

std::unique_ptr<SurfaceModel> make_stl_model(const Shape& shape, const std::string& source,
                                             const std::string& field);

}  // namespace cisamr::geometry
