#pragma once
// Finite cylinders with flat caps (exact side; convex).
#include "geometry/shape_model.hpp"

namespace cisamr::geometry {

std::unique_ptr<SurfaceModel> make_cylinder_model(const Shape& shape, const std::string& source,
                                                  const std::string& field);

}  // namespace cisamr::geometry
