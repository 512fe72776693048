#pragma once
// Spheres (exact) and ellipsoids (tolerant: the unit sphere in a rotated, scaled frame).
#include "geometry/shape_model.hpp"

namespace cisamr::geometry {

// Half the extent of the ellipsoid along world axis d (its box is center ± this).
double ellipsoid_half_extent(const Ellipsoid& e, int d);

std::unique_ptr<SurfaceModel> make_sphere_model(const Shape& shape, const std::string& source,
                                                const std::string& field);
std::unique_ptr<SurfaceModel> make_ellipsoid_model(const Shape& shape, const std::string& source,
                                                   const std::string& field);

}  // namespace cisamr::geometry
