#pragma once
// Circles (exact) and ellipses (tolerant: the unit circle in a rotated, scaled frame).
#include "geometry/shape_model.hpp"

namespace cisamr::geometry {

std::unique_ptr<CurveModel> make_circle_model(const Circle& circle, const std::string& source,
                                              const std::string& field);
std::unique_ptr<CurveModel> make_ellipse_model(const Ellipse& ellipse, const std::string& source,
                                               const std::string& field);

}  // namespace cisamr::geometry
