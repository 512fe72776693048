#pragma once
// Closed rational NURBS curves, as the chain of rational Bézier pieces of nurbs2.hpp.
#include "geometry/shape_model.hpp"

namespace cisamr::geometry {

std::unique_ptr<CurveModel> make_nurbs_curve_model(const NurbsCurve& curve, const std::string& source,
                                                   const std::string& field);

}  // namespace cisamr::geometry
