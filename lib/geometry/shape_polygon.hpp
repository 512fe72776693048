#pragma once
// Simple polygons, either orientation (exact predicates throughout).
#include "geometry/shape_model.hpp"

namespace cisamr::geometry {

std::unique_ptr<CurveModel> make_polygon_model(const Polygon& polygon, const std::string& source,
                                               const std::string& field);

}  // namespace cisamr::geometry
