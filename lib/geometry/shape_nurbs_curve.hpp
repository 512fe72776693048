#pragma once
// Closed rational NURBS curves, as the chain of rational Bézier pieces of nurbs2.hpp.
#include <cstddef>
#include <string_view>
#include <vector>

#include "geometry/shape_family.hpp"

namespace cisamr::geometry {

const ShapeFamily& nurbs_curve_family();

// Reading NURBS fields (also for nurbs_surface). A knot vector: non-decreasing, with a
// non-empty parameter range for `degree`, of expected_count knots unless that is 0.
std::vector<double> read_knots(const FieldReader& fields, std::string_view key, int degree,
                               std::size_t expected_count);
// Positive weights, one per control point; empty when the field is absent (all 1).
std::vector<double> read_weights(const FieldReader& fields, std::string_view key, std::size_t expected_count);

}  // namespace cisamr::geometry
