#pragma once
// The oracle model of a `nurbs_surface` inclusion (private to lib/geometry), made by its
// family (shape_nurbs_surface.cpp).
#include <memory>
#include <string>

#include "geometry/scene.hpp"

namespace cisamr::geometry {

class SurfaceModel;
namespace surface {
struct Body;
}

// Throws InputError(source, field + ".patches[k]…", …) for a surface that does not close a
// volume, cannot be oriented, intersects itself or has invalid patches.
std::unique_ptr<SurfaceModel> make_nurbs_surface_model(const Shape& shape, const std::string& source,
                                                       const std::string& field);
// The model of any built body (STEP solids), for the descriptor `shape`.
std::unique_ptr<SurfaceModel> make_body_model(const Shape& shape, std::shared_ptr<const surface::Body> body);

}  // namespace cisamr::geometry
