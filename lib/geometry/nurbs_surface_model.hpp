#pragma once
// The oracle model of a `nurbs_surface` inclusion (private to lib/geometry), made by its
// family (shape_nurbs_surface.cpp).
#include <memory>
#include <string>

#include "geometry/scene.hpp"

namespace cisamr::geometry {

class SurfaceModel;

// Throws InputError(source, field + ".patches[k]…", …) for a surface that does not close a
// volume, cannot be oriented, intersects itself or has invalid patches.
std::unique_ptr<SurfaceModel> make_nurbs_surface_model(const Shape& shape, const std::string& source,
                                                       const std::string& field);

}  // namespace cisamr::geometry
